//! Accuracy of a one-call fuse against a synthetic jaw's truth:
//! per fused tooth, the fused crown's mean distance to the true surface next to the CBCT-only
//! crown's, the band's largest deviation and smallest angle, and the registration TRE.

use super::PipelineResult;
use crate::fuse::VertexSource;
use crate::mesh_check::SurfaceDistance;
use crate::phantom::Phantom;
use crate::register::OutputFrame;
use std::collections::BTreeMap;

/// Accuracy of one fused tooth (mm, degrees).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FusionAccuracy {
    /// Mean distance of the fused mesh's IOS vertices to the true surface.
    pub crown_mean_mm: f64,
    /// Mean distance of the CBCT-only crown (CBCT vertices 0.5 mm above the true margin's mean
    /// height) to the true surface.
    pub cbct_crown_mean_mm: f64,
    /// Largest distance of a band vertex to the true surface.
    pub band_max_mm: f64,
    /// Smallest band triangle angle.
    pub band_min_angle_deg: f64,
    /// Registration TRE of the tooth.
    pub tre_mm: f64,
}

/// Measures every fused tooth of `r` (computed on `p` with output frame `r.registration.frame`)
/// against the true surfaces placed in the output frame.
pub fn fusion_accuracy(p: &Phantom, r: &PipelineResult) -> BTreeMap<u8, FusionAccuracy> {
    let mut out = BTreeMap::new();
    for (&fdi, f) in &r.jaw.teeth {
        let (Some(truth), Some(reg), Some(cbct)) = (
            p.truth.teeth.get(&fdi),
            r.registration.teeth.get(&fdi),
            p.cbct.get(&fdi),
        ) else {
            continue;
        };
        let to_out = match r.registration.frame {
            OutputFrame::Cbct => p.truth.world_to_cbct,
            OutputFrame::Ios => p.truth.world_to_ios.compose(&truth.ios_drift),
        };
        let dist = SurfaceDistance::new(&truth.surface.transformed(&to_out));
        let axis = to_out.apply_vector(truth.axis);
        let mh = truth
            .margin
            .iter()
            .map(|&m| to_out.apply(m).dot(axis))
            .sum::<f64>()
            / truth.margin.len().max(1) as f64;
        let mean = |it: &mut dyn Iterator<Item = f64>| {
            let (s, n) = it.fold((0.0, 0usize), |(s, n), d| (s + d, n + 1));
            s / n.max(1) as f64
        };
        let of = |src: VertexSource| {
            f.mesh
                .positions
                .iter()
                .zip(&f.source)
                .filter(move |(_, s)| **s == src as u8)
                .map(|(v, _)| dist.distance(*v))
        };
        let crown_mean_mm = mean(&mut of(VertexSource::Ios));
        let band_max_mm = of(VertexSource::Band).fold(0.0, f64::max);
        let cbct_out = cbct.transformed(&reg.cbct_to_output);
        let cbct_crown_mean_mm = mean(
            &mut cbct_out
                .positions
                .iter()
                .filter(|v| v.dot(axis) > mh + 0.5)
                .map(|v| dist.distance(*v)),
        );
        out.insert(
            fdi,
            FusionAccuracy {
                crown_mean_mm,
                cbct_crown_mean_mm,
                band_max_mm,
                band_min_angle_deg: f.quality.band_min_angle_deg,
                tre_mm: truth.tre(&p.truth.world_to_cbct, &reg.cbct_to_ios),
            },
        );
    }
    out
}
