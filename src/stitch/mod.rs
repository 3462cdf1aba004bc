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

pub mod chart;
mod chart_band;
pub mod chart_sample;
pub mod interp;
pub mod param;
mod polygon;

use crate::cut::ToothFrame;
use crate::{Error, Result};
use glam::DVec3;
use interp::{InterpOptions, ParamPoint};
use param::{Loft, LoopParam};
use polygon::Polygon;
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

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

/// Builds the band between the two loops. Its boundary is exactly the two loops.
pub fn build_band(loops: &BandLoops, frame: &ToothFrame, opts: &StitchOptions) -> Result<Band> {
    let (nu, nl) = (loops.upper.len(), loops.lower.len());
    if nu < 3 || nl < 3 || loops.upper_dir.len() != nu || loops.lower_dir.len() != nl {
        return Err(Error::InvalidArgument(
            "band loops need ≥ 3 vertices and one direction per vertex".into(),
        ));
    }
    // Orient both loops counter-clockwise about the axis; remember the original indices.
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
    let pick = |src: &[DVec3], o: &[u32]| o.iter().map(|&i| src[i as usize]).collect::<Vec<_>>();
    let (up_pts, lo_pts) = (pick(loops.upper, &uo), pick(loops.lower, &lo));
    let (up_dirs, lo_dirs) = (pick(loops.upper_dir, &uo), pick(loops.lower_dir, &lo));
    let loft = || {
        loft_band(
            loops,
            frame,
            opts,
            [&uo, &lo],
            [&up_pts, &lo_pts],
            [&up_dirs, &lo_dirs],
        )
    };
    if opts.points == PointGeneration::Chart {
        let ordered = chart_band::OrderedLoops {
            uo: &uo,
            lo: &lo,
            up_pts: &up_pts,
            lo_pts: &lo_pts,
            up_dirs: &up_dirs,
            lo_dirs: &lo_dirs,
        };
        // Where the loops do not chart as one simple annulus: the loft rings. Where the chart's
        // lift folds the band over (an inward offset beyond the reference curve's radius of
        // curvature: deep interproximal notches of narrow incisors), the loft rings too, and
        // the band whose faces cross each other less is kept (the chart band on a tie).
        let Ok(chart) = chart_band::chart_band(loops, frame, opts, &ordered) else {
            return loft();
        };
        if chart.folded == 0 {
            return Ok(chart.band);
        }
        // A folded chart band that does not cross itself cannot be beaten: no loft is built.
        let chart_count = band_self_intersections(&chart.band, loops, usize::MAX);
        if chart_count == 0 {
            return Ok(chart.band);
        }
        return Ok(match loft() {
            // The loft usually crosses itself many times more than the folded chart band: its
            // count stops at the chart band's.
            Ok(b) if band_self_intersections(&b, loops, chart_count) < chart_count => b,
            _ => chart.band,
        });
    }
    loft()
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

/// The loft band: points on rings (or the paper's recursive interpolation) on a Hermite loft
/// between the smoothed loops, triangulated in a cylindrical plane. `order` = the loops' caller
/// indices counter-clockwise, `pts`/`dirs` the loops in that order.
fn loft_band(
    loops: &BandLoops,
    frame: &ToothFrame,
    opts: &StitchOptions,
    order: [&[u32]; 2],
    pts: [&[DVec3]; 2],
    dirs: [&[DVec3]; 2],
) -> Result<Band> {
    let (nu, nl) = (loops.upper.len(), loops.lower.len());
    let [uo, lo] = order;
    let [up_pts, lo_pts] = pts;
    let [up_dirs, lo_dirs] = dirs;
    // The loft (where our interior points live) runs between smoothed copies of the loops, so the
    // loops' vertex-level jaggedness does not leak into the interior.
    let upper = LoopParam::upper(smooth(up_pts, 8), smooth_dirs(up_dirs, 8))?;
    let lower =
        LoopParam::lower_aligned(smooth(lo_pts, 4), smooth_dirs(lo_dirs, 4), &upper, frame)?;
    let loft = Loft::new(upper, lower, opts.tangent_scale);
    let (interior, spacing): (Vec<ParamPoint>, Box<dyn Fn(f64) -> f64>) = match opts.points {
        PointGeneration::Rings | PointGeneration::Chart => {
            let (e_u, e_l) = (mean_edge(up_pts), mean_edge(lo_pts));
            (
                rings(&loft, e_u, e_l),
                Box::new(move |v: f64| e_l + (e_u - e_l) * v),
            )
        }
        PointGeneration::Recursive(io) => {
            let vox = io.voxel;
            (
                recursive(&loft, up_pts, lo_pts, &io),
                Box::new(move |_| vox),
            )
        }
    };
    // Every band vertex is placed in the plane by its own 3D position: angle about the axis,
    // and log of the height scaled by the mean radius (conformal for a cylinder), so planar
    // triangles that do not overlap are 3D triangles that do not overlap on a radial-graph band.
    let r_mean = 0.5 * (loft.upper.length + loft.lower.length) / std::f64::consts::TAU;
    let h0 = lo_pts
        .iter()
        .map(|&p| frame.height(p))
        .fold(f64::INFINITY, f64::min);
    let plane = |p: DVec3| -> [f64; 2] {
        let r = ((frame.height(p) - h0) / r_mean).exp();
        let a = frame.angle(p);
        [r * a.cos(), r * a.sin()]
    };
    let place = |p: &ParamPoint| -> ([f64; 2], f64) {
        let xy = plane(p.pos);
        let rho = (xy[0] * xy[0] + xy[1] * xy[1]).sqrt();
        (xy, 0.4 * spacing(p.v) * rho / r_mean)
    };
    let up_xy: Vec<[f64; 2]> = up_pts.iter().map(|&p| plane(p)).collect();
    let lo_xy: Vec<[f64; 2]> = lo_pts.iter().map(|&p| plane(p)).collect();
    let inner: Vec<([f64; 2], DVec3, f64)> = interior
        .iter()
        .map(|p| {
            let (xy, d) = place(p);
            (xy, p.pos, d)
        })
        .collect();
    match triangulate(&up_xy, &lo_xy, uo, lo, &inner, loops, 0.0) {
        Ok((b, _)) => Ok(b),
        Err(first) => {
            // Fallback when a loop folds back around the axis (the cylindrical projection is not
            // simple): loops on concentric circles by their turn parameter, interior points by
            // theirs. Always a valid annulus; the quality report checks the 3D result.
            let up_raw = LoopParam::upper(up_pts.to_vec(), vec![DVec3::Z; nu])?;
            let lo_raw =
                LoopParam::lower_aligned(lo_pts.to_vec(), vec![DVec3::Z; nl], &up_raw, frame)?;
            let up_xy: Vec<[f64; 2]> = up_raw.phi.iter().map(|&f| loft.plane(f, 1.0)).collect();
            let lo_xy: Vec<[f64; 2]> = lo_raw.phi.iter().map(|&f| loft.plane(f, 0.0)).collect();
            let inner: Vec<([f64; 2], DVec3, f64)> = interior
                .iter()
                .map(|p| {
                    let xy = loft.plane(p.phi, p.v);
                    let rho = (xy[0] * xy[0] + xy[1] * xy[1]).sqrt();
                    (xy, p.pos, 0.4 * spacing(p.v) * rho / r_mean)
                })
                .collect();
            triangulate(&up_xy, &lo_xy, uo, lo, &inner, loops, 0.0)
                .map(|(b, _)| b)
                .map_err(|e| Error::InvalidArgument(format!("{first}; annulus fallback: {e}")))
        }
    }
}

/// Constrained Delaunay triangulation of the annulus between the polygons `up_xy` (outer,
/// counter-clockwise) and `lo_xy` (inner, counter-clockwise), with interior points
/// `(plane position, 3D position, minimum plane distance to the loops)`; keeps the triangles
/// between the polygons. `uo`/`lo` map polygon order back to the caller's loop indices. Also
/// returns, per band point, its plane position and the index of the `interior` entry it is
/// (`None`: a chord split).
fn triangulate(
    up_xy: &[[f64; 2]],
    lo_xy: &[[f64; 2]],
    uo: &[u32],
    lo: &[u32],
    interior: &[([f64; 2], DVec3, f64)],
    loops: &BandLoops,
    refine_deg: f64,
) -> Result<(Band, Vec<PointOrigin>)> {
    loop_cdt(up_xy, lo_xy, uo, lo)?.fill(interior, loops, refine_deg)
}

/// The first half of [`triangulate`]: both loops inserted and their edges constrained. Fails,
/// before any interior point is made, where the loops do not bound an annulus in the plane.
pub(crate) struct LoopCdt<'a> {
    up_xy: &'a [[f64; 2]],
    lo_xy: &'a [[f64; 2]],
    uo: &'a [u32],
    lo: &'a [u32],
    cdt: Cdt,
    handle_to_vertex: Vec<Option<BandVertex>>,
    up_h: Vec<usize>,
    lo_h: Vec<usize>,
}

