//! The registration gate: evidence, independent of the optimiser's own residuals, that the IOS
//! and the CBCT show the same jaw of the same patient with the same tooth numbers. It runs after
//! the per-tooth preparation and before the coarse stage, so wrong data are refused in a fraction
//! of a second instead of after a long registration that cannot succeed.
//!
//! A quick jaw-wide fit (`quick_fit`: centroid alignment, then a trimmed point-to-plane ICP on
//! at most 150 IOS points per tooth, with a uniform offset of the CBCT surfaces along their
//! normal estimated with the pose: a segmentation threshold biased either way grows or shrinks
//! every tooth alike, and without the offset the residuals, all of one sign, slid the crowns
//! millimetres along their axes) is run under competing hypotheses:
//!
//! * the data as given;
//! * the IOS mirrored (x → −x): when it fits clearly better, one modality is a reflection of the
//!   other ([`Error::Mirrored`]);
//! * the IOS labels moved by one tooth along the arch, either way: when that fits clearly better,
//!   the labels are shifted ([`Error::RegistrationRejected`]).
//!
//! With the given labels, each IOS crown is then compared with its own CBCT tooth and with the
//! CBCT teeth near it along the arch: a crown that lies on another tooth's CBCT surface is
//! misnumbered (two such crowns on each other's teeth: swapped) and is skipped with that reason.
//! Per tooth, an independent rigid fit from the jaw-wide fit measures how far each tooth must move
//! on its own ([`ToothEvidence::own_shift_mm`]): for the same patient only the scanner's smooth
//! drift and the CBCT's distortion; for another patient's arch, the teeth's individual positions
//! differ. The jaw is refused when the median fit or the tooth motions are beyond what the same
//! patient gives.

pub(crate) mod handedness;
mod verdict;

use super::ToothData;
use super::centroid::kabsch;
use super::correspondence::{NearestMemo, SurfaceIndex};
use super::icp::{Normal7, Pair, step_about};
use crate::arch::{arch_position, is_valid_fdi, jaw_of};
use crate::{Error, Rigid};
use glam::DVec3;
use handedness::ios_handedness;
use std::collections::BTreeMap;
use verdict::{jaw_verdict, misnumbered};
pub(crate) use verdict::{registered_mismatch, wrong_jaw};

