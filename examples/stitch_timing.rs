//! Stitching time per tooth on jaws the project did not make (the foreign cases, with their true
//! transforms) and on rough exports of the phantom: cuts each jaw once, then stitches every tooth
//! on one thread and prints its time, its band builds (made, and reused where a remedy asked
//! for a build it had made before), the band size, the IOS vertices trimmed
//! and the crossings the untangling left, with the jaw's totals and a checksum of every fused
//! mesh (positions bit for bit, faces, sources) to show a speed-up left the output
//! byte-identical.
//!
//! `cargo run --release --example stitch_timing [CASE_DIR ...]` (no argument: every foreign case
//! and a rough and a coarse phantom jaw). `STITCH_TIMING_ONLY="Coarse tooth 26"` stitches only
//! the teeth whose line would contain that text.

use std::path::PathBuf;
use std::time::Instant;
use toothfuse::fuse::{CutJaw, FuseOptions, Preset, cut_jaw, stitch_tooth};
use toothfuse::phantom::{IosExport, Phantom, PhantomOptions};

/// FNV-1a over the fused mesh's position bits, face indices and vertex sources.
fn checksum(f: &toothfuse::fuse::FusedTooth) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |x: u64| {
        h ^= x;
        h = h.wrapping_mul(0x0100_0000_01b3);
    };
    for p in &f.mesh.positions {
        p.to_array().iter().for_each(|c| eat(c.to_bits()));
    }
    for t in &f.mesh.triangles {
        t.iter().for_each(|&v| eat(v as u64));
    }
    for &s in &f.source {
        eat(s as u64);
    }
    h
}

fn report(name: &str, cut: &CutJaw, opts: &FuseOptions) {
    let mut total = 0.0;
    let mut all = 0u64;
    let mut builds = 0;
    let mut reused = 0;
    let only = std::env::var("STITCH_TIMING_ONLY").unwrap_or_default();
    for (fdi, ct) in &cut.teeth {
        if !format!("{name} tooth {fdi}").contains(&only) {
            continue;
        }
        let t0 = Instant::now();
        let r = stitch_tooth(ct, opts);
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        total += ms;
        match r {
            Ok(f) => {
                all = all.rotate_left(5) ^ checksum(&f);
                let left = f
                    .warnings
                    .iter()
                    .find(|w| w.contains("left after untangling"))
                    .map_or("", String::as_str);
                builds += f.band_builds;
                reused += f.band_builds_reused;
                println!(
                    "  {name} tooth {fdi}: {ms:8.1} ms, {:2} builds ({} reused), band {:5} faces, trimmed {:3} of {:6}, min angle {:4.1} {left}",
                    f.band_builds,
                    f.band_builds_reused,
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
        "{name}: stitch {total:.0} ms over {} teeth, {builds} band builds ({reused} reused), checksum {all:016x}",
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
        let t0 = Instant::now();
        let cut = cut_jaw(&c.ios, &c.cbct, &c.truth, &opts)?;
        println!("cut {:.0} ms", t0.elapsed().as_secs_f64() * 1e3);
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
            let t0 = Instant::now();
            let cut = cut_jaw(&p.ios, &p.cbct, &tr, &opts)?;
            println!("cut {:.0} ms", t0.elapsed().as_secs_f64() * 1e3);
            report(&format!("phantom {export:?}"), &cut, &opts);
        }
    }
    Ok(())
}
