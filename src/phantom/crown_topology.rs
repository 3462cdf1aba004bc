//! Makes every labeled crown of the IOS jaw an open disk: one component, manifold, one boundary
//! loop. Pinch vertices and stray islands are relabeled gingiva; small gingiva islands enclosed
//! by a crown are relabeled to that crown. Monotone, so it terminates.

use crate::mesh::{TriMesh, boundary_loops, connected_components};
use std::collections::{BTreeMap, BTreeSet};

/// Sorted undirected edge → faces table of a mesh.
struct EdgeFaces {
    keyed: Vec<(u32, u32, u32)>,
}

impl EdgeFaces {
    fn new(mesh: &TriMesh) -> Self {
        let mut keyed = Vec::with_capacity(mesh.triangles.len() * 3);
        for (f, t) in mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                keyed.push((a.min(b), a.max(b), f as u32));
            }
        }
        keyed.sort_unstable();
        EdgeFaces { keyed }
    }

    fn faces(&self, a: u32, b: u32) -> impl Iterator<Item = u32> + '_ {
        let key = (a.min(b), a.max(b));
        let start = self.keyed.partition_point(|e| (e.0, e.1) < key);
        self.keyed[start..]
            .iter()
            .take_while(move |e| (e.0, e.1) == key)
            .map(|e| e.2)
    }
}

/// Repairs `labels` (per vertex, 0 = gingiva) so that each crown label's faces form one open
/// disk; `allow_holes` keeps inner loops that are holes of the mesh itself. Returns the number
/// of relabeled vertices.
pub fn make_crowns_disks(mesh: &TriMesh, labels: &mut [i32], allow_holes: bool) -> usize {
    let ef = EdgeFaces::new(mesh);
    let mut local = vec![u32::MAX; mesh.positions.len()];
    let mut changed_total = 0;
    let mut dirty: Option<BTreeSet<i32>> = None;
    for _round in 0..40 {
        let mut now_dirty: BTreeSet<i32> = BTreeSet::new();
        let by_label = crown_faces_by_label(mesh, labels);
        let mut changed = orphans_to_gingiva(mesh, labels, &by_label, &mut now_dirty);
        for (&lab, faces) in &by_label {
            if dirty.as_ref().is_some_and(|d| !d.contains(&lab)) {
                continue;
            }
            let crown = Crown { mesh, ef: &ef, lab };
            let (c, touched) = crown.make_disk(labels, &mut local, faces, allow_holes);
            changed += c;
            if touched {
                now_dirty.insert(lab);
            }
        }
        changed_total += changed;
        if changed == 0 {
            break;
        }
        dirty = Some(now_dirty);
    }
    changed_total
}

/// Per crown label, its faces (all three corners carry the label).
fn crown_faces_by_label(mesh: &TriMesh, labels: &[i32]) -> BTreeMap<i32, Vec<u32>> {
    let mut by_label: BTreeMap<i32, Vec<u32>> = BTreeMap::new();
    for (f, t) in mesh.triangles.iter().enumerate() {
        let l = labels[t[0] as usize];
        if l != 0 && labels[t[1] as usize] == l && labels[t[2] as usize] == l {
            by_label.entry(l).or_default().push(f as u32);
        }
    }
    by_label
}

/// Labelled vertices in no crown face go to the gingiva; their labels are marked dirty.
/// Returns how many.
fn orphans_to_gingiva(
    mesh: &TriMesh,
    labels: &mut [i32],
    by_label: &BTreeMap<i32, Vec<u32>>,
    dirty: &mut BTreeSet<i32>,
) -> usize {
    let mut in_face = vec![false; labels.len()];
    for faces in by_label.values() {
        for &f in faces {
            for &v in &mesh.triangles[f as usize] {
                in_face[v as usize] = true;
            }
        }
    }
    let mut changed = 0;
    for (l, &in_face) in labels.iter_mut().zip(&in_face) {
        if *l != 0 && !in_face {
            dirty.insert(*l);
            *l = 0;
            changed += 1;
        }
    }
    changed
}

/// One crown label of the jaw mesh, with the mesh's edge → faces table.
struct Crown<'a> {
    mesh: &'a TriMesh,
    ef: &'a EdgeFaces,
    lab: i32,
}