/// Largest number of IOS points per tooth the gate's fits use (deterministic stride sample).
const SAMPLE: usize = 150;
/// The competing hypotheses (mirrored, shifted) fit every `ALT_STRIDE`-th point of the sample:
/// only a clearly better fit counts there, and a third of the points shows it as well.
const ALT_STRIDE: usize = 3;
/// ICP iterations of the quick jaw-wide fit.
const JAW_ITERATIONS: usize = 25;
/// ICP iterations of the independent per-tooth fit.
const TOOTH_ITERATIONS: usize = 20;
/// Largest number of IOS points per tooth of the independent per-tooth fit.
const TOOTH_SAMPLE: usize = 500;
/// An alternative hypothesis wins when its median fit is below this fraction of the given one's.
const BETTER: f64 = 0.6;
/// The reflected IOS wins when its median fit is below this fraction of the given one's (a valid
/// jaw's reflection fits about half as well, a mirrored jaw's about twice as well: 0.5-0.6
/// measured on the phantoms either way).
const MIRROR_BETTER: f64 = 0.75;
/// A hypothesis wins only with a median fit below this (mm): a clear fit.
const CLEAR_FIT_MM: f64 = 0.35;
/// Fewest teeth in both modalities for the "does not match" verdict.
const MIN_TEETH_FOR_MISMATCH: usize = 6;
/// Median per-tooth fit (mm) under which the given data are never said to fit worse than an
/// alternative: a fit this good is the right one whatever an alternative gives.
const GOOD_FIT_MM: f64 = 0.2;
/// Median per-tooth fit (mm) of the given data above which the jaw is refused.
const MAX_JAW_FIT_MM: f64 = 0.6;
/// Typical median fit (mm) of the quick jaw-wide fit on the same patient's scans.
const FIT_REF_MM: f64 = 0.17;
/// Typical median per-tooth translation (mm) of the independent fit on the same patient's scans.
const TRANSLATION_REF_MM: f64 = 0.25;
/// Mismatch score above which the jaw is refused as another patient's. On the phantom the margin
/// is narrow: same-patient jaws scored up to 2.09 (register_accuracy) and 2.18 (wrong_data, two
/// labels swapped, seed 6: its CBCT teeth lie 0.18 mm inside its IOS crowns), other patients'
/// jaws of wrong_data from 2.29; real patients differ far more than its ±5 % arch size. The
/// distributions overlap: the same-patient jaws of seed 18 (CBCT teeth 0.18-0.20 mm inside the
/// crowns) score 2.28-2.62 and are refused, while some other-patient pairs score from 1.7.
const MAX_MISMATCH: f64 = 2.23;
/// Median over teeth of the surface distance (mm, [`super::ToothRegistration::sd_mm`]) after
/// the full registration above which, with [`MIN_REGISTERED_INLIERS`], the jaw is refused as not
/// matching. The gate's own verdicts need six teeth (a short arch's quick fit is loose about the
/// arch line); the full registration, with its restarts, is not, so this holds on any arch. On
/// the same patient's scans the median is at most 0.34 mm and the median inlier share at least
/// 0.89 (98 phantom jaws of the CLI sweeps: rough, coarse and dense exports, every variant,
/// short arches of 3-5 teeth among them); a real scan's crowns on another patient's real CBCT
/// teeth (Mesh Labeler's Example_01 on Open-Full-Jaw patient 26, 4 teeth) 2.08 mm and 0.33.
const MAX_REGISTERED_SD_MM: f64 = 0.6;
/// Median inlier share (IOS crown points within the inlier distance of their CBCT tooth after
/// the full registration) below which, with [`MAX_REGISTERED_SD_MM`], the jaw is refused.
const MIN_REGISTERED_INLIERS: f64 = 0.6;
/// A crown whose fit to its own CBCT tooth is worse than this (mm) and at most [`BETTER`] times
/// that on another tooth's CBCT is misnumbered.
const TOOTH_MISFIT_MM: f64 = 1.0;

/// What the gate measured on one tooth.
#[derive(Clone, Debug, PartialEq)]
pub struct ToothEvidence {
    /// FDI number.
    pub fdi: u8,
    /// Median distance (mm) of its IOS sample to its own CBCT tooth after the jaw-wide fit.
    pub own_fit_mm: f64,
    /// The CBCT tooth (other than its own, up to two places along the arch) its IOS crown fits
    /// best, with that median distance; looked for only where it can decide, when the crown
    /// lies farther than 1 mm (median) from its own CBCT tooth (`None` otherwise, and where no
    /// such tooth is in the CBCT).
    pub best_other: Option<(u8, f64)>,
    /// How far (mm, at the crown) an independent rigid fit of this tooth moves it from the
    /// jaw-wide fit.
    pub own_shift_mm: f64,
    /// The part of that motion at the crown centre across the tooth's axis (mm).
    pub own_lateral_mm: f64,
    /// Median distance (mm) of its IOS sample to its own CBCT tooth after that independent fit.
    pub own_refit_mm: f64,
    /// That motion as the displacement of three points 5 mm apart around the crown centre
    /// (CBCT frame, mm), for comparing neighbours.
    pub own_motion: [DVec3; 3],
}

