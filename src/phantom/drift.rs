//! IOS stitching drift: the scanner registers each new view to the previous ones, so errors
//! accumulate tooth after tooth along the scan path. The first tooth scanned is exact; each
//! following tooth adds a small rigid increment (a persistent part plus noise), so the drift is
//! largest at the far end of the arch.

use super::rng::Rng;
use crate::Rigid;
use glam::{DMat3, DVec3};

/// Drift amplitudes at the far end of the arch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DriftAmount {
    /// Rotation at the far end (degrees).
    pub angle_deg: f64,
    /// Displacement of the far tooth's crown centre (mm).
    pub shift_mm: f64,
}

/// Per-tooth drifts for teeth with crown centres `centers`, listed in arch order. The scan
/// starts at the first (`start_at_first`) or the last tooth. Tooth k's drift rotates about its
/// own crown centre by the accumulated rotation and shifts it by the accumulated translation.
pub fn drifts(
    centers: &[DVec3],
    amount: DriftAmount,
    start_at_first: bool,
    rng: &mut Rng,
) -> Vec<Rigid> {
    let n = centers.len();
    let mut out = vec![Rigid::IDENTITY; n];
    if n < 2 {
        return out;
    }
    let steps = (n - 1) as f64;
    let w_axis = rng.unit_vector();
    let t_dir = rng.unit_vector();
    let w_mean = amount.angle_deg.to_radians() / steps;
    let t_mean = amount.shift_mm / steps;
    let mut w = DVec3::ZERO;
    let mut t = DVec3::ZERO;
    let order: Vec<usize> = if start_at_first {
        (0..n).collect()
    } else {
        (0..n).rev().collect()
    };
    for (step, &k) in order.iter().enumerate() {
        if step > 0 {
            w += w_axis * w_mean + rng.unit_vector() * (0.3 * w_mean);
            t += t_dir * t_mean + rng.unit_vector() * (0.3 * t_mean);
        }
        let angle = w.length();
        let rot = if angle > 0.0 {
            DMat3::from_axis_angle(w / angle, angle)
        } else {
            DMat3::IDENTITY
        };
        let c = centers[k];
        out[k] = Rigid::new(rot, c - rot * c + t);
    }
    out
}

/// A uniformly random rotation with a translation of up to `max_shift` mm per axis.
pub fn random_pose(rng: &mut Rng, max_shift: f64) -> Rigid {
    // Uniform random unit quaternion (Shoemake).
    let (u1, u2, u3) = (rng.unit(), rng.unit(), rng.unit());
    let (s1, s2) = ((1.0 - u1).sqrt(), u1.sqrt());
    let tau = std::f64::consts::TAU;
    let q = glam::DQuat::from_xyzw(
        s1 * (tau * u2).sin(),
        s1 * (tau * u2).cos(),
        s2 * (tau * u3).sin(),
        s2 * (tau * u3).cos(),
    )
    .normalize();
    let t = DVec3::new(
        rng.range(-max_shift, max_shift),
        rng.range(-max_shift, max_shift),
        rng.range(-max_shift, max_shift),
    );
    Rigid::new(DMat3::from_quat(q), t)
}
