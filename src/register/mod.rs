//! IOS–CBCT registration, paper section 2.2: centroid alignment (eq. 1, [`centroid`]), coarse
//! point-to-plane ICP with one transform for all teeth (eq. 2, `coarse`) and sequential fine
//! registration over groups of three neighbouring teeth (eq. 3, `fine`); plus, beyond the paper
//! and each behind an option, robust weights and pair rejection ([`icp`]), closest points on
//! triangles ([`correspondence`]), a crown-only CBCT centroid, subsampling, a CBCT surface offset,
//! a smooth-drift joint fine stage (`drift`) and a plausibility guard.
//!
//! Entry point: [`register`]. Presets: [`RegisterOptions::paper`] (faithful) and
//! [`RegisterOptions::default`] (measured better on the synthetic jaw; see `eval`).

pub mod centroid;
mod coarse;
pub mod correspondence;
mod drift;
mod fine;
pub mod gate;
pub mod icp;
mod measure;
mod options;
mod report;
mod vertex_grid;

pub use gate::{GateReport, ToothEvidence};
pub use icp::{Convergence, RobustKernel, WeightOptions};
pub use options::{
    CentroidMode, Correspondence, DriftOptions, FineMode, GuardOptions, OutputFrame, Preset,
    RegisterOptions, StageOptions,
};
pub use report::{Report, SkippedReport, ToothReport};

use crate::mesh::TriMesh;
use crate::{Error, Result, Rigid};
use correspondence::SurfaceIndex;
use glam::DVec3;
use std::collections::BTreeMap;
use std::time::Instant;

/// Iterations, convergence and residuals of one ICP stage (for one tooth or the jaw).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageStats {
    /// ICP iterations run.
    pub iterations: usize,
    /// Whether the stage met its convergence threshold before the iteration cap.
    pub converged: bool,
    /// Weighted RMS point-to-plane residual at the last iteration (mm).
    pub rms_mm: f64,
    /// Fraction of pairs with non-zero weight at the last iteration.
    pub inlier_fraction: f64,
}

/// One registered tooth.
#[derive(Clone, Debug, PartialEq)]
pub struct ToothRegistration {
    /// FDI number.
    pub fdi: u8,
    /// Estimated CBCT → IOS mapping of this tooth.
    pub cbct_to_ios: Rigid,
    /// CBCT → output frame.
    pub cbct_to_output: Rigid,
    /// IOS → output frame.
    pub ios_to_output: Rigid,
    /// Paper's surface distance: mean distance from the registered IOS crown points (a stride
    /// sample of at most [`RegisterOptions::report_points`]) to the CBCT surface
    /// (point-to-triangle), mm.
    pub sd_mm: f64,
    /// RMS of the same distances, mm.
    pub rmse_mm: f64,
    /// Fraction of IOS points within `inlier_distance_mm` of the CBCT surface.
    pub inlier_fraction: f64,
    /// ICP iterations of the last stage that moved this tooth.
    pub iterations: usize,
    /// Whether that stage converged.
    pub converged: bool,
    /// Largest displacement of a CBCT vertex of this tooth between the coarse and the final
    /// mapping (mm): how far the fine stage moved the tooth, root included.
    pub fine_correction_mm: f64,
    /// Human-readable warnings (suspect result); empty when all checks pass.
    pub warnings: Vec<String>,
}

/// A tooth present in one modality only.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Skipped {
    /// FDI number.
    pub fdi: u8,
    /// Why it was not registered.
    pub reason: String,
}

/// Wall-clock time per stage, milliseconds (not part of the deterministic result).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timing {
    /// Index building and input checks.
    pub prepare_ms: f64,
    /// The registration gate ([`gate`]).
    pub gate_ms: f64,
    /// Centroid alignment.
    pub centroid_ms: f64,
    /// Coarse registration.
    pub coarse_ms: f64,
    /// Fine registration.
    pub fine_ms: f64,
    /// Surface distances and checks.
    pub report_ms: f64,
    /// Everything.
    pub total_ms: f64,
}

