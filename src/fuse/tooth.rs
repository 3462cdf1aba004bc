//! One tooth: IOS crown + CBCT tooth + their rigid transforms into the output frame → one closed,
//! manifold, outward-oriented mesh that holds every IOS crown vertex at exactly its transformed
//! position (paper section 2.3, Algorithm 1 line 2–7 for one tooth).

use super::quality::{self, ToothQuality};
use super::{FuseOptions, VertexSource};
use crate::cut::{self, RootCut, ToothFrame};
use crate::mesh::{EdgeTopology, RepairOptions, TriMesh, boundary_loops, repair_open_surface};
use crate::stitch::{self, BandLoops, BandVertex};
use crate::{Error, Result, Rigid};
use glam::DVec3;

/// A fused tooth.
#[derive(Clone, Debug)]
pub struct FusedTooth {
    /// FDI number.
    pub fdi: u8,
    /// The fused closed mesh, output frame. Vertices: first the (repaired) IOS crown's, then the
    /// band interior, then the CBCT root.
    pub mesh: TriMesh,
    /// Per vertex: [`VertexSource`] as `u8` (0 IOS, 1 band or fill, 2 CBCT).
    pub source: Vec<u8>,
    /// Per vertex of `mesh`: the index of the IOS crown input vertex it is (its position is
    /// bitwise `ios_to_output.apply(input)`), or `u32::MAX` for band, fill and CBCT vertices.
    pub ios_vertex: Vec<u32>,
    /// Faces of `mesh`: the crown's first (`0..band_faces.start`), then the band's
    /// (`band_faces`), then the root's.
    pub band_faces: std::ops::Range<usize>,
    /// Quality report.
    pub quality: ToothQuality,
    /// Warnings (filled holes, flipped input orientation, self-intersections).
    pub warnings: Vec<String>,
    /// Time (ms) spent in crown removal (repair, frame, cut: [`CutTooth::cut_ms`]) and in
    /// stitching (band, assembly, flips, quality report) for this tooth.
    pub cut_ms: f64,
    /// See [`FusedTooth::cut_ms`].
    pub stitch_ms: f64,
}

impl FusedTooth {
    /// Intersecting pairs of two kept IOS crown faces (exact test): the input crown's own
    /// crossings, kept as given. Counted on demand (an all-pairs check of the crown through a
    /// grid: ~10–20 ms for a crown of 15 000 faces), not during the fusion.
    pub fn ios_self_intersections(&self) -> usize {
        let crown = TriMesh::new(
            self.mesh.positions.clone(),
            self.mesh.triangles[..self.band_faces.start].to_vec(),
        );
        crate::mesh_check::self_intersections(&crown).len()
    }
}

/// A tooth after crown removal, before stitching ([`cut_tooth`] → [`stitch_tooth`]): the
/// repaired IOS crown and the cut CBCT root, both in the output frame, with everything the band
/// needs. Made only by [`cut_tooth`], so its loops always index its meshes.
#[derive(Clone, Debug)]
pub struct CutTooth {
    fdi: u8,
    crown: TriMesh,
    margin: Vec<u32>,
    crown_dirs: Vec<DVec3>,
    frame: ToothFrame,
    ios_vertex: Vec<u32>,
    kept_ios: usize,
    dropped: usize,
    holes_filled: usize,
    trimmed: super::fringe::FringeTrim,
    dist_in: Vec<f64>,
    root: RootCut,
    root_dirs: Vec<DVec3>,
    chords: Vec<(BandVertex, BandVertex)>,
    warnings: Vec<String>,
    cut_ms: f64,
}

impl CutTooth {
    /// FDI number.
    pub fn fdi(&self) -> u8 {
        self.fdi
    }

    /// The repaired IOS crown in the output frame, outward-oriented: an open disk whose one
    /// boundary loop is [`CutTooth::margin`]. It becomes the first vertices of the fused mesh.
    pub fn crown(&self) -> &TriMesh {
        &self.crown
    }

