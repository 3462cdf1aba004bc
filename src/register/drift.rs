//! Smooth-drift fine registration (beyond the paper; replaces eq. (3) in the default preset).
//!
//! IOS stitching drift accumulates smoothly along the arch and the teeth are rigid, whereas
//! fitting each crown alone to its (distorted) CBCT crown rotates the tooth and throws the root
//! apex off. So all per-tooth corrections are solved *jointly*: the eq. (3) point-to-plane data
//! term of every tooth (IOS source, CBCT target), each normalised to a mean, plus a penalty on the
//! difference of neighbouring teeth's corrections, measured as the relative motion at the point
//! between them (`smooth_mm` weights the translation part, `smooth_rotation` the rotation part
//! scaled by a lever of `lever_mm`), and a penalty on each tooth's rotation away from the coarse
//! solution (`rotation_prior`). `smooth → ∞` gives one rigid transform (eq. 2); `smooth = 0`
//! gives independent per-tooth fits.

use super::correspondence::NearestMemo;
use super::fine::group_pairs;
use super::icp::{Normal7, step_about, weights};
use super::{DriftOptions, StageOptions, StageStats, ToothData, passes};
use crate::Rigid;
use glam::DVec3;
use nalgebra::{DMatrix, DVector, SMatrix};
use std::collections::BTreeMap;