/// What the gate measured on the jaw; kept on the registration.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GateReport {
    /// Median over teeth of the per-tooth median distance (mm) after the quick fit, as given (a
    /// uniform [`Self::surface_offset_mm`] counts in it).
    pub fit_mm: f64,
    /// The uniform offset (mm) of the CBCT tooth surfaces along their outward normal from the
    /// IOS crowns that the quick fit estimates with the pose: positive when the CBCT teeth are
    /// larger (a segmentation threshold biased outwards), negative when smaller.
    pub surface_offset_mm: f64,
    /// The same with the IOS mirrored.
    pub mirrored_fit_mm: f64,
    /// The same with the IOS labels moved by one tooth along the arch (the better direction).
    pub shifted_fit_mm: f64,
    /// Median over teeth of [`ToothEvidence::own_shift_mm`].
    pub tooth_shift_mm: f64,
    /// Median over teeth of [`ToothEvidence::own_refit_mm`].
    pub refit_mm: f64,
    /// Median over teeth of how far the independent per-tooth fit moves the crown centre across
    /// the tooth's axis (mm).
    pub tooth_translation_mm: f64,
    /// The mismatch score: `fit_mm / FIT_REF_MM + tooth_translation_mm / TRANSLATION_REF_MM`
    /// (measured on the same patient's phantom jaws 1.1-2.1, 2.18 with two labels swapped, 0.2-2.1
    /// on the STS phantom with realistic CBCT surface errors; on another patient's 1.7-4.4, 36 of
    /// 40 above 2.23, above which the jaw is refused).
    pub mismatch: f64,
    /// Median over teeth of how far a tooth's own motion departs from the mean of its two
    /// neighbours' along the arch (mm): smooth drift moves neighbours alike.
    pub roughness_mm: f64,
    /// Handedness of the IOS from its own geometry and FDI sides: `Some(true)` when it agrees
    /// with the numbering, `Some(false)` when mirrored, `None` when undecidable.
    pub ios_handed_ok: Option<bool>,
    /// Per tooth.
    pub teeth: Vec<ToothEvidence>,
    /// Findings accepted because the caller asked to accept questionable data (empty otherwise).
    pub accepted: Vec<String>,
}

/// The gate's verdict on the jaw and the teeth to leave out.
pub(crate) struct Verdict {
    pub report: GateReport,
    /// Jaw-level refusal (mirrored or rejected), if any.
    pub jaw: Option<Error>,
    /// Teeth to skip, with the reason.
    pub skip: Vec<(u8, String)>,
}

/// One tooth as a hypothesis pairs it: the CBCT surface and the IOS sample.
struct Pairing<'a> {
    fdi: u8,
    cbct: &'a SurfaceIndex,
    ios: Vec<DVec3>,
}

fn sample(d: &ToothData, n: usize) -> Vec<DVec3> {
    let all = d.ios_indices(super::Level::Full);
    let stride = all.len().div_ceil(n).max(1);
    all.iter()
        .step_by(stride)
        .map(|&k| d.ios_points[k])
        .collect()
}

/// The element at index `len / 2` of `v` sorted by `total_cmp` (the upper median), found by
/// selection instead of a sort; infinite for an empty `v`.
fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::INFINITY;
    }
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

fn mean(p: &[DVec3]) -> DVec3 {
    p.iter().copied().sum::<DVec3>() / p.len().max(1) as f64
}

/// Median distance (mm) of `pts`, mapped by `ios_to_cbct`, to `cbct`. A uniform surface offset
/// (threshold bias) counts in it: measured about the fitted offset instead, the phantom lost its
/// "another patient" margin (the IOS of seed 7 on the CBCT of seed 6, whose teeth lie 0.18 mm
/// inside, fell from 2.58 to 1.94 in the mismatch score: arches too alike for the lateral motion
/// alone to tell).
fn fit_of(cbct: &SurfaceIndex, pts: &[DVec3], ios_to_cbct: &Rigid) -> f64 {
    median(
        pts.iter()
            .map(|p| cbct.closest_point(ios_to_cbct.apply(*p)).distance)
            .collect(),
    )
}

