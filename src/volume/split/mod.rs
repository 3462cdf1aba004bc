//! Per-jaw teeth masks split into teeth by the IOS. Some CBCT segmenters (DentalSegmentator)
//! give one teeth label per jaw (3 upper, 4 lower) and no tooth numbers. For each jaw with IOS
//! crowns: the crowns are registered as one rigid arch to the jaw's mask surface
//! ([`ArchFit`]), refused when the fit is not trustworthy; the mask is then split by a
//! nearest-crown flood inside the mask, seeded by the registered crowns and steered by each
//! tooth's long axis (see `flood`); each tooth carries its split's confidence (the shares of
//! its voxels whose assignment is contested, that lie beyond its crown's footprint, and that lie
//! beyond the narrowest cut of the mask to a touching neighbour, see `neck`; such voxels are
//! first handed to the neighbour and the teeth measured again) and teeth whose split cannot be
//! trusted are refused with the reason. The result is a per-tooth FDI label volume for
//! [`crate::volume::surface_teeth`]; the registration here serves only the split (the
//! per-tooth registration then runs as usual on the surfaced teeth).

mod arch_fit;
mod flood;
mod mask;
mod neck;

pub use arch_fit::ArchFit;
pub use flood::ToothSplit;

use super::LabelVolume;
use crate::arch::{Jaw, jaw_of};
use crate::mesh::TriMesh;
use crate::{Error, Result};
use mask::JawMask;
use std::collections::BTreeMap;

/// Thresholds of [`split_teeth`].
#[derive(Clone, Debug, PartialEq)]
pub struct SplitOptions {
    /// A crown point within this distance (mm) of the mask surface lies on it.
    pub inlier_mm: f64,
    /// The arch fit is refused below this share of crown points on the mask.
    pub min_inlier_share: f64,
    /// The arch fit is refused above this RMS point-to-plane residual of its inliers (mm).
    pub max_rms_mm: f64,
    /// The arch fit is refused as ambiguous when a different pose fits nearly as well: its
    /// trimmed residual below this multiple of the fit's.
    pub min_runner_up_ratio: f64,
    /// A tooth is refused when less than this share of its crown's points lie on the mask.
    pub min_crown_inlier_share: f64,
    /// Depth (mm) behind a crown's surface within which mask voxels seed its tooth.
    pub seed_depth_mm: f64,
    /// Cost of a sideways step (across the occlusal-apical axis) over an axial one, when
    /// growing the teeth from their crowns.
    pub lateral_weight: f64,
    /// Weight of the long-axis prior: a step costs `1 + axis_weight·(d / r)²` times more at
    /// distance `d` from the tooth's long-axis line (fitted to the voxels the previous flood gave
    /// the tooth; `r`: their RMS distance from it); 0 turns it off.
    pub axis_weight: f64,
    /// A voxel is contested when its runner-up's path is at most this much (mm) longer.
    pub contested_margin_mm: f64,
    /// A tooth is refused above this share of contested voxels.
    pub max_contested_share: f64,
    /// A voxel is under its crown when within this distance (mm) across the occlusal-apical
    /// axis of one of the crown's vertices.
    pub footprint_mm: f64,
    /// A tooth is refused above this share of voxels not under its crown.
    pub max_outside_share: f64,
    /// Hand each tooth's voxels beyond the narrowest cut of the mask to a touching neighbour
    /// (on the neighbour's side of it: its flood ran through their contact into the neighbour)
    /// to that neighbour ([`ToothSplit::handed_over_voxels`]); false keeps the flood's split
    /// as drawn and only measures them.
    pub hand_over: bool,
    /// A tooth is refused above this share of voxels beyond the narrowest cut of the mask
    /// between its crown and a touching neighbour's ([`ToothSplit::overrun_share`], measured
    /// after the hand-over): its split runs through their contact into the neighbour.
    pub max_overrun_share: f64,
}

impl Default for SplitOptions {
    fn default() -> Self {
        SplitOptions {
            inlier_mm: 1.0,
            min_inlier_share: 0.85,
            max_rms_mm: 0.4,
            min_runner_up_ratio: 1.5,
            min_crown_inlier_share: 0.5,
            seed_depth_mm: 3.0,
            lateral_weight: 3.0,
            axis_weight: 3.0,
            contested_margin_mm: 1.0,
            max_contested_share: 0.25,
            footprint_mm: 3.5,
            max_outside_share: 0.2,
            hand_over: true,
            max_overrun_share: 0.05,
        }
    }
}

