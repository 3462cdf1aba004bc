//! Indexed triangle meshes in f64: construction from caller buffers, validation, topology
//! (edges, boundary loops, components), measures (normals, volume) and label splitting.

mod boundary;
mod buffers;
mod fan_pass;
mod hole_cap;
mod measure;
#[cfg(test)]
mod reference_tests;
mod repair;
mod repaired;
mod split;
mod topology;
mod validate;
mod vertex_sort;

pub use buffers::{Scalar, VertexBuffer};
pub use repair::{RepairOptions, RepairReport, repair_open_surface};
pub(crate) use repaired::{TakenAway, is_repaired, repair_taken, taken_away, without_faces};
pub use split::{LabelDomain, SubMesh, split_by_face_labels, split_by_vertex_labels};
pub use topology::{EdgeTopology, boundary_loops, boundary_loops_of, connected_components};
pub use validate::{ValidateOptions, ValidationReport, non_manifold_vertices};

use glam::DVec3;

/// A face's corners in ascending order: the key of its vertex set, whatever its orientation.
pub(crate) fn sorted_corners(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// An indexed triangle mesh: positions in millimetres (f64), counter-clockwise triangles seen
/// from outside.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Triangles as three vertex indices.
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Builds a mesh from owned parts without checking anything; see [`TriMesh::validate`].
    pub fn new(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Self {
        Self {
            positions,
            triangles,
        }
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn face_count(&self) -> usize {
        self.triangles.len()
    }

    /// The three corner positions of triangle `f`.
    #[inline]
    pub fn corners(&self, f: usize) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[f];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Applies a rigid transform to every vertex.
    pub fn transform(&mut self, t: &crate::Rigid) {
        for p in &mut self.positions {
            *p = t.apply(*p);
        }
    }

    /// A transformed copy.
    pub fn transformed(&self, t: &crate::Rigid) -> TriMesh {
        let mut m = self.clone();
        m.transform(t);
        m
    }

    /// Appends another mesh (indices shifted); returns the vertex offset of `other`.
    pub fn append(&mut self, other: &TriMesh) -> u32 {
        let off = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.triangles.extend(
            other
                .triangles
                .iter()
                .map(|t| [t[0] + off, t[1] + off, t[2] + off]),
        );
        off
    }

    /// Drops vertices no triangle uses; returns the map old index → new index (`u32::MAX` for dropped).
    pub fn compact(&mut self) -> Vec<u32> {
        let mut used = vec![false; self.positions.len()];
        for t in &self.triangles {
            for &v in t {
                used[v as usize] = true;
            }
        }
        let mut map = vec![u32::MAX; self.positions.len()];
        let mut next = 0u32;
        let mut pos = Vec::with_capacity(self.positions.len());
        for (i, &u) in used.iter().enumerate() {
            if u {
                map[i] = next;
                next += 1;
                pos.push(self.positions[i]);
            }
        }
        for t in &mut self.triangles {
            for v in t.iter_mut() {
                *v = map[*v as usize];
            }
        }
        self.positions = pos;
        map
    }
}

/// A mesh with optional per-vertex or per-face integer labels (FDI numbers, 0 = gingiva).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LabeledMesh {
    /// The geometry.
    pub mesh: TriMesh,
    /// One label per vertex, if the source had them.
    pub vertex_labels: Option<Vec<i32>>,
    /// One label per face, if the source had them.
    pub face_labels: Option<Vec<i32>>,
}

#[cfg(test)]
pub(crate) mod fixtures {
    //! Tiny hand-made meshes for tests.
    use super::TriMesh;
    use glam::DVec3;

    /// A unit tetrahedron, outward-oriented.
    pub fn tetrahedron() -> TriMesh {
        TriMesh::new(
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
                DVec3::new(0.0, 0.0, 1.0),
            ],
            vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        )
    }

    /// An axis-aligned cube [0,s]^3 of 12 triangles, outward-oriented.
    pub fn cube(s: f64) -> TriMesh {
        let p = |x: f64, y: f64, z: f64| DVec3::new(x * s, y * s, z * s);
        TriMesh::new(
            vec![
                p(0., 0., 0.),
                p(1., 0., 0.),
                p(1., 1., 0.),
                p(0., 1., 0.),
                p(0., 0., 1.),
                p(1., 0., 1.),
                p(1., 1., 1.),
                p(0., 1., 1.),
            ],
            vec![
                [0, 2, 1],
                [0, 3, 2],
                [4, 5, 6],
                [4, 6, 7],
                [0, 1, 5],
                [0, 5, 4],
                [1, 2, 6],
                [1, 6, 5],
                [2, 3, 7],
                [2, 7, 6],
                [3, 0, 4],
                [3, 4, 7],
            ],
        )
    }

    /// A closed, outward-oriented ellipsoid with semi-axes `(r, r, c)` about the origin: `rings`
    /// latitude rings of `segments` vertices each between the two poles (the last two
    /// vertices), the rings from the south pole up.
    pub fn ellipsoid(rings: u32, segments: u32, r: f64, c: f64) -> TriMesh {
        let mut positions = Vec::new();
        for i in 0..rings {
            let lat = std::f64::consts::PI * ((i + 1) as f64 / (rings + 1) as f64 - 0.5);
            for j in 0..segments {
                let lon = std::f64::consts::TAU * j as f64 / segments as f64;
                positions.push(DVec3::new(
                    r * lat.cos() * lon.cos(),
                    r * lat.cos() * lon.sin(),
                    c * lat.sin(),
                ));
            }
        }
        let (south, north) = (rings * segments, rings * segments + 1);
        positions.push(DVec3::new(0.0, 0.0, -c));
        positions.push(DVec3::new(0.0, 0.0, c));
        let at = |i: u32, j: u32| i * segments + j % segments;
        let mut triangles = Vec::new();
        for j in 0..segments {
            triangles.push([south, at(0, j + 1), at(0, j)]);
            triangles.push([north, at(rings - 1, j), at(rings - 1, j + 1)]);
            for i in 0..rings - 1 {
                triangles.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
                triangles.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
            }
        }
        TriMesh::new(positions, triangles)
    }

    /// A square of 2 triangles in the z=0 plane (one boundary loop of 4 vertices).
    pub fn square() -> TriMesh {
        TriMesh::new(
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }
}
