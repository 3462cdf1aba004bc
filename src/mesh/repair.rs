//! Repair of real-world open surfaces (IOS crowns): real scans are decimated and segmented by
//! other software, so a crown cut out by its labels may carry duplicate or degenerate faces,
//! edges shared by three or more faces, flipped faces, bow-tie vertices, stray islands and small
//! holes. [`repair_open_surface`] turns such a patch into one consistently oriented, manifold
//! disk whose longest boundary loop is the margin, and reports everything it changed.
//! Every input vertex that is still used keeps its exact position; split bow-tie vertices are
//! duplicated, never moved.

use super::topology::{EdgeTopology, boundary_loops, boundary_loops_of, connected_components_of};
use super::validate::{non_manifold_vertices, non_manifold_vertices_of};
use super::vertex_sort::sort_by_vertex;
use super::{TriMesh, sorted_corners};
use crate::mesh_check::{TriangleGrid, triangles_intersect};
use glam::DVec3;
use hole_choice::{Holes, Rim};

/// Options of [`repair_open_surface`].
#[derive(Clone, Copy, Debug)]
pub struct RepairOptions {
    /// Fill every boundary loop except the longest (the margin) whose perimeter is at most this
    /// fraction of the longest loop's perimeter. 0 fills nothing.
    pub max_hole_fraction: f64,
}

impl Default for RepairOptions {
    fn default() -> Self {
        Self {
            max_hole_fraction: 0.5,
        }
    }
}

/// What [`repair_open_surface`] changed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RepairReport {
    /// Faces dropped for repeating a vertex or having zero area.
    pub degenerate_faces: usize,
    /// Faces dropped as duplicates of an earlier face.
    pub duplicate_faces: usize,
    /// Faces dropped because an edge already had two faces.
    pub non_manifold_faces: usize,
    /// Faces flipped to agree with their neighbours.
    pub flipped_faces: usize,
    /// Faces dropped with components other than the largest.
    pub island_faces: usize,
    /// Vertices duplicated to split bow-ties.
    pub split_vertices: usize,
    /// Holes filled (loops other than the margin).
    pub filled_holes: usize,
    /// Vertices added as hole centres.
    pub added_vertices: usize,
    /// Filled holes whose cap crosses the surface: no cap tried was clear, even with the faces
    /// crossed taken with the hole (see [`repair_open_surface`]); the cap crossing fewest faces
    /// was kept.
    pub crossing_caps: usize,
    /// Faces taken with holes they lay over (their caps could not clear them).
    pub rim_faces_removed: usize,
}

impl RepairReport {
    /// True when nothing had to change.
    pub fn is_clean(&self) -> bool {
        *self == RepairReport::default()
    }
}

/// Rounds of [`repair_open_surface`] that take the faces a hole's cap could not clear with the
/// hole and cap it again, at most: a bound on the work, not a count any input was tuned to
/// (a rough phantom crown needed more than 6 rounds and at most 12, 43 faces in all).
const RIM_ROUNDS: usize = 16;

