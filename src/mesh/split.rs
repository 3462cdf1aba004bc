//! Splitting a labeled jaw mesh into per-tooth submeshes, keeping a map back to input vertices.

use super::TriMesh;
use crate::{Error, Result};
use std::collections::BTreeMap;

/// Where the labels live.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LabelDomain {
    /// One label per vertex; a face belongs to a label when all three of its vertices carry it.
    Vertex,
    /// One label per face.
    Face,
}

/// One label's part of a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct SubMesh {
    /// The label (FDI number, 0 = gingiva).
    pub label: i32,
    /// The part's geometry (only vertices its faces use).
    pub mesh: TriMesh,
    /// For each vertex of `mesh`, its index in the input mesh.
    pub source_vertex: Vec<u32>,
    /// For each face of `mesh`, its index in the input mesh.
    pub source_face: Vec<u32>,
}

/// Splits by per-vertex labels: a face goes to label L when all three vertices are labeled L
/// (faces straddling two labels belong to none, so each tooth's crown ends at the margin).
pub fn split_by_vertex_labels(mesh: &TriMesh, labels: &[i32]) -> Result<BTreeMap<i32, SubMesh>> {
    if labels.len() != mesh.positions.len() {
        return Err(Error::InvalidArgument(format!(
            "{} vertex labels for {} vertices",
            labels.len(),
            mesh.positions.len()
        )));
    }
    let face_labels: Vec<Option<i32>> = mesh
        .triangles
        .iter()
        .map(|t| {
            let l = labels[t[0] as usize];
            (labels[t[1] as usize] == l && labels[t[2] as usize] == l).then_some(l)
        })
        .collect();
    Ok(split_faces(mesh, &face_labels))
}

/// Splits by per-face labels.
pub fn split_by_face_labels(mesh: &TriMesh, labels: &[i32]) -> Result<BTreeMap<i32, SubMesh>> {
    if labels.len() != mesh.triangles.len() {
        return Err(Error::InvalidArgument(format!(
            "{} face labels for {} faces",
            labels.len(),
            mesh.triangles.len()
        )));
    }
    let face_labels: Vec<Option<i32>> = labels.iter().map(|&l| Some(l)).collect();
    Ok(split_faces(mesh, &face_labels))
}

fn split_faces(mesh: &TriMesh, face_labels: &[Option<i32>]) -> BTreeMap<i32, SubMesh> {
    // Faces per label, in face order; labels sorted (a label usually runs over many faces in a
    // row, so the last one is tried first).
    let mut labels: Vec<i32> = Vec::new();
    let mut groups: Vec<Vec<u32>> = Vec::new();
    let mut last: Option<(i32, usize)> = None;
    for (f, l) in face_labels.iter().enumerate() {
        let Some(l) = *l else { continue };
        let g = match last {
            Some((ll, g)) if ll == l => g,
            _ => match labels.binary_search(&l) {
                Ok(g) => g,
                Err(g) => {
                    labels.insert(g, l);
                    groups.insert(g, Vec::new());
                    g
                }
            },
        };
        last = Some((l, g));
        groups[g].push(f as u32);
    }
    // Per label: input vertex → local index in order of first use (one map, reset after each
    // label).
    let mut map = vec![u32::MAX; mesh.positions.len()];
    let mut out = BTreeMap::new();
    for (l, faces) in labels.into_iter().zip(groups) {
        let mut sub = SubMesh {
            label: l,
            mesh: TriMesh::default(),
            source_vertex: Vec::new(),
            source_face: Vec::with_capacity(faces.len()),
        };
        sub.mesh.triangles.reserve(faces.len());
        for f in faces {
            let t = mesh.triangles[f as usize];
            let mut tri = [0u32; 3];
            for (k, &v) in t.iter().enumerate() {
                if map[v as usize] == u32::MAX {
                    map[v as usize] = sub.mesh.positions.len() as u32;
                    sub.mesh.positions.push(mesh.positions[v as usize]);
                    sub.source_vertex.push(v);
                }
                tri[k] = map[v as usize];
            }
            sub.mesh.triangles.push(tri);
            sub.source_face.push(f);
        }
        for &v in &sub.source_vertex {
            map[v as usize] = u32::MAX;
        }
        out.insert(l, sub);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::cube;

    #[test]
    fn face_split_keeps_maps() {
        let m = cube(1.0);
        let labels: Vec<i32> = (0..12).map(|f| if f < 2 { 11 } else { 0 }).collect();
        let parts = split_by_face_labels(&m, &labels).unwrap();
        assert_eq!(parts.len(), 2);
        let p = &parts[&11];
        assert_eq!(p.mesh.triangles.len(), 2);
        assert_eq!(p.source_face, vec![0, 1]);
        for (i, &s) in p.source_vertex.iter().enumerate() {
            assert_eq!(p.mesh.positions[i], m.positions[s as usize]);
        }
        assert_eq!(parts[&0].mesh.triangles.len(), 10);
    }

    #[test]
    fn vertex_split_drops_straddling_faces() {
        let m = cube(1.0);
        // Bottom face vertices 0..3 labeled 21, top 4..7 labeled 0.
        let labels = vec![21, 21, 21, 21, 0, 0, 0, 0];
        let parts = split_by_vertex_labels(&m, &labels).unwrap();
        assert_eq!(parts[&21].mesh.triangles.len(), 2);
        assert_eq!(parts[&0].mesh.triangles.len(), 2);
        assert!(split_by_vertex_labels(&m, &labels[..3]).is_err());
    }
}
