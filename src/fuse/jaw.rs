//! Whole jaw: split the labeled IOS jaw into crowns, fuse every tooth present in both
//! modalities, report the teeth present in only one, and merge everything into one mesh with
//! per-vertex FDI labels and sources.

use super::FusedTooth;
use super::{CutTooth, FuseOptions, VertexSource, cut_tooth, stitch_tooth};
use crate::mesh::{LabeledMesh, TriMesh, split_by_face_labels, split_by_vertex_labels};
use crate::progress::Stage;
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

/// A jaw after crown removal, before stitching ([`cut_jaw`] → [`stitch_jaw`]).
#[derive(Clone, Debug, Default)]
pub struct CutJaw {
    /// Cut teeth by FDI.
    pub teeth: BTreeMap<u8, CutTooth>,
    /// Teeth whose crown is in the IOS but which have no CBCT tooth.
    pub ios_only: Vec<u8>,
    /// Teeth in the CBCT without an IOS crown.
    pub cbct_only: Vec<u8>,
    /// The CBCT-only teeth in the output frame (under their transform when they have one, else
    /// as given), for [`FuseOptions::pass_through_cbct_only`] at the stitch stage.
    pub cbct_only_meshes: BTreeMap<u8, TriMesh>,
    /// Teeth in both modalities whose cut failed (or that have no transform), with the reason.
    pub failed: Vec<(u8, Error)>,
}

/// The crown-removal stage of [`fuse_jaw`]: splits the labeled IOS jaw into crowns and runs
/// [`cut_tooth`] on every tooth present in both modalities (on up to 4 threads, deterministic).
/// A tooth without a transform, or whose cut fails, is listed in [`CutJaw::failed`]; the others
/// are still cut.
pub fn cut_jaw(
    ios: &LabeledMesh,
    cbct: &BTreeMap<u8, TriMesh>,
    transforms: &BTreeMap<u8, ToothTransforms>,
    opts: &FuseOptions,
) -> Result<CutJaw> {
    let cut = cut_crowns(&ios_crowns(ios)?, cbct, transforms, opts);
    crate::progress::check(Stage::Cut)?;
    Ok(cut)
}

