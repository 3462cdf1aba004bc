//! Closed polylines (the loops): mean edge length and smoothing.

use glam::DVec3;

/// Mean edge length of a closed polyline.
pub(super) fn mean_edge(p: &[DVec3]) -> f64 {
    (0..p.len())
        .map(|i| (p[(i + 1) % p.len()] - p[i]).length())
        .sum::<f64>()
        / p.len() as f64
}

/// `iters` passes of (1, 2, 1)/4 smoothing of a closed polyline.
pub(super) fn smooth(p: &[DVec3], iters: usize) -> Vec<DVec3> {
    let n = p.len();
    let mut cur = p.to_vec();
    for _ in 0..iters {
        cur = (0..n)
            .map(|i| (cur[(i + n - 1) % n] + 2.0 * cur[i] + cur[(i + 1) % n]) * 0.25)
            .collect();
    }
    cur
}

pub(super) fn smooth_dirs(d: &[DVec3], iters: usize) -> Vec<DVec3> {
    smooth(d, iters)
        .into_iter()
        .zip(d)
        .map(|(s, o)| {
            let u = s.normalize_or_zero();
            if u == DVec3::ZERO { *o } else { u }
        })
        .collect()
}
