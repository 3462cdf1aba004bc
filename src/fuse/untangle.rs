//! Local repair of the band after assembly. The chart band is a graph over the annulus chart, so
//! where the crown overhangs its own margin (bled gingiva curling under, narrow bays of the
//! margin) its first rows can cross crown faces, and where the lift stretches the chart a face can
//! keep an angle under the target. Here each free band vertex of such a face is moved within its
//! star to the best of a few candidate positions, every candidate checked exactly
//! ([`triangles_intersect`]) against the faces around it: a move is kept only if its star crosses
//! fewer faces, or as many and has a larger smallest angle, and no star face turns over. Loop
//! vertices (IOS margin, CBCT cut) never move. The exact tests that score candidates are
//! budgeted ([`TESTS_PER_BAND_FACE`] per band face): on a band that cannot be untangled the
//! rounds stop when it is spent, so the work stays proportional to the band whatever the input.

use super::band_crossings::{bbox, count_all, overlap};
use super::band_opt::min_angle;
use super::near_faces::NearFaces;
use crate::mesh::TriMesh;
use crate::mesh_check::{FixedCorners, intersect_moving_corner, triangles_intersect};
use glam::DVec3;
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

/// Directions (unnormalized): the 6 axes and 8 diagonals of a cube, in (t1, t2, normal).
const SPHERE: [(f64, f64, f64); 14] = [
    (1.0, 0.0, 0.0),
    (-1.0, 0.0, 0.0),
    (0.0, 1.0, 0.0),
    (0.0, -1.0, 0.0),
    (0.0, 0.0, 1.0),
    (0.0, 0.0, -1.0),
    (1.0, 1.0, 1.0),
    (1.0, 1.0, -1.0),
    (1.0, -1.0, 1.0),
    (1.0, -1.0, -1.0),
    (-1.0, 1.0, 1.0),
    (-1.0, 1.0, -1.0),
    (-1.0, -1.0, 1.0),
    (-1.0, -1.0, -1.0),
];

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
    // Star of each movable vertex (band faces only: movable vertices are in no other face).
    let nm = movable.len();
    let mut star: Vec<Vec<u32>> = vec![Vec::new(); nm];
    for f in band.clone() {
        for v in mesh.triangles[f] {
            if movable.contains(&v) {
                star[(v - movable.start) as usize].push(f as u32);
            }
        }
    }
    let scale = band_edge(mesh, band.clone());
    let saved: Vec<DVec3> = mesh.positions[movable.start as usize..movable.end as usize].to_vec();
    let mut first_pairs = Vec::new();
    // A vertex whose every candidate lost is tried again only after a neighbour has moved: the
    // work per band face is bounded whatever the input.
    let mut stuck = vec![false; nm];
    let mut changed: Vec<u32> = Vec::new();
    let full_budget = TESTS_PER_BAND_FACE * band.len();
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
        // Binned before the count: the count searches this round's grids too.
        near.update(mesh, band.clone(), scale);
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
        let mut moved = 0;
        for v in verts {
            let k = (v - movable.start) as usize;
            if budget == 0 {
                report.budget_spent = true;
                break;
            }
            if improve_vertex(mesh, v, &star[k], &near, scale, &mut budget) {
                moved += 1;
                changed.extend_from_slice(&star[k]);
                // Its neighbours may do better now.
                for &f in &star[k] {
                    for w in mesh.triangles[f as usize] {
                        if movable.contains(&w) {
                            stuck[(w - movable.start) as usize] = false;
                        }
                    }
                }
            } else {
                stuck[k] = true;
            }
        }
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

/// The faces around a star, split once per vertex: the other faces (which do not move while
/// the star's vertex `v` does) with their boxes, and the star's own faces among them by star
/// index; `fixed[k * others.len() + j]` what the test of star face `k` with other face `j`
/// knows of the star face's fixed corners (filled as the pairs are first tested).
struct Around {
    v: u32,
    others: Vec<(u32, (DVec3, DVec3))>,
    star_members: Vec<usize>,
    fixed: Vec<FixedCorners>,
}

impl Around {
    fn new(mesh: &TriMesh, v: u32, star: &[u32], faces: &[u32]) -> Around {
        let mut others = Vec::with_capacity(faces.len());
        let mut star_members = Vec::new();
        for &g in faces {
            match star.iter().position(|&f| f == g) {
                Some(j) => star_members.push(j),
                None => others.push((g, bbox(mesh, g as usize))),
            }
        }
        Around {
            v,
            fixed: vec![FixedCorners::Unknown; star.len() * others.len()],
            others,
            star_members,
        }
    }
}

