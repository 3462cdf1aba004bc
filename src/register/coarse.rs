//! Coarse registration (CR), paper eq. (2): one rigid transform for all teeth, CBCT as source and
//! IOS as target; for each IOS point `y ∈ Y_i` the closest CBCT point `Corr(y)` of the same tooth,
//! residual `(R(Corr(y)) − y) · n_Corr(y)` with the CBCT normal.

use super::correspondence::NearestMemo;
use super::icp::{Normal7, Pair, step_about, weights};
use super::{Correspondence, Level, Pass, StageOptions, StageStats, ToothData, passes};
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
    run_passes(teeth, start(init), o, &passes(o))
}

/// A stage's start: no passes run, the transform `init` and no surface offset.
fn start(init: Rigid) -> CoarseResult {
    CoarseResult {
        transform: init,
        offset: 0.0,
        stats: StageStats::default(),
    }
}

/// Runs eq. (2) through `passes` from where `from` left it (its transform and surface offset;
/// its iterations counted on, its convergence kept unless a judged pass is among `passes`).
fn run_passes(
    teeth: &BTreeMap<u8, ToothData>,
    from: CoarseResult,
    o: &StageOptions,
    passes: &[Pass],
) -> CoarseResult {
    let CoarseResult {
        transform: mut t,
        mut offset,
        mut stats,
    } = from;
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
    let memos: Vec<Mutex<Vec<NearestMemo>>> =
        teeth.keys().map(|_| Mutex::new(Vec::new())).collect();
    for pass in passes {
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

/// Iterations of the first pass a restart is probed with before the restarts are compared. The
/// restarts lie 30° apart about each axis, so one starts within 15° of the right minimum and
/// is near it within a few iterations, while a restart in a wrong minimum spends the pass's
/// whole cap (40) there. Over the 9 short arches of the CLI sweeps that restart, probing 12
/// iterations instead of 40 picks a winner in the same minimum on every jaw (every tooth's TRE
/// the same to the micrometre) and halves the probes' time.
const PROBE_ITERATIONS: usize = 12;

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
/// best fit wins. A good first fit is returned unchanged. The restarts are probed side by side
/// with at most [`PROBE_ITERATIONS`] of the stage's first pass (the warm-up sample's, by
/// default), compared in their order, and only the best runs the rest of the stage (run
/// through every pass, the 33 restarts of a 4-tooth arch hold its registration 10–50× as long
/// as a full jaw's).
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
    let all = passes(o);
    let (first_pass, rest) = all.split_at(1.min(all.len()));
    let probe: Vec<Pass> = first_pass
        .iter()
        .map(|p| Pass {
            cap: p.cap.min(PROBE_ITERATIONS),
            ..*p
        })
        .collect();
    let probe = &probe[..];
    let eig = crate::geom::scatter(&cs, c).symmetric_eigen();
    let turns: Vec<Rigid> = (0..3)
        .filter_map(|a| {
            let v = eig.eigenvectors.column(a);
            let axis = DVec3::new(v[0], v[1], v[2]).normalize_or_zero();
            (axis != DVec3::ZERO).then_some(axis)
        })
        .flat_map(|axis| {
            (1..12)
                .map(move |k| Rigid::from_axis_angle_about(axis, (30.0 * k as f64).to_radians(), c))
        })
        .collect();
    // The restarts are independent: probed side by side, compared in their order.
    let probed = crate::par::map_ordered(&turns, |turn| {
        let r = run_passes(teeth, start(turn.compose(&init)), o, probe);
        let cost = median_fit(teeth, &r.transform);
        (r, cost)
    });
    // The best so far, and whether it has run every pass.
    let mut best = (first, true);
    for (r, cost) in probed {
        if cost < best_cost {
            best_cost = cost;
            best = (r, rest.is_empty());
        }
    }
    match best {
        (r, true) => r,
        (r, false) => run_passes(teeth, r, o, rest),
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::fixture;
    use super::super::{RegisterOptions, prepare};
    use super::*;

    /// Every restart run through every pass, the best fit kept: the reference the probed
    /// restarts are checked against.
    fn every_restart_run_through(
        teeth: &BTreeMap<u8, ToothData>,
        init: Rigid,
        o: &StageOptions,
    ) -> CoarseResult {
        let mut best = coarse(teeth, init, o);
        let mut best_cost = median_fit(teeth, &best.transform);
        let cs: Vec<DVec3> = teeth.values().map(|d| d.ios_centroid).collect();
        let c = crate::geom::centroid(&cs).unwrap();
        let eig = crate::geom::scatter(&cs, c).symmetric_eigen();
        for a in 0..3 {
            let v = eig.eigenvectors.column(a);
            let axis = DVec3::new(v[0], v[1], v[2]).normalize();
            for k in 1..12 {
                let turn = Rigid::from_axis_angle_about(axis, (30.0 * k as f64).to_radians(), c);
                let r = coarse(teeth, turn.compose(&init), o);
                let cost = median_fit(teeth, &r.transform);
                if cost < best_cost {
                    (best, best_cost) = (r, cost);
                }
            }
        }
        best
    }

    /// A short posterior arch started 180° off about its own line (eq. (2) alone stays in a
    /// wrong minimum): the restarts probed on the first pass, only the best run on, end in the
    /// minimum every restart run through every pass ends in (within the stage's convergence
    /// step: of several restarts converging there, the ones compared after the first pass and
    /// after every pass may differ), bit for bit on one thread and on
    /// several.
    #[test]
    fn restarts_probed_on_the_first_pass_end_where_all_run_through_end() {
        let fx = fixture(0.0, 0.0);
        let opts = RegisterOptions::default();
        let teeth: BTreeMap<u8, ToothData> = [13u8, 14, 15, 16]
            .into_iter()
            .map(|f| (f, prepare(f, &fx.ios[&f], &fx.cbct[&f], &opts).unwrap()))
            .collect();
        let (a, b) = (teeth[&13].ios_centroid, teeth[&16].ios_centroid);
        let turn =
            Rigid::from_axis_angle_about((b - a).normalize(), 180f64.to_radians(), 0.5 * (a + b));
        let init = turn.compose(&fx.truth[&14].0);
        let stage = opts.coarse.unwrap();
        let bad = opts.coarse_restart_fit_mm.unwrap();
        assert!(median_fit(&teeth, &coarse(&teeth, init, &stage).transform) > bad);
        let want = every_restart_run_through(&teeth, init, &stage);
        let apart = |r: &CoarseResult| {
            fx.cbct
                .values()
                .flat_map(|m| m.positions.iter())
                .map(|&p| (r.transform.apply(p) - want.transform.apply(p)).length())
                .fold(0.0, f64::max)
        };
        let one =
            crate::par::with_max_threads(1, || coarse_with_restarts(&teeth, init, &stage, bad));
        let two =
            crate::par::with_max_threads(2, || coarse_with_restarts(&teeth, init, &stage, bad));
        let step = stage.convergence.step_mm;
        assert!(
            apart(&one) < step,
            "{} mm from every restart run through",
            apart(&one)
        );
        assert_eq!(one.transform, two.transform);
        assert_eq!(one.offset, two.offset);
        // The right minimum: every tooth within 0.05 mm of its truth.
        for (f, (truth, surface)) in &fx.truth {
            if teeth.contains_key(f) {
                let d = surface
                    .positions
                    .iter()
                    .map(|&p| (one.transform.apply(p) - truth.apply(p)).length())
                    .fold(0.0, f64::max);
                assert!(d < 0.05, "tooth {f}: {d} mm off");
            }
        }
    }
}
