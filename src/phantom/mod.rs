//! The synthetic jaw ("phantom"): realistic IOS and CBCT meshes with known ground truth,
//! deterministic from a seed. Every accuracy claim of the project is measured on it.
//!
//! Frames: the true anatomy lives in a *world* frame (mm). The IOS jaw mesh is the world
//! anatomy moved per tooth by the scanner's cumulative stitching drift `ios_drift`, then by one
//! random rigid pose `world_to_ios`. The CBCT teeth are the world anatomy (degraded by the CBCT
//! simulation) moved by another random pose `world_to_cbct`. So the true per-tooth mapping from
//! the CBCT frame to the IOS frame is `world_to_ios ∘ ios_drift ∘ world_to_cbct⁻¹`.
//!
//! # How it is made
//! - **Teeth** (`shape`): per type (incisor, canine, premolar, molar; upper/lower) an implicit
//!   solid: superellipse crown cross-section with cervical constriction and height of contour,
//!   an occlusal height field with Gaussian cusps (1 canine, 2 premolar, 4 upper / 5 lower molar)
//!   and fissure grooves, rounded edges, 1–3 tapered elliptic roots 12–17 mm long joined by
//!   smooth unions. Mesiodistal widths 5.5–10.5 mm, sizes varied ±4 %.
//! - **Arch** (`layout`): parabolic arch (upper wider than lower), per-type torque and tip plus
//!   random ±1.5–2°, each neighbour moved along the arch until the contact gap is 0.05–0.15 mm.
//! - **Meshing** (`grid`, `surface_nets`): coarse-to-fine sampling (blocks proven sign-constant
//!   by a Lipschitz bound are interpolated), a well-composedness repair (no ambiguous face or
//!   cube configuration), then surface nets: closed, oriented, 2-manifold by construction; the
//!   largest component is kept and vertices are projected onto the implicit surface.
//! - **IOS** (`ios`, `gingiva`, `crown_topology`): one surface-nets mesh (0.18 mm grid) of the
//!   union of the drifted crowns and a gingiva height field that meets each tooth at its
//!   scalloped margin (1.3–1.9 mm below the height of contour buccally, ~1.2 mm higher
//!   interproximally: papillae) and falls off into a ridge; cropped open; per-vertex labels with
//!   a ±0.25 mm label bleed along the margin; interproximal notches (0.55–0.9 mm radius, from
//!   above the contact down into the papilla) where the scanner misses the contact; optional
//!   holes ([`IosRealism::holes`], off by default); a repair pass makes every crown an open disk
//!   (one component, manifold, one boundary loop); clamped Gaussian noise σ = 0.01 mm.
//! - **Rough exports** (`rough`, [`IosExport`], [`IosRoughness`]; off by default, the clean scan
//!   above is unchanged bit for bit): what other scanners and segmentation tools deliver. Surface
//!   nets with marching-cubes-like slivers (each vertex pulled 70 % of the way to its cell's edge
//!   crossing nearest a grid corner, quads split along the longer diagonal), no relaxation, no
//!   crown cleaning; holes through crowns and notches (0.3–0.5 mm) across the margin; crowns
//!   made disks, then a segmentation tool's label noise on top: tooth-labelled islands in the
//!   gingiva 0.5–1 mm off a crown and gingiva-labelled holes inside crowns; isotropic noise
//!   σ = 0.02 mm (0.014 at 2x density, 0.01 at 4x) that folds the slivers; the label boundary
//!   clipped through the triangles (each edge between differently labelled vertices cut where
//!   the labelling level crosses zero, clamped to 1–99 % of the edge, a new vertex with the
//!   tooth's label: crowns end on the cut curve with slivers along it); `coarse` (0.45 mm grid),
//!   `dense2`/`dense4` (2x/4x the vertices), `subdivided` (dense2 then one midpoint
//!   subdivision). Only the IOS changes: CBCT, transforms and true surfaces are the clean jaw's.
//! - **Drift** (`drift`): from a random distal end, each tooth adds a persistent-plus-noise rigid
//!   increment about its crown centre: ~0.4–0.6° and ~0.15–0.25 mm at the far end
//!   ([`Variant::HeavyDrift`]: 4×).
//! - **CBCT** (`cbct`): per tooth a 0.3 mm voxel grid in the CBCT frame, partial-volume
//!   occupancy, correlated noise, Gaussian blur σ = 0.4 mm, segmentation with a per-tooth
//!   threshold bias (inflate/shrink 0.1–0.25 mm), split from touching neighbours along a plane
//!   (both flattened), surface nets, smooth low-frequency distortion (~0.25 mm amplitude);
//!   [`Variant::MetalArtefact`]: one posterior crown bloated by 0.5–0.9 mm with 5–7 streak
//!   spikes of 1.2–2.2 mm.
//! - **Real anatomy** (`real`): with [`PhantomOptions::anatomy`], real closed tooth meshes are
//!   the truth (kept in the caller's frame); long axis by PCA oriented to the wider crown end,
//!   margin from the cross-section profile; a sampled signed distance replaces the implicit.
//! - **Voxelized** ([`voxelize`]): closed tooth meshes (e.g. [`Phantom::cbct`]) as a label
//!   volume with known truth (per-tooth FDI labels, or one class for every tooth as
//!   DentalSegmentator writes them), on an axis-aligned or oblique grid.
//!
//! # Measured (seeds 1–4, full arch, both jaws, release build)
//! - IOS: 191k–201k vertices (380k–399k faces), crowns 4.6k–11.2k vertices each, mean crown
//!   edge 0.165 mm; crown vertices mapped back by `(world_to_ios ∘ ios_drift)⁻¹` lie on the true
//!   surface: median 0.0075 mm, 90 % quantile ≤ 0.019 mm (the rest is label bleed onto gingiva).
//!   The true margin ([`ToothTruth::margin`]) is where the simulated gingiva meets the tooth;
//!   the IOS crown boundary lies 0.36–0.41 mm (mean) from it (label bleed, polyline spacing),
//!   up to 3.5 mm where a notch reaches up to the contact.
//! - CBCT: 3.7k–10.3k vertices per tooth; deviation from the true surface over a jaw
//!   RMS 0.20–0.24 mm, mean 0.17–0.20 mm, max 0.64–0.79 mm; per tooth RMS 0.11–0.37 mm.
//! - Truth surfaces: 5.8k–14.3k vertices per tooth (0.25 mm surface nets).
//! - Drift at the far end: 0.42–0.52°, 0.15–0.18 mm (crown centroid shift).
//! - Time: ~3.9 s CPU per full jaw in release, single-threaded (criterion `benches/phantom.rs`
//!   measured 9.7 s upper / 7.8 s lower wall time while the 2-core machine ran at load ~7).
//! - Real anatomy (Open-Full-Jaw p26 mandible, 14 teeth): CBCT RMS 0.21 mm, max 0.70 mm;
//!   IOS 180k vertices.
//! - Rough exports (`cargo run --release --example ios_roughness -- 1 upper full`, seed 1 upper
//!   full arch; per jaw: IOS vertices, mean crown edge, crown faces with a corner under 5°,
//!   crossing crown face pairs by the exact test, crowns with >1 component / >1 boundary loop):
//!   clean 200.6k, 0.161 mm, 0.0 %, 0, 0 / 0; rough 207.5k, 0.197 mm, 6.9 %, 15 672, 4 / 11;
//!   coarse 35.1k, 0.46 mm, 7.7 %, 397, 4 / 10; dense2 411.9k, 0.140 mm, 6.7 %, 28 241, 5 / 13;
//!   dense4 822.8k, 0.100 mm, 6.5 %, 56 944, 6 / 11; subdivided 1.64M, 0.070 mm, 6.7 %,
//!   75 874, 5 / 13 (seed 2 lower: the same within a few %, but 0 coarse crowns with islands).
//!   The foreign jaws (`../shared/data/foreign`, same measure): 316k / 275k vertices, 0.120 mm,
//!   3.1 %, 15 603 / 13 421 crossing pairs, 0 / 0. Generation CPU (`toothfuse demo --seed 1
//!   --ios-export E`, user time): clean 4.2 s, rough 3.5 s (no relaxation, no crown cleaning),
//!   coarse 1.6 s, dense2 5.8 s, dense4 10.9 s, subdivided 6.1 s.