/// The result of [`register`].
#[derive(Clone, Debug, PartialEq)]
pub struct Registration {
    /// Output frame of `cbct_to_output` / `ios_to_output`.
    pub frame: OutputFrame,
    /// Registered teeth by FDI.
    pub teeth: BTreeMap<u8, ToothRegistration>,
    /// Teeth present in one modality only.
    pub skipped: Vec<Skipped>,
    /// The single CBCT → IOS transform after centroid alignment (or the caller's initial one).
    pub initial: Rigid,
    /// The single CBCT → IOS transform after coarse registration (= `initial` when skipped).
    pub coarse: Rigid,
    /// Estimated offset of the CBCT surface along its outward normal (mm; 0 unless estimated).
    pub cbct_offset_mm: f64,
    /// Jaw-level SD: mean over the measured IOS points of every tooth (at most
    /// [`RegisterOptions::report_points`] per tooth) of the distance to their CBCT tooth.
    pub sd_mm: f64,
    /// What the registration gate measured, and the findings accepted when
    /// [`RegisterOptions::accept_questionable`] is set (then [`Registration::questionable`]).
    pub gate: GateReport,
    /// Timing.
    pub timing: Timing,
}

/// Per-tooth working data.
pub(crate) struct ToothData {
    pub cbct: SurfaceIndex,
    pub ios_mesh: TriMesh,
    pub ios_points: Vec<DVec3>,
    pub ios_normals: Vec<DVec3>,
    pub ios_centroid: DVec3,
    /// The crown's occlusal direction (`gate::handedness::occlusal_of`; `None` for a closed
    /// crown).
    pub ios_occlusal: Option<DVec3>,
    pub ios_radius: f64,
    all: Vec<usize>,
    sub: Vec<usize>,
    warm: Vec<usize>,
    /// IOS points over which SD, RMSE and the inlier fraction are measured.
    report: Vec<usize>,
}

impl ToothData {
    /// IOS point indices of a resolution level.
    pub fn ios_indices(&self, level: Level) -> &[usize] {
        match level {
            Level::Full => &self.all,
            Level::Sub => &self.sub,
            Level::Warm => &self.warm,
        }
    }
}

/// Resolution of the IOS points an ICP pass iterates on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Level {
    /// At most [`RegisterOptions::warmup_points`] per tooth.
    Warm,
    /// At most [`RegisterOptions::subsample_points`] per tooth.
    Sub,
    /// Every usable point.
    Full,
}

/// One ICP pass of a stage: its resolution, iteration cap, and whether the stage's convergence
/// flag is judged on it (the fixed full-resolution refinement after a subsampled pass is not).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pass {
    pub level: Level,
    pub cap: usize,
    pub judged: bool,
}

/// The passes of a stage: the paper iterates at full resolution; subsampled stages optionally
/// start on the coarser warm-up sample (to convergence), then iterate on the subsample (to
/// convergence), then run `full_resolution_iterations` at full resolution.
pub(crate) fn passes(o: &StageOptions) -> Vec<Pass> {
    let cap = o.convergence.max_iterations;
    if !o.subsample {
        return vec![Pass {
            level: Level::Full,
            cap,
            judged: true,
        }];
    }
    let mut v = Vec::new();
    if o.warmup {
        v.push(Pass {
            level: Level::Warm,
            cap,
            judged: false,
        });
    }
    v.push(Pass {
        level: Level::Sub,
        cap,
        judged: true,
    });
    v.push(Pass {
        level: Level::Full,
        cap: o.full_resolution_iterations,
        judged: false,
    });
    v
}

/// Deterministic stride sample of at most `m` of `all` (all of them when `m` is large enough).
fn stride_sample(all: &[usize], m: usize) -> Vec<usize> {
    if m > 0 && all.len() > m {
        let stride = all.len().div_ceil(m);
        all.iter().copied().step_by(stride).collect()
    } else {
        all.to_vec()
    }
}