/// How a fit's ICP ends besides its iteration budget.
#[derive(Clone, Copy, PartialEq)]
enum Stop {
    /// Only when the step vanishes (the hypothesis as given, whose fit grades the data).
    Converged,
    /// Also when the median pair distance has dropped by less than [`STALL_DROP`] over the last
    /// [`STALL_WINDOW`] iterations (competing hypotheses: only whether they fit clearly better
    /// matters, and a fit that no longer improves has reached what it will show).
    Stalled,
}

/// Iterations over which a competing hypothesis must improve its median pair distance.
const STALL_WINDOW: usize = 3;
/// Relative drop of the median pair distance over [`STALL_WINDOW`] iterations below which a
/// competing hypothesis's ICP stops.
const STALL_DROP: f64 = 0.01;

/// The uniform offset (mm) of the CBCT surfaces along their outward normal from the IOS crowns
/// that an ICP fits with the pose: a CBCT segmentation's threshold bias grows or shrinks every
/// tooth alike, so that the true pose leaves every crown point the same distance inside (grown)
/// or outside (shrunk) its CBCT tooth.
#[derive(Clone, Copy, PartialEq)]
enum Offset {
    /// Estimated with the pose, from this start (the jaw-wide fits).
    Estimated(f64),
    /// Held at this value (the per-tooth fit, under the jaw's offset).
    Held(f64),
}

/// Trimmed point-to-plane ICP (closest CBCT vertex, its normal) moving the IOS samples of
/// `teeth` onto their CBCT teeth, displaced by the offset, from `ios_to_cbct`; returns the final
/// IOS → CBCT transform and offset. Without the offset, a biased segmentation's residuals (all
/// of one sign at the true pose) push the crowns along their axes at every iteration: the STS
/// phantom's teeth grown by one voxel (crown points 0.21 mm inside at the truth) ended about
/// 5 mm off.
fn icp(
    teeth: &[&Pairing],
    mut ios_to_cbct: Rigid,
    offset: Offset,
    iterations: usize,
    stop: Stop,
) -> (Rigid, f64) {
    let (mut b, estimate) = match offset {
        Offset::Estimated(b) => (b, true),
        Offset::Held(b) => (b, false),
    };
    let all: Vec<DVec3> = teeth.iter().flat_map(|t| t.ios.iter().copied()).collect();
    if all.is_empty() {
        return (ios_to_cbct, b);
    }
    let c0 = mean(&all);
    let mut medians = Vec::with_capacity(iterations);
    // Per point, its last nearest-vertex search: the pairs are those of a search every time.
    let mut memos = vec![NearestMemo::default(); all.len()];
    for _ in 0..iterations {
        let center = ios_to_cbct.apply(c0);
        // One thread: the hypotheses' fits run side by side ([`assess`]).
        let pairs: Vec<Pair> = teeth
            .iter()
            .flat_map(|t| t.ios.iter().map(move |p| (t, p)))
            .zip(memos.iter_mut())
            .map(|((t, p), memo)| {
                let q = ios_to_cbct.apply(*p);
                let c = t.cbct.pair_remembered(q, false, memo);
                Pair {
                    p: q,
                    q: c.point,
                    n: c.normal,
                    n_other: DVec3::ZERO,
                }
            })
            .collect();
        let med = median(pairs.iter().map(|p| p.p.distance(p.q)).collect());
        if stop == Stop::Stalled
            && medians.len() >= STALL_WINDOW
            && med > (1.0 - STALL_DROP) * medians[medians.len() - STALL_WINDOW]
        {
            break;
        }
        medians.push(med);
        let cut = 3.0 * med + 0.3;
        let w: Vec<f64> = pairs
            .iter()
            .map(|p| if p.p.distance(p.q) <= cut { 1.0 } else { 0.0 })
            .collect();
        // The residual `(p − q) · n` is the IOS point's signed distance from the CBCT surface;
        // the offset `b` is the part of it every pair shares.
        let mut ne = Normal7::new();
        ne.add_pairs(&pairs, &w, center, b);
        let Some((rw, rt, db)) = ne.solve(estimate) else {
            break;
        };
        b += db;
        ios_to_cbct = step_about(rw, rt, center)
            .compose(&ios_to_cbct)
            .orthonormalized();
        if rw.length() < 1e-5 && rt.length() < 1e-4 && db.abs() < 1e-4 {
            break;
        }
    }
    (ios_to_cbct, b)
}

