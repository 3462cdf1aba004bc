//! Per-tooth meshes: a folder of `tooth_<n>.<ext>` files, or one labeled jaw mesh split by its
//! labels, with the tooth numbers converted to FDI by a [`LabelScheme`].

use super::numbering::{Detected, detect_scheme};
use super::{Format, read_mesh, read_mesh_with, write_mesh};
use crate::arch::check_fdi;
use crate::mesh::{TriMesh, split_by_face_labels, split_by_vertex_labels};
use crate::{Error, Result};
use std::collections::BTreeMap;
use std::path::Path;

/// How the tooth numbers in a file (labels or `tooth_<n>` file names) are meant.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LabelScheme {
    /// FDI two-digit numbers already (Teeth3DS, our own files). 0 = gingiva.
    #[default]
    Fdi,
    /// Universal / UNN numbering 1–32 (Open-Full-Jaw file names): 1–8 = FDI 18…11,
    /// 9–16 = 21…28, 17–24 = 38…31, 25–32 = 41…48.
    Universal,
    /// Mesh Labeler / MeshSegNet ordinal labels (Example_01.vtp). Upper 1–8 = FDI 18…11 and
    /// 9–16 = 21…28, checked on Example_01 against its UR1 (FDI 11) landmarks; lower 17–32
    /// assumed to continue the same way as Universal (38…31, 41…48), which no available file
    /// verifies. 0 = gingiva.
    MeshLabeler,
}

impl LabelScheme {
    /// The CLI name: `fdi`, `universal` or `meshlabeler`.
    pub fn name(self) -> &'static str {
        match self {
            LabelScheme::Fdi => "fdi",
            LabelScheme::Universal => "universal",
            LabelScheme::MeshLabeler => "meshlabeler",
        }
    }

    /// The scheme of a CLI name ([`LabelScheme::name`]); `None` for other names.
    pub fn from_name(name: &str) -> Option<LabelScheme> {
        [
            LabelScheme::Fdi,
            LabelScheme::Universal,
            LabelScheme::MeshLabeler,
        ]
        .into_iter()
        .find(|s| s.name() == name)
    }

    /// True for the gingiva label: 0 in every scheme, and 33 in Universal numbering (as the
    /// DCBIA tools write it).
    pub fn is_gingiva(self, label: i32) -> bool {
        label == 0 || (self == LabelScheme::Universal && label == 33)
    }

    /// The FDI number of a non-zero label or file number; errors name the label and the
    /// scheme.
    pub fn to_fdi(self, label: i32) -> Result<u8> {
        match self {
            LabelScheme::Fdi => check_fdi(label).map_err(|_| {
                Error::InvalidArgument(format!(
                    "label {label} is not an FDI tooth number (11-18, 21-28, 31-38, 41-48, 51-85); \
                     if the file numbers teeth 1-32, read it with LabelScheme::Universal or \
                     LabelScheme::MeshLabeler"
                ))
            }),
            LabelScheme::Universal | LabelScheme::MeshLabeler => universal_to_fdi(label)
                .ok_or_else(|| {
                    Error::InvalidArgument(format!(
                        "label {label} is outside 1-32 ({self:?} numbering)"
                    ))
                }),
        }
    }
}

/// Universal / UNN tooth number (1–32) to FDI; `None` outside 1–32.
pub fn universal_to_fdi(n: i32) -> Option<u8> {
    let f = match n {
        1..=8 => 10 + (9 - n),
        9..=16 => 20 + (n - 8),
        17..=24 => 30 + (25 - n),
        25..=32 => 40 + (n - 24),
        _ => return None,
    };
    Some(f as u8)
}

/// FDI (permanent teeth) to Universal / UNN (1–32); `None` for primary or invalid numbers.
pub fn fdi_to_universal(fdi: u8) -> Option<i32> {
    (1..=32).find(|&n| universal_to_fdi(n) == Some(fdi))
}

