//! The synthetic jaw against its own ground truth: topology of every mesh, sizes, determinism,
//! truth consistency (IOS and CBCT back in the world frame), drift magnitudes, variants.

mod phantom_support;

use phantom_support::*;
use std::collections::BTreeMap;
use std::sync::{Mutex, OnceLock};
use toothfuse::arch::{Jaw, arch_order};
use toothfuse::mesh::boundary_loops;
use toothfuse::phantom::{Phantom, PhantomOptions, Variant};

type Key = (u64, bool, &'static str);

/// Generated phantoms shared by the tests of this binary (each generated once).
fn phantom(seed: u64, jaw: Jaw, variant: Variant) -> &'static Phantom {
    static CACHE: OnceLock<Mutex<BTreeMap<Key, &'static Phantom>>> = OnceLock::new();
    let key = (seed, jaw == Jaw::Upper, variant.name());
    let cache = CACHE.get_or_init(|| Mutex::new(BTreeMap::new()));
    if let Some(p) = cache.lock().unwrap().get(&key) {
        return p;
    }
    let p = Phantom::generate(&PhantomOptions {
        seed,
        jaw,
        variant,
        ..Default::default()
    })
    .expect("phantom generates");
    let p: &'static Phantom = Box::leak(Box::new(p));
    cache.lock().unwrap().insert(key, p);
    p
}

fn check_topology(p: &Phantom, what: &str) {
    for (fdi, t) in &p.truth.teeth {
        assert_eq!(*fdi, t.fdi);
        assert_closed_tooth(&t.surface, &format!("{what} truth {fdi}"));
        assert!(t.margin.len() >= 60, "{what} margin {fdi}");
        assert!((t.axis.length() - 1.0).abs() < 1e-9);
    }
    for (fdi, m) in &p.cbct {
        assert_closed_tooth(m, &format!("{what} cbct {fdi}"));
        assert!(
            (2500..=12000).contains(&m.positions.len()),
            "{what} cbct {fdi}: {} vertices",
            m.positions.len()
        );
        assert!(p.truth.teeth[fdi].in_cbct);
    }
    let crowns = p.ios_crowns();
    for (fdi, c) in &crowns {
        assert_disk(c, &format!("{what} ios crown {fdi}"));
        assert!(
            c.positions.len() > 2000,
            "{what} crown {fdi}: {} vertices",
            c.positions.len()
        );
        assert!(p.truth.teeth[fdi].in_ios);
    }
    let ios_teeth: Vec<u8> = p
        .truth
        .teeth
        .values()
        .filter(|t| t.in_ios)
        .map(|t| t.fdi)
        .collect();
    assert_eq!(
        crowns.keys().copied().collect::<Vec<_>>(),
        ios_teeth,
        "{what}: IOS crowns"
    );
    let cbct_teeth: Vec<u8> = p
        .truth
        .teeth
        .values()
        .filter(|t| t.in_cbct)
        .map(|t| t.fdi)
        .collect();
    assert_eq!(
        p.cbct.keys().copied().collect::<Vec<_>>(),
        cbct_teeth,
        "{what}: CBCT teeth"
    );
    // The whole IOS jaw: one connected open manifold surface.
    let r = p.ios.mesh.topology_report();
    assert_eq!(r.components, 1, "{what}: IOS components");
    assert_eq!(
        r.non_manifold_edges + r.non_manifold_vertices,
        0,
        "{what}: IOS manifold"
    );
    assert!(r.boundary_loops >= 1);
}

#[test]
fn full_jaws_are_closed_realistic_and_consistent() {
    for (seed, jaw) in [(1, Jaw::Upper), (2, Jaw::Lower)] {
        let p = phantom(seed, jaw, Variant::Full);
        let what = format!("seed {seed} {jaw:?}");
        check_topology(p, &what);
        assert_eq!(p.truth.teeth.len(), 14);
        let n = p.ios.mesh.positions.len();
        assert!((100_000..=220_000).contains(&n), "{what}: {n} IOS vertices");
        for (fdi, t) in &p.truth.teeth {
            assert_eq!(toothfuse::arch::jaw_of(*fdi), jaw);
            // cbct_to_ios = world_to_ios ∘ drift ∘ world_to_cbct⁻¹.
            let w = t.surface.positions[0];
            let c = p.truth.world_to_cbct.apply(w);
            let expect = p.truth.world_to_ios.apply(t.ios_drift.apply(w));
            assert!((t.cbct_to_ios.apply(c) - expect).length() < 1e-9);
        }
    }
}