/// What a quick jaw-wide fit ends at.
struct QuickFit {
    /// IOS → CBCT.
    pose: Rigid,
    /// The fitted offset of the IOS points from the CBCT surfaces (mm, positive outside).
    offset: f64,
    /// Median over teeth of each tooth's median distance (mm).
    fit: f64,
}

/// Centroid alignment (IOS sample centroid onto CBCT vertex centroid, keyed by tooth) then the
/// trimmed ICP with the offset estimated. `None` when the centroids are degenerate.
fn quick_fit(teeth: &[Pairing], stop: Stop) -> Option<QuickFit> {
    let src: Vec<DVec3> = teeth.iter().map(|t| mean(&t.ios)).collect();
    let mut dst: Vec<DVec3> = teeth
        .iter()
        .map(|t| mean(&t.cbct.mesh().positions))
        .collect();
    let mut init = kabsch(&src, &dst, None).ok()?;
    // The IOS holds crowns only: pair each crown centroid with the centroid of the CBCT
    // vertices near the mapped crown instead of the whole tooth's (two passes).
    for _ in 0..2 {
        dst = teeth
            .iter()
            .zip(&dst)
            .map(|(t, &d)| {
                // The CBCT vertices within 2 mm of the mapped crown, summed in index order.
                let positions = &t.cbct.mesh().positions;
                let mapped: Vec<DVec3> = t.ios.iter().map(|p| init.apply(*p)).collect();
                let is_near = t.cbct.vertices_near(&mapped, 4.0);
                let near: Vec<DVec3> = positions
                    .iter()
                    .zip(&is_near)
                    .filter(|(_, n)| **n)
                    .map(|(p, _)| *p)
                    .collect();
                if near.is_empty() { d } else { mean(&near) }
            })
            .collect();
        init = kabsch(&src, &dst, None).ok()?;
    }
    let refs: Vec<&Pairing> = teeth.iter().collect();
    let (pose, offset) = icp(&refs, init, Offset::Estimated(0.0), JAW_ITERATIONS, stop);
    let fit = median(
        teeth
            .iter()
            .map(|p| fit_of(p.cbct, &p.ios, &pose))
            .collect(),
    );
    Some(QuickFit { pose, offset, fit })
}

/// The FDI number `steps` teeth along the arch from `fdi` within its jaw (permanent teeth
/// 18 … 11, 21 … 28 or 48 … 41, 31 … 38), `None` past the end.
fn along_arch(fdi: u8, steps: i32) -> Option<u8> {
    let jaw_teeth: Vec<u8> = match jaw_of(fdi) {
        crate::arch::Jaw::Upper => [10u8, 20]
            .iter()
            .flat_map(|q| (1..=8).map(move |t| q + t))
            .collect(),
        crate::arch::Jaw::Lower => [40u8, 30]
            .iter()
            .flat_map(|q| (1..=8).map(move |t| q + t))
            .collect(),
    };
    let mut order = jaw_teeth;
    order.sort_by_key(|&t| arch_position(t));
    let i = order.iter().position(|&t| t == fdi)? as i32 + steps;
    usize::try_from(i).ok().and_then(|i| order.get(i).copied())
}

