//! The last remedy for a band that still crosses the crown where it skips a margin vertex. On
//! ragged exports two margin vertices can sit a few micrometres apart with a third between
//! them, or the margin can jut out at one vertex; the chart band then joins the two neighbours
//! of that vertex by a band edge (a chord of the margin) and folds through the vertex's sliver
//! crown faces. Trimming those faces leaves a notch as narrow as the gap, which the band
//! folds into next. Instead, the skipped vertex is collapsed onto one of its margin
//! neighbours: its crown faces are re-made on that neighbour (no vertex moves, none is added;
//! the faces re-made are not input faces and are counted as added crown faces), so the margin
//! runs straight along the chord, and the band is built again. The collapsed vertex leaves
//! the crown (counted as trimmed, at the margin).

use super::FuseOptions;
use super::assembly::{Assembled, add_trim, builds_from, crossings_left, trimmed_side};
use super::fringe::FringeTrim;
use super::tooth::CutTooth;
use crate::mesh::{EdgeTopology, TriMesh, boundary_loops};
use crate::mesh_check::crossing_pairs;

/// What [`rebuilt`] made: the build kept, the tooth's whole trim, and the margin vertices
/// collapsed.
pub(super) struct Collapsed {
    pub(super) kept: Assembled,
    pub(super) trim: FringeTrim,
    pub(super) vertices: usize,
}

/// The builds of `ct` made again from the crown of the build `a` (whose trim is `trim`) with the
/// margin vertices the band skips collapsed ([`skipped_vertices`], [`collapse`] onto the
/// vertex before, else the one after). `None` when no vertex can be collapsed, the builds fail
/// or leave no fewer crossings than `a`, or the tooth's builds are spent.
pub(super) fn rebuilt(
    ct: &CutTooth,
    opts: &FuseOptions,
    a: &Assembled,
    trim: &FringeTrim,
) -> Option<Collapsed> {
    if !super::build_budget::more() {
        return None;
    }
    let mut crown = crown_of(a);
    let skipped = skipped_vertices(a, &crown);
    let mut vertices = 0;
    for (before, k, after) in skipped {
        if let Some(c) = collapse(&crown, k, before).or_else(|| collapse(&crown, k, after)) {
            crown = c;
            vertices += 1;
        }
    }
    if vertices == 0 {
        return None;
    }
    let faces_before = crown.triangles.len();
    let remap = crown.compact();
    let mut map = vec![u32::MAX; crown.positions.len()];
    let mut lost = FringeTrim {
        faces: a.band.start - faces_before,
        ..FringeTrim::default()
    };
    for (old, &new) in remap.iter().enumerate() {
        let src = a.ios_vertex[old];
        if new != u32::MAX {
            map[new as usize] = src;
        } else if src != u32::MAX {
            lost.vertices += 1;
            lost.max_reach_mm = lost.max_reach_mm.max(ct.dist_in[src as usize]);
        }
    }
    if boundary_loops(&crown).len() != 1 {
        return None;
    }
    let side = trimmed_side(ct, crown, map);
    let (kept, t) = builds_from(ct, side, opts, None).ok()?;
    if crossings_left(&kept) >= crossings_left(a) {
        return None;
    }
    // The builds count their trims from the cut's; the tooth's are `trim`'s, the collapse's and
    // what the builds added.
    let mut total = *trim;
    add_trim(&mut total, &lost);
    add_trim(
        &mut total,
        &FringeTrim {
            faces: t.faces.saturating_sub(ct.trimmed.faces),
            vertices: t.vertices.saturating_sub(ct.trimmed.vertices),
            max_reach_mm: t.max_reach_mm,
            rounds: t.rounds.saturating_sub(ct.trimmed.rounds),
        },
    );
    Some(Collapsed {
        kept,
        trim: total,
        vertices,
    })
}

/// Margin vertices skipped by a band edge and holding a crown face the band crosses, with
/// their two margin neighbours: `(before, skipped, after)` in loop order, by skipped vertex.
/// `crown`: the crown part of `a` ([`crown_of`]).
pub(super) fn skipped_vertices(a: &Assembled, crown: &TriMesh) -> Vec<(u32, u32, u32)> {
    let Some(u) = &a.untangle else {
        return Vec::new();
    };
    let crown_vertices = a.crown_vertices;
    let loops = boundary_loops(crown);
    let [margin] = loops.as_slice() else {
        return Vec::new();
    };
    let n = margin.len();
    let mut at = vec![usize::MAX; crown_vertices];
    for (k, &v) in margin.iter().enumerate() {
        at[v as usize] = k;
    }
    let hit: Vec<u32> = u
        .crossing_pairs
        .iter()
        .flat_map(|&(f, g)| [f, g])
        .filter(|&f| (f as usize) < a.band.start)
        .collect();
    let holds_hit = |v: u32| {
        hit.iter()
            .any(|&f| a.mesh.triangles[f as usize].contains(&v))
    };
    let mut out = Vec::new();
    for f in a.band.clone() {
        let t = a.mesh.triangles[f];
        for e in 0..3 {
            let (p, q) = (t[e] as usize, t[(e + 1) % 3] as usize);
            if p >= crown_vertices || q >= crown_vertices {
                continue;
            }
            let (kp, kq) = (at[p], at[q]);
            if kp == usize::MAX || kq == usize::MAX {
                continue;
            }
            // Two apart along the loop, either way round: the vertex between is skipped.
            for (lo, hi) in [(kp, kq), (kq, kp)] {
                if (lo + 2) % n == hi {
                    let mid = margin[(lo + 1) % n];
                    if holds_hit(mid) {
                        out.push((margin[lo], mid, margin[hi]));
                    }
                }
            }
        }
    }
    out.sort_unstable_by_key(|s| s.1);
    out.dedup_by_key(|s| s.1);
    out
}

/// The crown part of `a`'s mesh (its crown vertices and the faces before the band).
fn crown_of(a: &Assembled) -> TriMesh {
    TriMesh::new(
        a.mesh.positions[..a.crown_vertices].to_vec(),
        a.mesh.triangles[..a.band.start].to_vec(),
    )
}

/// `crown` with vertex `k` collapsed onto `onto` (an edge of the crown): the faces holding both
/// go, `k` is replaced by `onto` in the others. `None` when that would repeat an edge or a face,
/// turn a face over (its normal against the old one), or make a face that crosses a crown face.
pub(super) fn collapse(crown: &TriMesh, k: u32, onto: u32) -> Option<TriMesh> {
    let normal = |t: [u32; 3]| {
        let [a, b, c] = t.map(|v| crown.positions[v as usize]);
        (b - a).cross(c - a)
    };
    let mut triangles = Vec::with_capacity(crown.triangles.len());
    let (mut made, mut on_edge) = (Vec::new(), false);
    for &t in &crown.triangles {
        if !t.contains(&k) {
            triangles.push(t);
        } else if t.contains(&onto) {
            on_edge = true;
        } else {
            let n = t.map(|v| if v == k { onto } else { v });
            if normal(n).dot(normal(t)) <= 0.0 {
                return None;
            }
            made.push(triangles.len() as u32);
            triangles.push(n);
        }
    }
    if !on_edge {
        return None;
    }
    let out = TriMesh::new(crown.positions.clone(), triangles);
    // Every undirected edge in at most two faces, once each way; no face twice.
    let topo = EdgeTopology::new(&out);
    let (_, non_manifold) = topo.edge_counts();
    if non_manifold > 0 {
        return None;
    }
    let crossed = crossing_pairs(&out, &made);
    crossed.is_empty().then_some(out)
}

#[cfg(test)]
mod tests;
