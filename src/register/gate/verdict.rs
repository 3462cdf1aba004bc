//! The gate's verdicts from its measures: the jaw refused (mirrored, labels shifted, another
//! patient, the other jaw) and the misnumbered teeth.

use super::{
    BETTER, CLEAR_FIT_MM, GOOD_FIT_MM, GateReport, MAX_JAW_FIT_MM, MAX_MISMATCH,
    MAX_REGISTERED_SD_MM, MIN_REGISTERED_INLIERS, MIN_TEETH_FOR_MISMATCH, MIRROR_BETTER,
    TOOTH_MISFIT_MM, median,
};
use crate::Error;
use crate::arch::jaw_of;
use crate::register::ToothRegistration;
use std::collections::BTreeMap;

/// The jaw-level verdict from the gate's measures: mirrored, labels shifted, or another
/// patient (the first that holds), if any.
pub(super) fn jaw_verdict(r: &GateReport, shift_step: i32) -> Option<Error> {
    // A short arch's nearly collinear teeth leave the quick fit's rotation about the arch line
    // loose (the full registration restarts for that): its verdicts need a hypothesis that fits
    // well, and the "does not match" verdict needs a long enough arch.
    let long_arch = r.teeth.len() >= MIN_TEETH_FOR_MISMATCH;
    // On a short arch with no evidence of the IOS's own handedness (teeth of one side only), a
    // reflection of a few nearly collinear teeth can fit as well as the truth: no mirror verdict.
    let mirror_decidable = long_arch || r.ios_handed_ok.is_some();
    if mirror_decidable
        && r.fit_mm > GOOD_FIT_MM
        && r.mirrored_fit_mm < MIRROR_BETTER * r.fit_mm
        && r.mirrored_fit_mm < CLEAR_FIT_MM
    {
        let which = match r.ios_handed_ok {
            Some(false) => {
                "the IOS is mirrored (its crowns' occlusal side and its left and right teeth \
                 contradict its FDI numbers)"
            }
            Some(true) => {
                "the CBCT is mirrored (the IOS crowns' occlusal side and left and right teeth \
                 agree with their FDI numbers)"
            }
            None => "one of them is mirrored",
        };
        return Some(Error::Mirrored(format!(
            "{which}: the IOS fits the CBCT with a median distance of {:.2} mm as given but \
             {:.2} mm when reflected; an x -> -x flip or an LPS/RAS conversion was applied to one \
             modality only",
            r.fit_mm, r.mirrored_fit_mm
        )));
    }
    if r.fit_mm > GOOD_FIT_MM
        && r.shifted_fit_mm < BETTER * r.fit_mm
        && r.shifted_fit_mm < CLEAR_FIT_MM
    {
        return Some(Error::RegistrationRejected(format!(
            "labels shifted by one tooth along the arch: the IOS crowns fit the CBCT teeth one \
             position {} with a median distance of {:.2} mm, but {:.2} mm with the labels as \
             given; renumber the IOS (or CBCT) teeth",
            if shift_step > 0 {
                "further left"
            } else {
                "further right"
            },
            r.shifted_fit_mm,
            r.fit_mm
        )));
    }
    if long_arch && (r.fit_mm > MAX_JAW_FIT_MM || r.mismatch > MAX_MISMATCH) {
        // With no crown within reach of its own CBCT tooth no tooth is fitted alone: the score
        // has no finite value, and the surface offset and the hint about biased segmentations
        // mean nothing. Said so rather than printed as "inf".
        if !r.mismatch.is_finite() {
            return Some(Error::RegistrationRejected(format!(
                "the IOS and the CBCT do not match (another patient?): after the jaw-wide fit the \
                 IOS crowns lie a median {:.2} mm from their CBCT teeth and none lies within \
                 {TOOTH_MISFIT_MM} mm of its own (the same patient's crowns: a median 0.1-0.3 \
                 mm); check that both scans are of this patient and the tooth numbers of both; \
                 accept questionable data to fuse anyway",
                r.fit_mm
            )));
        }
        return Some(Error::RegistrationRejected(format!(
            "the IOS and the CBCT do not match (another patient?): after the jaw-wide fit the IOS \
             crowns lie a median {:.2} mm from their CBCT teeth (the CBCT tooth surfaces {:+.2} mm \
             off them) and each tooth fitted alone moves across its axis a median {:.2} mm \
             (mismatch score {:.2}, refused above {MAX_MISMATCH}; on the phantom the same \
             patient's scans score 1.1-2.6, another patient's from 1.7); check that both scans \
             are of this patient; if they are (a CBCT segmentation biased by 0.2 mm or more, or a \
             coarse scan, can score this high), accept questionable data to fuse anyway",
            r.fit_mm, r.surface_offset_mm, r.tooth_translation_mm, r.mismatch
        )));
    }
    None
}

