//! Band clean-up after assembly (ours; replaces nothing in the paper, which leaves the
//! DELAUNAY3D output as is): edge flips between two band faces that raise the smaller minimum
//! angle (3D), and Laplacian (umbrella) relaxation of band-interior vertices only. Crown and
//! root vertices and edges are never touched, so every IOS crown vertex keeps its exact position
//! and the mesh stays closed and manifold (a flip is refused when the new edge already exists).
//! The whole clean-up is kept only if it does not add intersecting face pairs (exact test).

use crate::mesh::TriMesh;
use crate::mesh_check;
use glam::DVec3;
use rustc_hash::FxHashMap as HashMap;

/// Smallest angle (degrees) of a triangle given by corner positions (0 for a degenerate one):
/// the smallest of [`triangle_angles`](super::quality::triangle_angles), found as the angle at
/// the corner with the largest cosine (computed as `angle_between` does), so with one inverse
/// cosine instead of three.
pub(super) fn min_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    angle_of_cos(max_cos(a, b, c))
}

/// The largest corner cosine of a triangle (NaN only for a degenerate one): its smallest angle
/// is [`angle_of_cos`] of it. The inverse cosine decreases (up to its last bit), so the smallest
/// angle of several triangles is that of their largest cosine, and a larger largest cosine is
/// no larger smallest angle: comparisons need one inverse cosine, or none. The angles compared
/// here are compared with tolerances (0.1°, 10⁻⁶°) far above a last bit.
pub(super) fn max_cos(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let cos = |p: DVec3, q: DVec3, r: DVec3| {
        let (u, v) = (q - p, r - p);
        u.dot(v) / (u.length_squared() * v.length_squared()).sqrt()
    };
    cos(a, b, c).max(cos(b, c, a)).max(cos(c, a, b))
}

/// The angle (degrees) whose cosine is `m`, clamped to [-1, 1]; 0 for NaN.
pub(super) fn angle_of_cos(m: f64) -> f64 {
    let deg = m.clamp(-1.0, 1.0).acos().to_degrees();
    if deg.is_finite() { deg } else { 0.0 }
}

fn normal(a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    (b - a).cross(c - a)
}

/// Undirected edge key.
fn key(a: u32, b: u32) -> (u32, u32) {
    if a < b { (a, b) } else { (b, a) }
}

/// The faces of an edge: the first two, and how many there are.
#[derive(Clone, Copy, Default)]
struct EdgeFaces {
    faces: [usize; 2],
    count: usize,
}

impl EdgeFaces {
    fn push(&mut self, f: usize) {
        if self.count < 2 {
            self.faces[self.count] = f;
        }
        self.count += 1;
    }
}

/// One pass of min-angle-raising flips of edges shared by two band faces. `faces` must hold
/// every face that can hold an edge between two band vertices (the band faces and every face
/// touching a loop vertex): a flip must not create an edge that exists. Returns the flips made.
fn flip_pass(mesh: &mut TriMesh, band: std::ops::Range<usize>, faces: &[usize]) -> usize {
    flip_pass_where(mesh, band, faces, |_, _, _| true)
}

