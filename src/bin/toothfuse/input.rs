//! Reading the IOS and CBCT inputs of `register` and `fuse`, and the options they share.

use anyhow::{Context, Result, bail};
use clap::Args;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use toothfuse::TriMesh;
use toothfuse::io::LabelScheme;
use toothfuse::mesh::LabeledMesh;
use toothfuse::pipeline::PipelineOptions;
use toothfuse::register::{OutputFrame, Preset};

/// Inputs and options shared by `register` and `fuse`.
#[derive(Args, Clone, Debug)]
pub struct InputArgs {
    /// IOS jaw mesh with per-vertex or per-face tooth labels (.ply/.obj/.vtp/.vtk), or a folder
    /// of tooth_<n> crown files. Without --ios/--cbct: the built-in synthetic jaw.
    #[arg(long, requires = "cbct")]
    pub ios: Option<PathBuf>,
    /// CBCT teeth: a labeled mesh or a folder of tooth_<n>.stl/.ply/... files.
    #[arg(long, requires = "ios")]
    pub cbct: Option<PathBuf>,
    /// Tooth numbering of the input labels and file names.
    #[arg(long, default_value = "fdi", value_parser = ["fdi", "universal", "meshlabeler"])]
    pub labels: String,
    /// Output frame: cbct (fused teeth overlay the CBCT volume) or ios.
    #[arg(long, default_value = "cbct", value_parser = ["cbct", "ios"])]
    pub frame: String,
    /// Method preset: paper (faithful) or default (measured better).
    #[arg(long, default_value = "default", value_parser = ["paper", "default"])]
    pub preset: String,
    /// Register and fuse even when the registration gate finds the data questionable (mirrored,
    /// another patient, shifted or misnumbered labels); the findings are then listed under
    /// "questionable" in report.json and as warnings.
    #[arg(long)]
    pub accept_questionable: bool,
}

/// The IOS input: a labeled jaw or per-tooth crowns.
pub enum Ios {
    /// One labeled jaw mesh (labels converted to FDI).
    Jaw(LabeledMesh),
    /// Per-tooth crowns by FDI.
    Crowns(BTreeMap<u8, TriMesh>),
}

impl InputArgs {
    /// The label scheme.
    pub fn scheme(&self) -> LabelScheme {
        match self.labels.as_str() {
            "universal" => LabelScheme::Universal,
            "meshlabeler" => LabelScheme::MeshLabeler,
            _ => LabelScheme::Fdi,
        }
    }

    /// Pipeline options from --preset and --frame.
    pub fn options(&self) -> PipelineOptions {
        let p = Preset::from_name(&self.preset).unwrap_or_default();
        let f = OutputFrame::from_name(&self.frame).unwrap_or_default();
        let mut o = PipelineOptions::preset(p).with_frame(f);
        o.register.accept_questionable = self.accept_questionable;
        o
    }

    /// Both inputs, or `None` for the synthetic jaw.
    pub fn read(&self) -> Result<Option<(Ios, BTreeMap<u8, TriMesh>)>> {
        let (Some(ios), Some(cbct)) = (&self.ios, &self.cbct) else {
            return Ok(None);
        };
        let scheme = self.scheme();
        let ios = read_ios(ios, scheme)?;
        let cbct_teeth = toothfuse::io::read_teeth_with(cbct, scheme)
            .with_context(|| format!("reading CBCT {}", cbct.display()))?;
        Ok(Some((ios, cbct_teeth)))
    }
}

fn read_ios(path: &Path, scheme: LabelScheme) -> Result<Ios> {
    if path.is_dir() {
        let crowns = toothfuse::io::read_teeth_with(path, scheme)
            .with_context(|| format!("reading IOS {}", path.display()))?;
        return Ok(Ios::Crowns(crowns));
    }
    let mut lm = toothfuse::io::read_mesh(path)
        .with_context(|| format!("reading IOS {}", path.display()))?;
    if lm.vertex_labels.is_none() && lm.face_labels.is_none() {
        bail!(
            "{}: the IOS mesh has no tooth labels (a per-vertex or per-face `label` property is needed)",
            path.display()
        );
    }
    for labels in [&mut lm.vertex_labels, &mut lm.face_labels]
        .into_iter()
        .flatten()
    {
        for l in labels.iter_mut() {
            if *l != 0 {
                *l = scheme
                    .to_fdi(*l)
                    .with_context(|| format!("{}: IOS labels", path.display()))?
                    as i32;
            }
        }
    }
    Ok(Ios::Jaw(lm))
}

/// Creates the parent folder of `path`.
pub fn create_parent(path: &Path) -> Result<()> {
    if let Some(p) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(p).with_context(|| format!("creating {}", p.display()))?;
    }
    Ok(())
}