/// Inserts and constrains the loops of [`triangulate`].
pub(crate) fn loop_cdt<'a>(
    up_xy: &'a [[f64; 2]],
    lo_xy: &'a [[f64; 2]],
    uo: &'a [u32],
    lo: &'a [u32],
) -> Result<LoopCdt<'a>> {
    let (nu, nl) = (up_xy.len(), lo_xy.len());
    let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
        ConstrainedDelaunayTriangulation::new();
    let mut handle_to_vertex: Vec<Option<BandVertex>> = Vec::new();

    let mut up_h = Vec::with_capacity(nu);
    for (k, xy) in up_xy.iter().enumerate() {
        let h = cdt_insert(
            &mut cdt,
            &mut handle_to_vertex,
            *xy,
            BandVertex::Upper(uo[k]),
        )?
        .ok_or_else(|| {
            Error::InvalidArgument("margin loop vertices coincide in the band plane".into())
        })?;
        up_h.push(h);
    }
    let mut lo_h = Vec::with_capacity(nl);
    for (k, xy) in lo_xy.iter().enumerate() {
        let h = cdt_insert(
            &mut cdt,
            &mut handle_to_vertex,
            *xy,
            BandVertex::Lower(lo[k]),
        )?
        .ok_or_else(|| {
            Error::InvalidArgument("cut loop vertices coincide in the band plane".into())
        })?;
        lo_h.push(h);
    }
    let handles: Vec<spade::handles::FixedVertexHandle> = cdt.fixed_vertices().collect();
    for (ring, what) in [(&up_h, "margin"), (&lo_h, "cut")] {
        for i in 0..ring.len() {
            let (a, b) = (handles[ring[i]], handles[ring[(i + 1) % ring.len()]]);
            if !cdt.can_add_constraint(a, b) {
                return Err(Error::InvalidArgument(format!(
                    "{what} loop edge {i} crosses another loop edge around the tooth axis"
                )));
            }
            cdt.add_constraint(a, b);
        }
    }
    Ok(LoopCdt {
        up_xy,
        lo_xy,
        uo,
        lo,
        cdt,
        handle_to_vertex,
        up_h,
        lo_h,
    })
}

