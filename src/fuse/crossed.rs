//! Which crown faces a build leaves crossed by its band: the faces the rebuilds and the polish
//! trim from the crown's fringe.

use super::assembly::Assembled;

/// Crown faces (indices below `band.start`) to trim for the crossing pairs the untangling left:
/// the crown faces in a pair, or with `ring` those and every crown face sharing a vertex with
/// one (where trimming the faces alone has not cleared the band, it mostly crosses their
/// neighbours next); when no pair has a crown face (band with band or root), the crown faces at
/// the margin vertices of its band faces, so that the margin there moves and the band is laid
/// out anew.
pub(super) fn crown_faces_hit(a: &Assembled, ring: bool) -> Vec<u32> {
    let crown_vertices = a.crown_vertices;
    let Some(u) = &a.untangle else {
        return Vec::new();
    };
    let is_crown = |f: u32| (f as usize) < a.band.start;
    let corners = |f: u32| a.mesh.triangles[f as usize].into_iter();
    let mut hit: Vec<u32> = u
        .crossing_pairs
        .iter()
        .flat_map(|&(f, g)| [f, g])
        .filter(|&f| is_crown(f))
        .collect();
    if !ring && !hit.is_empty() {
        hit.sort_unstable();
        hit.dedup();
        return hit;
    }
    let mut at: Vec<u32> = hit.into_iter().flat_map(corners).collect();
    if at.is_empty() {
        at = u
            .crossing_pairs
            .iter()
            .flat_map(|&(f, g)| [f, g])
            .filter(|&f| a.band.contains(&(f as usize)))
            .flat_map(corners)
            .filter(|&x| (x as usize) < crown_vertices)
            .collect();
    }
    at.sort_unstable();
    at.dedup();
    if at.is_empty() {
        return Vec::new();
    }
    (0..a.band.start as u32)
        .filter(|&f| corners(f).any(|x| at.binary_search(&x).is_ok()))
        .collect()
}

/// The crown faces on a margin edge of a band face that crosses a crown face `g`, where the crown
/// face on that edge crosses `g` too: the margin edge then passes through `g` (a fold of the
/// crown at the margin), so no band face on that edge can clear `g` however its free corner
/// moves; the margin there has to move (or `g` go).
pub(super) fn pierced_margin_faces(a: &Assembled) -> Vec<u32> {
    let crown_vertices = a.crown_vertices;
    let Some(u) = &a.untangle else {
        return Vec::new();
    };
    let is_crown = |f: u32| (f as usize) < a.band.start;
    // The margin edges (both corners crown vertices) of the band faces that cross a crown face,
    // each with that crown face `g`, keyed by the edge's sorted corners.
    let mut edges: Vec<((u32, u32), u32)> = Vec::new();
    for &(f, g) in &u.crossing_pairs {
        let (band_face, g) = match (is_crown(f), is_crown(g)) {
            (false, true) => (f, g),
            (true, false) => (g, f),
            _ => continue,
        };
        if !a.band.contains(&(band_face as usize)) {
            continue;
        }
        let t = a.mesh.triangles[band_face as usize];
        for k in 0..3 {
            let (p, q) = (t[k], t[(k + 1) % 3]);
            if (p as usize) < crown_vertices && (q as usize) < crown_vertices {
                edges.push(((p.min(q), p.max(q)), g));
            }
        }
    }
    if edges.is_empty() {
        return Vec::new();
    }
    edges.sort_unstable();
    // One pass over the crown faces: those on one of the edges that cross its `g` too.
    let mut out = Vec::new();
    for (c, ct) in a.mesh.triangles[..a.band.start].iter().enumerate() {
        for k in 0..3 {
            let (p, q) = (ct[k], ct[(k + 1) % 3]);
            let key = (p.min(q), p.max(q));
            let from = edges.partition_point(|e| e.0 < key);
            for &(_, g) in edges[from..].iter().take_while(|e| e.0 == key) {
                if c as u32 != g && crate::mesh_check::triangles_intersect(&a.mesh, c, g as usize) {
                    out.push(c as u32);
                }
            }
        }
    }
    out
}
