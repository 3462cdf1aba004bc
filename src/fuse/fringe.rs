//! The crown's margin fringe. Real IOS crowns are clipped out of the jaw scan along the label
//! boundary, through triangles: the faces next to the margin are slivers, and with the scanner's
//! per-vertex noise many of them fold over their neighbours. A band attached to a folded margin
//! edge passes through the fold whatever its shape. So before the band is built, crown faces
//! within a short geodesic reach of the margin that cross other crown faces are peeled off, round
//! by round from the margin inwards (so the crown stays one disk whose boundary is the
//! new margin). Nothing farther than the reach from the original margin is removed, and every
//! kept vertex and face is kept bitwise; the crown's own crossings farther up are the input's and
//! stay.

use crate::mesh::{RepairOptions, TriMesh, boundary_loops, repair_open_surface};
use crate::mesh_check::{TriangleGrid, triangles_intersect};
use glam::DVec3;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// What [`trim_fringe`] removed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FringeTrim {
    /// Crown faces removed.
    pub faces: usize,
    /// Crown vertices no longer in the crown (no face left).
    pub vertices: usize,
    /// Largest geodesic distance (mm) of a removed vertex from the original margin.
    pub max_reach_mm: f64,
    /// Rounds of detection and removal run.
    pub rounds: usize,
}

/// Geodesic (edge-path) distance of every vertex from the vertices `sources`, computed up to
/// `limit` (farther vertices get infinity).
pub fn edge_distance(mesh: &TriMesh, sources: &[u32], limit: f64) -> Vec<f64> {
    let n = mesh.positions.len();
    // Vertex adjacency (CSR) from the faces.
    let mut deg = vec![0u32; n + 1];
    for t in &mesh.triangles {
        for &v in t {
            deg[v as usize + 1] += 2;
        }
    }
    for i in 0..n {
        deg[i + 1] += deg[i];
    }
    let mut fill = deg.clone();
    let mut adj = vec![0u32; deg[n] as usize];
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            for w in [b, c] {
                adj[fill[a as usize] as usize] = w;
                fill[a as usize] += 1;
            }
        }
    }
    let mut dist = vec![f64::INFINITY; n];
    // Non-negative f64 bit patterns order like the values.
    let mut heap = BinaryHeap::new();
    for &s in sources {
        dist[s as usize] = 0.0;
        heap.push(Reverse((0u64, s)));
    }
    while let Some(Reverse((bits, v))) = heap.pop() {
        let d = f64::from_bits(bits);
        if d > dist[v as usize] {
            continue;
        }
        let p = mesh.positions[v as usize];
        for &w in &adj[deg[v as usize] as usize..deg[v as usize + 1] as usize] {
            let nd = d + (mesh.positions[w as usize] - p).length();
            if nd <= limit && nd < dist[w as usize] {
                dist[w as usize] = nd;
                heap.push(Reverse((nd.to_bits(), w)));
            }
        }
    }
    dist
}

fn bbox(mesh: &TriMesh, f: usize) -> (DVec3, DVec3) {
    let [a, b, c] = mesh.corners(f);
    (a.min(b).min(c), a.max(b).max(c))
}