/// One jaw's split.
#[derive(Clone, Debug)]
pub struct JawSplit {
    /// The jaw.
    pub jaw: Jaw,
    /// Its teeth class in the volume (3 upper, 4 lower).
    pub label: u16,
    /// The arch registration of its IOS crowns to the mask.
    pub fit: ArchFit,
    /// Per FDI tooth, the split (refused teeth included).
    pub teeth: BTreeMap<u8, ToothSplit>,
    /// Teeth refused, with the reason (left out of the split volume).
    pub refused: BTreeMap<u8, String>,
    /// Mask voxels no crown's seed reached (teeth without an IOS crown, fragments).
    pub unreached_voxels: usize,
}

/// A per-jaw volume split into teeth.
#[derive(Clone, Debug)]
pub struct SplitVolume {
    /// Per-tooth FDI label volume (cropped to the split jaws; refused teeth left out).
    pub volume: LabelVolume,
    /// The jaws split.
    pub jaws: Vec<JawSplit>,
    /// Jaws not split, with why (e.g. a teeth class without IOS crowns).
    pub notes: Vec<String>,
}

impl SplitVolume {
    /// Every refused tooth with the reason, in FDI order.
    pub fn refused(&self) -> Vec<(u8, String)> {
        let mut v: Vec<(u8, String)> = self
            .jaws
            .iter()
            .flat_map(|j| j.refused.iter().map(|(f, r)| (*f, r.clone())))
            .collect();
        v.sort();
        v
    }

    /// The split as JSON: per jaw the arch fit's evidence, per tooth its voxels, contested,
    /// outside-footprint, interface (boundary drawn by the split), moved (by the long-axis
    /// prior) and overrun (beyond the narrowest cut to a neighbour, with that neighbour) shares,
    /// the voxels its flood took beyond the narrowest cut that were handed over (count, share of
    /// its flood's voxels, the neighbour given most) and those it received, and, when refused,
    /// the reason (`null` otherwise).
    pub fn to_json(&self) -> String {
        let jaws: Vec<serde_json::Value> = self
            .jaws
            .iter()
            .map(|j| {
                let teeth: Vec<serde_json::Value> = j
                    .teeth
                    .iter()
                    .map(|(fdi, t)| {
                        serde_json::json!({
                            "fdi": fdi,
                            "voxels": t.voxels,
                            "contested_share": t.contested_share(),
                            "outside_share": t.outside_share(),
                            "interface_share": t.interface_share(),
                            "moved_share": t.moved_share(),
                            "overrun_share": t.overrun_share(),
                            "overrun_into": t.overrun_into,
                            "handed_over_voxels": t.handed_over_voxels,
                            "handed_over_share": t.handed_over_share(),
                            "handed_over_to": t.handed_over_to,
                            "received_voxels": t.received_voxels,
                            "refused": j.refused.get(fdi),
                        })
                    })
                    .collect();
                serde_json::json!({
                    "jaw": jaw_name(j.jaw),
                    "label": j.label,
                    "fit_inlier_share": j.fit.inlier_share,
                    "fit_rms_mm": j.fit.rms_mm,
                    "fit_runner_up_ratio": finite_or_null(j.fit.runner_up_ratio),
                    "unreached_voxels": j.unreached_voxels,
                    "teeth": teeth,
                })
            })
            .collect();
        let v = serde_json::json!({ "jaws": jaws, "notes": self.notes });
        serde_json::to_string_pretty(&v).unwrap_or_default()
    }

    /// One line per split tooth: its confidence shares, or why it was refused.
    pub fn summary(&self) -> Vec<String> {
        let mut out = Vec::new();
        for j in &self.jaws {
            for (fdi, t) in &j.teeth {
                out.push(match j.refused.get(fdi) {
                    Some(r) => format!("tooth {fdi}: refused: {r}"),
                    None => format!(
                        "tooth {fdi}: split from the per-jaw mask, {} voxels, {:.1}% contested, \
                         {:.1}% outside its crown's footprint, {:.1}% beyond the narrowest cut \
                         to a neighbour, {:.1}% of its boundary drawn by the split{}",
                        t.voxels,
                        100.0 * t.contested_share(),
                        100.0 * t.outside_share(),
                        100.0 * t.overrun_share(),
                        100.0 * t.interface_share(),
                        handed_note(t)
                    ),
                });
            }
        }
        out
    }
}

/// The hand-over of a tooth's summary line: what its flood took beyond the narrowest cut and
/// gave back, and what it received (empty when neither).
fn handed_note(t: &ToothSplit) -> String {
    let mut s = String::new();
    if let Some(w) = t.handed_over_to {
        s += &format!(
            "; {} voxels ({:.1}% of its flood) lay beyond the narrowest cut to a neighbour and \
             were handed to it (most to tooth {w})",
            t.handed_over_voxels,
            100.0 * t.handed_over_share()
        );
    }
    if t.received_voxels > 0 {
        s += &format!("; received {} voxels from neighbours", t.received_voxels);
    }
    s
}

