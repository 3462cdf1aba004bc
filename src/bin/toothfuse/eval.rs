//! `toothfuse eval`: the registration ablation (CA / CA+CR / CA+CR+FR (paper) / default) over
//! synthetic jaws covering every variant and both jaws, and the fusion accuracy of the one-call
//! fuse (default preset) on the same jaws, as Markdown.

use crate::input::create_parent;
use anyhow::{Context, Result, bail};
use clap::Args;
use std::fmt::Write as _;
use std::path::PathBuf;
use toothfuse::eval::{ablation, cases, run as run_ablation};
use toothfuse::phantom::{IosExport, Phantom};
use toothfuse::pipeline::{self, PipelineOptions, accuracy::fusion_accuracy};

/// `toothfuse eval` arguments.
#[derive(Args, Debug)]
pub struct EvalArgs {
    /// Seeds as an inclusive range `a..b` (at least 20 cover every variant and both jaws twice).
    #[arg(long, default_value = "1..20")]
    seeds: String,
    /// Also write the Markdown to this file.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Skip the fusion accuracy table (registration only).
    #[arg(long)]
    no_fusion: bool,
    /// IOS export of every jaw (see `toothfuse demo --help`).
    #[arg(long, default_value = "clean", value_parser = ["clean", "rough", "coarse", "dense2", "dense4", "subdivided"])]
    ios_export: String,
}

fn parse_seeds(s: &str) -> Result<(u64, usize)> {
    let (a, b) = s
        .split_once("..")
        .with_context(|| format!("--seeds {s:?}: expected a range like 1..20"))?;
    let a: u64 = a.trim().parse().with_context(|| format!("--seeds {s:?}"))?;
    let b: u64 = b
        .trim_start_matches('=')
        .trim()
        .parse()
        .with_context(|| format!("--seeds {s:?}"))?;
    if b < a {
        bail!("--seeds {s:?}: empty range");
    }
    Ok((a, (b - a + 1) as usize))
}

/// Runs `toothfuse eval`.
pub fn run(a: &EvalArgs) -> Result<()> {
    let (first, n) = parse_seeds(&a.seeds)?;
    let Some(export) = IosExport::from_name(&a.ios_export) else {
        bail!("unknown IOS export {:?}", a.ios_export);
    };
    let mut cs = cases(first, n);
    for c in &mut cs {
        c.realism.ios.rough = export.roughness();
    }
    let mut md = run_ablation(&cs, &ablation())?.to_markdown();
    if !a.no_fusion {
        md.push('\n');
        md.push_str(&fusion_table(&cs)?);
    }
    print!("{md}");
    if let Some(out) = &a.out {
        create_parent(out)?;
        std::fs::write(out, &md).with_context(|| format!("writing {}", out.display()))?;
        println!("wrote {}", out.display());
    }
    Ok(())
}

fn fusion_table(cs: &[toothfuse::phantom::PhantomOptions]) -> Result<String> {
    let opts = PipelineOptions::default();
    let (mut crown, mut cbct, mut band_max, mut min_angle) =
        (Vec::new(), Vec::new(), 0.0f64, f64::INFINITY);
    let (mut fused, mut watertight, mut skipped_failed, mut ratio_min) =
        (0usize, 0usize, 0usize, f64::INFINITY);
    for c in cs {
        let p = Phantom::generate(c)?;
        let r = pipeline::fuse(&p.ios, &p.cbct, &opts)
            .with_context(|| format!("fusing seed {}", c.seed))?;
        skipped_failed += r.jaw.failed.len();
        watertight += r
            .jaw
            .teeth
            .values()
            .filter(|t| t.quality.watertight())
            .count();
        for acc in fusion_accuracy(&p, &r).values() {
            fused += 1;
            crown.push(acc.crown_mean_mm);
            cbct.push(acc.cbct_crown_mean_mm);
            ratio_min = ratio_min.min(acc.cbct_crown_mean_mm / acc.crown_mean_mm.max(1e-12));
            band_max = band_max.max(acc.band_max_mm);
            min_angle = min_angle.min(acc.band_min_angle_deg);
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Fusion over {} synthetic jaws (default preset, registered transforms, output frame = CBCT; distances to the true surface)\n",
        cs.len()
    );
    let _ = writeln!(
        s,
        "| fused teeth | watertight | failed | fused crown mean (mm): mean / max | CBCT-only crown mean (mm): mean / max | min CBCT/fused ratio | band max deviation (mm) | min band angle (°) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    let _ = writeln!(
        s,
        "| {fused} | {watertight} | {skipped_failed} | {:.4} / {:.4} | {:.4} / {:.4} | {:.1} | {:.3} | {:.1} |",
        mean(&crown),
        max(&crown),
        mean(&cbct),
        max(&cbct),
        ratio_min,
        band_max,
        min_angle
    );
    Ok(s)
}
