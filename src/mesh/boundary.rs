//! A mesh's boundary half-edges from its face corners alone, for the boundary loops of a mesh
//! whose other topology is not needed (one counting sort of the corners instead of the full
//! half-edge structure's two and the reversed list's one).
//!
//! The half-edge `p → v` of a face is its corner at `v` whose previous corner is `p` (a
//! bijection between half-edges and corners, degenerate faces included), so `v → b` has a
//! partner `b → v` exactly when some corner at `v` has `b` as its previous corner: each vertex's
//! own corners decide its outgoing boundary half-edges.

use super::topology::{origin_offsets, placed_by};

/// Directed boundary half-edges `a → b` (present with no `b → a`), sorted by `(a, b)`, repeats
/// kept: bitwise [`super::EdgeTopology::boundary_half_edges`] of the same faces.
pub(super) fn boundary_half_edges(triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let offsets = origin_offsets(triangles.iter().flatten().copied());
    // Per corner: (vertex, next corner, previous corner), grouped by vertex.
    let corners = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3], t[(k + 2) % 3])));
    let placed = placed_by(corners, &offsets, |c| c.0);
    let mut out = Vec::new();
    let mut run: Vec<(u32, u32)> = Vec::new();
    for w in offsets.windows(2) {
        let block = &placed[w[0] as usize..w[1] as usize];
        run.clear();
        run.extend(
            block
                .iter()
                .filter(|c| !block.iter().any(|d| d.2 == c.1))
                .map(|c| (c.0, c.1)),
        );
        run.sort_unstable();
        out.extend_from_slice(&run);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{cube, ellipsoid, square, tetrahedron};
    use crate::mesh::topology::tests::random_faces;
    use crate::mesh::{EdgeTopology, TriMesh, boundary_loops, boundary_loops_of};

    /// The corners' answer equals the half-edge structure's, and so do the loops, on random
    /// face lists (repeated, reversed, degenerate and duplicate faces, unused vertices, faces
    /// indexing past the vertices) and on closed and open fixtures, one face removed or not.
    #[test]
    fn corner_boundary_equals_the_half_edge_structure() {
        let mut rng = crate::phantom::rng::Rng::new(11);
        let mut meshes: Vec<TriMesh> = vec![
            cube(1.0),
            ellipsoid(12, 8, 3.0, 5.0),
            square(),
            tetrahedron(),
        ];
        for m in meshes.clone() {
            for f in [0, m.triangles.len() / 2] {
                let mut cut = m.clone();
                cut.triangles.remove(f);
                meshes.push(cut);
            }
        }
        for n in [1u32, 2, 3, 7, 40, 200] {
            for faces in [0usize, 1, 5, 60, 300] {
                let triangles = random_faces(&mut rng, n, faces);
                meshes.push(TriMesh::new(
                    vec![glam::DVec3::ZERO; n as usize / 2],
                    triangles,
                ));
            }
        }
        for m in &meshes {
            let topo = EdgeTopology::new(m);
            assert_eq!(
                boundary_half_edges(&m.triangles),
                topo.boundary_half_edges()
            );
            assert_eq!(boundary_loops(m), boundary_loops_of(&topo));
        }
    }
}
