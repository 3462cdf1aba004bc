//! Whole-jaw fusion on the synthetic phantom with its true per-tooth transforms (output frame =
//! IOS frame): topology by construction on every tooth, every IOS crown vertex kept bit for bit,
//! and accuracy against the known true surfaces (crown, band), for both jaws, every variant and
//! several seeds.

use std::collections::BTreeMap;
use toothfuse::arch::Jaw;
use toothfuse::fuse::{FuseOptions, Preset, ToothTransforms, VertexSource, fuse_jaw, ios_crowns};
use toothfuse::mesh_check::SurfaceDistance;
use toothfuse::phantom::{Phantom, PhantomOptions, Variant};
use toothfuse::{Rigid, TriMesh};

/// Accuracy of one fused tooth against the truth.
#[derive(Debug, Default, Clone, Copy)]
struct Accuracy {
    fused_crown_mean: f64,
    cbct_crown_mean: f64,
    band_max: f64,
}

fn run(seed: u64, jaw: Jaw, variant: Variant, preset: Preset) -> Vec<(u8, Accuracy, f64)> {
    let p = match Phantom::generate(&PhantomOptions {
        seed,
        jaw,
        variant,
        anatomy: None,
    }) {
        Ok(p) => p,
        Err(toothfuse::Error::WrongState(m)) => {
            println!("SKIPPED: the phantom generator is not on this branch yet ({m})");
            return Vec::new();
        }
        Err(e) => panic!("phantom: {e}"),
    };
    let transforms: BTreeMap<u8, ToothTransforms> = p
        .truth
        .teeth
        .iter()
        .map(|(&k, t)| {
            (
                k,
                ToothTransforms {
                    cbct_to_output: t.cbct_to_ios,
                    ios_to_output: Rigid::IDENTITY,
                },
            )
        })
        .collect();
    let mut opts = FuseOptions::preset(preset);
    opts.check_self_intersections = true;
    let fused = fuse_jaw(&p.ios, &p.cbct, &transforms, &opts).expect("fuse_jaw");
    let tag = format!("seed {seed} {jaw:?} {} {}", variant.name(), preset.name());
    if let Some((fdi, e)) = fused.failed.first() {
        panic!("{tag}: tooth {fdi} failed: {e}");
    }
    let crowns = ios_crowns(&p.ios).expect("crowns");
    // Modalities reported as the truth says.
    for (&fdi, t) in &p.truth.teeth {
        let has_crown = crowns.contains_key(&fdi);
        assert_eq!(
            t.in_cbct && has_crown,
            fused.teeth.contains_key(&fdi),
            "{tag}: tooth {fdi}"
        );
        assert_eq!(
            !t.in_cbct && has_crown,
            fused.ios_only.contains(&fdi),
            "{tag}: tooth {fdi}"
        );
        assert_eq!(
            t.in_cbct && !has_crown,
            fused.cbct_only.contains(&fdi),
            "{tag}: tooth {fdi}"
        );
    }
    assert_eq!(fused.labels.len(), fused.mesh.positions.len());
    assert_eq!(fused.source.len(), fused.mesh.positions.len());
    let mut out = Vec::new();
    for (&fdi, f) in &fused.teeth {
        let q = &f.quality;
        assert!(q.closed && q.manifold, "{tag}: tooth {fdi}: {q:?}");
        assert_eq!(q.components, 1, "{tag}: tooth {fdi}");
        assert!(q.volume > 0.0, "{tag}: tooth {fdi}");
        assert_eq!(q.degenerate_faces, 0, "{tag}: tooth {fdi}");
        assert_eq!(q.self_intersections, Some(0), "{tag}: tooth {fdi}");
        let crown = &crowns[&fdi];
        let t = &transforms[&fdi];
        let mut seen = vec![false; crown.positions.len()];
        for (i, &iv) in f.ios_vertex.iter().enumerate() {
            if iv != u32::MAX {
                let want = t.ios_to_output.apply(crown.positions[iv as usize]);
                assert_eq!(f.mesh.positions[i], want, "{tag}: tooth {fdi} vertex {iv}");
                assert_eq!(f.source[i], VertexSource::Ios as u8);
                seen[iv as usize] = true;
            }
        }
        let missing = seen.iter().filter(|s| !**s).count();
        assert_eq!(
            missing, 0,
            "{tag}: tooth {fdi}: IOS crown vertices missing from the fused mesh"
        );
        let truth = &p.truth.teeth[&fdi];
        let to_ios = p.truth.world_to_ios.compose(&truth.ios_drift);
        let surface: TriMesh = truth.surface.transformed(&to_ios);
        let dist = SurfaceDistance::new(&surface);
        let axis = to_ios.apply_vector(truth.axis);
        let margin: Vec<_> = truth.margin.iter().map(|&m| to_ios.apply(m)).collect();
        let mh = margin.iter().map(|m| m.dot(axis)).sum::<f64>() / margin.len() as f64;
        let mean = |it: &mut dyn Iterator<Item = f64>| {
            let (s, n) = it.fold((0.0, 0usize), |(s, n), d| (s + d, n + 1));
            s / n.max(1) as f64
        };
        let fused_crown_mean = mean(
            &mut f
                .mesh
                .positions
                .iter()
                .zip(&f.source)
                .filter(|(_, s)| **s == VertexSource::Ios as u8)
                .map(|(v, _)| dist.distance(*v)),
        );
        let cbct = p.cbct[&fdi].transformed(&t.cbct_to_output);
        let cbct_crown_mean = mean(
            &mut cbct
                .positions
                .iter()
                .filter(|v| v.dot(axis) > mh + 0.5)
                .map(|v| dist.distance(*v)),
        );
        let band_max = f
            .mesh
            .positions
            .iter()
            .zip(&f.source)
            .filter(|(_, s)| **s == VertexSource::Band as u8)
            .map(|(v, _)| dist.distance(*v))
            .fold(0.0, f64::max);
        let acc = Accuracy {
            fused_crown_mean,
            cbct_crown_mean,
            band_max,
        };
        println!(
            "{tag}: tooth {fdi}: crown mean {:.4} mm (CBCT-only {:.4}), band max {:.3} mm, band min angle {:.1}°, metal {}",
            acc.fused_crown_mean,
            acc.cbct_crown_mean,
            acc.band_max,
            q.band_min_angle_deg,
            truth.metal_artefact
        );
        out.push((fdi, acc, q.band_min_angle_deg));
    }
    out
}