fn finite_or_null(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

fn jaw_name(j: Jaw) -> &'static str {
    match j {
        Jaw::Upper => "upper",
        Jaw::Lower => "lower",
    }
}

/// Splits the teeth classes of a DentalSegmentator-style volume (3 upper teeth, 4 lower teeth)
/// into teeth with the IOS crowns `crowns` (IOS frame, by FDI). Each jaw with both a teeth
/// class and crowns is split; errors name the cause when no jaw can be (no teeth class, crowns
/// of the other jaw only, an arch fit that is not trustworthy, every tooth refused).
pub fn split_teeth(
    vol: &LabelVolume,
    crowns: &BTreeMap<u8, TriMesh>,
    opts: &SplitOptions,
) -> Result<SplitVolume> {
    let counts = vol.label_counts();
    let mut notes = Vec::new();
    let mut done = Vec::new();
    for (jaw, label) in [(Jaw::Upper, 3u16), (Jaw::Lower, 4u16)] {
        let mine: BTreeMap<u8, TriMesh> = crowns
            .iter()
            .filter(|(f, _)| jaw_of(**f) == jaw)
            .map(|(f, m)| (*f, m.clone()))
            .collect();
        let name = jaw_name(jaw);
        match (counts.contains_key(&label), mine.is_empty()) {
            (true, false) => done.push(split_jaw(vol, jaw, label, &mine, opts)?),
            (true, true) => notes.push(format!(
                "the {name} teeth class ({label}) was not split: the IOS has no {name} crowns"
            )),
            (false, false) => notes.push(format!(
                "the {name} IOS crowns were not used: the volume has no {name} teeth class ({label})"
            )),
            (false, true) => {}
        }
    }
    if done.is_empty() {
        return Err(no_jaw_error(&counts, crowns));
    }
    let volume = assemble(vol, &done);
    let jaws: Vec<JawSplit> = done.into_iter().map(|d| d.0).collect();
    if jaws.iter().all(|j| j.refused.len() == j.teeth.len()) {
        let why: Vec<String> = jaws
            .iter()
            .flat_map(|j| j.refused.iter().map(|(f, r)| format!("tooth {f}: {r}")))
            .collect();
        return Err(Error::RegistrationRejected(format!(
            "no tooth could be split from the per-jaw teeth mask: {}",
            why.join("; ")
        )));
    }
    Ok(SplitVolume {
        volume,
        jaws,
        notes,
    })
}

fn no_jaw_error(counts: &BTreeMap<u16, usize>, crowns: &BTreeMap<u8, TriMesh>) -> Error {
    let classes: Vec<u16> = [3u16, 4]
        .into_iter()
        .filter(|l| counts.contains_key(l))
        .collect();
    let fdis: Vec<u8> = crowns.keys().copied().collect();
    if classes.is_empty() {
        return Error::MissingData(format!(
            "the volume has no teeth class (3 upper teeth, 4 lower teeth); labels present: {:?}",
            counts.keys().collect::<Vec<_>>()
        ));
    }
    if fdis.is_empty() {
        return Error::MissingData(
            "no IOS crowns: a per-jaw teeth mask is split into teeth with the IOS crowns, so \
             the IOS must be given (added) first"
                .into(),
        );
    }
    let have = if classes == [3] {
        "upper (3)"
    } else {
        "lower (4)"
    };
    Error::InvalidArgument(format!(
        "the IOS crowns {fdis:?} are all of the other jaw: the volume has only the {have} teeth \
         class (is the IOS of the other jaw?)"
    ))
}

type Done = (JawSplit, JawMask, Vec<u8>);

