//! Rough IOS exports of the synthetic jaw ([`IosExport`]): measured to hold what they claim
//! (slivers, crossing crown faces, the margin clipped through triangles, label islands and
//! holes, coarse and dense resolutions), with valid truth, deterministic, on every variant and
//! both jaws; and the clean default unchanged by them.

mod phantom_support;

use phantom_support::*;
use toothfuse::TriMesh;
use toothfuse::arch::Jaw;
use toothfuse::mesh_check::self_intersections;
use toothfuse::phantom::{IosExport, Phantom, PhantomOptions, Variant};

fn generate(seed: u64, jaw: Jaw, variant: Variant, export: IosExport) -> Phantom {
    let mut opts = PhantomOptions {
        seed,
        jaw,
        variant,
        ..Default::default()
    };
    opts.realism.ios.rough = export.roughness();
    Phantom::generate(&opts).expect("phantom generates")
}

/// What the crowns of a jaw hold.
#[derive(Debug, Default)]
struct CrownStats {
    crowns: usize,
    vertices: usize,
    faces: usize,
    mean_edge: f64,
    /// Crown faces with a corner under 5°.
    slivers: usize,
    /// Crossing face pairs within each crown (exact test), summed.
    crossings: usize,
    /// Crowns whose label leaves them more than one component (stray islands).
    multi_component: usize,
    /// Crowns with more than one boundary loop (holes).
    multi_loop: usize,
    /// Crowns with a non-manifold vertex or edge.
    non_manifold: usize,
}

fn min_angle_deg(m: &TriMesh, t: [u32; 3]) -> f64 {
    let p = t.map(|v| m.positions[v as usize]);
    (0..3)
        .map(|k| (p[(k + 1) % 3] - p[k]).angle_between(p[(k + 2) % 3] - p[k]))
        .fold(f64::INFINITY, f64::min)
        .to_degrees()
}

fn crown_stats(p: &Phantom) -> CrownStats {
    let mut s = CrownStats::default();
    let (mut edge_sum, mut edges) = (0.0, 0usize);
    for m in p.ios_crowns().values() {
        s.crowns += 1;
        s.vertices += m.positions.len();
        s.faces += m.triangles.len();
        for &t in &m.triangles {
            s.slivers += usize::from(min_angle_deg(m, t) < 5.0);
            for k in 0..3 {
                edge_sum +=
                    (m.positions[t[k] as usize] - m.positions[t[(k + 1) % 3] as usize]).length();
                edges += 1;
            }
        }
        s.crossings += self_intersections(m).len();
        let r = m.topology_report();
        s.multi_component += usize::from(r.components > 1);
        s.multi_loop += usize::from(r.boundary_loops > 1);
        s.non_manifold += usize::from(r.non_manifold_edges + r.non_manifold_vertices > 0);
    }
    s.mean_edge = edge_sum / edges.max(1) as f64;
    s
}

/// Fraction of the crown/gingiva label-boundary vertices (crown vertices with a gingiva
/// neighbour) that lie on the straight segment between a crown neighbour and a gingiva
/// neighbour: vertices made by cutting a jaw edge.
fn clipped_fraction(p: &Phantom) -> f64 {
    let m = &p.ios.mesh;
    let labels = p.ios.vertex_labels.as_ref().unwrap();
    let mut adj: Vec<Vec<u32>> = vec![Vec::new(); m.positions.len()];
    for t in &m.triangles {
        for k in 0..3 {
            adj[t[k] as usize].push(t[(k + 1) % 3]);
            adj[t[(k + 1) % 3] as usize].push(t[k]);
        }
    }
    let (mut on_cut, mut boundary) = (0usize, 0usize);
    for v in 0..m.positions.len() {
        let l = labels[v];
        if l == 0 || !adj[v].iter().any(|&w| labels[w as usize] == 0) {
            continue;
        }
        boundary += 1;
        let pv = m.positions[v];
        let cut = adj[v].iter().any(|&a| {
            labels[a as usize] == l
                && adj[v].iter().any(|&b| {
                    let (pa, pb) = (m.positions[a as usize], m.positions[b as usize]);
                    labels[b as usize] == 0
                        && ((pv - pa).length() + (pb - pv).length() - (pb - pa).length()).abs()
                            < 1e-9
                })
        });
        on_cut += usize::from(cut);
    }
    on_cut as f64 / boundary.max(1) as f64
}

