//! The session's results: registration, the cut and stitch stages, the one-call fuse, and the
//! notes (warnings, skipped teeth) the C ABI hands out as borrowed strings.
//!
//! Stages: [`Session::register`] → [`Session::cut`] → [`Session::stitch`], or
//! [`Session::fuse_registered`] (cut + stitch) after a registration, or [`Session::fuse`]
//! (all three in one call). Any change of the held teeth drops every result; a new registration
//! or one-call fuse drops the cut and earlier fused results.

use super::{Modality, Session};
use crate::fuse::CutJaw;
use crate::pipeline::{self, PipelineCut, PipelineOptions, PipelineResult};
use crate::register::{Registration, register};
use crate::{Error, Result};
use std::collections::BTreeMap;
use std::ffi::CString;

/// NUL-terminated copies of the result messages, for borrowed `const char *` views in the C ABI:
/// per tooth, the registration's then the fusion's warnings; the skipped teeth with the reason.
#[derive(Clone, Debug, Default)]
pub struct Notes {
    /// Warnings per registered tooth.
    pub warnings: BTreeMap<u8, Vec<CString>>,
    /// Teeth not registered or not fused, with the reason, in FDI order.
    pub skipped: Vec<(u8, CString)>,
}

pub(super) fn c_string(s: &str) -> CString {
    CString::new(s.bytes().filter(|&b| b != 0).collect::<Vec<u8>>()).unwrap_or_default()
}

impl Notes {
    fn of_registration(r: &Registration) -> Self {
        Notes {
            warnings: r
                .teeth
                .iter()
                .map(|(&f, t)| (f, t.warnings.iter().map(|w| c_string(w)).collect()))
                .collect(),
            skipped: r
                .skipped
                .iter()
                .map(|k| (k.fdi, c_string(&k.reason)))
                .collect(),
        }
    }

    fn of_cut(c: &PipelineCut) -> Self {
        let mut n = Self::of_registration(&c.registration);
        for (fdi, t) in &c.jaw.teeth {
            n.warnings
                .entry(*fdi)
                .or_default()
                .extend(t.warnings().iter().map(|w| c_string(w)));
        }
        n.skipped.extend(
            c.jaw
                .failed
                .iter()
                .map(|(k, e)| (*k, c_string(&format!("cut failed: {e}")))),
        );
        n.skipped.sort_by_key(|k| k.0);
        n
    }

    fn of_fused(f: &PipelineResult) -> Self {
        let rep = f.report();
        Notes {
            warnings: rep
                .teeth
                .iter()
                .map(|t| {
                    let r = &t.registration;
                    (r.fdi, r.warnings.iter().map(|w| c_string(w)).collect())
                })
                .chain(
                    f.registration
                        .teeth
                        .iter()
                        .filter(|(k, _)| !f.jaw.teeth.contains_key(k))
                        .map(|(&k, t)| (k, t.warnings.iter().map(|w| c_string(w)).collect())),
                )
                .collect(),
            skipped: rep
                .skipped
                .iter()
                .map(|k| (k.fdi, c_string(&k.reason)))
                .collect(),
        }
    }
}

/// The result of [`Session::fuse`]: the pipeline's result and its report as JSON.
#[derive(Clone, Debug)]
pub struct Fused {
    /// Registration, fused jaw and timing.
    pub result: PipelineResult,
    /// The report of the `toothfuse fuse` output contract, pretty-printed JSON.
    pub report_json: String,
}

impl Session {
    /// Registers the held CBCT teeth to the held IOS crowns with `opts.register` (its frame set
    /// to `opts.frame`) and keeps the result, replacing any earlier registration and dropping
    /// earlier fusion results. Fails with `MissingData` when fewer than three teeth are in both
    /// modalities; on failure the session keeps its previous results.
    pub fn register(&mut self, opts: &PipelineOptions) -> Result<&Registration> {
        let mut ro = opts.register.clone();
        ro.frame = opts.frame;
        let r = register(
            &self.meshes(Modality::Ios),
            &self.meshes(Modality::Cbct),
            &ro,
        )?;
        self.fused = None;
        self.cut = None;
        self.notes = Notes::of_registration(&r);
        self.add_split_notes();
        Ok(self.registration.insert(r))
    }

    /// One-call fuse: always registers anew with `opts` (so the transforms and the fused meshes
    /// come from the same options), then cuts and stitches every tooth present in both
    /// modalities ([`pipeline::fuse_crowns`]). A tooth whose fusion fails is listed as skipped
    /// with the reason; the others are delivered. On failure the session keeps its previous
    /// results.
    pub fn fuse(&mut self, opts: &PipelineOptions) -> Result<&Fused> {
        let result = pipeline::fuse_crowns(
            &self.meshes(Modality::Ios),
            &self.meshes(Modality::Cbct),
            opts,
        )?;
        let report_json = report_json_of(&result)?;
        self.cut = None;
        Ok(self.keep_fused(result, report_json, true))
    }

