//! Shared by the tests of the per-jaw mask split (`volume_split*.rs`): the STS 2024 mask's teeth,
//! the real-anatomy phantom built on them with the mask placed in its CBCT frame, surfacing,
//! the gated fusion with its accuracy, and voxel measures (Dice, dilation).
#![allow(dead_code)]

use crate::real_data;
use glam::{DMat4, DVec3};
use std::collections::BTreeMap;
use toothfuse::TriMesh;
use toothfuse::arch::Jaw;
use toothfuse::io::read_label_volume;
use toothfuse::phantom::Phantom;
use toothfuse::pipeline::{self, PipelineOptions};
use toothfuse::volume::{Frame, LabelVolume, SurfaceOptions, VolumeScheme, surface_teeth};

/// The STS mask's teeth of one jaw (FDI labels), cropped to them.
pub fn mask(jaw: Jaw) -> Option<LabelVolume> {
    let p = real_data::real(real_data::STS_MASK)?;
    let v = read_label_volume(&p, Frame::Lps).unwrap().volume;
    let keep = move |l: u16| match jaw {
        Jaw::Lower => (31..=48).contains(&l),
        Jaw::Upper => (11..=28).contains(&l) && l != 11 && l != 14,
    };
    Some(
        v.relabeled(|l| if keep(l) { l } else { 0 })
            .cropped_to_labels(),
    )
}

/// The phantom built on the mask's teeth and the mask placed in its CBCT frame.
pub fn phantom(vol: &LabelVolume, jaw: Jaw) -> (Phantom, LabelVolume) {
    let p = real_data::phantom_on(vol, jaw, 5);
    let w2c = p.truth.world_to_cbct;
    let mut placed = vol.clone();
    placed.voxel_to_world =
        DMat4::from_mat3_translation(w2c.rot, w2c.trans) * placed.voxel_to_world;
    (p, placed)
}

/// The lower-jaw phantom and its placed mask, built once for all tests of this file.
pub fn lower() -> Option<(Phantom, LabelVolume)> {
    static LOWER: std::sync::OnceLock<Option<(Phantom, LabelVolume)>> = std::sync::OnceLock::new();
    LOWER
        .get_or_init(|| mask(Jaw::Lower).map(|v| phantom(&v, Jaw::Lower)))
        .clone()
}

/// Every tooth label of `v` surfaced (FDI numbering, default surfacing), by FDI.
pub fn surfaced(v: &LabelVolume) -> BTreeMap<u8, TriMesh> {
    surface_teeth(v, VolumeScheme::Fdi, &SurfaceOptions::default())
        .unwrap()
        .teeth
        .into_iter()
        .map(|(f, t)| (f, t.mesh))
        .collect()
}

/// Mean TRE (mm) over the fused teeth, the number fused, and whether all are watertight.
pub fn fuse_and_measure(
    p: &Phantom,
    cbct: BTreeMap<u8, TriMesh>,
    what: &str,
) -> (f64, usize, bool) {
    fuse_gated(p, cbct, what).0
}

/// The fusion with the default options (the registration gate must pass it), with the gate's
/// report.
pub fn fuse_gated(
    p: &Phantom,
    cbct: BTreeMap<u8, TriMesh>,
    what: &str,
) -> ((f64, usize, bool), toothfuse::register::GateReport) {
    let mut p = p.clone();
    p.cbct = cbct;
    let r = pipeline::fuse(&p.ios, &p.cbct, &PipelineOptions::default())
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    let acc = pipeline::accuracy::fusion_accuracy(&p, &r);
    let watertight = r.report().teeth.iter().all(|t| t.watertight);
    for (fdi, a) in &acc {
        eprintln!("{what}: tooth {fdi} TRE {:.3} mm", a.tre_mm);
    }
    let mean = acc.values().map(|a| a.tre_mm).sum::<f64>() / acc.len().max(1) as f64;
    let g = r.registration.gate;
    eprintln!(
        "{what}: gate mismatch {:.2} (fit {:.3} mm, lateral motion {:.3} mm), CBCT surface \
         offset {:+.3} mm",
        g.mismatch, g.fit_mm, g.tooth_translation_mm, g.surface_offset_mm
    );
    ((mean, r.jaw.teeth.len(), watertight), g)
}

/// Per tooth, the Dice overlap of the split's voxels with the mask's true tooth voxels.
pub fn dice(split: &LabelVolume, truth: &LabelVolume) -> BTreeMap<u16, f64> {
    overlap(split, truth)
        .into_iter()
        .map(|(l, (both, n_split, n_truth))| (l, 2.0 * both as f64 / (n_split + n_truth) as f64))
        .collect()
}

/// Per true tooth: voxels in both the split tooth and the true tooth, in the split tooth, in
/// the true tooth.
pub fn overlap(split: &LabelVolume, truth: &LabelVolume) -> BTreeMap<u16, (usize, usize, usize)> {
    let inv = truth.voxel_to_world.inverse();
    let mut both: BTreeMap<u16, usize> = BTreeMap::new();
    let t_counts = truth.label_counts();
    let s_counts = split.label_counts();
    let [nx, ny, _] = split.dims;
    for (id, &l) in split.labels.iter().enumerate() {
        if l == 0 {
            continue;
        }
        let ijk = DVec3::new(
            (id % nx) as f64,
            ((id / nx) % ny) as f64,
            (id / (nx * ny)) as f64,
        );
        let t = inv.transform_point3(split.world(ijk)).round();
        let idx = truth.idx(t.x as usize, t.y as usize, t.z as usize);
        if truth.labels[idx] == l {
            *both.entry(l).or_default() += 1;
        }
    }
    t_counts
        .iter()
        .map(|(&l, &n)| {
            let b = both.get(&l).copied().unwrap_or(0);
            (l, (b, s_counts.get(&l).copied().unwrap_or(0), n))
        })
        .collect()
}

/// Each tooth label grown by one voxel into the background (smallest label wins), `n` times:
/// closes the gaps between neighbouring teeth so that they touch, as in a blurrier segmentation.
pub fn dilate(v: &LabelVolume, n: usize) -> LabelVolume {
    let mut v = v.clone();
    let [nx, ny, nz] = v.dims;
    for _ in 0..n {
        let src = v.labels.clone();
        for k in 1..nz - 1 {
            for j in 1..ny - 1 {
                for i in 1..nx - 1 {
                    let id = v.idx(i, j, k);
                    if src[id] != 0 {
                        continue;
                    }
                    let nb = [id - 1, id + 1, id - nx, id + nx, id - nx * ny, id + nx * ny];
                    v.labels[id] = nb
                        .iter()
                        .map(|&u| src[u])
                        .filter(|&l| l != 0)
                        .min()
                        .unwrap_or(0);
                }
            }
        }
    }
    v
}
