//! Edge adjacency, ordered boundary loops and connected components. Deterministic: no hash-map
//! iteration order leaks into any result.

use super::TriMesh;

/// Directed half-edges sorted by (from, to), with their face; the basis of every adjacency query.
#[derive(Clone, Debug)]
pub struct EdgeTopology {
    /// `(from, to, face)` for every triangle side, sorted.
    pub half_edges: Vec<(u32, u32, u32)>,
    /// `half_edges[offsets[v]..offsets[v + 1]]` are the half-edges leaving vertex `v`.
    offsets: Vec<u32>,
}

impl EdgeTopology {
    /// Builds the half-edge list of `mesh` (counting sorts, no comparisons).
    pub fn new(mesh: &TriMesh) -> Self {
        let offsets = origin_offsets(mesh.triangles.iter().flatten().copied());
        // Two stable counting sorts, by target then by origin, leave the half-edges sorted by
        // (from, to, face). A vertex is the target of as many half-edges as it is the origin of
        // (one per face corner), so both sorts share the offsets.
        let corners = mesh
            .triangles
            .iter()
            .enumerate()
            .flat_map(|(f, t)| (0..3).map(move |k| (t[k], t[(k + 1) % 3], f as u32)));
        let by_to = placed_by(corners, &offsets, |e| e.1);
        let half_edges = placed_by(by_to.into_iter(), &offsets, |e| e.0);
        Self {
            half_edges,
            offsets,
        }
    }

    /// The half-edges leaving `v` (sorted by target vertex, then face); empty for a vertex no
    /// face uses.
    #[inline]
    pub fn leaving(&self, v: u32) -> &[(u32, u32, u32)] {
        match (
            self.offsets.get(v as usize),
            self.offsets.get(v as usize + 1),
        ) {
            (Some(&s), Some(&e)) => &self.half_edges[s as usize..e as usize],
            _ => &[],
        }
    }

    /// One more than the largest vertex index any face uses (0 without faces): the vertices
    /// with a block of half-edges, which may exceed the mesh's vertices when a face indexes
    /// past them.
    pub(super) fn vertex_span(&self) -> u32 {
        self.offsets.len().saturating_sub(1) as u32
    }

