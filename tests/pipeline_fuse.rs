//! The one-call fuse on synthetic jaws: equal, bit for bit, to registration followed by
//! `fuse_jaw` done by hand; deterministic across runs; a tooth whose fusion fails is reported
//! while the others are delivered; bad input is an error naming the tooth.

use toothfuse::arch::Jaw;
use toothfuse::fuse::{fuse_jaw, ios_crowns};
use toothfuse::phantom::{Phantom, PhantomOptions, Variant};
use toothfuse::pipeline::{self, PipelineOptions, PipelineResult, transforms_of};
use toothfuse::register::{OutputFrame, Preset, register};

fn phantom(seed: u64, jaw: Jaw, variant: Variant) -> Phantom {
    Phantom::generate(&PhantomOptions {
        seed,
        jaw,
        variant,
        ..PhantomOptions::default()
    })
    .expect("phantom")
}

/// Report JSON without timing, position bits, triangles, labels, sources.
type Fingerprint = (String, Vec<[u64; 3]>, Vec<[u32; 3]>, Vec<i32>, Vec<u8>);

/// Everything deterministic of a result (the timing is not).
fn fingerprint(r: &PipelineResult) -> Fingerprint {
    let mut rep = r.report();
    rep.timing_ms.clear();
    (
        serde_json::to_string(&rep).unwrap(),
        r.jaw
            .mesh
            .positions
            .iter()
            .map(|p| p.to_array().map(f64::to_bits))
            .collect(),
        r.jaw.mesh.triangles.clone(),
        r.jaw.labels.clone(),
        r.jaw.source.clone(),
    )
}

#[test]
fn one_call_equals_register_then_fuse_jaw_bitwise() {
    for (seed, jaw, variant, preset, frame) in [
        (
            3,
            Jaw::Upper,
            Variant::PartialArch,
            Preset::Default,
            OutputFrame::Cbct,
        ),
        (
            3,
            Jaw::Upper,
            Variant::PartialArch,
            Preset::Paper,
            OutputFrame::Ios,
        ),
    ] {
        let p = phantom(seed, jaw, variant);
        let opts = PipelineOptions::preset(preset).with_frame(frame);
        let r = pipeline::fuse(&p.ios, &p.cbct, &opts).expect("one-call fuse");
        let crowns = ios_crowns(&p.ios).unwrap();
        let mut ro = opts.register.clone();
        ro.frame = frame;
        let reg = register(&crowns, &p.cbct, &ro).unwrap();
        assert_eq!(reg.teeth, r.registration.teeth, "seed {seed}");
        assert_eq!(reg.skipped, r.registration.skipped, "seed {seed}");
        let jaw = fuse_jaw(&p.ios, &p.cbct, &transforms_of(&reg), &opts.fuse).unwrap();
        assert_eq!(jaw.mesh, r.jaw.mesh, "seed {seed}");
        assert_eq!(jaw.labels, r.jaw.labels);
        assert_eq!(jaw.source, r.jaw.source);
        assert_eq!(
            jaw.teeth.keys().collect::<Vec<_>>(),
            r.jaw.teeth.keys().collect::<Vec<_>>()
        );
        assert!(!r.jaw.teeth.is_empty());
        // The report follows the contract: every fused tooth watertight, frame named.
        let rep = r.report();
        assert_eq!(rep.frame, frame.name());
        assert_eq!(rep.teeth.len(), r.jaw.teeth.len());
        for k in ["register", "cut", "stitch", "total"] {
            assert!(rep.timing_ms[k] >= 0.0, "{k}");
        }
        // Both stages are timed and together make the fusion's wall time.
        assert!(rep.timing_ms["cut"] > 0.0 && rep.timing_ms["stitch"] > 0.0);
        let sum = rep.timing_ms["cut"] + rep.timing_ms["stitch"];
        assert!((sum - rep.timing_ms["fuse"]).abs() <= 1e-9 * rep.timing_ms["fuse"].max(1.0));
        if preset == Preset::Paper {
            // The paper preset is only required to be reproduced faithfully, not accurate.
            continue;
        }
        assert!(rep.teeth.iter().all(|t| t.watertight), "seed {seed}");
        // The registration is accurate against the truth (loosely: the fused jaw is placed).
        for (fdi, acc) in pipeline::accuracy::fusion_accuracy(&p, &r) {
            assert!(acc.tre_mm < 0.5, "seed {seed} tooth {fdi}: {acc:?}");
            assert!(
                acc.crown_mean_mm < acc.cbct_crown_mean_mm,
                "tooth {fdi}: {acc:?}"
            );
        }
    }
}