/// Registers and splits one jaw: its split, mask box and per-box-voxel FDI labels.
fn split_jaw(
    vol: &LabelVolume,
    jaw: Jaw,
    label: u16,
    crowns: &BTreeMap<u8, TriMesh>,
    opts: &SplitOptions,
) -> Result<Done> {
    let name = jaw_name(jaw);
    let mask = JawMask::from_volume(vol, label)
        .ok_or_else(|| Error::MissingData(format!("no {name} teeth voxels")))?;
    let (pts, normals) = mask.surface_points();
    let target = arch_fit::Target::new(pts, normals)?;
    let fit = arch_fit::fit_arch(crowns, &target, opts.inlier_mm)?;
    check_fit(&fit, name, opts)?;
    let placed: BTreeMap<u8, TriMesh> = crowns
        .iter()
        .map(|(f, m)| {
            let mut m = m.clone();
            for p in &mut m.positions {
                *p = fit.ios_to_volume.apply(*p);
            }
            (*f, m)
        })
        .collect();
    let seeds = flood::seeds(&mask, &placed, opts.seed_depth_mm);
    let (plain, mut best) = grow(&mask, &placed, &seeds, fit.up, opts);
    let found = neck::overruns(&mask, &best, &seeds);
    // Measured on the STS lower teeth grown to touch: Dice per tooth 0.942-1.000 as drawn,
    // 0.989-1.000 handed over (44, which ran into 43's root, 0.942 -> 0.996; 43 0.949 -> 0.995).
    let handed = if opts.hand_over {
        neck::hand_over(&mut best, &found)
    } else {
        BTreeMap::new()
    };
    // Re-measured on the corrected split: nothing lies beyond a cut whose pair's voxels the
    // hand-over left the same; a tooth that took voxels from a third may be cut anew.
    let found = if handed.is_empty() {
        found
    } else {
        neck::overruns(&mask, &best, &seeds)
    };
    let outside = flood::outside_footprint(&mask, &best, &placed, fit.up, opts.footprint_mm);
    let margin = opts.contested_margin_mm as f32;
    let (mut teeth, unreached_voxels) =
        flood::tally(&mask, &best, &plain, &seeds, &outside, margin);
    neck::count(&found, &mut teeth);
    for (fdi, h) in handed {
        let t = teeth.entry(fdi).or_default();
        t.handed_over_voxels = h.given;
        t.handed_over_to = h.to;
        t.received_voxels = h.received;
    }
    let refused = refuse(&fit, crowns, &mut teeth, opts);
    let labels = best
        .iter()
        .zip(&mask.inside)
        .map(|(&b, &inside)| {
            if inside && !refused.contains_key(&b) {
                b
            } else {
                0
            }
        })
        .collect();
    let split = JawSplit {
        jaw,
        label,
        fit,
        teeth,
        refused,
        unreached_voxels,
    };
    Ok((split, mask, labels))
}

/// Floods steered by the teeth's axis lines, each line fitted to the previous flood's teeth
/// (measured on the STS lower teeth grown to touch: the worst tooth's share of another tooth's
/// voxels 14.3 % after one, 10.7 % after three).
const AXIS_ROUNDS: usize = 3;

/// The flood of the mask from the crowns' seeds: first with step costs alone (sideways steps
/// about each crown's long axis costing more), then, while the long-axis prior is on, again
/// with each tooth's axis line fitted to the voxels the previous flood gave it. Returns the
/// plain flood and the final tooth per voxel.
fn grow(
    mask: &JawMask,
    placed: &BTreeMap<u8, TriMesh>,
    seeds: &[u8],
    up: glam::DVec3,
    opts: &SplitOptions,
) -> (flood::Flood, Vec<u8>) {
    let plain = flood::Growth::plain(flood::step_costs(mask, up, opts.lateral_weight));
    let mut growth = vec![plain; 256];
    let mut axes = BTreeMap::new();
    for (f, m) in placed {
        let axis = flood::crown_axis(m, up);
        growth[*f as usize] =
            flood::Growth::plain(flood::step_costs(mask, axis, opts.lateral_weight));
        axes.insert(*f, axis);
    }
    let first = flood::flood(mask, &growth, seeds);
    let mut best = first.best.clone();
    let rounds = if opts.axis_weight > 0.0 {
        AXIS_ROUNDS
    } else {
        0
    };
    for _ in 0..rounds {
        let mut pts: BTreeMap<u8, Vec<glam::DVec3>> = BTreeMap::new();
        for (id, &b) in best.iter().enumerate() {
            if b != 0 && mask.inside[id] {
                pts.entry(b).or_default().push(mask.world(id));
            }
        }
        for (t, axis) in &axes {
            if let Some(p) = pts.get(t) {
                let steps = growth[*t as usize].steps;
                growth[*t as usize] = flood::Growth::of_tooth(steps, p, *axis, opts.axis_weight);
            }
        }
        best = flood::flood(mask, &growth, seeds).best;
    }
    (first, best)
}