fn prepare(fdi: u8, ios: &TriMesh, cbct: &TriMesh, opts: &RegisterOptions) -> Result<ToothData> {
    let cbct_idx = SurfaceIndex::new(cbct)
        .map_err(|e| Error::MissingData(format!("CBCT mesh: {e}")).in_tooth(fdi))?;
    if ios.triangles.is_empty() {
        return Err(
            Error::MissingData("IOS crown: empty mesh (no triangles)".into()).in_tooth(fdi),
        );
    }
    if let Some(v) = ios.positions.iter().position(|p| !p.is_finite()) {
        return Err(Error::NonFinite { vertex: v }.in_tooth(fdi));
    }
    if let Some((f, &bad)) = ios.triangles.iter().enumerate().find_map(|(f, t)| {
        t.iter()
            .find(|&&v| v as usize >= ios.positions.len())
            .map(|b| (f, b))
    }) {
        return Err(Error::IndexOutOfBounds {
            face: f,
            index: bad,
            vertex_count: ios.positions.len(),
        }
        .in_tooth(fdi));
    }
    let normals = ios.vertex_normals();
    let all: Vec<usize> = (0..ios.positions.len())
        .filter(|&k| normals[k] != DVec3::ZERO)
        .collect();
    if all.len() < 3 {
        return Err(
            Error::MissingData("IOS crown has fewer than 3 usable vertices".into()).in_tooth(fdi),
        );
    }
    let sub = stride_sample(&all, opts.subsample_points);
    let report = stride_sample(&all, opts.report_points);
    let warm = stride_sample(&sub, opts.warmup_points);
    let c = crate::geom::centroid(&all.iter().map(|&k| ios.positions[k]).collect::<Vec<_>>())
        .unwrap_or(DVec3::ZERO);
    let r = all
        .iter()
        .map(|&k| ios.positions[k].distance(c))
        .fold(0.0, f64::max);
    Ok(ToothData {
        cbct: cbct_idx,
        ios_mesh: ios.clone(),
        ios_points: ios.positions.clone(),
        ios_normals: normals,
        ios_centroid: c,
        ios_occlusal: gate::handedness::occlusal_of(ios, c),
        ios_radius: r,
        all,
        sub,
        warm,
        report,
    })
}

/// Crown-only CBCT centroid: the area-weighted centroid of the CBCT faces lying within
/// `radius_mm` of the IOS crown once mapped by `t` (CBCT → IOS), paired with the IOS crown's
/// area-weighted centroid.
fn crown_centroids(d: &ToothData, t: &Rigid, radius_mm: f64) -> Option<(DVec3, DVec3)> {
    let m = d.cbct.mesh();
    let ios = SurfaceIndex::new(&d.ios_mesh).ok()?;
    let near: Vec<bool> = m
        .positions
        .iter()
        .map(|p| ios.closest_vertex(t.apply(*p)).distance <= radius_mm)
        .collect();
    let mut sum = DVec3::ZERO;
    let mut area = 0.0;
    for (f, tri) in m.triangles.iter().enumerate() {
        if tri.iter().all(|&v| near[v as usize]) {
            let [a, b, c] = m.corners(f);
            let w = 0.5 * (b - a).cross(c - a).length();
            sum += (a + b + c) * (w / 3.0);
            area += w;
        }
    }
    if area <= 0.0 {
        return None;
    }
    Some((sum / area, centroid::mesh_centroid(&d.ios_mesh, true)?))
}

/// Stage 1: the caller's transform, or the centroid alignment of eq. (1) (on crown centroids
/// with [`CentroidMode::CrownOnly`]). Fails with [`Error::MissingData`] under three teeth.
fn initial_alignment(
    teeth: &BTreeMap<u8, ToothData>,
    skipped: &[Skipped],
    opts: &RegisterOptions,
) -> Result<Rigid> {
    Ok(match opts.initial {
        Some(t) => t,
        None => {
            if teeth.len() < 3 {
                return Err(Error::MissingData(format!(
                    "registration needs at least 3 teeth present in both IOS and CBCT, found {} ({:?}); \
                 skipped: {}",
                    teeth.len(),
                    teeth.keys().collect::<Vec<_>>(),
                    skipped
                        .iter()
                        .map(|s| format!("{} ({})", s.fdi, s.reason))
                        .collect::<Vec<_>>()
                        .join("; ")
                )));
            }
            let area = opts.centroid != CentroidMode::WholeToothVertices;
            let cc: BTreeMap<u8, DVec3> = teeth
                .iter()
                .filter_map(|(f, d)| Some((*f, centroid::mesh_centroid(d.cbct.mesh(), area)?)))
                .collect();
            let ic: BTreeMap<u8, DVec3> = teeth
                .iter()
                .filter_map(|(f, d)| Some((*f, centroid::mesh_centroid(&d.ios_mesh, area)?)))
                .collect();
            let mut t = centroid::centroid_alignment(&cc, &ic)?;
            if let CentroidMode::CrownOnly { radius_mm, passes } = opts.centroid {
                for _ in 0..passes {
                    let (mut c2, mut i2) = (BTreeMap::new(), BTreeMap::new());
                    for (f, d) in teeth {
                        if let Some((c, i)) = crown_centroids(d, &t, radius_mm) {
                            c2.insert(*f, c);
                            i2.insert(*f, i);
                        }
                    }
                    match centroid::centroid_alignment(&c2, &i2) {
                        Ok(t2) => t = t2,
                        Err(_) => break,
                    }
                }
            }
            t
        }
    })
}

