//! Mesh file formats for the CLI and tests: PLY, STL, OBJ (+ Teeth3DS JSON labels), VTK XML
//! PolyData (`.vtp`) and legacy VTK (`.vtk`), plus per-tooth folders ([`read_teeth`]).
//!
//! Every reader returns a [`LabeledMesh`] in f64 and reports malformed content as
//! [`Error::Io`] naming the file, the place (line or byte offset when known) and what was
//! expected; no input makes a reader panic. Polygons are triangulated by fans `(v0, vi, vi+1)`,
//! so a face label is repeated on each of its triangles.

mod labels;
mod numbering;
mod obj;
mod ply;
mod ply_binary;
mod stl;
mod teeth;
pub mod volume;
mod vtk_legacy;
mod vtp;
mod vtp_data;
mod vtp_write;

pub use labels::{ArrayInfo, KNOWN_LABEL_NAMES, MeshFile};
pub use numbering::{Detected, detect_scheme, labels_to_fdi};
pub use obj::read_obj_labeled_bytes;
pub use ply::{read_ply_bytes, read_ply_bytes_with, write_ply};
pub use stl::{read_stl_bytes, write_stl};
pub use teeth::{
    LabelScheme, Teeth, TeethOptions, fdi_to_universal, read_teeth, read_teeth_opts,
    read_teeth_with, universal_to_fdi, write_teeth_dir,
};
pub use volume::{
    VolumeFile, VolumeHeader, is_volume_path, nrrd_bytes, read_label_volume, write_nrrd,
};
pub use vtk_legacy::{read_vtk_legacy_bytes, read_vtk_legacy_bytes_with};
pub use vtp::{VtpEncoding, read_vtp_bytes, read_vtp_bytes_with, write_vtp};

use crate::mesh::{LabeledMesh, TriMesh};
use crate::{Error, Result};
use glam::DVec3;
use std::path::{Path, PathBuf};

/// Mesh file formats known by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Stanford PLY (`.ply`), ASCII or binary.
    Ply,
    /// STL (`.stl`), ASCII or binary.
    Stl,
    /// Wavefront OBJ (`.obj`), optionally with a Teeth3DS label JSON beside it.
    Obj,
    /// VTK XML PolyData (`.vtp`).
    Vtp,
    /// Legacy VTK (`.vtk`), POLYDATA only.
    VtkLegacy,
}

impl Format {
    /// The format of a path by its extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Format> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        match ext.as_str() {
            "ply" => Ok(Format::Ply),
            "stl" => Ok(Format::Stl),
            "obj" => Ok(Format::Obj),
            "vtp" => Ok(Format::Vtp),
            "vtk" => Ok(Format::VtkLegacy),
            _ => Err(Error::Io(format!(
                "{}: unknown mesh file extension {ext:?} (expected .ply, .stl, .obj, .vtp or .vtk)",
                path.display()
            ))),
        }
    }
}

/// How [`write_mesh_with`] encodes a PLY file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PlyEncoding {
    /// Binary little-endian (compact, lossless); the default.
    #[default]
    BinaryLittleEndian,
    /// Binary big-endian.
    BinaryBigEndian,
    /// ASCII (shortest round-trip decimal, so still lossless).
    Ascii,
}

/// Reads a mesh file, choosing the format by extension (`.ply`, `.stl`, `.obj`, `.vtp`, `.vtk`,
/// case-insensitive). Labels found in the file (the per-vertex and/or per-face array with the
/// best-ranked known label name: `label`, `labels`, `UniversalID`, `PredictedID`, `FDI`, …, see
/// [`KNOWN_LABEL_NAMES`]) come back in the [`LabeledMesh`]. For `.obj`, a Teeth3DS JSON beside
/// the file (same stem, `.json`) supplies per-vertex labels.
pub fn read_mesh(path: impl AsRef<Path>) -> Result<LabeledMesh> {
    read_mesh_with(path, None).map(|f| f.mesh)
}