/// Refuses an arch fit whose evidence is weak, naming the measure and the likely cause.
fn check_fit(fit: &ArchFit, name: &str, o: &SplitOptions) -> Result<()> {
    let why = if fit.inlier_share < o.min_inlier_share {
        format!(
            "only {:.0}% of the crown points lie within {} mm of the mask (need {:.0}%)",
            100.0 * fit.inlier_share,
            o.inlier_mm,
            100.0 * o.min_inlier_share
        )
    } else if fit.rms_mm > o.max_rms_mm {
        format!(
            "residual {:.2} mm RMS (limit {} mm)",
            fit.rms_mm, o.max_rms_mm
        )
    } else if fit.runner_up_ratio < o.min_runner_up_ratio {
        format!(
            "ambiguous: another pose fits nearly as well (residual ratio {:.2}, need {})",
            fit.runner_up_ratio, o.min_runner_up_ratio
        )
    } else {
        return Ok(());
    };
    Err(Error::RegistrationRejected(format!(
        "the {name} IOS crowns do not fit the CBCT {name} teeth mask as one arch: {why} \
         [{:.0}% inliers, RMS {:.2} mm, runner-up ratio {:.2}] (is the IOS of the other jaw or \
         another patient, or are its labels wrong?)",
        100.0 * fit.inlier_share,
        fit.rms_mm,
        fit.runner_up_ratio
    )))
}

/// The teeth whose split cannot be trusted, with the reason; crowns without any voxel are
/// listed as teeth with an empty split.
fn refuse(
    fit: &ArchFit,
    crowns: &BTreeMap<u8, TriMesh>,
    teeth: &mut BTreeMap<u8, ToothSplit>,
    o: &SplitOptions,
) -> BTreeMap<u8, String> {
    let mut out = BTreeMap::new();
    for fdi in crowns.keys() {
        let t = teeth.entry(*fdi).or_default();
        let on = fit.crown_inlier_share.get(fdi).copied().unwrap_or(0.0);
        let why = if on < o.min_crown_inlier_share {
            Some(format!(
                "only {:.0}% of its IOS crown lies on the CBCT teeth mask (need {:.0}%): no CBCT \
                 tooth under the crown?",
                100.0 * on,
                100.0 * o.min_crown_inlier_share
            ))
        } else if t.seed_voxels == 0 {
            Some("its registered crown encloses no voxel of the teeth mask".into())
        } else if t.contested_share() > o.max_contested_share {
            Some(format!(
                "{:.0}% of its voxels are contested{} (limit {:.0}%): the mask gives no clear \
                 boundary between them",
                100.0 * t.contested_share(),
                t.contested_with
                    .map_or(String::new(), |w| format!(" with tooth {w}")),
                100.0 * o.max_contested_share
            ))
        } else if t.outside_share() > o.max_outside_share {
            Some(format!(
                "{:.0}% of its voxels lie beyond {} mm sideways of its crown (limit {:.0}%): a \
                 CBCT tooth without an IOS crown joined to it?",
                100.0 * t.outside_share(),
                o.footprint_mm,
                100.0 * o.max_outside_share
            ))
        } else if t.overrun_share() > o.max_overrun_share {
            let nb = t
                .overrun_into
                .map_or("a neighbour".to_string(), |w| format!("tooth {w}"));
            Some(format!(
                "{:.0}% of its voxels lie beyond the narrowest cut of the mask between its crown \
                 and {nb}'s (limit {:.0}%): its split ran through their contact into {nb} (whose \
                 split then lacks them)",
                100.0 * t.overrun_share(),
                100.0 * o.max_overrun_share
            ))
        } else {
            None
        };
        if let Some(w) = why {
            out.insert(*fdi, w);
        }
    }
    out
}

/// The per-tooth FDI volume: the input cropped to the union of the jaws' boxes, every voxel
/// set to its tooth (0 elsewhere).
fn assemble(vol: &LabelVolume, done: &[Done]) -> LabelVolume {
    let clamp = |v: i64, a: usize| v.clamp(0, vol.dims[a] as i64 - 1) as usize;
    let mut lo = [usize::MAX; 3];
    let mut hi = [0usize; 3];
    for (_, m, _) in done {
        for a in 0..3 {
            lo[a] = lo[a].min(clamp(m.lo[a], a));
            hi[a] = hi[a].max(clamp(m.lo[a] + m.dims[a] as i64 - 1, a));
        }
    }
    let mut out = vol.crop(lo, hi);
    out.labels.iter_mut().for_each(|l| *l = 0);
    for (_, m, labels) in done {
        for (id, &l) in labels.iter().enumerate() {
            if l == 0 {
                continue;
            }
            let [i, j, k] = m.ijk(id);
            let g = |x: usize, a: usize| (x as i64 + m.lo[a]) as usize - lo[a];
            let o = out.idx(g(i, 0), g(j, 1), g(k, 2));
            out.labels[o] = l as u16;
        }
    }
    out
}

#[cfg(test)]
mod tests;