/// The truth stays valid: every IOS tooth has its crown, crown vertices mapped back lie on the
/// true surface (up to the noise, and the label bleed for the 10 % quantile: `q90_max`; a
/// coarse crown has few vertices, so its bleed band of gingiva is a larger share of them),
/// transforms compose.
fn check_truth(p: &Phantom, what: &str, q90_max: f64) {
    let crowns = p.ios_crowns();
    for (fdi, t) in &p.truth.teeth {
        assert_eq!(crowns.contains_key(fdi), t.in_ios, "{what}: crown {fdi}");
        let w = t.surface.positions[0];
        let c = p.truth.world_to_cbct.apply(w);
        let expect = p.truth.world_to_ios.apply(t.ios_drift.apply(w));
        assert!((t.cbct_to_ios.apply(c) - expect).length() < 1e-9);
    }
    for (fdi, crown) in &crowns {
        let t = &p.truth.teeth[fdi];
        let back = p.truth.world_to_ios.compose(&t.ios_drift).inverse();
        let sd = SurfaceDistance::new(&t.surface);
        let mut d: Vec<f64> = crown
            .positions
            .iter()
            .map(|&q| sd.distance(back.apply(q)))
            .collect();
        d.sort_by(f64::total_cmp);
        let (median, q90) = (d[d.len() / 2], d[d.len() * 9 / 10]);
        assert!(median < 0.03, "{what} crown {fdi}: median {median} mm");
        assert!(q90 < q90_max, "{what} crown {fdi}: 90% quantile {q90} mm");
    }
    let r = p.ios.mesh.topology_report();
    assert_eq!(r.non_manifold_edges, 0, "{what}: IOS manifold edges");
}

#[test]
fn rough_crowns_hold_slivers_folds_a_clipped_margin_and_label_noise() {
    let clean = crown_stats(&generate(1, Jaw::Upper, Variant::Full, IosExport::Clean));
    assert_eq!(clean.crossings, 0, "clean crowns are cleaned: {clean:?}");
    assert_eq!(clean.multi_component + clean.multi_loop, 0, "{clean:?}");
    for (seed, jaw) in [(1, Jaw::Upper), (2, Jaw::Lower)] {
        let p = generate(seed, jaw, Variant::Full, IosExport::Rough);
        let what = format!("rough seed {seed} {jaw:?}");
        check_truth(&p, &what, 0.06);
        let s = crown_stats(&p);
        let sliver = s.slivers as f64 / s.faces as f64;
        let clean_sliver = clean.slivers as f64 / clean.faces as f64;
        assert!(
            sliver > 0.01 && sliver > 5.0 * clean_sliver,
            "{what}: {:.2} % crown faces under 5° (clean {:.2} %)",
            100.0 * sliver,
            100.0 * clean_sliver
        );
        assert!(s.crossings >= 500, "{what}: {s:?}");
        assert!(s.multi_component >= 2 && s.multi_loop >= 3, "{what}: {s:?}");
        assert_eq!(s.non_manifold, 0, "{what}: every crown manifold: {s:?}");
        assert!((0.16..0.23).contains(&s.mean_edge), "{what}: {s:?}");
        let ratio = s.vertices as f64 / clean.vertices as f64;
        assert!((0.8..1.3).contains(&ratio), "{what}: {s:?} vs {clean:?}");
        let clipped = clipped_fraction(&p);
        assert!(
            clipped > 0.95,
            "{what}: {clipped} of the margin on cut edges"
        );
    }
}

