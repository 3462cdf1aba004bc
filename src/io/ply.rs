//! PLY (Stanford polygon format), ASCII and binary, through the `ply-rs-bw` crate.
//!
//! Read: `vertex` element with `x, y, z` (any scalar type), optional per-vertex label property
//! (a given name, or else a known label name: see [`super::labels`]; any numeric type); `face`
//! element with `vertex_indices` or `vertex_index` (a list of any integer type,
//! fan-triangulated) and an optional face label of the same name.
//! The header and ASCII payloads are read through `ply-rs-bw` with typed elements (no
//! per-vertex maps), binary payloads in bulk ([`super::ply_binary`]). Write: `x, y, z` as
//! double (lossless) plus `int` vertex properties.

use super::labels::{ArrayInfo, MeshFile, choose};
use super::ply_binary::{self, Cursor, Faces};
use super::{FaceBuilder, PlyEncoding, check_finite, check_vertex_count, label_from_f64};
use crate::mesh::{LabeledMesh, TriMesh};
use crate::{Error, Result};
use glam::DVec3;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    DefaultElement, ElementDef, Encoding, Property, PropertyAccess, PropertyAccessResult,
    PropertyType,
};
use std::cell::RefCell;
use std::io::Write;

thread_local! {
    /// The label property being read on this thread. `PropertyAccess::new` takes no arguments,
    /// so the element types look the chosen name up here; set by [`read_ply_bytes_with`] for
    /// the duration of one parse.
    static LABEL_KEY: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Sets [`LABEL_KEY`] and clears it again when dropped.
struct LabelKey;

impl LabelKey {
    fn set(name: Option<String>) -> LabelKey {
        LABEL_KEY.with(|k| *k.borrow_mut() = name);
        LabelKey
    }
}

impl Drop for LabelKey {
    fn drop(&mut self) {
        LABEL_KEY.with(|k| *k.borrow_mut() = None);
    }
}

fn is_label_key(key: &str) -> bool {
    LABEL_KEY.with(|k| k.borrow().as_deref() == Some(key))
}

/// A `vertex` element as parsed: coordinates and the label property's value.
#[derive(Default)]
pub(super) struct PlyVertex {
    pub(super) xyz: [Option<f64>; 3],
    pub(super) label: Option<f64>,
}

impl PropertyAccess for PlyVertex {
    fn new() -> Self {
        Self::default()
    }
    fn set_property(&mut self, key: &str, p: Property) -> PropertyAccessResult {
        let slot = match key {
            "x" => Some(0),
            "y" => Some(1),
            "z" => Some(2),
            _ => None,
        };
        match (slot, scalar_f64(&p)) {
            (Some(k), v) => self.xyz[k] = v,
            (None, Some(v)) if is_label_key(key) => self.label = Some(v),
            (None, _) => {}
        }
        PropertyAccessResult::Set
    }
}

/// A `face` element as parsed: its index list (as stored) and the label property's value.
#[derive(Default)]
struct PlyFace {
    idx: Option<Property>,
    label: Option<f64>,
}

impl PropertyAccess for PlyFace {
    fn new() -> Self {
        Self::default()
    }
    fn set_property(&mut self, key: &str, p: Property) -> PropertyAccessResult {
        if key == "vertex_indices" || (key == "vertex_index" && self.idx.is_none()) {
            self.idx = Some(p);
        } else if is_label_key(key) {
            self.label = scalar_f64(&p);
        }
        PropertyAccessResult::Set
    }
}

/// Reads a PLY file held in memory; `file` names it in error messages.
pub fn read_ply_bytes(file: &str, bytes: &[u8]) -> Result<LabeledMesh> {
    read_ply_bytes_with(file, bytes, None).map(|f| f.mesh)
}

/// Like [`read_ply_bytes`], with the labels from the vertex or face property named
/// `label_array` instead of the automatic choice, and the scalar properties found.
pub fn read_ply_bytes_with(
    file: &str,
    bytes: &[u8],
    label_array: Option<&str>,
) -> Result<MeshFile> {
    read_ply(file, bytes, label_array, true)
}

/// [`read_ply_bytes_with`]; `bulk`: a binary payload read by [`super::ply_binary`] (else by
/// the crate's reader, as an ASCII one always is).
pub(super) fn read_ply(
    file: &str,
    bytes: &[u8],
    label_array: Option<&str>,
    bulk: bool,
) -> Result<MeshFile> {
    let err = |m: String| Error::Io(format!("{file}: {m}"));
    let perr = |e: ply_rs_bw::parser::ParseError| Error::Io(format!("{file}: malformed PLY: {e}"));
    let mut rd = Reader::new(bytes);
    let header = Parser::<DefaultElement>::new()
        .read_header(&mut rd)
        .map_err(perr)?;
    let vdef = header
        .elements
        .get("vertex")
        .ok_or_else(|| err("no `vertex` element in the header".into()))?;
    for c in ["x", "y", "z"] {
        match vdef.properties.get(c).map(|p| &p.data_type) {
            Some(PropertyType::Scalar(_)) => {}
            _ => return Err(err(format!("vertex property `{c}` missing or a list"))),
        }
    }
    let mut arrays = scalar_props(vdef, true);
    if let Some(fdef) = header.elements.get("face") {
        arrays.extend(scalar_props(fdef, false));
    }
    let chosen = choose(file, &arrays, label_array)?;
    let has_label = |def: &ElementDef| {
        chosen
            .as_deref()
            .is_some_and(|c| arrays.iter().any(|a| a.name == c) && def.properties.contains_key(c))
    };
    let has_vlabel = has_label(vdef);
    let face_key = header.elements.get("face").map(|def| {
        ["vertex_indices", "vertex_index"]
            .into_iter()
            .find(|k| def.properties.contains_key(*k))
    });
    if face_key == Some(None) {
        return Err(err(
            "face element has neither `vertex_indices` nor `vertex_index`".into(),
        ));
    }
    let face_key = face_key.flatten();
    let has_flabel = header.elements.get("face").is_some_and(has_label);
    // An item of an element without properties takes no bytes: reading a declared count of them
    // would loop that many times over nothing (a damaged header can declare 10^16).
    if let Some((name, def)) = header
        .elements
        .iter()
        .find(|(_, d)| d.properties.is_empty() && d.count > 0)
    {
        return Err(err(format!(
            "element `{name}` declares {} items but no properties",
            def.count
        )));
    }
    let (verts, faces) = if bulk && header.encoding != Encoding::Ascii {
        let big = header.encoding == Encoding::BinaryBigEndian;
        read_binary(rd.get_ref(), &header, big, chosen.as_deref(), face_key)
            .map_err(|e| err(format!("malformed PLY: {e}")))?
    } else {
        read_with_crate(&mut rd, &header, chosen.as_deref()).map_err(perr)?
    };
    check_vertex_count(file, verts.len())?;
    let mut positions = Vec::with_capacity(verts.len());
    let mut vlabels = has_vlabel.then(|| Vec::with_capacity(verts.len()));
    for (i, v) in verts.iter().enumerate() {
        let [Some(x), Some(y), Some(z)] = v.xyz else {
            return Err(err(format!("vertex {i} lacks a numeric x, y or z")));
        };
        positions.push(DVec3::new(x, y, z));
        if let Some(out) = vlabels.as_mut() {
            let l = v.label.unwrap_or(f64::NAN);
            out.push(label_from_f64(l, file, "vertex", i)?);
        }
    }
    check_finite(file, &positions)?;

    let mut fb = FaceBuilder::new(file, positions.len());
    fb.triangles.reserve(faces.len());
    fb.source_poly.reserve(faces.len());
    let mut plabels = Vec::with_capacity(if has_flabel { faces.len() } else { 0 });
    let key = face_key.unwrap_or("vertex_indices");
    for f in 0..faces.len() {
        if faces.not_integers == Some(f) {
            return Err(err(format!("face {f}: `{key}` is not a list of integers")));
        }
        fb.polygon(faces.indices(f))?;
        if has_flabel {
            let l = faces.label[f].unwrap_or(f64::NAN);
            plabels.push(label_from_f64(l, file, "face", f)?);
        }
    }
    let face_labels = has_flabel.then(|| {
        fb.source_poly
            .iter()
            .map(|&p| plabels[p as usize])
            .collect()
    });
    let found = vlabels.is_some() || face_labels.is_some();
    Ok(MeshFile {
        mesh: LabeledMesh {
            mesh: TriMesh::new(positions, fb.triangles),
            vertex_labels: vlabels,
            face_labels,
        },
        label_array: chosen.filter(|_| found),
        teeth3ds_json: false,
        arrays,
    })
}

/// Elements other than `vertex` and `face` are read (to advance) and dropped.
struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
    fn set_property(&mut self, _: &str, _: Property) -> PropertyAccessResult {
        PropertyAccessResult::Set
    }
}