/// A candidate's score `(crossings, turned-over faces, smallest angle)` ordered for
/// comparison: fewer crossings first, then fewer turned-over faces, then a larger smallest
/// angle (capped at 30°).
type Key = (usize, usize, f64);

fn key(s: (usize, usize, f64)) -> Key {
    (s.0, s.1, -s.2.min(30.0))
}

/// Whether a key with `folded` turned-over faces and smallest angle `ang` beats `best` on
/// those two alone (at equal crossings); a smallest angle must be larger by over 0.1°.
fn shape_beats(folded: usize, ang: f64, best: Key) -> bool {
    folded < best.1 || (folded == best.1 && -ang.min(30.0) < best.2 - 0.1)
}

/// Whether key `a` beats key `b`.
fn better(a: Key, b: Key) -> bool {
    a.0 < b.0 || (a.0 == b.0 && shape_beats(a.1, -a.2, b))
}

/// `(crossings of the star with its surroundings, star faces turned over against `normals`,
/// smallest star angle)` with `v` where it is. With `beat` (the best key so far), counting
/// stops as soon as the candidate cannot beat it (`None`): past `max_folded` turned-over faces,
/// past as many crossings as the best has, or, when its turned-over faces and angle do not beat
/// the best's, past one fewer (with a best of no crossing, no exact test is run at all). `None`
/// too when `budget` exact tests are spent. Each pair of star faces found among `around` counts
/// once.
fn score(
    mesh: &TriMesh,
    star: &[u32],
    normals: &[DVec3],
    around: &mut Around,
    max_folded: usize,
    beat: Option<Key>,
    budget: &mut usize,
) -> Option<(usize, usize, f64)> {
    let mut ang = 180.0f64;
    let mut folded = 0;
    let mut boxes = Vec::with_capacity(star.len());
    for (k, &f) in star.iter().enumerate() {
        let [a, b, c] = mesh.corners(f as usize);
        let n = (b - a).cross(c - a);
        if n.dot(normals[k]) <= 0.0 {
            folded += 1;
        }
        ang = ang.min(min_angle(a, b, c));
        boxes.push((a.min(b).min(c), a.max(b).max(c)));
    }
    if folded > max_folded {
        return None;
    }
    let max_crossings = match beat {
        None => usize::MAX,
        Some(b) if shape_beats(folded, ang, b) => b.0,
        Some(b) => b.0.checked_sub(1)?,
    };
    let mut crossings = 0;
    // Each exact test spends one of the budget; true when the candidate is out.
    let mut count = |hit: &mut dyn FnMut() -> bool| {
        if *budget == 0 {
            return true;
        }
        *budget -= 1;
        if hit() {
            crossings += 1;
        }
        crossings > max_crossings
    };
    let n_others = around.others.len();
    for (k, &f) in star.iter().enumerate() {
        let bf = boxes[k];
        let memo = &mut around.fixed[k * n_others..(k + 1) * n_others];
        for (&(g, bg), m) in around.others.iter().zip(memo) {
            if overlap(bf, bg)
                && count(&mut || intersect_moving_corner(mesh, f as usize, g as usize, around.v, m))
            {
                return None;
            }
        }
        for &j in &around.star_members {
            if j > k
                && overlap(bf, boxes[j])
                && count(&mut || triangles_intersect(mesh, f as usize, star[j] as usize))
            {
                return None;
            }
        }
    }
    Some((crossings, folded, ang))
}