/// [`flip_pass`] over the edges whose two faces `consider(f, g)` accepts.
fn flip_pass_where(
    mesh: &mut TriMesh,
    band: std::ops::Range<usize>,
    faces: &[usize],
    consider: impl Fn(&TriMesh, usize, usize) -> bool,
) -> usize {
    // Edge → its faces in `faces` order (the first two, and how many). A hash map for lookups
    // only: the edges are visited in sorted order, so the result does not depend on hashing.
    let mut edges: HashMap<(u32, u32), EdgeFaces> =
        HashMap::with_capacity_and_hasher(faces.len() * 2, Default::default());
    for &f in faces {
        let t = mesh.triangles[f];
        for k in 0..3 {
            edges.entry(key(t[k], t[(k + 1) % 3])).or_default().push(f);
        }
    }
    let in_band = |f: usize| band.contains(&f);
    let mut flips = 0;
    let mut keys: Vec<(u32, u32)> = edges.keys().copied().collect();
    crate::radix::sort_by_key(&mut keys, |&(a, b)| (a as u64) << 32 | b as u64);
    for e in keys {
        let (f, g) = match edges.get(&e) {
            Some(fs) if fs.count == 2 && in_band(fs.faces[0]) && in_band(fs.faces[1]) => {
                (fs.faces[0], fs.faces[1])
            }
            _ => continue,
        };
        if !consider(mesh, f, g) {
            continue;
        }
        let (tf, tg) = (mesh.triangles[f], mesh.triangles[g]);
        // Rotate so tf = (a, b, c) with directed edge a→b the shared edge; tg has b→a.
        let Some(kf) = (0..3).find(|&k| key(tf[k], tf[(k + 1) % 3]) == e) else {
            continue;
        };
        let (a, b, c) = (tf[kf], tf[(kf + 1) % 3], tf[(kf + 2) % 3]);
        let Some(kg) = (0..3).find(|&k| tg[k] == b && tg[(k + 1) % 3] == a) else {
            continue;
        };
        let d = tg[(kg + 2) % 3];
        if c == d || edges.contains_key(&key(c, d)) {
            continue;
        }
        let p = |v: u32| mesh.positions[v as usize];
        // New faces: (c, a, d) and (d, b, c) keep the orientation.
        let (n1, n2) = ([c, a, d], [d, b, c]);
        let cos_old = [max_cos(p(a), p(b), p(c)), max_cos(p(b), p(a), p(d))];
        let cos_new = [max_cos(p(c), p(a), p(d)), max_cos(p(d), p(b), p(c))];
        // A larger largest cosine is a smaller smallest angle: no gain, no inverse cosine.
        if cos_old.iter().chain(&cos_new).all(|m| !m.is_nan())
            && cos_new[0].max(cos_new[1]) >= cos_old[0].max(cos_old[1])
        {
            continue;
        }
        let old = angle_of_cos(cos_old[0]).min(angle_of_cos(cos_old[1]));
        let new = angle_of_cos(cos_new[0]).min(angle_of_cos(cos_new[1]));
        if new <= old + 1e-6 {
            continue;
        }
        // Refuse folds: both new normals must agree with the old pair's and with each other.
        let n_old = normal(p(a), p(b), p(c)).normalize_or_zero()
            + normal(p(b), p(a), p(d)).normalize_or_zero();
        let (m1, m2) = (
            normal(p(c), p(a), p(d)).normalize_or_zero(),
            normal(p(d), p(b), p(c)).normalize_or_zero(),
        );
        if m1.dot(n_old) <= 0.5 || m2.dot(n_old) <= 0.5 || m1.dot(m2) <= 0.5 {
            continue;
        }
        mesh.triangles[f] = n1;
        mesh.triangles[g] = n2;
        // Update the edge map for the four outer edges and the swapped diagonal.
        edges.remove(&e);
        edges.insert(
            key(c, d),
            EdgeFaces {
                faces: [f, g],
                count: 2,
            },
        );
        for (x, y, from, to) in [(b, c, f, g), (a, d, g, f)] {
            if let Some(v) = edges.get_mut(&key(x, y)) {
                for h in v.faces.iter_mut().take(v.count.min(2)) {
                    if *h == from {
                        *h = to;
                    }
                }
            }
        }
        flips += 1;
    }
    flips
}

/// Laplacian (umbrella) relaxation of vertices `movable` (band interior), one step of weight
/// `lambda`, using only band faces for the neighbourhoods.
fn relax_pass(
    mesh: &mut TriMesh,
    band: std::ops::Range<usize>,
    movable: std::ops::Range<u32>,
    lambda: f64,
) {
    let n = mesh.positions.len();
    let mut sum = vec![DVec3::ZERO; n];
    let mut cnt = vec![0u32; n];
    for f in band.clone() {
        let t = mesh.triangles[f];
        for k in 0..3 {
            let v = t[k] as usize;
            // Interior edges are seen from both faces: every neighbour counts twice, evenly.
            let w = t[(k + 1) % 3] as usize;
            sum[v] += mesh.positions[w];
            cnt[v] += 1;
            sum[w] += mesh.positions[v];
            cnt[w] += 1;
        }
    }
    let old = mesh.positions.clone();
    for v in movable {
        let v = v as usize;
        if cnt[v] == 0 {
            continue;
        }
        let c = sum[v] / cnt[v] as f64;
        // Full (not only tangential) umbrella step: measured on the phantom, flattening the
        // band's folds removes about half the remaining crossings; the loops stay fixed.
        mesh.positions[v] = old[v] + lambda * (c - old[v]);
    }
}

/// Smallest angle over the band faces.
pub fn band_min_angle(mesh: &TriMesh, band: std::ops::Range<usize>) -> f64 {
    band.map(|f| {
        let [a, b, c] = mesh.corners(f);
        min_angle(a, b, c)
    })
    .fold(180.0, f64::min)
}