/// Teeth whose IOS crown lies on another CBCT tooth, with the reason.
pub(super) fn misnumbered(r: &GateReport) -> Vec<(u8, String)> {
    let on_other: BTreeMap<u8, (u8, f64, f64)> = r
        .teeth
        .iter()
        .filter_map(|e| {
            let (o, d) = e.best_other?;
            (e.own_fit_mm > TOOTH_MISFIT_MM && d < BETTER * e.own_fit_mm)
                .then_some((e.fdi, (o, d, e.own_fit_mm)))
        })
        .collect();
    on_other
        .iter()
        .map(|(&f, &(o, d, own))| {
            let swapped = on_other.get(&o).is_some_and(|x| x.0 == f);
            let why = if swapped {
                format!("the IOS labels {f} and {o} look swapped")
            } else {
                "the IOS label looks wrong".to_string()
            };
            (
                f,
                format!(
                    "misnumbered: the IOS crown labelled {f} lies on CBCT tooth {o} (median \
                     distance {d:.2} mm) rather than on CBCT tooth {f} ({own:.2} mm): {why}; \
                     tooth not fused"
                ),
            )
        })
        .collect()
}

/// The error for IOS and CBCT teeth from different jaws, if that is the case.
pub(crate) fn wrong_jaw(ios: &[u8], cbct: &[u8]) -> Option<Error> {
    let jaws = |v: &[u8]| {
        let mut j: Vec<_> = v.iter().map(|&f| jaw_of(f)).collect();
        j.sort();
        j.dedup();
        j
    };
    let (ji, jc) = (jaws(ios), jaws(cbct));
    if ji.len() == 1 && jc.len() == 1 && ji != jc {
        let name = |j: crate::arch::Jaw| match j {
            crate::arch::Jaw::Upper => "upper",
            crate::arch::Jaw::Lower => "lower",
        };
        return Some(Error::RegistrationRejected(format!(
            "wrong jaw: the IOS teeth are of the {} jaw, the CBCT teeth of the {} jaw; give \
             both modalities of the same jaw",
            name(ji[0]),
            name(jc[0])
        )));
    }
    None
}

/// The error for a jaw whose teeth, registered in full, still do not lie on their CBCT teeth:
/// the median surface distance over the teeth above [`MAX_REGISTERED_SD_MM`] and the median
/// share of crown points within the inlier distance below [`MIN_REGISTERED_INLIERS`] (another
/// patient's teeth, or a registration that found no fit). Teeth of the same patient fit far
/// better whatever their export or CBCT errors; one tooth with a metal streak does not move the
/// medians.
pub(crate) fn registered_mismatch(teeth: &BTreeMap<u8, ToothRegistration>) -> Option<Error> {
    // The gate's upper median: infinite for no tooth, which is then not refused.
    let sd = median(teeth.values().map(|t| t.sd_mm).collect());
    let inliers = median(teeth.values().map(|t| t.inlier_fraction).collect());
    if sd <= MAX_REGISTERED_SD_MM || inliers >= MIN_REGISTERED_INLIERS {
        return None;
    }
    let per_tooth: Vec<String> = teeth
        .values()
        .map(|t| format!("{} {:.2} mm", t.fdi, t.sd_mm))
        .collect();
    Some(Error::RegistrationRejected(format!(
        "the IOS and the CBCT do not match (another patient?): registered in full, the IOS \
         crowns lie a median {sd:.2} mm from their CBCT teeth (per tooth: {}) and a median \
         {:.0} % of their points within the inlier distance (refused beyond {MAX_REGISTERED_SD_MM} \
         mm with under {:.0} %; the same patient's scans measure at most 0.34 mm and 89 % on the \
         phantom); check that both scans are of this patient and the tooth numbers of both; \
         accept questionable data to fuse anyway",
        per_tooth.join(", "),
        100.0 * inliers,
        100.0 * MIN_REGISTERED_INLIERS
    )))
}

#[cfg(test)]
mod tests {
    use super::super::ToothEvidence;
    use super::*;
    use glam::DVec3;

    /// A full arch whose crowns lie nowhere near their CBCT teeth (a real scan on another
    /// patient's segmentation measured a median 15.6 mm): no tooth is fitted alone, so the score
    /// is infinite; the refusal says why in words, with no "inf" and no surface offset.
    #[test]
    fn no_crown_near_its_tooth_is_refused_in_words() {
        let tooth = |fdi| ToothEvidence {
            fdi,
            own_fit_mm: 15.0,
            best_other: None,
            own_shift_mm: f64::INFINITY,
            own_lateral_mm: f64::INFINITY,
            own_refit_mm: f64::INFINITY,
            own_motion: [DVec3::ZERO; 3],
        };
        let r = GateReport {
            fit_mm: 15.58,
            surface_offset_mm: -15.1,
            mirrored_fit_mm: 16.0,
            shifted_fit_mm: 16.0,
            tooth_translation_mm: f64::INFINITY,
            mismatch: f64::INFINITY,
            teeth: [11, 12, 13, 21, 22, 23].into_iter().map(tooth).collect(),
            ..GateReport::default()
        };
        let e = jaw_verdict(&r, 1).expect("refused");
        let m = e.to_string();
        assert!(matches!(e, Error::RegistrationRejected(_)), "{m}");
        assert!(
            m.contains("15.58 mm") && m.contains("none lies within 1 mm"),
            "{m}"
        );
        assert!(!m.contains("inf") && !m.contains("-15.10"), "{m}");
    }
}