#[test]
fn coarse_and_dense_exports_have_their_resolution() {
    let stats: Vec<(IosExport, CrownStats)> = IosExport::ROUGH
        .into_iter()
        .map(|e| {
            let p = generate(5, Jaw::Lower, Variant::PartialArch, e);
            let q90 = if e == IosExport::Coarse { 0.2 } else { 0.06 };
            check_truth(&p, e.name(), q90);
            (e, crown_stats(&p))
        })
        .collect();
    let rough = &stats[0].1;
    for (e, s) in &stats {
        let ratio = s.vertices as f64 / rough.vertices as f64;
        let (edge, vertex_ratio) = match e {
            IosExport::Rough => (0.16..0.23, 1.0..1.01),
            IosExport::Coarse => (0.35..0.55, 0.1..0.25),
            IosExport::Dense2 => (0.12..0.17, 1.7..2.3),
            IosExport::Dense4 => (0.09..0.125, 3.4..4.6),
            IosExport::Subdivided => (0.055..0.085, 7.0..9.2),
            IosExport::Clean => unreachable!(),
        };
        let what = format!("{}: {s:?}, {ratio:.2}x the rough crown vertices", e.name());
        assert!(edge.contains(&s.mean_edge), "{what}");
        assert!(vertex_ratio.contains(&ratio), "{what}");
        assert!(s.crossings > 0, "{what}");
        assert!(s.multi_component + s.multi_loop > 0, "{what}");
        assert_eq!(s.non_manifold, 0, "{what}");
    }
}

#[test]
fn every_variant_and_both_jaws_have_rough_exports() {
    for (k, variant) in Variant::ALL.into_iter().enumerate() {
        let jaw = if k % 2 == 0 { Jaw::Lower } else { Jaw::Upper };
        let p = generate(20 + k as u64, jaw, variant, IosExport::Coarse);
        let what = format!("coarse {} {jaw:?}", variant.name());
        check_truth(&p, &what, 0.2);
        let s = crown_stats(&p);
        assert!(s.crossings > 0 && s.slivers > 0, "{what}: {s:?}");
        let in_ios = p.truth.teeth.values().filter(|t| t.in_ios).count();
        assert_eq!(s.crowns, in_ios, "{what}");
    }
}

#[test]
fn rough_exports_are_deterministic_and_the_clean_default_is_the_clean_scan() {
    let bits = |p: &Phantom| -> Vec<u64> {
        p.ios
            .mesh
            .positions
            .iter()
            .flat_map(|q| q.to_array().map(f64::to_bits))
            .collect()
    };
    let a = generate(7, Jaw::Upper, Variant::PartialArch, IosExport::Rough);
    // Generated anew, not read from the test command's phantom cache.
    let mut opts = PhantomOptions {
        seed: 7,
        jaw: Jaw::Upper,
        variant: Variant::PartialArch,
        ..Default::default()
    };
    opts.realism.ios.rough = IosExport::Rough.roughness();
    let b = Phantom::generate_uncached(&opts).expect("phantom generates");
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(a.ios.mesh.triangles, b.ios.mesh.triangles);
    assert_eq!(a.ios.vertex_labels, b.ios.vertex_labels);
    // The roughness touches the IOS only: CBCT and truth are the clean jaw's, bit for bit.
    let clean = generate(7, Jaw::Upper, Variant::PartialArch, IosExport::Clean);
    assert_eq!(PhantomOptions::default().realism.ios.rough, None);
    assert_ne!(bits(&a), bits(&clean));
    for (fdi, m) in &clean.cbct {
        assert_eq!(m.positions, a.cbct[fdi].positions);
        assert_eq!(m.triangles, a.cbct[fdi].triangles);
    }
    for (fdi, t) in &clean.truth.teeth {
        let r = &a.truth.teeth[fdi];
        assert_eq!(t.cbct_to_ios, r.cbct_to_ios);
        assert_eq!(t.surface.positions, r.surface.positions);
        assert_eq!(t.margin, r.margin);
    }
    // The clean jaw's crowns are single disks without crossings.
    for (fdi, c) in clean.ios_crowns() {
        assert_disk(&c, &format!("clean crown {fdi}"));
        assert!(self_intersections(&c).is_empty(), "clean crown {fdi}");
    }
}