#[test]
fn ios_crowns_lie_on_the_drifted_truth() {
    let p = phantom(1, Jaw::Upper, Variant::Full);
    for (fdi, crown) in p.ios_crowns() {
        let t = &p.truth.teeth[&fdi];
        let back = p.truth.world_to_ios.compose(&t.ios_drift).inverse();
        let sd = SurfaceDistance::new(&t.surface);
        let mut d: Vec<f64> = crown
            .positions
            .iter()
            .map(|&q| sd.distance(back.apply(q)))
            .collect();
        d.sort_by(|a, b| a.total_cmp(b));
        let q90 = d[d.len() * 9 / 10];
        let q99 = d[d.len() * 99 / 100];
        // Label bleed puts a thin band of gingiva vertices into the crown; the rest is the tooth
        // surface plus ~0.01 mm noise.
        assert!(q90 < 0.05, "crown {fdi}: 90% quantile {q90}");
        assert!(q99 < 0.5, "crown {fdi}: 99% quantile {q99}");
        // The crown's boundary follows the true margin (up to label bleed and the notches).
        let lp = &boundary_loops(&crown)[0];
        let mut md: Vec<f64> = lp
            .iter()
            .map(|&v| {
                let q = back.apply(crown.positions[v as usize]);
                t.margin
                    .iter()
                    .map(|m| (*m - q).length())
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        md.sort_by(|a, b| a.total_cmp(b));
        let median = md[md.len() / 2];
        assert!(median < 0.5, "crown {fdi}: margin median distance {median}");
        // The margin is closed, ordered and lies on the true surface.
        for w in t.margin.windows(2) {
            assert!((w[1] - w[0]).length() < 1.5, "crown {fdi}: margin step");
        }
        assert!(
            t.margin.iter().all(|m| sd.distance(*m) < 0.05),
            "crown {fdi}: margin on surface"
        );
    }
}

#[test]
fn cbct_deviates_from_truth_like_real_segmentations() {
    for (seed, jaw) in [(1, Jaw::Upper), (2, Jaw::Lower)] {
        let p = phantom(seed, jaw, Variant::Full);
        let back = p.truth.world_to_cbct.inverse();
        let mut all = Vec::new();
        for (fdi, m) in &p.cbct {
            let sd = SurfaceDistance::new(&p.truth.teeth[fdi].surface);
            let d: Vec<f64> = m
                .positions
                .iter()
                .map(|&q| sd.distance(back.apply(q)))
                .collect();
            let (rms, _, max) = stats(&d);
            assert!(
                (0.05..=0.4).contains(&rms),
                "seed {seed} tooth {fdi}: RMS {rms}"
            );
            assert!(max < 0.95, "seed {seed} tooth {fdi}: max {max}");
            all.extend(d);
        }
        let (rms, _, _) = stats(&all);
        assert!(
            (0.1..=0.35).contains(&rms),
            "seed {seed}: RMS over the jaw {rms}"
        );
    }
}

#[test]
fn drift_grows_along_the_scan_path() {
    for (variant, lo, hi) in [(Variant::Full, 0.25, 0.9), (Variant::HeavyDrift, 1.0, 3.5)] {
        let p = phantom(3, Jaw::Lower, variant);
        let order = arch_order(&p.truth.teeth.keys().copied().collect::<Vec<_>>());
        let ang: Vec<f64> = order
            .iter()
            .map(|f| p.truth.teeth[f].ios_drift.angle().to_degrees())
            .collect();
        let (first, last) = (ang[0], ang[ang.len() - 1]);
        let (start, far) = if first < last {
            (0, order.len() - 1)
        } else {
            (order.len() - 1, 0)
        };
        assert!(
            ang[start] < 1e-12,
            "{variant:?}: the first scanned tooth has no drift"
        );
        assert!(
            (lo..=hi).contains(&ang[far]),
            "{variant:?}: far-end drift {}°",
            ang[far]
        );
        let t = &p.truth.teeth[&order[far]];
        let c = toothfuse::geom::centroid(&t.surface.positions).unwrap();
        let shift = (t.ios_drift.apply(c) - c).length();
        let (slo, shi) = if variant == Variant::Full {
            (0.08, 0.45)
        } else {
            (0.4, 1.8)
        };
        assert!(
            (slo..=shi).contains(&shift),
            "{variant:?}: far-end shift {shift} mm"
        );
    }
}

#[test]
fn variants_do_what_they_say() {
    // Missing teeth: some only in one modality, one in neither (a gap in the arch).
    let p = phantom(4, Jaw::Upper, Variant::MissingTeeth);
    check_topology(p, "missing");
    assert_eq!(p.truth.teeth.len(), 13);
    let only_cbct = p
        .truth
        .teeth
        .values()
        .filter(|t| !t.in_ios && t.in_cbct)
        .count();
    let only_ios = p
        .truth
        .teeth
        .values()
        .filter(|t| t.in_ios && !t.in_cbct)
        .count();
    assert!(only_cbct >= 1 && only_ios >= 1);
    // Partial arch: 3–5 consecutive teeth.
    let p = phantom(5, Jaw::Lower, Variant::PartialArch);
    check_topology(p, "partial");
    let teeth: Vec<u8> = p.truth.teeth.keys().copied().collect();
    assert!((3..=5).contains(&teeth.len()));
    let all = toothfuse::arch::arch_order(&teeth);
    let pos: Vec<i32> = all
        .iter()
        .map(|&t| toothfuse::arch::arch_position(t))
        .collect();
    for w in pos.windows(2) {
        assert!(
            w[1] - w[0] == 2 || (w[0] == -2 && w[1] == 2),
            "consecutive: {all:?}"
        );
    }
    // Metal: one tooth flagged, bloated in CBCT.
    let p = phantom(6, Jaw::Lower, Variant::MetalArtefact);
    check_topology(p, "metal");
    let metal: Vec<u8> = p
        .truth
        .teeth
        .values()
        .filter(|t| t.metal_artefact)
        .map(|t| t.fdi)
        .collect();
    assert_eq!(metal.len(), 1);
    let back = p.truth.world_to_cbct.inverse();
    let m = &p.cbct[&metal[0]];
    let sd = SurfaceDistance::new(&p.truth.teeth[&metal[0]].surface);
    let max = m
        .positions
        .iter()
        .map(|&q| sd.distance(back.apply(q)))
        .fold(0.0, f64::max);
    assert!(
        max > 1.0,
        "metal crown bloated and spiky: max deviation {max}"
    );
}

#[test]
fn generation_is_deterministic() {
    let opts = PhantomOptions {
        seed: 7,
        jaw: Jaw::Upper,
        variant: Variant::PartialArch,
        ..Default::default()
    };
    // One through the cache (where the test command enables it), one generated anew: the
    // generator is deterministic and a cached jaw is the generated one.
    let a = Phantom::generate(&opts).unwrap();
    let b = Phantom::generate_uncached(&opts).unwrap();
    let bits = |m: &toothfuse::TriMesh| -> Vec<u64> {
        m.positions
            .iter()
            .flat_map(|p| p.to_array().map(f64::to_bits))
            .collect()
    };
    assert_eq!(bits(&a.ios.mesh), bits(&b.ios.mesh));
    assert_eq!(a.ios.mesh.triangles, b.ios.mesh.triangles);
    assert_eq!(a.ios.vertex_labels, b.ios.vertex_labels);
    for (fdi, m) in &a.cbct {
        assert_eq!(bits(m), bits(&b.cbct[fdi]));
        assert_eq!(m.triangles, b.cbct[fdi].triangles);
    }
    for (fdi, t) in &a.truth.teeth {
        assert_eq!(bits(&t.surface), bits(&b.truth.teeth[fdi].surface));
        assert_eq!(t.cbct_to_ios, b.truth.teeth[fdi].cbct_to_ios);
    }
    let c = Phantom::generate(&PhantomOptions { seed: 8, ..opts }).unwrap();
    assert_ne!(bits(&a.ios.mesh), bits(&c.ios.mesh));
}

#[test]
fn optional_holes_stay_inside_single_component_crowns() {
    let mut opts = PhantomOptions {
        seed: 9,
        jaw: Jaw::Lower,
        variant: Variant::PartialArch,
        ..Default::default()
    };
    opts.realism.ios.holes = 4;
    let p = Phantom::generate(&opts).unwrap();
    let crowns = p.ios_crowns();
    let mut loops = 0;
    for (fdi, c) in &crowns {
        let r = c.topology_report();
        assert_eq!(r.components, 1, "crown {fdi}");
        assert_eq!(
            r.non_manifold_edges + r.non_manifold_vertices,
            0,
            "crown {fdi}"
        );
        loops += r.boundary_loops;
    }
    assert!(
        loops > crowns.len(),
        "some crowns carry holes: {loops} loops for {} crowns",
        crowns.len()
    );
    let plain = phantom(9, Jaw::Lower, Variant::PartialArch);
    for (fdi, c) in plain.ios_crowns() {
        assert_eq!(
            c.topology_report().boundary_loops,
            1,
            "crown {fdi} without holes"
        );
    }
}
