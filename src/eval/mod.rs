//! Registration accuracy over synthetic jaws: per-tooth target registration
//! error (TRE, [`crate::phantom::ToothTruth::tre`]) and the paper's surface distance (SD) for the
//! ablation CA / CA+CR / CA+CR+FR (paper preset) / default, next to the paper's Table 1(a).

use crate::arch::Jaw;
use crate::mesh::{TriMesh, split_by_vertex_labels};
use crate::phantom::{Phantom, PhantomOptions, Variant};
use crate::register::{RegisterOptions, Registration, register};
use crate::{Error, Result};
use std::collections::BTreeMap;
use std::fmt::Write as _;

pub mod foreign;
pub mod oracle;

/// Name of the oracle row: crown fit with known correspondences (threshold bias and distortion).
pub const ORACLE_ROW: &str = "oracle (crown, known correspondences)";
/// Name of the oracle row without the threshold bias (distortion only).
pub const ORACLE_NO_BIAS_ROW: &str = "oracle (crown, known correspondences, no bias)";

/// The paper's Table 1(a) SD (mm) for CA, CA+CR, CA+CR+FR.
pub const PAPER_TABLE_1A: [(&str, f64); 3] =
    [("CA", 1.1486), ("CA+CR", 0.2540), ("CA+CR+FR", 0.2318)];

/// The phantom cases of an evaluation: `n` seeds starting at `first_seed`, cycling through every
/// variant and both jaws (each (variant, jaw) pair once per 10 seeds).
pub fn cases(first_seed: u64, n: usize) -> Vec<PhantomOptions> {
    (0..n as u64)
        .map(|k| {
            let s = first_seed + k;
            PhantomOptions {
                seed: s,
                jaw: if (k / 5) % 2 == 0 {
                    Jaw::Upper
                } else {
                    Jaw::Lower
                },
                variant: Variant::ALL[(k % 5) as usize],
                ..PhantomOptions::default()
            }
        })
        .collect()
}

/// The phantom's true per-tooth transforms with the IOS frame as output frame (CBCT → IOS from
/// the truth, IOS → output the identity): fusion measured without registration error.
pub fn true_transforms(p: &Phantom) -> BTreeMap<u8, crate::fuse::ToothTransforms> {
    p.truth
        .teeth
        .iter()
        .map(|(&k, t)| {
            (
                k,
                crate::fuse::ToothTransforms {
                    cbct_to_output: t.cbct_to_ios,
                    ios_to_output: crate::Rigid::IDENTITY,
                },
            )
        })
        .collect()
}

/// The registration inputs a host would pass for a phantom: IOS crowns split from the labeled
/// jaw (label = FDI, 0 = gingiva dropped) and the CBCT teeth.
pub fn phantom_inputs(p: &Phantom) -> Result<(BTreeMap<u8, TriMesh>, BTreeMap<u8, TriMesh>)> {
    let labels = p
        .ios
        .vertex_labels
        .as_ref()
        .ok_or_else(|| Error::MissingData("phantom IOS mesh has no vertex labels".into()))?;
    let parts = split_by_vertex_labels(&p.ios.mesh, labels)?;
    let ios = parts
        .into_iter()
        .filter(|(l, s)| *l > 0 && *l < 256 && !s.mesh.triangles.is_empty())
        .map(|(l, s)| (l as u8, s.mesh))
        .collect();
    Ok((ios, p.cbct.clone()))
}

/// The four ablation configurations: CA, CA+CR, CA+CR+FR (paper), default.
pub fn ablation() -> Vec<(String, RegisterOptions)> {
    vec![
        ("CA".into(), RegisterOptions::paper().centroid_only()),
        ("CA+CR".into(), RegisterOptions::paper().without_fine()),
        ("CA+CR+FR (paper)".into(), RegisterOptions::paper()),
        ("default".into(), RegisterOptions::default()),
    ]
}

/// One registered tooth of one case under one configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct ToothResult {
    /// Phantom seed.
    pub seed: u64,
    /// Phantom variant.
    pub variant: Variant,
    /// Jaw.
    pub jaw: Jaw,
    /// FDI number.
    pub fdi: u8,
    /// Target registration error (mm).
    pub tre_mm: f64,
    /// Surface distance (mm).
    pub sd_mm: f64,
    /// Whether the report warned about this tooth.
    pub flagged: bool,
    /// Whether the tooth carries a simulated metal artefact.
    pub metal: bool,
}

/// Summary of one configuration over all cases.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Configuration name.
    pub name: String,
    /// Every tooth result.
    pub teeth: Vec<ToothResult>,
    /// Cases where registration failed, with the error.
    pub failures: Vec<(u64, String)>,
}