mod cache;
mod cbct;
mod crown_clean;
mod crown_topology;
mod drift;
mod generate;
mod gingiva;
mod grid;
mod grid_fill;
mod ios;
mod layout;
mod project;
mod real;
mod relax;
pub mod rng;
mod rough;
mod shape;
mod surface_nets;
mod voxelize;

pub use cache::CACHE_ENV;
pub use cbct::CbctRealism;
pub use grid::Grid;
pub use ios::IosRealism;
pub use rough::{IosExport, IosRoughness};
pub use surface_nets::{extract_closed, largest_component, surface_nets};
pub use voxelize::{VoxelizeOptions, voxelize};

use crate::arch::Jaw;
use crate::mesh::{LabeledMesh, TriMesh};
use crate::{Result, Rigid};
use glam::DVec3;
use std::collections::BTreeMap;

/// Artefact amounts of the simulated modalities (realistic by default).
#[derive(Clone, Debug, PartialEq)]
pub struct Realism {
    /// IOS artefacts.
    pub ios: IosRealism,
    /// CBCT artefacts.
    pub cbct: CbctRealism,
    /// Scale of the IOS stitching drift (1 = ~0.5° and ~0.2 mm at the far end of the arch).
    pub drift_scale: f64,
    /// Extra drift factor of [`Variant::HeavyDrift`].
    pub heavy_drift_factor: f64,
    /// Surface-nets spacing of the true surfaces (mm).
    pub truth_spacing: f64,
}

