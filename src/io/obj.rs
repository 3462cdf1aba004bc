//! Wavefront OBJ (`v` and `f` records) with an optional Teeth3DS label JSON beside it.
//!
//! A small reader of our own rather than `tobj`: `tobj` renumbers vertices by first use in
//! faces (and drops unused ones), which would break Teeth3DS per-vertex labels that follow
//! the file's `v` order. Faces accept `v`, `v/vt`, `v//vn`, `v/vt/vn` and negative (relative)
//! indices; polygons are fan-triangulated; other records (`vt`, `vn`, `g`, `o`, `s`, `usemtl`,
//! `mtllib`, `l`, comments) are ignored.

use super::labels::{ArrayInfo, MeshFile, choose};
use super::{FaceBuilder, check_finite, check_vertex_count, file_err, label_from_f64};
use crate::mesh::{LabeledMesh, TriMesh};
use crate::{Error, Result};
use glam::DVec3;
use std::io::Write;
use std::path::Path;

/// Reads an OBJ, plus per-vertex labels from `<stem>.json` beside it when that file exists
/// (its `labels` array; `label_array`, if given, must name it).
pub(super) fn read_obj_with_labels(
    path: &Path,
    bytes: &[u8],
    label_array: Option<&str>,
) -> Result<MeshFile> {
    let name = path.display().to_string();
    let mesh = read_obj_bytes(&name, bytes)?;
    let json = path.with_extension("json");
    let arrays = if json.is_file() {
        vec![ArrayInfo::new("labels", true, "Teeth3DS JSON")]
    } else {
        Vec::new()
    };
    let chosen = choose(&name, &arrays, label_array)?;
    let vertex_labels = if chosen.is_some() {
        let text =
            std::fs::read(&json).map_err(|e| file_err(&json, format!("cannot read: {e}")))?;
        Some(parse_teeth3ds_labels(
            &json.display().to_string(),
            &text,
            mesh.vertex_count(),
        )?)
    } else {
        None
    };
    Ok(MeshFile {
        mesh: LabeledMesh {
            mesh,
            vertex_labels,
            face_labels: None,
        },
        teeth3ds_json: chosen.is_some(),
        label_array: chosen,
        arrays,
    })
}

/// Reads an OBJ held in memory (`file` names it in error messages) and, when `labels` is
/// given as `(name, bytes)`, its Teeth3DS label JSON (`{"jaw": "upper"|"lower", "labels": [one
/// FDI number per vertex, 0 = gingiva]}`) as per-vertex labels.
pub fn read_obj_labeled_bytes(
    file: &str,
    bytes: &[u8],
    labels: Option<(&str, &[u8])>,
) -> Result<LabeledMesh> {
    let mesh = read_obj_bytes(file, bytes)?;
    let vertex_labels = match labels {
        Some((name, text)) => Some(parse_teeth3ds_labels(name, text, mesh.vertex_count())?),
        None => None,
    };
    Ok(LabeledMesh {
        mesh,
        vertex_labels,
        face_labels: None,
    })
}

/// Reads the geometry of an OBJ held in memory; `file` names it in error messages.
pub(super) fn read_obj_bytes(file: &str, bytes: &[u8]) -> Result<TriMesh> {
    let text = String::from_utf8_lossy(bytes);
    let mut positions = Vec::new();
    let mut polys: Vec<(usize, Vec<i64>)> = Vec::new();
    for (ln, line) in text.lines().enumerate() {
        let ln = ln + 1;
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let mut c = [0.0f64; 3];
                for (k, slot) in c.iter_mut().enumerate() {
                    let tok = it.next().ok_or_else(|| {
                        Error::Io(format!(
                            "{file}: line {ln}: vertex has {k} coordinates (expected `v x y z`)"
                        ))
                    })?;
                    *slot = tok.parse().map_err(|_| {
                        Error::Io(format!(
                            "{file}: line {ln}: {tok:?} is not a number (expected `v x y z`)"
                        ))
                    })?;
                }
                positions.push(DVec3::from_array(c));
            }
            Some("f") => {
                let n_so_far = positions.len() as i64;
                let mut idx = Vec::new();
                for tok in it {
                    let first = tok.split('/').next().unwrap_or("");
                    let i: i64 = first.parse().map_err(|_| {
                        Error::Io(format!(
                            "{file}: line {ln}: face corner {tok:?} does not start with a vertex index"
                        ))
                    })?;
                    // 1-based; negative counts back from the last vertex read so far; 0 is invalid.
                    idx.push(match i {
                        0 => {
                            return Err(Error::Io(format!(
                                "{file}: line {ln}: vertex index 0 (OBJ indices start at 1)"
                            )));
                        }
                        i if i > 0 => i - 1,
                        i => n_so_far + i,
                    });
                }
                polys.push((ln, idx));
            }
            _ => {}
        }
    }
    check_vertex_count(file, positions.len())?;
    check_finite(file, &positions)?;
    let mut fb = FaceBuilder::new(file, positions.len());
    for (ln, idx) in &polys {
        fb.polygon(idx)
            .map_err(|e| Error::Io(format!("{e} (line {ln})")))?;
    }
    Ok(TriMesh::new(positions, fb.triangles))
}

/// Parses a Teeth3DS label file `{"jaw": "upper"|"lower", "labels": [...], "instances": [...]}`
/// and checks it has one label per vertex. Teeth3DS labels are FDI numbers (0 = gingiva).
pub(super) fn parse_teeth3ds_labels(file: &str, text: &[u8], vertices: usize) -> Result<Vec<i32>> {
    let v: serde_json::Value = serde_json::from_slice(text)
        .map_err(|e| Error::Io(format!("{file}: malformed JSON: {e}")))?;
    if let Some(jaw) = v.get("jaw") {
        match jaw.as_str() {
            Some("upper" | "lower") => {}
            _ => {
                return Err(Error::Io(format!(
                    "{file}: \"jaw\" is {jaw}, expected \"upper\" or \"lower\""
                )));
            }
        }
    }
    let labels = v.get("labels").and_then(|l| l.as_array()).ok_or_else(|| {
        Error::Io(format!(
            "{file}: no \"labels\" array (expected {{\"jaw\": ..., \"labels\": [one per vertex]}})"
        ))
    })?;
    if labels.len() != vertices {
        return Err(Error::Io(format!(
            "{file}: {} labels for {vertices} vertices of the OBJ",
            labels.len()
        )));
    }
    labels
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let x = l
                .as_f64()
                .ok_or_else(|| Error::Io(format!("{file}: label {i} is {l}, not a number")))?;
            label_from_f64(x, file, "vertex", i)
        })
        .collect()
}

/// Writes an OBJ (`v x y z` with shortest round-trip decimals, so f64 positions survive
/// exactly; `f a b c` 1-based). No properties.
pub(super) fn write_obj(out: &mut impl Write, mesh: &TriMesh) -> Result<()> {
    super::check_mesh_indices(mesh)?;
    let mut s = String::with_capacity(mesh.vertex_count() * 40 + mesh.face_count() * 24);
    s.push_str("# written by toothfuse (units: mm)\n");
    use std::fmt::Write as _;
    for p in &mesh.positions {
        let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
    }
    for t in &mesh.triangles {
        let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    out.write_all(s.as_bytes())
        .map_err(|e| Error::Io(format!("writing OBJ: {e}")))
}