/// Registers CBCT teeth to IOS crowns (paper section 2.2 and the options beyond it).
///
/// `ios`: open crown meshes per FDI in the IOS frame; `cbct`: closed tooth meshes per FDI in the
/// CBCT frame. Teeth in one modality only are listed in [`Registration::skipped`]. Fails with
/// [`Error::MissingData`] when fewer than three teeth are in both or their centroids are collinear
/// (and no initial transform is given), and names the tooth for unusable meshes.
pub fn register(
    ios: &BTreeMap<u8, TriMesh>,
    cbct: &BTreeMap<u8, TriMesh>,
    opts: &RegisterOptions,
) -> Result<Registration> {
    opts.check()?;
    let t0 = Instant::now();
    let mut timing = Timing::default();
    use crate::progress::{Stage, step};
    crate::progress::start(Stage::Register, 5);
    let mut skipped = Vec::new();
    for f in ios.keys().chain(cbct.keys()) {
        crate::arch::check_fdi(*f as i32)?;
    }
    crate::units::check_jaw_scales(ios, cbct)?;
    let both = paired(ios, cbct, &mut skipped);
    if both.is_empty()
        && let Some(e) = gate::wrong_jaw(
            &ios.keys().copied().collect::<Vec<_>>(),
            &cbct.keys().copied().collect::<Vec<_>>(),
        )
    {
        return Err(e);
    }
    // Per-tooth preparation on several threads; the first error in FDI order is returned, as
    // a sequential loop would.
    let mut teeth = BTreeMap::new();
    for ((f, _, _), d) in both.iter().zip(crate::par::map_ordered(&both, |(f, i, c)| {
        prepare(*f, i, c, opts)
    })) {
        teeth.insert(*f, d?);
    }
    timing.prepare_ms = ms(t0);
    step(Stage::Register)?;
    let tg = Instant::now();
    let (mut gate_report, gate_warnings) = run_gate(&mut teeth, &mut skipped, opts)?;
    timing.gate_ms = ms(tg);
    step(Stage::Register)?;
    let order = crate::arch::arch_order(&teeth.keys().copied().collect::<Vec<_>>());

    // Stage 1: centroid alignment, eq. (1) (or the caller's transform).
    let t1 = Instant::now();
    let initial = initial_alignment(&teeth, &skipped, opts)?;
    timing.centroid_ms = ms(t1);

    // Stage 2: coarse registration, eq. (2).
    let t2 = Instant::now();
    let (coarse_t, offset, coarse_stats) = coarse_stage(&teeth, initial, opts);
    timing.coarse_ms = ms(t2);
    step(Stage::Register)?;

    // Stage 3: fine registration, eq. (3) or the smooth-drift model.
    let t3 = Instant::now();
    let (ios_to_cbct, fine_stats) = fine_stage(&teeth, &order, &coarse_t, offset, opts);
    timing.fine_ms = ms(t3);
    step(Stage::Register)?;

    // Report: SD per tooth, plausibility guard, warnings.
    let t4 = Instant::now();
    // Per tooth on several threads (each tooth's report depends on that tooth only); the jaw's
    // mean SD is summed in arch order afterwards, as before.
    let stages = measure::Stages {
        coarse: coarse_t,
        fine: fine_stats.as_ref(),
        coarse_stats,
    };
    let per_tooth = crate::par::map_ordered(&order, |f| {
        measure::tooth_result(
            *f,
            &teeth[f],
            ios_to_cbct[f],
            gate_warnings.get(f),
            &stages,
            opts,
        )
    });
    let mut out = BTreeMap::new();
    let (mut sd_sum, mut sd_n) = (0.0, 0usize);
    for (f, (dist_sum, n, reg)) in order.iter().zip(per_tooth) {
        sd_sum += dist_sum;
        sd_n += n;
        out.insert(*f, reg);
    }
    timing.report_ms = ms(t4);
    // Judged only where the teeth were fitted (a centroid alignment alone, as the ablation
    // runs it, is not expected to lay the crowns on their teeth).
    if opts.coarse.is_some()
        && let Some(e) = gate::registered_mismatch(&out)
    {
        if !opts.accept_questionable {
            return Err(e);
        }
        gate_report
            .accepted
            .push(format!("{e} (accepted as questionable)"));
    }
    step(Stage::Register)?;
    timing.total_ms = ms(t0);
    Ok(Registration {
        frame: opts.frame,
        teeth: out,
        skipped,
        initial,
        coarse: coarse_t,
        cbct_offset_mm: offset,
        sd_mm: sd_sum / sd_n.max(1) as f64,
        gate: gate_report,
        timing,
    })
}

