//! The one-call fuse: registration ([`crate::register`], paper section 2.2)
//! then crown removal and stitching of every tooth ([`crate::fuse`], paper section 2.3 and
//! Algorithm 1), with wall-clock timing and the report of the `toothfuse fuse` output contract
//! ([`report`]).
//!
//! A tooth whose fusion fails is listed in the report's `skipped` with the reason; the other
//! teeth are still delivered. Registration failure (fewer than three teeth in both modalities,
//! unusable meshes) is an error naming what is missing.

pub mod accuracy;
pub mod report;

pub use report::{PipelineReport, PipelineTooth};

use crate::Result;
use crate::fuse::{
    self, CutJaw, FuseOptions, FusedJaw, ToothTransforms, cut_jaw, ios_crowns, stitch_jaw,
};
use crate::mesh::{LabeledMesh, TriMesh};
use crate::register::{OutputFrame, Preset, RegisterOptions, Registration, register};
use std::collections::BTreeMap;
use std::time::Instant;

/// Options of the one-call fuse.
#[derive(Clone, Debug, PartialEq)]
pub struct PipelineOptions {
    /// Registration options (their `frame` is overridden by [`PipelineOptions::frame`]).
    pub register: RegisterOptions,
    /// Crown removal and stitching options.
    pub fuse: FuseOptions,
    /// Output frame of the fused meshes and the reported transforms.
    pub frame: OutputFrame,
}

impl Default for PipelineOptions {
    fn default() -> Self {
        Self::preset(Preset::Default)
    }
}

impl PipelineOptions {
    /// Both stages from one preset: `paper` (the paper faithfully) or `default` (measured better).
    pub fn preset(p: Preset) -> Self {
        let fp = match p {
            Preset::Paper => fuse::Preset::Paper,
            Preset::Default => fuse::Preset::Default,
        };
        PipelineOptions {
            register: RegisterOptions::preset(p),
            fuse: FuseOptions::preset(fp),
            frame: OutputFrame::Cbct,
        }
    }

    /// The same options with another output frame.
    pub fn with_frame(mut self, frame: OutputFrame) -> Self {
        self.frame = frame;
        self
    }
}

/// Wall-clock time per stage in milliseconds (not part of the deterministic result).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PipelineTiming {
    /// Registration.
    pub register_ms: f64,
    /// Crown removal of all teeth ([`cut_jaw`], wall time).
    pub cut_ms: f64,
    /// Stitching and assembly of all teeth ([`stitch_jaw`], wall time).
    pub stitch_ms: f64,
    /// Crown removal, stitching and assembly of all teeth: `cut_ms + stitch_ms`.
    pub fuse_ms: f64,
    /// Everything, including splitting the IOS jaw into crowns.
    pub total_ms: f64,
}

/// The result of [`fuse`](fn@fuse): the registration, the fused jaw and the timing.
#[derive(Clone, Debug)]
pub struct PipelineResult {
    /// Registration (per-tooth transforms into the output frame, SD, warnings, skipped teeth).
    pub registration: Registration,
    /// Fused teeth, the whole-jaw mesh with labels and sources, failed teeth.
    pub jaw: FusedJaw,
    /// Timing.
    pub timing: PipelineTiming,
}

/// The result of [`cut`]: the registration it used and the cut jaw, before stitching.
#[derive(Clone, Debug)]
pub struct PipelineCut {
    /// The registration whose transforms placed the teeth in the output frame.
    pub registration: Registration,
    /// Per tooth the repaired IOS crown and the cut CBCT root, failed teeth.
    pub jaw: CutJaw,
    /// Registration time carried over to the result (0 when the registration was given).
    pub register_ms: f64,
    /// Wall time of the cut (ms).
    pub cut_ms: f64,
}

/// The per-tooth transforms of a registration, as [`fuse::fuse_jaw`] takes them.
pub fn transforms_of(r: &Registration) -> BTreeMap<u8, ToothTransforms> {
    r.teeth
        .iter()
        .map(|(&f, t)| {
            (
                f,
                ToothTransforms {
                    cbct_to_output: t.cbct_to_output,
                    ios_to_output: t.ios_to_output,
                },
            )
        })
        .collect()
}

/// One-call fuse of a labeled IOS jaw (per-vertex or per-face FDI labels, 0 = gingiva) with
/// CBCT teeth (closed meshes by FDI, CBCT frame): register, then cut and stitch every tooth
/// present in both. Equals [`register`] on [`ios_crowns`] followed by [`fuse::fuse_jaw`] with the
/// registered transforms, bit for bit.
pub fn fuse(
    ios: &LabeledMesh,
    cbct: &BTreeMap<u8, TriMesh>,
    opts: &PipelineOptions,
) -> Result<PipelineResult> {
    let t0 = Instant::now();
    let crowns = ios_crowns(ios)?;
    run(t0, crowns, cbct, opts)
}