impl LoopCdt<'_> {
    /// The second half of [`triangulate`]: the interior points, the chord splits, the
    /// refinement and the band's faces.
    pub(crate) fn fill(
        self,
        interior: &[([f64; 2], DVec3, f64)],
        loops: &BandLoops,
        refine_deg: f64,
    ) -> Result<(Band, Vec<PointOrigin>)> {
        let LoopCdt {
            up_xy,
            lo_xy,
            uo,
            lo,
            mut cdt,
            mut handle_to_vertex,
            up_h,
            lo_h,
        } = self;
        let (nu, nl) = (up_xy.len(), lo_xy.len());
        let (up_poly, lo_poly) = (Polygon::new(up_xy), Polygon::new(lo_xy));
        let mut points = Vec::new();
        let mut origin = Vec::new();
        for (k, &(xy, pos, min_d)) in interior.iter().enumerate() {
            if !pos.is_finite() {
                continue;
            }
            // Strictly inside the annulus, and not closer to a loop than `min_d` (distances only
            // when asked for: the chart's points come with none).
            if !up_poly.contains(xy) || lo_poly.contains(xy) {
                continue;
            }
            if min_d > 0.0 && (up_poly.distance(xy) < min_d || lo_poly.distance(xy) < min_d) {
                continue;
            }
            if cdt_insert(
                &mut cdt,
                &mut handle_to_vertex,
                xy,
                BandVertex::Interior(points.len() as u32),
            )?
            .is_some()
            {
                points.push(pos);
                origin.push((xy, Some(k as u32)));
            }
        }
        // Chords: split any band edge that duplicates a crown/root chord with a point in its middle.
        let handle_of = |bv: BandVertex| -> Option<usize> {
            match bv {
                BandVertex::Upper(i) => uo.iter().position(|&x| x == i).map(|k| up_h[k]),
                BandVertex::Lower(i) => lo.iter().position(|&x| x == i).map(|k| lo_h[k]),
                BandVertex::Interior(_) => None,
            }
        };
        let pos3 = |bv: BandVertex| match bv {
            BandVertex::Upper(i) => loops.upper[i as usize],
            BandVertex::Lower(i) => loops.lower[i as usize],
            BandVertex::Interior(i) => points[i as usize],
        };
        let pending: Vec<(usize, usize, DVec3, DVec3)> = loops
            .chords
            .iter()
            .filter_map(|&(a, b)| Some((handle_of(a)?, handle_of(b)?, pos3(a), pos3(b))))
            .collect();
        // A chord edge is broken by a point at its middle; repeat while one survives (a middle
        // that coincides with an existing vertex).
        for _round in 0..4 {
            let vh: Vec<spade::handles::FixedVertexHandle> = cdt.fixed_vertices().collect();
            let mut split = false;
            for &(a, b, pa, pb) in &pending {
                if let Some(e) = cdt.get_edge_from_neighbors(vh[a], vh[b]) {
                    let [va, vb] = e.vertices();
                    let (qa, qb) = (va.position(), vb.position());
                    let mid = [0.5 * (qa.x + qb.x), 0.5 * (qa.y + qb.y)];
                    // Only band edges matter: an edge outside the annulus is no band edge.
                    if !up_poly.contains(mid) || lo_poly.contains(mid) {
                        continue;
                    }
                    if cdt_insert(
                        &mut cdt,
                        &mut handle_to_vertex,
                        mid,
                        BandVertex::Interior(points.len() as u32),
                    )?
                    .is_some()
                    {
                        points.push(0.5 * (pa + pb));
                        origin.push((mid, None));
                        split = true;
                    }
                }
            }
            if !split {
                break;
            }
        }
        if refine_deg > 0.0 {
            refine(
                &mut cdt,
                &mut handle_to_vertex,
                &mut points,
                &mut origin,
                [&up_poly, &lo_poly],
                refine_deg,
            );
        }
        let triangles: Vec<[BandVertex; 3]> =
            band_faces_ordered(&cdt, &up_h, &lo_h, &handle_to_vertex)?;
        // An annulus triangulation has exactly nu + nl + 2·interior triangles.
        let expected = nu + nl + 2 * points.len();
        if triangles.len() != expected {
            return Err(Error::InvalidArgument(format!(
                "band has {} triangles, an annulus with these vertices has {expected}",
                triangles.len()
            )));
        }
        Ok((Band { points, triangles }, origin))
    }
}