/// Repairs an open surface patch (see the module doc). Returns the repaired mesh, for each of
/// its vertices the input vertex it comes from (`u32::MAX` for added hole centres), and a report.
///
/// A hole is capped only by a cap that crosses no face: the fan from its rim's centroid, fans
/// from apexes moved along the rim's normal, or a triangulation of the rim's own vertices,
/// whichever clears first. Where every cap tried crosses some (a hole whose rim folds over it:
/// scanner noise at a hole's edge), the faces crossed go with the hole (they lie over it) and
/// the repair runs again, up to 16 times; what is still crossed then is counted
/// (`crossing_caps`). Taking faces grows a hole: the later rounds keep the first round's
/// choices, so the margin stays the loop through the first round's margin and a hole it filled
/// is filled however far it grew (a coarse crown's hole at 49 % of the margin's length grew to
/// 72 % and was left open, the tooth lost), while a hole it left open for its size stays open.
/// Positions never move: a vertex only the removed faces used is dropped like any unused vertex.
pub fn repair_open_surface(
    mesh: &TriMesh,
    opts: &RepairOptions,
) -> (TriMesh, Vec<u32>, RepairReport) {
    let mut input = std::borrow::Cow::Borrowed(mesh);
    let mut removed = 0;
    // Per input vertex, what the first round made of its loop (see [`Rim`]).
    let mut rims: Vec<Rim> = Vec::new();
    for round in 0.. {
        let holes = if round == 0 {
            Holes::BySize(&mut rims)
        } else {
            Holes::AsFirst(&rims)
        };
        let (m, source, mut rep, crossed) = repair_once(&input, opts, holes);
        if crossed.is_empty() || round == RIM_ROUNDS {
            rep.rim_faces_removed = removed;
            return (m, source, rep);
        }
        // The crossed faces as input faces (by their corners' input vertices).
        let mut gone: Vec<[u32; 3]> = crossed
            .iter()
            .map(|&f| sorted_corners(m.triangles[f as usize].map(|v| source[v as usize])))
            .collect();
        gone.sort_unstable();
        let kept: Vec<[u32; 3]> = input
            .triangles
            .iter()
            .copied()
            .filter(|&t| gone.binary_search(&sorted_corners(t)).is_err())
            .collect();
        removed += input.triangles.len() - kept.len();
        input = std::borrow::Cow::Owned(TriMesh::new(mesh.positions.clone(), kept));
    }
    unreachable!("the rounds end at RIM_ROUNDS")
}

/// One pass of [`repair_open_surface`], also returning the faces of the repaired mesh that its
/// caps cross (ascending; empty when every cap is clear).
fn repair_once(
    mesh: &TriMesh,
    opts: &RepairOptions,
    holes: Holes,
) -> (TriMesh, Vec<u32>, RepairReport, Vec<u32>) {
    let mut rep = RepairReport::default();
    let n = mesh.positions.len();
    // 1. Degenerate and duplicate faces.
    let faces = distinct_faces(mesh, &mut rep);
    // 2. At most two faces per undirected edge (greedy in face order).
    let kept = two_faces_per_edge(faces, n, &mut rep);
    let m = TriMesh::new(mesh.positions.clone(), kept);
    let topo = EdgeTopology::new(&m);
    repair_rest(m, topo, opts, holes, rep)
}

/// Steps 3 to 7 of [`repair_once`] without hole filling, on `m` whose first two steps have
/// nothing to do (`topo` its topology): the repaired mesh, its vertices' sources and the report.
pub(super) fn repair_rest_unfilled(
    m: TriMesh,
    topo: EdgeTopology,
) -> (TriMesh, Vec<u32>, RepairReport) {
    let opts = RepairOptions {
        max_hole_fraction: 0.0,
    };
    let mut rims = Vec::new();
    let (m, source, rep, crossed) = repair_rest(
        m,
        topo,
        &opts,
        Holes::BySize(&mut rims),
        RepairReport::default(),
    );
    debug_assert!(crossed.is_empty(), "no hole is capped without hole filling");
    (m, source, rep)
}