    /// The gingival margin: the crown's boundary loop (crown vertex indices, crown on the left
    /// seen from outside).
    pub fn margin(&self) -> &[u32] {
        &self.margin
    }

    /// Per crown vertex: the index of the IOS crown input vertex it is, or `u32::MAX` for a
    /// vertex added by the repair (hole fill).
    pub fn ios_vertex(&self) -> &[u32] {
        &self.ios_vertex
    }

    /// The tooth frame (axis root → crown) found from the margin.
    pub fn frame(&self) -> &ToothFrame {
        &self.frame
    }

    /// The cut: the CBCT root in the output frame (an open disk, CBCT positions under
    /// `cbct_to_output`), its vertices' CBCT input indices, its single boundary loop and the
    /// number of crown faces removed.
    pub fn root(&self) -> &RootCut {
        &self.root
    }

    /// The root's boundary loop (root vertex indices), where the band meets the root.
    pub fn cut_loop(&self) -> &[u32] {
        &self.root.cut_loop
    }

    /// IOS crown holes filled by the repair.
    pub fn holes_filled(&self) -> usize {
        self.holes_filled
    }

    /// Warnings of the cut stage (repair, flipped orientations, dropped vertices).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Time (ms) spent in this tooth's cut stage (repair, frame, cut, loop directions).
    pub fn cut_ms(&self) -> f64 {
        self.cut_ms
    }
}

/// Unit surface directions across a loop: `normal × tangent`, signed to point along `+axis`.
fn loop_dirs(mesh: &TriMesh, lp: &[u32], axis: DVec3) -> Vec<DVec3> {
    let normals = mesh.vertex_normals();
    let n = lp.len();
    (0..n)
        .map(|i| {
            let p = |k: usize| mesh.positions[lp[k] as usize];
            let t = (p((i + 1) % n) - p((i + n - 1) % n)).normalize_or_zero();
            let nv = normals[lp[i] as usize];
            let mut d = nv.cross(t).normalize_or_zero();
            if d.dot(axis) < 0.0 {
                d = -d;
            }
            if d == DVec3::ZERO { axis } else { d }
        })
        .collect()
}

/// Fuses one tooth. `ios_crown` (IOS frame) is an open crown whose longest boundary loop is the
/// gingival margin; it is repaired first ([`repair_open_surface`]: small holes filled, bow-ties
/// split, islands dropped). `cbct` (CBCT frame) must
/// be closed and manifold. Equals [`stitch_tooth`] of [`cut_tooth`], bit for bit.
pub fn fuse_tooth(
    fdi: u8,
    ios_crown: &TriMesh,
    cbct: &TriMesh,
    ios_to_output: &Rigid,
    cbct_to_output: &Rigid,
    opts: &FuseOptions,
) -> Result<FusedTooth> {
    let cut = cut_tooth(fdi, ios_crown, cbct, ios_to_output, cbct_to_output, opts)?;
    stitch_tooth(&cut, opts)
}

/// The crown-removal stage of [`fuse_tooth`] (paper section 2.3.1): repairs the IOS crown and
/// moves it into the output frame, finds its margin loop and the tooth frame, and cuts the CBCT
/// crown off along the margin (`opts.cut`), keeping the root. Errors name the tooth.
pub fn cut_tooth(
    fdi: u8,
    ios_crown: &TriMesh,
    cbct: &TriMesh,
    ios_to_output: &Rigid,
    cbct_to_output: &Rigid,
    opts: &FuseOptions,
) -> Result<CutTooth> {
    cut_inner(fdi, ios_crown, cbct, ios_to_output, cbct_to_output, opts)
        .map_err(|e| e.in_tooth(fdi))
}