/// Like [`read_mesh`], with the labels from the point or cell array (PLY: vertex or face
/// property) named `label_array` when given (an error listing the file's arrays when it has
/// none of that name), and reporting which array the labels came from and every one-component
/// array found.
pub fn read_mesh_with(path: impl AsRef<Path>, label_array: Option<&str>) -> Result<MeshFile> {
    let path = path.as_ref();
    let format = Format::from_path(path)?;
    let bytes = std::fs::read(path).map_err(|e| file_err(path, format!("cannot read: {e}")))?;
    let name = path.display().to_string();
    match format {
        Format::Ply => read_ply_bytes_with(&name, &bytes, label_array),
        Format::Stl => {
            let mesh = read_stl_bytes(&name, &bytes)?;
            labels::choose(&name, &[], label_array)?;
            Ok(MeshFile {
                mesh: LabeledMesh {
                    mesh,
                    ..Default::default()
                },
                ..Default::default()
            })
        }
        Format::Obj => obj::read_obj_with_labels(path, &bytes, label_array),
        Format::Vtp => read_vtp_bytes_with(&name, &bytes, label_array),
        Format::VtkLegacy => read_vtk_legacy_bytes_with(&name, &bytes, label_array),
    }
}

/// Writes a mesh by extension: `.ply` binary little-endian with `x, y, z` as double (lossless)
/// and one `int` vertex property per entry of `vertex_int_props` (e.g. `("label", &labels)`);
/// `.stl` binary (f32, properties dropped); `.obj` (shortest round-trip decimals, properties
/// dropped); `.vtp` (appended raw, Float64 points, properties as Int32 point data).
pub fn write_mesh(
    path: impl AsRef<Path>,
    mesh: &TriMesh,
    vertex_int_props: &[(&str, &[i32])],
) -> Result<()> {
    write_mesh_with(path, mesh, vertex_int_props, PlyEncoding::default())
}

/// Like [`write_mesh`], choosing the PLY encoding (ignored for other formats).
pub fn write_mesh_with(
    path: impl AsRef<Path>,
    mesh: &TriMesh,
    vertex_int_props: &[(&str, &[i32])],
    ply_encoding: PlyEncoding,
) -> Result<()> {
    let path = path.as_ref();
    let format = Format::from_path(path)?;
    for (name, values) in vertex_int_props {
        if values.len() != mesh.vertex_count() {
            return Err(Error::InvalidArgument(format!(
                "vertex property {name:?} has {} values for {} vertices",
                values.len(),
                mesh.vertex_count()
            )));
        }
    }
    let mut bytes = Vec::new();
    match format {
        Format::Ply => {
            // Streamed to the file once checked: a large mesh is not first copied into memory.
            ply::check_ply(mesh, vertex_int_props)?;
            let cannot = |e: std::io::Error| file_err(path, format!("cannot write: {e}"));
            let file = std::fs::File::create(path).map_err(cannot)?;
            let mut w = std::io::BufWriter::new(file);
            ply::write_checked_ply(&mut w, mesh, vertex_int_props, ply_encoding)?;
            return std::io::Write::flush(&mut w).map_err(cannot);
        }
        Format::Stl => write_stl(&mut bytes, mesh)?,
        Format::Obj => obj::write_obj(&mut bytes, mesh)?,
        Format::Vtp => write_vtp(
            &mut bytes,
            mesh,
            vertex_int_props,
            &[],
            VtpEncoding::AppendedRaw {
                compressed: false,
                header64: false,
            },
        )?,
        Format::VtkLegacy => {
            return Err(Error::Io(format!(
                "{}: writing legacy .vtk is not supported (use .vtp or .ply)",
                path.display()
            )));
        }
    }
    std::fs::write(path, bytes).map_err(|e| file_err(path, format!("cannot write: {e}")))
}

/// The folder of real dental test meshes: `$TOOTHFUSE_REAL_DATA` if set, else
/// `<crate>/../shared/data/real`. `None` when it does not exist (tests then skip).
pub fn real_data_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("TOOTHFUSE_REAL_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/real"))
        });
    dir.is_dir().then_some(dir)
}

/// Converts a numeric label value to i32; fails on fractions or out-of-range values.
pub(crate) fn label_from_f64(v: f64, file: &str, what: &str, index: usize) -> Result<i32> {
    if v.fract() == 0.0 && v >= i32::MIN as f64 && v <= i32::MAX as f64 {
        Ok(v as i32)
    } else {
        Err(Error::Io(format!(
            "{file}: {what} {index} has label {v}, which is not an integer"
        )))
    }
}

