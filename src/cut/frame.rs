//! The tooth frame used by cutting and stitching: an origin on the margin, the long axis
//! (root → crown) and an angle around it; and the margin's height as a function of that angle.

use crate::{Error, Result};
use glam::DVec3;
use nalgebra::{Matrix3, SymmetricEigen};

/// Cylindrical frame of one tooth: `center` (margin centroid), unit `axis` pointing from the
/// root to the crown, and `e1`, `e2` spanning the plane across the axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToothFrame {
    /// Origin: the centroid of the margin loop.
    pub center: DVec3,
    /// Unit long axis, root → crown.
    pub axis: DVec3,
    /// First unit vector across the axis.
    pub e1: DVec3,
    /// Second unit vector across the axis (`axis × e1`).
    pub e2: DVec3,
}

impl ToothFrame {
    /// Frame from a margin loop (the best-fit plane's normal is the axis) oriented so that
    /// `crown_point` (e.g. the crown centroid) lies on the positive side.
    pub fn from_margin(margin: &[DVec3], crown_point: DVec3) -> Result<ToothFrame> {
        if margin.len() < 3 {
            return Err(Error::InvalidArgument(format!(
                "margin loop has {} vertices, at least 3 are needed",
                margin.len()
            )));
        }
        let center = crate::geom::centroid(margin).unwrap_or(DVec3::ZERO);
        let mut cov = Matrix3::<f64>::zeros();
        for p in margin {
            let d = *p - center;
            let v = nalgebra::Vector3::new(d.x, d.y, d.z);
            cov += v * v.transpose();
        }
        let eig = SymmetricEigen::new(cov);
        let (mut k, mut best) = (0, f64::INFINITY);
        for i in 0..3 {
            if eig.eigenvalues[i] < best {
                best = eig.eigenvalues[i];
                k = i;
            }
        }
        let n = eig.eigenvectors.column(k);
        let mut axis = DVec3::new(n[0], n[1], n[2]).normalize_or_zero();
        if axis == DVec3::ZERO || !axis.is_finite() {
            return Err(Error::InvalidArgument(
                "margin loop is degenerate (no plane)".into(),
            ));
        }
        if (crown_point - center).dot(axis) < 0.0 {
            axis = -axis;
        }
        Ok(Self::new(center, axis))
    }

    /// Frame with a given origin and axis (normalised here).
    pub fn new(center: DVec3, axis: DVec3) -> ToothFrame {
        let axis = axis.normalize();
        let e1 = axis.any_orthonormal_vector();
        let e2 = axis.cross(e1);
        Self {
            center,
            axis,
            e1,
            e2,
        }
    }

    /// Height of `p` along the axis, relative to the center.
    #[inline]
    pub fn height(&self, p: DVec3) -> f64 {
        (p - self.center).dot(self.axis)
    }

    /// Angle of `p` around the axis, in (-π, π].
    #[inline]
    pub fn angle(&self, p: DVec3) -> f64 {
        let d = p - self.center;
        d.dot(self.e2).atan2(d.dot(self.e1))
    }
}

/// The lowest margin height within a window around each angle, tabulated in one-degree bins:
/// the cut follows it (minus an offset) so the cut stays below the margin everywhere, even where
/// the margin rises into an interproximal notch.
#[derive(Clone, Debug)]
pub struct MarginHeight {
    bins: Vec<f64>,
}

const BINS: usize = 360;

impl MarginHeight {
    /// Tabulates the margin loop (closed polyline) in `frame`; `window` is the half-width in
    /// radians of the running minimum.
    pub fn new(frame: &ToothFrame, margin: &[DVec3], window: f64) -> MarginHeight {
        let mut raw = vec![f64::INFINITY; BINS];
        let bin = |a: f64| {
            (((a + std::f64::consts::PI) / std::f64::consts::TAU * BINS as f64).floor() as i64)
                .rem_euclid(BINS as i64) as usize
        };
        let n = margin.len();
        for i in 0..n {
            let (a, b) = (margin[i], margin[(i + 1) % n]);
            let steps = 8;
            for s in 0..steps {
                let p = a.lerp(b, s as f64 / steps as f64);
                let k = bin(frame.angle(p));
                raw[k] = raw[k].min(frame.height(p));
            }
        }
        // Fill empty bins from the nearest filled ones (circularly).
        let filled: Vec<usize> = (0..BINS).filter(|&k| raw[k].is_finite()).collect();
        if filled.is_empty() {
            return Self {
                bins: vec![0.0; BINS],
            };
        }
        let mut full = raw.clone();
        for k in 0..BINS {
            if !raw[k].is_finite() {
                let near = filled
                    .iter()
                    .min_by_key(|&&j| {
                        let d = (j as i64 - k as i64).rem_euclid(BINS as i64);
                        d.min(BINS as i64 - d)
                    })
                    .copied()
                    .unwrap_or(0);
                full[k] = raw[near];
            }
        }
        let w = ((window / std::f64::consts::TAU) * BINS as f64).round() as i64;
        let bins = (0..BINS as i64)
            .map(|k| {
                (-w..=w)
                    .map(|d| full[(k + d).rem_euclid(BINS as i64) as usize])
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        Self { bins }
    }

    /// Windowed minimum margin height at angle `a` (linear between bin centres).
    pub fn at(&self, a: f64) -> f64 {
        let x = (a + std::f64::consts::PI) / std::f64::consts::TAU * BINS as f64 - 0.5;
        let k0 = x.floor();
        let t = x - k0;
        let i0 = (k0 as i64).rem_euclid(BINS as i64) as usize;
        let i1 = (i0 + 1) % BINS;
        self.bins[i0] * (1.0 - t) + self.bins[i1] * t
    }
}