type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;

/// Delaunay refinement (Ruppert/Chew, spade's) of the band region to a minimum plane angle of
/// `deg`, keeping the loop edges whole; new points inside the annulus become band points (free,
/// at their plane position), points spade puts outside it are left out of the band.
fn refine(
    cdt: &mut Cdt,
    handle_to_vertex: &mut Vec<Option<BandVertex>>,
    points: &mut Vec<DVec3>,
    origin: &mut Vec<PointOrigin>,
    [up, lo]: [&Polygon; 2],
    deg: f64,
) {
    let before = cdt.num_vertices();
    let params = spade::RefinementParameters::<f64>::new()
        .exclude_outer_faces(true)
        .keep_constraint_edges()
        .with_angle_limit(spade::AngleLimit::from_deg(deg))
        .with_max_additional_vertices(before);
    cdt.refine(params);
    let vh: Vec<spade::handles::FixedVertexHandle> = cdt.fixed_vertices().collect();
    handle_to_vertex.resize(vh.len(), None);
    for h in &vh[before..] {
        let q = cdt.vertex(*h).position();
        let xy = [q.x, q.y];
        if up.contains(xy) && !lo.contains(xy) {
            handle_to_vertex[h.index()] = Some(BandVertex::Interior(points.len() as u32));
            points.push(DVec3::ZERO);
            origin.push((xy, None));
        }
    }
    // Band faces on three loop vertices (ears at concave margin corners, faces across narrow
    // bays) have no vertex that can move later: a point at their centroid (the insertion
    // re-legalises the chord).
    let loop_vertex = |v: spade::handles::VertexHandle<Point2<f64>, (), spade::CdtEdge<()>>| {
        matches!(
            handle_to_vertex.get(v.fix().index()).copied().flatten(),
            Some(BandVertex::Upper(_) | BandVertex::Lower(_))
        )
    };
    let centroids: Vec<[f64; 2]> = cdt
        .inner_faces()
        .filter(|f| f.vertices().iter().all(|&v| loop_vertex(v)))
        .map(|f| {
            let c = f.center();
            [c.x, c.y]
        })
        .filter(|&xy| up.contains(xy) && !lo.contains(xy))
        .collect();
    for xy in centroids {
        let bv = BandVertex::Interior(points.len() as u32);
        if let Ok(Some(_)) = cdt_insert(cdt, handle_to_vertex, xy, bv) {
            points.push(DVec3::ZERO);
            origin.push((xy, None));
        }
    }
}

