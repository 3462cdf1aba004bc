//! Mesh validation: finite coordinates, index range, degenerate and duplicate faces,
//! non-manifold edges and vertices, closedness. Every error names the vertex/face at fault.

use super::TriMesh;
use super::topology::EdgeTopology;
use crate::{Error, Result};

/// What [`TriMesh::validate`] requires beyond the basic checks.
#[derive(Clone, Copy, Debug, Default)]
pub struct ValidateOptions {
    /// Require a closed surface (every edge in exactly two faces).
    pub require_closed: bool,
    /// Allow zero-area (but index-distinct) triangles instead of rejecting them.
    pub allow_zero_area: bool,
}

/// Topological facts about a mesh that passed the basic checks.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ValidationReport {
    /// Vertices.
    pub vertices: usize,
    /// Triangles.
    pub faces: usize,
    /// Edges used by exactly one face.
    pub boundary_edges: usize,
    /// Edges used by more than two faces or twice in one direction.
    pub non_manifold_edges: usize,
    /// Vertices whose faces form more than one fan.
    pub non_manifold_vertices: usize,
    /// Vertices used by no face.
    pub unused_vertices: usize,
    /// Connected components (by shared edges).
    pub components: usize,
    /// Ordered boundary loops.
    pub boundary_loops: usize,
}

impl ValidationReport {
    /// Closed and manifold: no boundary, no non-manifold edge or vertex.
    pub fn is_closed_manifold(&self) -> bool {
        self.boundary_edges == 0 && self.non_manifold_edges == 0 && self.non_manifold_vertices == 0
    }
}

impl TriMesh {
    /// Checks the mesh and returns the first problem found, naming the vertex or face.
    /// Order: non-finite vertex, index out of range, degenerate face, duplicate face,
    /// non-manifold edge, non-manifold vertex, then (if required) not closed.
    pub fn validate(&self, opts: &ValidateOptions) -> Result<ValidationReport> {
        let n = self.positions.len();
        if let Some(v) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(Error::NonFinite { vertex: v });
        }
        for (f, t) in self.triangles.iter().enumerate() {
            if let Some(&bad) = t.iter().find(|&&v| v as usize >= n) {
                return Err(Error::IndexOutOfBounds {
                    face: f,
                    index: bad,
                    vertex_count: n,
                });
            }
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return Err(Error::DegenerateFace { face: f });
            }
            if !opts.allow_zero_area {
                let [a, b, c] = self.corners(f);
                if (b - a).cross(c - a).length_squared() == 0.0 {
                    return Err(Error::DegenerateFace { face: f });
                }
            }
        }
        // Duplicate faces: same vertex set.
        let mut keyed: Vec<([u32; 3], usize)> = self
            .triangles
            .iter()
            .enumerate()
            .map(|(f, t)| {
                let mut k = *t;
                k.sort_unstable();
                (k, f)
            })
            .collect();
        keyed.sort_unstable();
        if let Some(w) = keyed.windows(2).find(|w| w[0].0 == w[1].0) {
            return Err(Error::DuplicateFace {
                face: w[1].1,
                first: w[0].1,
            });
        }
        let report = self.topology_report();
        if report.non_manifold_edges > 0 {
            let topo = EdgeTopology::new(self);
            for (a, b, c) in topo.undirected_edges() {
                let same_dir = topo.faces_of_directed(a, b).count() > 1
                    || topo.faces_of_directed(b, a).count() > 1;
                if c > 2 || same_dir {
                    return Err(Error::NonManifoldEdge { a, b, faces: c });
                }
            }
        }
        if report.non_manifold_vertices > 0
            && let Some(v) = non_manifold_vertices(self).first()
        {
            return Err(Error::NonManifoldVertex {
                vertex: *v as usize,
            });
        }
        if opts.require_closed && report.boundary_edges > 0 {
            return Err(Error::NotClosed {
                boundary_edges: report.boundary_edges,
            });
        }
        Ok(report)
    }

    /// Counts boundary/non-manifold edges and vertices, components and loops without failing.
    pub fn topology_report(&self) -> ValidationReport {
        let topo = EdgeTopology::new(self);
        let mut boundary_edges = 0;
        let mut non_manifold_edges = 0;
        for (a, b, c) in topo.undirected_edges() {
            let same_dir = topo.faces_of_directed(a, b).count() > 1
                || topo.faces_of_directed(b, a).count() > 1;
            if c == 1 {
                boundary_edges += 1;
            } else if c > 2 || same_dir {
                non_manifold_edges += 1;
            }
        }
        let mut used = vec![false; self.positions.len()];
        for t in &self.triangles {
            for &v in t {
                if let Some(u) = used.get_mut(v as usize) {
                    *u = true;
                }
            }
        }
        let (_, components) = super::topology::connected_components_of(&topo, self.triangles.len());
        let loops = if non_manifold_edges == 0 {
            super::topology::boundary_loops_of(&topo).len()
        } else {
            0
        };
        ValidationReport {
            vertices: self.positions.len(),
            faces: self.triangles.len(),
            boundary_edges,
            non_manifold_edges,
            non_manifold_vertices: non_manifold_vertices(self).len(),
            unused_vertices: used.iter().filter(|u| !**u).count(),
            components,
            boundary_loops: loops,
        }
    }
}

