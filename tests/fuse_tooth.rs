//! Fusion of one synthetic tooth (parametric, known truth): topology by construction, every IOS
//! vertex kept bit for bit, band quality and accuracy, for both presets.

mod common;

use toothfuse::fuse::{FuseOptions, Preset, VertexSource, fuse_tooth};
use toothfuse::mesh_check::{SurfaceDistance, self_intersections};

fn check(preset: Preset, seed: u64) {
    let c = common::case(seed, 0.1);
    let mut opts = FuseOptions::preset(preset);
    opts.check_self_intersections = true;
    let f = fuse_tooth(
        11,
        &c.crown,
        &c.cbct,
        &c.ios_to_output,
        &c.cbct_to_output,
        &opts,
    )
    .unwrap_or_else(|e| panic!("{preset:?} seed {seed}: {e}"));
    let q = &f.quality;
    println!("{preset:?} seed {seed}: {q:?} warnings {:?}", f.warnings);
    assert!(q.closed && q.manifold, "{q:?}");
    assert_eq!(q.components, 1);
    assert!(q.volume > 0.0);
    assert_eq!(q.degenerate_faces, 0);
    assert_eq!(self_intersections(&f.mesh).len(), 0, "self-intersections");
    // Every IOS crown vertex, bitwise, in order, labeled IOS.
    let mut seen = vec![false; c.crown.positions.len()];
    for (i, &iv) in f.ios_vertex.iter().enumerate() {
        if iv != u32::MAX {
            assert_eq!(
                f.mesh.positions[i],
                c.ios_to_output.apply(c.crown.positions[iv as usize])
            );
            assert_eq!(f.source[i], VertexSource::Ios as u8);
            seen[iv as usize] = true;
        }
    }
    assert!(
        seen.iter().all(|&s| s),
        "every IOS crown vertex is in the fused mesh"
    );
    assert_eq!(f.source.len(), f.mesh.positions.len());
    // Accuracy against the truth.
    let truth = SurfaceDistance::new(&c.truth);
    let band_max = f
        .mesh
        .positions
        .iter()
        .zip(&f.source)
        .filter(|(_, s)| **s == VertexSource::Band as u8)
        .map(|(p, _)| truth.distance(*p))
        .fold(0.0, f64::max);
    println!(
        "{preset:?} seed {seed}: band max deviation {band_max:.3} mm, min angle {:.1}°",
        q.band_min_angle_deg
    );
    if preset == Preset::Default {
        assert!(
            q.band_min_angle_deg >= 5.0,
            "band min angle {}",
            q.band_min_angle_deg
        );
        assert!(band_max <= 0.25, "band max deviation {band_max}");
    }
}

#[test]
fn default_preset_is_watertight_and_keeps_ios() {
    for seed in 0..2 {
        check(Preset::Default, seed);
    }
}

#[test]
fn paper_preset_is_watertight_and_keeps_ios() {
    check(Preset::Paper, 1);
}