fn cut_inner(
    fdi: u8,
    ios_crown: &TriMesh,
    cbct: &TriMesh,
    ios_to_output: &Rigid,
    cbct_to_output: &Rigid,
    opts: &FuseOptions,
) -> Result<CutTooth> {
    let t_start = std::time::Instant::now();
    let mut warnings = Vec::new();
    // Real crowns are messy: make the crown one oriented manifold disk, filling small holes
    // (every kept vertex keeps its exact position).
    let (repaired, rep_src, rep) = repair_open_surface(ios_crown, &RepairOptions::default());
    if !rep.is_clean() {
        warnings.push(format!("IOS crown repaired: {rep:?}"));
    }
    let mut crown = repaired.transformed(ios_to_output);
    let mut rep_src = rep_src;
    let mut trimmed = super::fringe::FringeTrim::default();
    let mut dist_in = Vec::new();
    if opts.fringe_reach_mm > 0.0 {
        let loops = boundary_loops(&crown);
        if loops.len() == 1 {
            let d = super::fringe::edge_distance(&crown, &loops[0], opts.fringe_reach_mm);
            dist_in = vec![f64::INFINITY; ios_crown.positions.len()];
            for (v, &s) in rep_src.iter().enumerate() {
                if s != u32::MAX {
                    dist_in[s as usize] = dist_in[s as usize].min(d[v]);
                }
            }
            if let Some((m, map, t)) = super::fringe::trim_fringe(
                &crown,
                &rep_src,
                &dist_in,
                opts.fringe_reach_mm,
                &[],
                false,
            ) {
                crown = m;
                rep_src = map;
                trimmed = t;
                warnings.push(format!(
                    "{} IOS crown vertices ({} faces) trimmed from the margin fringe (folded over other crown faces; at most {:.2} mm from the margin)",
                    t.vertices, t.faces, t.max_reach_mm
                ));
            }
        }
    }
    let mut root_in = cbct.transformed(cbct_to_output);
    if root_in.signed_volume() < 0.0 {
        root_in.flip();
        warnings.push("CBCT tooth was inward-oriented; flipped".into());
    }
    let loops = boundary_loops(&crown);
    if loops.len() != 1 {
        return Err(Error::InvalidArgument(format!(
            "IOS crown has {} boundary loops after repair; exactly one (the gingival margin) is needed",
            loops.len()
        )));
    }
    let mut margin = loops.into_iter().next().unwrap_or_default();
    let crown_centroid = crate::geom::centroid(&crown.positions).unwrap_or(DVec3::ZERO);
    let margin_pts: Vec<DVec3> = margin
        .iter()
        .map(|&v| crown.positions[v as usize])
        .collect();
    let mut frame = ToothFrame::from_margin(&margin_pts, crown_centroid)?;
    // The crown lies to the left of its margin seen from outside: counter-clockwise about the
    // axis. If not, the crown is inward-oriented: flip it (positions untouched).
    if stitch::param::winding(&frame, &margin_pts) < 0.0 {
        crown.flip();
        margin.reverse();
        warnings.push("IOS crown was inward-oriented; flipped".into());
    }
    let ios_vertex = rep_src;
    let kept_ios = ios_vertex.iter().filter(|&&s| s != u32::MAX).count();
    let dropped = ios_crown
        .positions
        .len()
        .saturating_sub(kept_ios + trimmed.vertices);
    if dropped > 0 {
        warnings.push(format!(
            "{dropped} IOS crown vertices dropped by the repair (islands, unused)"
        ));
    }
    // Crown removal.
    let margin_pts = margin_pts_of(&crown, &margin);
    let mut rc = cut::cut_crown(&root_in, &margin_pts, &frame, &opts.cut)?;
    // The margin's best-fit plane normal is the tooth axis where the margin is a ring around the
    // tooth; a narrow, deeply scalloped or ragged margin can tilt it far off, and then the cut
    // does not go around the tooth. Such a cut is made again about the CBCT tooth's long axis
    // when the two are more than `MAX_AXIS_TILT_DEG` apart (a tooth that cuts well keeps its
    // margin frame: a molar's long axis can lie across it).
    if !winds_once(&frame, &rc)
        && let Some((_, long)) = crate::geom::principal_axis(&root_in.positions)
    {
        let long = if long.dot(frame.axis) < 0.0 {
            -long
        } else {
            long
        };
        let tilt = frame.axis.angle_between(long).to_degrees();
        let long_frame = ToothFrame::new(frame.center, long);
        if tilt > MAX_AXIS_TILT_DEG
            && let Ok(r) = cut::cut_crown(&root_in, &margin_pts, &long_frame, &opts.cut)
            && winds_once(&long_frame, &r)
        {
            warnings.push(format!(
                "the margin's plane is tilted {tilt:.0}° from the CBCT tooth's long axis and the cut about it did not go around the tooth: cut about the long axis"
            ));
            frame = long_frame;
            rc = r;
        }
    }
    let crown_dirs = loop_dirs(&crown, &margin, frame.axis);
    let root_dirs = loop_dirs(&rc.root, &rc.cut_loop, frame.axis);
    let chords = loop_chords(&crown, &margin, BandVertex::Upper)
        .into_iter()
        .chain(loop_chords(&rc.root, &rc.cut_loop, BandVertex::Lower))
        .collect::<Vec<_>>();
    let cut_ms = t_start.elapsed().as_secs_f64() * 1e3;
    Ok(CutTooth {
        fdi,
        crown,
        margin,
        crown_dirs,
        frame,
        ios_vertex,
        kept_ios,
        dropped,
        holes_filled: rep.filled_holes,
        trimmed,
        dist_in,
        root: rc,
        root_dirs,
        chords,
        warnings,
        cut_ms,
    })
}