/// How [`read_teeth_opts`] reads per-tooth meshes.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TeethOptions {
    /// The numbering of labels and file names; `None` detects it ([`detect_scheme`]).
    pub scheme: Option<LabelScheme>,
    /// The label array of a labeled mesh file; `None` chooses by name.
    pub label_array: Option<String>,
}

/// Per-tooth meshes as read by [`read_teeth_opts`], with how their numbers were read.
#[derive(Clone, Debug)]
pub struct Teeth {
    /// The teeth by FDI number.
    pub teeth: BTreeMap<u8, TriMesh>,
    /// The numbering used (given or detected) and why.
    pub scheme: Detected,
    /// The label array of a labeled mesh file (`None` for a folder).
    pub label_array: Option<String>,
}

/// Reads per-tooth meshes like [`read_teeth_with`], choosing the label array and detecting the
/// numbering unless `opts` names them.
pub fn read_teeth_opts(path: impl AsRef<Path>, opts: &TeethOptions) -> Result<Teeth> {
    let path = path.as_ref();
    let what = path.display().to_string();
    let given = |s: LabelScheme| Detected {
        scheme: s,
        reason: "given".into(),
    };
    if path.is_dir() {
        let numbers = folder_files(path)?;
        let nums: Vec<i32> = numbers.iter().map(|(n, _)| *n).collect();
        let scheme = match opts.scheme {
            Some(s) => given(s),
            None => detect_scheme(&what, Some("tooth_<n> file names"), false, &nums)?,
        };
        let teeth = read_folder(path, scheme.scheme)?;
        return Ok(Teeth {
            teeth,
            scheme,
            label_array: None,
        });
    }
    let f = read_mesh_with(path, opts.label_array.as_deref())?;
    let labels = f
        .mesh
        .face_labels
        .as_ref()
        .or(f.mesh.vertex_labels.as_ref());
    let scheme = match (opts.scheme, labels) {
        (Some(s), _) => given(s),
        (None, Some(l)) => detect_scheme(&what, f.label_array.as_deref(), f.teeth3ds_json, l)?,
        (None, None) => {
            return Err(Error::Io(format!(
                "{what}: no tooth label array, so it cannot be split into teeth; one-component                  arrays in the file: {} (name one with --cbct-label-array)",
                f.arrays_list()
            )));
        }
    };
    let teeth = split_teeth(path, &f.mesh, scheme.scheme)?;
    Ok(Teeth {
        teeth,
        scheme,
        label_array: f.label_array,
    })
}

/// Reads per-tooth meshes with FDI numbering; see [`read_teeth_with`].
pub fn read_teeth(path: impl AsRef<Path>) -> Result<BTreeMap<u8, TriMesh>> {
    read_teeth_with(path, LabelScheme::Fdi)
}

/// Reads per-tooth meshes from `path`:
/// - a folder: every `tooth_<n>.<stl|ply|obj|vtp|vtk>` file (other files ignored), `n`
///   converted by `scheme`; an empty folder or two files for one tooth are errors;
/// - a labeled mesh file: split by its face labels (preferred) or vertex labels (a face goes
///   to a tooth when its three vertices carry that label); label 0 (gingiva) is dropped,
///   other labels are converted by `scheme` (errors name the label).
pub fn read_teeth_with(
    path: impl AsRef<Path>,
    scheme: LabelScheme,
) -> Result<BTreeMap<u8, TriMesh>> {
    let path = path.as_ref();
    if path.is_dir() {
        return read_folder(path, scheme);
    }
    let lm = read_mesh(path)?;
    split_teeth(path, &lm, scheme)
}

