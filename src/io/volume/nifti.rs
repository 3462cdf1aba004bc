//! NIfTI-1 (348-byte header) and NIfTI-2 (540-byte header) single-file volumes (`n+1`, `n+2`),
//! either byte order, optionally gzip-compressed (detected by its magic bytes).

use super::{Decode, Elem, VolumeFile, VolumeHeader, cropped, read_slices};
use crate::volume::Frame;
use crate::{Error, Result};
use glam::{DMat3, DMat4, DQuat, DVec3, DVec4};
use std::io::{BufRead, Read};

/// The header fields a label volume needs, from either version.
struct Header {
    version: u8,
    dims: Vec<i64>,
    datatype: i16,
    pixdim: [f64; 8],
    vox_offset: f64,
    slope: f64,
    inter: f64,
    qform_code: i32,
    sform_code: i32,
    quatern: [f64; 3],
    qoffset: [f64; 3],
    srow: [[f64; 4]; 3],
    xyzt_units: i32,
}

/// Reads a NIfTI-1 or NIfTI-2 volume from `r` (`name` is used in errors).
pub fn read_nifti_from(name: &str, mut r: impl BufRead) -> Result<VolumeFile> {
    let gz = r
        .fill_buf()
        .map(|b| b.starts_with(&[0x1f, 0x8b]))
        .unwrap_or(false);
    if gz {
        let mut d =
            std::io::BufReader::with_capacity(1 << 20, flate2::bufread::MultiGzDecoder::new(r));
        read_plain(name, &mut d)
    } else {
        read_plain(name, &mut r)
    }
}

fn read_plain(name: &str, r: &mut impl Read) -> Result<VolumeFile> {
    let mut head = vec![0u8; 348];
    r.read_exact(&mut head)
        .map_err(|e| Error::Io(format!("{name}: too short for a NIfTI header ({e})")))?;
    let n1 = i32::from_le_bytes([head[0], head[1], head[2], head[3]]);
    let (version, big) = match (n1, n1.swap_bytes()) {
        (348, _) => (1, false),
        (_, 348) => (1, true),
        (540, _) => (2, false),
        (_, 540) => (2, true),
        _ => {
            return Err(Error::Io(format!(
                "{name}: not a NIfTI file (header size field {n1}, expected 348 or 540)"
            )));
        }
    };
    if version == 2 {
        let mut rest = vec![0u8; 540 - 348];
        r.read_exact(&mut rest)
            .map_err(|e| Error::Io(format!("{name}: NIfTI-2 header cut short ({e})")))?;
        head.extend_from_slice(&rest);
    }
    let h = if version == 1 {
        parse1(name, &head, big)?
    } else {
        parse2(name, &head, big)?
    };
    let dims = volume_dims(name, &h)?;
    let elem = elem_of(name, h.datatype)?;
    let (affine, source) = affine_of(name, &h)?;
    let header_len = if version == 1 { 348 } else { 540 };
    let skip = (h.vox_offset as usize).saturating_sub(header_len);
    std::io::copy(&mut r.by_ref().take(skip as u64), &mut std::io::sink())
        .map_err(|e| Error::Io(format!("{name}: cannot skip to the voxel data ({e})")))?;
    let (slope, inter) = if h.slope == 0.0 || !h.slope.is_finite() {
        (1.0, 0.0)
    } else {
        (h.slope, if h.inter.is_finite() { h.inter } else { 0.0 })
    };
    let dec = Decode {
        elem,
        big_endian: big,
        slope,
        inter,
    };
    let (labels, lo, cd) = read_slices(name, r, dims, dec)?;
    let volume = cropped(affine, Frame::Ras, labels, lo, cd)
        .map_err(|e| Error::Io(format!("{name}: {e}")))?;
    Ok(VolumeFile {
        volume,
        header: VolumeHeader {
            format: if h.version == 1 { "NIfTI-1" } else { "NIfTI-2" },
            full_dims: dims,
            element: elem.name(),
            orientation_source: source,
            full_voxel_to_world: affine,
            segments: Vec::new(),
        },
    })
}

struct Fields<'a> {
    b: &'a [u8],
    big: bool,
}

impl Fields<'_> {
    fn arr<const N: usize>(&self, at: usize) -> [u8; N] {
        let mut a = [0u8; N];
        a.copy_from_slice(&self.b[at..at + N]);
        if self.big {
            a.reverse();
        }
        a
    }
    fn i16(&self, at: usize) -> i16 {
        i16::from_le_bytes(self.arr(at))
    }
    fn i32(&self, at: usize) -> i32 {
        i32::from_le_bytes(self.arr(at))
    }
    fn i64(&self, at: usize) -> i64 {
        i64::from_le_bytes(self.arr(at))
    }
    fn f32(&self, at: usize) -> f64 {
        f32::from_le_bytes(self.arr(at)) as f64
    }
    fn f64(&self, at: usize) -> f64 {
        f64::from_le_bytes(self.arr(at))
    }
}

fn parse1(name: &str, b: &[u8], big: bool) -> Result<Header> {
    if &b[344..347] != b"n+1" {
        return Err(Error::Io(format!(
            "{name}: NIfTI-1 magic {:?} is not \"n+1\" (a .hdr/.img pair is not supported: use a \
             single .nii file)",
            String::from_utf8_lossy(&b[344..347])
        )));
    }
    let f = Fields { b, big };
    Ok(Header {
        version: 1,
        dims: (0..8).map(|d| f.i16(40 + 2 * d) as i64).collect(),
        datatype: f.i16(70),
        pixdim: std::array::from_fn(|d| f.f32(76 + 4 * d)),
        vox_offset: f.f32(108),
        slope: f.f32(112),
        inter: f.f32(116),
        qform_code: f.i16(252) as i32,
        sform_code: f.i16(254) as i32,
        quatern: std::array::from_fn(|d| f.f32(256 + 4 * d)),
        qoffset: std::array::from_fn(|d| f.f32(268 + 4 * d)),
        srow: std::array::from_fn(|r| std::array::from_fn(|c| f.f32(280 + 16 * r + 4 * c))),
        xyzt_units: b[123] as i32,
    })
}