    /// Faces holding the directed edge `a → b`.
    pub fn faces_of_directed(&self, a: u32, b: u32) -> impl Iterator<Item = u32> + '_ {
        let block: &[(u32, u32, u32)] = match (
            self.offsets.get(a as usize),
            self.offsets.get(a as usize + 1),
        ) {
            (Some(&s), Some(&e)) => &self.half_edges[s as usize..e as usize],
            _ => &[],
        };
        block
            .iter()
            .filter(move |&&(_, y, _)| y == b)
            .map(|&(_, _, f)| f)
    }

    /// Number of faces holding edge {a, b} in either direction.
    pub fn edge_face_count(&self, a: u32, b: u32) -> usize {
        self.faces_of_directed(a, b).count() + self.faces_of_directed(b, a).count()
    }

    /// Undirected edges with their use count, sorted by (min, max).
    pub fn undirected_edges(&self) -> Vec<(u32, u32, usize)> {
        let mut out: Vec<(u32, u32, usize)> = Vec::with_capacity(self.half_edges.len() / 2 + 1);
        for (a, b, same) in self.directed_runs() {
            let rev = self.faces_of_directed(b, a).count();
            if a < b || rev == 0 {
                out.push((a.min(b), a.max(b), same + rev));
            }
        }
        out.sort_unstable();
        out
    }

    /// The directed edges `a → b` in sorted order, each with the number of faces using it in
    /// that direction (the runs of equal `(a, b)` in the sorted half-edges).
    fn directed_runs(&self) -> impl Iterator<Item = (u32, u32, usize)> + '_ {
        let h = &self.half_edges;
        let mut i = 0;
        std::iter::from_fn(move || {
            let &(a, b, _) = h.get(i)?;
            let mut j = i + 1;
            while j < h.len() && h[j].0 == a && h[j].1 == b {
                j += 1;
            }
            let same = j - i;
            i = j;
            Some((a, b, same))
        })
    }

    /// `(boundary, non-manifold)` undirected edge counts, classified as in
    /// [`EdgeTopology::undirected_edges`]: used by one face, or by more than two faces or twice
    /// in one direction. One pass over the half-edges, nothing allocated.
    pub fn edge_counts(&self) -> (usize, usize) {
        let (mut boundary, mut non_manifold) = (0, 0);
        for (a, b, same) in self.directed_runs() {
            let rev = self.faces_of_directed(b, a).count();
            count_edge(a, b, same, rev, &mut boundary, &mut non_manifold);
        }
        (boundary, non_manifold)
    }

    /// Per vertex (`n` of them): whether it lies on an edge used by exactly one face (as
    /// [`EdgeTopology::edge_face_count`] counts). One pass over the half-edges.
    pub fn on_single_face_edge(&self, n: usize) -> Vec<bool> {
        let mut on = vec![false; n];
        for (a, b, same) in self.directed_runs() {
            if same == 1 && self.faces_of_directed(b, a).next().is_none() {
                for v in [a, b] {
                    if let Some(o) = on.get_mut(v as usize) {
                        *o = true;
                    }
                }
            }
        }
        on
    }

    /// The topology of the mesh less the faces marked in `remove` (faces renumbered in order,
    /// vertices as they are): what [`EdgeTopology::new`] builds for it, from this one by
    /// dropping the removed faces' half-edges (the order of the rest is kept).
    pub fn without_faces(&self, remove: &[bool]) -> Self {
        let mut new_face = Vec::with_capacity(remove.len());
        let mut next = 0u32;
        for &r in remove {
            new_face.push(next);
            next += u32::from(!r);
        }
        let half_edges: Vec<(u32, u32, u32)> = self
            .half_edges
            .iter()
            .filter(|e| !remove[e.2 as usize])
            .map(|&(a, b, f)| (a, b, new_face[f as usize]))
            .collect();
        // Every corner of a face is the origin of one of its half-edges.
        let offsets = origin_offsets(half_edges.iter().map(|e| e.0));
        Self {
            half_edges,
            offsets,
        }
    }

    /// Directed boundary half-edges: `a → b` present with no `b → a` partner, sorted.
    pub fn boundary_half_edges(&self) -> Vec<(u32, u32)> {
        // Every half-edge reversed, `(b, a)` for `a → b`, sorted: a stable counting sort by
        // target of the list sorted by origin (a vertex is as often a target as an origin: the
        // same offsets). `a → b` has a partner exactly when `(a, b)` is among them, found by
        // walking both sorted lists together (no lookup in another vertex's block per
        // half-edge).
        let flipped = self.half_edges.iter().map(|&(a, b, _)| (b, a));
        let reversed = placed_by(flipped, &self.offsets, |e| e.0);
        let mut j = 0;
        self.half_edges
            .iter()
            .map(|&(a, b, _)| (a, b))
            .filter(|&key| {
                while j < reversed.len() && reversed[j] < key {
                    j += 1;
                }
                reversed.get(j) != Some(&key)
            })
            .collect()
    }
}

/// Where each vertex's half-edges start in the sorted list, from the origin of every half-edge
/// (one entry per vertex up to the highest origin, and one more: the count).
pub(super) fn origin_offsets(origins: impl Iterator<Item = u32> + Clone) -> Vec<u32> {
    let n = origins.clone().map(|v| v as usize + 1).max().unwrap_or(0);
    let mut offsets = vec![0u32; n + 1];
    for v in origins {
        offsets[v as usize + 1] += 1;
    }
    for v in 0..n {
        offsets[v + 1] += offsets[v];
    }
    offsets
}

/// `items` in a stable counting sort by `vertex(item)`, whose runs start at `offsets` (one
/// more entry than vertices; the last the item count): each vertex's items in their order in
/// `items`.
pub(super) fn placed_by<K: Copy + Default>(
    items: impl Iterator<Item = K>,
    offsets: &[u32],
    vertex: impl Fn(&K) -> u32,
) -> Vec<K> {
    let mut fill = offsets.to_vec();
    let mut out = vec![K::default(); offsets.last().map_or(0, |&n| n as usize)];
    for item in items {
        let v = vertex(&item) as usize;
        out[fill[v] as usize] = item;
        fill[v] += 1;
    }
    out
}

