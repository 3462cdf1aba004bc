//! The point-to-plane ICP step shared by eq. (2) and eq. (3): for pairs `(p, q, n)` the residual
//! is `(p − q) · n`; the rigid update is linearised about a centre `c`
//! (`R(p) ≈ p + w × (p − c) + t`) and found by 6-DoF weighted least squares (nalgebra), optionally
//! with a 7th unknown `b`, a constant offset of the target surface along its normal (models the
//! CBCT segmentation threshold that inflates or shrinks a whole tooth; beyond the paper).
//!
//! Beyond the paper, pairs can be weighted robustly (Huber or Tukey with a MAD scale) and
//! rejected (disagreeing normals, outlier distance).

use crate::Rigid;
use glam::DVec3;
use nalgebra::{SMatrix, SVector};

/// One correspondence: source point `p` (current position), target point `q`, plane normal `n`
/// (unit), and the other surface's normal `n_other` for the normal-agreement test (zero = none).
#[derive(Clone, Copy, Debug)]
pub struct Pair {
    /// Source point, current position.
    pub p: DVec3,
    /// Target point.
    pub q: DVec3,
    /// Unit normal of the plane the residual is measured along.
    pub n: DVec3,
    /// Unit normal of the other surface at its point (zero when unknown).
    pub n_other: DVec3,
}

impl Pair {
    /// The signed point-to-plane residual `(p − q) · n`.
    #[inline]
    pub fn residual(&self) -> f64 {
        (self.p - self.q).dot(self.n)
    }
}

/// Robust kernel for the point-to-plane residuals.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum RobustKernel {
    /// Plain least squares (the paper).
    None,
    /// Huber: weight 1 inside `k·σ`, `k·σ/|r|` outside.
    Huber,
    /// Tukey biweight: `(1 − (r/(k·σ))²)²` inside `k·σ`, 0 outside.
    Tukey,
}

/// How pairs are weighted and rejected.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WeightOptions {
    /// Robust kernel on residuals (scale σ = 1.4826·MAD of the residuals).
    pub kernel: RobustKernel,
    /// Kernel width in units of σ.
    pub kernel_k: f64,
    /// Lower bound of σ in mm (a perfect fit must not make every pair an outlier).
    pub min_scale_mm: f64,
    /// Reject pairs whose two normals make an angle above this (degrees); `None` keeps all.
    pub max_normal_angle_deg: Option<f64>,
    /// Reject pairs farther apart than median + this many σ_d (MAD of distances); `None` keeps all.
    pub distance_mads: Option<f64>,
    /// Reject pairs farther apart than this (mm); `f64::INFINITY` keeps all.
    pub max_distance_mm: f64,
}

impl WeightOptions {
    /// The paper: every pair, unit weight.
    pub const PLAIN: WeightOptions = WeightOptions {
        kernel: RobustKernel::None,
        kernel_k: 1.0,
        min_scale_mm: 0.0,
        max_normal_angle_deg: None,
        distance_mads: None,
        max_distance_mm: f64::INFINITY,
    };
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    // Selection instead of a full sort: the same order statistics, bit for bit.
    let m = v.len() / 2;
    let odd = v.len() % 2 == 1;
    let (lo, &mut hi, _) = v.select_nth_unstable_by(m, |a, b| a.total_cmp(b));
    if odd {
        hi
    } else {
        let below = lo.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        0.5 * (below + hi)
    }
}

/// Weights of the pairs (0 = rejected), given the residuals' current offset `b`.
pub fn weights(pairs: &[Pair], offset: f64, o: &WeightOptions) -> Vec<f64> {
    let cos_max = o.max_normal_angle_deg.map(|a| a.to_radians().cos());
    let mut w: Vec<f64> = pairs
        .iter()
        .map(|pr| {
            let d = (pr.p - pr.q).length();
            let normal_ok = match cos_max {
                Some(c) if pr.n_other != DVec3::ZERO => pr.n.dot(pr.n_other) >= c,
                _ => true,
            };
            if normal_ok && d <= o.max_distance_mm {
                1.0
            } else {
                0.0
            }
        })
        .collect();
    if let Some(k) = o.distance_mads {
        let mut d: Vec<f64> = pairs
            .iter()
            .zip(&w)
            .filter(|(_, w)| **w > 0.0)
            .map(|(p, _)| (p.p - p.q).length())
            .collect();
        let med = median(&mut d);
        let mut dev: Vec<f64> = d.iter().map(|x| (x - med).abs()).collect();
        let s = (1.4826 * median(&mut dev)).max(o.min_scale_mm);
        let lim = med + k * s;
        for (wi, p) in w.iter_mut().zip(pairs) {
            if (p.p - p.q).length() > lim {
                *wi = 0.0;
            }
        }
    }
    if o.kernel != RobustKernel::None {
        let mut r: Vec<f64> = pairs
            .iter()
            .zip(&w)
            .filter(|(_, w)| **w > 0.0)
            .map(|(p, _)| p.residual() - offset)
            .collect();
        let med = median(&mut r);
        let mut dev: Vec<f64> = r.iter().map(|x| (x - med).abs()).collect();
        let s = (1.4826 * median(&mut dev)).max(o.min_scale_mm);
        let c = o.kernel_k * s;
        for (wi, p) in w.iter_mut().zip(pairs) {
            if *wi == 0.0 {
                continue;
            }
            let a = (p.residual() - offset).abs();
            *wi = match o.kernel {
                RobustKernel::Huber => {
                    if a <= c {
                        1.0
                    } else {
                        c / a
                    }
                }
                RobustKernel::Tukey => {
                    if a < c {
                        let u = a / c;
                        (1.0 - u * u).powi(2)
                    } else {
                        0.0
                    }
                }
                RobustKernel::None => 1.0,
            };
        }
    }
    w
}

