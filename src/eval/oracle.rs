//! The accuracy floor of crown-based registration on the synthetic jaw: per tooth, the best rigid
//! CBCT → IOS mapping that any method fitting the IOS crown to the CBCT crown could find, given
//! the *known* correspondences.
//!
//! For every true surface vertex `p` above the true gingival margin (the part of the tooth the
//! IOS sees), its IOS position is `world_to_ios ∘ drift(p)` (stitching drift included) and the
//! same material point in the CBCT is where the phantom's CBCT model puts it: moved along the true
//! outward normal by the tooth's segmentation threshold bias `b`, into the CBCT frame, then by the
//! scan's smooth spatial distortion `D` (`x ↦ x + D(x)`, evaluated in the CBCT frame as the
//! phantom does). The least-squares rigid fit of those pairs (Kabsch, no scale) is the oracle; its
//! TRE over the whole true tooth is what fitting a crown costs when the CBCT crown is warped and
//! the root is extrapolated from it. A second oracle drops the bias (a perfect offset model).
//!
//! The phantom does not publish its distortion field or its biases, so they are re-derived here
//! from the seed exactly as `phantom::generate` draws them (`Rng::new(seed).fork(6)`: the three
//! plane waves, then the scan-wide and per-tooth biases in arch order);
//! [`OracleTooth::model_rms_mm`] checks that re-derivation against the actual CBCT mesh (the
//! modelled points lie on it up to blur, noise and contact flattening). Metal bloat and contact
//! flattening are not modelled: they only make the oracle optimistic (a lower bound).

use crate::arch::arch_position;
use crate::phantom::rng::Rng;
use crate::phantom::{Phantom, PhantomOptions, ToothTruth};
use crate::register::centroid::kabsch;
use crate::register::correspondence::SurfaceIndex;
use crate::{Error, Result};
use glam::DVec3;
use std::collections::BTreeMap;

/// The phantom's smooth CBCT distortion (sum of three plane waves per axis), re-derived.
#[derive(Clone, Debug)]
pub struct CbctModel {
    waves: Vec<(DVec3, DVec3, f64)>,
    /// Segmentation bias per CBCT tooth (mm, + inflates), by FDI.
    pub bias: BTreeMap<u8, f64>,
}

impl CbctModel {
    /// Re-derives the distortion field and threshold biases of the phantom of `opts` (parametric
    /// teeth only: real anatomy is placed through another frame).
    pub fn of(p: &Phantom, opts: &PhantomOptions) -> Result<CbctModel> {
        if opts.anatomy.is_some() {
            return Err(Error::InvalidArgument(
                "the oracle models parametric phantoms only".into(),
            ));
        }
        let mut crng = Rng::new(opts.seed).fork(6);
        let amp = opts.realism.cbct.distortion;
        let waves = (0..3)
            .map(|_| {
                let k = crng.unit_vector() * (std::f64::consts::TAU / crng.range(15.0, 40.0));
                let a = crng.unit_vector() * (amp * crng.range(0.5, 0.8));
                (k, a, crng.range(0.0, std::f64::consts::TAU))
            })
            .collect();
        let tb = opts.realism.cbct.threshold_bias;
        let scan_bias = crng.range(-0.25, 0.25) * tb;
        let mut cbct_teeth: Vec<u8> = p
            .truth
            .teeth
            .values()
            .filter(|t| t.in_cbct)
            .map(|t| t.fdi)
            .collect();
        cbct_teeth.sort_by_key(|&f| arch_position(f));
        let bias = cbct_teeth
            .into_iter()
            .map(|f| {
                let s = crng.sign();
                (
                    f,
                    (scan_bias + s * crng.range(0.4, 1.0) * tb).clamp(-tb, tb),
                )
            })
            .collect();
        Ok(CbctModel { waves, bias })
    }

    /// Displacement of the distortion at CBCT-frame point `x`.
    pub fn distortion(&self, x: DVec3) -> DVec3 {
        self.waves.iter().fold(DVec3::ZERO, |acc, (k, a, ph)| {
            acc + *a * (k.dot(x) + ph).sin()
        })
    }
}

/// The oracle of one tooth.
#[derive(Clone, Debug, PartialEq)]
pub struct OracleTooth {
    /// FDI number.
    pub fdi: u8,
    /// TRE (mm) of the crown fit with known correspondences (bias and distortion).
    pub tre_mm: f64,
    /// TRE (mm) of the same fit without the threshold bias (distortion only).
    pub tre_no_bias_mm: f64,
    /// True surface vertices above the margin used in the fit.
    pub crown_points: usize,
    /// RMS distance (mm) from the modelled CBCT crown points to the actual CBCT mesh: checks the
    /// re-derived model (blur, noise and contact flattening remain).
    pub model_rms_mm: f64,
    /// Same RMS without the model (true points mapped rigidly into the CBCT frame), for contrast.
    pub raw_rms_mm: f64,
}

