//! Shared helpers of the phantom tests: point-to-surface distances and topology checks.
#![allow(dead_code)]

use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use toothfuse::mesh::{TriMesh, ValidateOptions, boundary_loops, connected_components};

/// Point-to-triangle distance (Ericson, Real-Time Collision Detection 5.1.5).
pub fn point_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.length();
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return bp.length();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (p - (a + ab * v)).length();
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return cp.length();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (p - (a + ac * w)).length();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).length();
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (p - (a + ab * v + ac * w)).length()
}

/// Distance queries to a triangle mesh: nearest vertices by k-d tree, then their faces.
pub struct SurfaceDistance<'a> {
    mesh: &'a TriMesh,
    tree: ImmutableKdTree<f64, 3>,
    faces_of: Vec<Vec<u32>>,
}

impl<'a> SurfaceDistance<'a> {
    pub fn new(mesh: &'a TriMesh) -> Self {
        let pts: Vec<[f64; 3]> = mesh.positions.iter().map(|p| p.to_array()).collect();
        let tree = ImmutableKdTree::new_from_slice(&pts).expect("k-d tree");
        let mut faces_of = vec![Vec::new(); mesh.positions.len()];
        for (f, t) in mesh.triangles.iter().enumerate() {
            for &v in t {
                faces_of[v as usize].push(f as u32);
            }
        }
        Self {
            mesh,
            tree,
            faces_of,
        }
    }

    /// Distance from `p` to the surface (exact over the faces of the 8 nearest vertices).
    pub fn distance(&self, p: DVec3) -> f64 {
        let near = self
            .tree
            .query(&p.to_array())
            .nearest_n::<SquaredEuclidean<f64>>(std::num::NonZero::new(8).unwrap())
            .execute();
        let mut best = f64::INFINITY;
        for n in near {
            for &f in &self.faces_of[n.item as usize] {
                let [a, b, c] = self.mesh.corners(f as usize);
                best = best.min(point_triangle(p, a, b, c));
            }
            best = best.min(n.distance.sqrt());
        }
        best
    }
}

/// Closed, manifold, one component, positive volume.
pub fn assert_closed_tooth(m: &TriMesh, what: &str) {
    let r = m
        .validate(&ValidateOptions {
            require_closed: true,
            allow_zero_area: true,
        })
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(r.is_closed_manifold(), "{what}: {r:?}");
    assert_eq!(r.components, 1, "{what}: components");
    assert!(
        m.signed_volume() > 0.0,
        "{what}: volume {}",
        m.signed_volume()
    );
}

/// One component, manifold, exactly one boundary loop.
pub fn assert_disk(m: &TriMesh, what: &str) {
    let r = m
        .validate(&ValidateOptions {
            require_closed: false,
            allow_zero_area: true,
        })
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    assert_eq!(
        r.non_manifold_edges + r.non_manifold_vertices,
        0,
        "{what}: {r:?}"
    );
    assert_eq!(connected_components(m).1, 1, "{what}: components");
    assert_eq!(boundary_loops(m).len(), 1, "{what}: boundary loops");
}

/// RMS, mean and max of a list of values.
pub fn stats(v: &[f64]) -> (f64, f64, f64) {
    let n = v.len().max(1) as f64;
    let rms = (v.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
    let mean = v.iter().sum::<f64>() / n;
    let max = v.iter().cloned().fold(0.0, f64::max);
    (rms, mean, max)
}
