//! The crown's margin fringe. Real IOS crowns are clipped out of the jaw scan along the label
//! boundary, through triangles: the faces next to the margin are slivers, and with the scanner's
//! per-vertex noise many of them fold over their neighbours. A band attached to a folded margin
//! edge passes through the fold whatever its shape. So before the band is built, crown faces
//! within a short geodesic reach of the margin that cross other crown faces are peeled off, round
//! by round from the margin inwards (so the crown stays one disk whose boundary is the
//! new margin). Nothing farther than the reach from the original margin is removed, and every
//! kept vertex and face is kept bitwise; the crown's own crossings farther up are the input's and
//! stay.

use crate::mesh::{EdgeTopology, TriMesh, is_repaired};
pub use crate::mesh_check::crossing_pairs;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Which listed faces (the `extra` of [`trim_fringe`]) count as fringe beside the faces whose
/// corners all lie within the reach.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Listed {
    /// None: only faces within the reach.
    Within,
    /// A listed face with one corner beyond the reach; and a listed face touching the margin
    /// at a vertex goes with that vertex's whole fan even where faces of the fan reach beyond.
    Apex,
    /// As [`Listed::Apex`], and a listed face on a margin edge whatever the reach of its
    /// corners (after earlier trims the margin itself may lie beyond the reach); where nothing
    /// else goes, the fringe faces on the margin beside a listed face that lies off it.
    MarginEdge,
}

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

/// Removes from the crown (an open disk with one boundary loop; `src[v]` the input vertex each
/// crown vertex is) the faces within geodesic `reach` (mm) of its margin that cross other crown
/// faces or are listed in `extra` (crown faces the band could not clear), with the faces between
/// them and the margin, and repairs it back to one disk. Returns `None` when nothing had to go.
/// `dist_in` is the geodesic distance of each *input* vertex from the original margin
/// ([`edge_distance`] over the first crown), so repeated calls never reach farther. With
/// [`Listed::Apex`], a face of `extra` counts as fringe also when only one of its corners lies
/// beyond the reach (a coarse crown's face on a margin edge, its apex farther than the reach):
/// removing it keeps that corner in the faces around; and a listed face touching the margin at
/// a vertex goes with that vertex's whole fan even where faces of the fan reach beyond. With
/// [`Listed::MarginEdge`] besides, a listed face on a margin edge counts whatever the reach of
/// its corners (earlier trims may have moved the margin itself beyond the reach): it goes alone
/// and its corners stay in the faces around. Either way no vertex beyond the reach is lost: a
/// removal that would lose one is put back (see `peel`).
pub fn trim_fringe(
    crown: &TriMesh,
    src: &[u32],
    dist_in: &[f64],
    reach: f64,
    extra: &[u32],
    listed_mode: Listed,
) -> Option<(TriMesh, Vec<u32>, FringeTrim)> {
    trim_rounds(
        crown,
        src,
        dist_in,
        reach,
        extra,
        listed_mode,
        Shortcuts::ALL,
    )
}

/// Work [`trim_rounds`] may spare where it can prove the result the same (the tests compare
/// every combination).
#[derive(Clone, Copy, Debug)]
struct Shortcuts {
    /// A round takes the crossing pairs from the round before where it can (see
    /// [`carried_pairs`]) instead of searching the crown for them again.
    carry_pairs: bool,
    /// A peel off a crown the repair would leave as it is repairs only what the removal can
    /// have changed ([`taken_away`], [`repair_taken`]) instead of the whole crown.
    skip_repair: bool,
}

impl Shortcuts {
    const ALL: Shortcuts = Shortcuts {
        carry_pairs: true,
        skip_repair: true,
    };
}

