//! Whole jaw: split the labeled IOS jaw into crowns, fuse every tooth present in both
//! modalities, report the teeth present in only one, and merge everything into one mesh with
//! per-vertex FDI labels and sources.

use super::{FuseOptions, FusedTooth, VertexSource, fuse_tooth};
use crate::mesh::{LabeledMesh, TriMesh, split_by_face_labels, split_by_vertex_labels};
use crate::{Error, Result, Rigid};
use std::collections::BTreeMap;

/// The rigid transforms of one tooth into the output frame.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct ToothTransforms {
    /// CBCT frame → output frame.
    pub cbct_to_output: Rigid,
    /// IOS frame → output frame.
    pub ios_to_output: Rigid,
}

/// A fused jaw.
#[derive(Clone, Debug, Default)]
pub struct FusedJaw {
    /// Fused teeth by FDI.
    pub teeth: BTreeMap<u8, FusedTooth>,
    /// All fused (and passed-through) teeth in one mesh.
    pub mesh: TriMesh,
    /// Per vertex of `mesh`: FDI number.
    pub labels: Vec<i32>,
    /// Per vertex of `mesh`: [`VertexSource`] as `u8`.
    pub source: Vec<u8>,
    /// Teeth whose crown is in the IOS but which have no CBCT tooth (not in the output).
    pub ios_only: Vec<u8>,
    /// Teeth in the CBCT without an IOS crown.
    pub cbct_only: Vec<u8>,
    /// CBCT-only teeth copied into `mesh` unfused (all CBCT source).
    pub passed_through: Vec<u8>,
    /// Teeth in both modalities whose fusion failed, with the reason.
    pub failed: Vec<(u8, Error)>,
}

/// Per-tooth IOS crowns from a labeled jaw (label 0 = gingiva is skipped), by FDI.
pub fn ios_crowns(ios: &LabeledMesh) -> Result<BTreeMap<u8, TriMesh>> {
    let parts = if let Some(l) = &ios.vertex_labels {
        split_by_vertex_labels(&ios.mesh, l)?
    } else if let Some(l) = &ios.face_labels {
        split_by_face_labels(&ios.mesh, l)?
    } else {
        return Err(Error::MissingData(
            "the IOS mesh has no tooth labels".into(),
        ));
    };
    Ok(parts
        .into_iter()
        .filter(|(l, _)| *l > 0 && *l <= u8::MAX as i32)
        .map(|(l, s)| (l as u8, s.mesh))
        .collect())
}

/// Fuses every tooth present in both the IOS (labeled jaw) and the CBCT, with the given
/// per-tooth transforms into the output frame. A tooth without a transform, or whose fusion
/// fails, is listed in [`FusedJaw::failed`]; the others are still fused.
pub fn fuse_jaw(
    ios: &LabeledMesh,
    cbct: &BTreeMap<u8, TriMesh>,
    transforms: &BTreeMap<u8, ToothTransforms>,
    opts: &FuseOptions,
) -> Result<FusedJaw> {
    let crowns = ios_crowns(ios)?;
    let mut jaw = FusedJaw::default();
    let mut work = Vec::new();
    for (&fdi, crown) in &crowns {
        let Some(tooth) = cbct.get(&fdi) else {
            jaw.ios_only.push(fdi);
            continue;
        };
        let Some(t) = transforms.get(&fdi) else {
            jaw.failed.push((
                fdi,
                Error::MissingData("no transform for this tooth".into()).in_tooth(fdi),
            ));
            continue;
        };
        work.push((fdi, crown, tooth, t));
    }
    // Teeth are independent: fused on up to 4 threads, each result depends on its tooth only,
    // so the output is the same bit for bit whatever the thread count.
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .clamp(1, 4)
        .min(work.len().max(1));
    let fuse_one = |&(fdi, crown, tooth, t): &(u8, &TriMesh, &TriMesh, &ToothTransforms)| {
        (
            fdi,
            fuse_tooth(fdi, crown, tooth, &t.ios_to_output, &t.cbct_to_output, opts),
        )
    };
    let results: Vec<(u8, Result<FusedTooth>)> = if threads <= 1 {
        work.iter().map(fuse_one).collect()
    } else {
        std::thread::scope(|s| {
            let handles: Vec<_> = (0..threads)
                .map(|k| {
                    let work = &work;
                    let fuse_one = &fuse_one;
                    s.spawn(move || {
                        work.iter()
                            .skip(k)
                            .step_by(threads)
                            .map(fuse_one)
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            let mut all = Vec::new();
            for h in handles {
                match h.join() {
                    Ok(r) => all.extend(r),
                    Err(p) => std::panic::resume_unwind(p),
                }
            }
            all.sort_by_key(|r| r.0);
            all
        })
    };
    for (fdi, r) in results {
        match r {
            Ok(f) => {
                jaw.teeth.insert(fdi, f);
            }
            Err(e) => jaw.failed.push((fdi, e)),
        }
    }
    jaw.failed.sort_by_key(|f| f.0);
    jaw.cbct_only = cbct
        .keys()
        .copied()
        .filter(|k| !crowns.contains_key(k))
        .collect();
    let mut parts: BTreeMap<u8, (TriMesh, Vec<u8>)> = jaw
        .teeth
        .iter()
        .map(|(&k, f)| (k, (f.mesh.clone(), f.source.clone())))
        .collect();
    if opts.pass_through_cbct_only {
        for &fdi in &jaw.cbct_only {
            let m = cbct[&fdi].transformed(
                &transforms
                    .get(&fdi)
                    .map(|t| t.cbct_to_output)
                    .unwrap_or_default(),
            );
            let n = m.positions.len();
            parts.insert(fdi, (m, vec![VertexSource::Cbct as u8; n]));
            jaw.passed_through.push(fdi);
        }
    }
    for (fdi, (m, s)) in parts {
        jaw.mesh.append(&m);
        jaw.labels
            .extend(std::iter::repeat_n(fdi as i32, m.positions.len()));
        jaw.source.extend(s);
    }
    Ok(jaw)
}
