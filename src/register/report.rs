//! The registration report in the JSON form shared with `toothfuse fuse`:
//! `{"frame", "teeth": [{"fdi", "cbct_to_output", "ios_to_output", "sd_mm", "rmse_mm",
//! "inlier_fraction", "iterations", "converged", "warnings"}], "skipped": [{"fdi", "reason"}],
//! "timing_ms": {...}}` (transforms as row-major 4×4, 16 numbers).

use super::Registration;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One tooth in the report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ToothReport {
    /// FDI number.
    pub fdi: u8,
    /// CBCT → output frame, row-major 4×4.
    pub cbct_to_output: Vec<f64>,
    /// IOS → output frame, row-major 4×4.
    pub ios_to_output: Vec<f64>,
    /// Surface distance (paper), mm.
    pub sd_mm: f64,
    /// RMS surface distance, mm.
    pub rmse_mm: f64,
    /// Fraction of IOS points near the CBCT surface.
    pub inlier_fraction: f64,
    /// ICP iterations.
    pub iterations: usize,
    /// Convergence flag.
    pub converged: bool,
    /// Warnings.
    pub warnings: Vec<String>,
}

/// A skipped tooth in the report.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SkippedReport {
    /// FDI number.
    pub fdi: u8,
    /// Why it was skipped.
    pub reason: String,
}

/// The whole report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// `"cbct"` or `"ios"`.
    pub frame: String,
    /// Registered teeth in FDI order.
    pub teeth: Vec<ToothReport>,
    /// Teeth present in one modality only.
    pub skipped: Vec<SkippedReport>,
    /// Jaw-level surface distance, mm.
    pub sd_mm: f64,
    /// Stage timings (ms), keyed by stage name.
    pub timing_ms: BTreeMap<String, f64>,
    /// Whether the registration was accepted although the gate found the data questionable
    /// (only with `accept_questionable`).
    #[serde(default)]
    pub questionable: bool,
    /// The gate's findings accepted with `accept_questionable` (empty otherwise).
    #[serde(default)]
    pub questionable_findings: Vec<String>,
}

impl Registration {
    /// The report structure (serialise with [`Registration::to_json`]).
    pub fn report(&self) -> Report {
        let t = &self.timing;
        let timing_ms = [
            ("prepare", t.prepare_ms),
            ("gate", t.gate_ms),
            ("centroid", t.centroid_ms),
            ("coarse", t.coarse_ms),
            ("fine", t.fine_ms),
            ("report", t.report_ms),
            ("total", t.total_ms),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
        Report {
            frame: self.frame.name().to_string(),
            teeth: self
                .teeth
                .values()
                .map(|r| ToothReport {
                    fdi: r.fdi,
                    cbct_to_output: r.cbct_to_output.to_row_major().to_vec(),
                    ios_to_output: r.ios_to_output.to_row_major().to_vec(),
                    sd_mm: r.sd_mm,
                    rmse_mm: r.rmse_mm,
                    inlier_fraction: r.inlier_fraction,
                    iterations: r.iterations,
                    converged: r.converged,
                    warnings: r.warnings.clone(),
                })
                .collect(),
            skipped: self
                .skipped
                .iter()
                .map(|s| SkippedReport {
                    fdi: s.fdi,
                    reason: s.reason.clone(),
                })
                .collect(),
            sd_mm: self.sd_mm,
            timing_ms,
            questionable: self.questionable(),
            questionable_findings: self.gate.accepted.clone(),
        }
    }

    /// The report as pretty-printed JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(&self.report())
            .unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }
}