impl Crown<'_> {
    /// One step towards a disk for this crown, whose faces are `faces`: pinch vertices to the
    /// gingiva, else every component but the largest, else its first inner loop closed (the
    /// gingiva patch across it relabelled) or cut open to the outer loop. Returns the vertices
    /// relabelled and whether the crown is to be looked at again.
    fn make_disk(
        &self,
        labels: &mut [i32],
        local: &mut [u32],
        faces: &[u32],
        allow_holes: bool,
    ) -> (usize, bool) {
        let (globals, sub) = self.submesh(local, faces);
        let pin = crate::mesh::non_manifold_vertices(&sub);
        if !pin.is_empty() {
            for &v in &pin {
                labels[globals[v as usize] as usize] = 0;
            }
            return (pin.len(), true);
        }
        let (ids, count) = connected_components(&sub);
        if count > 1 {
            return (keep_largest(&sub, &globals, &ids, count, labels), true);
        }
        let loops: Vec<Vec<u32>> = boundary_loops(&sub)
            .into_iter()
            .map(|lp| lp.into_iter().map(|v| globals[v as usize]).collect())
            .collect();
        // One inner loop per round (labels change under the others), past the mesh holes kept.
        let changed = loops
            .iter()
            .skip(1)
            .find_map(|lp| {
                self.close_inner_loop(&sub, &globals, labels, lp, &loops[0], allow_holes)
            })
            .unwrap_or(0);
        (changed, changed > 0)
    }

    /// The crown as a mesh of its own (vertex `i` is mesh vertex `globals[i]`); `local` is all
    /// `u32::MAX` before and after.
    fn submesh(&self, local: &mut [u32], faces: &[u32]) -> (Vec<u32>, TriMesh) {
        let mut globals: Vec<u32> = Vec::new();
        let mut tris = Vec::with_capacity(faces.len());
        for &f in faces {
            let t = self.mesh.triangles[f as usize];
            let mut lt = [0u32; 3];
            for (k, &v) in t.iter().enumerate() {
                if local[v as usize] == u32::MAX {
                    local[v as usize] = globals.len() as u32;
                    globals.push(v);
                }
                lt[k] = local[v as usize];
            }
            tris.push(lt);
        }
        for &g in &globals {
            local[g as usize] = u32::MAX;
        }
        let positions = globals
            .iter()
            .map(|&g| self.mesh.positions[g as usize])
            .collect();
        (globals, TriMesh::new(positions, tris))
    }

    fn is_crown_face(&self, labels: &[i32], f: usize) -> bool {
        self.mesh.triangles[f]
            .iter()
            .all(|&v| labels[v as usize] == self.lab)
    }

    /// Closes the inner loop `lp` by relabelling the gingiva patch across it to the crown where
    /// that patch is small, enclosed and holds no other tooth's vertex; else (or where the loop
    /// is a hole of the mesh itself and holes are not kept) cuts the crown open to `outer`.
    /// Returns the vertices relabelled, or `None` for a hole of the mesh itself kept with
    /// `allow_holes` (left as it is).
    fn close_inner_loop(
        &self,
        sub: &TriMesh,
        globals: &[u32],
        labels: &mut [i32],
        lp: &[u32],
        outer: &[u32],
        allow_holes: bool,
    ) -> Option<usize> {
        // The faces across this loop (not crown faces): flood them.
        let mut seeds = Vec::new();
        let mut mesh_hole = false;
        for w in 0..lp.len() {
            let (a, b) = (lp[w], lp[(w + 1) % lp.len()]);
            let mut any = false;
            for f in self.ef.faces(a, b) {
                if !self.is_crown_face(labels, f as usize) {
                    seeds.push(f);
                    any = true;
                }
            }
            if !any {
                mesh_hole = true;
            }
        }
        if mesh_hole && allow_holes {
            return None;
        }
        Some(match self.flood(labels, seeds) {
            Some(seen) if !mesh_hole => {
                let mut changed = 0;
                for &f in &seen {
                    for &v in &self.mesh.triangles[f as usize] {
                        if labels[v as usize] != self.lab {
                            labels[v as usize] = self.lab;
                            changed += 1;
                        }
                    }
                }
                changed
            }
            // Cannot fill: cut the crown open to this loop by relabeling a path of crown
            // vertices between it and the outer loop as gingiva.
            _ => cut_to_outer(sub, globals, labels, self.lab, lp, outer),
        })
    }

    /// The non-crown faces reachable from `seeds` without crossing a crown face, or `None` when
    /// the flood grows past 4 000 faces, meets another tooth's vertex or the mesh boundary.
    fn flood(&self, labels: &[i32], seeds: Vec<u32>) -> Option<BTreeSet<u32>> {
        let mut seen: BTreeSet<u32> = seeds.iter().copied().collect();
        let mut stack = seeds;
        while let Some(f) = stack.pop() {
            if seen.len() > 4000 {
                return None;
            }
            let t = self.mesh.triangles[f as usize];
            if t.iter()
                .any(|&v| labels[v as usize] != self.lab && labels[v as usize] != 0)
            {
                return None;
            }
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let mut cnt = 0;
                for g in self.ef.faces(a, b) {
                    cnt += 1;
                    if g != f && !self.is_crown_face(labels, g as usize) && seen.insert(g) {
                        stack.push(g);
                    }
                }
                if cnt < 2 {
                    return None; // reached the mesh boundary
                }
            }
        }
        Some(seen)
    }
}