#[test]
fn deterministic_bit_for_bit() {
    let p = phantom(5, Jaw::Lower, Variant::PartialArch);
    let opts = PipelineOptions::default();
    let a = pipeline::fuse(&p.ios, &p.cbct, &opts).unwrap();
    let b = pipeline::fuse(&p.ios, &p.cbct, &opts).unwrap();
    assert_eq!(fingerprint(&a), fingerprint(&b));
    // Per-tooth crowns give the same fused jaw as the labeled jaw.
    let c = pipeline::fuse_crowns(&ios_crowns(&p.ios).unwrap(), &p.cbct, &opts).unwrap();
    assert_eq!(c.registration.teeth, a.registration.teeth);
    assert_eq!(c.jaw.mesh.triangles.len(), a.jaw.mesh.triangles.len());
}

#[test]
fn failing_tooth_is_reported_others_delivered() {
    let p = phantom(6, Jaw::Upper, Variant::PartialArch);
    let mut cbct = p.cbct.clone();
    let (&bad, tooth) = cbct.iter_mut().next().unwrap();
    // Open the apex of one CBCT tooth: registration still works on the crown, but the fused
    // mesh cannot be closed.
    let axis = p.truth.world_to_cbct.apply_vector(p.truth.teeth[&bad].axis);
    let h: Vec<f64> = (0..tooth.triangles.len())
        .map(|f| tooth.corners(f).iter().map(|v| v.dot(axis)).sum::<f64>() / 3.0)
        .collect();
    let lo = h.iter().copied().fold(f64::INFINITY, f64::min);
    let keep: Vec<[u32; 3]> = tooth
        .triangles
        .iter()
        .zip(&h)
        .filter(|(_, z)| **z > lo + 2.0)
        .map(|(t, _)| *t)
        .collect();
    assert!(keep.len() < tooth.triangles.len());
    tooth.triangles = keep;
    let r = pipeline::fuse(&p.ios, &cbct, &PipelineOptions::default()).expect("fuse");
    let rep = r.report();
    let sk = rep
        .skipped
        .iter()
        .find(|s| s.fdi == bad)
        .unwrap_or_else(|| panic!("tooth {bad} not reported: {:?}", rep.skipped));
    assert!(sk.reason.contains("fusion failed"), "{}", sk.reason);
    assert!(rep.teeth.iter().all(|t| t.registration.fdi != bad));
    let others = p.cbct.len() - 1;
    assert_eq!(rep.teeth.len(), others, "{:?}", rep.skipped);
    assert!(rep.teeth.iter().all(|t| t.watertight));
    assert!(r.jaw.labels.iter().all(|&l| l != bad as i32));
}

#[test]
fn bad_input_names_the_tooth() {
    let p = phantom(7, Jaw::Upper, Variant::PartialArch);
    let mut cbct = p.cbct.clone();
    let (&bad, tooth) = cbct.iter_mut().next().unwrap();
    tooth.positions[0].x = f64::NAN;
    let e = pipeline::fuse(&p.ios, &cbct, &PipelineOptions::default()).unwrap_err();
    assert!(e.to_string().contains(&bad.to_string()), "{e}");
    // An IOS without labels.
    let mut ios = p.ios.clone();
    ios.vertex_labels = None;
    ios.face_labels = None;
    let e = pipeline::fuse(&ios, &p.cbct, &PipelineOptions::default()).unwrap_err();
    assert!(e.to_string().contains("labels"), "{e}");
}
