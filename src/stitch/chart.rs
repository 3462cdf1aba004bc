//! Ours (the default band): the gap between the two loops is meshed in a flat chart of the
//! tooth's side and lifted back to 3D as a radial graph over that chart.
//!
//! * Chart: `x` = arc length along a strongly smoothed copy of the IOS margin seen along the
//!   tooth axis ([`RefCurve`]), `y` = height along the axis; a point's third coordinate is its
//!   horizontal offset along the curve's normal. Near the cervical line the tooth side is steep,
//!   so the chart is close to isometric there and planar angles survive the lift.
//! * Points: a graded, deterministic Poisson-disk sample of the region between the two loop
//!   polylines ([`super::chart_sample::sample`]): spacing from the margin's edge length at the
//!   top to the cut's at the bottom, kept clear of loop vertices and edges so no sliver forms
//!   against a loop.
//! * Lift: every interior point keeps its chart position; its offset is a cubic Hermite profile
//!   between the smoothed loops (tangent to crown and root) plus a harmonic correction that makes
//!   it meet the real, jagged loop vertices exactly. A graph over a planar triangulation cannot
//!   fold onto itself, and the crown (above the margin in the chart) and the root (below the
//!   cut) are graphs over regions the band does not cover, so the band stays clear of them.

use crate::cut::ToothFrame;
use crate::{Error, Result};
use glam::DVec3;

/// Wraps `d` into `(-period/2, period/2]`.
pub(super) fn wrap(d: f64, period: f64) -> f64 {
    d - period * crate::geom::round(d / period)
}

/// The chart's reference: a strongly smoothed copy of the margin, projected along the axis. A
/// point's chart `x` is the arc length of its horizontal projection's closest point on this
/// curve, its offset the signed horizontal distance along the curve's outward normal.
#[derive(Clone, Debug)]
pub struct RefCurve {
    frame: ToothFrame,
    /// Horizontal positions relative to the frame center.
    pts: Vec<DVec3>,
    /// Unit outward horizontal normals at the vertices.
    normals: Vec<DVec3>,
    /// Arc length at each vertex.
    s: Vec<f64>,
    /// Length of the curve (the chart's period, mm).
    pub length: f64,
    /// Per run of [`BLOCK`] consecutive segments: a ball (center, radius) holding them, to skip
    /// runs that cannot hold the closest point in [`RefCurve::locate`].
    blocks: Vec<(DVec3, f64)>,
}

/// Segments per bounding ball of [`RefCurve`].
const BLOCK: usize = 16;

/// Slack (mm) on a ball's distance bound: far above rounding error at tooth scale, so a skipped
/// segment's computed distance is certainly above the best one.
const BOUND_SLACK: f64 = 1e-9;

impl RefCurve {
    /// The reference curve of `pts` (closed, counter-clockwise about `frame`'s axis).
    pub fn new(frame: &ToothFrame, pts: &[DVec3]) -> Result<RefCurve> {
        let n = pts.len();
        if n < 3 {
            return Err(Error::InvalidArgument("reference loop too short".into()));
        }
        let hp: Vec<DVec3> = pts
            .iter()
            .map(|&p| {
                let d = p - frame.center;
                d - d.dot(frame.axis) * frame.axis
            })
            .collect();
        let mut s = Vec::with_capacity(n);
        let mut length = 0.0;
        let mut area = 0.0;
        for i in 0..n {
            s.push(length);
            let (a, b) = (hp[i], hp[(i + 1) % n]);
            length += (b - a).length();
            area += a.cross(b).dot(frame.axis);
        }
        if !(length.is_finite() && length > 0.0) || area <= 0.0 {
            return Err(Error::InvalidArgument(
                "margin loop does not run counter-clockwise around the tooth axis".into(),
            ));
        }
        let normals = (0..n)
            .map(|i| {
                let t = hp[(i + 1) % n] - hp[(i + n - 1) % n];
                t.cross(frame.axis).normalize_or_zero()
            })
            .collect();
        let blocks = (0..n)
            .step_by(BLOCK)
            .map(|i0| {
                // The run's segments i0..i1 use vertices i0..=i1 (wrapping).
                let i1 = (i0 + BLOCK).min(n);
                let vs = || (i0..=i1).map(|i| hp[i % n]);
                let c = vs().fold(DVec3::ZERO, |acc, p| acc + p) / (i1 - i0 + 1) as f64;
                let r = vs().map(|p| (p - c).length()).fold(0.0, f64::max);
                (c, r)
            })
            .collect();
        Ok(Self {
            frame: *frame,
            pts: hp,
            normals,
            s,
            length,
            blocks,
        })
    }