/// Steps 3 to 7 of [`repair_once`] on `m` (after the first two steps; `topo` its topology,
/// `rep` what those steps counted).
fn repair_rest(
    mut m: TriMesh,
    topo: EdgeTopology,
    opts: &RepairOptions,
    holes: Holes,
    mut rep: RepairReport,
) -> (TriMesh, Vec<u32>, RepairReport, Vec<u32>) {
    let n = m.positions.len();
    // 3. Largest component only. The edge topology is kept for the later steps while the
    // triangles stay exactly as they are (the usual clean crown).
    let (ids, count) = connected_components_of(&topo, m.triangles.len());
    // Consistent here, consistent after the islands go (fewer faces use no directed edge twice).
    let consistent = orientation_consistent(&topo);
    let mut same_topo = Some(topo).filter(|_| count == 1);
    if count > 1 {
        let mut sizes = vec![0usize; count];
        for &c in &ids {
            sizes[c as usize] += 1;
        }
        let best = (0..count)
            .max_by_key(|&c| (sizes[c], std::cmp::Reverse(c)))
            .unwrap_or(0) as u32;
        let before = m.triangles.len();
        m.triangles = m
            .triangles
            .iter()
            .zip(&ids)
            .filter_map(|(t, &c)| (c == best).then_some(*t))
            .collect();
        rep.island_faces = before - m.triangles.len();
    }
    // 4. Consistent orientation by breadth-first propagation, then majority by area. On faces
    // already consistent (the usual crown, or what is left of a peeled one) the propagation
    // flips and drops nothing.
    let before = m.triangles.len();
    rep.flipped_faces = if consistent {
        0
    } else {
        orient_consistently(&mut m)
    };
    // No face flipped an odd number of times and none dropped: the triangles are unchanged.
    if rep.flipped_faces > 0 || m.triangles.len() != before {
        same_topo = None;
    }
    // 5. Split bow-tie vertices.
    let mut source: Vec<u32> = (0..n as u32).collect();
    rep.split_vertices = split_bow_ties(&mut m, &mut source, same_topo.as_ref());
    if rep.split_vertices > 0 {
        same_topo = None;
    }
    // 6. Fill small holes (first round: every loop but the longest, up to the size limit; the
    // later rounds as the first chose).
    let crossed = if opts.max_hole_fraction > 0.0 {
        fill_small_holes(
            &mut m,
            &mut source,
            same_topo.as_ref(),
            opts,
            holes,
            &mut rep,
        )
    } else {
        Vec::new()
    };
    // 7. Drop unused vertices, keeping the source map in step.
    let new_source = compact_with_source(&mut m, |old| source[old]);
    (m, new_source, rep, crossed)
}

/// Drops `m`'s unused vertices ([`TriMesh::compact`]); returns per vertex left the source of
/// the vertex it was (`source_of` its index before).
pub(super) fn compact_with_source(m: &mut TriMesh, source_of: impl Fn(usize) -> u32) -> Vec<u32> {
    let map = m.compact();
    let mut new_source = vec![0u32; m.positions.len()];
    for (old, &new) in map.iter().enumerate() {
        if new != u32::MAX {
            new_source[new as usize] = source_of(old);
        }
    }
    new_source
}

/// Step 1 of [`repair_open_surface`]: the faces without an out-of-range index, a repeated
/// vertex or a zero area, and of faces on the same three vertices the first; counted in `rep`.
fn distinct_faces(mesh: &TriMesh, rep: &mut RepairReport) -> Vec<[u32; 3]> {
    let n = mesh.positions.len();
    let mut faces: Vec<[u32; 3]> = Vec::with_capacity(mesh.triangles.len());
    let mut seen: Vec<[u32; 3]> = Vec::new();
    for (f, t) in mesh.triangles.iter().enumerate() {
        let bad_index = t.iter().any(|&v| v as usize >= n);
        if bad_index
            || t[0] == t[1]
            || t[1] == t[2]
            || t[0] == t[2]
            || mesh.face_cross(f) == DVec3::ZERO
        {
            rep.degenerate_faces += 1;
            continue;
        }
        let k = sorted_corners(*t);
        seen.push(k);
        faces.push(*t);
    }
    // Sorted by (vertex set, face): the keys are distinct, so an unstable sort gives the
    // stable order.
    let mut order: Vec<([u32; 3], u32)> = seen
        .iter()
        .enumerate()
        .map(|(i, &k)| (k, i as u32))
        .collect();
    sort_by_vertex(&mut order, n, |k| k.0[0]);
    let mut dup = vec![false; faces.len()];
    for w in order.windows(2) {
        if w[0].0 == w[1].0 {
            dup[w[1].1 as usize] = true;
        }
    }
    rep.duplicate_faces = dup.iter().filter(|d| **d).count();
    faces
        .into_iter()
        .zip(dup)
        .filter_map(|(t, d)| (!d).then_some(t))
        .collect()
}