/// Where a band point came from: its plane position and the index of the interior input point it
/// is (`None`: a chord split).
type PointOrigin = ([f64; 2], Option<u32>);

/// The triangles between the two loop polygons (counter-clockwise in the plane).
fn band_faces_ordered(
    cdt: &Cdt,
    up_h: &[usize],
    lo_h: &[usize],
    handle_to_vertex: &[Option<BandVertex>],
) -> Result<Vec<[BandVertex; 3]>> {
    // Every loop edge must have survived as a constraint edge.
    let vh: Vec<spade::handles::FixedVertexHandle> = cdt.fixed_vertices().collect();
    let mut seeds = Vec::new();
    for (ring, outer) in [(&up_h, true), (&lo_h, false)] {
        for i in 0..ring.len() {
            let (a, b) = (vh[ring[i]], vh[ring[(i + 1) % ring.len()]]);
            let e = cdt.get_edge_from_neighbors(a, b).ok_or_else(|| {
                Error::InvalidArgument("band triangulation lost a loop edge".into())
            })?;
            // Band side: inside the outer (margin) polygon, outside the inner (cut) polygon.
            let f = if outer { e.face() } else { e.rev().face() };
            let f = f.as_inner().ok_or_else(|| {
                Error::InvalidArgument("band triangulation: loop edge on the hull's outside".into())
            })?;
            seeds.push(f.fix());
        }
    }
    // Flood the band region from the seeds without crossing constraint edges.
    let nfaces = cdt.num_all_faces();
    let mut in_band = vec![false; nfaces];
    let mut stack = Vec::new();
    for s in seeds {
        if !in_band[s.index()] {
            in_band[s.index()] = true;
            stack.push(s);
        }
    }
    while let Some(f) = stack.pop() {
        for e in cdt.face(f).adjacent_edges() {
            if e.is_constraint_edge() {
                continue;
            }
            if let Some(g) = e.rev().face().as_inner() {
                let gi = g.fix().index();
                if !in_band[gi] {
                    in_band[gi] = true;
                    stack.push(g.fix());
                }
            } else {
                return Err(Error::InvalidArgument(
                    "band region leaks outside the margin loop".into(),
                ));
            }
        }
    }
    let mut triangles = Vec::new();
    for f in cdt.inner_faces() {
        if !in_band[f.fix().index()] {
            continue;
        }
        let vs = f.vertices();
        let t = vs.map(|v| handle_to_vertex[v.fix().index()]);
        match t {
            [Some(a), Some(b), Some(c)] => triangles.push([a, b, c]),
            _ => {
                return Err(Error::InvalidArgument(
                    "band triangulation vertex lost".into(),
                ));
            }
        }
    }
    Ok(triangles)
}

