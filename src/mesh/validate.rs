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
        self.check_elements(opts)?;
        let topo = EdgeTopology::new(self);
        let (report, first_non_manifold) = self.report_of(&topo);
        self.check_topology(opts, &topo, &report, first_non_manifold)?;
        Ok(report)
    }

    /// [`TriMesh::validate`] without the report's components and loops, returning the edge
    /// topology it built (for callers that need it next, e.g. face adjacency): the same
    /// errors, in the same order.
    pub(crate) fn validate_into_topology(&self, opts: &ValidateOptions) -> Result<EdgeTopology> {
        self.check_elements(opts)?;
        let topo = EdgeTopology::new(self);
        let c = super::fan_pass::fan_counts(self, &topo, false);
        let counts = ValidationReport {
            boundary_edges: c.boundary_edges,
            non_manifold_edges: c.non_manifold_edges,
            non_manifold_vertices: c.non_manifold_vertices.len(),
            ..Default::default()
        };
        let first_non_manifold = c.non_manifold_vertices.first().copied();
        self.check_topology(opts, &topo, &counts, first_non_manifold)?;
        Ok(topo)
    }

    /// The per-element checks of [`TriMesh::validate`]: finite positions, indices in range,
    /// no degenerate or duplicate face.
    fn check_elements(&self, opts: &ValidateOptions) -> Result<()> {
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
        super::vertex_sort::sort_by_vertex(&mut keyed, n, |k| k.0[0]);
        if let Some(w) = keyed.windows(2).find(|w| w[0].0 == w[1].0) {
            return Err(Error::DuplicateFace {
                face: w[1].1,
                first: w[0].1,
            });
        }
        Ok(())
    }

    /// The topological checks of [`TriMesh::validate`] from the counts in `report` and the
    /// lowest non-manifold vertex the counting found.
    fn check_topology(
        &self,
        opts: &ValidateOptions,
        topo: &EdgeTopology,
        report: &ValidationReport,
        first_non_manifold: Option<u32>,
    ) -> Result<()> {
        if report.non_manifold_edges > 0 {
            for (a, b, c) in topo.undirected_edges() {
                let same_dir = topo.faces_of_directed(a, b).count() > 1
                    || topo.faces_of_directed(b, a).count() > 1;
                if c > 2 || same_dir {
                    return Err(Error::NonManifoldEdge { a, b, faces: c });
                }
            }
        }
        if let Some(v) = first_non_manifold {
            return Err(Error::NonManifoldVertex { vertex: v as usize });
        }
        if opts.require_closed && report.boundary_edges > 0 {
            return Err(Error::NotClosed {
                boundary_edges: report.boundary_edges,
            });
        }
        Ok(())
    }

    /// Counts boundary/non-manifold edges and vertices, components and loops without failing.
    pub fn topology_report(&self) -> ValidationReport {
        self.topology_report_of(&EdgeTopology::new(self))
    }

    /// [`TriMesh::topology_report`] from an already built topology of this mesh.
    pub fn topology_report_of(&self, topo: &EdgeTopology) -> ValidationReport {
        self.report_of(topo).0
    }

    /// [`TriMesh::topology_report_of`] and the lowest non-manifold vertex (the one
    /// [`TriMesh::validate`] names).
    fn report_of(&self, topo: &EdgeTopology) -> (ValidationReport, Option<u32>) {
        let c = super::fan_pass::fan_counts(self, topo, true);
        // Without non-manifold edges, a boundary half-edge (no reverse partner) is exactly a
        // boundary edge: no boundary edge, no loop.
        let loops = if c.non_manifold_edges == 0 && c.boundary_edges > 0 {
            super::topology::boundary_loops_of(topo).len()
        } else {
            0
        };
        let report = ValidationReport {
            vertices: self.positions.len(),
            faces: self.triangles.len(),
            boundary_edges: c.boundary_edges,
            non_manifold_edges: c.non_manifold_edges,
            non_manifold_vertices: c.non_manifold_vertices.len(),
            unused_vertices: c.unused_vertices,
            components: c.components.unwrap_or_default(),
            boundary_loops: loops,
        };
        (report, c.non_manifold_vertices.first().copied())
    }
}

/// Vertices whose incident faces form more than one edge-connected fan, sorted.
pub fn non_manifold_vertices(mesh: &TriMesh) -> Vec<u32> {
    non_manifold_vertices_of(mesh, &EdgeTopology::new(mesh))
}

/// [`non_manifold_vertices`] from an already built topology of `mesh`.
pub fn non_manifold_vertices_of(mesh: &TriMesh, topo: &EdgeTopology) -> Vec<u32> {
    let mut scratch = FanScratch::default();
    (0..mesh.positions.len() as u32)
        .filter(|&v| {
            let block = topo.leaving(v);
            !block.is_empty() && !scratch.one_fan(mesh, v, block)
        })
        .collect()
}

/// Reusable buffers of [`FanScratch::one_fan`], so that testing many vertices allocates once.
#[derive(Default)]
pub(crate) struct FanScratch {
    prev: Vec<u32>,
    parent: Vec<usize>,
    nb: Vec<(u32, usize)>,
}

