//! NRRD volumes (`.nrrd`, 3D Slicer's `.seg.nrrd`): the text header (`NRRD000n`, `field: value`
//! and `key:=value` lines up to a blank line), then raw or gzip data in the same file.
//!
//! A `.seg.nrrd` with one layer is a 3-D label map (or 4-D with a leading axis of size 1); its
//! `SegmentN_Name` / `SegmentN_LabelValue` pairs are kept as segment names. Several layers
//! (overlapping segments) are refused with a message.

use super::{Decode, Elem, VolumeFile, VolumeHeader, cropped, read_slices};
use crate::volume::Frame;
use crate::{Error, Result};
use glam::{DMat4, DVec3, DVec4};
use std::collections::BTreeMap;
use std::io::{BufRead, Read};

/// Reads an NRRD volume with attached data from `r` (`name` is used in errors).
pub fn read_nrrd_from(name: &str, mut r: impl BufRead) -> Result<VolumeFile> {
    let (fields, kv) = read_header(name, &mut r)?;
    let get = |k: &str| fields.get(k).map(String::as_str);
    let need = |k: &str| {
        get(k).ok_or_else(|| Error::Io(format!("{name}: NRRD header has no `{k}` field")))
    };
    if let Some(f) = get("data file").or(get("datafile")) {
        return Err(Error::Io(format!(
            "{name}: detached data (`data file: {f}`) is not supported: save the volume as one \
             .nrrd file"
        )));
    }
    let elem = elem_of(name, need("type")?)?;
    let ndim: usize = parse_num(name, "dimension", need("dimension")?)?;
    let sizes: Vec<usize> = need("sizes")?
        .split_whitespace()
        .map(|s| parse_num(name, "sizes", s))
        .collect::<Result<_>>()?;
    if sizes.len() != ndim {
        return Err(Error::Io(format!(
            "{name}: `sizes` has {} entries for dimension {ndim}",
            sizes.len()
        )));
    }
    let dirs = parse_directions(name, get("space directions"), ndim)?;
    // A leading non-spatial axis (seg.nrrd layers, kinds `list`) must have size 1.
    let spatial: Vec<usize> = (0..ndim).filter(|&a| dirs[a].is_some()).collect();
    if spatial.len() != 3 || (ndim == 4 && (spatial != [1, 2, 3] || sizes[0] != 1)) {
        return Err(Error::InvalidArgument(format!(
            "{name}: {ndim}-D NRRD with sizes {sizes:?}: a label volume has 3 spatial axes \
             (a .seg.nrrd with {} layers has overlapping segments; merge them to one layer)",
            if ndim == 4 { sizes[0] } else { 1 }
        )));
    }
    let dims = [sizes[spatial[0]], sizes[spatial[1]], sizes[spatial[2]]];
    let frame = frame_of(name, get("space"))?;
    let origin = match get("space origin") {
        Some(o) => parse_vector(name, o)?,
        None => DVec3::ZERO,
    };
    let cols: Vec<DVec3> = spatial
        .iter()
        .map(|&a| dirs[a].unwrap_or_default())
        .collect();
    let (cols, frame) = match frame {
        Space::Frame(f) => (cols, f),
        // left-anterior-superior: negate y to reach LPS.
        Space::Las => {
            let flip = DVec3::new(1.0, -1.0, 1.0);
            (cols.iter().map(|c| *c * flip).collect(), Frame::Lps)
        }
    };
    let origin = if matches!(frame_of(name, get("space"))?, Space::Las) {
        origin * DVec3::new(1.0, -1.0, 1.0)
    } else {
        origin
    };
    let affine = DMat4::from_cols(
        cols[0].extend(0.0),
        cols[1].extend(0.0),
        cols[2].extend(0.0),
        DVec4::new(origin.x, origin.y, origin.z, 1.0),
    );
    let big = elem.size() > 1 && get("endian").is_some_and(|e| e.trim() == "big");
    let enc = need("encoding")?.trim().to_ascii_lowercase();
    let dec = Decode {
        elem,
        big_endian: big,
        slope: 1.0,
        inter: 0.0,
    };
    let (labels, lo, cd) = match enc.as_str() {
        "raw" => read_slices(name, &mut r, dims, dec)?,
        "gzip" | "gz" => {
            let mut d =
                std::io::BufReader::with_capacity(1 << 20, flate2::bufread::MultiGzDecoder::new(r));
            read_slices(name, &mut d, dims, dec)?
        }
        other => {
            return Err(Error::Io(format!(
                "{name}: NRRD encoding `{other}` is not supported (raw or gzip)"
            )));
        }
    };
    let volume =
        cropped(affine, frame, labels, lo, cd).map_err(|e| Error::Io(format!("{name}: {e}")))?;
    Ok(VolumeFile {
        volume,
        header: VolumeHeader {
            format: "NRRD",
            full_dims: dims,
            element: elem.name(),
            orientation_source: "space directions",
            full_voxel_to_world: affine,
            segments: segments(&kv),
        },
    })
}

type Fields = BTreeMap<String, String>;