impl Default for Realism {
    fn default() -> Self {
        Self {
            ios: IosRealism::default(),
            cbct: CbctRealism::default(),
            drift_scale: 1.0,
            heavy_drift_factor: 4.0,
            truth_spacing: 0.25,
        }
    }
}

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
    /// Artefact amounts.
    pub realism: Realism,
}

impl Default for PhantomOptions {
    fn default() -> Self {
        Self {
            seed: 1,
            jaw: Jaw::Upper,
            variant: Variant::Full,
            anatomy: None,
            realism: Realism::default(),
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
    /// Generates a phantom. Deterministic in `opts`. With the environment variable
    /// [`CACHE_ENV`] (`TOOTHFUSE_PHANTOM_CACHE`) naming a directory, a jaw made before from the
    /// same options by the same library source is read from there instead, bit for bit the
    /// generated one (the test command sets it so that its test executables share jaws).
    pub fn generate(opts: &PhantomOptions) -> Result<Phantom> {
        cache::cached(opts, || generate::generate(opts))
    }

    /// Generates a phantom, never reading nor writing the cache of [`Phantom::generate`].
    pub fn generate_uncached(opts: &PhantomOptions) -> Result<Phantom> {
        generate::generate(opts)
    }

    /// The IOS crowns split by vertex label (label 0, the gingiva, left out), IOS frame.
    pub fn ios_crowns(&self) -> BTreeMap<u8, TriMesh> {
        let Some(labels) = &self.ios.vertex_labels else {
            return BTreeMap::new();
        };
        crate::mesh::split_by_vertex_labels(&self.ios.mesh, labels)
            .map(|parts| {
                parts
                    .into_iter()
                    .filter(|(l, _)| *l > 0 && *l < 256)
                    .map(|(l, s)| (l as u8, s.mesh))
                    .collect()
            })
            .unwrap_or_default()
    }

    /// Teeth of the truth in arch order.
    pub fn teeth_in_arch_order(&self) -> Vec<u8> {
        crate::arch::arch_order(&self.truth.teeth.keys().copied().collect::<Vec<_>>())
    }
}