/// [`cut_jaw`] on the jaw's crowns as [`ios_crowns`] gives them.
pub(crate) fn cut_crowns(
    crowns: &BTreeMap<u8, TriMesh>,
    cbct: &BTreeMap<u8, TriMesh>,
    transforms: &BTreeMap<u8, ToothTransforms>,
    opts: &FuseOptions,
) -> CutJaw {
    let mut jaw = CutJaw::default();
    let mut work = Vec::new();
    for (&fdi, crown) in crowns {
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
    // The largest crowns and teeth first (see `map_ordered_by_cost`).
    crate::progress::start(Stage::Cut, work.len());
    let results = crate::par::map_ordered_by_cost(
        &work,
        |w| w.1.triangles.len() + w.2.triangles.len(),
        |&(fdi, crown, tooth, t): &(u8, &TriMesh, &TriMesh, &ToothTransforms)| {
            let r = crate::progress::unit(Stage::Cut, || {
                cut_tooth(fdi, crown, tooth, &t.ios_to_output, &t.cbct_to_output, opts)
            });
            (fdi, r)
        },
    );
    crate::progress::ended();
    for (fdi, r) in results {
        match r {
            Ok(c) => {
                jaw.teeth.insert(fdi, c);
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
    jaw.cbct_only_meshes = jaw
        .cbct_only
        .iter()
        .map(|fdi| {
            let to_output = transforms
                .get(fdi)
                .map(|t| t.cbct_to_output)
                .unwrap_or_default();
            (*fdi, cbct[fdi].transformed(&to_output))
        })
        .collect();
    jaw
}

/// The stitching stage of [`fuse_jaw`]: runs [`stitch_tooth`] on every cut tooth (on up to 4
/// threads, deterministic) and merges the fused teeth (and, with
/// [`FuseOptions::pass_through_cbct_only`], the CBCT-only teeth) into one mesh. The cut's
/// failures are carried over; a tooth whose stitching fails joins them. `opts.cut` is not used.
/// Under a progress callback ([`crate::progress::with_progress`]) that asks to stop, the teeth
/// not yet stitched join the failures with [`Error::Cancelled`].
pub fn stitch_jaw(cut: &CutJaw, opts: &FuseOptions) -> FusedJaw {
    let work: Vec<&CutTooth> = cut.teeth.values().collect();
    crate::progress::start(Stage::Stitch, work.len());
    // The longest margins first: the band grows with the margin (see `map_ordered_by_cost`).
    let results = crate::par::map_ordered_by_cost(
        &work,
        |c| c.margin.len(),
        |c| {
            let r = crate::progress::unit(Stage::Stitch, || stitch_tooth(c, opts));
            (c.fdi(), r)
        },
    );
    crate::progress::ended();
    merged(results, cut, opts)
}

/// [`stitch_jaw`] on a cut it may consume: each cut tooth is dropped once stitched, so the cut
/// teeth and the fused ones are not all held at once (the same result).
pub(crate) fn stitch_jaw_owned(mut cut: CutJaw, opts: &FuseOptions) -> FusedJaw {
    let teeth = std::mem::take(&mut cut.teeth);
    // Each item is handed to one thread once, which takes the cut tooth out of it.
    let work: Vec<(u8, usize, std::sync::Mutex<Option<CutTooth>>)> = teeth
        .into_iter()
        .map(|(fdi, c)| (fdi, c.margin.len(), std::sync::Mutex::new(Some(c))))
        .collect();
    crate::progress::start(Stage::Stitch, work.len());
    let results = crate::par::map_ordered_by_cost(
        &work,
        |w| w.1,
        |(fdi, _, tooth)| {
            let taken = tooth
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .take();
            let r = match taken {
                Some(c) => crate::progress::unit(Stage::Stitch, || stitch_tooth(&c, opts)),
                None => Err(Error::InvalidArgument(format!(
                    "tooth {fdi}: handed out for stitching twice"
                ))),
            };
            (*fdi, r)
        },
    );
    crate::progress::ended();
    merged(results, &cut, opts)
}

/// The fused jaw of the stitching `results` (in FDI order) of `cut`'s teeth.
fn merged(results: Vec<(u8, Result<FusedTooth>)>, cut: &CutJaw, opts: &FuseOptions) -> FusedJaw {
    let mut jaw = FusedJaw {
        ios_only: cut.ios_only.clone(),
        cbct_only: cut.cbct_only.clone(),
        failed: cut.failed.clone(),
        ..FusedJaw::default()
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
    let mut parts: BTreeMap<u8, (&TriMesh, Vec<u8>)> = jaw
        .teeth
        .iter()
        .map(|(&k, f)| (k, (&f.mesh, f.source.clone())))
        .collect();
    if opts.pass_through_cbct_only {
        for (&fdi, m) in &cut.cbct_only_meshes {
            parts.insert(fdi, (m, vec![VertexSource::Cbct as u8; m.positions.len()]));
            jaw.passed_through.push(fdi);
        }
    }
    let (mut mesh, mut labels, mut source) = (TriMesh::default(), Vec::new(), Vec::new());
    for (fdi, (m, s)) in parts {
        mesh.append(m);
        labels.extend(std::iter::repeat_n(fdi as i32, m.positions.len()));
        source.extend(s);
    }
    jaw.mesh = mesh;
    jaw.labels = labels;
    jaw.source = source;
    jaw
}

/// Fuses every tooth present in both the IOS (labeled jaw) and the CBCT, with the given
/// per-tooth transforms into the output frame: [`stitch_jaw`] of [`cut_jaw`]. A tooth without a
/// transform, or whose fusion fails, is listed in [`FusedJaw::failed`]; the others are still
/// fused.
pub fn fuse_jaw(
    ios: &LabeledMesh,
    cbct: &BTreeMap<u8, TriMesh>,
    transforms: &BTreeMap<u8, ToothTransforms>,
    opts: &FuseOptions,
) -> Result<FusedJaw> {
    let jaw = stitch_jaw_owned(cut_jaw(ios, cbct, transforms, opts)?, opts);
    crate::progress::check(Stage::Stitch)?;
    Ok(jaw)
}
