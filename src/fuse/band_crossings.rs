//! The crossings of a band with itself and with the faces around it, counted once in full and
//! then kept up to date as the untangling moves band vertices: only the pairs of the faces that
//! moved are tested again. Both give exactly the pairs a full count would (every pair of a band
//! face with any other face whose boxes overlap, decided by the exact [`triangles_intersect`]).

use crate::mesh::TriMesh;
use crate::mesh_check::{TriangleGrid, triangles_intersect};
use glam::DVec3;
use std::ops::Range;

/// Bounding box of face `f`.
pub(super) use crate::mesh_check::face_box as bbox;

/// Whether two boxes overlap (closed).
pub(super) fn overlap(a: (DVec3, DVec3), b: (DVec3, DVec3)) -> bool {
    a.0.cmple(b.1).all() && b.0.cmple(a.1).all()
}

fn inside(a: (DVec3, DVec3), region: (DVec3, DVec3)) -> bool {
    a.0.cmpge(region.0).all() && a.1.cmple(region.1).all()
}

/// The band's bounding box grown by `grow`.
pub(super) fn band_region(mesh: &TriMesh, band: Range<usize>, grow: f64) -> (DVec3, DVec3) {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for f in band {
        let (l, h) = bbox(mesh, f);
        lo = lo.min(l);
        hi = hi.max(h);
    }
    (lo - DVec3::splat(grow), hi + DVec3::splat(grow))
}

/// The band faces binned in cells of `2 * scale` over the band's box grown by a cell, unless
/// `binned` holds them already (binned at the current positions, over any region: every face
/// a query finds is checked against the box asked for, so the grid only speeds the search).
fn band_grid<'a>(
    mesh: &TriMesh,
    band: Range<usize>,
    scale: f64,
    binned: Option<&'a TriangleGrid>,
    own: &'a mut Option<TriangleGrid>,
) -> &'a TriangleGrid {
    match binned {
        Some(g) => g,
        None => {
            let region = band_region(mesh, band.clone(), 2.0 * scale);
            let band_faces: Vec<u32> = band.map(|f| f as u32).collect();
            own.insert(TriangleGrid::over_region(
                mesh,
                &band_faces,
                region,
                2.0 * scale,
            ))
        }
    }
}

/// Intersecting pairs with a band face, each once as `(smaller, larger)` face index, sorted.
/// `binned`: the band faces binned at their current positions, if at hand.
pub(super) fn count_all(
    mesh: &TriMesh,
    band: Range<usize>,
    scale: f64,
    binned: Option<&TriangleGrid>,
) -> Vec<(u32, u32)> {
    let region = band_region(mesh, band.clone(), 2.0 * scale);
    let mut own = None;
    let grid = band_grid(mesh, band.clone(), scale, binned, &mut own);
    // Band–band pairs, then band–other: faces in the band's cells, each pair once (the pairs
    // are only tested: their order does not matter).
    let mut pairs = grid.candidate_pairs_unordered(mesh);
    let mut hits = Vec::new();
    for g in (0..mesh.triangles.len()).filter(|g| !band.contains(g)) {
        let bg = bbox(mesh, g);
        if !overlap(bg, region) {
            continue;
        }
        hits.clear();
        grid.for_each_in_box(bg.0, bg.1, |f| {
            if overlap(bbox(mesh, f as usize), bg) {
                hits.push(f);
            }
        });
        hits.sort_unstable();
        hits.dedup();
        pairs.extend(hits.iter().map(|&f| (f, g as u32)));
    }
    let mut crossings: Vec<(u32, u32)> = pairs
        .into_iter()
        .filter(|&(f, g)| triangles_intersect(mesh, f as usize, g as usize))
        .map(|(f, g)| (f.min(g), f.max(g)))
        .collect();
    crossings.sort_unstable();
    crossings.dedup();
    crossings
}

/// The faces that are not band faces, binned (they never move while the band does): every
/// such face whose box meets `region` is in `others`.
pub(super) struct Recount<'a> {
    pub(super) region: (DVec3, DVec3),
    pub(super) others: &'a TriangleGrid,
}

impl Recount<'_> {
    /// The crossing pairs after the band faces `changed` (sorted, unique) moved, from the pairs
    /// `before` they moved: the pairs of unmoved faces are kept, the moved faces' pairs tested
    /// again. `None` when a moved face left the binned region (count in full then). `binned`:
    /// the band faces binned at their current positions, if at hand.
    pub(super) fn update(
        &self,
        mesh: &TriMesh,
        band: Range<usize>,
        scale: f64,
        before: &[(u32, u32)],
        changed: &[u32],
        binned: Option<&TriangleGrid>,
    ) -> Option<Vec<(u32, u32)>> {
        if changed.is_empty() {
            return Some(before.to_vec());
        }
        let moved = |f: u32| changed.binary_search(&f).is_ok();
        let boxes: Vec<(DVec3, DVec3)> = changed.iter().map(|&f| bbox(mesh, f as usize)).collect();
        if boxes.iter().any(|&b| !inside(b, self.region)) {
            return None;
        }
        let mut out: Vec<(u32, u32)> = before
            .iter()
            .copied()
            .filter(|&(f, g)| !moved(f) && !moved(g))
            .collect();
        let mut own = None;
        let grid = band_grid(mesh, band, scale, binned, &mut own);
        let mut tests: Vec<(u32, u32)> = Vec::new();
        for (&f, &bf) in changed.iter().zip(&boxes) {
            grid.for_each_in_box(bf.0, bf.1, |g| {
                if g != f && overlap(bf, bbox(mesh, g as usize)) {
                    tests.push((f.min(g), f.max(g)));
                }
            });
            self.others.for_each_in_box(bf.0, bf.1, |g| {
                if overlap(bf, bbox(mesh, g as usize)) {
                    tests.push((f, g));
                }
            });
        }
        tests.sort_unstable();
        tests.dedup();
        out.extend(
            tests
                .into_iter()
                .filter(|&(f, g)| triangles_intersect(mesh, f as usize, g as usize))
                .map(|(f, g)| (f.min(g), f.max(g))),
        );
        out.sort_unstable();
        out.dedup();
        Some(out)
    }
}
