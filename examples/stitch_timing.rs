//! Stitching time per tooth on jaws the project did not make (the foreign cases, with their true
//! transforms) and on rough exports of the phantom: cuts each jaw once, then stitches every tooth
//! on one thread and prints its time, the band size, the IOS vertices trimmed and the crossings
//! the untangling left, with the jaw's total.
//!
//! `cargo run --release --example stitch_timing [CASE_DIR ...]` (no argument: every foreign case
//! and a rough and a coarse phantom jaw).

use std::path::PathBuf;
use std::time::Instant;
use toothfuse::fuse::{CutJaw, FuseOptions, Preset, cut_jaw, stitch_tooth};
use toothfuse::phantom::{IosExport, Phantom, PhantomOptions};

fn report(name: &str, cut: &CutJaw, opts: &FuseOptions) {
    let mut total = 0.0;
    for (fdi, ct) in &cut.teeth {
        let t0 = Instant::now();
        let r = stitch_tooth(ct, opts);
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        total += ms;
        match r {
            Ok(f) => {
                let left = f
                    .warnings
                    .iter()
                    .find(|w| w.contains("left after untangling"))
                    .map_or("", String::as_str);
                println!(
                    "  {name} tooth {fdi}: {ms:8.1} ms, band {:5} faces, trimmed {:3} of {:6}, min angle {:4.1} {left}",
                    f.band_faces.len(),
                    f.quality.ios_vertices_trimmed,
                    f.quality.crown_vertices + f.quality.ios_vertices_trimmed,
                    f.quality.band_min_angle_deg,
                );
            }
            Err(e) => println!("  {name} tooth {fdi}: {ms:8.1} ms, FAILED: {e}"),
        }
    }
    println!(
        "{name}: stitch {total:.0} ms over {} teeth",
        cut.teeth.len()
    );
}

fn main() -> anyhow::Result<()> {
    let opts = FuseOptions::preset(Preset::Default);
    let mut dirs: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    let phantoms = dirs.is_empty();
    if dirs.is_empty() {
        dirs = toothfuse::eval::foreign::case_dirs();
    }
    for dir in dirs {
        let c = toothfuse::eval::foreign::read_case(&dir)?;
        let cut = cut_jaw(&c.ios, &c.cbct, &c.truth, &opts)?;
        let name = dir.file_name().unwrap_or_default().to_string_lossy();
        report(&name, &cut, &opts);
    }
    if phantoms {
        for export in [IosExport::Rough, IosExport::Coarse] {
            let mut po = PhantomOptions {
                seed: 3,
                ..PhantomOptions::default()
            };
            po.realism.ios.rough = export.roughness();
            let p = Phantom::generate(&po)?;
            let tr = toothfuse::eval::true_transforms(&p);
            let cut = cut_jaw(&p.ios, &p.cbct, &tr, &opts)?;
            report(&format!("phantom {export:?}"), &cut, &opts);
        }
    }
    Ok(())
}
