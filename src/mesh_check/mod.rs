//! Independent geometric checks of a triangle mesh: exact triangle–triangle self-intersection
//! (Shewchuk's adaptive-precision orientation predicates from the `robust` crate), and
//! point-to-surface distance. Both use a uniform grid of triangle bounding boxes to stay fast.

mod distance;
mod grid;
mod tri_tri;

pub use distance::SurfaceDistance;
pub use grid::TriangleGrid;
pub use tri_tri::{
    FixedCorners, TrianglePairKind, intersect_moving_corner, pair_kind, triangles_intersect,
};

use crate::mesh::TriMesh;
use glam::DVec3;

/// Pairs of faces `(f, g)`, `f < g`, that intersect improperly: anything beyond sharing exactly
/// the vertices/edge they have in common in the mesh (crossing, touching, coplanar overlap,
/// fold-over). Sorted. Exact: decided with robust orientation predicates.
pub fn self_intersections(mesh: &TriMesh) -> Vec<(u32, u32)> {
    intersecting_pairs(mesh).collect()
}

/// `min(self_intersections(mesh).len(), limit)`, found without testing past the `limit`-th
/// intersecting pair: enough to tell whether a mesh crosses itself less than another does.
pub fn self_intersections_up_to(mesh: &TriMesh, limit: usize) -> usize {
    if limit == 0 {
        return 0;
    }
    // A count: the pairs need no order.
    let grid = TriangleGrid::new(mesh, 0.0);
    grid.candidate_pairs_unordered(mesh)
        .into_iter()
        .filter(|&(f, g)| triangles_intersect(mesh, f as usize, g as usize))
        .take(limit)
        .count()
}

/// The intersecting pairs of [`self_intersections`], tested lazily in order.
fn intersecting_pairs(mesh: &TriMesh) -> impl Iterator<Item = (u32, u32)> + '_ {
    let grid = TriangleGrid::new(mesh, 0.0);
    grid.candidate_pairs(mesh)
        .into_iter()
        .filter(move |&(f, g)| triangles_intersect(mesh, f as usize, g as usize))
}

/// Number of degenerate faces: repeated index or exactly zero area (exactly collinear corners).
pub fn degenerate_faces(mesh: &TriMesh) -> usize {
    (0..mesh.triangles.len())
        .filter(|&f| is_degenerate(mesh, f))
        .count()
}

/// Whether face `f` repeats a vertex index or has exactly collinear corners (exact test).
pub fn is_degenerate(mesh: &TriMesh, f: usize) -> bool {
    let t = mesh.triangles[f];
    t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || tri_tri::is_collinear(mesh, f)
}

/// The axis-aligned bounding box (lower, upper corner) of face `f` of `mesh`.
pub fn face_box(mesh: &TriMesh, f: usize) -> (DVec3, DVec3) {
    let [a, b, c] = mesh.corners(f);
    (a.min(b).min(c), a.max(b).max(c))
}

