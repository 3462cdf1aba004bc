//! One free band vertex moved within its star to the best of a few candidate positions, every
//! candidate scored exactly against the faces around the star.

use super::super::band_crossings::{bbox, overlap};
use super::super::band_opt::{angle_of_cos, max_cos};
use super::super::near_faces::NearFaces;
use crate::mesh::TriMesh;
use crate::mesh_check::{FixedCorners, intersect_moving_corner, triangles_intersect};
use glam::DVec3;

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

/// The faces around a star, split once per vertex: the other faces (which do not move while
/// the star's vertex `v` does) with their boxes, and the star's own faces among them by star
/// index; `fixed[k * others.len() + j]` what the test of star face `k` with other face `j`
/// knows of the star face's fixed corners (filled as the pairs are first tested); and the
/// pairs `(k, j)` found crossing at an earlier candidate (`hot`, marked in `is_hot`), tested
/// first at the next ones: a candidate that cannot beat the best is most often out on them.
struct Around {
    v: u32,
    others: Vec<(u32, (DVec3, DVec3))>,
    star_members: Vec<usize>,
    fixed: Vec<FixedCorners>,
    hot: Vec<(u32, u32)>,
    is_hot: Vec<bool>,
    /// Scratch: the indices into `others` of the faces meeting the star's box at the
    /// candidate being scored.
    meeting: Vec<u32>,
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
            hot: Vec::new(),
            is_hot: vec![false; star.len() * others.len()],
            meeting: Vec::with_capacity(others.len()),
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
    // The smallest angle of the star is that of its largest corner cosine (0 when a face is
    // degenerate).
    let mut cos = f64::NEG_INFINITY;
    let mut degenerate = false;
    let mut folded = 0;
    let mut boxes = Vec::with_capacity(star.len());
    for (k, &f) in star.iter().enumerate() {
        let [a, b, c] = mesh.corners(f as usize);
        let n = (b - a).cross(c - a);
        if n.dot(normals[k]) <= 0.0 {
            folded += 1;
        }
        let m = max_cos(a, b, c);
        degenerate |= m.is_nan();
        cos = cos.max(m);
        boxes.push((a.min(b).min(c), a.max(b).max(c)));
    }
    let ang = if degenerate {
        0.0
    } else if star.is_empty() {
        180.0
    } else {
        angle_of_cos(cos)
    };
    if folded > max_folded {
        return None;
    }
    let max_crossings = match beat {
        None => usize::MAX,
        Some(b) if shape_beats(folded, ang, b) => b.0,
        Some(b) => b.0.checked_sub(1)?,
    };
    let mut crossings = 0;
    let n_others = around.others.len();
    // Each exact test spends one of the budget (out when it is spent); a candidate is out past
    // `max_crossings`. Which pairs are tested first changes how soon a candidate is out, not
    // whether it is, nor the count of one that is not.
    for i in 0..around.hot.len() {
        let (k, j) = (around.hot[i].0 as usize, around.hot[i].1 as usize);
        let (g, bg) = around.others[j];
        if !overlap(boxes[k], bg) {
            continue;
        }
        if *budget == 0 {
            return None;
        }
        *budget -= 1;
        let memo = &mut around.fixed[k * n_others + j];
        if intersect_moving_corner(mesh, star[k] as usize, g as usize, around.v, memo) {
            crossings += 1;
            if crossings > max_crossings {
                return None;
            }
        }
    }
    // The other faces meeting the star's box: only they can meet a star face's box.
    let empty = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let star_box = boxes
        .iter()
        .fold(empty, |u, b| (u.0.min(b.0), u.1.max(b.1)));
    around.meeting.clear();
    around
        .meeting
        .extend((0..n_others as u32).filter(|&j| overlap(star_box, around.others[j as usize].1)));
    for (k, &f) in star.iter().enumerate() {
        let bf = boxes[k];
        for m in 0..around.meeting.len() {
            let j = around.meeting[m] as usize;
            let (g, bg) = around.others[j];
            if around.is_hot[k * n_others + j] || !overlap(bf, bg) {
                continue;
            }
            if *budget == 0 {
                return None;
            }
            *budget -= 1;
            let memo = &mut around.fixed[k * n_others + j];
            if intersect_moving_corner(mesh, f as usize, g as usize, around.v, memo) {
                around.is_hot[k * n_others + j] = true;
                around.hot.push((k as u32, j as u32));
                crossings += 1;
                if crossings > max_crossings {
                    return None;
                }
            }
        }
    }
    for (k, &f) in star.iter().enumerate() {
        for &j in &around.star_members {
            if j <= k || !overlap(boxes[k], boxes[j]) {
                continue;
            }
            if *budget == 0 {
                return None;
            }
            *budget -= 1;
            if triangles_intersect(mesh, f as usize, star[j] as usize) {
                crossings += 1;
                if crossings > max_crossings {
                    return None;
                }
            }
        }
    }
    Some((crossings, folded, ang))
}

