//! `toothfuse demo`: writes a synthetic jaw and its ground truth.

use anyhow::{Context, Result, bail};
use clap::Args;
use serde_json::json;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use toothfuse::TriMesh;
use toothfuse::arch::Jaw;
use toothfuse::phantom::{IosExport, Phantom, PhantomOptions, Variant, VoxelizeOptions, voxelize};

/// Options shared by every command that builds a synthetic jaw.
#[derive(Args, Clone, Debug)]
pub struct PhantomArgs {
    /// Seed of the synthetic jaw (same seed, same jaw, bit for bit).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Jaw: upper or lower.
    #[arg(long, default_value = "upper", value_parser = ["upper", "lower"])]
    pub jaw: String,
    /// Scenario: full, missing, partial, metal or drift.
    #[arg(long, default_value = "full", value_parser = ["full", "missing", "partial", "metal", "drift"])]
    pub variant: String,
    /// IOS export: clean (the project's scan), or a rough export (raw slivers, folds, margin
    /// clipped through triangles, notches, holes, label noise) at the scan density (rough), at
    /// ~0.4 mm edges (coarse), 2x or 4x the vertices (dense2, dense4), or 2x then midpoint-
    /// subdivided (subdivided, ~0.06 mm edges).
    #[arg(long, default_value = "clean", value_parser = ["clean", "rough", "coarse", "dense2", "dense4", "subdivided"])]
    pub ios_export: String,
}

impl PhantomArgs {
    /// Generator options from the command line.
    pub fn options(&self) -> Result<PhantomOptions> {
        let jaw = if self.jaw == "lower" {
            Jaw::Lower
        } else {
            Jaw::Upper
        };
        let Some(variant) = Variant::from_name(&self.variant) else {
            bail!("unknown variant {:?}", self.variant);
        };
        let Some(export) = IosExport::from_name(&self.ios_export) else {
            bail!("unknown IOS export {:?}", self.ios_export);
        };
        let mut opts = PhantomOptions {
            seed: self.seed,
            jaw,
            variant,
            ..PhantomOptions::default()
        };
        opts.realism.ios.rough = export.roughness();
        Ok(opts)
    }

    /// Generates the jaw.
    pub fn generate(&self) -> Result<Phantom> {
        Phantom::generate(&self.options()?).context("generating the synthetic jaw")
    }
}

/// `toothfuse demo` arguments.
#[derive(Args, Debug)]
pub struct DemoArgs {
    #[command(flatten)]
    phantom: PhantomArgs,
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Also write the CBCT teeth as label volumes voxelized at this size (mm), the way CBCT
    /// segmentation tools give them: `cbct_labels.nrrd` (one FDI label per tooth) and
    /// `cbct_teeth_class.nrrd` (every tooth one class, 3 upper or 4 lower, as DentalSegmentator
    /// writes them), LPS, on the CBCT frame's axes.
    #[arg(long, value_name = "MM")]
    cbct_volume: Option<f64>,
}

/// Merges per-tooth meshes into one mesh with a per-vertex FDI label.
pub fn merge_labeled(teeth: &BTreeMap<u8, TriMesh>) -> (TriMesh, Vec<i32>) {
    let mut all = TriMesh::default();
    let mut labels = Vec::new();
    for (&fdi, m) in teeth {
        all.append(m);
        labels.extend(std::iter::repeat_n(fdi as i32, m.positions.len()));
    }
    (all, labels)
}

/// Runs `toothfuse demo`.
pub fn run(a: &DemoArgs) -> Result<()> {
    let ph = a.phantom.generate()?;
    write_phantom(&ph, &a.out)?;
    if let Some(voxel_mm) = a.cbct_volume {
        write_volumes(&ph, &a.out, voxel_mm)?;
    }
    let ios_labels = ph.ios.vertex_labels.as_ref().map(|l| l.len()).unwrap_or(0);
    println!(
        "wrote {}: ios.ply ({} vertices, {} labels), cbct.ply ({} teeth), truth/",
        a.out.display(),
        ph.ios.mesh.positions.len(),
        ios_labels,
        ph.cbct.len()
    );
    Ok(())
}

/// Writes the CBCT teeth voxelized at `voxel_mm` into `dir` as a per-tooth FDI label volume
/// (`cbct_labels.nrrd`) and as one teeth class of the jaw (`cbct_teeth_class.nrrd`).
fn write_volumes(ph: &Phantom, dir: &Path, voxel_mm: f64) -> Result<()> {
    let class = match ph.jaw {
        Jaw::Upper => 3,
        Jaw::Lower => 4,
    };
    for (name, class) in [
        ("cbct_labels.nrrd", None),
        ("cbct_teeth_class.nrrd", Some(class)),
    ] {
        let opts = VoxelizeOptions {
            voxel_mm,
            class,
            ..VoxelizeOptions::default()
        };
        let v = voxelize(&ph.cbct, &opts).with_context(|| format!("voxelizing {name}"))?;
        toothfuse::io::write_nrrd(dir.join(name), &v)?;
    }
    Ok(())
}

/// Writes `ios.ply`, `cbct.ply` and `truth/` into `dir`.
pub fn write_phantom(ph: &Phantom, dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir.join("truth"))
        .with_context(|| format!("creating {}", dir.display()))?;
    let labels = ph
        .ios
        .vertex_labels
        .clone()
        .context("synthetic IOS has no labels")?;
    toothfuse::io::write_mesh(dir.join("ios.ply"), &ph.ios.mesh, &[("label", &labels)])?;
    let (cbct, cbct_labels) = merge_labeled(&ph.cbct);
    toothfuse::io::write_mesh(dir.join("cbct.ply"), &cbct, &[("label", &cbct_labels)])?;
    let mut teeth = Vec::new();
    for (&fdi, t) in &ph.truth.teeth {
        toothfuse::io::write_mesh(dir.join(format!("truth/tooth_{fdi}.ply")), &t.surface, &[])?;
        teeth.push(json!({
            "fdi": fdi,
            "cbct_to_ios": t.cbct_to_ios.to_row_major(),
            "ios_drift": t.ios_drift.to_row_major(),
            "axis": t.axis.to_array(),
            "margin": t.margin.iter().map(|p| p.to_array()).collect::<Vec<_>>(),
            "in_ios": t.in_ios,
            "in_cbct": t.in_cbct,
            "metal_artefact": t.metal_artefact,
        }));
    }
    let truth = json!({
        "jaw": format!("{:?}", ph.jaw).to_lowercase(),
        "world_to_ios": ph.truth.world_to_ios.to_row_major(),
        "world_to_cbct": ph.truth.world_to_cbct.to_row_major(),
        "note": "true surfaces (truth/tooth_<fdi>.ply) and margins are in the world frame; matrices are row-major 4x4",
        "teeth": teeth,
    });
    std::fs::write(
        dir.join("truth/truth.json"),
        serde_json::to_string_pretty(&truth)?,
    )?;
    Ok(())
}