/// The payload's `vertex` and `face` elements read by the crate's reader (each element with its
/// own type; the others read and dropped).
fn read_with_crate(
    rd: &mut Reader<&[u8]>,
    header: &ply_rs_bw::ply::Header,
    label: Option<&str>,
) -> std::result::Result<(Vec<PlyVertex>, Faces), ply_rs_bw::parser::ParseError> {
    let _key = LabelKey::set(label.map(str::to_owned));
    let mut verts = Vec::new();
    let mut faces = Faces::with_capacity(0);
    for (name, def) in &header.elements {
        match name.as_str() {
            "vertex" => {
                verts = Parser::<PlyVertex>::new().read_payload_for_element(rd, def, header)?;
            }
            "face" => {
                let read = Parser::<PlyFace>::new().read_payload_for_element(rd, def, header)?;
                faces = Faces::with_capacity(read.len());
                for (f, e) in read.iter().enumerate() {
                    if !list_i64(e.idx.as_ref(), &mut faces.idx) {
                        faces.not_integers.get_or_insert(f);
                    }
                    faces.start.push(faces.idx.len());
                    faces.label.push(e.label);
                }
            }
            _ => {
                Parser::<Skip>::new().read_payload_for_element(rd, def, header)?;
            }
        }
    }
    Ok((verts, faces))
}