/// [`trim_fringe`], with the `shortcuts` it takes (the same trim with any of them).
fn trim_rounds(
    crown: &TriMesh,
    src: &[u32],
    dist_in: &[f64],
    reach: f64,
    extra: &[u32],
    listed_mode: Listed,
    shortcuts: Shortcuts,
) -> Option<(TriMesh, Vec<u32>, FringeTrim)> {
    let mut mesh = crown.clone();
    let mut map = src.to_vec();
    let mut report = FringeTrim::default();
    // The faces of `extra`, for the first round only (the crown changes after it).
    let mut listed = vec![false; mesh.triangles.len()];
    for &f in extra {
        if let Some(l) = listed.get_mut(f as usize) {
            *l = true;
        }
    }
    // The crossing pairs with a face of the last round's fringe, renumbered for the crown as it
    // is now, when the peel allows (see `carried_pairs`).
    let mut carried: Option<Vec<(u32, u32)>> = None;
    // The crown's topology when a peel has built it, and whether the crown is known to be one
    // the repair would leave as it is ([`is_repaired`]; `None`: not looked at yet).
    let mut topo: Option<EdgeTopology> = None;
    let mut repaired: Option<bool> = None;
    for _ in 0..4 {
        report.rounds += 1;
        let round = Round {
            mesh: &mesh,
            map: &map,
            dist_in,
            reach,
            listed: &listed,
            mode: listed_mode,
            topo: topo
                .take()
                .map(std::cell::OnceCell::from)
                .unwrap_or_default(),
        };
        let (fringe, is_fringe) = round.fringe();
        let pairs = match carried.take() {
            // This round's fringe faces were fringe faces last round: their pairs are there.
            Some(p) => p
                .into_iter()
                .filter(|&(f, g)| is_fringe[f as usize] || is_fringe[g as usize])
                .collect(),
            None => crossing_pairs(&mesh, &fringe),
        };
        let bad = round.targets(&pairs, &is_fringe);
        if !bad.contains(&true) {
            // Nothing to remove: the round ends as the peel would, without its topology.
            break;
        }
        let mut remove = round.removal(&is_fringe, &bad);
        let known = shortcuts.skip_repair
            && *repaired.get_or_insert_with(|| is_repaired(&mesh, round.topo()));
        let Some(p) = peel(
            &mesh,
            &map,
            &mut remove,
            dist_in,
            reach,
            known.then(|| round.topo()),
        ) else {
            break;
        };
        listed.clear();
        if shortcuts.carry_pairs
            && let Some(old_of_new) = &p.face_of
        {
            carried = Some(carried_pairs(&pairs, old_of_new, mesh.triangles.len()));
        }
        report.faces += p.removed;
        map = p.map;
        mesh = p.crown;
        topo = Some(p.topo);
        repaired = p.repaired.then_some(true);
    }
    if report.faces == 0 {
        return None;
    }
    count_lost(src, &map, dist_in, &mut report);
    Some((mesh, map, report))
}

/// One round of [`trim_fringe`] on the crown as it is: which faces are fringe, which of them
/// have to go, and what goes with them.
struct Round<'a> {
    mesh: &'a TriMesh,
    /// Per crown vertex: its input vertex (`u32::MAX` for a filled hole's).
    map: &'a [u32],
    dist_in: &'a [f64],
    reach: f64,
    /// Per face: listed by the caller (first round only; empty after).
    listed: &'a [bool],
    mode: Listed,
    /// The crown's topology, built when first needed (a round with nothing to remove does not
    /// need it).
    topo: std::cell::OnceCell<crate::mesh::EdgeTopology>,
}