/// The stitching stage of [`fuse_tooth`] (paper Algorithm 1): builds the band between the
/// crown's margin loop and the root's cut loop (`opts.stitch`), assembles crown + band + root
/// into one closed mesh, optimises the band and measures the quality. `opts.cut` is not used (the
/// cut is done). Errors name the tooth.
pub fn stitch_tooth(cut: &CutTooth, opts: &FuseOptions) -> Result<FusedTooth> {
    stitch_inner(cut, opts).map_err(|e| e.in_tooth(cut.fdi))
}

/// The crown side of the band: the (possibly trimmed) crown, its margin, the directions across
/// the margin, the crown's chords and its vertices' IOS input indices.
struct CrownSide {
    crown: TriMesh,
    margin: Vec<u32>,
    dirs: Vec<DVec3>,
    chords: Vec<(BandVertex, BandVertex)>,
    ios_vertex: Vec<u32>,
}

/// Crown + band + root of one attempt, with what the untangling left.
struct Assembled {
    mesh: TriMesh,
    source: Vec<u8>,
    ios_vertex: Vec<u32>,
    band: std::ops::Range<usize>,
    untangle: Option<super::untangle::UntangleReport>,
}

/// Crown faces (indices below `band.start`) to trim for the crossing pairs the untangling left:
/// the crown faces in a pair, or with `ring` those and every crown face sharing a vertex with
/// one (where trimming the faces alone has not cleared the band, it mostly crosses their
/// neighbours next); when no pair has a crown face (band with band or root), the crown faces at
/// the margin vertices of its band faces, so that the margin there moves and the band is laid
/// out anew.
fn crown_faces_hit(a: &Assembled, crown_vertices: usize, ring: bool) -> Vec<u32> {
    let Some(u) = &a.untangle else {
        return Vec::new();
    };
    let is_crown = |f: u32| (f as usize) < a.band.start;
    let corners = |f: u32| a.mesh.triangles[f as usize].into_iter();
    let mut hit: Vec<u32> = u
        .crossing_pairs
        .iter()
        .flat_map(|&(f, g)| [f, g])
        .filter(|&f| is_crown(f))
        .collect();
    if !ring && !hit.is_empty() {
        hit.sort_unstable();
        hit.dedup();
        return hit;
    }
    let mut at: Vec<u32> = hit.into_iter().flat_map(corners).collect();
    if at.is_empty() {
        at = u
            .crossing_pairs
            .iter()
            .flat_map(|&(f, g)| [f, g])
            .filter(|&f| a.band.contains(&(f as usize)))
            .flat_map(corners)
            .filter(|&x| (x as usize) < crown_vertices)
            .collect();
    }
    at.sort_unstable();
    at.dedup();
    if at.is_empty() {
        return Vec::new();
    }
    (0..a.band.start as u32)
        .filter(|&f| corners(f).any(|x| at.binary_search(&x).is_ok()))
        .collect()
}

