//! `toothfuse register`: registration only; writes the report JSON. Without inputs it runs on the
//! synthetic jaw and prints per-tooth accuracy against its truth.

use crate::demo::PhantomArgs;
use crate::input::{InputArgs, Ios, create_parent};
use anyhow::{Context, Result};
use clap::Args;
use std::fmt::Write as _;
use std::path::PathBuf;
use toothfuse::fuse::ios_crowns;
use toothfuse::register::{Registration, register};

/// `toothfuse register` arguments.
#[derive(Args, Debug)]
pub struct RegisterArgs {
    #[command(flatten)]
    input: InputArgs,
    #[command(flatten)]
    phantom: PhantomArgs,
    /// Write the report JSON here (default: print it when inputs are given).
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Runs `toothfuse register`.
pub fn run(a: &RegisterArgs) -> Result<()> {
    let mut opts = a.input.options().register;
    opts.frame = a.input.options().frame;
    let r = match a.input.read()? {
        Some((ios, cbct, _split)) => {
            let crowns = match ios {
                Ios::Jaw(lm) => ios_crowns(&lm).context("splitting the IOS jaw into crowns")?,
                Ios::Crowns(c) => c,
            };
            let r = register(&crowns, &cbct, &opts)?;
            if a.out.is_none() {
                // JSON alone on stdout (for scripts), the table on stderr.
                eprint!("{}", table(&r, None));
                println!("{}", r.to_json());
            } else {
                print!("{}", table(&r, None));
            }
            r
        }
        None => {
            let ph = a.phantom.generate()?;
            let crowns = ph.ios_crowns();
            let r = register(&crowns, &ph.cbct, &opts)?;
            println!(
                "synthetic jaw: seed {}, {} jaw, variant {}, preset {}",
                a.phantom.seed, a.phantom.jaw, a.phantom.variant, a.input.preset
            );
            print!("{}", table(&r, Some(&ph)));
            r
        }
    };
    if let Some(out) = &a.out {
        create_parent(out)?;
        std::fs::write(out, r.to_json()).with_context(|| format!("writing {}", out.display()))?;
        println!("wrote {}", out.display());
    }
    Ok(())
}

fn table(r: &Registration, truth: Option<&toothfuse::phantom::Phantom>) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| tooth | TRE (mm) | SD (mm) | RMSE (mm) | inliers | iterations | converged | warnings |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    let mut tres = Vec::new();
    for t in r.teeth.values() {
        let tre = truth.and_then(|p| {
            let tt = p.truth.teeth.get(&t.fdi)?;
            Some(tt.tre(&p.truth.world_to_cbct, &t.cbct_to_ios))
        });
        if let Some(x) = tre {
            tres.push(x);
        }
        let _ = writeln!(
            s,
            "| {} | {} | {:.4} | {:.4} | {:.2} | {} | {} | {} |",
            t.fdi,
            tre.map_or("–".into(), |x| format!("{x:.4}")),
            t.sd_mm,
            t.rmse_mm,
            t.inlier_fraction,
            t.iterations,
            if t.converged { "yes" } else { "no" },
            t.warnings.join("; ")
        );
    }
    for sk in &r.skipped {
        let _ = writeln!(s, "skipped tooth {}: {}", sk.fdi, sk.reason);
    }
    if !tres.is_empty() {
        tres.sort_by(f64::total_cmp);
        let _ = writeln!(
            s,
            "TRE median {:.4} mm, max {:.4} mm; jaw SD {:.4} mm; {:.1} ms",
            tres[tres.len() / 2],
            tres[tres.len() - 1],
            r.sd_mm,
            r.timing.total_ms
        );
    } else {
        let _ = writeln!(s, "jaw SD {:.4} mm; {:.1} ms", r.sd_mm, r.timing.total_ms);
    }
    s
}