/// Improves the band faces `band` of `mesh` in place (flips, then relaxation of the vertices
/// `movable` alternating with flips). Kept only if the mesh gets no more intersecting face pairs
/// and no smaller band minimum angle; returns whether it was kept.
pub fn optimize_band(
    mesh: &mut TriMesh,
    band: std::ops::Range<usize>,
    movable: std::ops::Range<u32>,
) -> bool {
    let before = mesh.clone();
    let si_before = mesh_check::self_intersections(mesh).len();
    let ang_before = band_min_angle(mesh, band.clone());
    let deg_before = mesh_check::degenerate_faces(mesh);
    let all: Vec<usize> = (0..mesh.triangles.len()).collect();
    for _ in 0..6 {
        if flip_pass(mesh, band.clone(), &all) == 0 {
            break;
        }
    }
    for _ in 0..24 {
        relax_pass(mesh, band.clone(), movable.clone(), 0.5);
        flip_pass(mesh, band.clone(), &all);
    }
    for _ in 0..4 {
        if flip_pass(mesh, band.clone(), &all) == 0 {
            break;
        }
    }
    let ok = mesh.positions.iter().all(|p| p.is_finite())
        && mesh_check::degenerate_faces(mesh) <= deg_before
        && band_min_angle(mesh, band.clone()) >= ang_before
        && mesh_check::self_intersections(mesh).len() <= si_before;
    if !ok {
        *mesh = before;
    }
    ok
}

/// Min-angle-raising edge flips between band faces only (no vertex moves, no global check):
/// fast, keeps the mesh closed and manifold, and refuses flips that fold (see [`flip_pass`]).
/// Returns the number of flips.
pub fn flip_band(mesh: &mut TriMesh, band: std::ops::Range<usize>, passes: usize) -> usize {
    let faces = flip_faces(mesh, band.clone());
    let mut total = 0;
    for _ in 0..passes {
        let n = flip_pass(mesh, band.clone(), &faces);
        total += n;
        if n == 0 {
            break;
        }
    }
    total
}

/// Flips only edges of band faces with exactly collinear corners (zero area), each to the
/// neighbour across it that makes both new faces better (the same fold-refusing rule as
/// [`flip_band`]); for presets without the band flips (the paper's), whose point clouds can put
/// three band vertices on a line. Returns the number of flips.
pub fn fix_degenerate_band(mesh: &mut TriMesh, band: std::ops::Range<usize>) -> usize {
    let flat = |m: &TriMesh, f: usize| crate::mesh_check::is_degenerate(m, f);
    if !band.clone().any(|f| flat(mesh, f)) {
        return 0;
    }
    let faces = flip_faces(mesh, band.clone());
    let mut total = 0;
    for _ in 0..4 {
        let n = flip_pass_where(mesh, band.clone(), &faces, |m, f, g| {
            flat(m, f) || flat(m, g)
        });
        total += n;
        if n == 0 {
            break;
        }
    }
    total
}

/// The band faces and every face touching a band vertex (see [`flip_pass`]).
fn flip_faces(mesh: &TriMesh, band: std::ops::Range<usize>) -> Vec<usize> {
    let mut on_band = vec![false; mesh.positions.len()];
    for f in band.clone() {
        for v in mesh.triangles[f] {
            on_band[v as usize] = true;
        }
    }
    (0..mesh.triangles.len())
        .filter(|&f| band.contains(&f) || mesh.triangles[f].iter().any(|&v| on_band[v as usize]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fuse::quality::triangle_angles;

    /// The one-acos smallest angle is bitwise the smallest of the three angles, on random
    /// triangles, slivers, needles and degenerate ones (repeated or collinear corners: 0).
    #[test]
    fn min_angle_is_the_smallest_of_the_three() {
        let mut rng = crate::phantom::rng::Rng::new(1);
        let mut next = || rng.range(-1.0, 1.0);
        let reference = |a, b, c| {
            let [x, y, z] = triangle_angles(a, b, c);
            let m = x.min(y).min(z);
            if m.is_finite() { m } else { 0.0 }
        };
        for k in 0..100_000 {
            let a = DVec3::new(next(), next(), next());
            let mut b = DVec3::new(next(), next(), next());
            let mut c = DVec3::new(next(), next(), next());
            match k % 5 {
                1 => c = a + (b - a) * 0.5 + DVec3::splat(1e-9 * next()),
                2 => c = a + (b - a) * 1e-7,
                3 => b = a,
                4 => c = a + (b - a) * 2.0,
                _ => {}
            }
            let (m, r) = (min_angle(a, b, c), reference(a, b, c));
            assert_eq!(m.to_bits(), r.to_bits(), "{a} {b} {c}: {m} vs {r}");
        }
        assert_eq!(min_angle(DVec3::ZERO, DVec3::ZERO, DVec3::ZERO), 0.0);
    }
}
