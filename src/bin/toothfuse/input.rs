//! Reading the IOS and CBCT inputs of `register` and `fuse`, and the options they share.

use anyhow::{Context, Result, anyhow};
use clap::Args;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use toothfuse::TriMesh;
use toothfuse::io::{LabelScheme, TeethOptions, detect_scheme, labels_to_fdi};
use toothfuse::mesh::LabeledMesh;
use toothfuse::pipeline::PipelineOptions;
use toothfuse::register::{OutputFrame, Preset};
use toothfuse::volume::numbering::looks_like_dentalsegmentator;
use toothfuse::volume::{
    Frame, LabelVolume, SplitOptions, SurfaceOptions, VolumeScheme, split_teeth, surface_teeth,
};

/// Inputs and options shared by `register` and `fuse`.
#[derive(Args, Clone, Debug)]
pub struct InputArgs {
    /// IOS jaw mesh with per-vertex or per-face tooth labels (.ply/.obj/.vtp/.vtk), or a folder
    /// of tooth_<n> crown files. Without --ios/--cbct: the built-in synthetic jaw.
    #[arg(long, requires = "cbct")]
    pub ios: Option<PathBuf>,
    /// CBCT teeth: a labeled mesh, a folder of tooth_<n>.stl/.ply/... files, or a label volume
    /// (.nii, .nii.gz, .nrrd, .seg.nrrd) with one label per tooth, surfaced here.
    #[arg(long, requires = "ios")]
    pub cbct: Option<PathBuf>,
    /// Numbering of a CBCT label volume's values: fdi (STS 2024 and most tooth models),
    /// universal (1-32), toothfairy2 (teeth at FDI numbers, other structures skipped) or
    /// dentalsegmentator (3 upper teeth, 4 lower teeth, no tooth numbers: each jaw's teeth are
    /// split into teeth with the IOS crowns; also chosen when the labels look like it).
    #[arg(long, default_value = "fdi", value_parser = ["fdi", "universal", "toothfairy2", "dentalsegmentator"])]
    pub cbct_classes: String,
    /// World frame the CBCT label volume is expressed in (and so the fused teeth, with
    /// --frame cbct): lps (DICOM, ITK, 3D Slicer files) or ras (NIfTI, Slicer's scene).
    #[arg(long, default_value = "lps", value_parser = ["lps", "ras"])]
    pub cbct_frame: String,
    /// Tooth numbering of the input labels and file names; auto detects it from the array
    /// name (UniversalID, PredictedID: universal) or the values where unambiguous.
    #[arg(long, default_value = "auto", value_parser = ["auto", "fdi", "universal", "meshlabeler"])]
    pub labels: String,
    /// Name of the IOS label array (point or cell data; PLY vertex or face property). Default:
    /// the first known name (Label, labels, UniversalID, PredictedID, FDI, ...).
    #[arg(long, value_name = "NAME")]
    pub ios_label_array: Option<String>,
    /// Name of the CBCT label array when --cbct is one labeled mesh.
    #[arg(long, value_name = "NAME")]
    pub cbct_label_array: Option<String>,
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

/// The IOS input, the CBCT teeth by FDI, and the split's JSON when the CBCT was a per-jaw
/// volume split with the IOS.
pub type Inputs = (Ios, BTreeMap<u8, TriMesh>, Option<String>);

/// The IOS input: a labeled jaw or per-tooth crowns.
pub enum Ios {
    /// One labeled jaw mesh (labels converted to FDI).
    Jaw(LabeledMesh),
    /// Per-tooth crowns by FDI.
    Crowns(BTreeMap<u8, TriMesh>),
}

impl InputArgs {
    /// The label scheme given by --labels (`None`: detect).
    pub fn scheme(&self) -> Option<LabelScheme> {
        LabelScheme::from_name(&self.labels)
    }

