//! Stitching (paper section 2.3.2, Algorithm 1): the band that closes the gap between the IOS
//! margin loop and the CBCT cut loop.
//!
//! The band's two boundaries are exactly the two loops, vertex for vertex, so crown + band +
//! root is closed by construction. The band is parametrised as an annulus (`φ` around the tooth
//! × height fraction `v`, see [`param`]); its interior points come either from the paper's
//! recursive interpolation ([`interp`], Algorithm 1 lines 5–6 and 9–24) or from graded rings
//! (ours); they are triangulated with a constrained Delaunay triangulation (spade) in the
//! log-polar plane with both loops as constraint polygons — our replacement for the paper's
//! DELAUNAY3D (line 7), which cannot guarantee the boundaries.

mod cdt;
pub mod chart;
mod chart_band;
pub mod chart_sample;
pub mod interp;
mod loft_band;
pub mod param;
mod polygon;
mod polyline;

use crate::cut::ToothFrame;
use crate::{Error, Result};
use cdt::loop_cdt;
use glam::DVec3;
use interp::InterpOptions;
use loft_band::loft_band;
use polyline::{mean_edge, smooth, smooth_dirs};

/// The two loops to join, in the output frame.
#[derive(Clone, Copy, Debug)]
pub struct BandLoops<'a> {
    /// The IOS margin loop, ordered (either direction).
    pub upper: &'a [DVec3],
    /// Per upper vertex: unit tangent of the crown surface, across the loop, pointing from the
    /// margin into the crown.
    pub upper_dir: &'a [DVec3],
    /// The CBCT cut loop, ordered (either direction).
    pub lower: &'a [DVec3],
    /// Per lower vertex: unit tangent of the root surface, across the loop, pointing from the
    /// root toward the crown (out of the root).
    pub lower_dir: &'a [DVec3],
    /// Pairs of loop vertices already joined by a crown or root edge that is not a loop edge
    /// (a chord): the band must not use them as an edge too, or that edge would have 4 faces.
    pub chords: &'a [(BandVertex, BandVertex)],
}

/// Where the band's interior points come from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PointGeneration {
    /// Ours (default): graded Poisson-disk points in a flat chart of the tooth side, lifted as a
    /// radial graph (Hermite profile tangent to crown and root, harmonic fit to the loops); see
    /// [`chart`]. Falls back to [`PointGeneration::Rings`] where the loops do not chart simply.
    Chart,
    /// Ours (earlier): rings at heights graded from the margin's edge length to the cut's, points evenly
    /// spaced on each ring, placed on the Hermite loft.
    Rings,
    /// Paper: Algorithm 1 recursive interpolation and voxel downsampling; the points keep their
    /// generated positions.
    Recursive(InterpOptions),
}

/// Options of the stitching.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StitchOptions {
    /// Interior point generation.
    pub points: PointGeneration,
    /// Hermite tangent length as a fraction of the loop-to-loop distance (0: ruled band).
    pub tangent_scale: f64,
    /// After assembly, improve the band in place: min-angle edge flips between band faces and
    /// tangential relaxation of band-interior vertices (kept only if no intersection is added).
    /// Slow (exact intersection checks of the whole tooth); off by default.
    pub optimize: bool,
    /// After assembly, min-angle edge flips between band faces only (fast, no vertex moves).
    pub flips: bool,
    /// After the flips, move free band vertices of band faces that cross other faces or have
    /// an angle under 5° to better places in their star, each move checked exactly against the
    /// faces around it (`fuse::untangle`).
    pub untangle: bool,
}

impl Default for StitchOptions {
    fn default() -> Self {
        Self {
            points: PointGeneration::Chart,
            tangent_scale: 0.8,
            optimize: false,
            flips: true,
            untangle: true,
        }
    }
}

/// A vertex of the band.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum BandVertex {
    /// Index into [`BandLoops::upper`].
    Upper(u32),
    /// Index into [`BandLoops::lower`].
    Lower(u32),
    /// Index into [`Band::points`].
    Interior(u32),
}

/// The band: new interior points and triangles over loop and interior vertices. Triangles are
/// consistently oriented; [`Band::triangles`] may need flipping as a whole to match the crown.
#[derive(Clone, Debug, Default)]
pub struct Band {
    /// Interior points (new vertices).
    pub points: Vec<DVec3>,
    /// Triangles.
    pub triangles: Vec<[BandVertex; 3]>,
}

/// A band as [`build_band`] makes it.
#[derive(Clone, Debug, Default)]
pub struct BuiltBand {
    /// The band.
    pub band: Band,
    /// The chart's lift folded the band over in places (an inward offset beyond the reference
    /// curve's radius of curvature: deep interproximal notches of narrow incisors), so its
    /// faces may cross each other there; where they still do after the band is untangled, the
    /// loft band ([`less_crossed_loft`]) may cross itself less.
    pub folded: bool,
}