fn quantile(v: &[f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    let pos = q * (s.len() - 1) as f64;
    let (i, f) = (pos.floor() as usize, pos.fract());
    if i + 1 < s.len() {
        s[i] * (1.0 - f) + s[i + 1] * f
    } else {
        s[i]
    }
}

impl Row {
    /// TREs of all teeth.
    pub fn tres(&self) -> Vec<f64> {
        self.teeth.iter().map(|t| t.tre_mm).collect()
    }
    /// Median per-tooth TRE.
    pub fn tre_median(&self) -> f64 {
        quantile(&self.tres(), 0.5)
    }
    /// 95th percentile of per-tooth TRE.
    pub fn tre_p95(&self) -> f64 {
        quantile(&self.tres(), 0.95)
    }
    /// Worst per-tooth TRE.
    pub fn tre_max(&self) -> f64 {
        self.tres().into_iter().fold(0.0, f64::max)
    }
    /// Mean per-tooth SD (the paper's figure).
    pub fn sd_mean(&self) -> f64 {
        self.teeth.iter().map(|t| t.sd_mm).sum::<f64>() / self.teeth.len().max(1) as f64
    }
    /// Teeth with TRE > `mm` that the report did not flag.
    pub fn unflagged_above(&self, mm: f64) -> Vec<&ToothResult> {
        self.teeth
            .iter()
            .filter(|t| t.tre_mm > mm && !t.flagged)
            .collect()
    }
}

/// The evaluation table.
#[derive(Clone, Debug, PartialEq)]
pub struct EvalTable {
    /// Number of phantom cases.
    pub cases: usize,
    /// One row per configuration.
    pub rows: Vec<Row>,
}

/// Scores one registration against the phantom's truth.
pub fn score(p: &Phantom, seed: u64, variant: Variant, r: &Registration) -> Vec<ToothResult> {
    r.teeth
        .values()
        .filter_map(|t| {
            let truth = p.truth.teeth.get(&t.fdi)?;
            Some(ToothResult {
                seed,
                variant,
                jaw: p.jaw,
                fdi: t.fdi,
                tre_mm: truth.tre(&p.truth.world_to_cbct, &t.cbct_to_ios),
                sd_mm: t.sd_mm,
                flagged: !t.warnings.is_empty(),
                metal: truth.metal_artefact,
            })
        })
        .collect()
}

/// Runs every configuration on every case (single-threaded, deterministic), followed by the two
/// oracle rows ([`ORACLE_ROW`], [`ORACLE_NO_BIAS_ROW`]; see [`oracle`]; their SD is NaN).
pub fn run(cases: &[PhantomOptions], configs: &[(String, RegisterOptions)]) -> Result<EvalTable> {
    let mut rows: Vec<Row> = configs
        .iter()
        .map(|(n, _)| n.as_str())
        .chain([ORACLE_ROW, ORACLE_NO_BIAS_ROW])
        .map(|n| Row {
            name: n.to_string(),
            teeth: Vec::new(),
            failures: Vec::new(),
        })
        .collect();
    for c in cases {
        let p = Phantom::generate(c)?;
        let (ios, cbct) = phantom_inputs(&p)?;
        for (row, (_, o)) in rows.iter_mut().zip(configs) {
            match register(&ios, &cbct, o) {
                Ok(r) => row.teeth.extend(score(&p, c.seed, c.variant, &r)),
                Err(e) => row.failures.push((c.seed, e.to_string())),
            }
        }
        let n = configs.len();
        match oracle::oracle(&p, c) {
            Ok(o) => {
                for t in o.values() {
                    let truth = &p.truth.teeth[&t.fdi];
                    for (k, tre) in [(n, t.tre_mm), (n + 1, t.tre_no_bias_mm)] {
                        rows[k].teeth.push(ToothResult {
                            seed: c.seed,
                            variant: c.variant,
                            jaw: p.jaw,
                            fdi: t.fdi,
                            tre_mm: tre,
                            sd_mm: f64::NAN,
                            flagged: false,
                            metal: truth.metal_artefact,
                        });
                    }
                }
            }
            Err(e) => {
                for row in &mut rows[n..] {
                    row.failures.push((c.seed, e.to_string()));
                }
            }
        }
    }
    Ok(EvalTable {
        cases: cases.len(),
        rows,
    })
}

impl EvalTable {
    /// The row of a configuration by name.
    pub fn row(&self, name: &str) -> Option<&Row> {
        self.rows.iter().find(|r| r.name == name)
    }

    /// Markdown table: per configuration, per-tooth TRE median / p95 / max, mean SD, the paper's
    /// SD where it has one, flagged teeth and failures.
    pub fn to_markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "Registration over {} synthetic jaws (per-tooth TRE over the whole true tooth; SD = mean IOS→CBCT surface distance)\n",
            self.cases
        );
        let _ = writeln!(
            s,
            "| configuration | teeth | TRE median (mm) | TRE p95 (mm) | TRE max (mm) | SD mean (mm) | paper SD (mm) | flagged | >0.5 mm unflagged | failed cases |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
        for r in &self.rows {
            let paper = PAPER_TABLE_1A
                .iter()
                .find(|(n, _)| {
                    r.name.starts_with(n)
                        && (r.name.len() == n.len() || r.name.as_bytes()[n.len()] == b' ')
                })
                .map_or("–".to_string(), |(_, v)| format!("{v:.4}"));
            let sd = match r.sd_mean() {
                x if x.is_nan() => "–".to_string(),
                x => format!("{x:.4}"),
            };
            let _ = writeln!(
                s,
                "| {} | {} | {:.4} | {:.4} | {:.4} | {} | {} | {} | {} | {} |",
                r.name,
                r.teeth.len(),
                r.tre_median(),
                r.tre_p95(),
                r.tre_max(),
                sd,
                paper,
                r.teeth.iter().filter(|t| t.flagged).count(),
                r.unflagged_above(0.5).len(),
                r.failures.len()
            );
        }
        s
    }
}