/// Step 2 of [`repair_open_surface`]: at most two faces per undirected edge, greedy in face
/// order (a face that would be an edge's third goes, counted in `rep`). Edge ids in sorted
/// (min, max) order, one per face side; `n` vertices.
fn two_faces_per_edge(faces: Vec<[u32; 3]>, n: usize, rep: &mut RepairReport) -> Vec<[u32; 3]> {
    let mut kept: Vec<[u32; 3]> = Vec::with_capacity(faces.len());
    let mut keyed: Vec<(u32, u32, u32)> = Vec::with_capacity(faces.len() * 3);
    for (f, t) in faces.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            keyed.push((a.min(b), a.max(b), (3 * f + k) as u32));
        }
    }
    sort_by_vertex(&mut keyed, n, |k| k.0);
    let mut side_edge = vec![0u32; keyed.len()];
    let mut edges = 0u32;
    for (i, &(a, b, side)) in keyed.iter().enumerate() {
        if i > 0 && (keyed[i - 1].0, keyed[i - 1].1) != (a, b) {
            edges += 1;
        }
        side_edge[side as usize] = edges;
    }
    let mut edge_use = vec![0u8; edges as usize + 1];
    for (f, t) in faces.iter().enumerate() {
        let es = [side_edge[3 * f], side_edge[3 * f + 1], side_edge[3 * f + 2]];
        if es.iter().any(|&e| edge_use[e as usize] >= 2) {
            rep.non_manifold_faces += 1;
            continue;
        }
        for e in es {
            edge_use[e as usize] += 1;
        }
        kept.push(*t);
    }
    kept
}

/// Step 6 of [`repair_open_surface`]: the loops `holes` says (first round: every boundary loop
/// but the longest, the margin, whose perimeter is at most `opts.max_hole_fraction` of the
/// margin's) are capped ([`super::hole_cap::cap_hole`]: a fan around a new vertex at its
/// centroid where that crosses nothing, else another cap; `source` gets `u32::MAX` for a new
/// vertex); `same_topo` is `m`'s edge topology when still valid. Counted in `rep`. Returns the
/// faces of `m` crossed by caps (ascending), where no cap tried was clear.
fn fill_small_holes(
    m: &mut TriMesh,
    source: &mut Vec<u32>,
    same_topo: Option<&EdgeTopology>,
    opts: &RepairOptions,
    holes: Holes,
    rep: &mut RepairReport,
) -> Vec<u32> {
    let mut crossed = Vec::new();
    let loops = match same_topo {
        Some(topo) => boundary_loops_of(topo),
        None => boundary_loops(m),
    };
    let perims: Vec<f64> = loops
        .iter()
        .map(|l| {
            (0..l.len())
                .map(|i| {
                    (m.positions[l[i] as usize] - m.positions[l[(i + 1) % l.len()] as usize])
                        .length()
                })
                .sum()
        })
        .collect();
    let filled = hole_choice::filled_loops(&loops, &perims, source, opts, holes);
    // Built once a hole is to be capped: the topology when the caller's is stale, and the grid
    // of the faces before any cap. Caps of other holes never join two vertices of this one
    // (holes sharing vertices are bow-ties, split in step 5), so the topology stays valid for
    // the chords caps may use; crossings between caps are looked for once all are made.
    let mut built: Option<EdgeTopology> = None;
    let mut grid: Option<TriangleGrid> = None;
    let mut caps: Vec<std::ops::Range<usize>> = Vec::new();
    for (i, l) in loops.iter().enumerate() {
        if !filled[i] {
            continue;
        }
        let topo = match same_topo {
            Some(t) => t,
            None => built.get_or_insert_with(|| EdgeTopology::new(m)),
        };
        let grid = grid.get_or_insert_with(|| TriangleGrid::new(m, 0.0));
        let surface = super::hole_cap::Surface { topo, grid };
        let cap = super::hole_cap::cap_hole(m, &surface, l);
        if let Some(p) = cap.apex {
            m.positions.push(p);
            source.push(u32::MAX);
            rep.added_vertices += 1;
        }
        let first = m.triangles.len();
        m.triangles.extend_from_slice(&cap.faces);
        if cap.crossings > 0 {
            rep.crossing_caps += 1;
            crossed.extend_from_slice(&cap.crossed);
        } else {
            caps.push(first..m.triangles.len());
        }
        rep.filled_holes += 1;
    }
    rep.crossing_caps += caps_crossing_each_other(m, &caps);
    crossed.sort_unstable();
    crossed.dedup();
    crossed
}