/// Tries candidate positions for `v`; keeps the best if it beats the current one.
fn improve_vertex(
    mesh: &mut TriMesh,
    v: u32,
    star: &[u32],
    near: &NearFaces,
    scale: f64,
    budget: &mut usize,
) -> bool {
    let vi = v as usize;
    let p0 = mesh.positions[vi];
    // Reference normals: each star face's own, unless it is folded against the star's mean
    // (then the mean, so the move may unfold it).
    let own: Vec<DVec3> = star
        .iter()
        .map(|&f| {
            let [a, b, c] = mesh.corners(f as usize);
            (b - a).cross(c - a)
        })
        .collect();
    let mean = own.iter().copied().sum::<DVec3>().normalize_or_zero();
    let normals: Vec<DVec3> = own
        .iter()
        .map(|&n| if n.dot(mean) > 0.0 { n } else { mean })
        .collect();
    // Neighbour ring and the faces around the star (the star may move by up to ~ one edge).
    let mut ring: Vec<u32> = star
        .iter()
        .flat_map(|&f| mesh.triangles[f as usize])
        .filter(|&w| w != v)
        .collect();
    ring.sort_unstable();
    ring.dedup();
    let (mut lo, mut hi) = (p0, p0);
    for &w in &ring {
        lo = lo.min(mesh.positions[w as usize]);
        hi = hi.max(mesh.positions[w as usize]);
    }
    let grow = DVec3::splat(0.5 * scale);
    let mut around = Around::new(
        mesh,
        v,
        star,
        &near.faces_in_box(mesh, lo - grow, hi + grow),
    );
    let Some(current) = score(mesh, star, &normals, &mut around, usize::MAX, None, budget) else {
        return false;
    };
    let centroid = ring
        .iter()
        .map(|&w| mesh.positions[w as usize])
        .sum::<DVec3>()
        / ring.len() as f64;
    let h = ring
        .iter()
        .map(|&w| (mesh.positions[w as usize] - p0).length())
        .sum::<f64>()
        / ring.len() as f64;
    let mut cands = vec![
        p0 + 0.5 * (centroid - p0),
        centroid,
        p0 + 0.3 * h * mean,
        p0 - 0.3 * h * mean,
        p0 + 0.6 * h * mean,
        p0 - 0.6 * h * mean,
    ];
    for &f in star {
        let t = mesh.triangles[f as usize];
        let k = t.iter().position(|&x| x == v).unwrap_or(0);
        let (a, b) = (
            mesh.positions[t[(k + 1) % 3] as usize],
            mesh.positions[t[(k + 2) % 3] as usize],
        );
        // Towards the apex of the equilateral triangle on the opposite edge.
        let m = 0.5 * (a + b);
        let apex = m + (p0 - m).normalize_or_zero() * (0.866 * (b - a).length());
        cands.push(p0 + 0.5 * (apex - p0));
        cands.push(apex);
        // The face turned about its opposite edge (finds a narrow free wedge between crown
        // faces that fold at the margin).
        let axis = (b - a).normalize_or_zero();
        if axis != DVec3::ZERO {
            for deg in [
                15.0f64, -15.0, 30.0, -30.0, 60.0, -60.0, 90.0, -90.0, 135.0, -135.0,
            ] {
                let q = glam::DQuat::from_axis_angle(axis, deg.to_radians());
                cands.push(a + q * (p0 - a));
            }
        }
    }
    for &w in &ring {
        cands.push(p0 + 0.4 * (mesh.positions[w as usize] - p0));
    }
    // A coarse sphere of directions in the star's frame, at three radii.
    let (t1, t2) = mean.any_orthonormal_pair();
    for r in [0.3, 0.6, 1.0, 1.5] {
        for (a, b, c) in SPHERE {
            cands.push(p0 + r * h * (a * t1 + b * t2 + c * mean).normalize_or_zero());
        }
    }
    // Fewer crossings first, then fewer turned-over faces, then a larger smallest angle; a
    // move may never turn more faces over.
    let mut best = (key(current), p0);
    // Nothing beats no crossing, no turned-over face and every angle at the cap.
    let perfect = (0, 0, -30.0);
    for c in cands {
        if best.0 == perfect {
            break;
        }
        if !c.is_finite() || (c - p0).length() > 2.0 * h {
            continue;
        }
        mesh.positions[vi] = c;
        let Some(s) = score(
            mesh,
            star,
            &normals,
            &mut around,
            current.1,
            Some(best.0),
            budget,
        ) else {
            if *budget == 0 {
                break;
            }
            continue;
        };
        if better(key(s), best.0) {
            best = (key(s), c);
        }
    }
    mesh.positions[vi] = best.1;
    best.1 != p0
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// A sliver (free apex almost on its base) is opened up.
    /// A band that cannot be untangled (a flat grid of band faces pierced everywhere by a dense
    /// pleated sheet of fixed faces): the rounds stop when the test budget is spent, and the
    /// band is not left worse than it came.
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
        assert!(r.budget_spent, "{r:?}");
        assert!(r.tests <= TESTS_PER_BAND_FACE * band.len(), "{}", r.tests);
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
