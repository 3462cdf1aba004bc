//! The band's triangulation: a constrained Delaunay triangulation (spade) of the annulus between
//! the two loop polygons in a plane, with the interior points inserted; the triangles between
//! the polygons are the band's.

use super::polygon::Polygon;
use super::{Band, BandLoops, BandVertex};
use crate::{Error, Result};
use glam::DVec3;
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

/// Constrained Delaunay triangulation of the annulus between the polygons `up_xy` (outer,
/// counter-clockwise) and `lo_xy` (inner, counter-clockwise), with interior points
/// `(plane position, 3D position, minimum plane distance to the loops)`; keeps the triangles
/// between the polygons. `uo`/`lo` map polygon order back to the caller's loop indices. Also
/// returns, per band point, its plane position and the index of the `interior` entry it is
/// (`None`: a chord split).
pub(super) fn triangulate(
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
pub(super) type PointOrigin = ([f64; 2], Option<u32>);

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
