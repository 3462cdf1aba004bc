//! What the registration reports per tooth once its transform is found: the surface distance
//! (paper SD), RMSE and inlier share over the report points, and the plausibility guard's
//! findings (a fine correction beyond plausible drift, a crown slid along its tooth, a poor fit,
//! an ICP that did not converge) as warnings.

use super::{OutputFrame, RegisterOptions, StageStats, ToothData, ToothRegistration};
use crate::Rigid;
use glam::DVec3;
use std::collections::BTreeMap;

/// The jaw's stages a tooth's result is measured against.
pub(super) struct Stages<'a> {
    /// The coarse stage's jaw-wide CBCT → IOS transform.
    pub coarse: Rigid,
    /// The fine stage's statistics per tooth (`None` without a fine stage).
    pub fine: Option<&'a BTreeMap<u8, StageStats>>,
    /// The coarse stage's statistics (`None` without a coarse stage).
    pub coarse_stats: Option<StageStats>,
}

/// Tooth `f`'s registration from its IOS → CBCT transform: its measures and warnings (the
/// gate's `gate_warning` first); with [`super::GuardOptions::reject_implausible`] an implausible
/// fine correction is replaced by the coarse transform. Returns the sum of its report points'
/// distances and their number (for the jaw's mean SD) with the registration.
pub(super) fn tooth_result(
    f: u8,
    d: &ToothData,
    ios_to_cbct: Rigid,
    gate_warning: Option<&String>,
    stages: &Stages,
    opts: &RegisterOptions,
) -> (f64, usize, ToothRegistration) {
    let mut warnings: Vec<String> = gate_warning.cloned().into_iter().collect();
    let (m, fine_correction) = guarded(d, ios_to_cbct, stages, opts, &mut warnings);
    let dist: Vec<f64> = d
        .report
        .iter()
        .map(|&k| d.cbct.closest_point(m.apply(d.ios_points[k])).distance)
        .collect();
    let nd = dist.len().max(1) as f64;
    let sd = dist.iter().sum::<f64>() / nd;
    let rmse = (dist.iter().map(|x| x * x).sum::<f64>() / nd).sqrt();
    let inl = dist
        .iter()
        .filter(|&&x| x <= opts.inlier_distance_mm)
        .count() as f64
        / nd;
    let dist_sum = dist.iter().sum::<f64>();
    fit_warnings(sd, top_gap(d, &m), inl, opts, &mut warnings);
    let st = stages
        .fine
        .and_then(|s| s.get(&f).copied())
        .or(stages.coarse_stats)
        .unwrap_or(StageStats {
            converged: true,
            ..StageStats::default()
        });
    if !st.converged {
        warnings.push(format!(
            "ICP did not converge within {} iterations",
            st.iterations
        ));
    }
    let cbct_to_ios = m.inverse();
    let (c2o, i2o) = match opts.frame {
        OutputFrame::Cbct => (Rigid::IDENTITY, m),
        OutputFrame::Ios => (cbct_to_ios, Rigid::IDENTITY),
    };
    (
        dist_sum,
        dist.len(),
        ToothRegistration {
            fdi: f,
            cbct_to_ios,
            cbct_to_output: c2o,
            ios_to_output: i2o,
            sd_mm: sd,
            rmse_mm: rmse,
            inlier_fraction: inl,
            iterations: st.iterations,
            converged: st.converged,
            fine_correction_mm: fine_correction,
            warnings,
        },
    )
}

/// The fine transform `ios_to_cbct` under the plausibility guard: how far (mm) it moves the
/// CBCT tooth from the coarse transform, a warning when that is beyond the flag or the limit,
/// and beyond the limit (with `reject_implausible`) the coarse transform instead. Returns the
/// transform kept and its correction.
fn guarded(
    d: &ToothData,
    ios_to_cbct: Rigid,
    stages: &Stages,
    opts: &RegisterOptions,
    warnings: &mut Vec<String>,
) -> (Rigid, f64) {
    let coarse_t = stages.coarse;
    let fine_c2i = ios_to_cbct.inverse();
    let fine_correction = d
        .cbct
        .mesh()
        .positions
        .iter()
        .map(|p| fine_c2i.apply(*p).distance(coarse_t.apply(*p)))
        .fold(0.0, f64::max);
    if stages.fine.is_some() && fine_correction > opts.guard.max_fine_correction_mm {
        warnings.push(format!(
            "fine registration moved the tooth by up to {fine_correction:.3} mm, more than the \
             plausible drift of {:.3} mm (implausible: the fit diverged or slid); {}",
            opts.guard.max_fine_correction_mm,
            if opts.guard.reject_implausible {
                "kept the coarse transform instead"
            } else {
                "accepted as computed, check this tooth"
            }
        ));
        if opts.guard.reject_implausible {
            return (coarse_t.inverse(), 0.0);
        }
    } else if stages.fine.is_some() && fine_correction > opts.guard.flag_correction_mm {
        warnings.push(format!(
            "fine registration moved the tooth by up to {fine_correction:.3} mm relative to the \
             jaw-wide transform: large drift or a distorted CBCT crown, check this tooth"
        ));
    }
    (ios_to_cbct, fine_correction)
}

/// Warnings on the surface fit of a registered tooth: its mean surface distance `sd`, the gap
/// `gap` between the IOS and CBCT crown tops and the inlier fraction `inl`, each against its
/// guard.
fn fit_warnings(sd: f64, gap: f64, inl: f64, opts: &RegisterOptions, warnings: &mut Vec<String>) {
    if sd > opts.guard.max_sd_mm {
        warnings.push(format!(
            "surface distance {sd:.3} mm exceeds {:.3} mm: CBCT artefact (metal?) or misregistration",
            opts.guard.max_sd_mm
        ));
    }
    if gap.abs() > opts.guard.max_top_gap_mm {
        warnings.push(format!(
            "the IOS crown top lies {:.3} mm {} the CBCT crown top: the crown may have slid \
             along the tooth",
            gap.abs(),
            if gap < 0.0 { "below" } else { "above" }
        ));
    }
    if inl < opts.guard.min_inlier_fraction {
        warnings.push(format!(
            "only {:.0}% of the IOS crown lies within {:.2} mm of the CBCT tooth",
            inl * 100.0,
            opts.inlier_distance_mm
        ));
    }
}

/// Signed gap (mm) between the occlusal tops of the IOS crown (mapped by `ios_to_cbct`) and the
/// CBCT tooth, along the direction from the CBCT tooth centroid to the crown centroid.
fn top_gap(d: &ToothData, ios_to_cbct: &Rigid) -> f64 {
    let cm = d.cbct.mesh();
    let Some(cc) = crate::geom::centroid(&cm.positions) else {
        return 0.0;
    };
    let dir = (ios_to_cbct.apply(d.ios_centroid) - cc).normalize_or_zero();
    if dir == DVec3::ZERO {
        return 0.0;
    }
    let top_c = cm
        .positions
        .iter()
        .map(|p| p.dot(dir))
        .fold(f64::MIN, f64::max);
    let top_i = d
        .all
        .iter()
        .map(|&k| ios_to_cbct.apply(d.ios_points[k]).dot(dir))
        .fold(f64::MIN, f64::max);
    top_i - top_c
}