/// Of the clear caps `caps` (face ranges of `m`, one per hole), those crossing a cap of another
/// hole (holes close together): counted, nothing else can be done about them.
fn caps_crossing_each_other(m: &TriMesh, caps: &[std::ops::Range<usize>]) -> usize {
    if caps.len() < 2 {
        return 0;
    }
    let faces: Vec<u32> = caps
        .iter()
        .flat_map(|r| r.clone())
        .map(|f| f as u32)
        .collect();
    let hole_of = |f: u32| caps.partition_point(|r| r.end <= f as usize);
    let mut crossing = vec![false; caps.len()];
    for (f, g) in TriangleGrid::over(m, &faces, 0.0).candidate_pairs_unordered(m) {
        let (a, b) = (hole_of(f), hole_of(g));
        if a != b && triangles_intersect(m, f as usize, g as usize) {
            crossing[a] = true;
            crossing[b] = true;
        }
    }
    crossing.iter().filter(|&&c| c).count()
}

/// Whether no directed edge is used by two faces. With at most two faces per undirected edge
/// and no two faces on the same three vertices (steps 1 and 2 of [`repair_open_surface`]), two
/// faces sharing an edge then run it in opposite directions, and [`orient_consistently`] flips
/// and drops nothing.
pub(super) fn orientation_consistent(topo: &EdgeTopology) -> bool {
    topo.half_edges
        .windows(2)
        .all(|w| (w[0].0, w[0].1) != (w[1].0, w[1].1))
}

/// Makes every edge shared by two faces run in opposite directions in them; returns the number
/// of faces flipped. Faces that cannot be made consistent (non-orientable) are dropped.
fn orient_consistently(m: &mut TriMesh) -> usize {
    let nf = m.triangles.len();
    // Undirected edge → faces.
    let mut keyed: Vec<(u32, u32, u32)> = Vec::with_capacity(nf * 3);
    for (f, t) in m.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            keyed.push((a.min(b), a.max(b), f as u32));
        }
    }
    sort_by_vertex(&mut keyed, m.positions.len(), |k| k.0);
    // Face → neighbour faces across shared edges, in sorted-edge order (CSR: no small vectors).
    let mut start = vec![0usize; nf + 1];
    let same_edge = |x: &(u32, u32, u32), y: &(u32, u32, u32)| (x.0, x.1) == (y.0, y.1);
    for w in keyed.windows(2) {
        if same_edge(&w[0], &w[1]) {
            start[w[0].2 as usize + 1] += 1;
            start[w[1].2 as usize + 1] += 1;
        }
    }
    for f in 0..nf {
        start[f + 1] += start[f];
    }
    let mut fill = start.clone();
    let mut adjacent = vec![0u32; start[nf]];
    for w in keyed.windows(2) {
        if same_edge(&w[0], &w[1]) {
            let (f, g) = (w[0].2 as usize, w[1].2 as usize);
            adjacent[fill[f]] = w[1].2;
            fill[f] += 1;
            adjacent[fill[g]] = w[0].2;
            fill[g] += 1;
        }
    }
    let nbrs = |f: usize| &adjacent[start[f]..start[f + 1]];
    let has_directed =
        |t: &[u32; 3], a: u32, b: u32| (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b);
    let mut state = vec![0u8; nf]; // 0 unvisited, 1 kept, 2 flipped
    let mut drop = vec![false; nf];
    let mut flipped = 0;
    for seed in 0..nf {
        if state[seed] != 0 {
            continue;
        }
        state[seed] = 1;
        let mut queue = std::collections::VecDeque::from([seed]);
        let mut comp = vec![seed];
        while let Some(f) = queue.pop_front() {
            let tf = m.triangles[f];
            for &g in nbrs(f) {
                let g = g as usize;
                let tg = m.triangles[g];
                // Shared edge a→b in f; consistent when g has b→a.
                let shared = (0..3)
                    .map(|k| (tf[k], tf[(k + 1) % 3]))
                    .find(|&(a, b)| tg.contains(&a) && tg.contains(&b));
                let Some((a, b)) = shared else { continue };
                let consistent_now = has_directed(&tg, b, a);
                if state[g] == 0 {
                    if !consistent_now {
                        m.triangles[g].swap(1, 2);
                        state[g] = 2;
                    } else {
                        state[g] = 1;
                    }
                    comp.push(g);
                    queue.push_back(g);
                } else if !consistent_now && !drop[f] {
                    drop[g] = true;
                }
            }
        }
        // Majority orientation by original area: flip the whole component back if most of its
        // area was flipped.
        let flipped_area: f64 = comp
            .iter()
            .filter(|&&f| state[f] == 2)
            .map(|&f| m.face_cross(f).length())
            .sum();
        let total: f64 = comp.iter().map(|&f| m.face_cross(f).length()).sum();
        if flipped_area > 0.5 * total {
            for &f in &comp {
                m.triangles[f].swap(1, 2);
                state[f] = if state[f] == 2 { 1 } else { 2 };
            }
        }
        flipped += comp.iter().filter(|&&f| state[f] == 2).count();
    }
    if drop.iter().any(|d| *d) {
        let kept: Vec<[u32; 3]> = m
            .triangles
            .iter()
            .zip(&drop)
            .filter_map(|(t, &d)| (!d).then_some(*t))
            .collect();
        m.triangles = kept;
    }
    flipped
}