/// Vertices whose incident faces form more than one edge-connected fan, sorted.
pub fn non_manifold_vertices(mesh: &TriMesh) -> Vec<u32> {
    let n = mesh.positions.len();
    // Corners grouped by vertex (counting sort; faces in order within a vertex):
    // (vertex, face, the two other vertices).
    let mut start = vec![0usize; n + 1];
    for t in &mesh.triangles {
        for &v in t {
            if (v as usize) < n {
                start[v as usize + 1] += 1;
            }
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut corners: Vec<(u32, u32, u32, u32)> = vec![(0, 0, 0, 0); start[n]];
    for (f, t) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let v = t[k] as usize;
            if v < n {
                corners[start[v]] = (t[k], f as u32, t[(k + 1) % 3], t[(k + 2) % 3]);
                start[v] += 1;
            }
        }
    }
    let mut out = Vec::new();
    let mut parent: Vec<usize> = Vec::new();
    let mut nb: Vec<(u32, usize)> = Vec::new();
    let mut i = 0;
    while i < corners.len() {
        let v = corners[i].0;
        let mut j = i;
        while j < corners.len() && corners[j].0 == v {
            j += 1;
        }
        let fan = &corners[i..j];
        // Union faces of the fan that share a neighbour vertex (= share an edge through v).
        let m = fan.len();
        parent.clear();
        parent.extend(0..m);
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        nb.clear();
        for (idx, c) in fan.iter().enumerate() {
            nb.push((c.2, idx));
            nb.push((c.3, idx));
        }
        nb.sort_unstable();
        for w in nb.windows(2) {
            if w[0].0 == w[1].0 {
                let (a, b) = (find(&mut parent, w[0].1), find(&mut parent, w[1].1));
                parent[a.max(b)] = a.min(b);
            }
        }
        let roots = (0..m).filter(|&x| find(&mut parent, x) == x).count();
        if roots > 1 {
            out.push(v);
        }
        i = j;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{cube, square, tetrahedron};
    use glam::DVec3;

    #[test]
    fn valid_closed_meshes_pass() {
        let r = cube(1.0)
            .validate(&ValidateOptions {
                require_closed: true,
                ..Default::default()
            })
            .unwrap();
        assert!(r.is_closed_manifold());
        assert_eq!(r.components, 1);
        assert_eq!(r.boundary_loops, 0);
        tetrahedron().validate(&ValidateOptions::default()).unwrap();
    }

    #[test]
    fn open_mesh_fails_only_when_closed_required() {
        let sq = square();
        let r = sq.validate(&ValidateOptions::default()).unwrap();
        assert_eq!(r.boundary_edges, 4);
        assert_eq!(r.boundary_loops, 1);
        assert_eq!(
            sq.validate(&ValidateOptions {
                require_closed: true,
                ..Default::default()
            }),
            Err(Error::NotClosed { boundary_edges: 4 })
        );
    }

    #[test]
    fn names_the_faulty_element() {
        let mut m = cube(1.0);
        m.positions[5].y = f64::NAN;
        assert_eq!(
            m.validate(&Default::default()),
            Err(Error::NonFinite { vertex: 5 })
        );

        let mut m = cube(1.0);
        m.triangles[3] = [4, 4, 7];
        assert_eq!(
            m.validate(&Default::default()),
            Err(Error::DegenerateFace { face: 3 })
        );

        let mut m = cube(1.0);
        m.triangles.push([2, 1, 0]);
        assert_eq!(
            m.validate(&Default::default()),
            Err(Error::DuplicateFace { face: 12, first: 0 })
        );

        let mut m = cube(1.0);
        m.triangles[7] = [1, 6, 99];
        assert!(matches!(
            m.validate(&Default::default()),
            Err(Error::IndexOutOfBounds {
                face: 7,
                index: 99,
                ..
            })
        ));

        // Collinear corners: zero area.
        let mut m = square();
        m.positions[2] = DVec3::new(2.0, 0.0, 0.0);
        assert_eq!(
            m.validate(&Default::default()),
            Err(Error::DegenerateFace { face: 0 })
        );
    }

    #[test]
    fn detects_non_manifold_edge_and_bow_tie_vertex() {
        // Three triangles on one edge (0,1).
        let m = TriMesh::new(
            vec![
                DVec3::ZERO,
                DVec3::X,
                DVec3::Y,
                DVec3::new(0.0, -1.0, 0.0),
                DVec3::Z,
            ],
            vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
        );
        assert!(matches!(
            m.validate(&Default::default()),
            Err(Error::NonManifoldEdge {
                a: 0,
                b: 1,
                faces: 3
            })
        ));
        // Two triangles touching at vertex 0 only.
        let m = TriMesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, -DVec3::X, -DVec3::Y],
            vec![[0, 1, 2], [0, 3, 4]],
        );
        assert_eq!(
            m.validate(&Default::default()),
            Err(Error::NonManifoldVertex { vertex: 0 })
        );
    }
}
