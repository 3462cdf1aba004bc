//! The paper's point generation (Algorithm 1, lines 6 and 9–24): GENINTERPOINTS recursion,
//! INTERPOLATEPOINTS with a k-d tree (kiddo), and voxel downsampling. Each generated point also
//! carries its band parameter `(φ, v)`, interpolated exactly like its position, so the points
//! can be triangulated in the annulus with the two loops as constraints.

use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::collections::BTreeMap;
use std::num::NonZeroUsize;

/// A 3D point with its band parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamPoint {
    /// Position.
    pub pos: DVec3,
    /// Turn parameter around the tooth.
    pub phi: f64,
    /// Height fraction: 0 on the CBCT loop, 1 on the IOS margin.
    pub v: f64,
}

/// Options of Algorithm 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InterpOptions {
    /// N: neighbours per point.
    pub neighbours: usize,
    /// K: interpolated points per segment.
    pub per_segment: usize,
    /// m: recursion depth.
    pub depth: u32,
    /// Voxel size of the downsampling (mm); the paper uses 0.05.
    pub voxel: f64,
}

impl Default for InterpOptions {
    fn default() -> Self {
        Self {
            neighbours: 2,
            per_segment: 2,
            depth: 2,
            voxel: 0.05,
        }
    }
}

/// Algorithm 1, INTERPOLATEPOINTS (lines 16–24): for each point of `a`, its N nearest points of
/// `b` (k-d tree) and K points evenly inside each connecting segment.
pub fn interpolate_points(
    a: &[ParamPoint],
    b: &[ParamPoint],
    n: usize,
    k: usize,
) -> Vec<ParamPoint> {
    if a.is_empty() || b.is_empty() || n == 0 || k == 0 {
        return Vec::new();
    }
    let pts: Vec<[f64; 3]> = b.iter().map(|p| p.pos.to_array()).collect();
    let tree = ImmutableKdTree::<f64, 3>::new_from_slice(&pts).expect("kd-tree over points");
    let nn = NonZeroUsize::new(n.min(b.len())).unwrap_or(NonZeroUsize::MIN);
    let mut out = Vec::with_capacity(a.len() * n * k);
    for p in a {
        let found = tree
            .query(&p.pos.to_array())
            .nearest_n::<SquaredEuclidean<f64>>(nn)
            .execute();
        for r in found {
            let q = b[r.item as usize];
            let dphi = q.phi - p.phi - crate::geom::round(q.phi - p.phi);
            for j in 1..=k {
                let t = j as f64 / (k + 1) as f64;
                out.push(ParamPoint {
                    pos: p.pos.lerp(q.pos, t),
                    phi: p.phi + t * dphi,
                    v: p.v + t * (q.v - p.v),
                });
            }
        }
    }
    out
}

/// Algorithm 1, GENINTERPOINTS (lines 9–15): midpoints between `a` and `b`, then recursively
/// between `a` and the midpoints and between the midpoints and `b`, `m` levels deep.
pub fn gen_inter_points(
    a: &[ParamPoint],
    b: &[ParamPoint],
    n: usize,
    k: usize,
    m: u32,
) -> Vec<ParamPoint> {
    if m == 0 {
        return Vec::new();
    }
    let mid = interpolate_points(a, b, n, k);
    let mut out = gen_inter_points(a, &mid, n, k, m - 1);
    let pts_b = gen_inter_points(&mid, b, n, k, m - 1);
    out.extend_from_slice(&mid);
    out.extend(pts_b);
    out
}

/// Per-voxel sums: position, cos φ, sin φ, v, count.
type Acc = (DVec3, f64, f64, f64, usize);

/// Algorithm 1, DOWNSAMPLE (line 6): one point per occupied voxel of edge `voxel`, the mean of
/// the points in it (positions, parameters). Output sorted by voxel index (deterministic).
pub fn voxel_downsample(points: &[ParamPoint], voxel: f64) -> Vec<ParamPoint> {
    if voxel.is_nan() || voxel <= 0.0 {
        return points.to_vec();
    }
    let mut cells: BTreeMap<(i64, i64, i64), Acc> = BTreeMap::new();
    for p in points {
        let q = (p.pos / voxel).floor();
        let key = (q.x as i64, q.y as i64, q.z as i64);
        let e = cells.entry(key).or_insert((DVec3::ZERO, 0.0, 0.0, 0.0, 0));
        let a = std::f64::consts::TAU * p.phi;
        e.0 += p.pos;
        e.1 += a.cos();
        e.2 += a.sin();
        e.3 += p.v;
        e.4 += 1;
    }
    cells
        .values()
        .map(|&(s, c, si, v, n)| ParamPoint {
            pos: s / n as f64,
            phi: si.atan2(c) / std::f64::consts::TAU,
            v: v / n as f64,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(z: f64, v: f64, n: usize) -> Vec<ParamPoint> {
        (0..n)
            .map(|i| ParamPoint {
                pos: DVec3::new(i as f64 * 0.1, 0.0, z),
                phi: i as f64 / n as f64,
                v,
            })
            .collect()
    }

    #[test]
    fn recursion_counts_match_algorithm_1() {
        let a = line(1.0, 1.0, 10);
        let b = line(0.0, 0.0, 10);
        // m = 1: |A|·N·K midpoints.
        assert_eq!(gen_inter_points(&a, &b, 2, 3, 1).len(), 10 * 2 * 3);
        // m = 2: |A|NK (left) + |A|NK (mid) + |A|(NK)^2 (right).
        assert_eq!(gen_inter_points(&a, &b, 2, 3, 2).len(), 60 + 60 + 360);
        assert!(gen_inter_points(&a, &b, 2, 3, 0).is_empty());
        let pts = gen_inter_points(&a, &b, 1, 1, 1);
        // Nearest of each A point is the B point right below: midpoints at z = 0.5, v = 0.5.
        assert!(
            pts.iter()
                .all(|p| (p.pos.z - 0.5).abs() < 1e-12 && (p.v - 0.5).abs() < 1e-12)
        );
    }

    #[test]
    fn downsampling_merges_points_per_voxel() {
        let pts: Vec<ParamPoint> = (0..100)
            .map(|i| ParamPoint {
                pos: DVec3::new(0.001 * i as f64, 0.0, 0.0),
                phi: 0.0,
                v: 0.5,
            })
            .collect();
        let d = voxel_downsample(&pts, 0.05);
        assert_eq!(d.len(), 2);
        assert!((d[0].pos.x - 0.0245).abs() < 1e-12);
    }
}
