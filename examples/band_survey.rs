//! Band quality of the default fusion over the eval jaws with the true transforms (the README's
//! fusion table): `cargo run --release --example band_survey [first_seed] [jaws]` (default 1 20).
//! Prints each tooth the fusion adds intersecting face pairs to, and the totals.

use toothfuse::fuse::{FuseOptions, fuse_jaw, ios_crowns};
use toothfuse::mesh_check::{SurfaceDistance, self_intersections};
use toothfuse::phantom::Phantom;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let first: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1);
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(20);
    let (mut teeth, mut failed, mut with_added, mut input_si, mut at_least_5) = (0, 0, 0, 0, 0);
    let mut added_counts = Vec::new();
    let mut angles = Vec::new();
    let mut band_max = Vec::new();
    let mut excess = Vec::new();
    for o in toothfuse::eval::cases(first, n) {
        let p = Phantom::generate(&o).expect("phantom");
        let transforms = toothfuse::eval::true_transforms(&p);
        let fused = fuse_jaw(&p.ios, &p.cbct, &transforms, &FuseOptions::default()).expect("fuse");
        let tag = format!("seed {} {:?} {}", o.seed, o.jaw, o.variant.name());
        for (fdi, e) in &fused.failed {
            println!("{tag} tooth {fdi}: FAILED {e}");
            failed += 1;
        }
        let crowns = ios_crowns(&p.ios).expect("crowns");
        for (fdi, f) in &fused.teeth {
            teeth += 1;
            let m = &f.mesh;
            if !self_intersections(&crowns[fdi]).is_empty() {
                input_si += 1;
            }
            let crown_face = |fi: u32| {
                m.triangles[fi as usize]
                    .iter()
                    .all(|&v| f.source[v as usize] == 0)
            };
            let added = self_intersections(m)
                .into_iter()
                .filter(|&(a, b)| !(crown_face(a) && crown_face(b)))
                .count();
            if added > 0 {
                with_added += 1;
                added_counts.push(added);
                println!("{tag} tooth {fdi}: {added} added intersecting pairs");
            }
            let a = f.quality.band_min_angle_deg;
            angles.push(a);
            if a >= 5.0 {
                at_least_5 += 1;
            } else {
                println!("{tag} tooth {fdi}: band min angle {a:.2} deg");
            }
            let to_out = p.truth.world_to_ios.compose(&p.truth.teeth[fdi].ios_drift);
            let truth = SurfaceDistance::new(&p.truth.teeth[fdi].surface.transformed(&to_out));
            let bmax = m
                .positions
                .iter()
                .zip(&f.source)
                .filter(|(_, s)| **s == 1)
                .map(|(q, _)| truth.distance(*q))
                .fold(0.0, f64::max);
            // The loops the band is pinned to: non-band vertices of faces with a band vertex.
            let mut lmax: f64 = 0.0;
            for t in &m.triangles {
                if t.iter().any(|&v| f.source[v as usize] == 1) {
                    for &v in t.iter().filter(|&&v| f.source[v as usize] != 1) {
                        lmax = lmax.max(truth.distance(m.positions[v as usize]));
                    }
                }
            }
            band_max.push(bmax);
            excess.push(bmax - lmax);
        }
    }
    let q = |v: &mut Vec<f64>, f: f64| {
        v.sort_by(f64::total_cmp);
        v[((v.len() - 1) as f64 * f).round() as usize]
    };
    added_counts.sort_unstable();
    println!(
        "teeth {teeth}, failed {failed}, input crown self-intersecting {input_si}, with added pairs {with_added} (median {}, max {})",
        added_counts
            .get(added_counts.len() / 2)
            .copied()
            .unwrap_or(0),
        added_counts.last().copied().unwrap_or(0)
    );
    println!(
        "band min angle >= 5 deg: {at_least_5}; per-tooth minimum p5 {:.1} median {:.1} worst {:.1}",
        q(&mut angles, 0.05),
        q(&mut angles, 0.5),
        q(&mut angles, 0.0)
    );
    println!(
        "band max deviation median {:.3} max {:.3}; minus its loops' max: median {:.3} p95 {:.3} max {:.3}",
        q(&mut band_max, 0.5),
        q(&mut band_max, 1.0),
        q(&mut excess, 0.5),
        q(&mut excess, 0.95),
        q(&mut excess, 1.0)
    );
}