    /// Squared distance from `q` to segment `i` and the closest point's parameter on it.
    #[inline]
    fn segment_distance(&self, q: DVec3, i: usize) -> (f64, f64) {
        let n = self.pts.len();
        let (a, b) = (self.pts[i], self.pts[(i + 1) % n]);
        let e = b - a;
        let l2 = e.length_squared();
        let t = if l2 > 0.0 {
            ((q - a).dot(e) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        ((a + t * e - q).length_squared(), t)
    }

    /// Chart `x` and signed offset of `p`'s horizontal projection.
    pub fn locate(&self, p: DVec3) -> (f64, f64) {
        let d = p - self.frame.center;
        let q = d - d.dot(self.frame.axis) * self.frame.axis;
        let n = self.pts.len();
        // The first segment (lowest index) of least squared distance, as a scan of all of them
        // finds it; runs whose bounding ball is farther than an already computed distance
        // (`bound`: first from the run of nearest ball) cannot hold it and are skipped.
        let lower = |&(c, r): &(DVec3, f64)| (q - c).length() - r - BOUND_SLACK;
        let nearest = (0..self.blocks.len())
            .min_by(|&a, &b| lower(&self.blocks[a]).total_cmp(&lower(&self.blocks[b])))
            .unwrap_or(0);
        let mut bound = (nearest * BLOCK..((nearest + 1) * BLOCK).min(n))
            .map(|i| self.segment_distance(q, i).0)
            .fold(f64::INFINITY, f64::min);
        let mut best = (f64::INFINITY, 0usize, 0.0);
        for (k, ball) in self.blocks.iter().enumerate() {
            let l = lower(ball);
            if l > 0.0 && l * l > bound {
                continue;
            }
            for i in k * BLOCK..((k + 1) * BLOCK).min(n) {
                let (d2, t) = self.segment_distance(q, i);
                if d2 < best.0 {
                    best = (d2, i, t);
                }
            }
            bound = bound.min(best.0);
        }
        let (_, i, t) = best;
        let j = (i + 1) % n;
        let seg = (self.pts[j] - self.pts[i]).length();
        let base = self.pts[i].lerp(self.pts[j], t);
        let nrm = self.normals[i].lerp(self.normals[j], t).normalize_or_zero();
        (self.s[i] + t * seg, (q - base).dot(nrm))
    }

    /// Base point (horizontal, relative to the center) and unit normal at chart `x`.
    fn at(&self, x: f64) -> (DVec3, DVec3) {
        let n = self.pts.len();
        let x = x.rem_euclid(self.length);
        let k = self.s.partition_point(|&t| t <= x).clamp(1, n);
        let i = k - 1;
        let j = k % n;
        let end = if k == n { self.length } else { self.s[k] };
        let t = if end > self.s[i] {
            ((x - self.s[i]) / (end - self.s[i])).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (
            self.pts[i].lerp(self.pts[j], t),
            self.normals[i].lerp(self.normals[j], t).normalize_or_zero(),
        )
    }
}

/// The horizontal convex hull of `pts` about `frame`'s axis, resampled at `spacing` and
/// smoothed (`iters` passes of (1, 2, 1)/4, which keep it convex), counter-clockwise, at height
/// 0 — a reference curve whose inward normal offsets do not fold over concave tooth sides.
pub fn convex_reference(
    frame: &ToothFrame,
    pts: &[DVec3],
    spacing: f64,
    iters: usize,
) -> Vec<DVec3> {
    let mut q: Vec<[f64; 2]> = pts
        .iter()
        .map(|&p| {
            let d = p - frame.center;
            [d.dot(frame.e1), d.dot(frame.e2)]
        })
        .collect();
    q.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    q.dedup();
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(q.len() + 1);
    for pass in 0..2 {
        let start = hull.len();
        let it: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(q.iter())
        } else {
            Box::new(q.iter().rev())
        };
        for &p in it {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    // Resample uniformly, in the frame's plane (z = 0).
    let n = hull.len();
    let mut out: Vec<DVec3> = Vec::new();
    if n < 3 {
        return Vec::new();
    }
    for i in 0..n {
        let (a, b) = (hull[i], hull[(i + 1) % n]);
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        let k = ((len / spacing).ceil() as usize).max(1);
        for j in 0..k {
            let t = j as f64 / k as f64;
            out.push(DVec3::new(
                a[0] + t * (b[0] - a[0]),
                a[1] + t * (b[1] - a[1]),
                0.0,
            ));
        }
    }
    // Smoothed like the loops themselves.
    super::smooth(&out, iters)
        .iter()
        .map(|p| frame.center + p.x * frame.e1 + p.y * frame.e2)
        .collect()
}

/// A smoothed loop as periodic functions of the chart `x`: height, offset from the reference
/// curve and slope `d(offset)/dy` of the adjacent surface.
#[derive(Clone, Debug)]
struct Profile {
    x: Vec<f64>,
    y: Vec<f64>,
    r: Vec<f64>,
    s: Vec<f64>,
    period: f64,
}

impl Profile {
    fn new(frame: &ToothFrame, rc: &RefCurve, pts: &[DVec3], dirs: &[DVec3]) -> Profile {
        let period = rc.length;
        let mut rows: Vec<(f64, f64, f64, f64)> = pts
            .iter()
            .zip(dirs)
            .map(|(&p, &d)| {
                let (x, r) = rc.locate(p);
                let (_, nrm) = rc.at(x);
                let s = (d.dot(nrm) / d.dot(frame.axis).max(0.3)).clamp(-1.5, 1.5);
                (x, frame.height(p), r, s)
            })
            .collect();
        rows.sort_by(|a, b| a.0.total_cmp(&b.0));
        Profile {
            x: rows.iter().map(|r| r.0).collect(),
            y: rows.iter().map(|r| r.1).collect(),
            r: rows.iter().map(|r| r.2).collect(),
            s: rows.iter().map(|r| r.3).collect(),
            period,
        }
    }

    /// `(y, r, s)` at chart `x` (periodic linear interpolation).
    fn at(&self, x: f64) -> (f64, f64, f64) {
        let n = self.x.len();
        let x = x.rem_euclid(self.period);
        let k = self.x.partition_point(|&t| t <= x);
        if k == 0 || k == n {
            let (x0, x1) = (self.x[n - 1], self.x[0] + self.period);
            let xx = if k == 0 { x + self.period } else { x };
            let t = if x1 > x0 { (xx - x0) / (x1 - x0) } else { 0.0 };
            return self.lerp(n - 1, 0, t.clamp(0.0, 1.0));
        }
        let (x0, x1) = (self.x[k - 1], self.x[k]);
        let t = if x1 > x0 { (x - x0) / (x1 - x0) } else { 0.0 };
        self.lerp(k - 1, k, t.clamp(0.0, 1.0))
    }

    fn lerp(&self, i: usize, j: usize, t: f64) -> (f64, f64, f64) {
        let l = |v: &[f64]| v[i] + (v[j] - v[i]) * t;
        (l(&self.y), l(&self.r), l(&self.s))
    }
}

/// The lift from the chart to 3D: Hermite offset profile between the smoothed loops.
#[derive(Clone, Debug)]
pub struct Lift {
    frame: ToothFrame,
    curve: RefCurve,
    upper: Profile,
    lower: Profile,
    tangent_scale: f64,
}

impl Lift {
    /// Builds the lift from the reference curve and the smoothed loops with their surface
    /// directions (see [`super::BandLoops`]).
    pub fn new(
        frame: &ToothFrame,
        curve: RefCurve,
        upper: (&[DVec3], &[DVec3]),
        lower: (&[DVec3], &[DVec3]),
        tangent_scale: f64,
    ) -> Lift {
        let up = Profile::new(frame, &curve, upper.0, upper.1);
        let lo = Profile::new(frame, &curve, lower.0, lower.1);
        Lift {
            frame: *frame,
            curve,
            upper: up,
            lower: lo,
            tangent_scale,
        }
    }

    /// Chart period (the reference curve's length, mm).
    pub fn period(&self) -> f64 {
        self.curve.length
    }

    /// Chart coordinates and offset of a 3D point.
    pub fn chart(&self, p: DVec3) -> ([f64; 2], f64) {
        let (x, r) = self.curve.locate(p);
        ([x, self.frame.height(p)], r)
    }

    /// The Hermite profile's offset at chart point `c`.
    pub fn profile_offset(&self, c: [f64; 2]) -> f64 {
        let (yu, ru, su) = self.upper.at(c[0]);
        let (yl, rl, sl) = self.lower.at(c[0]);
        let h = yu - yl;
        if h.abs() < 1e-9 {
            return 0.5 * (ru + rl);
        }
        let (mu, ml) = (self.tangent_scale * su * h, self.tangent_scale * sl * h);
        // Beyond the smoothed loops (notches, jagged margins) the profile stays flat; the
        // harmonic correction carries the real loops' offsets there.
        let t = ((c[1] - yl) / h).clamp(0.0, 1.0);
        let (t2, t3) = (t * t, t * t * t);
        (2.0 * t3 - 3.0 * t2 + 1.0) * rl
            + (t3 - 2.0 * t2 + t) * ml
            + (-2.0 * t3 + 3.0 * t2) * ru
            + (t3 - t2) * mu
    }

    /// The outward unit normal (horizontal) of the reference curve at chart `x`.
    pub fn outward(&self, x: f64) -> DVec3 {
        self.curve.at(x).1
    }

    /// The 3D point at chart `c` and offset `r`.
    pub fn point(&self, c: [f64; 2], r: f64) -> DVec3 {
        let (base, nrm) = self.curve.at(c[0]);
        self.frame.center + c[1] * self.frame.axis + base + r * nrm
    }
}

/// Harmonic interpolation over a triangulation in chart coordinates: `values[i]` is kept where
/// `fixed[i]`, the others solve the discrete Laplace equation (cotangent weights, clamped
/// positive) by Gauss–Seidel sweeps in index order (deterministic).
pub fn harmonic(
    chart: &[[f64; 2]],
    period: f64,
    triangles: &[[u32; 3]],
    fixed: &[bool],
    values: &mut [f64],
) {
    let n = chart.len();
    let mut edges: Vec<(u32, u32, f64)> = Vec::with_capacity(triangles.len() * 6);
    for t in triangles {
        let p0 = chart[t[0] as usize];
        let loc = |v: u32| {
            let q = chart[v as usize];
            [p0[0] + wrap(q[0] - p0[0], period), q[1]]
        };
        let c = [loc(t[0]), loc(t[1]), loc(t[2])];
        for k in 0..3 {
            let (a, b, o) = (c[(k + 1) % 3], c[(k + 2) % 3], c[k]);
            let (ux, uy) = (a[0] - o[0], a[1] - o[1]);
            let (vx, vy) = (b[0] - o[0], b[1] - o[1]);
            let cross = (ux * vy - uy * vx).abs();
            let w = if cross > 0.0 {
                0.5 * (ux * vx + uy * vy) / cross
            } else {
                0.0
            };
            let (i, j) = (t[(k + 1) % 3], t[(k + 2) % 3]);
            edges.push((i, j, w));
            edges.push((j, i, w));
        }
    }
    // Stable: the weights of an edge are summed in the order they were pushed.
    crate::radix::sort_by_key(&mut edges, |e| (e.0 as u64) << 32 | e.1 as u64);
    let mut start = vec![0usize; n + 1];
    let mut adj: Vec<(u32, f64)> = Vec::with_capacity(edges.len() / 2);
    let mut k = 0;
    for (i, st) in start.iter_mut().enumerate().take(n) {
        *st = adj.len();
        while k < edges.len() && edges[k].0 as usize == i {
            let j = edges[k].1;
            let mut w = 0.0;
            while k < edges.len() && edges[k].0 as usize == i && edges[k].1 == j {
                w += edges[k].2;
                k += 1;
            }
            adj.push((j, w.max(0.02)));
        }
    }
    start[n] = adj.len();
    for _ in 0..400 {
        let mut change: f64 = 0.0;
        for i in 0..n {
            if fixed[i] || start[i] == start[i + 1] {
                continue;
            }
            let (mut s, mut ws) = (0.0, 0.0);
            for &(j, w) in &adj[start[i]..start[i + 1]] {
                s += w * values[j as usize];
                ws += w;
            }
            let v = s / ws;
            change = change.max((v - values[i]).abs());
            values[i] = v;
        }
        if change < 1e-7 {
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    fn circle(r: f64, z: f64, n: usize, wobble: f64) -> Vec<DVec3> {
        (0..n)
            .map(|i| {
                let a = TAU * i as f64 / n as f64;
                DVec3::new(r * a.cos(), r * a.sin(), z + wobble * (7.0 * a).sin())
            })
            .collect()
    }

    /// `locate`'s choice by a scan of every segment (what the ball skipping must reproduce).
    fn locate_by_scan(c: &RefCurve, p: DVec3) -> (f64, f64) {
        let d = p - c.frame.center;
        let q = d - d.dot(c.frame.axis) * c.frame.axis;
        let n = c.pts.len();
        let mut best = (f64::INFINITY, 0usize, 0.0);
        for i in 0..n {
            let (d2, t) = c.segment_distance(q, i);
            if d2 < best.0 {
                best = (d2, i, t);
            }
        }
        let (_, i, t) = best;
        let j = (i + 1) % n;
        let seg = (c.pts[j] - c.pts[i]).length();
        let base = c.pts[i].lerp(c.pts[j], t);
        let nrm = c.normals[i].lerp(c.normals[j], t).normalize_or_zero();
        (c.s[i] + t * seg, (q - base).dot(nrm))
    }

    #[test]
    fn locate_skipping_equals_full_scan() {
        let f = ToothFrame::new(DVec3::new(0.3, -0.2, 1.0), DVec3::new(0.1, 0.2, 1.0));
        let mut x = 99u64;
        let mut rnd = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for (n, wobble) in [(3, 0.0), (17, 0.3), (40, 0.0), (333, 0.2), (401, 0.05)] {
            // Radially wobbled (non-convex for the larger wobbles), tilted by the frame.
            let pts: Vec<DVec3> = circle(3.0, 0.5, n, wobble)
                .into_iter()
                .map(|p| {
                    let a = p.y.atan2(p.x);
                    let k = 1.0 + wobble * (5.0 * a).sin();
                    f.center + (p.x * k) * f.e1 + (p.y * k) * f.e2 + p.z * f.axis
                })
                .collect();
            let c = RefCurve::new(&f, &pts).unwrap();
            // Random points near and far, the exact center (all segments nearly tied) and the
            // curve's own vertices and midpoints (ties between neighbouring segments).
            let mut qs: Vec<DVec3> = (0..400)
                .map(|_| f.center + DVec3::new(rnd(), rnd(), rnd()) * 10.0)
                .collect();
            qs.push(f.center);
            qs.extend(pts.iter().copied());
            qs.extend((0..n).map(|i| pts[i].lerp(pts[(i + 1) % n], 0.5)));
            for q in qs {
                let (a, b) = (c.locate(q), locate_by_scan(&c, q));
                assert_eq!(a.0.to_bits(), b.0.to_bits(), "{q}");
                assert_eq!(a.1.to_bits(), b.1.to_bits(), "{q}");
            }
        }
    }

    #[test]
    fn ref_curve_round_trips() {
        let f = ToothFrame::new(DVec3::ZERO, DVec3::Z);
        let pts = circle(3.0, 0.0, 400, 0.1);
        let c = RefCurve::new(&f, &pts).unwrap();
        assert!((c.length - TAU * 3.0).abs() < 0.01);
        for k in 0..50 {
            let x = c.length * k as f64 / 50.0;
            for r in [-0.4, 0.0, 0.3] {
                let (base, nrm) = c.at(x);
                let p = base + r * nrm + DVec3::Z * 0.7;
                let (x2, r2) = c.locate(p);
                assert!(wrap(x2 - x, c.length).abs() < 5e-3, "{x} {x2}");
                assert!((r2 - r).abs() < 1e-3, "{r} {r2}");
            }
        }
        let rev: Vec<DVec3> = pts.iter().rev().copied().collect();
        assert!(RefCurve::new(&f, &rev).is_err(), "clockwise loop refused");
    }

    #[test]
    fn harmonic_interpolates_linear_data_exactly() {
        // A strip triangulated as a grid: linear boundary data → linear interior.
        let (nx, ny) = (12usize, 5usize);
        let period = nx as f64;
        let mut chart = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                chart.push([i as f64, j as f64]);
            }
        }
        let id = |i: usize, j: usize| (j * nx + i % nx) as u32;
        let mut tris = Vec::new();
        for j in 0..ny - 1 {
            for i in 0..nx {
                tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let fixed: Vec<bool> = chart.iter().map(|p| p[1] == 0.0 || p[1] == 4.0).collect();
        let mut v: Vec<f64> = chart
            .iter()
            .zip(&fixed)
            .map(|(p, &f)| if f { 2.0 * p[1] + 1.0 } else { 0.0 })
            .collect();
        harmonic(&chart, period, &tris, &fixed, &mut v);
        for (p, x) in chart.iter().zip(&v) {
            assert!((x - (2.0 * p[1] + 1.0)).abs() < 1e-5, "{p:?} {x}");
        }
    }
}
