//! The output contract on inputs the project did not shape: rough phantom exports (raw slivers,
//! folds, a margin clipped through triangles, holes, notches, label noise; coarse and dense) of
//! every variant and both jaws, and the two foreign jaws of `../shared/data/foreign/` (an
//! independent generator), each fused with its true transforms. On every tooth: closed,
//! manifold, one component, positive volume; every kept IOS crown vertex bitwise at its
//! transformed input position; no intersecting face pair other than two kept input crown faces
//! (exact test); no trimmed IOS vertex farther than 0.3 mm (along the surface) from the margin,
//! except on a tooth whose warnings say the fringe was trimmed farther (the builds within
//! 0.3 mm left the band crossing the crown), and there at most 0.9 mm. The trimmed share is
//! bounded by what is measured, which is not yet the aim (at most 0.5 %): see the bounds below
//! and the README's fusion table.

use std::collections::{BTreeMap, HashSet};
use toothfuse::arch::Jaw;
use toothfuse::fuse::{FuseOptions, FusedJaw, Preset, ToothTransforms, fuse_jaw, ios_crowns};
use toothfuse::mesh::LabeledMesh;
use toothfuse::mesh_check::self_intersections;
use toothfuse::phantom::{IosExport, Phantom, PhantomOptions, Variant};

/// Measured bounds of one family of inputs: trimmed share, teeth whose fringe was trimmed
/// beyond 0.3 mm.
struct Bounds {
    trimmed_share: f64,
    widened: usize,
}

/// Foreign jaws: at most 0.45 % trimmed, nothing beyond 0.3 mm.
const FOREIGN: Bounds = Bounds {
    trimmed_share: 0.005,
    widened: 0,
};
/// Rough phantom exports (much rougher than the foreign jaws: 4x their crossing crown pairs per
/// crown on dense exports): at most 7.9 % trimmed (a coarse crown of a few hundred vertices;
/// at most 3.3 % on the rough and dense ones); the fringe trimmed beyond 0.3 mm (at most
/// 0.52 mm) on 12 teeth of the 20 jaws, at most 2 per jaw.
const ROUGH: Bounds = Bounds {
    trimmed_share: 0.08,
    widened: 2,
};

/// The widest trim allowed: three times the default 0.3 mm reach (the last of the wider
/// reaches the fusion tries on a tooth the builds left crossed).
const WIDEST_MM: f64 = 0.9;