/// Pairs `(f, g)` of faces of `mesh`, `f` among `candidates`, that cross (or touch improperly),
/// exact test; each pair once, sorted.
pub fn crossing_pairs(mesh: &TriMesh, candidates: &[u32]) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    if candidates.is_empty() {
        return out;
    }
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for &f in candidates {
        let (l, h) = bbox(mesh, f as usize);
        lo = lo.min(l);
        hi = hi.max(h);
    }
    let near: Vec<u32> = (0..mesh.triangles.len() as u32)
        .filter(|&g| {
            let (l, h) = bbox(mesh, g as usize);
            l.cmple(hi).all() && lo.cmple(h).all()
        })
        .collect();
    let grid = TriangleGrid::over_region(mesh, &near, (lo, hi), 0.0);
    for &f in candidates {
        let (l, h) = bbox(mesh, f as usize);
        for g in grid.faces_in_box(l, h) {
            if g == f {
                continue;
            }
            let (gl, gh) = bbox(mesh, g as usize);
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

/// Removes from the crown (an open disk with one boundary loop; `src[v]` the input vertex each
/// crown vertex is) the faces within geodesic `reach` (mm) of its margin that cross other crown
/// faces or are listed in `extra` (crown faces the band could not clear), with the faces between
/// them and the margin, and repairs it back to one disk. Returns `None` when nothing had to go.
/// `dist_in` is the geodesic distance of each *input* vertex from the original margin
/// ([`edge_distance`] over the first crown), so repeated calls never reach farther. With
/// `listed_apex`, a face of `extra` counts as fringe also when only one of its corners lies
/// beyond the reach (a coarse crown's face on a margin edge, its apex farther than the reach):
/// removing it keeps that corner in the faces around, and a round that would lose a vertex
/// beyond the reach is undone as always.
pub fn trim_fringe(
    crown: &TriMesh,
    src: &[u32],
    dist_in: &[f64],
    reach: f64,
    extra: &[u32],
    listed_apex: bool,
) -> Option<(TriMesh, Vec<u32>, FringeTrim)> {
    let mut mesh = crown.clone();
    let mut map = src.to_vec();
    let mut report = FringeTrim::default();
    let in_reach = |map: &[u32], v: u32| {
        let s = map[v as usize];
        s != u32::MAX && dist_in.get(s as usize).is_some_and(|&d| d <= reach)
    };
    // The faces of `extra`, for the first round only (the crown changes after it).
    let mut listed = vec![false; mesh.triangles.len()];
    for &f in extra {
        if let Some(l) = listed.get_mut(f as usize) {
            *l = true;
        }
    }
    for _ in 0..4 {
        let is_listed = |f: u32| listed.get(f as usize).copied().unwrap_or(false);
        let fringe: Vec<u32> = (0..mesh.triangles.len() as u32)
            .filter(|&f| {
                let near = mesh.triangles[f as usize]
                    .iter()
                    .filter(|&&v| in_reach(&map, v))
                    .count();
                near == 3 || (listed_apex && near == 2 && is_listed(f))
            })
            .collect();
        let is_fringe = {
            let mut v = vec![false; mesh.triangles.len()];
            for &f in &fringe {
                v[f as usize] = true;
            }
            v
        };
        // Of a crossing pair one face has to go: the one nearer the margin (so the least of the
        // crown goes), or the only one in the fringe.
        let depth = |f: u32| {
            mesh.triangles[f as usize]
                .iter()
                .map(|&v| dist_in[map[v as usize] as usize])
                .fold(f64::INFINITY, f64::min)
        };
        let mut bad = vec![false; mesh.triangles.len()];
        for (f, g) in crossing_pairs(&mesh, &fringe) {
            let pick = match (is_fringe[f as usize], is_fringe[g as usize]) {
                (true, true) if depth(g) < depth(f) => g,
                (true, _) => f,
                _ => g,
            };
            bad[pick as usize] = true;
        }
        for (b, &l) in bad.iter_mut().zip(&listed) {
            *b |= l;
        }
        listed.clear();
        // Only faces with an edge on the margin go in one round (peeling): removing a face
        // deeper in would cut a slot into the crown, and a margin that doubles back on itself
        // no longer charts around the tooth. What lies under a removed face is looked at again
        // in the next round.
        let topo = crate::mesh::EdgeTopology::new(&mesh);
        let on_edge = |a: u32, b: u32| topo.edge_face_count(a, b) == 1;
        let mut boundary_vertex = vec![false; mesh.positions.len()];
        for t in &mesh.triangles {
            for k in 0..3 {
                if on_edge(t[k], t[(k + 1) % 3]) {
                    boundary_vertex[t[k] as usize] = true;
                    boundary_vertex[t[(k + 1) % 3] as usize] = true;
                }
            }
        }
        // A target with an edge on the margin goes alone; one touching the margin at a vertex
        // only goes with that vertex's whole fan (removing it alone would pinch the margin).
        let mut remove = vec![false; mesh.triangles.len()];
        let mut fans: Vec<u32> = Vec::new();
        for f in (0..mesh.triangles.len()).filter(|&f| is_fringe[f] && bad[f]) {
            let t = mesh.triangles[f];
            if (0..3).any(|k| on_edge(t[k], t[(k + 1) % 3])) {
                remove[f] = true;
            } else {
                fans.extend(t.iter().copied().filter(|&v| boundary_vertex[v as usize]));
            }
        }
        if !fans.is_empty() {
            fans.sort_unstable();
            fans.dedup();
            let mut fan_faces: Vec<Vec<usize>> = vec![Vec::new(); fans.len()];
            for (f, t) in mesh.triangles.iter().enumerate() {
                for v in t {
                    if let Ok(i) = fans.binary_search(v) {
                        fan_faces[i].push(f);
                    }
                }
            }
            for faces in fan_faces {
                if faces.iter().all(|&f| is_fringe[f]) {
                    for f in faces {
                        remove[f] = true;
                    }
                }
            }
        }
        report.rounds += 1;
        let before = mesh.triangles.len();
        let kept: Vec<[u32; 3]> = mesh
            .triangles
            .iter()
            .enumerate()
            .filter(|&(f, _)| !remove[f])
            .map(|(_, t)| *t)
            .collect();
        if kept.len() == before {
            break;
        }
        let removed = before - kept.len();
        let cut = TriMesh::new(mesh.positions.clone(), kept);
        let (rep, rep_src, _) = repair_open_surface(
            &cut,
            &RepairOptions {
                max_hole_fraction: 0.0,
            },
        );
        if boundary_loops(&rep).len() != 1 {
            break;
        }
        let next: Vec<u32> = rep_src
            .iter()
            .map(|&s| {
                if s == u32::MAX {
                    u32::MAX
                } else {
                    map[s as usize]
                }
            })
            .collect();
        // The repair drops pieces the peeling cut off; should one reach beyond the fringe,
        // this round is not kept (nothing beyond the reach is ever removed).
        let mut still = vec![false; dist_in.len()];
        for &s in next.iter().filter(|&&s| s != u32::MAX) {
            still[s as usize] = true;
        }
        if map
            .iter()
            .any(|&s| s != u32::MAX && !still[s as usize] && dist_in[s as usize] > reach)
        {
            break;
        }
        report.faces += removed;
        map = next;
        mesh = rep;
    }
    if report.faces == 0 {
        return None;
    }
    let mut had = vec![false; dist_in.len()];
    for &s in src.iter().filter(|&&s| s != u32::MAX) {
        had[s as usize] = true;
    }
    for &s in map.iter().filter(|&&s| s != u32::MAX) {
        had[s as usize] = false;
    }
    for (s, h) in had.iter().enumerate() {
        if *h {
            report.vertices += 1;
            report.max_reach_mm = report.max_reach_mm.max(dist_in[s]);
        }
    }
    Some((mesh, map, report))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fan crown: apex 0 at 1 mm from its margin (the ring 1..=8). A listed face on a
    /// margin edge goes only with `listed_apex`, and then alone: its apex stays in the faces
    /// around, so no vertex is lost and the crown stays one disk.
    #[test]
    fn a_listed_margin_face_goes_with_its_apex_beyond_the_reach_kept() {
        let mut positions = vec![DVec3::new(0.0, 0.0, 1.0)];
        positions.extend((0..8).map(|k| {
            let a = std::f64::consts::TAU * k as f64 / 8.0;
            DVec3::new(a.cos(), a.sin(), 0.0)
        }));
        let triangles: Vec<[u32; 3]> = (0..8u32).map(|k| [0, 1 + k, 1 + (k + 1) % 8]).collect();
        let crown = TriMesh::new(positions, triangles);
        let src: Vec<u32> = (0..9).collect();
        let dist_in = edge_distance(&crown, &(1..=8).collect::<Vec<u32>>(), 10.0);
        assert!(dist_in[0] > 0.3 && dist_in[1..].iter().all(|&d| d == 0.0));
        assert!(trim_fringe(&crown, &src, &dist_in, 0.3, &[2], false).is_none());
        let (trimmed, map, t) = trim_fringe(&crown, &src, &dist_in, 0.3, &[2], true).unwrap();
        assert_eq!((t.faces, t.vertices), (1, 0), "{t:?}");
        assert_eq!(trimmed.triangles.len(), 7);
        assert_eq!(map.len(), 9);
        assert_eq!(boundary_loops(&trimmed).len(), 1);
        // The apex is now on the margin, at its position.
        let apex = map.iter().position(|&s| s == 0).unwrap();
        assert_eq!(trimmed.positions[apex], crown.positions[0]);
    }
}
