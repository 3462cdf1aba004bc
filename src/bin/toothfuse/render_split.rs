//! `toothfuse render --split`: a tooth split out of a per-jaw teeth mask and fused, on the real
//! STS 2024 mask of the shared real data: its lower teeth merged into DentalSegmentator's one
//! lower-teeth class (4) and placed in the CBCT frame of a phantom whose true teeth are those
//! teeth. Panels: the teeth class (the mask's teeth in one colour), the teeth split from it by
//! the phantom's IOS crowns, and one tooth fused (vertices coloured by source).

use crate::demo::PhantomArgs;
use crate::render::{Image, Item, Rgb, View, render};
use anyhow::{Context, Result};
use glam::{DMat4, DVec3};
use std::collections::BTreeMap;
use std::path::Path;
use toothfuse::TriMesh;
use toothfuse::arch::Jaw;
use toothfuse::phantom::Phantom;
use toothfuse::pipeline::{self, PipelineOptions};
use toothfuse::volume::{
    Frame, SplitOptions, SurfaceOptions, VolumeScheme, split_teeth, surface_teeth,
};

/// The STS 2024 mask, relative to the real data folder.
const STS_MASK: &str = "cbct_toothseg_sts2024/Validation_0001_Mask.nii.gz";

/// The per-jaw mask's colour (the CBCT colour of the fused tooth).
const CBCT: Rgb = [0.55, 0.68, 0.86];
/// Colours of the split teeth, in turn.
const PALETTE: [Rgb; 4] = [
    [0.55, 0.68, 0.86],
    [0.93, 0.72, 0.45],
    [0.62, 0.82, 0.60],
    [0.82, 0.62, 0.82],
];

/// Renders the picture to `out`.
pub fn run(ph_args: &PhantomArgs, tooth: Option<u8>, out: &Path, w: usize) -> Result<()> {
    let dir = toothfuse::io::real_data_dir()
        .context("the real data folder is needed (set TOOTHFUSE_REAL_DATA)")?;
    let mask = toothfuse::io::read_label_volume(dir.join(STS_MASK), Frame::Lps)?.volume;
    let lower = mask
        .relabeled(|l| if (31..=48).contains(&l) { l } else { 0 })
        .cropped_to_labels();
    // The phantom's true teeth are the mask's teeth, in the mask's world.
    let anatomy: BTreeMap<u8, TriMesh> =
        surface_teeth(&lower, VolumeScheme::Fdi, &SurfaceOptions::default())?
            .teeth
            .into_iter()
            .map(|(f, t)| (f, t.mesh))
            .collect();
    let mut opts = ph_args.options()?;
    opts.jaw = Jaw::Lower;
    opts.anatomy = Some(anatomy);
    let ph = Phantom::generate(&opts).context("generating the phantom")?;
    let w2c = ph.truth.world_to_cbct;
    // The teeth class as the mask holds it (no tooth numbers): its teeth drawn in one colour.
    let class: Vec<TriMesh> = opts
        .anatomy
        .iter()
        .flat_map(|a| a.values().map(|m| m.transformed(&w2c)))
        .collect();
    // The mask in the phantom's CBCT frame, its teeth merged into one lower-teeth class.
    let mut merged = lower.relabeled(|l| if l != 0 { 4 } else { 0 });
    merged.voxel_to_world =
        DMat4::from_mat3_translation(w2c.rot, w2c.trans) * merged.voxel_to_world;
    let split = split_teeth(&merged, &ph.ios_crowns(), &SplitOptions::default())?;
    let teeth: BTreeMap<u8, TriMesh> =
        surface_teeth(&split.volume, VolumeScheme::Fdi, &SurfaceOptions::default())?
            .teeth
            .into_iter()
            .map(|(f, t)| (f, t.mesh))
            .collect();
    let r = pipeline::fuse(&ph.ios, &teeth, &PipelineOptions::default())?;
    let (fdi, f) = crate::render_fused::fused_tooth(&r, tooth)?;

    // Views: the arch from the front and above (occlusal axis up), the tooth from its buccal side.
    let axis = ph
        .truth
        .teeth
        .values()
        .map(|t| w2c.apply_vector(t.axis))
        .fold(DVec3::ZERO, |a, b| a + b)
        .normalize();
    let centre = |m: &TriMesh| toothfuse::geom::centroid(&m.positions).unwrap_or_default();
    let c_arch = toothfuse::geom::centroid(&class.iter().map(centre).collect::<Vec<_>>())
        .unwrap_or_default();
    let c_front = toothfuse::geom::centroid(
        &teeth
            .iter()
            .filter(|(f, _)| *f % 10 <= 2)
            .map(|(_, m)| centre(m))
            .collect::<Vec<_>>(),
    )
    .unwrap_or_default();
    let off_axis = |d: DVec3| (d - axis * d.dot(axis)).normalize_or(axis.any_orthonormal_vector());
    let arch_view = View {
        look: -(off_axis(c_front - c_arch) + axis * 0.7).normalize(),
        up: axis,
    };
    let tooth_view = View {
        look: -off_axis(centre(&f.mesh) - c_arch),
        up: axis,
    };
    let h = w * 3 / 4;
    let whole = render(
        &class
            .iter()
            .map(|m| Item::uniform(m, CBCT))
            .collect::<Vec<_>>(),
        arch_view,
        w,
        h,
    );
    let parts: Vec<Item> = teeth
        .values()
        .enumerate()
        .map(|(i, m)| Item::uniform(m, PALETTE[i % PALETTE.len()]))
        .collect();
    let split_img = render(&parts, arch_view, w, h);
    let colors = crate::render_fused::source_colors(f);
    let fused = render(
        &[Item {
            mesh: &f.mesh,
            colors,
        }],
        tooth_view,
        w * 2 / 3,
        h,
    );
    let img = Image::hstack(&[whole, split_img, fused]);
    crate::input::create_parent(out)?;
    img.save_png(out)?;
    println!(
        "wrote {}: lower-teeth class | {} teeth split by the IOS | tooth {fdi} fused (IOS sand, \
         band orange, CBCT blue)",
        out.display(),
        teeth.len()
    );
    Ok(())
}