/// Normal equations `A x = −g` of the linearised point-to-plane problem in
/// `x = [w (rotation), t (translation), b (offset)]`.
#[derive(Clone, Debug)]
pub struct Normal7 {
    /// `Σ w a aᵀ`.
    pub a: SMatrix<f64, 7, 7>,
    /// `Σ w a r`.
    pub g: SVector<f64, 7>,
    /// `Σ w r²` (at x = 0).
    pub rr: f64,
    /// `Σ w`.
    pub wsum: f64,
}

impl Normal7 {
    /// Empty system.
    pub fn new() -> Self {
        Normal7 {
            a: SMatrix::zeros(),
            g: SVector::zeros(),
            rr: 0.0,
            wsum: 0.0,
        }
    }

    /// Adds the pairs with their weights, linearised about `center`, for current offset `offset`.
    pub fn add_pairs(&mut self, pairs: &[Pair], w: &[f64], center: DVec3, offset: f64) {
        // Only the upper triangle is summed (`a_i a_j = a_j a_i` bit for bit) and mirrored at
        // the end; every entry gets the same terms in the same order as `A += w a aᵀ` would
        // give it.
        let mut upper = [[0.0f64; 7]; 7];
        for (i, row) in upper.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate().skip(i) {
                *x = self.a[(i, j)];
            }
        }
        for (p, &wk) in pairs.iter().zip(w) {
            if wk <= 0.0 {
                continue;
            }
            let c = (p.p - center).cross(p.n);
            let a = [c.x, c.y, c.z, p.n.x, p.n.y, p.n.z, -1.0];
            let r = p.residual() - offset;
            for (i, row) in upper.iter_mut().enumerate() {
                for (j, x) in row.iter_mut().enumerate().skip(i) {
                    *x += a[i] * a[j] * wk;
                }
            }
            let wr = wk * r;
            for (g, ai) in self.g.iter_mut().zip(a) {
                *g += ai * wr;
            }
            self.rr += wk * r * r;
            self.wsum += wk;
        }
        for (i, row) in upper.iter().enumerate() {
            for (j, &x) in row.iter().enumerate().skip(i) {
                self.a[(i, j)] = x;
                self.a[(j, i)] = x;
            }
        }
    }

    /// Solves for the 6-DoF step (and the offset step when `with_offset`); `None` when singular.
    pub fn solve(&self, with_offset: bool) -> Option<(DVec3, DVec3, f64)> {
        if with_offset {
            let mut a = self.a;
            let d = damping(&a);
            for i in 0..7 {
                a[(i, i)] += d;
            }
            let x = a.cholesky()?.solve(&(-self.g));
            Some((
                DVec3::new(x[0], x[1], x[2]),
                DVec3::new(x[3], x[4], x[5]),
                x[6],
            ))
        } else {
            let mut a: SMatrix<f64, 6, 6> = self.a.fixed_view::<6, 6>(0, 0).into_owned();
            let d = damping(&a);
            for i in 0..6 {
                a[(i, i)] += d;
            }
            let g: SVector<f64, 6> = self.g.fixed_rows::<6>(0).into_owned();
            let x = a.cholesky()?.solve(&(-g));
            Some((
                DVec3::new(x[0], x[1], x[2]),
                DVec3::new(x[3], x[4], x[5]),
                0.0,
            ))
        }
    }
}

impl Default for Normal7 {
    fn default() -> Self {
        Self::new()
    }
}

/// A tiny Levenberg term relative to the system's scale (keeps degenerate geometry solvable).
fn damping<const N: usize>(a: &SMatrix<f64, N, N>) -> f64 {
    let tr: f64 = (0..N).map(|i| a[(i, i)]).sum();
    1e-9 * tr / N as f64
}

/// The rigid update `p ↦ R(w)(p − c) + c + t` of a step about centre `c`.
pub fn step_about(w: DVec3, t: DVec3, c: DVec3) -> Rigid {
    let r = Rigid::from_twist(w, DVec3::ZERO);
    Rigid::new(r.rot, c - r.rot * c + t)
}