/// Ordered boundary loops, each a cycle of vertex indices following the faces' orientation
/// (the surface lies to the left when walking a loop seen from outside). Loops are sorted by
/// length, longest first (ties: by smallest vertex). Assumes a manifold mesh; at a boundary
/// vertex shared by two loops the walk takes the first unused edge in sorted order.
pub fn boundary_loops(mesh: &TriMesh) -> Vec<Vec<u32>> {
    loops_of_edges(&super::boundary::boundary_half_edges(&mesh.triangles))
}

/// [`boundary_loops`] from an already built topology.
pub fn boundary_loops_of(topo: &EdgeTopology) -> Vec<Vec<u32>> {
    loops_of_edges(&topo.boundary_half_edges())
}

/// The loops of the sorted boundary half-edges `edges` (see [`boundary_loops`]).
fn loops_of_edges(edges: &[(u32, u32)]) -> Vec<Vec<u32>> {
    let mut used = vec![false; edges.len()];
    let mut loops = Vec::new();
    for start in 0..edges.len() {
        if used[start] {
            continue;
        }
        let mut lp = Vec::new();
        let mut cur = start;
        loop {
            used[cur] = true;
            let (a, b) = edges[cur];
            lp.push(a);
            let first = edges.partition_point(|&(x, _)| x < b);
            let next = (first..edges.len())
                .take_while(|&i| edges[i].0 == b)
                .find(|&i| !used[i]);
            match next {
                Some(n) => cur = n,
                None => break,
            }
        }
        loops.push(lp);
    }
    loops.sort_by(|a, b| {
        b.len()
            .cmp(&a.len())
            .then_with(|| a.iter().min().cmp(&b.iter().min()))
    });
    loops
}

/// Connected components by shared edges: a component id per face, and the number of
/// components. Ids are assigned in order of each component's lowest face index.
pub fn connected_components(mesh: &TriMesh) -> (Vec<u32>, usize) {
    connected_components_of(&EdgeTopology::new(mesh), mesh.triangles.len())
}

/// [`connected_components`] from an already built topology of a mesh with `nf` faces.
pub fn connected_components_of(topo: &EdgeTopology, nf: usize) -> (Vec<u32>, usize) {
    let mut parent = face_union(topo, nf);
    let mut ids = vec![u32::MAX; nf];
    let mut root_id = vec![u32::MAX; nf];
    let mut count = 0u32;
    for (f, id) in ids.iter_mut().enumerate() {
        let r = find(&mut parent, f as u32) as usize;
        if root_id[r] == u32::MAX {
            root_id[r] = count;
            count += 1;
        }
        *id = root_id[r];
    }
    (ids, count as usize)
}

/// [`EdgeTopology::edge_counts`] and the component count of [`connected_components_of`] in one pass over the half-edges:
/// `(boundary edges, non-manifold edges, components)`. The reference the per-vertex pass
/// ([`super::fan_pass::fan_counts`], which the library uses) is tested against.
#[cfg(test)]
pub(super) fn edge_and_component_counts(topo: &EdgeTopology, nf: usize) -> (usize, usize, usize) {
    let mut parent: Vec<u32> = (0..nf as u32).collect();
    let (mut boundary, mut non_manifold) = (0, 0);
    let h = &topo.half_edges;
    let mut i = 0;
    while i < h.len() {
        let (a, b, _) = h[i];
        let mut j = i + 1;
        while j < h.len() && h[j].0 == a && h[j].1 == b {
            // The same directed edge twice (non-manifold input) joins its faces too.
            union_roots(&mut parent, h[j - 1].2, h[j].2);
            j += 1;
        }
        let same = j - i;
        let mut rev = 0;
        for g in topo.faces_of_directed(b, a) {
            rev += 1;
            if a < b {
                for &(_, _, f) in &h[i..j] {
                    union_roots(&mut parent, f, g);
                }
            }
        }
        count_edge(a, b, same, rev, &mut boundary, &mut non_manifold);
        i = j;
    }
    let components = parent
        .iter()
        .enumerate()
        .filter(|&(f, &p)| p == f as u32)
        .count();
    (boundary, non_manifold, components)
}

