//! Local repair of the band after assembly. The chart band is a graph over the annulus chart, so
//! where the crown overhangs its own margin (bled gingiva curling under, narrow bays of the
//! margin) its first rows can cross crown faces, and where the lift stretches the chart a face can
//! keep an angle under the target. Here each free band vertex of such a face is moved within its
//! star to the best of a few candidate positions, every candidate checked exactly
//! ([`triangles_intersect`](crate::mesh_check::triangles_intersect)) against the faces around it: a move is kept only if its star crosses
//! fewer faces, or as many and has a larger smallest angle, and no star face turns over. Loop
//! vertices (IOS margin, CBCT cut) never move. The exact tests that score candidates are
//! budgeted ([`TESTS_PER_BAND_FACE`] per band face, a tenth of that on a band tangled from the
//! start): on a band that cannot be untangled the
//! rounds stop when it is spent, so the work stays proportional to the band whatever the input.

mod moves;

use super::band_crossings::count_all;
use super::near_faces::NearFaces;
use crate::mesh::TriMesh;
use glam::DVec3;
use moves::improve_vertex;
use std::ops::Range;

/// What [`untangle_band`] did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UntangleReport {
    /// Intersecting face pairs with a band face, before.
    pub crossings_before: usize,
    /// The same, after.
    pub crossings_after: usize,
    /// Vertex moves kept.
    pub moves: usize,
    /// The intersecting pairs left (face indices, band face or not), sorted.
    pub crossing_pairs: Vec<(u32, u32)>,
    /// Exact triangle-triangle tests run to score candidate positions.
    pub tests: usize,
    /// Whether the test budget ran out before the rounds ended.
    pub budget_spent: bool,
}

/// Exact triangle-triangle tests allowed per band face for scoring candidate moves: the
/// untangling's work is bounded by the band's size whatever the input (a clean band needs
/// none; a folded foreign margin a few hundred per face, rarely over a thousand on a coarse one).
pub const TESTS_PER_BAND_FACE: usize = 2000;

/// Exact tests per band face allowed instead for a tangled band: one whose faces cross others
/// in more pairs than an eighth of its faces before any move (`TANGLED_SHARE`). Such a band
/// is not untangled whole, whatever the budget: the builds that follow trim the crown faces it
/// crosses and lay the band anew. Spending the full budget on each of them made a coarse molar
/// (bands crossing in 1 400-2 200 pairs, 65 builds) hold its jaw's fuse for 11.8 s and still
/// end with 4 pairs; with this budget the jaw takes 4.0 s and the molar ends with none (the
/// foreign jaws' fused meshes are unchanged).
const TESTS_PER_TANGLED_BAND_FACE: usize = 200;

/// A band is tangled when its crossing pairs before any move exceed its faces divided by this.
const TANGLED_SHARE: usize = 8;

/// Whether a corner angle of `a, b, c` is under the angle whose cosine is `cos_limit` (no
/// inverse cosine: the test runs on every band face).
fn has_angle_under(a: DVec3, b: DVec3, c: DVec3, cos_limit: f64) -> bool {
    let corner = |p: DVec3, q: DVec3, r: DVec3| {
        let (u, v) = (q - p, r - p);
        let l = (u.length_squared() * v.length_squared()).sqrt();
        l == 0.0 || u.dot(v) > cos_limit * l
    };
    corner(a, b, c) || corner(b, c, a) || corner(c, a, b)
}

