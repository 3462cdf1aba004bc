//! One pass over the vertices' corner fans that gives a mesh's edge counts, its non-manifold
//! vertices and (when asked) its edge-connected components: what a pass over the half-edges
//! (looking up each reverse edge in the other end's block; kept as the tests' reference) and
//! [`super::validate::non_manifold_vertices_of`] give, from each vertex's own block of
//! half-edges alone.
//!
//! A face corner at `v` is the half-edge `v → next` with the face's third corner `prev`, and
//! `prev → v` is a half-edge of the same face. Over `v`'s corners, the `prev`s are therefore the
//! origins of every half-edge ending at `v`: the faces holding `b → v` are those of the corners
//! at `v` whose `prev` is `b`, whatever the mesh (repeated corners included). So both directions
//! of every edge at `v` are read from `v`'s block, without looking up the other end's block.
//! Where a vertex's corners follow one another in a single cycle (an interior manifold vertex:
//! the usual case) every edge at it is used once each way and nothing is counted; only the
//! faces across its edges are joined.

use super::TriMesh;
use super::topology::{EdgeTopology, count_edge, union_roots};
use super::validate::{FanScratch, one_cycle, third_corners};

/// What [`fan_counts`] measures.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct FanCounts {
    /// Undirected edges used by exactly one face.
    pub boundary_edges: usize,
    /// Undirected edges used by more than two faces or twice in one direction.
    pub non_manifold_edges: usize,
    /// Vertices whose faces form more than one edge-connected fan, sorted.
    pub non_manifold_vertices: Vec<u32>,
    /// Vertices used by no face.
    pub unused_vertices: usize,
    /// Edge-connected components of the faces (`None` when not asked for).
    pub components: Option<usize>,
}

