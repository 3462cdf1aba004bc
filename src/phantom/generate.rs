//! `Phantom::generate`: lays out the teeth, draws the variant's scenario, the drift and the
//! frames, meshes the truth, and simulates the IOS and the CBCT.

use super::cbct::{self, Distortion, Metal, Neighbour};
use super::drift::{DriftAmount, drifts, random_pose};
use super::ios::{self, Contact, IosTooth};
use super::layout::{PlacedTooth, contact, jaw_teeth, layout};
use super::project::{mesh_implicit, project};
use super::rng::Rng;
use super::{Phantom, PhantomOptions, ToothTruth, Truth, Variant};
use crate::arch::{Jaw, ToothType, arch_position, tooth_type};
use crate::mesh::{LabeledMesh, TriMesh};
use crate::{Result, Rigid};
use glam::DVec3;
use std::collections::BTreeMap;

/// Which teeth exist and where each modality holds them.
struct Scenario {
    /// Teeth that exist, arch order.
    present: Vec<u8>,
    in_ios: Vec<u8>,
    in_cbct: Vec<u8>,
    metal: Option<u8>,
}

fn scenario(all: Vec<u8>, variant: Variant, rng: &mut Rng) -> Result<Scenario> {
    let mut present = all.clone();
    let mut in_ios = all.clone();
    let mut in_cbct = all.clone();
    let mut metal = None;
    match variant {
        Variant::Full | Variant::HeavyDrift => {}
        Variant::PartialArch => {
            if all.len() < 3 {
                return Err(crate::Error::InvalidArgument(
                    "a partial arch needs at least 3 teeth".into(),
                ));
            }
            let n = (3 + rng.below(3)).min(all.len());
            let start = rng.below(all.len() - n + 1);
            present = all[start..start + n].to_vec();
            in_ios = present.clone();
            in_cbct = present.clone();
        }
        Variant::MissingTeeth => {
            if all.len() < 7 {
                return Err(crate::Error::InvalidArgument(
                    "missing-teeth variant needs at least 7 teeth".into(),
                ));
            }
            let mut pool: Vec<u8> = all.clone();
            let mut take = |rng: &mut Rng| pool.remove(rng.below(pool.len()));
            let gone = take(rng);
            let ios_missing = [take(rng), take(rng)];
            let cbct_missing = [take(rng), take(rng)];
            present.retain(|&t| t != gone);
            in_ios.retain(|t| *t != gone && !ios_missing.contains(t));
            in_cbct.retain(|t| *t != gone && !cbct_missing.contains(t));
        }
        Variant::MetalArtefact => {
            let posterior: Vec<u8> = all
                .iter()
                .copied()
                .filter(|&t| matches!(tooth_type(t), ToothType::Premolar | ToothType::Molar))
                .collect();
            let pool = if posterior.is_empty() {
                &all
            } else {
                &posterior
            };
            metal = Some(pool[rng.below(pool.len())]);
        }
    }
    Ok(Scenario {
        present,
        in_ios,
        in_cbct,
        metal,
    })
}

/// Parametric teeth: all 14 positions laid out (so gaps stay where teeth are missing), then the
/// present ones kept.
fn parametric(jaw: Jaw, present: &[u8], rng: &mut Rng) -> Vec<PlacedTooth> {
    let all = layout(jaw, &jaw_teeth(jaw), rng);
    all.into_iter()
        .filter(|t| present.contains(&t.shape.fdi))
        .collect()
}

/// The true surface of a placed tooth: surface nets at `h`, vertices projected onto the
/// implicit surface.
pub fn true_surface(t: &PlacedTooth, h: f64) -> TriMesh {
    let (lo, hi) = t.world_box();
    let mut m = mesh_implicit(lo, hi, h, |p| t.eval(p));
    for p in &mut m.positions {
        *p = project(*p, &|q| t.eval(q), 0.5 * h);
    }
    m
}

