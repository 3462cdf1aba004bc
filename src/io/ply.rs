//! PLY (Stanford polygon format), ASCII and binary, through the `ply-rs-bw` crate.
//!
//! Read: `vertex` element with `x, y, z` (any scalar type), optional per-vertex label property
//! (see [`super::label_rank`]; any numeric type); `face` element with `vertex_indices` or
//! `vertex_index` (a list of any integer type, fan-triangulated) and an optional face label.
//! Write: `x, y, z` as double (lossless) plus `int` vertex properties.

use super::{
    FaceBuilder, PlyEncoding, check_finite, check_vertex_count, label_from_f64, label_rank,
};
use crate::mesh::{LabeledMesh, TriMesh};
use crate::{Error, Result};
use glam::DVec3;
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{
    DefaultElement, ElementDef, Encoding, Ply, Property, PropertyDef, PropertyType, ScalarType,
};
use ply_rs_bw::writer::Writer;
use std::io::Write;

/// Reads a PLY file held in memory; `file` names it in error messages.
pub fn read_ply_bytes(file: &str, bytes: &[u8]) -> Result<LabeledMesh> {
    let parser = Parser::<DefaultElement>::new();
    let mut src = bytes;
    let ply = parser
        .read_ply(&mut src)
        .map_err(|e| Error::Io(format!("{file}: malformed PLY: {e}")))?;
    let err = |m: String| Error::Io(format!("{file}: {m}"));

    let vdef = ply
        .header
        .elements
        .get("vertex")
        .ok_or_else(|| err("no `vertex` element in the header".into()))?;
    for c in ["x", "y", "z"] {
        match vdef.properties.get(c).map(|p| &p.data_type) {
            Some(PropertyType::Scalar(_)) => {}
            _ => return Err(err(format!("vertex property `{c}` missing or a list"))),
        }
    }
    let vlabel_name = best_label(vdef);
    let verts = ply.payload.get("vertex").map(Vec::as_slice).unwrap_or(&[]);
    check_vertex_count(file, verts.len())?;
    let mut positions = Vec::with_capacity(verts.len());
    let mut vlabels = vlabel_name
        .as_ref()
        .map(|_| Vec::with_capacity(verts.len()));
    for (i, v) in verts.iter().enumerate() {
        let c = |k: &str| v.get(k).and_then(scalar_f64);
        let (Some(x), Some(y), Some(z)) = (c("x"), c("y"), c("z")) else {
            return Err(err(format!("vertex {i} lacks a numeric x, y or z")));
        };
        positions.push(DVec3::new(x, y, z));
        if let (Some(name), Some(out)) = (&vlabel_name, vlabels.as_mut()) {
            let l = v
                .get(name.as_str())
                .and_then(scalar_f64)
                .unwrap_or(f64::NAN);
            out.push(label_from_f64(l, file, "vertex", i)?);
        }
    }
    check_finite(file, &positions)?;

    let mut fb = FaceBuilder::new(file, positions.len());
    let mut face_labels = None;
    if let Some(fdef) = ply.header.elements.get("face") {
        let key = ["vertex_indices", "vertex_index"]
            .into_iter()
            .find(|k| fdef.properties.contains_key(*k))
            .ok_or_else(|| {
                err("face element has neither `vertex_indices` nor `vertex_index`".into())
            })?;
        let flabel_name = best_label(fdef);
        let faces = ply.payload.get("face").map(Vec::as_slice).unwrap_or(&[]);
        let mut plabels = Vec::new();
        let mut idx = Vec::new();
        for (f, e) in faces.iter().enumerate() {
            idx.clear();
            if !list_i64(e.get(key), &mut idx) {
                return Err(err(format!("face {f}: `{key}` is not a list of integers")));
            }
            fb.polygon(&idx)?;
            if let Some(name) = &flabel_name {
                let l = e
                    .get(name.as_str())
                    .and_then(scalar_f64)
                    .unwrap_or(f64::NAN);
                plabels.push(label_from_f64(l, file, "face", f)?);
            }
        }
        if flabel_name.is_some() {
            face_labels = Some(
                fb.source_poly
                    .iter()
                    .map(|&p| plabels[p as usize])
                    .collect(),
            );
        }
    }
    Ok(LabeledMesh {
        mesh: TriMesh::new(positions, fb.triangles),
        vertex_labels: vlabels,
        face_labels,
    })
}