/// An [`Error::Io`] naming a file.
pub(crate) fn file_err(path: &Path, msg: impl std::fmt::Display) -> Error {
    Error::Io(format!("{}: {msg}", path.display()))
}

/// Collects polygons (given as vertex-index lists) into triangles by fan, checking indices.
/// `labels_of_poly` (if any) is expanded to one label per triangle.
pub(crate) struct FaceBuilder<'a> {
    file: &'a str,
    vertex_count: usize,
    /// Triangles so far.
    pub triangles: Vec<[u32; 3]>,
    /// For each triangle, the index of the polygon it came from.
    pub source_poly: Vec<u32>,
    polys: usize,
}

impl<'a> FaceBuilder<'a> {
    pub(crate) fn new(file: &'a str, vertex_count: usize) -> Self {
        Self {
            file,
            vertex_count,
            triangles: Vec::new(),
            source_poly: Vec::new(),
            polys: 0,
        }
    }

    /// Adds polygon number `self.polys` (fan-triangulated); fewer than 3 vertices is an error.
    pub(crate) fn polygon(&mut self, idx: &[i64]) -> Result<()> {
        let f = self.polys;
        if idx.len() < 3 {
            return Err(Error::Io(format!(
                "{}: face {f} has {} vertices (at least 3 expected)",
                self.file,
                idx.len()
            )));
        }
        // Every index checked first (the first bad one named), then used as checked.
        for &i in idx {
            self.check(f, i)?;
        }
        let v = |k: usize| idx[k] as u32;
        for k in 1..idx.len() - 1 {
            self.triangles.push([v(0), v(k), v(k + 1)]);
            self.source_poly.push(f as u32);
        }
        self.polys += 1;
        Ok(())
    }

    /// Adds a triangle strip as one cell (triangles alternate orientation as in VTK).
    pub(crate) fn strip(&mut self, idx: &[i64]) -> Result<()> {
        let f = self.polys;
        if idx.len() < 3 {
            return Err(Error::Io(format!(
                "{}: triangle strip {f} has {} vertices (at least 3 expected)",
                self.file,
                idx.len()
            )));
        }
        for &i in idx {
            self.check(f, i)?;
        }
        let v = |k: usize| idx[k] as u32;
        for k in 0..idx.len() - 2 {
            let t = if k % 2 == 0 {
                [v(k), v(k + 1), v(k + 2)]
            } else {
                [v(k + 1), v(k), v(k + 2)]
            };
            self.triangles.push(t);
            self.source_poly.push(f as u32);
        }
        self.polys += 1;
        Ok(())
    }

    fn check(&self, f: usize, i: i64) -> Result<u32> {
        if i < 0 || i as u64 >= self.vertex_count as u64 {
            return Err(Error::Io(format!(
                "{}: face {f} refers to vertex {i}, but the file has only {} vertices",
                self.file, self.vertex_count
            )));
        }
        Ok(i as u32)
    }

    /// Number of polygons/strips added.
    pub(crate) fn poly_count(&self) -> usize {
        self.polys
    }
}

/// Checks that every coordinate is finite (naming the vertex otherwise).
pub(crate) fn check_finite(file: &str, positions: &[DVec3]) -> Result<()> {
    match positions.iter().position(|p| !p.is_finite()) {
        Some(v) => Err(Error::Io(format!(
            "{file}: vertex {v} has a non-finite coordinate ({:?})",
            positions[v]
        ))),
        None => Ok(()),
    }
}

/// Checks a vertex count fits u32 indices.
pub(crate) fn check_vertex_count(file: &str, n: usize) -> Result<()> {
    if n > u32::MAX as usize {
        return Err(Error::Io(format!(
            "{file}: {n} vertices exceed the supported maximum of {}",
            u32::MAX
        )));
    }
    Ok(())
}

/// Checks every triangle index of a mesh about to be written (naming the face otherwise).
pub(crate) fn check_mesh_indices(mesh: &TriMesh) -> Result<()> {
    let n = mesh.vertex_count();
    for (f, t) in mesh.triangles.iter().enumerate() {
        if let Some(&index) = t.iter().find(|&&v| v as usize >= n) {
            return Err(Error::IndexOutOfBounds {
                face: f,
                index,
                vertex_count: n,
            });
        }
    }
    Ok(())
}