fn stitch_inner(ct: &CutTooth, opts: &FuseOptions) -> Result<FusedTooth> {
    let t_start = std::time::Instant::now();
    let mut warnings = ct.warnings.clone();
    let mut side = CrownSide {
        crown: ct.crown.clone(),
        margin: ct.margin.clone(),
        dirs: ct.crown_dirs.clone(),
        chords: ct
            .chords
            .iter()
            .copied()
            .filter(|c| matches!(c.0, BandVertex::Upper(_)))
            .collect(),
        ios_vertex: ct.ios_vertex.clone(),
    };
    let mut trimmed = ct.trimmed;
    // Where the band cannot clear a crown face within the fringe, that face goes (with the faces
    // between it and the margin) and the band is built again on the new margin. Of the attempts,
    // the one with the fewest crossings left is kept (the earliest, least trimmed, on a tie).
    let mut best: Option<(Assembled, super::fringe::FringeTrim)> = None;
    for attempt in 1..=6 {
        let a = assemble(ct, &side, opts)?;
        let hits = if crossings_left(&a) > 0 {
            crown_faces_hit(&a, side.crown.positions.len(), attempt > 2)
        } else {
            Vec::new()
        };
        if best
            .as_ref()
            .is_none_or(|(b, _)| crossings_left(&a) < crossings_left(b))
        {
            best = Some((a, trimmed));
        }
        if hits.is_empty() || opts.fringe_reach_mm <= 0.0 || attempt == 6 {
            break;
        }
        // Only where nothing within the reach can go: a crossed face whose apex lies beyond it.
        let trim = |listed_apex| {
            super::fringe::trim_fringe(
                &side.crown,
                &side.ios_vertex,
                &ct.dist_in,
                opts.fringe_reach_mm,
                &hits,
                listed_apex,
            )
        };
        let Some((crown, map, t)) = trim(false).or_else(|| trim(true)) else {
            break;
        };
        let margin = boundary_loops(&crown)
            .into_iter()
            .next()
            .unwrap_or_default();
        trimmed.faces += t.faces;
        trimmed.vertices += t.vertices;
        trimmed.max_reach_mm = trimmed.max_reach_mm.max(t.max_reach_mm);
        trimmed.rounds += t.rounds;
        side = CrownSide {
            dirs: loop_dirs(&crown, &margin, ct.frame.axis),
            chords: loop_chords(&crown, &margin, BandVertex::Upper),
            crown,
            margin,
            ios_vertex: map,
        };
    }
    let (a, trimmed) = best.expect("at least one attempt");
    if trimmed.vertices > ct.trimmed.vertices {
        warnings.push(format!(
            "{} more IOS crown vertices trimmed from the margin fringe (crossed by the band)",
            trimmed.vertices - ct.trimmed.vertices
        ));
    }
    let band_crossings_left = crossings_left(&a);
    if let Some(u) = a.untangle.as_ref().filter(|u| u.crossings_after > 0) {
        warnings.push(format!(
            "{} intersecting face pairs with a band face left after untangling ({} before{})",
            u.crossings_after,
            u.crossings_before,
            if u.budget_spent {
                "; its bounded work spent"
            } else {
                ""
            }
        ));
    }
    let Assembled {
        mesh,
        source,
        ios_vertex,
        band,
        ..
    } = a;
    let (band_start, band_end) = (band.start, band.end);
    let rc = &ct.root;
    let mut q = quality::measure(&mesh, band_start..band_end, opts.check_self_intersections);
    // The band rebuilds may have trimmed more of the fringe than the cut did.
    q.crown_vertices = ct
        .kept_ios
        .saturating_sub(trimmed.vertices - ct.trimmed.vertices);
    q.holes_filled = ct.holes_filled;
    q.ios_vertices_trimmed = trimmed.vertices;
    q.ios_trim_reach_mm = trimmed.max_reach_mm;
    q.ios_vertices_dropped = ct.dropped;
    q.cbct_faces_removed = rc.removed_faces;
    q.band_crossings_left = band_crossings_left;
    if !(q.closed && q.manifold && q.components == 1) {
        let topo = EdgeTopology::new(&mesh);
        let bad: Vec<String> = topo
            .undirected_edges()
            .into_iter()
            .filter(|&(a, b, c)| c != 2 || topo.faces_of_directed(a, b).count() != 1)
            .take(4)
            .map(|(a, b, c)| {
                format!(
                    "({a}:{}, {b}:{}) x{c}",
                    source[a as usize], source[b as usize]
                )
            })
            .collect();
        return Err(Error::InvalidArgument(format!(
            "fused mesh is not a closed 2-manifold ({} boundary edges, {} non-manifold edges, {} non-manifold vertices, {} components; edges {bad:?})",
            q.boundary_edges, q.non_manifold_edges, q.non_manifold_vertices, q.components
        )));
    }
    if let Some(n) = q.self_intersections.filter(|&n| n > 0) {
        warnings.push(format!("{n} intersecting face pairs"));
    }
    let stitch_ms = t_start.elapsed().as_secs_f64() * 1e3;
    Ok(FusedTooth {
        fdi: ct.fdi,
        mesh,
        source,
        ios_vertex,
        band_faces: band_start..band_end,
        quality: q,
        warnings,
        cut_ms: ct.cut_ms,
        stitch_ms,
    })
}