/// One-call fuse of per-tooth IOS crowns (open meshes by FDI, IOS frame) with CBCT teeth; see
/// [`fuse`](fn@fuse). The crowns are merged into one labeled mesh for [`fuse::fuse_jaw`] (vertices not used by a
/// face are dropped there).
pub fn fuse_crowns(
    crowns: &BTreeMap<u8, TriMesh>,
    cbct: &BTreeMap<u8, TriMesh>,
    opts: &PipelineOptions,
) -> Result<PipelineResult> {
    let t0 = Instant::now();
    let jaw = merge_crowns(crowns)?;
    let split = ios_crowns(&jaw)?;
    drop(jaw);
    run(t0, split, cbct, opts)
}

/// Cut and stitch only, with an existing registration (e.g. one made earlier by
/// [`crate::register::register`] with the same teeth): the second half of [`fuse_crowns`], for
/// hosts that register once and fuse with other fusion options. [`stitch`] of [`cut`]: the
/// result holds a copy of `registration` and `register_ms` = 0. Teeth without a registered
/// transform are reported failed.
pub fn fuse_crowns_registered(
    crowns: &BTreeMap<u8, TriMesh>,
    cbct: &BTreeMap<u8, TriMesh>,
    registration: &Registration,
    opts: &PipelineOptions,
) -> Result<PipelineResult> {
    Ok(stitch(&cut(crowns, cbct, registration, opts)?, opts))
}

/// The crown-removal stage with an existing registration: the crowns merged into one labeled
/// jaw, then [`cut_jaw`] with the registered transforms and `opts.fuse`. Teeth without a
/// registered transform are reported failed.
pub fn cut(
    crowns: &BTreeMap<u8, TriMesh>,
    cbct: &BTreeMap<u8, TriMesh>,
    registration: &Registration,
    opts: &PipelineOptions,
) -> Result<PipelineCut> {
    let t0 = Instant::now();
    let jaw = merge_crowns(crowns)?;
    let cut = cut_jaw(&jaw, cbct, &transforms_of(registration), &opts.fuse)?;
    Ok(PipelineCut {
        registration: registration.clone(),
        jaw: cut,
        register_ms: 0.0,
        cut_ms: ms(t0),
    })
}

/// The stitching stage: [`stitch_jaw`] of a [`cut`] with `opts.fuse` (its cut options are not
/// used). Timing: the cut's `register_ms` and `cut_ms`, the stitch's wall time, `total_ms` their
/// sum.
pub fn stitch(cut: &PipelineCut, opts: &PipelineOptions) -> PipelineResult {
    let t0 = Instant::now();
    let jaw = stitch_jaw(&cut.jaw, &opts.fuse);
    let stitch_ms = ms(t0);
    PipelineResult {
        registration: cut.registration.clone(),
        jaw,
        timing: PipelineTiming {
            register_ms: cut.register_ms,
            cut_ms: cut.cut_ms,
            stitch_ms,
            fuse_ms: cut.cut_ms + stitch_ms,
            total_ms: cut.register_ms + cut.cut_ms + stitch_ms,
        },
    }
}

/// Per-tooth crowns merged into one mesh with per-vertex FDI labels.
fn merge_crowns(crowns: &BTreeMap<u8, TriMesh>) -> Result<LabeledMesh> {
    let mut jaw = LabeledMesh::default();
    let mut labels = Vec::new();
    for (&fdi, m) in crowns {
        crate::arch::check_fdi(fdi as i32)?;
        jaw.mesh.append(m);
        labels.extend(std::iter::repeat_n(fdi as i32, m.positions.len()));
    }
    jaw.vertex_labels = Some(labels);
    Ok(jaw)
}

/// Registers the jaw's `crowns` ([`ios_crowns`]) and fuses them: the crowns are dropped once
/// cut and each cut tooth once stitched, so no stage's data outlives its use.
fn run(
    t0: Instant,
    crowns: BTreeMap<u8, TriMesh>,
    cbct: &BTreeMap<u8, TriMesh>,
    opts: &PipelineOptions,
) -> Result<PipelineResult> {
    let mut ro = opts.register.clone();
    ro.frame = opts.frame;
    let t1 = Instant::now();
    let registration = register(&crowns, cbct, &ro)?;
    let register_ms = ms(t1);
    let t2 = Instant::now();
    let cut = crate::fuse::cut_crowns(&crowns, cbct, &transforms_of(&registration), &opts.fuse);
    crate::progress::check(crate::progress::Stage::Cut)?;
    drop(crowns);
    let cut_ms = ms(t2);
    let t3 = Instant::now();
    let jaw = crate::fuse::stitch_jaw_owned(cut, &opts.fuse);
    crate::progress::check(crate::progress::Stage::Stitch)?;
    let stitch_ms = ms(t3);
    Ok(PipelineResult {
        registration,
        jaw,
        timing: PipelineTiming {
            register_ms,
            cut_ms,
            stitch_ms,
            fuse_ms: cut_ms + stitch_ms,
            total_ms: ms(t0),
        },
    })
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