/// The binary payload `payload` (after the header) read in bulk ([`super::ply_binary`]).
fn read_binary(
    payload: &[u8],
    header: &ply_rs_bw::ply::Header,
    big: bool,
    label: Option<&str>,
    face_key: Option<&str>,
) -> std::result::Result<(Vec<PlyVertex>, Faces), String> {
    let mut c = Cursor::new(payload, big);
    let mut verts = Vec::new();
    let mut faces = Faces::with_capacity(0);
    for (name, def) in &header.elements {
        match (name.as_str(), face_key) {
            ("vertex", _) => verts = ply_binary::vertices(&mut c, def, label)?,
            ("face", Some(key)) => faces = ply_binary::faces(&mut c, def, key, label)?,
            _ => ply_binary::skip(&mut c, def)?,
        }
    }
    Ok((verts, faces))
}

/// The scalar properties of an element other than `x, y, z` (label candidates).
fn scalar_props(def: &ElementDef, on_points: bool) -> Vec<ArrayInfo> {
    def.properties
        .values()
        .filter(|p| !(on_points && matches!(p.name.as_str(), "x" | "y" | "z")))
        .filter_map(|p| match &p.data_type {
            PropertyType::Scalar(t) => Some(ArrayInfo::new(
                &p.name,
                on_points,
                &format!("{t:?}").to_ascii_lowercase(),
            )),
            PropertyType::List(..) => None,
        })
        .collect()
}

fn scalar_f64(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => v.into(),
        Property::UChar(v) => v.into(),
        Property::Short(v) => v.into(),
        Property::UShort(v) => v.into(),
        Property::Int(v) => v.into(),
        Property::UInt(v) => v.into(),
        Property::Float(v) => v.into(),
        Property::Double(v) => v,
        _ => return None,
    })
}

fn list_i64(p: Option<&Property>, out: &mut Vec<i64>) -> bool {
    match p {
        Some(Property::ListChar(v)) => out.extend(v.iter().map(|&x| x as i64)),
        Some(Property::ListUChar(v)) => out.extend(v.iter().map(|&x| x as i64)),
        Some(Property::ListShort(v)) => out.extend(v.iter().map(|&x| x as i64)),
        Some(Property::ListUShort(v)) => out.extend(v.iter().map(|&x| x as i64)),
        Some(Property::ListInt(v)) => out.extend(v.iter().map(|&x| x as i64)),
        Some(Property::ListUInt(v)) => out.extend(v.iter().map(|&x| x as i64)),
        _ => return false,
    }
    true
}