    /// Pipeline options from --preset and --frame.
    pub fn options(&self) -> PipelineOptions {
        let p = Preset::from_name(&self.preset).unwrap_or_default();
        let f = OutputFrame::from_name(&self.frame).unwrap_or_default();
        let mut o = PipelineOptions::preset(p).with_frame(f);
        o.register.accept_questionable = self.accept_questionable;
        o
    }

    /// Both inputs, or `None` for the synthetic jaw; with a per-jaw CBCT volume, also the split's
    /// JSON.
    pub fn read(&self) -> Result<Option<Inputs>> {
        let (Some(ios), Some(cbct)) = (&self.ios, &self.cbct) else {
            return Ok(None);
        };
        let read_ios_here = || read_ios(ios, self.scheme(), self.ios_label_array.as_deref());
        if toothfuse::io::is_volume_path(cbct) {
            // A per-jaw volume may need the IOS crowns to split its teeth: IOS first.
            let (ios, ios_note) = read_ios_here()?;
            let (teeth, split) = self.read_volume_teeth(cbct, &ios)?;
            eprintln!("{ios_note}");
            return Ok(Some((ios, teeth, split)));
        }
        let opts = TeethOptions {
            scheme: self.scheme(),
            label_array: self.cbct_label_array.clone(),
        };
        let read_cbct = || {
            toothfuse::io::read_teeth_opts(cbct, &opts)
                .with_context(|| format!("reading CBCT {}", cbct.display()))
        };
        // The two files are independent: read side by side (most of a fresh process's reading
        // is the kernel handing it new pages), the IOS's error first when both fail; one after
        // the other under `--threads 1`.
        let cap = toothfuse::max_threads();
        let (ios_read, cbct_read) = if cap == 1 {
            (read_ios_here(), read_cbct())
        } else {
            std::thread::scope(|s| {
                let c = s.spawn(|| toothfuse::with_max_threads(cap, read_cbct));
                let i = read_ios_here();
                let c = c.join().unwrap_or_else(|p| std::panic::resume_unwind(p));
                (i, c)
            })
        };
        let (ios, ios_note) = ios_read?;
        let t = cbct_read?;
        // How the labels were read, said once both inputs are read (errors stay one line).
        eprintln!("{ios_note}");
        eprintln!(
            "CBCT {}: {}numbering {} ({})",
            cbct.display(),
            t.label_array
                .as_ref()
                .map_or(String::new(), |a| format!("labels {a:?}, ")),
            t.scheme.scheme.name(),
            t.scheme.reason
        );
        Ok(Some((ios, t.teeth, None)))
    }