/// Gives each extra fan of a bow-tie vertex its own copy of the vertex; returns copies made.
/// `topo`, if given, is the edge topology of `m` as it comes in (used by the first round).
fn split_bow_ties(m: &mut TriMesh, source: &mut Vec<u32>, topo: Option<&EdgeTopology>) -> usize {
    let mut made = 0;
    for round in 0..4 {
        let bad = match topo {
            Some(t) if round == 0 => non_manifold_vertices_of(m, t),
            _ => non_manifold_vertices(m),
        };
        if bad.is_empty() {
            break;
        }
        // The faces around each bad vertex, in face order, gathered in one pass (splitting one
        // vertex renames only its own corners, so the others' face lists stay as they are).
        let mut order: Vec<(u32, usize)> = bad.iter().enumerate().map(|(i, &v)| (v, i)).collect();
        order.sort_unstable();
        let mut fans: Vec<Vec<usize>> = vec![Vec::new(); bad.len()];
        for (f, t) in m.triangles.iter().enumerate() {
            for c in t {
                if let Ok(j) = order.binary_search_by_key(c, |o| o.0) {
                    fans[order[j].1].push(f);
                }
            }
        }
        for (v, fan_faces) in bad.into_iter().zip(fans) {
            if fan_faces.is_empty() {
                continue;
            }
            // Faces around v, grouped into fans by shared edges through v.
            let k = fan_faces.len();
            let mut parent: Vec<usize> = (0..k).collect();
            fn find(p: &mut [usize], mut x: usize) -> usize {
                while p[x] != x {
                    p[x] = p[p[x]];
                    x = p[x];
                }
                x
            }
            for i in 0..k {
                for j in i + 1..k {
                    let (ti, tj) = (m.triangles[fan_faces[i]], m.triangles[fan_faces[j]]);
                    let shares = ti.iter().any(|&a| a != v && tj.contains(&a));
                    if shares {
                        let (a, b) = (find(&mut parent, i), find(&mut parent, j));
                        parent[a.max(b)] = a.min(b);
                    }
                }
            }
            let mut roots: Vec<usize> = (0..k).map(|i| find(&mut parent, i)).collect();
            let first_root = roots[0];
            let mut copies: Vec<(usize, u32)> = Vec::new();
            for i in 0..k {
                let r = roots[i];
                if r == first_root {
                    continue;
                }
                let nv = match copies.iter().find(|c| c.0 == r) {
                    Some(c) => c.1,
                    None => {
                        let nv = m.positions.len() as u32;
                        m.positions.push(m.positions[v as usize]);
                        source.push(source[v as usize]);
                        copies.push((r, nv));
                        made += 1;
                        nv
                    }
                };
                for c in m.triangles[fan_faces[i]].iter_mut() {
                    if *c == v {
                        *c = nv;
                    }
                }
            }
            roots.clear();
        }
    }
    made
}

mod hole_choice;

#[cfg(test)]
mod tests;
