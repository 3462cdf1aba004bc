//! The fusion pipeline after registration (paper section 2.3): per tooth, crown removal
//! ([`crate::cut`]) and stitching ([`crate::stitch`]) into one watertight mesh; per jaw, all
//! fused teeth in one mesh with per-vertex FDI labels and sources.

mod assembly;
mod band_crossings;
mod band_opt;
mod build_budget;
mod build_memo;
mod crossed;
mod flat_cut;
mod fold_wide;
pub mod fringe;
mod inlet;
mod jaw;
mod near_faces;
mod polish;
pub mod quality;
mod remedy;
mod root_trim;
mod skipped;
#[cfg(test)]
mod test_teeth;
mod tooth;
pub mod untangle;

pub use assembly::stitch_tooth;
pub use jaw::{CutJaw, FusedJaw, ToothTransforms, cut_jaw, fuse_jaw, ios_crowns, stitch_jaw};
pub(crate) use jaw::{cut_crowns, stitch_jaw_owned};
pub use quality::ToothQuality;
pub use tooth::{CutTooth, FusedTooth, cut_tooth, fuse_tooth};

use crate::cut::{CutMethod, CutOptions};
use crate::stitch::interp::InterpOptions;
use crate::stitch::{PointGeneration, StitchOptions};

/// Where a fused vertex comes from (stored as `u8` in the per-vertex source attribute).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[repr(u8)]
pub enum VertexSource {
    /// An IOS crown vertex, at exactly its input position under `ios_to_output`.
    Ios = 0,
    /// A new vertex of the stitching band (or of a filled crown hole).
    Band = 1,
    /// A CBCT root vertex, at its position under `cbct_to_output`.
    Cbct = 2,
}

/// Named option sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Preset {
    /// The paper: Dijkstra vertex-path cut, Algorithm 1 point generation (N = 2, K = 2, m = 2,
    /// 0.05 mm voxels), straight (ruled) segments; meshed in the annulus so it is watertight.
    Paper,
    /// Ours: level-set cut below the margin's windowed minimum height, graded rings on a Hermite
    /// loft tangent to both surfaces.
    #[default]
    Default,
}

impl Preset {
    /// Command-line name (`paper`, `default`).
    pub fn name(self) -> &'static str {
        match self {
            Preset::Paper => "paper",
            Preset::Default => "default",
        }
    }

    /// Parses a command-line name.
    pub fn from_name(s: &str) -> Option<Preset> {
        [Preset::Paper, Preset::Default]
            .into_iter()
            .find(|p| p.name() == s)
    }
}

/// Options of the fusion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FuseOptions {
    /// Crown removal.
    pub cut: CutOptions,
    /// Stitching.
    pub stitch: StitchOptions,
    /// Geodesic reach (mm) from the IOS margin within which crown faces that fold over other
    /// crown faces, or that the band cannot clear, are trimmed ([`fringe`]); a tooth the band
    /// still crosses is built again with the narrow slits of its margin closed and
    /// then with 2x and 3x this reach (warned). 0 trims nothing and closes no slit.
    pub fringe_reach_mm: f64,
    /// Count intersecting face pairs in the quality report (exact test; costs time).
    pub check_self_intersections: bool,
    /// Put teeth present only in the CBCT into the jaw output unfused (flagged in
    /// [`FusedJaw::passed_through`]).
    pub pass_through_cbct_only: bool,
}

impl Default for FuseOptions {
    fn default() -> Self {
        Self::preset(Preset::Default)
    }
}

impl FuseOptions {
    /// The options of a preset.
    pub fn preset(p: Preset) -> FuseOptions {
        match p {
            Preset::Paper => FuseOptions {
                cut: CutOptions {
                    method: CutMethod::Dijkstra,
                    offset: 0.8,
                    window: 0.0,
                    max_slope: 0.0,
                },
                stitch: StitchOptions {
                    points: PointGeneration::Recursive(InterpOptions::default()),
                    tangent_scale: 0.0,
                    optimize: false,
                    flips: false,
                    untangle: false,
                },
                fringe_reach_mm: 0.0,
                check_self_intersections: false,
                pass_through_cbct_only: false,
            },
            Preset::Default => FuseOptions {
                cut: CutOptions::default(),
                stitch: StitchOptions::default(),
                fringe_reach_mm: 0.3,
                check_self_intersections: false,
                pass_through_cbct_only: false,
            },
        }
    }
}
