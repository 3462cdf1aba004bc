//! `toothfuse render --fused`: before/after of one tooth of the synthetic jaw after the one-call
//! fuse (default preset, CBCT frame): the CBCT-only tooth, the fused tooth, and a close-up of the
//! seam with vertices coloured by source (IOS / band / CBCT).

use crate::demo::PhantomArgs;
use crate::render::{Image, Item, Rgb, View, render};
use anyhow::{Context, Result};
use glam::DVec3;
use std::path::Path;
use toothfuse::TriMesh;
use toothfuse::fuse::FusedTooth;
use toothfuse::pipeline::{self, PipelineOptions, PipelineResult};

const IOS: Rgb = [0.93, 0.88, 0.74];
const BAND: Rgb = [0.95, 0.45, 0.20];
const CBCT: Rgb = [0.55, 0.68, 0.86];

/// Faces of `m` whose centroid height along `axis` lies in `[lo, hi]` (vertices kept as is).
fn slab(m: &TriMesh, axis: DVec3, lo: f64, hi: f64) -> TriMesh {
    let triangles = (0..m.triangles.len())
        .filter(|&f| {
            let h = m.corners(f).iter().map(|v| v.dot(axis)).sum::<f64>() / 3.0;
            (lo..=hi).contains(&h)
        })
        .map(|f| m.triangles[f])
        .collect();
    TriMesh::new(m.positions.clone(), triangles)
}

/// Per vertex of fused tooth `f`: the colour of its source (IOS crown, band, CBCT root).
pub fn source_colors(f: &FusedTooth) -> Vec<Rgb> {
    f.source
        .iter()
        .map(|&s| match s {
            0 => IOS,
            1 => BAND,
            _ => CBCT,
        })
        .collect()
}

/// The fused tooth `tooth` of `r`, or its first fused tooth when `None`.
pub fn fused_tooth(r: &PipelineResult, tooth: Option<u8>) -> Result<(u8, &FusedTooth)> {
    let fdi = match tooth {
        Some(t) => t,
        None => *r.jaw.teeth.keys().next().context("no tooth was fused")?,
    };
    let f = r
        .jaw
        .teeth
        .get(&fdi)
        .with_context(|| format!("tooth {fdi} was not fused"))?;
    Ok((fdi, f))
}

/// Renders the picture to `out`.
pub fn run(ph_args: &PhantomArgs, tooth: Option<u8>, out: &Path, w: usize) -> Result<()> {
    let ph = ph_args.generate()?;
    let r = pipeline::fuse(&ph.ios, &ph.cbct, &PipelineOptions::default())?;
    let (fdi, f) = fused_tooth(&r, tooth)?;
    let truth = ph.truth.teeth.get(&fdi).context("tooth not in the truth")?;
    let reg = &r.registration.teeth[&fdi];
    let cbct = ph.cbct[&fdi].transformed(&reg.cbct_to_output);
    let axis = ph.truth.world_to_cbct.apply_vector(truth.axis).normalize();
    // Buccal direction: from the arch centre to the tooth, off the axis.
    let c_tooth = toothfuse::geom::centroid(&cbct.positions).unwrap_or_default();
    let all: Vec<DVec3> = ph
        .cbct
        .values()
        .flat_map(|m| m.positions.iter().copied())
        .collect();
    let c_arch = toothfuse::geom::centroid(&all).unwrap_or_default();
    let d = c_tooth - c_arch;
    let buccal = (d - axis * d.dot(axis)).normalize_or(axis.any_orthonormal_vector());
    let view = View {
        look: -buccal,
        up: axis,
    };
    let colors = source_colors(f);
    let h = w * 4 / 3;
    let before = render(&[Item::uniform(&cbct, CBCT)], view, w, h);
    let after = render(
        &[Item {
            mesh: &f.mesh,
            colors: colors.clone(),
        }],
        view,
        w,
        h,
    );
    let band_h: Vec<f64> = f
        .mesh
        .positions
        .iter()
        .zip(&f.source)
        .filter(|(_, s)| **s == 1)
        .map(|(v, _)| v.dot(axis))
        .collect();
    let lo = band_h.iter().copied().fold(f64::INFINITY, f64::min) - 2.0;
    let hi = band_h.iter().copied().fold(f64::NEG_INFINITY, f64::max) + 2.0;
    let mut seam = slab(&f.mesh, axis, lo, hi);
    // Only the slab's vertices, so the renderer frames the seam.
    let map = seam.compact();
    let mut seam_colors = vec![BAND; seam.positions.len()];
    for (old, &new) in map.iter().enumerate() {
        if new != u32::MAX {
            seam_colors[new as usize] = colors[old];
        }
    }
    let close = render(
        &[Item {
            mesh: &seam,
            colors: seam_colors,
        }],
        view,
        w * 3 / 2,
        h,
    );
    let img = Image::hstack(&[before, after, close]);
    crate::input::create_parent(out)?;
    img.save_png(out)?;
    println!(
        "wrote {}: tooth {fdi}, CBCT-only | fused | seam close-up (IOS sand, band orange, CBCT blue)",
        out.display()
    );
    Ok(())
}
