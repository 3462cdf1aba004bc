//! Fine registration (FR), paper eq. (3): groups `G_i = {i−1, i, i+1}` of consecutive present
//! teeth in arch order, registered *in sequence* with IOS as source and CBCT as target; each
//! group's result `R_i^fine` is applied to the IOS points of its three teeth before the next group,
//! so tooth `i` ends with `R_{i+1}^fine ∘ R_i^fine ∘ R_{i−1}^fine` (end teeth: only the groups
//! they belong to). Gaps from missing teeth are skipped over in arch order.
//!
//! Everything runs in the CBCT frame: the IOS points are first mapped by the coarse transform's
//! inverse; a tooth's correction `F` then gives CBCT → IOS as `T ∘ F⁻¹`.

use super::correspondence::NearestMemo;
use super::icp::{Normal7, Pair, step_about, weights};
use super::{Correspondence, Level, StageOptions, StageStats, ToothData, passes};
use crate::Rigid;
use glam::DVec3;
use std::collections::BTreeMap;

/// Pairs of eq. (3) for the teeth of `group`: source = IOS points moved by `t⁻¹` then by the
/// tooth's correction `f`, target = that tooth's CBCT surface, normal = the IOS normal `n_y`
/// (paper) or the CBCT normal. `memos[i]` holds what the points of `group[i]` remember of their
/// last nearest-vertex search (see [`NearestMemo`]; any memo gives the search's answer, so one
/// kept across iterations only saves searches).
pub(crate) fn group_pairs(
    teeth: &BTreeMap<u8, ToothData>,
    group: &[u8],
    ios_to_cbct: &BTreeMap<u8, Rigid>,
    level: Level,
    o: &StageOptions,
    source_normals: bool,
    memos: &mut [Vec<NearestMemo>],
) -> Vec<Pair> {
    let mut out = Vec::new();
    for (fdi, memo) in group.iter().zip(memos) {
        let d = &teeth[fdi];
        let m = ios_to_cbct[fdi];
        let idx = d.ios_indices(level);
        memo.resize(idx.len(), NearestMemo::default());
        let on_faces = o.correspondence == Correspondence::ClosestPoint;
        for (&k, memo) in idx.iter().zip(memo.iter_mut()) {
            let z = m.apply(d.ios_points[k]);
            let nz = m.apply_vector(d.ios_normals[k]);
            let sp = d.cbct.pair_remembered(z, on_faces, memo);
            let (n, n_other) = if source_normals {
                (nz, sp.normal)
            } else {
                (sp.normal, nz)
            };
            out.push(Pair {
                p: z,
                q: sp.point,
                n,
                n_other,
            });
        }
    }
    out
}

/// ICP on one group; returns the group's rigid correction (in the CBCT frame) and its stats.
fn register_group(
    teeth: &BTreeMap<u8, ToothData>,
    group: &[u8],
    ios_to_cbct: &BTreeMap<u8, Rigid>,
    o: &StageOptions,
    offset0: f64,
) -> (Rigid, StageStats) {
    let mut g = Rigid::IDENTITY;
    let mut offset = offset0;
    let mut local = ios_to_cbct.clone();
    let pts: Vec<DVec3> = group
        .iter()
        .map(|f| ios_to_cbct[f].apply(teeth[f].ios_centroid))
        .collect();
    let center = pts.iter().fold(DVec3::ZERO, |a, p| a + *p) / pts.len().max(1) as f64;
    let radius = group
        .iter()
        .map(|f| ios_to_cbct[f].apply(teeth[f].ios_centroid).distance(center) + teeth[f].ios_radius)
        .fold(0.0, f64::max);
    let mut stats = StageStats::default();
    let mut memos = vec![Vec::new(); group.len()];
    for pass in passes(o) {
        let mut prev_rms = f64::INFINITY;
        let mut converged = false;
        for _ in 0..pass.cap {
            for f in group {
                local.insert(*f, g.compose(&ios_to_cbct[f]));
            }
            let pr = group_pairs(
                teeth,
                group,
                &local,
                pass.level,
                o,
                o.source_normals,
                &mut memos,
            );
            let w = weights(&pr, offset, &o.weights);
            let mut ne = Normal7::new();
            // The offset models the CBCT surface displaced along its normal: with IOS as source
            // the residual sign flips relative to eq. (2), handled by negating the offset.
            ne.add_pairs(&pr, &w, center, -offset);
            stats.iterations += 1;
            let Some((rw, rt, db)) = ne.solve(o.estimate_offset) else {
                break;
            };
            g = step_about(rw, rt, center).compose(&g).orthonormalized();
            offset -= db;
            let rms = (ne.rr / ne.wsum.max(1e-300)).sqrt();
            stats.rms_mm = rms;
            stats.inlier_fraction = ne.wsum / pr.len().max(1) as f64;
            if o.convergence.step_small(rw, rt, radius) || o.convergence.rms_stalled(prev_rms, rms)
            {
                converged = true;
                break;
            }
            prev_rms = rms;
        }
        // Convergence is judged on the subsampled pass that ran to its threshold (the
        // full-resolution pass after it is a fixed refinement).
        if pass.judged {
            stats.converged = converged;
        }
    }
    (g, stats)
}

/// Eq. (3), sequential groups of three in arch order. `order` is the registered teeth in arch
/// order; `coarse` is CBCT → IOS after CR. Returns per tooth the IOS → CBCT mapping after the
/// corrections and the per-tooth stats (iterations summed over its groups).
pub(crate) fn fine_sequential(
    teeth: &BTreeMap<u8, ToothData>,
    order: &[u8],
    coarse: &Rigid,
    offset: f64,
    o: &StageOptions,
) -> (BTreeMap<u8, Rigid>, BTreeMap<u8, StageStats>) {
    let inv = coarse.inverse();
    let mut ios_to_cbct: BTreeMap<u8, Rigid> = order.iter().map(|&f| (f, inv)).collect();
    let mut stats: BTreeMap<u8, StageStats> = order
        .iter()
        .map(|&f| {
            (
                f,
                StageStats {
                    converged: true,
                    ..StageStats::default()
                },
            )
        })
        .collect();
    let groups: Vec<&[u8]> = if order.len() <= 3 {
        vec![order]
    } else {
        order.windows(3).collect()
    };
    for group in groups {
        let (g, st) = register_group(teeth, group, &ios_to_cbct, o, offset);
        for f in group {
            let m = ios_to_cbct[f];
            ios_to_cbct.insert(*f, g.compose(&m).orthonormalized());
            let s = stats.get_mut(f).expect("tooth in order");
            s.iterations += st.iterations;
            s.converged &= st.converged;
            s.rms_mm = st.rms_mm;
            s.inlier_fraction = st.inlier_fraction;
        }
    }
    (ios_to_cbct, stats)
}
