//! `toothfuse render`: pictures for the README, made by the software renderer.

use crate::demo::PhantomArgs;
use crate::render::{Image, Item, View, render};
use anyhow::Result;
use clap::Args;
use glam::DVec3;
use std::path::PathBuf;

/// `toothfuse render` arguments.
#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    phantom: PhantomArgs,
    /// Output PNG.
    #[arg(long, default_value = "docs/jaw.png")]
    out: PathBuf,
    /// Width of each panel in pixels.
    #[arg(long, default_value_t = 640)]
    width: usize,
    /// Instead: before/after of one tooth (CBCT-only vs fused, seam close-up coloured by source).
    #[arg(long)]
    fused: bool,
    /// Instead: a tooth split out of a per-jaw teeth mask and fused (the real STS 2024 mask's
    /// lower teeth as one class, on a phantom of those teeth; needs the real data folder).
    #[arg(long, conflicts_with = "fused")]
    split: bool,
    /// Tooth of the --fused or --split picture (FDI; default the first fused tooth).
    #[arg(long)]
    tooth: Option<u8>,
}

const IOS_CROWN: [f64; 3] = [0.93, 0.88, 0.74];
const GINGIVA: [f64; 3] = [0.86, 0.52, 0.55];
const CBCT: [f64; 3] = [0.55, 0.68, 0.86];

/// Runs `toothfuse render`: two panels (occlusal and buccal view) of the IOS jaw with the CBCT
/// teeth placed by the true transforms, plus one panel of the CBCT teeth alone.
pub fn run(a: &RenderArgs) -> Result<()> {
    if a.fused {
        return crate::render_fused::run(&a.phantom, a.tooth, &a.out, a.width);
    }
    if a.split {
        return crate::render_split::run(&a.phantom, a.tooth, &a.out, a.width);
    }
    let ph = a.phantom.generate()?;
    let labels = ph.ios.vertex_labels.clone().unwrap_or_default();
    let ios_colors: Vec<[f64; 3]> = labels
        .iter()
        .map(|&l| if l == 0 { GINGIVA } else { IOS_CROWN })
        .collect();
    // CBCT teeth into the IOS frame by the true per-tooth mapping.
    let cbct_in_ios: Vec<_> = ph
        .cbct
        .iter()
        .filter_map(|(fdi, m)| Some(m.transformed(&ph.truth.teeth.get(fdi)?.cbct_to_ios)))
        .collect();
    // Camera axes from the jaw's true frame: occlusal axis = mean tooth axis in the IOS frame.
    let axis = ph
        .truth
        .teeth
        .values()
        .map(|t| ph.truth.world_to_ios.apply_vector(t.axis))
        .fold(DVec3::ZERO, |a, b| a + b)
        .normalize();
    let front = {
        // Direction from arch centre towards the incisors, projected off the axis.
        let c = |fdi_pred: fn(u8) -> bool| {
            let pts: Vec<DVec3> = ph
                .truth
                .teeth
                .values()
                .filter(|t| fdi_pred(t.fdi))
                .map(|t| {
                    let w = toothfuse::geom::centroid(&t.surface.positions).unwrap_or_default();
                    ph.truth.world_to_ios.apply(w)
                })
                .collect();
            toothfuse::geom::centroid(&pts).unwrap_or_default()
        };
        let d = c(|f| f % 10 <= 2) - c(|_| true);
        (d - axis * d.dot(axis)).normalize_or(DVec3::X)
    };
    let mut items = vec![Item {
        mesh: &ph.ios.mesh,
        colors: ios_colors,
    }];
    items.extend(cbct_in_ios.iter().map(|m| Item::uniform(m, CBCT)));
    let cbct_items: Vec<Item> = cbct_in_ios.iter().map(|m| Item::uniform(m, CBCT)).collect();
    let w = a.width;
    let occlusal = render(
        &items,
        View {
            look: -axis,
            up: front,
        },
        w,
        w * 3 / 4,
    );
    let buccal = render(
        &items,
        View {
            look: -front,
            up: axis,
        },
        w,
        w * 3 / 4,
    );
    let cbct_only = render(
        &cbct_items,
        View {
            look: -front,
            up: axis,
        },
        w,
        w * 3 / 4,
    );
    let img = Image::hstack(&[occlusal, buccal, cbct_only]);
    if let Some(parent) = a.out.parent() {
        std::fs::create_dir_all(parent)?;
    }
    img.save_png(&a.out)?;
    println!("wrote {}", a.out.display());
    Ok(())
}