/// Ours: rings between the loops, spacing graded geometrically from the margin's mean edge
/// length (v = 1) to the cut's (v = 0), alternate rings shifted by half a step.
fn rings(loft: &Loft, e_u: f64, e_l: f64) -> Vec<ParamPoint> {
    let h = loft.mean_height;
    let row = 0.866; // equilateral row spacing
    let n = if (e_u - e_l).abs() < 1e-9 {
        (h / (row * e_u)).round()
    } else {
        (h / (row * (e_u - e_l)) * (e_u / e_l).ln()).round()
    }
    .max(1.0) as usize;
    let mut out = Vec::new();
    for k in 1..n {
        let (e, v) = if (e_u - e_l).abs() < 1e-9 {
            (e_u, 1.0 - k as f64 / n as f64)
        } else {
            let e = e_u * (e_l / e_u).powf(k as f64 / n as f64);
            (e, (e - e_l) / (e_u - e_l))
        };
        let len = loft.lower.length + (loft.upper.length - loft.lower.length) * v;
        let count = ((len / e).round() as usize).max(3);
        let shift = if k % 2 == 1 { 0.5 } else { 0.0 };
        for j in 0..count {
            let phi = loft.upper.phi[0] + (j as f64 + shift) / count as f64;
            out.push(ParamPoint {
                pos: loft.point(phi, v),
                phi,
                v,
            });
        }
    }
    out
}

/// Paper: Algorithm 1 between the two loops, then voxel downsampling; points near a loop vertex
/// (closer than half a voxel) are dropped so no sliver forms against the boundary.
fn recursive(loft: &Loft, up: &[DVec3], lo: &[DVec3], o: &InterpOptions) -> Vec<ParamPoint> {
    let a: Vec<ParamPoint> = (0..up.len())
        .map(|i| ParamPoint {
            pos: up[i],
            phi: loft.upper.phi[i],
            v: 1.0,
        })
        .collect();
    let b: Vec<ParamPoint> = (0..lo.len())
        .map(|i| ParamPoint {
            pos: lo[i],
            phi: loft.lower.phi[i],
            v: 0.0,
        })
        .collect();
    let pts = interp::gen_inter_points(&a, &b, o.neighbours, o.per_segment, o.depth);
    let pts = interp::voxel_downsample(&pts, o.voxel);
    let loop_pts: Vec<[f64; 3]> = a.iter().chain(b.iter()).map(|p| p.pos.to_array()).collect();
    let tree =
        kiddo::ImmutableKdTree::<f64, 3>::new_from_slice(&loop_pts).expect("kd-tree over loops");
    let min_d2 = (0.5 * o.voxel).powi(2);
    pts.into_iter()
        .filter(|p| {
            let r = tree
                .query(&p.pos.to_array())
                .nearest_one::<kiddo::SquaredEuclidean<f64>>()
                .execute();
            r.distance >= min_d2
        })
        .collect()
}

/// Mean edge length of a closed polyline.
fn mean_edge(p: &[DVec3]) -> f64 {
    (0..p.len())
        .map(|i| (p[(i + 1) % p.len()] - p[i]).length())
        .sum::<f64>()
        / p.len() as f64
}

/// `iters` passes of (1, 2, 1)/4 smoothing of a closed polyline.
fn smooth(p: &[DVec3], iters: usize) -> Vec<DVec3> {
    let n = p.len();
    let mut cur = p.to_vec();
    for _ in 0..iters {
        cur = (0..n)
            .map(|i| (cur[(i + n - 1) % n] + 2.0 * cur[i] + cur[(i + 1) % n]) * 0.25)
            .collect();
    }
    cur
}

fn smooth_dirs(d: &[DVec3], iters: usize) -> Vec<DVec3> {
    smooth(d, iters)
        .into_iter()
        .zip(d)
        .map(|(s, o)| {
            let u = s.normalize_or_zero();
            if u == DVec3::ZERO { *o } else { u }
        })
        .collect()
}

/// Inserts a plane point; `None` if it coincides with an existing vertex.
fn cdt_insert(
    cdt: &mut Cdt,
    handle_to_vertex: &mut Vec<Option<BandVertex>>,
    xy: [f64; 2],
    bv: BandVertex,
) -> Result<Option<usize>> {
    let h = cdt
        .insert(Point2::new(xy[0], xy[1]))
        .map_err(|e| Error::InvalidArgument(format!("band triangulation: {e:?}")))?;
    let i = h.index();
    if i < handle_to_vertex.len() {
        return Ok(None);
    }
    handle_to_vertex.resize(i + 1, None);
    handle_to_vertex[i] = Some(bv);
    Ok(Some(i))
}