/// Band faces `band` of `mesh` (closed: crown, band, root) whose free vertices (`movable`) may
/// move: see the module doc. `min_angle_deg`: faces with a smaller angle are improved too.
/// Rounds stop when nothing is left to fix or no move helps. Deterministic.
pub fn untangle_band(
    mesh: &mut TriMesh,
    band: Range<usize>,
    movable: Range<u32>,
    min_angle_deg: f64,
) -> UntangleReport {
    let mut report = UntangleReport::default();
    if band.is_empty() {
        return report;
    }
    let star = stars(mesh, band.clone(), movable.clone());
    let nm = movable.len();
    let scale = band_edge(mesh, band.clone());
    let saved: Vec<DVec3> = mesh.positions[movable.start as usize..movable.end as usize].to_vec();
    let mut first_pairs = Vec::new();
    // A vertex whose every candidate lost is tried again only after a neighbour has moved: the
    // work per band face is bounded whatever the input.
    let mut stuck = vec![false; nm];
    let mut changed: Vec<u32> = Vec::new();
    let mut full_budget = TESTS_PER_BAND_FACE * band.len();
    let mut budget = full_budget;
    // After the first full count, only the pairs of the faces moved since are tested again,
    // searched in the grids `near` binned at the current positions.
    let count = |mesh: &TriMesh,
                 pairs: &[(u32, u32)],
                 changed: &mut Vec<u32>,
                 first: bool,
                 near: &NearFaces| {
        changed.sort_unstable();
        changed.dedup();
        let out = if first {
            None
        } else {
            near.recount()
                .and_then(|r| r.update(mesh, band.clone(), scale, pairs, changed, near.band_grid()))
        };
        changed.clear();
        out.unwrap_or_else(|| count_all(mesh, band.clone(), scale, near.band_grid()))
    };
    let mut near = NearFaces::default();
    for round in 0..4 {
        // Binned before the count: the count searches this round's grids too. The first count
        // searches the band's grid only; the faces off the band are binned once a vertex is to
        // move (on the mesh as it is here: nothing moves in between).
        if round == 0 {
            near.update_band(mesh, band.clone(), scale);
        } else {
            near.update(mesh, band.clone(), scale);
        }
        let pairs = count(
            mesh,
            &report.crossing_pairs,
            &mut changed,
            round == 0,
            &near,
        );
        let bad = bad_faces(mesh, band.clone(), &pairs, min_angle_deg);
        if round == 0 {
            report.crossings_before = pairs.len();
            first_pairs = pairs.clone();
            if pairs.len() * TANGLED_SHARE > band.len() {
                full_budget = TESTS_PER_TANGLED_BAND_FACE * band.len();
                budget = full_budget;
            }
        }
        report.crossings_after = pairs.len();
        report.crossing_pairs = pairs;
        let mut verts: Vec<u32> = bad
            .iter()
            .flat_map(|&f| mesh.triangles[f as usize])
            .filter(|v| movable.contains(v) && !stuck[(v - movable.start) as usize])
            .collect();
        verts.sort_unstable();
        verts.dedup();
        if verts.is_empty() {
            break;
        }
        if round == 0 {
            near.update_fixed(mesh, band.clone(), scale);
        }
        let moved = Movers {
            star: &star,
            movable: movable.clone(),
            near: &near,
            scale,
        }
        .run(mesh, &verts, &mut budget, &mut stuck, &mut changed);
        report.moves += moved;
        report.budget_spent |= budget == 0;
        if moved == 0 || report.budget_spent {
            break;
        }
    }
    report.tests = full_budget - budget;
    if report.moves > 0 {
        // Recount after the last round's moves.
        near.update(mesh, band.clone(), scale);
        let pairs = count(mesh, &report.crossing_pairs, &mut changed, false, &near);
        report.crossings_after = pairs.len();
        report.crossing_pairs = pairs;
        // Within a round the grid does not follow the moves; should a late move have crossed
        // an earlier one, nothing is kept.
        if report.crossings_after > report.crossings_before {
            mesh.positions[movable.start as usize..movable.end as usize].copy_from_slice(&saved);
            report.crossings_after = report.crossings_before;
            report.crossing_pairs = first_pairs;
            report.moves = 0;
        }
    }
    report
}

/// Star of each movable vertex (band faces only: movable vertices are in no other face), by
/// its index in `movable`.
fn stars(mesh: &TriMesh, band: Range<usize>, movable: Range<u32>) -> Vec<Vec<u32>> {
    let mut star: Vec<Vec<u32>> = vec![Vec::new(); movable.len()];
    for f in band {
        for v in mesh.triangles[f] {
            if movable.contains(&v) {
                star[(v - movable.start) as usize].push(f as u32);
            }
        }
    }
    star
}

/// What one round's vertex moves need besides the mesh.
struct Movers<'a> {
    star: &'a [Vec<u32>],
    movable: Range<u32>,
    near: &'a NearFaces,
    scale: f64,
}

impl Movers<'_> {
    /// Tries to move each of `verts` in turn ([`improve_vertex`]) while `budget` lasts; a
    /// vertex that moves adds its star to `changed` and frees its neighbours from `stuck`, one
    /// that does not becomes stuck. Returns the number of moves.
    fn run(
        &self,
        mesh: &mut TriMesh,
        verts: &[u32],
        budget: &mut usize,
        stuck: &mut [bool],
        changed: &mut Vec<u32>,
    ) -> usize {
        let mut moved = 0;
        for &v in verts {
            let k = (v - self.movable.start) as usize;
            if *budget == 0 {
                break;
            }
            if improve_vertex(mesh, v, &self.star[k], self.near, self.scale, budget) {
                moved += 1;
                changed.extend_from_slice(&self.star[k]);
                // Its neighbours may do better now.
                for &f in &self.star[k] {
                    for w in mesh.triangles[f as usize] {
                        if self.movable.contains(&w) {
                            stuck[(w - self.movable.start) as usize] = false;
                        }
                    }
                }
            } else {
                stuck[k] = true;
            }
        }
        moved
    }
}

fn band_edge(mesh: &TriMesh, band: Range<usize>) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for f in band {
        let [a, b, c] = mesh.corners(f);
        sum += (b - a).length() + (c - b).length() + (a - c).length();
        n += 3;
    }
    if n == 0 { 0.1 } else { sum / n as f64 }
}