impl FanScratch {
    /// Whether the corners `block` of vertex `v` (its leaving half-edges `v → next` of faces of
    /// `mesh`, sorted by `next`, not empty) form one edge-connected fan. A corner's face `f`
    /// has `prev` as its third corner; two corners are in one fan when they share a neighbour
    /// vertex (an edge through `v`), transitively.
    pub(crate) fn one_fan(&mut self, mesh: &TriMesh, v: u32, block: &[(u32, u32, u32)]) -> bool {
        let mut prev = std::mem::take(&mut self.prev);
        third_corners(mesh, v, block, &mut prev);
        let one = one_cycle(block, &prev) || self.fans_joined(block, &prev);
        self.prev = prev;
        one
    }

    /// The general case of [`FanScratch::one_fan`], given the corners' third corners `prev`:
    /// whether the corners that share a neighbour vertex, joined, make one set.
    pub(crate) fn fans_joined(&mut self, block: &[(u32, u32, u32)], prev: &[u32]) -> bool {
        let (parent, nb) = (&mut self.parent, &mut self.nb);
        let m = block.len();
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
        for (idx, (&(_, next, _), &pv)) in block.iter().zip(prev.iter()).enumerate() {
            nb.push((next, idx));
            nb.push((pv, idx));
        }
        nb.sort_unstable();
        for w in nb.windows(2) {
            if w[0].0 == w[1].0 {
                let (a, b) = (find(parent, w[0].1), find(parent, w[1].1));
                parent[a.max(b)] = a.min(b);
            }
        }
        (0..m).filter(|&x| find(parent, x) == x).count() == 1
    }
}

/// The third corner of each corner of `v` in `block` (its half-edges `v → b` of face `f`), into
/// `out`: the half-edge is `t[k] → t[k + 1]` for some k, so the third corner `t[k + 2]` is the
/// exclusive or of all three with both ends (whatever corners repeat).
pub(super) fn third_corners(mesh: &TriMesh, v: u32, block: &[(u32, u32, u32)], out: &mut Vec<u32>) {
    out.clear();
    out.extend(block.iter().map(|&(_, b, f)| {
        let t = mesh.triangles[f as usize];
        t[0] ^ t[1] ^ t[2] ^ v ^ b
    }));
}

/// A sufficient test that a vertex's corners form one fan: following each corner to the corner
/// whose `next` is its `prev` (they share that edge) visits all of them in one cycle. `block` is
/// sorted by `next`; any other shape (a boundary fan, a repeated `next`) answers false and is
/// decided by the general union.
pub(super) fn one_cycle(block: &[(u32, u32, u32)], prev: &[u32]) -> bool {
    let m = block.len();
    if block.windows(2).any(|w| w[0].1 == w[1].1) {
        return false;
    }
    let mut cur = 0usize;
    for step in 1..=m {
        let p = prev[cur];
        // The first corner whose `next` is not below `p`: a branch-free count over a vertex's
        // usual handful of corners, a binary search over a large fan.
        let j = if m <= 16 {
            block.iter().filter(|e| e.1 < p).count()
        } else {
            block.partition_point(|e| e.1 < p)
        };
        if j >= m || block[j].1 != p {
            return false;
        }
        cur = j;
        if cur == 0 {
            return step == m;
        }
    }
    false
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

    /// Per vertex, whether its corners (taken from the faces directly) fall into more than one
    /// fan of corners sharing a neighbour vertex: the definition, without the topology.
    fn non_manifold_by_definition(mesh: &TriMesh) -> Vec<u32> {
        let mut out = Vec::new();
        for v in 0..mesh.positions.len() as u32 {
            let corners: Vec<[u32; 2]> = mesh
                .triangles
                .iter()
                .flat_map(|t| {
                    (0..3)
                        .filter(move |&k| t[k] == v)
                        .map(move |k| [t[(k + 1) % 3], t[(k + 2) % 3]])
                })
                .collect();
            let mut fan: Vec<usize> = (0..corners.len()).collect();
            let mut changed = true;
            while changed {
                changed = false;
                for i in 0..corners.len() {
                    for j in 0..corners.len() {
                        let shared = corners[i].iter().any(|x| corners[j].contains(x));
                        if shared && fan[j] > fan[i] {
                            fan[j] = fan[i];
                            changed = true;
                        }
                    }
                }
            }
            let mut roots = fan.clone();
            roots.sort_unstable();
            roots.dedup();
            if roots.len() > 1 {
                out.push(v);
            }
        }
        out
    }

    /// The non-manifold vertices from the topology are those of the definition, on random face
    /// lists (repeated, reversed, degenerate and duplicate faces) and on closed meshes.
    #[test]
    fn non_manifold_vertices_match_the_definition() {
        let mut rng = crate::phantom::rng::Rng::new(13);
        for n in [3u32, 5, 12, 40] {
            for faces in [1usize, 4, 20, 80] {
                let triangles = crate::mesh::topology::tests::random_faces(&mut rng, n, faces);
                let mesh = TriMesh::new(vec![DVec3::ZERO; n as usize + 1], triangles);
                assert_eq!(
                    non_manifold_vertices(&mesh),
                    non_manifold_by_definition(&mesh),
                    "{:?}",
                    mesh.triangles
                );
            }
        }
        for mesh in [cube(1.0), tetrahedron()] {
            assert!(non_manifold_vertices(&mesh).is_empty());
            assert!(non_manifold_by_definition(&mesh).is_empty());
        }
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