fn sorted(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// Asserts the contract on every fused tooth; returns the number of teeth, the trimmed
/// vertices in all and the teeth whose slits at the margin were closed.
fn check(
    b: &Bounds,
    tag: &str,
    ios: &LabeledMesh,
    fused: &FusedJaw,
    tr: &BTreeMap<u8, ToothTransforms>,
) -> (usize, usize, usize) {
    let crowns = ios_crowns(ios).expect("crowns");
    let mut trimmed = 0;
    let mut inlets = 0;
    let mut widened = 0;
    let mut worst_share = 0.0f64;
    for (fdi, t) in &fused.teeth {
        let q = &t.quality;
        let what = format!("{tag}: tooth {fdi}");
        assert!(q.closed && q.manifold && q.components == 1, "{what}: {q:?}");
        assert!(q.volume > 0.0, "{what}: volume {}", q.volume);
        // The crown faces that are no input face (hole caps, slit strips), found here from
        // the input crown itself and checked against the fused tooth's own list.
        let input = &crowns[fdi];
        let input_faces: HashSet<[u32; 3]> = input.triangles.iter().map(|&t| sorted(t)).collect();
        let added_faces: Vec<u32> = (0..t.band_faces.start as u32)
            .filter(|&f| {
                let k = sorted(t.mesh.triangles[f as usize].map(|v| t.ios_vertex[v as usize]));
                k[2] == u32::MAX || !input_faces.contains(&k)
            })
            .collect();
        assert_eq!(
            added_faces, t.crown_faces_added,
            "{what}: the crown faces added"
        );
        let is_input =
            |f: u32| (f as usize) < t.band_faces.start && added_faces.binary_search(&f).is_err();
        let (own, added): (Vec<_>, Vec<_>) = self_intersections(&t.mesh)
            .into_iter()
            .partition(|&(a, b)| is_input(a) && is_input(b));
        assert_eq!(
            t.ios_self_intersections(),
            own.len(),
            "{what}: the report's ios_self_intersections against the crown pairs found"
        );
        assert!(
            added.is_empty(),
            "{what}: {} crossing pairs added by the fusion ({} reported with a face added to the crown): {:?}",
            added.len(),
            q.crown_crossings_added,
            &added[..added.len().min(6)]
        );
        assert_eq!(
            q.band_crossings_left, 0,
            "{what}: the report's band_crossings_left"
        );
        assert_eq!(
            q.crown_crossings_added, 0,
            "{what}: the report's crown_crossings_added"
        );
        let to_out = tr[fdi].ios_to_output;
        for (v, &s) in t.ios_vertex.iter().enumerate() {
            if s != u32::MAX {
                assert_eq!(
                    t.mesh.positions[v],
                    to_out.apply(input.positions[s as usize]),
                    "{what}: vertex {v}"
                );
            }
        }
        // Every input crown vertex is accounted for: kept (bitwise, above), trimmed from the
        // fringe, or dropped by the repair (label-noise islands apart from the crown).
        let kept = t.ios_vertex.iter().filter(|&&s| s != u32::MAX).count();
        assert_eq!(kept, q.crown_vertices, "{what}: kept IOS vertices");
        assert_eq!(
            kept + q.ios_vertices_trimmed + q.ios_vertices_dropped,
            input.positions.len(),
            "{what}: kept + trimmed + dropped against the input crown"
        );
        let n = q.crown_vertices + q.ios_vertices_trimmed;
        assert!(
            q.ios_vertices_trimmed as f64 <= b.trimmed_share * n as f64,
            "{what}: {} of {n} IOS vertices trimmed",
            q.ios_vertices_trimmed
        );
        if q.ios_trim_reach_mm > 0.3 {
            println!(
                "{what}: trimmed {:.3} mm from the margin",
                q.ios_trim_reach_mm
            );
            widened += 1;
            assert!(
                q.ios_trim_reach_mm <= WIDEST_MM,
                "{what}: trimmed {:.3} mm from the margin",
                q.ios_trim_reach_mm
            );
            assert!(
                t.warnings
                    .iter()
                    .any(|w| w.contains("with the fringe reaching")),
                "{what}: trimmed {:.3} mm from the margin without a warning saying so: {:?}",
                q.ios_trim_reach_mm,
                t.warnings
            );
        }
        if t.warnings.iter().any(|w| w.contains("narrow inlets")) {
            println!("{what}: slits at the margin closed: {:?}", t.warnings);
            inlets += 1;
        }
        trimmed += q.ios_vertices_trimmed;
        worst_share = worst_share.max(q.ios_vertices_trimmed as f64 / n as f64);
    }
    println!("{tag}: largest trimmed share {:.2} %", 100.0 * worst_share);
    assert!(
        widened <= b.widened,
        "{tag}: {widened} teeth trimmed beyond 0.3 mm"
    );
    (fused.teeth.len(), trimmed, inlets)
}

/// Fuses each rough jaw with its true transforms and checks it; returns the teeth whose slits
/// at the margin were closed.
fn rough_jaws(cases: &[(u64, Jaw, Variant, IosExport)]) -> usize {
    let mut inlets = 0;
    for &(seed, jaw, variant, export) in cases {
        let mut opts = PhantomOptions {
            seed,
            jaw,
            variant,
            ..Default::default()
        };
        opts.realism.ios.rough = export.roughness();
        let p = Phantom::generate(&opts).expect("phantom");
        let tr = toothfuse::eval::true_transforms(&p);
        let fused =
            fuse_jaw(&p.ios, &p.cbct, &tr, &FuseOptions::preset(Preset::Default)).expect("fuse");
        let tag = format!("seed {seed} {jaw:?} {} {}", variant.name(), export.name());
        // Every tooth of these jaws is fused: none lost to label noise or holes, and the coarse
        // lower incisor whose ragged margin tilts its plane 49° off the tooth (seed 20, tooth 31),
        // whose cut about that plane's normal does not go around the tooth, is cut again about
        // the CBCT tooth's long axis.
        assert!(fused.failed.is_empty(), "{tag}: failed {:?}", fused.failed);
        let (n, trimmed, closed) = check(&ROUGH, &tag, &p.ios, &fused, &tr);
        println!("{tag}: {n} teeth fused, {trimmed} IOS vertices trimmed");
        inlets += closed;
    }
    inlets
}

use Jaw::{Lower, Upper};
use Variant::{Full, HeavyDrift, MetalArtefact, MissingTeeth, PartialArch};

#[test]
fn rough_full_arches() {
    let _ = rough_jaws(&[
        (11, Upper, Full, IosExport::Rough),
        (12, Lower, Full, IosExport::Rough),
        (13, Upper, HeavyDrift, IosExport::Rough),
        (14, Lower, MetalArtefact, IosExport::Rough),
        (15, Upper, MissingTeeth, IosExport::Rough),
    ]);
}

#[test]
fn coarse_and_partial_arches() {
    let inlets = rough_jaws(&[
        (16, Lower, Full, IosExport::Coarse),
        (17, Upper, MetalArtefact, IosExport::Coarse),
        (18, Lower, PartialArch, IosExport::Rough),
        (19, Upper, PartialArch, IosExport::Coarse),
        (20, Lower, MissingTeeth, IosExport::Coarse),
        (21, Upper, HeavyDrift, IosExport::Coarse),
        (22, Lower, PartialArch, IosExport::Dense2),
        (23, Upper, PartialArch, IosExport::Rough),
    ]);
    // Coarse and rough crowns with slits at their margins whose first band build crosses the
    // crown are fused with the slits closed (measured: 19 teeth of these 8 jaws, among them
    // seed 16 tooth 46 and seed 21 tooth 15).
    assert!(
        inlets >= 10,
        "{inlets} teeth with slits at the margin closed"
    );
}

/// Dense exports (2x, 4x, subdivided): ~2.5 min of CPU, outside the test command's time budget;
/// `cargo test --release --test fuse_rough -- --ignored`.
#[test]
#[ignore]
fn dense_arches() {
    let _ = rough_jaws(&[
        (24, Upper, PartialArch, IosExport::Dense4),
        (25, Lower, Full, IosExport::Dense2),
        (26, Lower, HeavyDrift, IosExport::Rough),
        (27, Upper, PartialArch, IosExport::Subdivided),
        (28, Lower, MetalArtefact, IosExport::Dense2),
        (29, Upper, MissingTeeth, IosExport::Rough),
        (30, Lower, PartialArch, IosExport::Dense4),
    ]);
}

#[test]
fn foreign_jaws() {
    let dirs = toothfuse::eval::foreign::case_dirs();
    if dirs.is_empty() {
        println!("SKIPPED: ../shared/data/foreign is not beside the checkout");
        return;
    }
    for d in dirs {
        let case = d.file_name().unwrap_or_default().to_string_lossy();
        let c = toothfuse::eval::foreign::read_case(&d).expect("case");
        let (ios, cbct, tr) = (c.ios, c.cbct, c.truth);
        let fused =
            fuse_jaw(&ios, &cbct, &tr, &FuseOptions::preset(Preset::Default)).expect("fuse");
        assert!(fused.failed.is_empty(), "{case}: failed {:?}", fused.failed);
        assert_eq!(fused.teeth.len(), 14, "{case}");
        let (n, trimmed, _) = check(&FOREIGN, &case, &ios, &fused, &tr);
        println!("{case}: {n} teeth fused, {trimmed} IOS vertices trimmed");
    }
}
