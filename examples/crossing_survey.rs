//! Crossing survey of the fusion on jaws the project did not make: fuses each case in
//! `../shared/data/foreign/` with its true transforms and classifies every intersecting face
//! pair of each fused tooth by where its faces come from (crown, band, root). Pairs of two crown
//! faces are the input's own; every other pair was added by the fusion.
//!
//! `cargo run --release --example crossing_survey [CASE_DIR ...]`

use std::path::PathBuf;
use std::time::Instant;
use toothfuse::fuse::{FuseOptions, Preset, fuse_jaw};
use toothfuse::mesh_check::self_intersections;

fn main() -> anyhow::Result<()> {
    let mut dirs: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    if dirs.is_empty() {
        dirs = toothfuse::eval::foreign::case_dirs();
    }
    for dir in dirs {
        let toothfuse::eval::foreign::ForeignCase {
            ios,
            cbct,
            truth: mut tr,
        } = toothfuse::eval::foreign::read_case(&dir)?;
        if let Ok(only) = std::env::var("ONLY") {
            let keep: Vec<u8> = only.split(',').filter_map(|x| x.parse().ok()).collect();
            tr.retain(|k, _| keep.contains(k));
        }
        let opts = FuseOptions::preset(Preset::Default);
        let t0 = Instant::now();
        let jaw = fuse_jaw(&ios, &cbct, &tr, &opts)?;
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        println!(
            "{}: fuse {ms:.0} ms, {} fused, {} failed",
            dir.display(),
            jaw.teeth.len(),
            jaw.failed.len()
        );
        for (f, e) in &jaw.failed {
            println!("  tooth {f} failed: {e}");
        }
        for (fdi, t) in &jaw.teeth {
            let pairs = self_intersections(&t.mesh);
            let cat = |f: u32| {
                let f = f as usize;
                if f < t.band_faces.start {
                    0
                } else if f < t.band_faces.end {
                    1
                } else {
                    2
                }
            };
            let mut counts = [[0usize; 3]; 3];
            // Crown margin vertices: on a crown edge used once among crown faces.
            let crown = toothfuse::mesh::TriMesh::new(
                t.mesh.positions.clone(),
                t.mesh.triangles[..t.band_faces.start].to_vec(),
            );
            let loops = toothfuse::mesh::boundary_loops(&crown);
            let marg: Vec<glam::DVec3> = loops
                .iter()
                .flatten()
                .map(|&v| crown.positions[v as usize])
                .collect();
            let dist = |f: u32| {
                let c = t.mesh.corners(f as usize);
                c.iter()
                    .map(|p| {
                        marg.iter()
                            .map(|q| (*p - *q).length())
                            .fold(f64::INFINITY, f64::min)
                    })
                    .fold(f64::INFINITY, f64::min)
            };
            let mut hist_cb = [0usize; 6];
            let mut hist_cc = [0usize; 6];
            let bin = |d: f64| {
                if d < 0.05 {
                    0
                } else if d < 0.1 {
                    1
                } else if d < 0.2 {
                    2
                } else if d < 0.3 {
                    3
                } else if d < 0.6 {
                    4
                } else {
                    5
                }
            };
            for (a, b) in pairs {
                let (x, y) = (cat(a).min(cat(b)), cat(a).max(cat(b)));
                counts[x][y] += 1;
                if x == 0 && y == 1 {
                    let cf = if cat(a) == 0 { a } else { b };
                    hist_cb[bin(dist(cf))] += 1;
                } else if x == 0 && y == 0 {
                    hist_cc[bin(dist(a).min(dist(b)))] += 1;
                }
            }
            println!(
                "    loops {} crown-band by crown-face margin distance <.05/.1/.2/.3/.6/more {:?}; crown-crown {:?}",
                loops.len(),
                hist_cb,
                hist_cc
            );
            println!(
                "  tooth {fdi}: trimmed {} of {} IOS vertices; stitch {:.0} ms crown-crown {} crown-band {} band-band {} band-root {} crown-root {} root-root {} | closed {} manifold {} comps {} minangle {:.1} | {:?}",
                t.quality.ios_vertices_trimmed,
                t.quality.crown_vertices + t.quality.ios_vertices_trimmed,
                t.stitch_ms,
                counts[0][0],
                counts[0][1],
                counts[1][1],
                counts[1][2],
                counts[0][2],
                counts[2][2],
                t.quality.closed,
                t.quality.manifold,
                t.quality.components,
                t.quality.band_min_angle_deg,
                t.warnings
            );
        }
    }
    Ok(())
}
