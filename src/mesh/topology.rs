//! Edge adjacency, ordered boundary loops and connected components. Deterministic: no hash-map
//! iteration order leaks into any result.

use super::TriMesh;

/// Directed half-edges sorted by (from, to), with their face; the basis of every adjacency query.
#[derive(Clone, Debug)]
pub struct EdgeTopology {
    /// `(from, to, face)` for every triangle side, sorted.
    pub half_edges: Vec<(u32, u32, u32)>,
}

impl EdgeTopology {
    /// Builds the half-edge list of `mesh`.
    pub fn new(mesh: &TriMesh) -> Self {
        let mut half_edges = Vec::with_capacity(mesh.triangles.len() * 3);
        for (f, t) in mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                half_edges.push((t[k], t[(k + 1) % 3], f as u32));
            }
        }
        half_edges.sort_unstable();
        Self { half_edges }
    }

    /// Faces holding the directed edge `a → b`.
    pub fn faces_of_directed(&self, a: u32, b: u32) -> impl Iterator<Item = u32> + '_ {
        let start = self
            .half_edges
            .partition_point(|&(x, y, _)| (x, y) < (a, b));
        self.half_edges[start..]
            .iter()
            .take_while(move |&&(x, y, _)| x == a && y == b)
            .map(|&(_, _, f)| f)
    }

    /// Number of faces holding edge {a, b} in either direction.
    pub fn edge_face_count(&self, a: u32, b: u32) -> usize {
        self.faces_of_directed(a, b).count() + self.faces_of_directed(b, a).count()
    }

    /// Undirected edges with their use count, sorted by (min, max).
    pub fn undirected_edges(&self) -> Vec<(u32, u32, usize)> {
        let mut e: Vec<(u32, u32)> = self
            .half_edges
            .iter()
            .map(|&(a, b, _)| (a.min(b), a.max(b)))
            .collect();
        e.sort_unstable();
        let mut out: Vec<(u32, u32, usize)> = Vec::with_capacity(e.len() / 2 + 1);
        for (a, b) in e {
            match out.last_mut() {
                Some(last) if last.0 == a && last.1 == b => last.2 += 1,
                _ => out.push((a, b, 1)),
            }
        }
        out
    }

    /// Directed boundary half-edges: `a → b` present with no `b → a` partner, sorted.
    pub fn boundary_half_edges(&self) -> Vec<(u32, u32)> {
        self.half_edges
            .iter()
            .filter(|&&(a, b, _)| self.faces_of_directed(b, a).next().is_none())
            .map(|&(a, b, _)| (a, b))
            .collect()
    }
}

/// Ordered boundary loops, each a cycle of vertex indices following the faces' orientation
/// (the surface lies to the left when walking a loop seen from outside). Loops are sorted by
/// length, longest first (ties: by smallest vertex). Assumes a manifold mesh; at a boundary
/// vertex shared by two loops the walk takes the first unused edge in sorted order.
pub fn boundary_loops(mesh: &TriMesh) -> Vec<Vec<u32>> {
    boundary_loops_of(&EdgeTopology::new(mesh))
}

/// [`boundary_loops`] from an already built topology.
pub fn boundary_loops_of(topo: &EdgeTopology) -> Vec<Vec<u32>> {
    let edges = topo.boundary_half_edges();
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
    let nf = mesh.triangles.len();
    let mut parent: Vec<u32> = (0..nf as u32).collect();
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    // Faces sharing an undirected edge join; sort half-edges by undirected key.
    let mut keyed: Vec<(u32, u32, u32)> = Vec::with_capacity(nf * 3);
    for (f, t) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            keyed.push((a.min(b), a.max(b), f as u32));
        }
    }
    keyed.sort_unstable();
    for w in keyed.windows(2) {
        if w[0].0 == w[1].0 && w[0].1 == w[1].1 {
            let (ra, rb) = (find(&mut parent, w[0].2), find(&mut parent, w[1].2));
            if ra != rb {
                let (lo, hi) = (ra.min(rb), ra.max(rb));
                parent[hi as usize] = lo;
            }
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{cube, square, tetrahedron};

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