/// Splits a labeled mesh into teeth by its face labels (preferred) or vertex labels.
fn split_teeth(
    path: &Path,
    lm: &crate::mesh::LabeledMesh,
    scheme: LabelScheme,
) -> Result<BTreeMap<u8, TriMesh>> {
    let parts = match (&lm.face_labels, &lm.vertex_labels) {
        (Some(fl), _) => split_by_face_labels(&lm.mesh, fl)?,
        (None, Some(vl)) => split_by_vertex_labels(&lm.mesh, vl)?,
        (None, None) => {
            return Err(Error::Io(format!(
                "{}: no per-vertex or per-face labels, so it cannot be split into teeth",
                path.display()
            )));
        }
    };
    let mut out = BTreeMap::new();
    for (label, sub) in parts {
        if scheme.is_gingiva(label) {
            continue;
        }
        let fdi = scheme
            .to_fdi(label)
            .map_err(|e| Error::Io(format!("{}: {e}", path.display())))?;
        out.insert(fdi, sub.mesh);
    }
    if out.is_empty() {
        return Err(Error::MissingData(format!(
            "{}: no tooth labels (only gingiva or nothing)",
            path.display()
        )));
    }
    Ok(out)
}

/// The `tooth_<n>` files of a folder with their numbers, sorted by path.
fn folder_files(dir: &Path) -> Result<Vec<(i32, std::path::PathBuf)>> {
    let entries = std::fs::read_dir(dir)
        .map_err(|e| Error::Io(format!("{}: cannot list folder: {e}", dir.display())))?;
    let mut out = Vec::new();
    for e in entries {
        let p = e
            .map_err(|e| Error::Io(format!("{}: cannot list folder: {e}", dir.display())))?
            .path();
        if let Some(n) = tooth_number(&p) {
            out.push((n, p));
        }
    }
    out.sort_by(|a, b| a.1.cmp(&b.1));
    Ok(out)
}

fn read_folder(dir: &Path, scheme: LabelScheme) -> Result<BTreeMap<u8, TriMesh>> {
    let mut files: BTreeMap<u8, std::path::PathBuf> = BTreeMap::new();
    for (n, p) in folder_files(dir)? {
        let fdi = scheme
            .to_fdi(n)
            .map_err(|e| Error::Io(format!("{}: {e}", p.display())))?;
        if let Some(prev) = files.insert(fdi, p.clone()) {
            let (a, b) = if prev < p { (prev, p) } else { (p, prev) };
            return Err(Error::Io(format!(
                "two files for tooth {fdi}: {} and {}",
                a.display(),
                b.display()
            )));
        }
    }
    if files.is_empty() {
        return Err(Error::MissingData(format!(
            "{}: no tooth_<number>.<stl|ply|obj|vtp|vtk> files in this folder",
            dir.display()
        )));
    }
    let mut out = BTreeMap::new();
    for (fdi, p) in files {
        let lm = read_mesh(&p).map_err(|e| e.in_tooth(fdi))?;
        if lm.mesh.triangles.is_empty() {
            return Err(Error::Io(format!("{}: no triangles", p.display())).in_tooth(fdi));
        }
        out.insert(fdi, lm.mesh);
    }
    Ok(out)
}

/// `n` of a `tooth_<n>.<mesh ext>` file name.
fn tooth_number(p: &Path) -> Option<i32> {
    Format::from_path(p).ok()?;
    let stem = p.file_stem()?.to_str()?;
    let digits = stem.strip_prefix("tooth_")?;
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) || digits.len() > 3 {
        return None;
    }
    digits.parse().ok()
}

/// Writes each tooth to `dir/tooth_<fdi>.<ext>` (creating `dir`); `ext` is `stl`, `ply`,
/// `obj` or `vtp`.
pub fn write_teeth_dir(
    dir: impl AsRef<Path>,
    teeth: &BTreeMap<u8, TriMesh>,
    ext: &str,
) -> Result<()> {
    let dir = dir.as_ref();
    std::fs::create_dir_all(dir)
        .map_err(|e| Error::Io(format!("{}: cannot create folder: {e}", dir.display())))?;
    for (&fdi, mesh) in teeth {
        check_fdi(fdi as i32)?;
        write_mesh(dir.join(format!("tooth_{fdi}.{ext}")), mesh, &[])
            .map_err(|e| e.in_tooth(fdi))?;
    }
    Ok(())
}