/// Joins the sets of faces `f` and `g` (the lower root becomes the root).
pub(super) fn union_roots(parent: &mut [u32], f: u32, g: u32) {
    let (ra, rb) = (find(parent, f), find(parent, g));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

fn find(p: &mut [u32], mut x: u32) -> u32 {
    while p[x as usize] != x {
        p[x as usize] = p[p[x as usize] as usize];
        x = p[x as usize];
    }
    x
}

/// Union-find forest of the faces joined by shared edges (roots: the component's lowest face).
fn face_union(topo: &EdgeTopology, nf: usize) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..nf as u32).collect();
    let mut union = |f: u32, g: u32| {
        let (ra, rb) = (find(&mut parent, f), find(&mut parent, g));
        if ra != rb {
            let (lo, hi) = (ra.min(rb), ra.max(rb));
            parent[hi as usize] = lo;
        }
    };
    // Faces sharing an edge (either direction) join; the partition does not depend on order.
    let he = &topo.half_edges;
    for (i, &(a, b, f)) in he.iter().enumerate() {
        if a < b {
            for g in topo.faces_of_directed(b, a) {
                union(f, g);
            }
        }
        // The same directed edge twice (non-manifold input): adjacent in the sorted block.
        if let Some(&(a2, b2, g)) = he.get(i + 1)
            && a2 == a
            && b2 == b
        {
            union(f, g);
        }
    }
    parent
}