/// The best label property of an element (scalar only).
fn best_label(def: &ElementDef) -> Option<String> {
    def.properties
        .values()
        .filter(|p| matches!(p.data_type, PropertyType::Scalar(_)))
        .filter_map(|p| label_rank(&p.name).map(|r| (r, p.name.clone())))
        .min_by_key(|(r, _)| *r)
        .map(|(_, n)| n)
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

/// Writes a PLY: `x, y, z` as double, one `int` property per entry of `vertex_int_props`, and
/// faces as `vertex_indices` (uchar count, int indices).
pub fn write_ply(
    out: &mut impl Write,
    mesh: &TriMesh,
    vertex_int_props: &[(&str, &[i32])],
    encoding: PlyEncoding,
) -> Result<()> {
    super::check_mesh_indices(mesh)?;
    let mut ply = Ply::<DefaultElement>::new();
    ply.header.encoding = match encoding {
        PlyEncoding::BinaryLittleEndian => Encoding::BinaryLittleEndian,
        PlyEncoding::BinaryBigEndian => Encoding::BinaryBigEndian,
        PlyEncoding::Ascii => Encoding::Ascii,
    };
    ply.header
        .comments
        .push("written by toothfuse (units: mm)".into());
    let mut vdef = ElementDef::new("vertex".into());
    vdef.count = mesh.vertex_count();
    for c in ["x", "y", "z"] {
        add_prop(&mut vdef, c, PropertyType::Scalar(ScalarType::Double));
    }
    for (name, values) in vertex_int_props {
        if ["x", "y", "z"].contains(name) || vdef.properties.contains_key(*name) {
            return Err(Error::InvalidArgument(format!(
                "vertex property name {name:?} is used twice"
            )));
        }
        if values.len() != mesh.vertex_count() {
            return Err(Error::InvalidArgument(format!(
                "vertex property {name:?} has {} values for {} vertices",
                values.len(),
                mesh.vertex_count()
            )));
        }
        add_prop(&mut vdef, name, PropertyType::Scalar(ScalarType::Int));
    }
    let mut fdef = ElementDef::new("face".into());
    fdef.count = mesh.face_count();
    add_prop(
        &mut fdef,
        "vertex_indices",
        PropertyType::List(ScalarType::UChar, ScalarType::Int),
    );
    ply.header.elements.insert("vertex".into(), vdef);
    ply.header.elements.insert("face".into(), fdef);

    let verts = mesh
        .positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut e = DefaultElement::new();
            e.insert("x".into(), Property::Double(p.x));
            e.insert("y".into(), Property::Double(p.y));
            e.insert("z".into(), Property::Double(p.z));
            for (name, values) in vertex_int_props {
                e.insert((*name).to_string(), Property::Int(values[i]));
            }
            e
        })
        .collect();
    let faces = mesh
        .triangles
        .iter()
        .map(|t| {
            let mut e = DefaultElement::new();
            e.insert(
                "vertex_indices".into(),
                Property::ListInt(t.iter().map(|&v| v as i32).collect()),
            );
            e
        })
        .collect();
    ply.payload.insert("vertex".into(), verts);
    ply.payload.insert("face".into(), faces);
    Writer::new()
        .write_ply(out, &mut ply)
        .map_err(|e| Error::Io(format!("writing PLY: {e}")))?;
    Ok(())
}

fn add_prop(def: &mut ElementDef, name: &str, t: PropertyType) {
    def.properties
        .insert(name.to_string(), PropertyDef::new(name.to_string(), t));
}