/// Relabels to gingiva every vertex of `sub` (vertex `i` is mesh vertex `globals[i]`) outside
/// its largest component (`ids`: component per face, `count` of them). Returns how many.
fn keep_largest(
    sub: &TriMesh,
    globals: &[u32],
    ids: &[u32],
    count: usize,
    labels: &mut [i32],
) -> usize {
    let mut sizes = vec![0usize; count];
    for &c in ids {
        sizes[c as usize] += 1;
    }
    let best = (0..count)
        .max_by_key(|&c| (sizes[c], usize::MAX - c))
        .unwrap_or(0) as u32;
    let mut keep = vec![false; globals.len()];
    for (k, &c) in ids.iter().enumerate() {
        if c == best {
            for &v in &sub.triangles[k] {
                keep[v as usize] = true;
            }
        }
    }
    let mut changed = 0;
    for (lv, &g) in globals.iter().enumerate() {
        if !keep[lv] {
            labels[g as usize] = 0;
            changed += 1;
        }
    }
    changed
}

/// Relabels to gingiva the vertices of a shortest edge path (by hops, within the crown `sub`,
/// whose vertex `i` is mesh vertex `globals[i]`) from loop `inner` to loop `outer` (mesh
/// vertex ids), which merges the two boundary loops into one.
fn cut_to_outer(
    sub: &TriMesh,
    globals: &[u32],
    labels: &mut [i32],
    lab: i32,
    inner: &[u32],
    outer: &[u32],
) -> usize {
    let n = sub.positions.len();
    let mut adj: Vec<Vec<u32>> = vec![Vec::new(); n];
    for t in &sub.triangles {
        for k in 0..3 {
            adj[t[k] as usize].push(t[(k + 1) % 3]);
            adj[t[(k + 1) % 3] as usize].push(t[k]);
        }
    }
    for a in &mut adj {
        a.sort_unstable();
        a.dedup();
    }
    let is_outer: BTreeSet<u32> = outer.iter().copied().collect();
    let is_inner: BTreeSet<u32> = inner.iter().copied().collect();
    let mut prev = vec![u32::MAX; n];
    let mut queue = std::collections::VecDeque::new();
    for (lv, &g) in globals.iter().enumerate() {
        if is_inner.contains(&g) {
            prev[lv] = lv as u32;
            queue.push_back(lv as u32);
        }
    }
    while let Some(v) = queue.pop_front() {
        if is_outer.contains(&globals[v as usize]) {
            let mut count = 0;
            let mut c = v;
            loop {
                let g = globals[c as usize] as usize;
                if labels[g] == lab {
                    labels[g] = 0;
                    count += 1;
                }
                if prev[c as usize] == c {
                    break;
                }
                c = prev[c as usize];
            }
            return count;
        }
        for &w in &adj[v as usize] {
            if prev[w as usize] == u32::MAX {
                prev[w as usize] = v;
                queue.push_back(w);
            }
        }
    }
    0
}