/// Counts the undirected edge `a`–`b` with `same` half-edges a→b and `rev` half-edges b→a as a
/// boundary or non-manifold edge. Counted once: from its smaller end, or from this end when the
/// other direction is absent (as [`EdgeTopology::undirected_edges`] lists it).
pub(super) fn count_edge(
    a: u32,
    b: u32,
    same: usize,
    rev: usize,
    boundary: &mut usize,
    non_manifold: &mut usize,
) {
    if a < b || rev == 0 {
        if same + rev == 1 {
            *boundary += 1;
        } else if same + rev > 2 || same > 1 || rev > 1 {
            *non_manifold += 1;
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::mesh::fixtures::{cube, square, tetrahedron};

    /// `faces` faces of random corners among vertices `0..n`: repeated corners (degenerate
    /// faces), repeated and reversed faces all occur.
    pub(in crate::mesh) fn random_faces(
        rng: &mut crate::phantom::rng::Rng,
        n: u32,
        faces: usize,
    ) -> Vec<[u32; 3]> {
        let mut pick = || rng.below(n as usize) as u32;
        (0..faces).map(|_| [pick(), pick(), pick()]).collect()
    }

    /// The half-edges come out exactly as sorting every `(from, to, face)` would order them,
    /// on random face lists with repeated, reversed, degenerate and duplicate faces and unused
    /// vertices.
    #[test]
    fn half_edges_are_sorted_by_origin_target_and_face() {
        let mut rng = crate::phantom::rng::Rng::new(5);
        for n in [1u32, 2, 3, 7, 40] {
            for faces in [0usize, 1, 5, 60, 300] {
                let triangles = random_faces(&mut rng, n, faces);
                let mesh = TriMesh::new(vec![glam::DVec3::ZERO; n as usize + 2], triangles);
                let mut want: Vec<(u32, u32, u32)> = mesh
                    .triangles
                    .iter()
                    .enumerate()
                    .flat_map(|(f, t)| (0..3).map(move |k| (t[k], t[(k + 1) % 3], f as u32)))
                    .collect();
                want.sort_unstable();
                let topo = EdgeTopology::new(&mesh);
                assert_eq!(topo.half_edges, want, "{n} vertices, {faces} faces");
                for v in 0..n + 2 {
                    let leaving: Vec<_> = want.iter().filter(|e| e.0 == v).copied().collect();
                    assert_eq!(topo.leaving(v), leaving.as_slice());
                }
            }
        }
    }

    /// The boundary half-edges found by walking the sorted lists together are those without a
    /// reverse partner, on random face lists (repeated and reversed faces, degenerate ones).
    #[test]
    fn boundary_half_edges_are_those_without_a_partner() {
        let mut rng = crate::phantom::rng::Rng::new(9);
        for n in [1u32, 2, 4, 9, 30] {
            for faces in [0usize, 1, 3, 20, 200] {
                let mut triangles = random_faces(&mut rng, n, faces);
                // Some faces twice, some reversed: partners and duplicate half-edges.
                let extra: Vec<[u32; 3]> = triangles
                    .iter()
                    .step_by(3)
                    .map(|t| {
                        if t[0] % 2 == 0 {
                            *t
                        } else {
                            [t[0], t[2], t[1]]
                        }
                    })
                    .collect();
                triangles.extend(extra);
                let mesh = TriMesh::new(vec![glam::DVec3::ZERO; n as usize], triangles);
                let topo = EdgeTopology::new(&mesh);
                let want: Vec<(u32, u32)> = topo
                    .half_edges
                    .iter()
                    .filter(|&&(a, b, _)| topo.faces_of_directed(b, a).next().is_none())
                    .map(|&(a, b, _)| (a, b))
                    .collect();
                assert_eq!(
                    topo.boundary_half_edges(),
                    want,
                    "{n} vertices, {faces} faces"
                );
            }
        }
    }

    #[test]
    fn closed_meshes_have_no_boundary() {
        assert!(boundary_loops(&tetrahedron()).is_empty());
        assert!(boundary_loops(&cube(2.0)).is_empty());
    }

    #[test]
    fn square_boundary_is_one_ordered_loop() {
        let loops = boundary_loops(&square());
        assert_eq!(loops.len(), 1);
        let l = &loops[0];
        assert_eq!(l.len(), 4);
        // Follows face orientation: 0→1→2→3.
        let i = l.iter().position(|&v| v == 0).unwrap();
        let rot: Vec<u32> = (0..4).map(|k| l[(i + k) % 4]).collect();
        assert_eq!(rot, vec![0, 1, 2, 3]);
    }

    /// The vertices on single-face edges are those [`EdgeTopology::edge_face_count`] finds,
    /// on random triangle soups over few vertices (boundary, non-manifold and twice-directed
    /// edges, unused vertices).
    #[test]
    fn single_face_edge_vertices_match_edge_face_counts() {
        let mut rng = crate::phantom::rng::Rng::new(3);
        for case in 0..300 {
            let n = 4 + case % 9;
            let faces = 1 + rng.below(3 * n);
            let tris: Vec<[u32; 3]> = (0..faces)
                .map(|_| {
                    // Three distinct vertices: the k-th vertex that is neither a nor b.
                    let a = rng.below(n);
                    let b = (a + 1 + rng.below(n - 1)) % n;
                    let k = rng.below(n - 2);
                    let c = (0..n).filter(|&x| x != a && x != b).nth(k).unwrap();
                    [a as u32, b as u32, c as u32]
                })
                .collect();
            let m = TriMesh::new(vec![glam::DVec3::ZERO; n + 2], tris);
            let topo = EdgeTopology::new(&m);
            let mut expect = vec![false; n + 2];
            for t in &m.triangles {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    if topo.edge_face_count(a, b) == 1 {
                        expect[a as usize] = true;
                        expect[b as usize] = true;
                    }
                }
            }
            assert_eq!(
                topo.on_single_face_edge(n + 2),
                expect,
                "case {case}: {:?}",
                m.triangles
            );
        }
    }

    #[test]
    fn components_counts_separate_pieces() {
        let mut m = cube(1.0);
        let t = tetrahedron();
        m.append(&t);
        let (ids, n) = connected_components(&m);
        assert_eq!(n, 2);
        assert!(ids[..12].iter().all(|&i| i == 0));
        assert!(ids[12..].iter().all(|&i| i == 1));
    }

    #[test]
    fn cube_with_one_face_removed_has_square_hole() {
        let mut m = cube(1.0);
        m.triangles.drain(0..2);
        let loops = boundary_loops(&m);
        assert_eq!(loops.len(), 1);
        let mut l = loops[0].clone();
        l.sort();
        assert_eq!(l, vec![0, 1, 2, 3]);
    }
}