/// The teeth in both modalities in FDI order; the others go to `skipped` with the reason.
fn paired<'a>(
    ios: &'a BTreeMap<u8, TriMesh>,
    cbct: &'a BTreeMap<u8, TriMesh>,
    skipped: &mut Vec<Skipped>,
) -> Vec<(u8, &'a TriMesh, &'a TriMesh)> {
    let mut all_fdi: Vec<u8> = ios.keys().chain(cbct.keys()).copied().collect();
    all_fdi.sort_unstable();
    all_fdi.dedup();
    let mut both = Vec::new();
    for f in all_fdi {
        match (ios.get(&f), cbct.get(&f)) {
            (Some(i), Some(c)) => both.push((f, i, c)),
            (Some(_), None) => skipped.push(Skipped {
                fdi: f,
                reason: "present in the IOS only (no CBCT tooth): nothing to register it to".into(),
            }),
            (None, _) => skipped.push(Skipped {
                fdi: f,
                reason: "present in the CBCT only (no IOS crown): no crown to register".into(),
            }),
        }
    }
    both
}

/// Stage 2, eq. (2): the jaw-wide coarse transform from `initial`, the CBCT surface offset it
/// fits and its statistics (`initial`, no offset and none without a coarse stage).
fn coarse_stage(
    teeth: &BTreeMap<u8, ToothData>,
    initial: Rigid,
    opts: &RegisterOptions,
) -> (Rigid, f64, Option<StageStats>) {
    match &opts.coarse {
        Some(o) => {
            let r = match opts.coarse_restart_fit_mm {
                Some(bad) => coarse::coarse_with_restarts(teeth, initial, o, bad),
                None => coarse::coarse(teeth, initial, o),
            };
            (r.transform, r.offset, Some(r.stats))
        }
        None => (initial, 0.0, None),
    }
}

/// Stage 3: each tooth's IOS → CBCT transform by eq. (3) or the smooth-drift model (the
/// coarse transform's inverse for every tooth without a fine stage), with the statistics.
fn fine_stage(
    teeth: &BTreeMap<u8, ToothData>,
    order: &[u8],
    coarse_t: &Rigid,
    offset: f64,
    opts: &RegisterOptions,
) -> (BTreeMap<u8, Rigid>, Option<BTreeMap<u8, StageStats>>) {
    match &opts.fine {
        FineMode::None => {
            let coarse_inv = coarse_t.inverse();
            (order.iter().map(|&f| (f, coarse_inv)).collect(), None)
        }
        FineMode::Sequential(o) => {
            let (m, s) = fine::fine_sequential(teeth, order, coarse_t, offset, o);
            (m, Some(s))
        }
        FineMode::SmoothDrift(o, d) => {
            let (m, s) = drift::fine_smooth(teeth, order, coarse_t, offset, o, d);
            (m, Some(s))
        }
    }
}

/// Runs the registration gate on the prepared teeth (three or more): a jaw-level finding is
/// returned as the error, misnumbered teeth move from `teeth` to `skipped`; with
/// [`RegisterOptions::accept_questionable`] both are kept as findings of the report and warnings of
/// the teeth instead.
fn run_gate(
    teeth: &mut BTreeMap<u8, ToothData>,
    skipped: &mut Vec<Skipped>,
    opts: &RegisterOptions,
) -> Result<(GateReport, BTreeMap<u8, String>)> {
    let mut warnings = BTreeMap::new();
    if teeth.len() < 3 {
        return Ok((GateReport::default(), warnings));
    }
    let v = gate::assess(teeth);
    let mut report = v.report;
    if let Some(e) = v.jaw {
        if !opts.accept_questionable {
            return Err(e);
        }
        report
            .accepted
            .push(format!("{e} (accepted as questionable)"));
    }
    for (f, why) in v.skip {
        if opts.accept_questionable {
            report
                .accepted
                .push(format!("tooth {f}: {why} (accepted as questionable)"));
            warnings.insert(f, format!("{why} (accepted as questionable)"));
        } else {
            teeth.remove(&f);
            skipped.push(Skipped {
                fdi: f,
                reason: why,
            });
        }
    }
    skipped.sort_by_key(|s| s.fdi);
    Ok((report, warnings))
}

impl Registration {
    /// Whether the result was accepted although the gate found the data questionable.
    pub fn questionable(&self) -> bool {
        !self.gate.accepted.is_empty()
    }
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

#[cfg(test)]
mod tests;