/// Arch neighbours among `teeth` (consecutive in arch order and actually close): pairs of
/// indices with their contact point.
fn touching(teeth: &[&PlacedTooth]) -> Vec<(usize, usize, DVec3)> {
    let mut out = Vec::new();
    for i in 0..teeth.len().saturating_sub(1) {
        let (g, c) = contact(teeth[i], teeth[i + 1]);
        if g.is_finite() && g < 0.6 {
            out.push((i, i + 1, c));
        }
    }
    out
}

/// The phantom's teeth and where each modality holds them: the scenario drawn for the variant,
/// the teeth placed (parametric, or the caller's anatomy) in arch order, and the map from the
/// caller's world frame to the canonical jaw frame the simulation works in.
fn arrange(opts: &PhantomOptions, root: &Rng) -> Result<(Scenario, Vec<PlacedTooth>, Rigid)> {
    let jaw = opts.jaw;
    let mut srng = root.fork(2);
    // Real anatomy is simulated in a canonical jaw frame (occlusal direction ±Z); `canon` maps
    // the caller's world frame to it (identity for parametric teeth).
    let (all, real) = match &opts.anatomy {
        Some(anatomy) => {
            let r = super::real::prepare(anatomy, jaw, &mut root.fork(7))?;
            (
                r.teeth.iter().map(|t| t.shape.fdi).collect::<Vec<u8>>(),
                Some(r),
            )
        }
        None => (jaw_teeth(jaw), None),
    };
    let sc = scenario(all, opts.variant, &mut srng)?;
    let (mut teeth, canon) = match real {
        Some(r) => (
            r.teeth
                .into_iter()
                .filter(|t| sc.present.contains(&t.shape.fdi))
                .collect::<Vec<_>>(),
            r.canon,
        ),
        None => (
            parametric(jaw, &sc.present, &mut root.fork(1)),
            crate::Rigid::IDENTITY,
        ),
    };
    teeth.sort_by_key(|t| arch_position(t.shape.fdi));
    Ok((sc, teeth, canon))
}

/// The scanner frames of a phantom: per tooth the IOS stitching drift, the two scanner poses and
/// the occlusal direction.
struct Frames {
    drift: Vec<Rigid>,
    world_to_ios: Rigid,
    world_to_cbct: Rigid,
    occ: DVec3,
}

/// Draws the drift along the scan path and the two scanner frames.
fn frames(opts: &PhantomOptions, teeth: &[PlacedTooth], root: &Rng) -> Frames {
    let realism = &opts.realism;
    let mut drng = root.fork(3);
    let heavy = if opts.variant == Variant::HeavyDrift {
        realism.heavy_drift_factor
    } else {
        1.0
    };
    let amount = DriftAmount {
        angle_deg: drng.range(0.4, 0.6) * realism.drift_scale * heavy,
        shift_mm: drng.range(0.15, 0.25) * realism.drift_scale * heavy,
    };
    let start_first = drng.sign() > 0.0;
    let centers: Vec<DVec3> = teeth.iter().map(|t| t.crown_center()).collect();
    let drift = drifts(&centers, amount, start_first, &mut drng);
    let mut prng = root.fork(4);
    let world_to_ios = random_pose(&mut prng, 40.0);
    let world_to_cbct = random_pose(&mut prng, 40.0);
    let occ = if opts.jaw == Jaw::Upper {
        -DVec3::Z
    } else {
        DVec3::Z
    };
    Frames {
        drift,
        world_to_ios,
        world_to_cbct,
        occ,
    }
}