/// Convergence thresholds of an ICP loop.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Convergence {
    /// Iteration cap.
    pub max_iterations: usize,
    /// Stop when the step moves no point of the source's extent more than this (mm).
    pub step_mm: f64,
    /// Stop when the relative change of the weighted RMS residual is below this.
    pub relative_rms: f64,
}

impl Convergence {
    /// True when a step `(w, t)` about the centre is small for a source of radius `radius`.
    pub fn step_small(&self, w: DVec3, t: DVec3, radius: f64) -> bool {
        t.length() + w.length() * radius <= self.step_mm
    }

    /// True when the RMS changed by less than the relative threshold.
    pub fn rms_stalled(&self, prev: f64, now: f64) -> bool {
        prev.is_finite() && (prev - now).abs() <= self.relative_rms * prev.max(1e-12)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The normal equations summed by upper triangle are bit for bit those of `A += w a aᵀ`,
    /// `g += a (w r)`, on pairs with weights of every size (and zero ones skipped), added onto a
    /// system that already holds terms.
    #[test]
    fn upper_triangle_sums_are_the_full_products() {
        let mut rng = crate::phantom::rng::Rng::new(12345);
        let mut unit = move || rng.range(-0.5, 0.5);
        let pairs: Vec<Pair> = (0..500)
            .map(|_| Pair {
                p: DVec3::new(unit(), unit(), unit()) * 40.0,
                q: DVec3::new(unit(), unit(), unit()) * 40.0,
                n: DVec3::new(unit(), unit(), unit()).normalize(),
                n_other: DVec3::ZERO,
            })
            .collect();
        let w: Vec<f64> = (0..500)
            .map(|k| {
                if k % 7 == 0 {
                    0.0
                } else {
                    (unit() + 0.5) * 10f64.powi(k % 5 - 2)
                }
            })
            .collect();
        let (center, offset) = (DVec3::new(1.5, -2.0, 3.0), 0.125);
        let mut fast = Normal7::new();
        fast.add_pairs(&pairs[..100], &w[..100], center, offset);
        fast.add_pairs(&pairs[100..], &w[100..], center, offset);
        let mut full = Normal7::new();
        for (p, &wk) in pairs.iter().zip(&w) {
            if wk <= 0.0 {
                continue;
            }
            let c = (p.p - center).cross(p.n);
            let a = SVector::<f64, 7>::from([c.x, c.y, c.z, p.n.x, p.n.y, p.n.z, -1.0]);
            let r = p.residual() - offset;
            full.a += a * a.transpose() * wk;
            full.g += a * (wk * r);
            full.rr += wk * r * r;
            full.wsum += wk;
        }
        assert_eq!(fast.a, full.a);
        assert_eq!(fast.g, full.g);
        assert_eq!((fast.rr, fast.wsum), (full.rr, full.wsum));
    }

    #[test]
    fn one_step_recovers_a_small_translation_on_three_planes() {
        let mut pairs = Vec::new();
        let shift = DVec3::new(0.1, -0.05, 0.02);
        for n in [
            DVec3::X,
            DVec3::Y,
            DVec3::Z,
            -DVec3::X,
            -DVec3::Y,
            -DVec3::Z,
        ] {
            for k in 0..5 {
                let q = n * 5.0 + n.any_orthonormal_vector() * k as f64;
                pairs.push(Pair {
                    p: q + shift,
                    q,
                    n,
                    n_other: n,
                });
            }
        }
        let w = weights(&pairs, 0.0, &WeightOptions::PLAIN);
        let mut ne = Normal7::new();
        ne.add_pairs(&pairs, &w, DVec3::ZERO, 0.0);
        let (rw, t, _) = ne.solve(false).unwrap();
        assert!(rw.length() < 1e-9);
        assert!((t + shift).length() < 1e-9, "{t:?}");
    }

    #[test]
    fn tukey_zeroes_a_gross_outlier() {
        let mut pairs: Vec<Pair> = (0..20)
            .map(|k| Pair {
                p: DVec3::new(k as f64, 0.0, 0.01 * (k % 3) as f64),
                q: DVec3::new(k as f64, 0.0, 0.0),
                n: DVec3::Z,
                n_other: DVec3::Z,
            })
            .collect();
        pairs.push(Pair {
            p: DVec3::new(0.0, 0.0, 3.0),
            q: DVec3::ZERO,
            n: DVec3::Z,
            n_other: -DVec3::Z,
        });
        let o = WeightOptions {
            kernel: RobustKernel::Tukey,
            kernel_k: 4.685,
            min_scale_mm: 0.005,
            max_normal_angle_deg: None,
            distance_mads: None,
            max_distance_mm: f64::INFINITY,
        };
        let w = weights(&pairs, 0.0, &o);
        assert_eq!(w[20], 0.0);
        assert!(w[..20].iter().all(|&x| x > 0.5));
        let o2 = WeightOptions {
            max_normal_angle_deg: Some(60.0),
            ..WeightOptions::PLAIN
        };
        let w2 = weights(&pairs, 0.0, &o2);
        assert_eq!(w2[20], 0.0);
        assert_eq!(w2[0], 1.0);
    }
}
