//! The report of the `toothfuse fuse` output contract:
//! `{"frame", "teeth": [{"fdi", "cbct_to_output", "ios_to_output", "sd_mm", "rmse_mm",
//! "watertight", "warnings", ...}], "skipped": [{"fdi", "reason"}], "timing_ms": {"register",
//! "cut", "stitch", "total", ...}}`. Each tooth also carries the registration fields of
//! [`crate::register::ToothReport`] (inlier fraction, iterations, convergence), the fused
//! mesh's [`ToothQuality`], and the tooth's band builds.

use super::PipelineResult;
use crate::fuse::ToothQuality;
use crate::register::{SkippedReport, ToothReport};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One fused tooth in the report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PipelineTooth {
    /// The registration fields (`fdi`, transforms, `sd_mm`, `rmse_mm`, ..., `warnings`: the
    /// registration's and the fusion's warnings).
    #[serde(flatten)]
    pub registration: ToothReport,
    /// Closed, manifold, one component, positive volume, no degenerate face (and no
    /// self-intersection when checked).
    pub watertight: bool,
    /// The fused mesh's quality report (absent when read back from a file that lacks it).
    #[serde(default, skip_deserializing)]
    pub quality: Option<ToothQuality>,
    /// Band builds made for the tooth ([`crate::fuse::FusedTooth::band_builds`]: 1 for a clean
    /// crown, several where the margin fringe was trimmed and the band built again).
    #[serde(default)]
    pub band_builds: usize,
    /// Band builds asked for again with inputs built before, reused instead of made
    /// ([`crate::fuse::FusedTooth::band_builds_reused`]).
    #[serde(default)]
    pub band_builds_reused: usize,
}

/// The whole report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PipelineReport {
    /// `"cbct"` or `"ios"`.
    pub frame: String,
    /// Fused teeth in FDI order.
    pub teeth: Vec<PipelineTooth>,
    /// Teeth not fused, with the reason (one modality only, or fusion failed).
    pub skipped: Vec<SkippedReport>,
    /// Jaw-level surface distance of the registration, mm.
    pub sd_mm: f64,
    /// Stage timings (ms): `register`, `cut`, `stitch`, `total`, and `fuse` (= cut + stitch).
    pub timing_ms: BTreeMap<String, f64>,
    /// How to read `timing_ms`.
    pub timing_note: String,
    /// Whether the result was accepted although the registration gate found the data
    /// questionable (only with `accept_questionable`).
    pub questionable: bool,
    /// The gate's findings accepted with `accept_questionable` (empty otherwise).
    pub questionable_findings: Vec<String>,
}

impl PipelineResult {
    /// The report of the output contract.
    pub fn report(&self) -> PipelineReport {
        let reg = self.registration.report();
        let mut teeth = Vec::new();
        let mut skipped = reg.skipped.clone();
        for mut t in reg.teeth {
            match self.jaw.teeth.get(&t.fdi) {
                Some(f) => {
                    t.warnings.extend(f.warnings.iter().cloned());
                    teeth.push(PipelineTooth {
                        registration: t,
                        watertight: f.quality.watertight(),
                        quality: Some(f.quality.clone()),
                        band_builds: f.band_builds,
                        band_builds_reused: f.band_builds_reused,
                    });
                }
                None => {
                    let reason = self
                        .jaw
                        .failed
                        .iter()
                        .find(|(k, _)| *k == t.fdi)
                        .map_or("not fused".to_string(), |(_, e)| {
                            format!("fusion failed: {e}")
                        });
                    skipped.push(SkippedReport { fdi: t.fdi, reason });
                }
            }
        }
        skipped.sort_by_key(|s| s.fdi);
        let tm = &self.timing;
        let timing_ms = [
            ("register", tm.register_ms),
            ("cut", tm.cut_ms),
            ("stitch", tm.stitch_ms),
            ("fuse", tm.fuse_ms),
            ("total", tm.total_ms),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
        PipelineReport {
            frame: reg.frame,
            teeth,
            skipped,
            sd_mm: reg.sd_mm,
            timing_ms,
            timing_note: "wall time of each stage; fuse = cut + stitch; within a stage the teeth \
                          are processed in parallel"
                .into(),
            questionable: reg.questionable,
            questionable_findings: reg.questionable_findings,
        }
    }

    /// The report as pretty-printed JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(&self.report())
            .unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }
}