/// The IOS jaw mesh (IOS frame, per-vertex labels) and per IOS tooth its true margin (world).
fn simulate_ios(
    opts: &PhantomOptions,
    sc: &Scenario,
    teeth: &[PlacedTooth],
    f: &Frames,
    root: &Rng,
) -> (LabeledMesh, BTreeMap<u8, Vec<DVec3>>) {
    let realism = &opts.realism;
    let (drift, occ) = (&f.drift, f.occ);
    let mut irng = root.fork(5);
    let ios_idx: Vec<usize> = (0..teeth.len())
        .filter(|&i| sc.in_ios.contains(&teeth[i].shape.fdi))
        .collect();
    let ios_teeth: Vec<IosTooth> = ios_idx
        .iter()
        .map(|&i| {
            let mut r = irng.fork(teeth[i].shape.fdi as u64);
            let amp = realism.ios.label_bleed;
            IosTooth {
                tooth: teeth[i].moved(&drift[i]),
                fdi: teeth[i].shape.fdi,
                bleed: (
                    amp,
                    r.range(0.0, std::f64::consts::TAU),
                    r.range(0.0, std::f64::consts::TAU),
                    amp * r.range(-0.4, 0.4),
                ),
            }
        })
        .collect();
    let ios_refs: Vec<&PlacedTooth> = ios_idx.iter().map(|&i| &teeth[i]).collect();
    let contacts: Vec<Contact> = touching(&ios_refs)
        .into_iter()
        .map(|(a, b, c)| Contact {
            point: 0.5 * (drift[ios_idx[a]].apply(c) + drift[ios_idx[b]].apply(c)),
        })
        .collect();
    // True margins (world): where the simulated gingiva meets each IOS tooth; nominal for the
    // others.
    let mut margins: BTreeMap<u8, Vec<DVec3>> = BTreeMap::new();
    let ios = if ios_teeth.is_empty() {
        LabeledMesh::default()
    } else {
        let (mut mesh, labels, ms) =
            ios::simulate(&ios_teeth, &contacts, occ, &realism.ios, &mut irng);
        for (k, m) in ms.into_iter().enumerate() {
            let back = drift[ios_idx[k]].inverse();
            margins.insert(
                teeth[ios_idx[k]].shape.fdi,
                m.into_iter().map(|p| back.apply(p)).collect(),
            );
        }
        mesh.transform(&f.world_to_ios);
        LabeledMesh {
            mesh,
            vertex_labels: Some(labels),
            face_labels: None,
        }
    };
    (ios, margins)
}

/// The CBCT teeth (CBCT frame), each simulated on its own in parallel.
fn simulate_cbct(
    opts: &PhantomOptions,
    sc: &Scenario,
    teeth: &[PlacedTooth],
    f: &Frames,
    root: &Rng,
) -> Result<BTreeMap<u8, TriMesh>> {
    let realism = &opts.realism;
    let occ = f.occ;
    let mut crng = root.fork(6);
    let distortion = Distortion::new(&mut crng, realism.cbct.distortion);
    let cbct_idx: Vec<usize> = (0..teeth.len())
        .filter(|&i| sc.in_cbct.contains(&teeth[i].shape.fdi))
        .collect();
    // Segmentation bias: a scan-wide part plus a per-tooth part of random sign.
    let tb = realism.cbct.threshold_bias;
    let scan_bias = crng.range(-0.25, 0.25) * tb;
    let biases: Vec<f64> = cbct_idx
        .iter()
        .map(|_| (scan_bias + crng.sign() * crng.range(0.4, 1.0) * tb).clamp(-tb, tb))
        .collect();
    let cbct_refs: Vec<&PlacedTooth> = cbct_idx.iter().map(|&i| &teeth[i]).collect();
    let cbct_contacts = touching(&cbct_refs);
    // Each tooth draws from its own fork of the CBCT stream: the teeth are simulated in parallel
    // and the result does not depend on the thread count.
    let order: Vec<(usize, usize)> = cbct_idx.iter().copied().enumerate().collect();
    let simulated = crate::par::map_ordered(&order, |&(k, i)| {
        let t = &teeth[i];
        let mut trng = crng.fork(t.shape.fdi as u64);
        let metal = (sc.metal == Some(t.shape.fdi)).then(|| Metal::new(t, &mut trng));
        let neighbours: Vec<Neighbour<'_>> = cbct_contacts
            .iter()
            .filter(|c| c.0 == k || c.1 == k)
            .map(|&(a, b, c)| {
                let other = if a == k { b } else { a };
                let mut n = cbct_refs[other].crown_center() - t.crown_center();
                n -= occ * n.dot(occ);
                Neighbour {
                    tooth: cbct_refs[other],
                    bias: biases[other],
                    contact: c,
                    normal: n.normalize(),
                }
            })
            .collect();
        let mut m = cbct::simulate(
            t,
            biases[k],
            metal.as_ref(),
            &neighbours,
            &f.world_to_cbct,
            &distortion,
            &realism.cbct,
            &mut trng,
        );
        m.triangles.shrink_to_fit();
        (t.shape.fdi, m)
    });
    let mut cbct = BTreeMap::new();
    for (fdi, m) in simulated {
        if m.triangles.is_empty() {
            return Err(
                crate::Error::WrongState("CBCT simulation produced no surface".into())
                    .in_tooth(fdi),
            );
        }
        cbct.insert(fdi, m);
    }
    Ok(cbct)
}