fn read_header(name: &str, r: &mut impl BufRead) -> Result<(Fields, Fields)> {
    let mut line = String::new();
    let mut fields = Fields::new();
    let mut kv = Fields::new();
    let mut first = true;
    loop {
        line.clear();
        let n = r
            .by_ref()
            .take(1 << 16)
            .read_line(&mut line)
            .map_err(|e| Error::Io(format!("{name}: NRRD header unreadable ({e})")))?;
        if n == 0 {
            return Err(Error::Io(format!(
                "{name}: NRRD header has no end (blank line)"
            )));
        }
        let l = line.trim_end_matches(['\n', '\r']);
        if first {
            if !l.starts_with("NRRD000") {
                return Err(Error::Io(format!(
                    "{name}: not an NRRD file (first line {l:?}, expected NRRD000n)"
                )));
            }
            first = false;
            continue;
        }
        if l.is_empty() {
            return Ok((fields, kv));
        }
        if l.starts_with('#') {
            continue;
        }
        if let Some((k, v)) = l.split_once(":=") {
            kv.insert(k.to_string(), v.to_string());
        } else if let Some((k, v)) = l.split_once(": ") {
            fields.insert(k.trim().to_ascii_lowercase(), v.trim().to_string());
        } else {
            return Err(Error::Io(format!(
                "{name}: NRRD header line {l:?} is not `field: value`"
            )));
        }
    }
}

fn parse_num<T: std::str::FromStr>(name: &str, what: &str, s: &str) -> Result<T> {
    s.trim()
        .parse()
        .map_err(|_| Error::Io(format!("{name}: NRRD `{what}` value {s:?} is not a number")))
}

fn parse_vector(name: &str, s: &str) -> Result<DVec3> {
    let t = s.trim();
    let inner = t
        .strip_prefix('(')
        .and_then(|x| x.strip_suffix(')'))
        .ok_or_else(|| Error::Io(format!("{name}: NRRD vector {t:?} is not (x,y,z)")))?;
    let v: Vec<f64> = inner
        .split(',')
        .map(|x| parse_num(name, "vector", x))
        .collect::<Result<_>>()?;
    if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
        return Err(Error::Io(format!(
            "{name}: NRRD vector {t:?} needs 3 finite numbers"
        )));
    }
    Ok(DVec3::new(v[0], v[1], v[2]))
}

fn parse_directions(name: &str, s: Option<&str>, ndim: usize) -> Result<Vec<Option<DVec3>>> {
    let Some(s) = s else {
        return Err(Error::InvalidArgument(format!(
            "{name}: no `space directions`: the volume has no orientation and cannot be placed in \
             patient space (re-save it from 3D Slicer or with space directions and origin)"
        )));
    };
    let parts: Vec<&str> = s.split_whitespace().collect();
    if parts.len() != ndim {
        return Err(Error::Io(format!(
            "{name}: `space directions` has {} entries for dimension {ndim}",
            parts.len()
        )));
    }
    parts
        .iter()
        .map(|p| {
            if *p == "none" {
                Ok(None)
            } else {
                parse_vector(name, p).map(Some)
            }
        })
        .collect()
}

enum Space {
    Frame(Frame),
    Las,
}

fn frame_of(name: &str, s: Option<&str>) -> Result<Space> {
    let s = s.map(|x| x.trim().to_ascii_lowercase()).unwrap_or_default();
    Ok(match s.as_str() {
        "left-posterior-superior" | "lps" => Space::Frame(Frame::Lps),
        "right-anterior-superior" | "ras" => Space::Frame(Frame::Ras),
        "left-anterior-superior" | "las" => Space::Las,
        "" => {
            return Err(Error::InvalidArgument(format!(
                "{name}: no `space` field: the volume's world frame (LPS or RAS) is unknown"
            )));
        }
        other => {
            return Err(Error::InvalidArgument(format!(
                "{name}: NRRD space `{other}` is not a patient frame (left-posterior-superior, \
                 right-anterior-superior or left-anterior-superior)"
            )));
        }
    })
}

fn elem_of(name: &str, t: &str) -> Result<Elem> {
    Ok(match t.trim() {
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => Elem::U8,
        "signed char" | "int8" | "int8_t" => Elem::I8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => {
            Elem::I16
        }
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => Elem::U16,
        "int" | "signed int" | "int32" | "int32_t" => Elem::I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => Elem::U32,
        "longlong" | "long long" | "long long int" | "signed long long" | "int64" | "int64_t" => {
            Elem::I64
        }
        "ulonglong" | "unsigned long long" | "unsigned long long int" | "uint64" | "uint64_t" => {
            Elem::U64
        }
        "float" => Elem::F32,
        "double" => Elem::F64,
        other => {
            return Err(Error::InvalidArgument(format!(
                "{name}: NRRD type `{other}` is not a scalar label type"
            )));
        }
    })
}

/// (label value, name) of each `SegmentN_` of a 3D Slicer segmentation.
fn segments(kv: &Fields) -> Vec<(u16, String)> {
    let mut out = Vec::new();
    for n in 0.. {
        let Some(name) = kv.get(&format!("Segment{n}_Name")) else {
            break;
        };
        let label = kv
            .get(&format!("Segment{n}_LabelValue"))
            .and_then(|v| v.trim().parse().ok())
            .unwrap_or(0);
        out.push((label, name.clone()));
    }
    out
}