/// Height along `axis` of the closed margin polyline, interpolated by angle about `axis` around
/// `center`; returns a function of a point telling whether it lies above the margin.
fn above_margin(margin: &[DVec3], axis: DVec3) -> Option<impl Fn(DVec3) -> bool + '_> {
    let center = crate::geom::centroid(margin)?;
    let u = axis.any_orthonormal_vector();
    let v = axis.cross(u);
    let angle = move |p: DVec3| {
        let d = p - center;
        d.dot(v).atan2(d.dot(u))
    };
    let mut prof: Vec<(f64, f64)> = margin
        .iter()
        .map(|&m| (angle(m), (m - center).dot(axis)))
        .collect();
    prof.sort_by(|a, b| a.0.total_cmp(&b.0));
    if prof.len() < 3 {
        return None;
    }
    Some(move |p: DVec3| {
        let a = angle(p);
        let h = (p - center).dot(axis);
        let k = prof.partition_point(|x| x.0 < a);
        let n = prof.len();
        let (lo, hi) = (prof[(k + n - 1) % n], prof[k % n]);
        let span = (hi.0 - lo.0).rem_euclid(std::f64::consts::TAU);
        let t = if span > 0.0 {
            ((a - lo.0).rem_euclid(std::f64::consts::TAU) / span).clamp(0.0, 1.0)
        } else {
            0.0
        };
        h > lo.1 + t * (hi.1 - lo.1)
    })
}

/// The oracle of one tooth; `None` when the tooth lacks a margin or a crown.
fn oracle_tooth(
    p: &Phantom,
    model: &CbctModel,
    t: &ToothTruth,
    cbct: Option<&SurfaceIndex>,
) -> Option<OracleTooth> {
    let bias = *model.bias.get(&t.fdi)?;
    let above = above_margin(&t.margin, t.axis)?;
    let normals = t.surface.vertex_normals();
    let w2c = p.truth.world_to_cbct;
    let (mut src, mut src_nb, mut dst) = (Vec::new(), Vec::new(), Vec::new());
    let (mut model_ss, mut raw_ss) = (0.0, 0.0);
    for (&w, &n) in t.surface.positions.iter().zip(&normals) {
        if n == DVec3::ZERO || !above(w) {
            continue;
        }
        let c = w2c.apply(w);
        let warp = |x: DVec3| x + model.distortion(x);
        let cb = warp(w2c.apply(w + n * bias));
        if let Some(ix) = cbct {
            model_ss += ix.closest_point(cb).distance.powi(2);
            raw_ss += ix.closest_point(c).distance.powi(2);
        }
        src.push(cb);
        src_nb.push(warp(c));
        dst.push(t.cbct_to_ios.apply(c));
    }
    let fit = kabsch(&src, &dst, None).ok()?;
    let fit_nb = kabsch(&src_nb, &dst, None).ok()?;
    let n = src.len() as f64;
    Some(OracleTooth {
        fdi: t.fdi,
        tre_mm: t.tre(&w2c, &fit),
        tre_no_bias_mm: t.tre(&w2c, &fit_nb),
        crown_points: src.len(),
        model_rms_mm: (model_ss / n).sqrt(),
        raw_rms_mm: (raw_ss / n).sqrt(),
    })
}

/// The oracle of every tooth present in both modalities of the phantom generated from `opts`.
pub fn oracle(p: &Phantom, opts: &PhantomOptions) -> Result<BTreeMap<u8, OracleTooth>> {
    let model = CbctModel::of(p, opts)?;
    let mut out = BTreeMap::new();
    for t in p.truth.teeth.values().filter(|t| t.in_ios && t.in_cbct) {
        let ix = p.cbct.get(&t.fdi).and_then(|m| SurfaceIndex::new(m).ok());
        if let Some(o) = oracle_tooth(p, &model, t, ix.as_ref()) {
            out.insert(t.fdi, o);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phantom::Variant;

    #[test]
    fn re_derived_cbct_model_matches_the_phantom_and_bounds_tre() {
        let opts = PhantomOptions {
            seed: 3,
            variant: Variant::PartialArch,
            ..PhantomOptions::default()
        };
        let p = Phantom::generate(&opts).unwrap();
        let o = oracle(&p, &opts).unwrap();
        assert!(o.len() >= 3, "{} teeth", o.len());
        // The model explains most of the CBCT's deviation from the true surface (what remains
        // is blur, noise and contact flattening).
        let mean = |f: fn(&OracleTooth) -> f64| o.values().map(f).sum::<f64>() / o.len() as f64;
        let (model, raw) = (mean(|t| t.model_rms_mm), mean(|t| t.raw_rms_mm));
        assert!(model < 0.6 * raw && model < 0.15, "{o:?}");
        for t in o.values() {
            assert!(t.model_rms_mm < 0.2, "{t:?}");
            assert!(t.crown_points > 500, "{t:?}");
            assert!(t.tre_mm > 0.0 && t.tre_mm < 0.5, "{t:?}");
        }
    }
}