/// The verdict on `teeth` (the teeth in both modalities, prepared).
pub(crate) fn assess(teeth: &BTreeMap<u8, ToothData>) -> Verdict {
    let samples: BTreeMap<u8, Vec<DVec3>> =
        teeth.iter().map(|(&f, d)| (f, sample(d, SAMPLE))).collect();
    let given: Vec<Pairing> = teeth
        .iter()
        .map(|(&f, d)| Pairing {
            fdi: f,
            cbct: &d.cbct,
            ios: samples[&f].clone(),
        })
        .collect();
    let mut report = GateReport::default();
    let mirrored: Vec<Pairing> = given
        .iter()
        .map(|p| Pairing {
            fdi: p.fdi,
            cbct: p.cbct,
            ios: p
                .ios
                .iter()
                .step_by(ALT_STRIDE)
                .map(|v| DVec3::new(-v.x, v.y, v.z))
                .collect(),
        })
        .collect();
    let shifted: Vec<(i32, Vec<Pairing>)> = [-1, 1]
        .into_iter()
        .map(|step| {
            let moved = given
                .iter()
                .filter_map(|p| {
                    let to = along_arch(p.fdi, step).filter(|&f| is_valid_fdi(f as i32))?;
                    Some(Pairing {
                        fdi: to,
                        cbct: &teeth.get(&to)?.cbct,
                        ios: p.ios.iter().step_by(ALT_STRIDE).copied().collect(),
                    })
                })
                .collect();
            (step, moved)
        })
        .collect();
    // The hypotheses are independent: their fits run side by side, each on one thread. Each
    // with its stop rule and the fewest teeth it is fitted with (a shift along the arch keeps
    // at least 3).
    let mut hypotheses: Vec<(&[Pairing], Stop, usize)> =
        vec![(&given, Stop::Converged, 0), (&mirrored, Stop::Stalled, 0)];
    hypotheses.extend(
        shifted
            .iter()
            .map(|(_, moved)| (moved.as_slice(), Stop::Stalled, 3)),
    );
    let mut fits = crate::par::map_ordered(&hypotheses, |&(teeth, stop, fewest)| {
        (teeth.len() >= fewest)
            .then(|| quick_fit(teeth, stop))
            .flatten()
    })
    .into_iter();
    let Some(QuickFit {
        pose: t,
        offset,
        fit,
    }) = fits.next().flatten()
    else {
        return Verdict {
            report,
            jaw: None,
            skip: Vec::new(),
        };
    };
    report.fit_mm = fit;
    report.surface_offset_mm = -offset;
    report.mirrored_fit_mm = fits.next().flatten().map_or(f64::INFINITY, |r| r.fit);
    let mut shifted_best = (f64::INFINITY, 0);
    for ((step, _), q) in shifted.iter().zip(fits) {
        if let Some(q) = q
            && q.fit < shifted_best.0
        {
            shifted_best = (q.fit, *step);
        }
    }
    report.shifted_fit_mm = shifted_best.0;
    report.teeth = tooth_evidence(teeth, &given, &t, offset);
    report.tooth_shift_mm = median(report.teeth.iter().map(|e| e.own_shift_mm).collect());
    report.roughness_mm = roughness(&report.teeth);
    report.refit_mm = median(report.teeth.iter().map(|e| e.own_refit_mm).collect());
    report.tooth_translation_mm = median(
        report
            .teeth
            .iter()
            .filter(|e| e.own_fit_mm <= TOOTH_MISFIT_MM)
            .map(|e| e.own_lateral_mm)
            .collect(),
    );
    report.mismatch = report.fit_mm / FIT_REF_MM + report.tooth_translation_mm / TRANSLATION_REF_MM;
    report.ios_handed_ok = ios_handedness(teeth);
    let jaw = jaw_verdict(&report, shifted_best.1);
    let skip = if jaw.is_some() || report.fit_mm > CLEAR_FIT_MM {
        Vec::new()
    } else {
        misnumbered(&report)
    };
    Verdict { report, jaw, skip }
}