/// What [`write_ply`] checks before it writes anything: face indices within the vertices, and
/// property names that are non-empty, without spaces, not `x`/`y`/`z`, used once, each with one
/// value per vertex.
pub(crate) fn check_ply(mesh: &TriMesh, vertex_int_props: &[(&str, &[i32])]) -> Result<()> {
    super::check_mesh_indices(mesh)?;
    for (k, (name, values)) in vertex_int_props.iter().enumerate() {
        let bad_name = name.is_empty() || name.chars().any(|c| c.is_whitespace());
        if bad_name
            || ["x", "y", "z"].contains(name)
            || vertex_int_props[..k].iter().any(|(n, _)| n == name)
        {
            return Err(Error::InvalidArgument(format!(
                "vertex property name {name:?} is empty, has spaces or is used twice"
            )));
        }
        if values.len() != mesh.vertex_count() {
            return Err(Error::InvalidArgument(format!(
                "vertex property {name:?} has {} values for {} vertices",
                values.len(),
                mesh.vertex_count()
            )));
        }
    }
    Ok(())
}

/// Writes a PLY: `x, y, z` as double, one `int` property per entry of `vertex_int_props`, and
/// faces as `vertex_indices` (uchar count, int indices). Written directly (the header is
/// simple and the payload is a flat record per element), read back by `ply-rs-bw` in tests.
pub fn write_ply(
    out: &mut impl Write,
    mesh: &TriMesh,
    vertex_int_props: &[(&str, &[i32])],
    encoding: PlyEncoding,
) -> Result<()> {
    check_ply(mesh, vertex_int_props)?;
    write_checked_ply(out, mesh, vertex_int_props, encoding)
}

/// [`write_ply`] of a mesh and properties [`check_ply`] has passed.
pub(crate) fn write_checked_ply(
    out: &mut impl Write,
    mesh: &TriMesh,
    vertex_int_props: &[(&str, &[i32])],
    encoding: PlyEncoding,
) -> Result<()> {
    let format = match encoding {
        PlyEncoding::BinaryLittleEndian => "binary_little_endian",
        PlyEncoding::BinaryBigEndian => "binary_big_endian",
        PlyEncoding::Ascii => "ascii",
    };
    // Written in chunks of about `CHUNK` bytes: a large mesh is never held twice in memory.
    const CHUNK: usize = 1 << 20;
    let mut b: Vec<u8> = Vec::with_capacity(CHUNK + 4096);
    let io_err = |e: std::io::Error| Error::Io(format!("writing PLY: {e}"));
    let _ = write!(
        b,
        "ply\nformat {format} 1.0\ncomment written by toothfuse (units: mm)\n\
         element vertex {}\nproperty double x\nproperty double y\nproperty double z\n",
        mesh.vertex_count()
    );
    for (name, _) in vertex_int_props {
        let _ = writeln!(b, "property int {name}");
    }
    let _ = write!(
        b,
        "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.face_count()
    );
    let big = encoding == PlyEncoding::BinaryBigEndian;
    let f64b = |v: f64| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let i32b = |v: i32| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    for (i, p) in mesh.positions.iter().enumerate() {
        if encoding == PlyEncoding::Ascii {
            let _ = write!(b, "{} {} {}", p.x, p.y, p.z);
            for (_, v) in vertex_int_props {
                let _ = write!(b, " {}", v[i]);
            }
            b.push(b'\n');
        } else {
            for c in p.to_array() {
                b.extend_from_slice(&f64b(c));
            }
            for (_, v) in vertex_int_props {
                b.extend_from_slice(&i32b(v[i]));
            }
        }
        if b.len() >= CHUNK {
            out.write_all(&b).map_err(io_err)?;
            b.clear();
        }
    }
    for t in &mesh.triangles {
        if encoding == PlyEncoding::Ascii {
            let _ = writeln!(b, "3 {} {} {}", t[0], t[1], t[2]);
        } else {
            b.push(3);
            for &v in t {
                b.extend_from_slice(&i32b(v as i32));
            }
        }
        if b.len() >= CHUNK {
            out.write_all(&b).map_err(io_err)?;
            b.clear();
        }
    }
    out.write_all(&b).map_err(io_err)
}
