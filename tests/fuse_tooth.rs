//! Fusion of one synthetic tooth (parametric, known truth): topology by construction, every IOS
//! vertex kept bit for bit, band quality and accuracy, for both presets.

mod common;

use toothfuse::fuse::{FuseOptions, Preset, VertexSource, cut_tooth, fuse_tooth, stitch_tooth};
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

/// The two stages: `stitch_tooth(cut_tooth(..))` is `fuse_tooth` bit for bit, the cut carries
/// everything the stitch needs (stitching one cut with the paper's stitch options equals
/// `fuse_tooth` with default cut + paper stitch), stitching is repeatable, and the fused mesh is
/// the cut's crown, then the band, then the cut's root, unchanged.
#[test]
fn cut_then_stitch_equals_fuse_tooth() {
    let c = common::case(3, 0.1);
    let opts = FuseOptions::default();
    let fuse = |o: &FuseOptions| {
        fuse_tooth(
            11,
            &c.crown,
            &c.cbct,
            &c.ios_to_output,
            &c.cbct_to_output,
            o,
        )
        .unwrap()
    };
    let cut = cut_tooth(
        11,
        &c.crown,
        &c.cbct,
        &c.ios_to_output,
        &c.cbct_to_output,
        &opts,
    )
    .unwrap();
    let mut mixed = opts;
    mixed.stitch = FuseOptions::preset(Preset::Paper).stitch;
    for o in [opts, mixed] {
        let staged = stitch_tooth(&cut, &o).unwrap();
        let again = stitch_tooth(&cut, &o).unwrap();
        let whole = fuse(&o);
        for f in [&again, &whole] {
            assert_eq!(staged.mesh.triangles, f.mesh.triangles);
            let bits = |m: &toothfuse::TriMesh| {
                m.positions
                    .iter()
                    .map(|p| p.to_array().map(f64::to_bits))
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(&staged.mesh), bits(&f.mesh));
            assert_eq!(staged.source, f.source);
            assert_eq!(staged.ios_vertex, f.ios_vertex);
            assert_eq!(staged.quality, f.quality);
            assert_eq!(staged.warnings, f.warnings);
        }
        let nc = cut.crown().positions.len();
        let root = &cut.root().root;
        let nr = root.positions.len();
        let n = staged.mesh.positions.len();
        assert_eq!(&staged.mesh.positions[..nc], &cut.crown().positions[..]);
        assert_eq!(&staged.mesh.positions[n - nr..], &root.positions[..]);
        assert!(
            staged.source[n - nr..]
                .iter()
                .all(|&s| s == VertexSource::Cbct as u8)
        );
        assert_eq!(&staged.ios_vertex[..nc], cut.ios_vertex());
        let off = (n - nr) as u32;
        let nt = staged.mesh.triangles.len();
        let root_tris: Vec<[u32; 3]> = root.triangles.iter().map(|t| t.map(|v| v + off)).collect();
        assert_eq!(
            &staged.mesh.triangles[nt - root_tris.len()..],
            &root_tris[..]
        );
        assert_eq!(staged.cut_ms, cut.cut_ms());
    }
    // Different stitch options do change the band (the options reach the stitch).
    assert_ne!(
        stitch_tooth(&cut, &opts).unwrap().mesh.positions.len(),
        stitch_tooth(&cut, &mixed).unwrap().mesh.positions.len()
    );
}