/// Per tooth: its own fit, its best fit on another CBCT tooth nearby, its independent motion
/// (the tooth's ICP holding the jaw's offset `offset` of the IOS points from the CBCT surfaces).
fn tooth_evidence(
    teeth: &BTreeMap<u8, ToothData>,
    given: &[Pairing],
    t: &Rigid,
    offset: f64,
) -> Vec<ToothEvidence> {
    crate::par::map_ordered(given, |p| {
        let own_fit_mm = fit_of(p.cbct, &p.ios, t);
        let dense = Pairing {
            fdi: p.fdi,
            cbct: p.cbct,
            ios: sample(&teeth[&p.fdi], TOOTH_SAMPLE),
        };
        // Only a crown that misfits its own tooth can be misnumbered ([`misnumbered`]): the
        // other teeth's fits (four searches of the crown sample each) are made for it alone.
        let best_other = (-2..=2)
            .filter(|&s| s != 0 && own_fit_mm > TOOTH_MISFIT_MM)
            .filter_map(|s| along_arch(p.fdi, s))
            .filter_map(|f| Some((f, fit_of(&teeth.get(&f)?.cbct, &p.ios, t))))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        let (own, _) = icp(
            &[&dense],
            *t,
            Offset::Held(offset),
            TOOTH_ITERATIONS,
            Stop::Converged,
        );
        let c = mean(&p.ios);
        let own_motion = [DVec3::ZERO, DVec3::X * 5.0, DVec3::Y * 5.0]
            .map(|o| own.apply(c + o) - t.apply(c + o));
        let own_shift_mm = own_motion.iter().map(|v| v.length()).fold(0.0, f64::max);
        let own_refit_mm = fit_of(p.cbct, &dense.ios, &own);
        // Only the motion across the axis counts towards the mismatch score (the score's
        // references were set on it; a biased segmentation moved crowns along their axes when
        // the fits had no offset).
        let up = t
            .apply_vector(teeth[&p.fdi].ios_occlusal.unwrap_or(DVec3::ZERO))
            .normalize_or_zero();
        let v = own_motion[0];
        let own_lateral_mm = (v - up * v.dot(up)).length();
        ToothEvidence {
            own_lateral_mm,
            own_refit_mm,
            fdi: p.fdi,
            own_fit_mm,
            best_other,
            own_shift_mm,
            own_motion,
        }
    })
}

/// Median over interior teeth (in arch order) of the largest departure of a tooth's own motion
/// from the mean of its neighbours' (mm).
fn roughness(ev: &[ToothEvidence]) -> f64 {
    let mut e: Vec<&ToothEvidence> = ev.iter().collect();
    e.sort_by_key(|x| arch_position(x.fdi));
    median(
        e.windows(3)
            .map(|w| {
                (0..3)
                    .map(|k| {
                        (w[1].own_motion[k] - 0.5 * (w[0].own_motion[k] + w[2].own_motion[k]))
                            .length()
                    })
                    .fold(0.0, f64::max)
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::median;

    /// The selection gives bitwise the element a full sort puts at `len / 2`, with repeated
    /// values, signed zeros, infinities and NaNs among the inputs.
    #[test]
    fn median_is_the_sorted_middle_element() {
        let mut rng = crate::phantom::rng::Rng::new(7);
        let specials = [
            0.0,
            -0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            1.5,
            1.5,
        ];
        for len in 0..200usize {
            let v: Vec<f64> = (0..len)
                .map(|_| {
                    let r = rng.next_u64();
                    if r.is_multiple_of(5) {
                        specials[(r >> 8) as usize % specials.len()]
                    } else {
                        ((r >> 11) % 50) as f64 * 0.01 - 0.2
                    }
                })
                .collect();
            let mut sorted = v.clone();
            sorted.sort_by(f64::total_cmp);
            let want = sorted.get(len / 2).copied().unwrap_or(f64::INFINITY);
            assert_eq!(median(v).to_bits(), want.to_bits(), "len {len}");
        }
    }
}