impl Round<'_> {
    fn topo(&self) -> &crate::mesh::EdgeTopology {
        self.topo
            .get_or_init(|| crate::mesh::EdgeTopology::new(self.mesh))
    }

    fn in_reach(&self, v: u32) -> bool {
        let s = self.map[v as usize];
        s != u32::MAX
            && self
                .dist_in
                .get(s as usize)
                .is_some_and(|&d| d <= self.reach)
    }

    fn is_listed(&self, f: u32) -> bool {
        self.listed.get(f as usize).copied().unwrap_or(false)
    }

    fn on_edge(&self, a: u32, b: u32) -> bool {
        self.topo().edge_face_count(a, b) == 1
    }

    fn on_margin_edge(&self, f: usize) -> bool {
        let t = self.mesh.triangles[f];
        (0..3).any(|k| self.on_edge(t[k], t[(k + 1) % 3]))
    }

    /// The fringe faces (every corner within the reach, or listed as the mode allows), as a
    /// list and as a mask over the faces.
    fn fringe(&self) -> (Vec<u32>, Vec<bool>) {
        let apex = self.mode >= Listed::Apex;
        let fringe: Vec<u32> = (0..self.mesh.triangles.len() as u32)
            .filter(|&f| {
                let near = self.mesh.triangles[f as usize]
                    .iter()
                    .filter(|&&v| self.in_reach(v))
                    .count();
                near == 3
                    || (apex && near == 2 && self.is_listed(f))
                    || (self.mode == Listed::MarginEdge
                        && self.is_listed(f)
                        && self.on_margin_edge(f as usize))
            })
            .collect();
        let mut is_fringe = vec![false; self.mesh.triangles.len()];
        for &f in &fringe {
            is_fringe[f as usize] = true;
        }
        (fringe, is_fringe)
    }

    /// Per face: whether it has to go, for the crossing `pairs` of the fringe faces
    /// ([`crossing_pairs`] of the fringe). Of a crossing pair one face has to go: the one nearer
    /// the margin (so the least of the crown goes), or the only one in the fringe; and every
    /// listed face.
    fn targets(&self, pairs: &[(u32, u32)], is_fringe: &[bool]) -> Vec<bool> {
        // Vertices that are no input vertex (a filled hole's) have no distance: they do not
        // count.
        let depth = |f: u32| {
            self.mesh.triangles[f as usize]
                .iter()
                .filter_map(|&v| self.dist_in.get(self.map[v as usize] as usize))
                .fold(f64::INFINITY, |a, &d| a.min(d))
        };
        let mut bad = vec![false; self.mesh.triangles.len()];
        for &(f, g) in pairs {
            let pick = match (is_fringe[f as usize], is_fringe[g as usize]) {
                (true, true) if depth(g) < depth(f) => g,
                (true, _) => f,
                _ => g,
            };
            bad[pick as usize] = true;
        }
        for (b, &l) in bad.iter_mut().zip(self.listed) {
            *b |= l;
        }
        bad
    }

    /// The faces to remove this round for the fringe targets `bad`. Only faces with an edge on
    /// the margin go in one round (peeling): removing a face deeper in would cut a slot into
    /// the crown, and a margin that doubles back on itself no longer charts around the tooth.
    /// What lies under a removed face is looked at again in the next round. A target with an
    /// edge on the margin goes alone; one touching the margin at a vertex only goes with that
    /// vertex's whole fan (removing it alone would pinch the margin).
    /// With [`Listed::MarginEdge`], where nothing else goes, the faces of [`Round::toward_margin`].
    fn removal(&self, is_fringe: &[bool], bad: &[bool]) -> Vec<bool> {
        let boundary_vertex = self.topo().on_single_face_edge(self.mesh.positions.len());
        let mut remove = self.peeled(is_fringe, bad, &boundary_vertex);
        if self.mode == Listed::MarginEdge && !remove.contains(&true) {
            self.toward_margin(is_fringe, bad, &boundary_vertex, &mut remove);
        }
        remove
    }

    /// Marks in `remove` the fringe faces on a margin edge that share a corner with a listed
    /// target lying off the margin (no corner on it: one ring in, behind faces nothing
    /// crosses), so that the target reaches the margin for the next build. Nothing else can
    /// bring such a target to go: the peeling takes faces on the margin only.
    fn toward_margin(
        &self,
        is_fringe: &[bool],
        bad: &[bool],
        boundary_vertex: &[bool],
        remove: &mut [bool],
    ) {
        let mesh = self.mesh;
        for f in 0..mesh.triangles.len() {
            let t = mesh.triangles[f];
            if !(is_fringe[f] && bad[f] && self.is_listed(f as u32))
                || t.iter().any(|&v| boundary_vertex[v as usize])
            {
                continue;
            }
            for &v in &t {
                for &(_, _, g) in self.topo().leaving(v) {
                    let g = g as usize;
                    if is_fringe[g] && self.on_margin_edge(g) {
                        remove[g] = true;
                    }
                }
            }
        }
    }

    /// The peeling's part of [`Round::removal`] (see there).
    fn peeled(&self, is_fringe: &[bool], bad: &[bool], boundary_vertex: &[bool]) -> Vec<bool> {
        let mesh = self.mesh;
        let mut remove = vec![false; mesh.triangles.len()];
        let mut fans: Vec<u32> = Vec::new();
        for f in (0..mesh.triangles.len()).filter(|&f| is_fringe[f] && bad[f]) {
            if self.on_margin_edge(f) {
                remove[f] = true;
            } else {
                let t = mesh.triangles[f];
                fans.extend(t.iter().copied().filter(|&v| boundary_vertex[v as usize]));
            }
        }
        if fans.is_empty() {
            return remove;
        }
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
        let apex = self.mode >= Listed::Apex;
        for faces in fan_faces {
            if apex || faces.iter().all(|&f| is_fringe[f]) {
                for f in faces {
                    remove[f] = true;
                }
            }
        }
        remove
    }
}

/// Counts into `report` the input vertices of `src` that `map` (the trimmed crown's) no longer
/// holds, and the farthest of them from the original margin.
fn count_lost(src: &[u32], map: &[u32], dist_in: &[f64], report: &mut FringeTrim) {
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
}

/// The crossing pairs `pairs` (face indices of the crown before a peel, `(smaller, larger)`,
/// sorted) of the faces the peel kept, renumbered: `old_of_new[f]` is the index before the peel
/// of the peeled crown's face `f`. The peel keeps faces in their order (so the pairs stay
/// ordered and sorted), changes no position and, where it hands `old_of_new` out, splits no
/// vertex and turns no face: two kept faces cross after it exactly when they did before, and
/// no new pair can arise. So a later round's pairs with a face of its fringe (which were fringe
/// faces in the earlier round too: the fringe is fixed by the input vertices' distances and
/// the listed faces count in the first round only) are these, filtered.
fn carried_pairs(pairs: &[(u32, u32)], old_of_new: &[u32], old_faces: usize) -> Vec<(u32, u32)> {
    let mut new_of_old = vec![u32::MAX; old_faces];
    for (new, &old) in old_of_new.iter().enumerate() {
        new_of_old[old as usize] = new as u32;
    }
    pairs
        .iter()
        .map(|&(f, g)| (new_of_old[f as usize], new_of_old[g as usize]))
        .filter(|&(f, g)| f != u32::MAX && g != u32::MAX)
        .collect()
}

mod peel;

use peel::peel;
#[cfg(test)]
use peel::{Peeled, SPARED};

#[cfg(test)]
mod tests;
