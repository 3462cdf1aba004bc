//! Caps for the small holes of an open surface ([`super::repair_open_surface`]). A hole in a
//! real crown lies in scanner noise: its rim folds, and a cap laid naively across it (a fan from
//! the rim's centroid) can pass through the rim's faces, through faces folded over the hole, or
//! fold over itself. A cap is new surface, not the input's, so it must cross nothing: several
//! caps are tried in turn and the first that crosses no face of the surface (nor itself) is
//! kept. Where none is clear, the one crossing fewest faces is kept and counted.

use super::TriMesh;
use super::topology::EdgeTopology;
use crate::mesh_check::{TriangleGrid, face_box, triangles_intersect};
use glam::DVec3;

/// Offsets of a fan's apex from the rim's centroid along the rim's normal, in units of the
/// rim's mean radius, tried after the centroid itself.
const APEX_OFFSETS: [f64; 6] = [0.25, -0.25, 0.5, -0.5, 1.0, -1.0];

/// Largest rim (vertices) triangulated without a new vertex: the triangulation's search takes
/// time cubic in the rim's length (~45 000 steps at this length). The holes whose fans crossed
/// on rough phantom crowns had rims of 14-36 vertices.
const MAX_FLAT_RIM: usize = 64;

/// A hole's cap: its faces and, for a fan, the apex they share (the new vertex, given the index
/// `apex_index` in the faces).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Cap {
    /// Faces, each using a rim edge reversed (so the cap continues the surface's orientation).
    pub(super) faces: Vec<[u32; 3]>,
    /// The new vertex of a fan, `None` for a cap on the rim's own vertices.
    pub(super) apex: Option<DVec3>,
    /// Face pairs the cap crosses (0 unless no cap tried was clear).
    pub(super) crossings: usize,
    /// The faces of the surface the cap crosses, ascending.
    pub(super) crossed: Vec<u32>,
}

/// What a cap is tested against: the surface's faces before any cap was added, binned once,
/// and its edges. Each cap then costs what its neighbourhood holds, however many holes there are.
pub(super) struct Surface<'a> {
    /// The surface's edge topology (a triangulation never adds an edge the surface has).
    pub(super) topo: &'a EdgeTopology,
    /// The surface's faces (all of them, before any cap).
    pub(super) grid: &'a TriangleGrid,
}

/// The cap of the hole `rim` of `m` (a boundary loop, the surface on its left): the first clear
/// one of a fan from the rim's centroid, fans from apexes moved off it along the rim's normal,
/// and triangulations of the rim's own vertices; else the one crossing fewest faces (first of
/// equals). Clear means crossing no face of `surface` and no face of itself; caps of other holes
/// are checked by the caller.
pub(super) fn cap_hole(m: &mut TriMesh, surface: &Surface, rim: &[u32]) -> Cap {
    let at = |v: u32| m.positions[v as usize];
    let centroid = rim.iter().fold(DVec3::ZERO, |a, &v| a + at(v)) / rim.len() as f64;
    let radius = rim
        .iter()
        .map(|&v| (at(v) - centroid).length())
        .sum::<f64>()
        / rim.len() as f64;
    let normal = rim_normal(m, rim);
    let apex_index = m.positions.len() as u32;
    let fan = |apex: DVec3| fan(rim, apex_index, apex);
    let mut best: Option<Cap> = None;
    let fans = std::iter::once(0.0).chain(APEX_OFFSETS);
    for k in fans {
        let cap = fan(centroid + normal * (k * radius));
        if let Some(clear) = keep_better(m, surface, cap, &mut best) {
            return clear;
        }
    }
    for shape in [Shape::Tilt, Shape::Fold] {
        if let Some(cap) = flat_cap(m, surface.topo, rim, shape)
            && let Some(clear) = keep_better(m, surface, cap, &mut best)
        {
            return clear;
        }
    }
    best.unwrap_or_else(|| fan(centroid))
}

/// The fan over `rim` from a new vertex at `apex`, to be given the index `apex_index`.
pub(super) fn fan(rim: &[u32], apex_index: u32, apex: DVec3) -> Cap {
    Cap {
        faces: (0..rim.len())
            .map(|j| [rim[(j + 1) % rim.len()], rim[j], apex_index])
            .collect(),
        apex: Some(apex),
        crossings: 0,
        crossed: Vec::new(),
    }
}

/// `cap` when it crosses nothing in `m`; else `None`, with `cap` (its crossings counted) put
/// in `best` when it crosses fewer faces than the cap there.
fn keep_better(
    m: &mut TriMesh,
    surface: &Surface,
    cap: Cap,
    best: &mut Option<Cap>,
) -> Option<Cap> {
    let (crossings, crossed) = crossings_of(m, surface.grid, &cap);
    if crossings == 0 {
        return Some(cap);
    }
    if best.as_ref().is_none_or(|b| crossings < b.crossings) {
        *best = Some(Cap {
            crossings,
            crossed,
            ..cap
        });
    }
    None
}

