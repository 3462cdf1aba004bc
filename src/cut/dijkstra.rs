//! The paper's cut path (section 2.3.1): the CBCT vertices nearest to the IOS boundary points,
//! joined by Dijkstra shortest paths on the CBCT mesh graph into one closed vertex path.

use crate::mesh::TriMesh;
use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Vertex adjacency lists (sorted, unique).
pub fn vertex_neighbours(mesh: &TriMesh) -> Vec<Vec<u32>> {
    let mut nb = vec![Vec::new(); mesh.positions.len()];
    for t in &mesh.triangles {
        for k in 0..3 {
            nb[t[k] as usize].push(t[(k + 1) % 3]);
            nb[t[(k + 1) % 3] as usize].push(t[k]);
        }
    }
    for l in &mut nb {
        l.sort_unstable();
        l.dedup();
    }
    nb
}

/// Nearest mesh vertex to each target point (consecutive repeats removed, and the last one if it
/// equals the first).
pub fn nearest_vertices(mesh: &TriMesh, targets: &[DVec3]) -> Vec<u32> {
    let pts: Vec<[f64; 3]> = mesh.positions.iter().map(|p| p.to_array()).collect();
    let tree = ImmutableKdTree::<f64, 3>::new_from_slice(&pts).expect("kd-tree over vertices");
    let mut out: Vec<u32> = Vec::with_capacity(targets.len());
    for t in targets {
        let r = tree
            .query(&t.to_array())
            .nearest_one::<SquaredEuclidean<f64>>()
            .execute();
        let v = r.item;
        if out.last() != Some(&v) {
            out.push(v);
        }
    }
    while out.len() > 1 && out.first() == out.last() {
        out.pop();
    }
    out
}

/// Shortest path (by edge length) from `a` to `b`, both included; ties broken by vertex index.
pub fn shortest_path(mesh: &TriMesh, nb: &[Vec<u32>], a: u32, b: u32) -> Option<Vec<u32>> {
    let n = mesh.positions.len();
    let mut dist = vec![f64::INFINITY; n];
    let mut prev = vec![u32::MAX; n];
    let mut heap = BinaryHeap::new();
    dist[a as usize] = 0.0;
    heap.push(Reverse((OrdF64(0.0), a)));
    while let Some(Reverse((OrdF64(d), v))) = heap.pop() {
        if v == b {
            break;
        }
        if d > dist[v as usize] {
            continue;
        }
        for &w in &nb[v as usize] {
            let nd = d + (mesh.positions[w as usize] - mesh.positions[v as usize]).length();
            if nd < dist[w as usize] {
                dist[w as usize] = nd;
                prev[w as usize] = v;
                heap.push(Reverse((OrdF64(nd), w)));
            }
        }
    }
    if !dist[b as usize].is_finite() {
        return None;
    }
    let mut path = vec![b];
    let mut v = b;
    while v != a {
        v = prev[v as usize];
        path.push(v);
    }
    path.reverse();
    Some(path)
}

/// Closed vertex path through `anchors` (in order), each consecutive pair joined by a shortest
/// path; the result does not repeat its first vertex at the end.
pub fn closed_path(mesh: &TriMesh, nb: &[Vec<u32>], anchors: &[u32]) -> Option<Vec<u32>> {
    let mut out = Vec::new();
    for i in 0..anchors.len() {
        let (a, b) = (anchors[i], anchors[(i + 1) % anchors.len()]);
        let p = shortest_path(mesh, nb, a, b)?;
        out.extend_from_slice(&p[..p.len() - 1]);
    }
    Some(out)
}

#[derive(Clone, Copy, PartialEq)]
struct OrdF64(f64);
impl Eq for OrdF64 {}
impl PartialOrd for OrdF64 {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for OrdF64 {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}