/// The ground truth: per tooth its true surface, margin, axis and mappings, in the caller's
/// world frame.
fn truth(
    opts: &PhantomOptions,
    sc: &Scenario,
    teeth: &[PlacedTooth],
    f: &Frames,
    canon: Rigid,
    mut margins: BTreeMap<u8, Vec<DVec3>>,
) -> Truth {
    let realism = &opts.realism;
    let (drift, world_to_ios, world_to_cbct) = (&f.drift, f.world_to_ios, f.world_to_cbct);
    // Real anatomy: the caller's mesh, where it was; parametric: our mesh of the implicit (each
    // tooth on its own, in parallel).
    let surfaces = crate::par::map_ordered(teeth, |t| match &opts.anatomy {
        Some(a) => a[&t.shape.fdi].clone(),
        None => true_surface(t, realism.truth_spacing),
    });
    let mut truth_teeth = BTreeMap::new();
    for ((i, t), surface) in teeth.iter().enumerate().zip(surfaces) {
        let fdi = t.shape.fdi;
        let cbct_to_ios = world_to_ios
            .compose(&drift[i])
            .compose(&world_to_cbct.inverse());
        let uncanon = canon.inverse();
        truth_teeth.insert(
            fdi,
            ToothTruth {
                fdi,
                surface,
                margin: margins
                    .remove(&fdi)
                    .unwrap_or_else(|| t.margin(120))
                    .into_iter()
                    .map(|p| uncanon.apply(p))
                    .collect(),
                axis: uncanon.apply_vector(t.axis()),
                ios_drift: uncanon.compose(&drift[i]).compose(&canon),
                cbct_to_ios,
                in_ios: sc.in_ios.contains(&fdi),
                in_cbct: sc.in_cbct.contains(&fdi),
                metal_artefact: sc.metal == Some(fdi),
            },
        );
    }
    Truth {
        teeth: truth_teeth,
        world_to_ios: world_to_ios.compose(&canon),
        world_to_cbct: world_to_cbct.compose(&canon),
    }
}

pub(super) fn generate(opts: &PhantomOptions) -> Result<Phantom> {
    let root = Rng::new(opts.seed);
    let (sc, teeth, canon) = arrange(opts, &root)?;
    let frames = frames(opts, &teeth, &root);
    let (ios, margins) = simulate_ios(opts, &sc, &teeth, &frames, &root);
    let cbct = simulate_cbct(opts, &sc, &teeth, &frames, &root)?;
    let truth = truth(opts, &sc, &teeth, &frames, canon, margins);
    Ok(Phantom {
        jaw: opts.jaw,
        ios,
        cbct,
        truth,
    })
}