fn assert_accuracy(results: &[(u8, Accuracy, f64)], preset: Preset) {
    for (fdi, a, min_angle) in results {
        assert!(a.fused_crown_mean <= 0.03, "tooth {fdi}: {a:?}");
        assert!(
            a.cbct_crown_mean >= 3.0 * a.fused_crown_mean,
            "tooth {fdi}: {a:?}"
        );
        assert!(a.band_max <= 0.25, "tooth {fdi}: {a:?}");
        if preset == Preset::Default {
            assert!(*min_angle >= 5.0, "tooth {fdi}: band min angle {min_angle}");
        }
    }
}

#[test]
fn default_preset_every_variant_both_jaws() {
    for (i, variant) in Variant::ALL.into_iter().enumerate() {
        for jaw in [Jaw::Upper, Jaw::Lower] {
            let r = run(1 + i as u64, jaw, variant, Preset::Default);
            assert_accuracy(&r, Preset::Default);
        }
    }
}

#[test]
fn paper_preset_is_watertight_too() {
    for (seed, jaw, variant) in [
        (7, Jaw::Upper, Variant::Full),
        (8, Jaw::Lower, Variant::MetalArtefact),
    ] {
        let r = run(seed, jaw, variant, Preset::Paper);
        for (fdi, a, ang) in &r {
            println!("paper seed {seed}: tooth {fdi}: {a:?}, min angle {ang:.1}°");
        }
    }
}
