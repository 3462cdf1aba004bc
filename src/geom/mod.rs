//! Small geometric primitives shared by every stage: rigid transforms, points, boxes.

mod rigid;
mod triangle;

pub use glam::{DMat3, DVec3};
pub use rigid::Rigid;
pub use triangle::closest_point_on_triangle;

/// Axis-aligned bounding box of a point set; `None` when empty.
pub fn bounding_box(points: &[DVec3]) -> Option<(DVec3, DVec3)> {
    let first = *points.first()?;
    Some(
        points
            .iter()
            .fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))),
    )
}

/// `x.round()` (halves away from zero), the same value for every input (signed zeros, NaN and
/// infinities included), without the library call the baseline x86-64 target makes for it: the
/// periodic wraps of the stitching charts call it millions of times per tooth.
#[inline]
pub fn round(x: f64) -> f64 {
    // Below 2^52 the integer part fits an i64 and `x - trunc(x)` is exact.
    if x.abs() < 4_503_599_627_370_496.0 {
        let t = (x as i64) as f64;
        let r = x - t;
        let n = if r >= 0.5 {
            t + 1.0
        } else if r <= -0.5 {
            t - 1.0
        } else {
            t
        };
        n.copysign(x)
    } else {
        x.round()
    }
}

/// Mean of a point set; `None` when empty.
pub fn centroid(points: &[DVec3]) -> Option<DVec3> {
    if points.is_empty() {
        return None;
    }
    let sum = points.iter().fold(DVec3::ZERO, |acc, p| acc + *p);
    Some(sum / points.len() as f64)
}

/// The scatter matrix `Σ (p − c)(p − c)ᵀ` of `points` about `c` (entries accumulated point by
/// point, in order): what the principal axes and frames of tooth, arch and crown point sets are
/// taken from.
pub fn scatter<'a>(
    points: impl IntoIterator<Item = &'a DVec3>,
    c: DVec3,
) -> nalgebra::Matrix3<f64> {
    let mut m = nalgebra::Matrix3::<f64>::zeros();
    for p in points {
        let d = *p - c;
        for i in 0..3 {
            for j in 0..3 {
                m[(i, j)] += d[i] * d[j];
            }
        }
    }
    m
}

/// The centroid of `points` and their principal axis (unit eigenvector of the largest
/// eigenvalue of their [`scatter`] matrix; its sign is arbitrary), or `None` without points.
pub fn principal_axis(points: &[DVec3]) -> Option<(DVec3, DVec3)> {
    let c = centroid(points)?;
    let eig = scatter(points, c).symmetric_eigen();
    let mut best = 0;
    for k in 1..3 {
        if eig.eigenvalues[k] > eig.eigenvalues[best] {
            best = k;
        }
    }
    let a = eig.eigenvectors.column(best);
    Some((c, DVec3::new(a[0], a[1], a[2]).normalize()))
}

/// `x.floor() as i64` (saturating, 0 for NaN) without the library call that `floor` is on
/// targets without a rounding instruction: the conversion truncates toward zero, and one is
/// taken off where that rounded a negative fraction up.
#[inline(always)]
pub(crate) fn floor_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// `x.ceil() as i64` (saturating, 0 for NaN) the same way as [`floor_i64`].
#[inline(always)]
pub(crate) fn ceil_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) < x {
        t.saturating_add(1)
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::{ceil_i64, floor_i64, round};

    /// The same as `floor`/`ceil` then the saturating conversion: fractions and integers of
    /// both signs, zeros, values near and beyond the `i64` range, infinities and NaN.
    #[test]
    fn floor_and_ceil_i64_equal_the_library_then_cast() {
        let mut rng = crate::phantom::rng::Rng::new(4);
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            -1e-300,
            f64::MIN_POSITIVE,
            9.2e18,
            -9.2e18,
            9.3e18,
            -9.3e18,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            i64::MAX as f64,
            i64::MIN as f64,
        ];
        for _ in 0..100_000 {
            let x = rng.range(-1e3, 1e3);
            xs.extend([x, x.round(), x * 1e-6, x * 1e15]);
        }
        for x in xs {
            assert_eq!(floor_i64(x), x.floor() as i64, "{x:e}");
            assert_eq!(ceil_i64(x), x.ceil() as i64, "{x:e}");
        }
    }

    #[test]
    fn round_is_f64_round_bit_for_bit() {
        let mut special = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            -2.5,
            0.49999999999999994,
            -0.49999999999999994,
            4_503_599_627_370_495.5,
            -4_503_599_627_370_495.5,
            4_503_599_627_370_496.0,
            9.1e18,
            -9.3e18,
            1e300,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        // A deterministic spread of magnitudes and fractions.
        let mut rng = crate::phantom::rng::Rng::new(7);
        for _ in 0..200_000 {
            let s = rng.next_u64();
            let scale = 10f64.powi((s % 40) as i32 - 20);
            special.push(((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * scale);
            special.push(f64::from_bits(s));
        }
        for x in special {
            assert_eq!(round(x).to_bits(), x.round().to_bits(), "{x:e}");
        }
    }
}
