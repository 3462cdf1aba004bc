//! Coarse registration (CR), paper eq. (2): one rigid transform for all teeth, CBCT as source and
//! IOS as target; for each IOS point `y ∈ Y_i` the closest CBCT point `Corr(y)` of the same tooth,
//! residual `(R(Corr(y)) − y) · n_Corr(y)` with the CBCT normal.

use super::correspondence::NearestMemo;
use super::icp::{Normal7, Pair, step_about, weights};
use super::{Correspondence, Level, StageOptions, StageStats, ToothData, passes};
use crate::Rigid;
use glam::DVec3;
use std::collections::BTreeMap;
use std::sync::Mutex;

/// Result of the coarse stage.
pub(crate) struct CoarseResult {
    /// CBCT → IOS for every tooth.
    pub transform: Rigid,
    /// Estimated CBCT surface offset along its normal (mm; 0 unless estimated).
    pub offset: f64,
    /// Iterations and convergence.
    pub stats: StageStats,
}

/// Builds the eq. (2) pairs in the IOS frame for the current `t` (CBCT → IOS), tooth by tooth
/// in FDI order (the teeth's correspondences on several threads, concatenated in that order).
/// `memos` holds per tooth, in FDI order, what its points remember of their last nearest-vertex
/// search ([`NearestMemo`]: only searches are saved, the pairs are the same).
fn pairs(
    teeth: &BTreeMap<u8, ToothData>,
    t: &Rigid,
    level: Level,
    o: &StageOptions,
    memos: &[Mutex<Vec<NearestMemo>>],
) -> Vec<Pair> {
    let inv = t.inverse();
    let on_faces = o.correspondence == Correspondence::ClosestPoint;
    let ds: Vec<(&ToothData, &Mutex<Vec<NearestMemo>>)> = teeth.values().zip(memos).collect();
    let per_tooth = crate::par::map_ordered(&ds, |(d, memo)| {
        let mut memo = memo.lock().unwrap_or_else(|e| e.into_inner());
        let idx = d.ios_indices(level);
        memo.resize(idx.len(), NearestMemo::default());
        idx.iter()
            .zip(memo.iter_mut())
            .map(|(&k, memo)| {
                let y = d.ios_points[k];
                let sp = d.cbct.pair_remembered(inv.apply(y), on_faces, memo);
                Pair {
                    p: t.apply(sp.point),
                    q: y,
                    n: t.apply_vector(sp.normal),
                    n_other: d.ios_normals[k],
                }
            })
            .collect::<Vec<_>>()
    });
    per_tooth.concat()
}

/// Runs eq. (2) from the initial transform `init` (CBCT → IOS).
pub(crate) fn coarse(
    teeth: &BTreeMap<u8, ToothData>,
    init: Rigid,
    o: &StageOptions,
) -> CoarseResult {
    let mut t = init;
    let mut offset = 0.0;
    let center = {
        let (s, n) = teeth.values().fold((DVec3::ZERO, 0usize), |(s, n), d| {
            (
                s + d.ios_centroid * d.ios_points.len() as f64,
                n + d.ios_points.len(),
            )
        });
        s / n.max(1) as f64
    };
    let radius = teeth
        .values()
        .flat_map(|d| d.ios_points.iter())
        .fold(0.0f64, |r, p| r.max((*p - center).length()));
    let mut stats = StageStats::default();
    let memos: Vec<Mutex<Vec<NearestMemo>>> =
        teeth.keys().map(|_| Mutex::new(Vec::new())).collect();
    for pass in passes(o) {
        let mut prev_rms = f64::INFINITY;
        let mut converged = false;
        for _ in 0..pass.cap {
            let pr = pairs(teeth, &t, pass.level, o, &memos);
            let w = weights(&pr, offset, &o.weights);
            let mut ne = Normal7::new();
            ne.add_pairs(&pr, &w, center, offset);
            stats.iterations += 1;
            let Some((rw, rt, db)) = ne.solve(o.estimate_offset) else {
                break;
            };
            t = step_about(rw, rt, center).compose(&t).orthonormalized();
            offset += db;
            let rms = (ne.rr / ne.wsum.max(1e-300)).sqrt();
            stats.rms_mm = rms;
            stats.inlier_fraction = ne.wsum / pr.len().max(1) as f64;
            if o.convergence.step_small(rw, rt, radius) || o.convergence.rms_stalled(prev_rms, rms)
            {
                converged = true;
                break;
            }
            prev_rms = rms;
        }
        // Convergence is judged on the pass that ran to its threshold on the subsample (the
        // full-resolution pass after it is a fixed refinement).
        if pass.judged {
            stats.converged = converged;
        }
    }
    CoarseResult {
        transform: t,
        offset,
        stats,
    }
}

/// Median distance (mm) from the warm-up sample of IOS points, mapped by `t⁻¹`, to the closest
/// CBCT vertex of their tooth: how well a jaw-wide transform fits.
fn median_fit(teeth: &BTreeMap<u8, ToothData>, t: &Rigid) -> f64 {
    let inv = t.inverse();
    let mut d: Vec<f64> = teeth
        .values()
        .flat_map(|d| {
            d.ios_indices(Level::Warm)
                .iter()
                .map(|&k| d.cbct.closest_vertex(inv.apply(d.ios_points[k])).distance)
        })
        .collect();
    if d.is_empty() {
        return f64::INFINITY;
    }
    let m = d.len() / 2;
    *d.select_nth_unstable_by(m, |a, b| a.total_cmp(b)).1
}

/// Eq. (2) with restarts (beyond the paper): when the converged jaw-wide fit is poor (median
/// point distance above `bad_fit_mm`, e.g. a short arch whose nearly collinear centroids leave
/// the rotation about the arch line undetermined), the initial transform is rotated about each
/// principal axis of the IOS tooth centroids by multiples of 30° and eq. (2) rerun from each; the
/// best fit wins. A good first fit is returned unchanged.
pub(crate) fn coarse_with_restarts(
    teeth: &BTreeMap<u8, ToothData>,
    init: Rigid,
    o: &StageOptions,
    bad_fit_mm: f64,
) -> CoarseResult {
    let first = coarse(teeth, init, o);
    let mut best_cost = median_fit(teeth, &first.transform);
    if best_cost <= bad_fit_mm || teeth.is_empty() {
        return first;
    }
    let cs: Vec<DVec3> = teeth.values().map(|d| d.ios_centroid).collect();
    let Some(c) = crate::geom::centroid(&cs) else {
        return first;
    };
    let eig = crate::geom::scatter(&cs, c).symmetric_eigen();
    let mut best = first;
    for a in 0..3 {
        let v = eig.eigenvectors.column(a);
        let axis = DVec3::new(v[0], v[1], v[2]).normalize_or_zero();
        if axis == DVec3::ZERO {
            continue;
        }
        for k in 1..12 {
            let turn = Rigid::from_axis_angle_about(axis, (30.0 * k as f64).to_radians(), c);
            let r = coarse(teeth, turn.compose(&init), o);
            let cost = median_fit(teeth, &r.transform);
            if cost < best_cost {
                best_cost = cost;
                best = r;
            }
        }
    }
    best
}
