//! Which array of a mesh file holds the tooth labels: the names dental tools write
//! (`Label`, `UniversalID`, `PredictedID`, `FDI`, …), a name the user gives, and the list of
//! candidate arrays for messages when none fits.

use crate::mesh::LabeledMesh;
use crate::{Error, Result};

/// A one-component array (or PLY scalar property) found in a mesh file: a candidate for tooth
/// labels.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ArrayInfo {
    /// The array's name as written in the file.
    pub name: String,
    /// True for point (vertex) data, false for cell (face) data.
    pub on_points: bool,
    /// The stored type as the file names it (`Int32`, `Float32`, `int`, `uchar`, …).
    pub data_type: String,
}

impl ArrayInfo {
    pub(crate) fn new(name: &str, on_points: bool, data_type: &str) -> ArrayInfo {
        ArrayInfo {
            name: name.to_string(),
            on_points,
            data_type: data_type.to_string(),
        }
    }
}

impl std::fmt::Display for ArrayInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let dom = if self.on_points { "point" } else { "cell" };
        write!(f, "{:?} ({dom} data, {})", self.name, self.data_type)
    }
}

/// A mesh file as read: the labeled mesh, which array the labels came from, and every
/// one-component array the file holds.
#[derive(Clone, Debug, Default)]
pub struct MeshFile {
    /// Geometry and the labels of the chosen array (per vertex and/or per face).
    pub mesh: LabeledMesh,
    /// The name of the array the labels came from (`None`: the mesh has no labels).
    pub label_array: Option<String>,
    /// True when the labels came from a Teeth3DS JSON beside an OBJ (FDI numbers by format).
    pub teeth3ds_json: bool,
    /// Every one-component array (or PLY scalar property other than x, y, z) in the file.
    pub arrays: Vec<ArrayInfo>,
}

impl MeshFile {
    /// The one-component arrays, listed for messages (`none` when there are none).
    pub fn arrays_list(&self) -> String {
        list(&self.arrays)
    }
}

/// Lists arrays for a message.
pub(crate) fn list(arrays: &[ArrayInfo]) -> String {
    if arrays.is_empty() {
        return "none".into();
    }
    arrays
        .iter()
        .map(ArrayInfo::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Names recognised as tooth labels without being asked for, in order of preference
/// (compared case-insensitively): the generic `label`/`labels`, DCBIA's `UniversalID` and
/// `PredictedID`, explicit FDI arrays, then any name containing `label`.
pub const KNOWN_LABEL_NAMES: &[&str] = &[
    "label",
    "labels",
    "universalid",
    "universal_id",
    "predictedid",
    "predicted_id",
    "fdi",
    "fdi_label",
    "toothid",
    "tooth_id",
];

/// The preference rank of an array name for automatic detection (lower is better); `None`
/// for names that do not look like tooth labels.
pub(crate) fn auto_rank(name: &str) -> Option<usize> {
    let l = name.to_ascii_lowercase();
    match KNOWN_LABEL_NAMES.iter().position(|k| *k == l) {
        Some(i) => Some(i),
        None if l.contains("label") => Some(KNOWN_LABEL_NAMES.len()),
        None => None,
    }
}

/// Chooses the label array among `arrays`: the `requested` name (exact; else the one name
/// equal ignoring case), or without a request the best-ranked known name ([`auto_rank`]).
/// `Ok(None)` when nothing looks like labels; an error naming the file and listing the arrays
/// when a requested name is absent.
pub(crate) fn choose(
    file: &str,
    arrays: &[ArrayInfo],
    requested: Option<&str>,
) -> Result<Option<String>> {
    match requested {
        Some(want) => {
            if arrays.iter().any(|a| a.name == want) {
                return Ok(Some(want.to_string()));
            }
            let mut loose: Vec<&str> = arrays
                .iter()
                .filter(|a| a.name.eq_ignore_ascii_case(want))
                .map(|a| a.name.as_str())
                .collect();
            loose.dedup();
            if loose.len() == 1 {
                return Ok(Some(loose[0].to_string()));
            }
            Err(Error::MissingData(format!(
                "{file}: no label array named {want:?}; one-component arrays in the file: {}",
                list(arrays)
            )))
        }
        None => Ok(arrays
            .iter()
            .filter_map(|a| auto_rank(&a.name).map(|r| (r, &a.name)))
            .min_by_key(|(r, _)| *r)
            .map(|(_, n)| n.clone())),
    }
}