/// The face pairs `cap` crosses (with its apex added to `m`): with the faces binned in `grid`
/// and among its own faces; and the faces of `m` among them (ascending). Tested in place, then
/// taken off.
fn crossings_of(m: &mut TriMesh, grid: &TriangleGrid, cap: &Cap) -> (usize, Vec<u32>) {
    let (nv, nf) = (m.positions.len(), m.triangles.len());
    if let Some(p) = cap.apex {
        m.positions.push(p);
    }
    m.triangles.extend_from_slice(&cap.faces);
    let boxes: Vec<(DVec3, DVec3)> = (0..m.triangles.len())
        .skip(nf)
        .map(|c| face_box(m, c))
        .collect();
    let overlap =
        |a: (DVec3, DVec3), b: (DVec3, DVec3)| a.0.cmple(b.1).all() && b.0.cmple(a.1).all();
    let (mut pairs, mut crossed, mut near) = (0, Vec::new(), Vec::new());
    for (i, &bc) in boxes.iter().enumerate() {
        let c = nf + i;
        near.clear();
        grid.for_each_in_box(bc.0, bc.1, |g| near.push(g));
        near.sort_unstable();
        near.dedup();
        for &g in &near {
            if overlap(bc, face_box(m, g as usize)) && triangles_intersect(m, c, g as usize) {
                pairs += 1;
                crossed.push(g);
            }
        }
        for (j, &bd) in boxes[..i].iter().enumerate() {
            if overlap(bc, bd) && triangles_intersect(m, c, nf + j) {
                pairs += 1;
            }
        }
    }
    m.triangles.truncate(nf);
    m.positions.truncate(nv);
    crossed.sort_unstable();
    crossed.dedup();
    (pairs, crossed)
}

/// The rim's unit normal, pointing to the side the surface faces (the area vector of the rim
/// reversed, as the cap runs it): zero for a degenerate rim.
fn rim_normal(m: &TriMesh, rim: &[u32]) -> DVec3 {
    let at = |v: u32| m.positions[v as usize];
    let o = at(rim[0]);
    let area = (1..rim.len().saturating_sub(1)).fold(DVec3::ZERO, |a, j| {
        a + (at(rim[j]) - o).cross(at(rim[j + 1]) - o)
    });
    (-area).normalize_or_zero()
}

/// What a triangulation of a rim on its own vertices ([`flat_cap`]) makes least.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Shape {
    /// The worst tilt of a face from the rim's normal, then the area: a cap that stays across
    /// the hole's mean plane.
    Tilt,
    /// The worst fold between neighbouring faces (the cap's and the surface's at the rim), then
    /// the area: a cap that continues the surface around it smoothly.
    Fold,
}

/// A triangulation of the rim on its own vertices (no new vertex) making `shape`'s measure
/// least at worst, then the area (dynamic programming over the rim's sub-chains). Chords that
/// are already edges of `m` are not used. `None` for a rim too long ([`MAX_FLAT_RIM`]) or with
/// no such triangulation.
pub(super) fn flat_cap(m: &TriMesh, topo: &EdgeTopology, rim: &[u32], shape: Shape) -> Option<Cap> {
    let n = rim.len();
    if !(3..=MAX_FLAT_RIM).contains(&n) {
        return None;
    }
    let at = |i: usize| m.positions[rim[i] as usize];
    let normal = rim_normal(m, rim);
    // The unit normal of the surface's face on each rim edge i → i + 1 (zero where none).
    let rim_faces: Vec<DVec3> = (0..n)
        .map(|i| {
            topo.faces_of_directed(rim[i], rim[(i + 1) % n])
                .next()
                .map_or(DVec3::ZERO, |f| {
                    let [a, b, c] = m.corners(f as usize);
                    (b - a).cross(c - a).normalize_or_zero()
                })
        })
        .collect();
    // A chord may be used when it is a rim edge or joins two vertices no edge of `m` joins.
    let usable = |i: usize, k: usize| {
        k == i + 1 || (i == 0 && k == n - 1) || topo.edge_face_count(rim[i], rim[k]) == 0
    };
    // The face on i, j, k runs the rim reversed: k → j → i. Its area vector.
    let area_vec = |i: usize, j: usize, k: usize| (at(j) - at(k)).cross(at(i) - at(k));
    let fold = |a: DVec3, b: DVec3| {
        if a == DVec3::ZERO {
            0.0
        } else {
            1.0 - a.dot(b)
        }
    };
    // cost[i][k]: (worst measure, area) of the best triangulation of the chain i..=k closed by
    // the chord (i, k); split[i][k] its apex; unit[i][k] the unit normal of its face on (i, k).
    const NONE: (f64, f64) = (f64::INFINITY, f64::INFINITY);
    let mut cost = vec![NONE; n * n];
    let mut split = vec![usize::MAX; n * n];
    let mut unit = vec![DVec3::ZERO; n * n];
    for i in 0..n - 1 {
        cost[i * n + i + 1] = (0.0, 0.0);
        unit[i * n + i + 1] = rim_faces[i];
    }
    for len in 2..n {
        for i in 0..n - len {
            let k = i + len;
            if !usable(i, k) {
                continue;
            }
            for j in i + 1..k {
                let (a, b) = (cost[i * n + j], cost[j * n + k]);
                if a.0.is_infinite() || b.0.is_infinite() {
                    continue;
                }
                let v = area_vec(i, j, k);
                let area = 0.5 * v.length();
                if area <= 0.0 {
                    continue;
                }
                let u = v / (2.0 * area);
                let measure = match shape {
                    Shape::Tilt => 1.0 - u.dot(normal),
                    Shape::Fold => fold(unit[i * n + j], u).max(fold(unit[j * n + k], u)),
                };
                let c = (a.0.max(b.0).max(measure), a.1 + b.1 + area);
                if c < cost[i * n + k] {
                    cost[i * n + k] = c;
                    split[i * n + k] = j;
                    unit[i * n + k] = u;
                }
            }
        }
    }
    if cost[n - 1].0.is_infinite() {
        return None;
    }
    let mut faces = Vec::with_capacity(n - 2);
    let mut stack = vec![(0, n - 1)];
    while let Some((i, k)) = stack.pop() {
        if k <= i + 1 {
            continue;
        }
        let j = split[i * n + k];
        faces.push([rim[k], rim[j], rim[i]]);
        stack.push((i, j));
        stack.push((j, k));
    }
    Some(Cap {
        faces,
        apex: None,
        crossings: 0,
        crossed: Vec::new(),
    })
}

#[cfg(test)]
mod tests;