fn parse2(name: &str, b: &[u8], big: bool) -> Result<Header> {
    if &b[4..7] != b"n+2" {
        return Err(Error::Io(format!(
            "{name}: NIfTI-2 magic {:?} is not \"n+2\" (a .hdr/.img pair is not supported)",
            String::from_utf8_lossy(&b[4..7])
        )));
    }
    let f = Fields { b, big };
    Ok(Header {
        version: 2,
        dims: (0..8).map(|d| f.i64(16 + 8 * d)).collect(),
        datatype: f.i16(12),
        pixdim: std::array::from_fn(|d| f.f64(104 + 8 * d)),
        vox_offset: f.i64(168) as f64,
        slope: f.f64(176),
        inter: f.f64(184),
        qform_code: f.i32(344),
        sform_code: f.i32(348),
        quatern: std::array::from_fn(|d| f.f64(352 + 8 * d)),
        qoffset: std::array::from_fn(|d| f.f64(376 + 8 * d)),
        srow: std::array::from_fn(|r| std::array::from_fn(|c| f.f64(400 + 32 * r + 8 * c))),
        xyzt_units: f.i32(500),
    })
}

fn volume_dims(name: &str, h: &Header) -> Result<[usize; 3]> {
    let nd = h.dims[0];
    if !(1..=7).contains(&nd) {
        return Err(Error::Io(format!("{name}: dim[0] = {nd} (expected 1-7)")));
    }
    let mut d = [1usize; 3];
    for (a, &n) in h.dims[1..=nd as usize].iter().enumerate() {
        if n < 1 {
            return Err(Error::Io(format!(
                "{name}: dim[{}] = {n} (must be ≥ 1)",
                a + 1
            )));
        }
        if a < 3 {
            d[a] = n as usize;
        } else if n != 1 {
            return Err(Error::InvalidArgument(format!(
                "{name}: a {nd}-D volume with {n} entries along axis {}: a label volume is 3-D",
                a + 1
            )));
        }
    }
    if d.iter().map(|&x| x as u128).product::<u128>() > (1u128 << 34) {
        return Err(Error::InvalidArgument(format!(
            "{name}: volume {d:?} is too large"
        )));
    }
    Ok(d)
}

fn elem_of(name: &str, datatype: i16) -> Result<Elem> {
    Ok(match datatype {
        2 => Elem::U8,
        4 => Elem::I16,
        8 => Elem::I32,
        16 => Elem::F32,
        64 => Elem::F64,
        256 => Elem::I8,
        512 => Elem::U16,
        768 => Elem::U32,
        1024 => Elem::I64,
        1280 => Elem::U64,
        other => {
            return Err(Error::InvalidArgument(format!(
                "{name}: NIfTI datatype {other} is not a scalar label type (integer or float \
                 holding integers)"
            )));
        }
    })
}

/// Millimetres per the file's spatial unit (xyzt_units & 7: 1 m, 2 mm, 3 µm; 0 = unknown,
/// taken as mm).
fn unit_scale(name: &str, units: i32) -> Result<f64> {
    match units & 7 {
        0 | 2 => Ok(1.0),
        1 => Ok(1000.0),
        3 => Ok(0.001),
        u => Err(Error::Io(format!("{name}: unknown spatial unit code {u}"))),
    }
}

/// Voxel-to-world in RAS millimetres: sform when its code is set, else qform; neither is a
/// missing orientation.
fn affine_of(name: &str, h: &Header) -> Result<(DMat4, &'static str)> {
    let s = unit_scale(name, h.xyzt_units)?;
    if h.sform_code > 0 {
        let r = &h.srow;
        let m = DMat4::from_cols(
            DVec4::new(r[0][0], r[1][0], r[2][0], 0.0) * s,
            DVec4::new(r[0][1], r[1][1], r[2][1], 0.0) * s,
            DVec4::new(r[0][2], r[1][2], r[2][2], 0.0) * s,
            DVec4::new(r[0][3] * s, r[1][3] * s, r[2][3] * s, 1.0),
        );
        return Ok((m, "sform"));
    }
    if h.qform_code > 0 {
        let [b, c, d] = h.quatern;
        let a = (1.0 - (b * b + c * c + d * d)).max(0.0).sqrt();
        let rot = DMat3::from_quat(DQuat::from_xyzw(b, c, d, a).normalize());
        let qfac = if h.pixdim[0] < 0.0 { -1.0 } else { 1.0 };
        let sc = DVec3::new(h.pixdim[1], h.pixdim[2], qfac * h.pixdim[3]) * s;
        let m3 = DMat3::from_cols(rot.x_axis * sc.x, rot.y_axis * sc.y, rot.z_axis * sc.z);
        let t = DVec3::from_array(h.qoffset) * s;
        return Ok((DMat4::from_mat3_translation(m3, t), "qform"));
    }
    Err(Error::InvalidArgument(format!(
        "{name}: no orientation (sform_code and qform_code are both 0): the volume cannot be \
         placed in patient space; re-save it with an sform or qform"
    )))
}