    /// Cut and stitch only, with the session's last registration ([`Session::register`] or an
    /// earlier [`Session::fuse`]) and the fusion options of `opts` (its registration options are
    /// not used): for hosts that register once and fuse again with other options. Equals
    /// [`Session::cut`] then [`Session::stitch`] (the cut is kept). `WrongState` without a
    /// registration; on failure the session keeps its previous results.
    pub fn fuse_registered(&mut self, opts: &PipelineOptions) -> Result<&Fused> {
        let cut = self.make_cut(opts)?;
        let result = pipeline::stitch(&cut, opts);
        crate::progress::check(crate::progress::Stage::Stitch)?;
        let report_json = report_json_of(&result)?;
        self.cut = Some(cut);
        Ok(self.keep_fused(result, report_json, false))
    }

    fn make_cut(&self, opts: &PipelineOptions) -> Result<PipelineCut> {
        pipeline::cut(
            &self.meshes(Modality::Ios),
            &self.meshes(Modality::Cbct),
            self.registration()?,
            opts,
        )
    }

    /// The crown-removal stage with the session's last registration: every tooth present in both
    /// modalities is repaired, moved into the output frame and its CBCT crown cut off along the
    /// IOS margin (`opts.fuse.cut`; registration options unused). The cut is kept for
    /// [`Session::stitch`], replacing an earlier one; fused results are kept. A tooth whose cut
    /// fails is listed as skipped (in [`Session::notes`]) with the reason. `WrongState` without a
    /// registration; on failure the session keeps its previous results.
    pub fn cut(&mut self, opts: &PipelineOptions) -> Result<&CutJaw> {
        let cut = self.make_cut(opts)?;
        self.notes = Notes::of_cut(&cut);
        self.add_split_notes();
        Ok(&self.cut.insert(cut).jaw)
    }

    /// The stitching stage on the held cut ([`Session::cut`]) with `opts.fuse` (its cut options
    /// are unused: the cut is done); the result replaces earlier fused results and the cut stays,
    /// so it can be stitched again with other options. [`Session::fuse_registered`] gives the same
    /// meshes bit for bit. `WrongState` without a cut; on failure the session keeps its previous
    /// results.
    pub fn stitch(&mut self, opts: &PipelineOptions) -> Result<&Fused> {
        let cut = self.cut.as_ref().ok_or_else(|| {
            Error::WrongState(
                "no cut: call cut after register (the cut is dropped when the teeth change or \
                 on a new register or fuse)"
                    .into(),
            )
        })?;
        let result = pipeline::stitch(cut, opts);
        crate::progress::check(crate::progress::Stage::Stitch)?;
        let report_json = report_json_of(&result)?;
        Ok(self.keep_fused(result, report_json, false))
    }

    /// The held cut ([`Session::cut`]); `WrongState` if none.
    pub fn cut_result(&self) -> Result<&PipelineCut> {
        self.cut.as_ref().ok_or_else(|| {
            Error::WrongState(
                "no cut: call cut after register and after the last change of teeth".into(),
            )
        })
    }

    /// Keeps a fusion result (with its report JSON and notes), and its registration when
    /// `new_registration`.
    fn keep_fused(
        &mut self,
        result: PipelineResult,
        report_json: String,
        new_registration: bool,
    ) -> &Fused {
        if new_registration {
            self.registration = Some(result.registration.clone());
        }
        self.notes = Notes::of_fused(&result);
        self.add_split_notes();
        self.fused.insert(Fused {
            result,
            report_json,
        })
    }

    /// The last registration (by [`Session::register`] or [`Session::fuse`]); `WrongState` if
    /// none since the teeth last changed.
    pub fn registration(&self) -> Result<&Registration> {
        self.registration.as_ref().ok_or_else(|| {
            Error::WrongState(
                "no registration: call register (or fuse) after the last change of teeth".into(),
            )
        })
    }

    /// The report JSON of the last result: the fuse report (`toothfuse fuse` contract) after
    /// [`Session::fuse`], else the registration report; `WrongState` when there is neither.
    pub fn report_json(&self) -> Result<String> {
        match (&self.fused, &self.registration) {
            (Some(f), _) => Ok(f.report_json.clone()),
            (None, Some(r)) => Ok(r.to_json()),
            (None, None) => Err(Error::WrongState(
                "no result: call register or fuse after the last change of teeth".into(),
            )),
        }
    }

    /// The last fusion result; `WrongState` if none since the teeth last changed.
    pub fn fused(&self) -> Result<&Fused> {
        self.fused.as_ref().ok_or_else(|| {
            Error::WrongState("no fused result: call fuse after the last change of teeth".into())
        })
    }
}

/// The report JSON of a result; an error if it cannot be serialised.
fn report_json_of(result: &PipelineResult) -> Result<String> {
    serde_json::to_string_pretty(&result.report())
        .map_err(|e| Error::InvalidArgument(format!("report serialisation failed: {e}")))
}