/// Largest angle (degrees) between the margin plane's normal and the CBCT tooth's long axis
/// for the normal to be the tooth axis.
const MAX_AXIS_TILT_DEG: f64 = 45.0;

/// Whether the root's cut loop goes once around the tooth axis (either way), as the band needs.
fn winds_once(frame: &ToothFrame, rc: &RootCut) -> bool {
    let w = stitch::param::winding(frame, &margin_pts_of(&rc.root, &rc.cut_loop));
    stitch::param::once_around(w).is_some()
}

/// Intersecting face pairs with a band face the untangling left (0 without untangling).
fn crossings_left(a: &Assembled) -> usize {
    a.untangle.as_ref().map_or(0, |u| u.crossings_after)
}

fn margin_pts_of(mesh: &TriMesh, margin: &[u32]) -> Vec<DVec3> {
    margin.iter().map(|&v| mesh.positions[v as usize]).collect()
}

/// Mesh edges joining two non-consecutive vertices of loop `lp`, as loop positions.
fn loop_chords(
    mesh: &TriMesh,
    lp: &[u32],
    wrap: fn(u32) -> BandVertex,
) -> Vec<(BandVertex, BandVertex)> {
    let mut pos = vec![u32::MAX; mesh.positions.len()];
    for (k, &v) in lp.iter().enumerate() {
        pos[v as usize] = k as u32;
    }
    let n = lp.len() as u32;
    let mut out = Vec::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (pos[t[k] as usize], pos[t[(k + 1) % 3] as usize]);
            if a == u32::MAX || b == u32::MAX || a > b {
                continue;
            }
            if b - a != 1 && !(a == 0 && b == n - 1) {
                out.push((wrap(a), wrap(b)));
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Builds the band between `side`'s margin and the root's cut loop, assembles crown + band +
/// root, and optimises and untangles the band (as `opts.stitch` says).
fn assemble(ct: &CutTooth, side: &CrownSide, opts: &FuseOptions) -> Result<Assembled> {
    let (margin, frame, rc) = (&side.margin, &ct.frame, &ct.root);
    let mut mesh = side.crown.clone();
    let mut ios_vertex = side.ios_vertex.clone();
    let mut source: Vec<u8> = ios_vertex
        .iter()
        .map(|&s| {
            if s == u32::MAX {
                VertexSource::Band as u8
            } else {
                VertexSource::Ios as u8
            }
        })
        .collect();
    let lower_pts = margin_pts_of(&rc.root, &rc.cut_loop);
    let upper_pts = margin_pts_of(&mesh, margin);
    let chords: Vec<(BandVertex, BandVertex)> = side
        .chords
        .iter()
        .copied()
        .chain(
            ct.chords
                .iter()
                .copied()
                .filter(|c| matches!(c.0, BandVertex::Lower(_))),
        )
        .collect();
    let band = stitch::build_band(
        &BandLoops {
            upper: &upper_pts,
            upper_dir: &side.dirs,
            lower: &lower_pts,
            lower_dir: &ct.root_dirs,
            chords: &chords,
        },
        frame,
        &opts.stitch,
    )?;
    // Assemble: band interior, then root.
    let band_off = mesh.positions.len() as u32;
    mesh.positions.extend_from_slice(&band.points);
    ios_vertex.resize(mesh.positions.len() + rc.root.positions.len(), u32::MAX);
    source.extend(std::iter::repeat_n(
        VertexSource::Band as u8,
        band.points.len(),
    ));
    let root_off = mesh.positions.len() as u32;
    mesh.positions.extend_from_slice(&rc.root.positions);
    source.extend(std::iter::repeat_n(
        VertexSource::Cbct as u8,
        rc.root.positions.len(),
    ));
    let map = |b: BandVertex| match b {
        BandVertex::Upper(i) => margin[i as usize],
        BandVertex::Lower(i) => rc.cut_loop[i as usize] + root_off,
        BandVertex::Interior(i) => i + band_off,
    };
    let mut band_tris: Vec<[u32; 3]> = band.triangles.iter().map(|t| t.map(map)).collect();
    // Orient the band against the crown: the crown holds margin[0] → margin[1].
    let (m0, m1) = (margin[0], margin[1 % margin.len()]);
    debug_assert!(
        EdgeTopology::new(&mesh)
            .faces_of_directed(m0, m1)
            .next()
            .is_some()
    );
    let band_has = |a: u32, b: u32, tris: &[[u32; 3]]| {
        tris.iter()
            .any(|t| (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b))
    };
    if band_has(m0, m1, &band_tris) {
        for t in &mut band_tris {
            t.swap(1, 2);
        }
    }
    let band_start = mesh.triangles.len();
    mesh.triangles.extend_from_slice(&band_tris);
    let band_end = mesh.triangles.len();
    let (c0, c1) = (rc.cut_loop[0] + root_off, rc.cut_loop[1] + root_off);
    if band_has(c0, c1, &band_tris) {
        return Err(Error::InvalidArgument(
            "CBCT root and IOS crown have opposite orientations after the cut".into(),
        ));
    }
    mesh.triangles
        .extend(rc.root.triangles.iter().map(|t| t.map(|v| v + root_off)));
    if opts.stitch.optimize {
        super::band_opt::optimize_band(&mut mesh, band_start..band_end, band_off..root_off);
    } else if opts.stitch.flips {
        super::band_opt::flip_band(&mut mesh, band_start..band_end, 6);
    } else {
        super::band_opt::fix_degenerate_band(&mut mesh, band_start..band_end);
    }
    let untangle = opts.stitch.untangle.then(|| {
        super::untangle::untangle_band(&mut mesh, band_start..band_end, band_off..root_off, 5.0)
    });
    Ok(Assembled {
        mesh,
        source,
        ios_vertex,
        band: band_start..band_end,
        untangle,
    })
}