/// Cross-product matrix `[v]×` (so `[v]× w = v × w`).
fn skew(v: DVec3) -> SMatrix<f64, 3, 3> {
    SMatrix::<f64, 3, 3>::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Joint smooth-drift registration. `order`: registered teeth in arch order; `coarse`: CBCT →
/// IOS after CR. Returns per tooth the IOS → CBCT mapping and per-tooth stats.
pub(crate) fn fine_smooth(
    teeth: &BTreeMap<u8, ToothData>,
    order: &[u8],
    coarse: &Rigid,
    offset0: f64,
    o: &StageOptions,
    d: &DriftOptions,
) -> (BTreeMap<u8, Rigid>, BTreeMap<u8, StageStats>) {
    let n = order.len();
    let inv = coarse.inverse();
    let cen: Vec<DVec3> = order
        .iter()
        .map(|f| inv.apply(teeth[f].ios_centroid))
        .collect();
    let center = cen.iter().fold(DVec3::ZERO, |a, p| a + *p) / n.max(1) as f64;
    // Accumulated twists about `center` (CBCT frame), one per tooth, and per-tooth offsets.
    let mut x = vec![[0.0f64; 6]; n];
    let mut offs = vec![offset0; n];
    let to_rigid = |xi: &[f64; 6]| {
        step_about(
            DVec3::new(xi[0], xi[1], xi[2]),
            DVec3::new(xi[3], xi[4], xi[5]),
            center,
        )
    };
    let mut stats: BTreeMap<u8, StageStats> =
        order.iter().map(|&f| (f, StageStats::default())).collect();
    let mut ios_to_cbct: BTreeMap<u8, Rigid> = order.iter().map(|&f| (f, inv)).collect();
    let pair_m = smoothness_blocks(&cen, center, d);
    let radius = order
        .iter()
        .map(|f| teeth[f].ios_radius)
        .fold(0.0, f64::max);
    let mut iterations = 0usize;
    let mut converged = false;
    // Each tooth's nearest-vertex memos, touched by one thread at a time.
    let memos: Vec<(u8, std::sync::Mutex<Vec<NearestMemo>>)> = order
        .iter()
        .map(|&f| (f, std::sync::Mutex::new(Vec::new())))
        .collect();
    for pass in passes(o) {
        let mut phase_converged = false;
        for _ in 0..pass.cap {
            for (k, f) in order.iter().enumerate() {
                ios_to_cbct.insert(*f, to_rigid(&x[k]).compose(&inv));
            }
            let dim = 7 * n;
            let mut a = DMatrix::<f64>::zeros(dim, dim);
            let mut g = DVector::<f64>::zeros(dim);
            // The teeth's correspondences on several threads; everything summed in arch order.
            let all_pairs = crate::par::map_ordered(&memos, |(f, memo)| {
                let mut memo = memo.lock().unwrap_or_else(|e| e.into_inner());
                group_pairs(
                    teeth,
                    std::slice::from_ref(f),
                    &ios_to_cbct,
                    pass.level,
                    o,
                    o.source_normals,
                    std::slice::from_mut(&mut *memo),
                )
            });
            for ((k, f), pr) in order.iter().enumerate().zip(&all_pairs) {
                let pr = pr.as_slice();
                let w = weights(pr, -offs[k], &o.weights);
                let mut ne = Normal7::new();
                // Linearised about the current pose: the step is applied after the current
                // correction, and added to the accumulated twist (small-angle composition).
                ne.add_pairs(pr, &w, center, -offs[k]);
                let s = 1.0 / ne.wsum.max(1e-12);
                let st = stats.get_mut(f).expect("tooth in order");
                st.rms_mm = (ne.rr * s).sqrt();
                st.inlier_fraction = ne.wsum / pr.len().max(1) as f64;
                add_tooth_terms(&mut a, &mut g, k, (&ne, s), &x[k], o.estimate_offset, d);
            }
            add_smoothness(&mut a, &mut g, &pair_m, &x);
            let tr: f64 = (0..dim).map(|i| a[(i, i)]).sum::<f64>() / dim as f64;
            for i in 0..dim {
                a[(i, i)] += 1e-9 * tr;
            }
            iterations += 1;
            let Some(ch) = a.cholesky() else {
                break;
            };
            let step = ch.solve(&(-g));
            let mut max_move = 0.0f64;
            for k in 0..n {
                let w = DVec3::new(step[7 * k], step[7 * k + 1], step[7 * k + 2]);
                let t = DVec3::new(step[7 * k + 3], step[7 * k + 4], step[7 * k + 5]);
                let lever = (cen[k] - center).length() + radius;
                max_move = max_move.max(t.length() + w.length() * lever);
                for (i, xi) in x[k].iter_mut().enumerate() {
                    *xi += step[7 * k + i];
                }
                offs[k] -= step[7 * k + 6];
            }
            if max_move <= o.convergence.step_mm {
                phase_converged = true;
                break;
            }
        }
        // The full-resolution pass after a subsampled one is a fixed refinement.
        if pass.judged {
            converged = phase_converged;
        }
    }
    for (k, f) in order.iter().enumerate() {
        ios_to_cbct.insert(*f, to_rigid(&x[k]).compose(&inv).orthonormalized());
        let st = stats.get_mut(f).expect("tooth in order");
        st.iterations = iterations;
        st.converged = converged;
    }
    (ios_to_cbct, stats)
}

/// Smoothness blocks M (6×6) per neighbouring pair of teeth (centroids `cen`, arch order):
/// `M e = [L·Δw ; Δw × (m − c) + Δt]` scaled, `m` the point between the two teeth, `c` the
/// twists' centre.
fn smoothness_blocks(cen: &[DVec3], center: DVec3, d: &DriftOptions) -> Vec<SMatrix<f64, 6, 6>> {
    (0..cen.len().saturating_sub(1))
        .map(|k| {
            let m = 0.5 * (cen[k] + cen[k + 1]) - center;
            let mut mm = SMatrix::<f64, 6, 6>::zeros();
            let sr = d.smooth_rotation.sqrt() * d.lever_mm;
            let st = d.smooth_mm.sqrt();
            for i in 0..3 {
                mm[(i, i)] = sr;
                mm[(3 + i, 3 + i)] = st;
            }
            let s = -skew(m) * st;
            mm.fixed_view_mut::<3, 3>(3, 0).copy_from(&s);
            mm
        })
        .collect()
}

/// Adds tooth `k`'s data term (its normal equations `ne` scaled by `s`) to the joint system,
/// its offset held at zero unless `estimate_offset`, and the rotation prior
/// `κ L² ‖w_k‖²` on its accumulated twist `xk`.
fn add_tooth_terms(
    a: &mut DMatrix<f64>,
    g: &mut DVector<f64>,
    k: usize,
    (ne, s): (&Normal7, f64),
    xk: &[f64; 6],
    estimate_offset: bool,
    d: &DriftOptions,
) {
    for i in 0..7 {
        g[7 * k + i] += ne.g[i] * s;
        for j in 0..7 {
            a[(7 * k + i, 7 * k + j)] += ne.a[(i, j)] * s;
        }
    }
    if !estimate_offset {
        for i in 0..7 {
            a[(7 * k + 6, 7 * k + i)] = 0.0;
            a[(7 * k + i, 7 * k + 6)] = 0.0;
        }
        a[(7 * k + 6, 7 * k + 6)] = 1.0;
        g[7 * k + 6] = 0.0;
    }
    let kr = d.rotation_prior * d.lever_mm * d.lever_mm;
    for i in 0..3 {
        a[(7 * k + i, 7 * k + i)] += kr;
        g[7 * k + i] += kr * xk[i];
    }
}

/// Adds the smoothness penalty `‖M_k (x_k − x_{k+1})‖²` of every neighbouring pair to the
/// joint system (twists `x`, blocks `pair_m`).
fn add_smoothness(
    a: &mut DMatrix<f64>,
    g: &mut DVector<f64>,
    pair_m: &[SMatrix<f64, 6, 6>],
    x: &[[f64; 6]],
) {
    for (k, mm) in pair_m.iter().enumerate() {
        let q = mm.transpose() * mm;
        let e: SMatrix<f64, 6, 1> = SMatrix::from_fn(|i, _| x[k][i] - x[k + 1][i]);
        let qe = q * e;
        for i in 0..6 {
            g[7 * k + i] += qe[i];
            g[7 * (k + 1) + i] -= qe[i];
            for j in 0..6 {
                a[(7 * k + i, 7 * k + j)] += q[(i, j)];
                a[(7 * (k + 1) + i, 7 * (k + 1) + j)] += q[(i, j)];
                a[(7 * k + i, 7 * (k + 1) + j)] -= q[(i, j)];
                a[(7 * (k + 1) + i, 7 * k + j)] -= q[(i, j)];
            }
        }
    }
}
