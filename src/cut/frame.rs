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

    /// Distance of `p` from the axis.
    #[inline]
    pub fn radius(&self, p: DVec3) -> f64 {
        let d = p - self.center;
        (d - self.axis * d.dot(self.axis)).length()
    }
}

/// The lowest margin height within a window around each angle, tabulated in one-degree bins:
/// the cut follows it (minus an offset) so the cut stays below the margin everywhere, even where
/// the margin rises into an interproximal notch. With a slope limit, it is lowered further where
/// it would climb faster than that: the cut then stays clear of the flanks of the tall horns a
/// labelled crown can have at its contacts (see [`MarginHeight::new`]).
#[derive(Clone, Debug)]
pub struct MarginHeight {
    bins: Vec<f64>,
}

const BINS: usize = 360;

impl MarginHeight {
    /// Tabulates the margin loop (closed polyline) in `frame`; `window` is the half-width in
    /// radians of the running minimum. `max_slope` > 0 bounds how fast the height may climb
    /// along the margin, in height per unit of length around the tooth (at the margin's mean
    /// distance from the axis): the table is then the largest function below the running minimum
    /// that climbs no faster (0: no bound).
    ///
    /// Where a labelled crown reaches up a contact (a lower incisor's label can run from the
    /// cervix to the incisal edge there), the running minimum climbs that flank as steeply as the
    /// margin does, and the band between them, a strip a fraction of the offset wide measured
    /// across the flank, folds over itself and through the root; the bound keeps the cut lower
    /// there and the band as tall as it needs.
    pub fn new(frame: &ToothFrame, margin: &[DVec3], window: f64, max_slope: f64) -> MarginHeight {
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
        let mut bins: Vec<f64> = (0..BINS as i64)
            .map(|k| {
                (-w..=w)
                    .map(|d| full[(k + d).rem_euclid(BINS as i64) as usize])
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        if max_slope > 0.0 && max_slope.is_finite() {
            let radius = margin.iter().map(|&p| frame.radius(p)).sum::<f64>() / n as f64;
            limit_slope(
                &mut bins,
                max_slope * radius * std::f64::consts::TAU / BINS as f64,
            );
        }
        Self { bins }
    }

    /// The table: per one-degree bin from -π, the height the cut follows.
    pub fn bins(&self) -> &[f64] {
        &self.bins
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

/// Lowers the circular table `bins` to the largest function below it whose neighbouring bins
/// differ by at most `step`: `bins[k] = min_j (bins[j] + step * d(j, k))`, `d` the circular bin
/// distance. Two laps each way carry every bin's bound around the whole circle.
fn limit_slope(bins: &mut [f64], step: f64) {
    let n = bins.len();
    for k in (0..2 * n).map(|i| i % n) {
        let prev = bins[(k + n - 1) % n] + step;
        bins[k] = bins[k].min(prev);
    }
    for k in (0..2 * n).rev().map(|i| i % n) {
        let next = bins[(k + 1) % n] + step;
        bins[k] = bins[k].min(next);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phantom::rng::Rng;

    /// [`limit_slope`] gives the lower envelope `min_j (bins[j] + step * d(j, k))` with the
    /// circular bin distance, on random tables (spikes, plateaus, wrap-around).
    #[test]
    fn slope_limit_is_the_circular_lower_envelope() {
        let mut rng = Rng::new(11);
        for case in 0..200 {
            let n = 3 + rng.below(60);
            let bins: Vec<f64> = (0..n)
                .map(|_| match rng.below(3) {
                    0 => 10.0 * rng.unit(),
                    1 => 0.0,
                    _ => -3.0,
                })
                .collect();
            let step = 0.05 + rng.unit();
            let mut got = bins.clone();
            limit_slope(&mut got, step);
            for (k, &g) in got.iter().enumerate() {
                let want = bins
                    .iter()
                    .enumerate()
                    .map(|(j, &b)| {
                        let d = (j as i64 - k as i64).rem_euclid(n as i64) as usize;
                        b + step * d.min(n - d) as f64
                    })
                    .fold(f64::INFINITY, f64::min);
                assert!((g - want).abs() < 1e-9, "case {case} bin {k}");
            }
        }
    }

    /// A ring margin of radius 3 mm at height 0 with a horn climbing to 5 mm over 8° (a contact
    /// reached by the crown's label): without a bound the table climbs the horn's flanks as
    /// steeply; with `max_slope` 1 it climbs no faster than 1 mm per mm around the tooth, stays
    /// below the unbounded table everywhere, and equals it where the margin is flat.
    #[test]
    fn slope_bound_keeps_the_table_off_a_horn_flank() {
        let frame = ToothFrame::new(DVec3::ZERO, DVec3::Z);
        let margin: Vec<DVec3> = (0..720)
            .map(|i| {
                let a = (i as f64 / 2.0 - 180.0).to_radians();
                let horn = (1.0 - (a - 1.0).abs() / 4f64.to_radians()).max(0.0);
                let p = DVec3::new(3.0 * a.cos(), 3.0 * a.sin(), 5.0 * horn);
                // In the frame's own angles (its e1, e2 are any orthonormal pair).
                let q = p.x * frame.e1 + p.y * frame.e2;
                DVec3::new(q.x, q.y, p.z)
            })
            .collect();
        let free = MarginHeight::new(&frame, &margin, 0.0, 0.0);
        let bound = MarginHeight::new(&frame, &margin, 0.0, 1.0);
        let step = 3.0 * std::f64::consts::TAU / 360.0;
        let free_top = free.bins().iter().copied().fold(f64::MIN, f64::max);
        let bound_top = bound.bins().iter().copied().fold(f64::MIN, f64::max);
        assert!(
            free_top > 4.0,
            "the unbounded table climbs the horn: {free_top}"
        );
        // 1 mm per mm from the horn's feet, 4° (4 bins) on either side of its top.
        assert!(
            bound_top <= 5.0 * step + 1e-9 && bound_top >= 3.0 * step,
            "the bound table rises a little: {bound_top}"
        );
        let b = bound.bins();
        for k in 0..b.len() {
            let next = b[(k + 1) % b.len()];
            assert!(
                (next - b[k]).abs() <= step + 1e-9,
                "bin {k}: {} → {next}",
                b[k]
            );
            assert!(b[k] <= free.bins()[k], "bin {k}");
        }
        // Half a turn from the horn the margin is flat at 0: both tables are 0 there.
        let far = ((1.0 - std::f64::consts::PI).to_degrees() + 180.0).rem_euclid(360.0) as usize;
        assert_eq!(b[far], 0.0);
        assert_eq!(free.bins()[far], 0.0);
    }
}