/// Tries candidate positions for `v` ([`candidates`]); keeps the best if it beats the current
/// one.
pub(super) fn improve_vertex(
    mesh: &mut TriMesh,
    v: u32,
    star: &[u32],
    near: &NearFaces,
    scale: f64,
    budget: &mut usize,
) -> bool {
    let vi = v as usize;
    let p0 = mesh.positions[vi];
    let (normals, mean) = star_normals(mesh, star);
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
    // The ring's mean distance from `v`: the scale of the moves.
    let h = ring
        .iter()
        .map(|&w| (mesh.positions[w as usize] - p0).length())
        .sum::<f64>()
        / ring.len() as f64;
    // Fewer crossings first, then fewer turned-over faces, then a larger smallest angle; a
    // move may never turn more faces over.
    let mut best = (key(current), p0);
    // Nothing beats no crossing, no turned-over face and every angle at the cap.
    let perfect = (0, 0, -30.0);
    for c in candidates(mesh, v, star, &ring, mean, h) {
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

/// Reference normals of a star's faces for telling a face turned over: each face's own, unless
/// it is folded against the star's mean (then the mean, so that a move may unfold it); and the
/// mean (unit).
fn star_normals(mesh: &TriMesh, star: &[u32]) -> (Vec<DVec3>, DVec3) {
    let own: Vec<DVec3> = star
        .iter()
        .map(|&f| {
            let [a, b, c] = mesh.corners(f as usize);
            (b - a).cross(c - a)
        })
        .collect();
    let mean = own.iter().copied().sum::<DVec3>().normalize_or_zero();
    let normals = own
        .iter()
        .map(|&n| if n.dot(mean) > 0.0 { n } else { mean })
        .collect();
    (normals, mean)
}

/// Candidate positions for `v` (star `star`, neighbour ring `ring`, mean star normal `mean`,
/// ring distance `h`), in the order they are tried: towards the ring's centroid, along the
/// normal, towards and onto the apex of the equilateral triangle on each star face's opposite
/// edge, each star face turned about that edge, towards each ring vertex, and a coarse sphere
/// of directions at four radii.
fn candidates(
    mesh: &TriMesh,
    v: u32,
    star: &[u32],
    ring: &[u32],
    mean: DVec3,
    h: f64,
) -> Vec<DVec3> {
    let p0 = mesh.positions[v as usize];
    let centroid = ring
        .iter()
        .map(|&w| mesh.positions[w as usize])
        .sum::<DVec3>()
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
    for &w in ring {
        cands.push(p0 + 0.4 * (mesh.positions[w as usize] - p0));
    }
    // A coarse sphere of directions in the star's frame, at four radii.
    let (t1, t2) = mean.any_orthonormal_pair();
    for r in [0.3, 0.6, 1.0, 1.5] {
        for (a, b, c) in SPHERE {
            cands.push(p0 + r * h * (a * t1 + b * t2 + c * mean).normalize_or_zero());
        }
    }
    cands
}