/// The counts of `mesh` from its topology `topo` (see the module doc); the components only with
/// `components`. Equal to the separate passes' answers on every mesh (property test).
pub(crate) fn fan_counts(mesh: &TriMesh, topo: &EdgeTopology, components: bool) -> FanCounts {
    let mut out = FanCounts::default();
    let mut parent: Vec<u32> = if components {
        (0..mesh.triangles.len() as u32).collect()
    } else {
        Vec::new()
    };
    let mut scratch = FanScratch::default();
    let mut prev: Vec<u32> = Vec::new();
    let mut by_prev: Vec<(u32, u32)> = Vec::new();
    let nv = mesh.positions.len() as u32;
    // Vertices past the mesh's (a face indexing beyond them) count in the edges and
    // components, neither unused nor non-manifold: as the separate passes have it.
    for v in 0..nv.max(topo.vertex_span()) {
        let block = topo.leaving(v);
        if block.is_empty() {
            if v < nv {
                out.unused_vertices += 1;
            }
            continue;
        }
        third_corners(mesh, v, block, &mut prev);
        if one_cycle(block, &prev) {
            // Every edge at `v` once each way: nothing to count; the faces across each edge
            // joined from its smaller end.
            if components {
                for (&p, &(_, _, f)) in prev.iter().zip(block) {
                    if v < p {
                        let j = block.partition_point(|e| e.1 < p);
                        union_roots(&mut parent, f, block[j].2);
                    }
                }
            }
            continue;
        }
        // Not one cycle: the general test of one fan decides.
        if v < nv && !scratch.fans_joined(block, &prev) {
            out.non_manifold_vertices.push(v);
        }
        // The corners by third corner: the faces of `b → v` for each `b` found by binary
        // search, so that a vertex with many corners costs O(m log m), not O(m²).
        by_prev.clear();
        by_prev.extend(prev.iter().zip(block).map(|(&p, e)| (p, e.2)));
        by_prev.sort_unstable();
        let mut i = 0;
        while i < block.len() {
            let b = block[i].1;
            let mut j = i + 1;
            while j < block.len() && block[j].1 == b {
                if components {
                    // The same directed edge twice (non-manifold input) joins its faces too.
                    union_roots(&mut parent, block[j - 1].2, block[j].2);
                }
                j += 1;
            }
            let lo = by_prev.partition_point(|e| e.0 < b);
            let hi = lo + by_prev[lo..].partition_point(|e| e.0 == b);
            let rev = hi - lo;
            if components && v < b {
                // The run's faces are joined already: one of them with each face of `b → v`.
                for &(_, g) in &by_prev[lo..hi] {
                    union_roots(&mut parent, block[i].2, g);
                }
            }
            count_edge(
                v,
                b,
                j - i,
                rev,
                &mut out.boundary_edges,
                &mut out.non_manifold_edges,
            );
            i = j;
        }
    }
    if components {
        out.components = Some(
            parent
                .iter()
                .enumerate()
                .filter(|&(f, &p)| p == f as u32)
                .count(),
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{cube, ellipsoid, square, tetrahedron};
    use crate::mesh::topology::edge_and_component_counts;
    use crate::mesh::topology::tests::random_faces;
    use crate::mesh::validate::non_manifold_vertices_of;

    /// The separate passes' answers.
    fn reference(mesh: &TriMesh) -> FanCounts {
        let topo = EdgeTopology::new(mesh);
        let (boundary_edges, non_manifold_edges, components) =
            edge_and_component_counts(&topo, mesh.triangles.len());
        let mut used = vec![false; mesh.positions.len()];
        for &v in mesh.triangles.iter().flatten() {
            if let Some(u) = used.get_mut(v as usize) {
                *u = true;
            }
        }
        FanCounts {
            boundary_edges,
            non_manifold_edges,
            non_manifold_vertices: non_manifold_vertices_of(mesh, &topo),
            unused_vertices: used.iter().filter(|u| !**u).count(),
            components: Some(components),
        }
    }

    fn check(mesh: &TriMesh) {
        let topo = EdgeTopology::new(mesh);
        let want = reference(mesh);
        assert_eq!(fan_counts(mesh, &topo, true), want, "{mesh:?}");
        let without = fan_counts(mesh, &topo, false);
        assert_eq!(without.components, None);
        assert_eq!(
            FanCounts {
                components: want.components,
                ..without
            },
            want
        );
    }

    #[test]
    fn equals_the_separate_passes_on_fixtures() {
        for m in [
            cube(1.0),
            tetrahedron(),
            square(),
            ellipsoid(6, 9, 1.0, 1.5),
            TriMesh::default(),
        ] {
            check(&m);
        }
        // Two cubes sharing a vertex (a bow-tie vertex, two components), and an unused vertex.
        let mut m = cube(1.0);
        let off = m.positions.len() as u32;
        let c = cube(1.0);
        m.positions
            .extend(c.positions.iter().map(|p| *p + glam::DVec3::ONE));
        m.triangles.extend(
            c.triangles
                .iter()
                .map(|t| t.map(|v| if v == 0 { 7 } else { v + off })),
        );
        m.positions.push(glam::DVec3::splat(9.0));
        check(&m);
        // Cones of 300 faces around their apex, closed and open: vertices of many corners.
        let k = 300u32;
        let mut positions = vec![glam::DVec3::Z];
        positions.extend((0..k).map(|i| {
            let a = i as f64 * std::f64::consts::TAU / k as f64;
            glam::DVec3::new(a.cos(), a.sin(), 0.0)
        }));
        positions.push(glam::DVec3::ZERO);
        let side: Vec<[u32; 3]> = (0..k).map(|i| [0, 1 + i, 1 + (i + 1) % k]).collect();
        let base = (0..k).map(|i| [k + 1, 1 + (i + 1) % k, 1 + i]);
        check(&TriMesh::new(positions.clone(), side.clone()));
        check(&TriMesh::new(
            positions,
            side.into_iter().chain(base).collect(),
        ));
    }

    /// Random faces over few vertices: repeated corners, repeated, reversed and
    /// non-manifold faces, unused vertices, several components.
    #[test]
    fn equals_the_separate_passes_on_random_meshes() {
        let mut rng = crate::phantom::rng::Rng::new(7);
        for round in 0..400 {
            let n = 3 + round % 17;
            let faces = 1 + round % 40;
            // Every fifth mesh has faces indexing past its vertices.
            let tris = random_faces(
                &mut rng,
                (n + usize::from(round % 5 == 0) * 2) as u32,
                faces,
            );
            let positions = (0..n)
                .map(|i| glam::DVec3::new(i as f64, (i * i) as f64, 0.5 * i as f64))
                .collect();
            check(&TriMesh::new(positions, tris));
        }
    }
}
