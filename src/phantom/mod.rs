//! The synthetic jaw ("phantom"): realistic IOS and CBCT meshes with known ground truth,
//! deterministic from a seed. Every accuracy claim of the project is measured on it.
//!
//! Frames: the true anatomy lives in a *world* frame (mm). The IOS jaw mesh is the world
//! anatomy moved per tooth by the scanner's cumulative stitching drift `ios_drift`, then by one
//! random rigid pose `world_to_ios`. The CBCT teeth are the world anatomy (degraded by the CBCT
//! simulation) moved by another random pose `world_to_cbct`. So the true per-tooth mapping from
//! the CBCT frame to the IOS frame is `world_to_ios ∘ ios_drift ∘ world_to_cbct⁻¹`.

use crate::arch::Jaw;
use crate::mesh::{LabeledMesh, TriMesh};
use crate::{Result, Rigid};
use glam::DVec3;
use std::collections::BTreeMap;

/// Which scenario to generate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Variant {
    /// Full arch (14 teeth, no third molars), moderate drift.
    #[default]
    Full,
    /// Some teeth missing in one modality only (IOS-only and CBCT-only teeth).
    MissingTeeth,
    /// Partial arch: 3–5 consecutive teeth.
    PartialArch,
    /// One tooth with a metal restoration: bloated, spiky crown in CBCT.
    MetalArtefact,
    /// Heavy IOS stitching drift (several times the usual).
    HeavyDrift,
}

impl Variant {
    /// Every variant, for sweeps.
    pub const ALL: [Variant; 5] = [
        Variant::Full,
        Variant::MissingTeeth,
        Variant::PartialArch,
        Variant::MetalArtefact,
        Variant::HeavyDrift,
    ];

    /// Command-line name (`full`, `missing`, `partial`, `metal`, `drift`).
    pub fn name(self) -> &'static str {
        match self {
            Variant::Full => "full",
            Variant::MissingTeeth => "missing",
            Variant::PartialArch => "partial",
            Variant::MetalArtefact => "metal",
            Variant::HeavyDrift => "drift",
        }
    }

    /// Parses a command-line name.
    pub fn from_name(s: &str) -> Option<Variant> {
        Variant::ALL.into_iter().find(|v| v.name() == s)
    }
}

/// Options of the generator.
#[derive(Clone, Debug)]
pub struct PhantomOptions {
    /// Seed: same options, same phantom, bit for bit.
    pub seed: u64,
    /// Upper or lower jaw.
    pub jaw: Jaw,
    /// Scenario.
    pub variant: Variant,
    /// Real whole-tooth meshes (closed, mm, keyed by FDI) to use as the true anatomy instead of
    /// parametric teeth; they are placed on the arch as they are (their own frame is kept).
    pub anatomy: Option<BTreeMap<u8, TriMesh>>,
}

impl Default for PhantomOptions {
    fn default() -> Self {
        Self {
            seed: 1,
            jaw: Jaw::Upper,
            variant: Variant::Full,
            anatomy: None,
        }
    }
}

/// Ground truth of one tooth.
#[derive(Clone, Debug)]
pub struct ToothTruth {
    /// FDI number.
    pub fdi: u8,
    /// The true closed tooth surface (crown + root), world frame.
    pub surface: TriMesh,
    /// The true gingival margin on the crown, a closed polyline, world frame.
    pub margin: Vec<DVec3>,
    /// Unit long axis of the tooth, pointing from the root apex to the occlusal surface, world frame.
    pub axis: DVec3,
    /// IOS stitching drift of this tooth (world → drifted world).
    pub ios_drift: Rigid,
    /// True mapping from the CBCT frame to the IOS frame for this tooth.
    pub cbct_to_ios: Rigid,
    /// Whether the IOS holds this tooth's crown.
    pub in_ios: bool,
    /// Whether the CBCT holds this tooth.
    pub in_cbct: bool,
    /// Whether this tooth carries a simulated metal artefact in CBCT.
    pub metal_artefact: bool,
}

/// Ground truth of a phantom.
#[derive(Clone, Debug)]
pub struct Truth {
    /// Per tooth, keyed by FDI.
    pub teeth: BTreeMap<u8, ToothTruth>,
    /// World → IOS frame (applied after the drift).
    pub world_to_ios: Rigid,
    /// World → CBCT frame.
    pub world_to_cbct: Rigid,
}

/// A generated jaw: what a host would hand us, plus the truth.
#[derive(Clone, Debug)]
pub struct Phantom {
    /// Upper or lower.
    pub jaw: Jaw,
    /// The IOS jaw mesh in the IOS frame, per-vertex labels (FDI; 0 = gingiva).
    pub ios: LabeledMesh,
    /// Closed CBCT tooth meshes in the CBCT frame, keyed by FDI.
    pub cbct: BTreeMap<u8, TriMesh>,
    /// Ground truth.
    pub truth: Truth,
}

impl ToothTruth {
    /// Target registration error of an estimated CBCT→IOS mapping: the RMS, over the true tooth
    /// surface vertices (crown and root) expressed in the CBCT frame, of the distance between the
    /// estimated and the true mapping of each point.
    pub fn tre(&self, world_to_cbct: &Rigid, estimated_cbct_to_ios: &Rigid) -> f64 {
        let n = self.surface.positions.len().max(1) as f64;
        let s: f64 = self
            .surface
            .positions
            .iter()
            .map(|&w| {
                let c = world_to_cbct.apply(w);
                (estimated_cbct_to_ios.apply(c) - self.cbct_to_ios.apply(c)).length_squared()
            })
            .sum();
        (s / n).sqrt()
    }
}

impl Phantom {
    /// Generates a phantom. Deterministic in `opts`.
    pub fn generate(opts: &PhantomOptions) -> Result<Phantom> {
        let _ = opts;
        Err(crate::Error::WrongState(
            "phantom generator not built yet".into(),
        ))
    }
}