/// The loops ordered counter-clockwise about the axis: per loop, the original indices in that
/// order, and the points and directions so ordered.
struct Ordered {
    uo: Vec<u32>,
    lo: Vec<u32>,
    up_pts: Vec<DVec3>,
    lo_pts: Vec<DVec3>,
    up_dirs: Vec<DVec3>,
    lo_dirs: Vec<DVec3>,
}

impl Ordered {
    fn new(loops: &BandLoops, frame: &ToothFrame) -> Result<Ordered> {
        let (nu, nl) = (loops.upper.len(), loops.lower.len());
        if nu < 3 || nl < 3 || loops.upper_dir.len() != nu || loops.lower_dir.len() != nl {
            return Err(Error::InvalidArgument(
                "band loops need ≥ 3 vertices and one direction per vertex".into(),
            ));
        }
        let order = |pts: &[DVec3], what: &str| -> Result<Vec<u32>> {
            let w = param::winding(frame, pts);
            let n = pts.len() as u32;
            match param::once_around(w) {
                Some(true) => Ok((0..n).collect()),
                Some(false) => Ok((0..n).rev().collect()),
                None => Err(Error::InvalidArgument(format!(
                    "{what} loop winds {w:.2} times around the tooth axis, expected once"
                ))),
            }
        };
        let uo = order(loops.upper, "margin")?;
        let lo = order(loops.lower, "cut")?;
        let pick =
            |src: &[DVec3], o: &[u32]| o.iter().map(|&i| src[i as usize]).collect::<Vec<_>>();
        Ok(Ordered {
            up_pts: pick(loops.upper, &uo),
            lo_pts: pick(loops.lower, &lo),
            up_dirs: pick(loops.upper_dir, &uo),
            lo_dirs: pick(loops.lower_dir, &lo),
            uo,
            lo,
        })
    }

    fn loft(&self, loops: &BandLoops, frame: &ToothFrame, opts: &StitchOptions) -> Result<Band> {
        loft_band(
            loops,
            frame,
            opts,
            [&self.uo, &self.lo],
            [&self.up_pts, &self.lo_pts],
            [&self.up_dirs, &self.lo_dirs],
        )
    }
}

/// Builds the band between the two loops. Its boundary is exactly the two loops. With
/// [`PointGeneration::Chart`], the chart band, or the loft band where the loops do not chart as
/// one simple annulus; otherwise the loft band.
pub fn build_band(
    loops: &BandLoops,
    frame: &ToothFrame,
    opts: &StitchOptions,
) -> Result<BuiltBand> {
    let o = Ordered::new(loops, frame)?;
    if opts.points == PointGeneration::Chart {
        let ordered = chart_band::OrderedLoops {
            uo: &o.uo,
            lo: &o.lo,
            up_pts: &o.up_pts,
            lo_pts: &o.lo_pts,
            up_dirs: &o.up_dirs,
            lo_dirs: &o.lo_dirs,
        };
        if let Ok(chart) = chart_band::chart_band(loops, frame, opts, &ordered) {
            return Ok(BuiltBand {
                band: chart.band,
                folded: chart.folded > 0,
            });
        }
    }
    Ok(BuiltBand {
        band: o.loft(loops, frame, opts)?,
        folded: false,
    })
}

/// The loft band between the two loops (rings on a Hermite loft, or the paper's recursive
/// points with [`PointGeneration::Recursive`]) when its faces cross each other fewer times than
/// `chart`'s (a band between the same loops; exact test): the alternative to a folded chart
/// band ([`BuiltBand::folded`]). `None` when `chart` does not cross itself, when the loft
/// crosses itself as often or more (the usual case: its count stops at the chart band's), or
/// when it fails to build.
pub fn less_crossed_loft(
    loops: &BandLoops,
    frame: &ToothFrame,
    opts: &StitchOptions,
    chart: &Band,
) -> Option<Band> {
    let chart_count = band_self_intersections(chart, loops, usize::MAX);
    if chart_count == 0 {
        return None;
    }
    let loft = Ordered::new(loops, frame)
        .ok()?
        .loft(loops, frame, opts)
        .ok()?;
    (band_self_intersections(&loft, loops, chart_count) < chart_count).then_some(loft)
}

/// Pairs of band faces that intersect each other (exact test), counted up to `limit`: how
/// badly a band folds over.
fn band_self_intersections(band: &Band, loops: &BandLoops, limit: usize) -> usize {
    let (nu, nl) = (loops.upper.len() as u32, loops.lower.len() as u32);
    let positions: Vec<DVec3> = loops
        .upper
        .iter()
        .chain(loops.lower)
        .chain(&band.points)
        .copied()
        .collect();
    let index = |b: BandVertex| match b {
        BandVertex::Upper(i) => i,
        BandVertex::Lower(i) => nu + i,
        BandVertex::Interior(i) => nu + nl + i,
    };
    let mesh = crate::mesh::TriMesh::new(
        positions,
        band.triangles.iter().map(|t| t.map(index)).collect(),
    );
    crate::mesh_check::self_intersections_up_to(&mesh, limit)
}