/// The band faces to fix: in a crossing pair of `pairs`, or with an angle under
/// `min_angle_deg`.
fn bad_faces(
    mesh: &TriMesh,
    band: Range<usize>,
    pairs: &[(u32, u32)],
    min_angle_deg: f64,
) -> Vec<u32> {
    let cos_limit = min_angle_deg.to_radians().cos();
    let mut hit = vec![false; band.len()];
    for &(f, g) in pairs {
        for x in [f as usize, g as usize] {
            if band.contains(&x) {
                hit[x - band.start] = true;
            }
        }
    }
    band.clone()
        .filter(|&f| {
            let [a, b, c] = mesh.corners(f);
            hit[f - band.start] || has_angle_under(a, b, c, cos_limit)
        })
        .map(|f| f as u32)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fuse::band_opt::min_angle;

    /// A flat square of band faces around one free vertex pushed through a "crown" triangle
    /// hanging over it: the move must take the vertex out.
    #[test]
    fn moves_a_vertex_out_of_a_crossing_face() {
        // Band: 4 faces around vertex 4 (free) in the z = 0 plane, but vertex 4 raised to
        // z = 0.5, piercing the crown face 5-6-7 at z = 0.3.
        let positions = vec![
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(1.0, -1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(-1.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 0.5),
            DVec3::new(-0.3, -0.3, 0.3),
            DVec3::new(0.4, -0.3, 0.3),
            DVec3::new(0.0, 0.4, 0.3),
        ];
        let triangles = vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [5, 6, 7]];
        let mut m = TriMesh::new(positions, triangles);
        let r = untangle_band(&mut m, 0..4, 4..5, 5.0);
        assert!(r.crossings_before > 0, "{r:?}");
        assert_eq!(r.crossings_after, 0, "{r:?}");
        assert!(r.moves > 0);
        // Loop (fixed) vertices did not move.
        assert_eq!(m.positions[0], DVec3::new(-1.0, -1.0, 0.0));
        assert_eq!(m.positions[5], DVec3::new(-0.3, -0.3, 0.3));
    }

    /// A band that cannot be untangled (a flat grid of band faces pierced everywhere by a dense
    /// pleated sheet of fixed faces): tangled from the start, it gets the smaller budget; the
    /// rounds stop when that is spent, and the band is not left worse than it came.
    #[test]
    fn hopeless_band_costs_a_bounded_number_of_tests() {
        let n = 10;
        let mut positions = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                positions.push(DVec3::new(i as f64, j as f64, 0.0));
            }
        }
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut triangles = Vec::new();
        for j in 0..n {
            for i in 0..n {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let band = 0..triangles.len();
        // Every grid vertex is free; the sheet's vertices (fixed) come after them.
        let free = 0..positions.len() as u32;
        // The sheet: strips along y at x = k / 4 + 0.1, zig-zagging through z = 0.
        for k in 0..4 * n {
            let x = k as f64 / 4.0 + 0.1;
            let base = positions.len() as u32;
            for j in 0..=4 * n {
                let y = j as f64 / 4.0;
                let dx = if j % 2 == 0 { 0.05 } else { -0.05 };
                positions.push(DVec3::new(x + dx, y, -0.3));
                positions.push(DVec3::new(x - dx, y, 0.3));
            }
            for j in 0..4 * n as u32 {
                let (a, b, c, d) = (
                    base + 2 * j,
                    base + 2 * j + 1,
                    base + 2 * j + 2,
                    base + 2 * j + 3,
                );
                triangles.push([a, c, b]);
                triangles.push([b, c, d]);
            }
        }
        let mut m = TriMesh::new(positions, triangles);
        let r = untangle_band(&mut m, band.clone(), free, 5.0);
        assert!(r.crossings_before > 500, "{r:?}");
        assert!(r.crossings_before * TANGLED_SHARE > band.len(), "{r:?}");
        assert!(r.budget_spent, "{r:?}");
        assert_eq!(r.tests, TESTS_PER_TANGLED_BAND_FACE * band.len());
        assert!(r.crossings_after <= r.crossings_before);
    }

    #[test]
    fn raises_a_tiny_angle() {
        let positions = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.5, 0.02, 0.0),
        ];
        let triangles = vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]];
        let mut m = TriMesh::new(positions, triangles);
        let before = (0..4)
            .map(|f| {
                let [a, b, c] = m.corners(f);
                min_angle(a, b, c)
            })
            .fold(180.0, f64::min);
        let r = untangle_band(&mut m, 0..4, 4..5, 5.0);
        let after = (0..4)
            .map(|f| {
                let [a, b, c] = m.corners(f);
                min_angle(a, b, c)
            })
            .fold(180.0, f64::min);
        assert!(before < 5.0 && after >= 5.0, "{before} -> {after} {r:?}");
    }
}