/// Pairs `(f, g)` of faces of `mesh`, `f` among `candidates`, that cross (or touch improperly),
/// exact test; each pair once, sorted. The candidates (a crown's fringe: a thin ring of faces)
/// are binned, and every face of the mesh whose box meets their region looks up the candidates
/// its box overlaps: linear in the mesh's faces, so cheap for a few candidates on a large mesh.
pub fn crossing_pairs(mesh: &TriMesh, candidates: &[u32]) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    if candidates.is_empty() {
        return out;
    }
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let mut edges = 0.0;
    for &f in candidates {
        let (l, h) = face_box(mesh, f as usize);
        lo = lo.min(l);
        hi = hi.max(h);
        let [a, b, c] = mesh.corners(f as usize);
        edges += (b - a).length() + (c - b).length() + (a - c).length();
    }
    let cell = 2.0 * edges / (3 * candidates.len()) as f64;
    let grid = TriangleGrid::over_region(mesh, candidates, (lo, hi), cell);
    // A pair of two candidates is met from both sides: tested only from its larger face.
    let mut is_candidate = vec![false; mesh.triangles.len()];
    for &f in candidates {
        if let Some(c) = is_candidate.get_mut(f as usize) {
            *c = true;
        }
    }
    let mut hits = Vec::new();
    for g in 0..mesh.triangles.len() as u32 {
        let (gl, gh) = face_box(mesh, g as usize);
        if !(gl.cmple(hi).all() && lo.cmple(gh).all()) {
            continue;
        }
        hits.clear();
        grid.for_each_in_box(gl, gh, |f| hits.push(f));
        hits.sort_unstable();
        hits.dedup();
        let g_candidate = is_candidate[g as usize];
        for &f in &hits {
            if f == g || (g_candidate && f > g) {
                continue;
            }
            let (l, h) = face_box(mesh, f as usize);
            if gl.cmple(h).all()
                && l.cmple(gh).all()
                && triangles_intersect(mesh, f as usize, g as usize)
            {
                out.push((f.min(g), f.max(g)));
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{cube, tetrahedron};
    use glam::DVec3;

    #[test]
    fn closed_convex_meshes_do_not_self_intersect() {
        assert!(self_intersections(&cube(1.0)).is_empty());
        assert!(self_intersections(&tetrahedron()).is_empty());
        assert_eq!(degenerate_faces(&cube(1.0)), 0);
    }

    #[test]
    fn two_interpenetrating_cubes_intersect() {
        let mut m = cube(1.0);
        let mut c = cube(1.0);
        for p in &mut c.positions {
            *p += DVec3::new(0.5, 0.3, 0.2);
        }
        m.append(&c);
        let s = self_intersections(&m);
        assert!(!s.is_empty());
        assert!(s.iter().all(|&(f, g)| f < 12 && g >= 12));
        // Counting up to a limit stops there.
        assert!(s.len() > 4, "{}", s.len());
        assert_eq!(self_intersections_up_to(&m, 3), 3);
        assert_eq!(self_intersections_up_to(&m, s.len() + 10), s.len());
        assert_eq!(self_intersections_up_to(&m, 0), 0);
        assert_eq!(self_intersections_up_to(&cube(1.0), 5), 0);
    }

    #[test]
    fn fold_over_and_touching_are_caught() {
        // Two triangles sharing edge 0-1, the second folded onto the first (coplanar overlap).
        let m = TriMesh::new(
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
                DVec3::new(0.5, 0.5, 0.0),
            ],
            vec![[0, 1, 2], [1, 0, 3]],
        );
        assert_eq!(self_intersections(&m), vec![(0, 1)]);
        // Sharing one vertex, second triangle's far edge pierces the first.
        let m = TriMesh::new(
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(0.0, 2.0, 0.0),
                DVec3::new(0.5, 0.5, -1.0),
                DVec3::new(0.5, 0.5, 1.0),
            ],
            vec![[0, 1, 2], [0, 3, 4]],
        );
        assert_eq!(self_intersections(&m), vec![(0, 1)]);
        // Sharing one vertex, the other triangle only touches there: fine.
        let m = TriMesh::new(
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(0.0, 2.0, 0.0),
                DVec3::new(-1.0, -1.0, 1.0),
                DVec3::new(-1.0, 0.0, -1.0),
            ],
            vec![[0, 1, 2], [0, 3, 4]],
        );
        assert!(self_intersections(&m).is_empty());
        // A vertex of one triangle exactly on the other (touching, no shared index).
        let m = TriMesh::new(
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(0.0, 2.0, 0.0),
                DVec3::new(0.5, 0.5, 0.0),
                DVec3::new(0.5, 0.5, 1.0),
                DVec3::new(1.5, 0.5, 1.0),
            ],
            vec![[0, 1, 2], [3, 4, 5]],
        );
        assert_eq!(self_intersections(&m), vec![(0, 1)]);
    }
}