    /// The teeth of a CBCT label volume, surfaced in the --cbct-frame world (a per-jaw volume
    /// split with the IOS crowns first); skipped labels (fragments, non-tooth structures) and
    /// the split per tooth are named on stderr.
    fn read_volume_teeth(
        &self,
        path: &Path,
        ios: &Ios,
    ) -> Result<(BTreeMap<u8, TriMesh>, Option<String>)> {
        let frame = Frame::from_name(&self.cbct_frame).unwrap_or_default();
        let mut scheme = VolumeScheme::from_name(&self.cbct_classes).unwrap_or_default();
        let vf = toothfuse::io::read_label_volume(path, frame)
            .with_context(|| format!("reading CBCT volume {}", path.display()))?;
        let mut vol = vf.volume;
        let labels: Vec<u16> = vol.label_counts().keys().copied().collect();
        if scheme == VolumeScheme::Fdi && looks_like_dentalsegmentator(&labels) {
            eprintln!(
                "note: {}: labels {labels:?} look like DentalSegmentator classes (3 upper teeth, \
                 4 lower teeth): splitting them into teeth with the IOS",
                path.display()
            );
            scheme = VolumeScheme::DentalSegmentator;
        }
        let mut split = None;
        if scheme == VolumeScheme::DentalSegmentator {
            let (v, json) = split_with_ios(&vol, ios)
                .with_context(|| format!("splitting the teeth of {}", path.display()))?;
            (vol, split, scheme) = (v, Some(json), VolumeScheme::Fdi);
        }
        let t = surface_teeth(&vol, scheme, &SurfaceOptions::default())
            .with_context(|| format!("surfacing the teeth of {}", path.display()))?;
        for (label, why) in &t.skipped {
            eprintln!("note: {}: label {label} skipped: {why}", path.display());
        }
        for (fdi, tooth) in &t.teeth {
            if tooth.touches_border {
                eprintln!(
                    "note: {}: tooth {fdi} (label {}) reaches the edge of the volume: it may be cut \
                     by the field of view",
                    path.display(),
                    tooth.label
                );
            }
        }
        Ok((
            t.teeth.into_iter().map(|(f, t)| (f, t.mesh)).collect(),
            split,
        ))
    }
}

/// The per-tooth FDI volume split from a per-jaw volume with the IOS crowns; the split per
/// tooth (contested share or why refused) on stderr; and the split's JSON.
fn split_with_ios(vol: &LabelVolume, ios: &Ios) -> Result<(LabelVolume, String)> {
    let crowns = match ios {
        Ios::Jaw(lm) => toothfuse::fuse::ios_crowns(lm)?,
        Ios::Crowns(c) => c.clone(),
    };
    let split = split_teeth(vol, &crowns, &SplitOptions::default())?;
    for n in &split.notes {
        eprintln!("note: {n}");
    }
    for j in &split.jaws {
        eprintln!(
            "split: {:?} arch fit of the IOS crowns to the teeth mask: {:.0}% of crown points \
             within 1 mm, RMS {:.2} mm",
            j.jaw,
            100.0 * j.fit.inlier_share,
            j.fit.rms_mm
        );
    }
    for line in split.summary() {
        eprintln!("split: {line}");
    }
    let json = split.to_json();
    Ok((split.volume, json))
}

/// The IOS input and a line saying which labels and numbering were used.
fn read_ios(
    path: &Path,
    scheme: Option<LabelScheme>,
    array: Option<&str>,
) -> Result<(Ios, String)> {
    let what = format!("IOS {}", path.display());
    if path.is_dir() {
        let opts = TeethOptions {
            scheme,
            label_array: None,
        };
        let t = toothfuse::io::read_teeth_opts(path, &opts)
            .with_context(|| format!("reading {what}"))?;
        let note = format!(
            "{what}: numbering {} ({})",
            t.scheme.scheme.name(),
            t.scheme.reason
        );
        return Ok((Ios::Crowns(t.teeth), note));
    }
    let f =
        toothfuse::io::read_mesh_with(path, array).with_context(|| format!("reading {what}"))?;
    let arrays = f.arrays_list();
    let mut lm = f.mesh;
    let labels = lm.face_labels.as_ref().or(lm.vertex_labels.as_ref());
    let Some(labels) = labels else {
        return Err(anyhow!(
            "{}: the IOS mesh has no tooth label array; one-component arrays in the file: {} \
             (name the label array with --ios-label-array)",
            path.display(),
            arrays
        ));
    };
    let detected = match scheme {
        Some(s) => toothfuse::io::Detected {
            scheme: s,
            reason: "given by --labels".into(),
        },
        None => detect_scheme(
            &path.display().to_string(),
            f.label_array.as_deref(),
            f.teeth3ds_json,
            labels,
        )?,
    };
    let note = format!(
        "{what}: labels {:?}, numbering {} ({})",
        f.label_array.as_deref().unwrap_or(""),
        detected.scheme.name(),
        detected.reason
    );
    for labels in [&mut lm.vertex_labels, &mut lm.face_labels]
        .into_iter()
        .flatten()
    {
        labels_to_fdi(detected.scheme, labels)
            .with_context(|| format!("{}: IOS labels", path.display()))?;
    }
    Ok((Ios::Jaw(lm), note))
}

/// Creates the parent folder of `path`.
pub fn create_parent(path: &Path) -> Result<()> {
    if let Some(p) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(p).with_context(|| format!("creating {}", p.display()))?;
    }
    Ok(())
}
