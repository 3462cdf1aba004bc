//! The stitching stage of one tooth: the band between the crown's margin and the root's cut
//! loop, crown + band + root assembled into one closed mesh, the band untangled, and where a
//! crossing the untangling cannot remove is left, the crown's fringe trimmed and the band built
//! again (the crossed crown faces: [`super::crossed`]), or, where the band crosses no crown
//! face, built with other tangent lengths; where crossings are left after the builds, the best
//! one is polished ([`super::polish`]).

use super::crossed::{crown_faces_hit, pierced_margin_faces};
use super::fringe::Listed;
use super::polish::polish;
use super::quality;
use super::tooth::{CutTooth, FusedTooth, loop_chords, loop_dirs, margin_pts_of};
use super::{FuseOptions, VertexSource};
use crate::mesh::{EdgeTopology, TriMesh, boundary_loops};
use crate::stitch::{self, BandLoops, BandVertex};
use crate::{Error, Result};
use glam::DVec3;

/// The stitching stage of [`fuse_tooth`](super::fuse_tooth) (paper Algorithm 1): builds the band between the
/// crown's margin loop and the root's cut loop (`opts.stitch`), assembles crown + band + root
/// into one closed mesh, optimises the band and measures the quality. `opts.cut` is not used (the
/// cut is done). Errors name the tooth.
pub fn stitch_tooth(cut: &CutTooth, opts: &FuseOptions) -> Result<FusedTooth> {
    stitch_inner(cut, opts).map_err(|e| e.in_tooth(cut.fdi))
}

/// The crown side of the band: the (possibly trimmed) crown, its margin, the directions across
/// the margin, the crown's chords and its vertices' IOS input indices.
#[derive(Clone)]
pub(super) struct CrownSide {
    /// The crown (its single boundary loop is the margin).
    pub(super) crown: TriMesh,
    pub(super) margin: Vec<u32>,
    pub(super) dirs: Vec<DVec3>,
    pub(super) chords: Vec<(BandVertex, BandVertex)>,
    pub(super) ios_vertex: Vec<u32>,
}

impl CrownSide {
    /// `ct` with this crown side as its crown: crown, margin, directions, the crown's chords
    /// (with the root's), IOS indices and `kept_ios` from this side, the rest as `ct` has it.
    pub(super) fn into_tooth(self, ct: &CutTooth) -> CutTooth {
        CutTooth {
            kept_ios: self.ios_vertex.iter().filter(|&&s| s != u32::MAX).count(),
            chords: self.chords.into_iter().chain(ct.root_chords()).collect(),
            crown: self.crown,
            margin: self.margin,
            crown_dirs: self.dirs,
            ios_vertex: self.ios_vertex,
            ..ct.clone()
        }
    }

    /// This crown's fringe trimmed for the `listed` faces ([`super::fringe::trim_fringe`]) by
    /// the first of `modes` that removes anything; `None` for an empty list or when none does.
    pub(super) fn trim(
        &self,
        ct: &CutTooth,
        reach: f64,
        listed: &[u32],
        modes: &[Listed],
    ) -> Option<(TriMesh, Vec<u32>, super::fringe::FringeTrim)> {
        if listed.is_empty() {
            return None;
        }
        modes.iter().find_map(|&mode| {
            super::fringe::trim_fringe(
                &self.crown,
                &self.ios_vertex,
                &ct.dist_in,
                reach,
                listed,
                mode,
            )
        })
    }
}

/// Crown + band + root of one attempt, with what the untangling left.
#[derive(Clone)]
pub(super) struct Assembled {
    /// Crown, band and root in one mesh (crown faces first, then the band's, then the root's).
    pub(super) mesh: TriMesh,
    /// Per vertex: its [`VertexSource`] as a byte.
    pub(super) source: Vec<u8>,
    /// Per vertex: its IOS input index (`u32::MAX` for band and root vertices).
    pub(super) ios_vertex: Vec<u32>,
    /// The band's faces in `mesh`.
    pub(super) band: std::ops::Range<usize>,
    /// What the untangling did and left (`None` without untangling).
    pub(super) untangle: Option<super::untangle::UntangleReport>,
    /// The crown's vertices: the first this many of `mesh`.
    pub(super) crown_vertices: usize,
}

/// Band builds per tooth at most (the first and the rebuilds after trimming the fringe). Each
/// rebuild lays the band out anew on a changed margin, so the crossings left do not fall steadily
/// from one attempt to the next: on rough phantom exports some teeth still crossed after six
/// attempts are clear by the tenth. Only such teeth pay for the later attempts (the foreign
/// jaws' teeth take at most four).
const MAX_ATTEMPTS: usize = 10;

/// The crown side of the cut tooth as it is.
pub(super) fn cut_side(ct: &CutTooth) -> CrownSide {
    CrownSide {
        crown: ct.crown.clone(),
        margin: ct.margin.clone(),
        dirs: ct.crown_dirs.clone(),
        chords: ct.crown_chords().collect(),
        ios_vertex: ct.ios_vertex.clone(),
    }
}

/// The builds of one tooth from the crown side `side` ([`build_attempts`], then [`polish`]),
/// with `first` the first build from `side` when it is already made: the build kept and the
/// tooth's trim.
pub(super) fn builds_from(
    ct: &CutTooth,
    side: CrownSide,
    opts: &FuseOptions,
    first: Option<Assembled>,
) -> Result<(Assembled, super::fringe::FringeTrim)> {
    let (kept, kept_trim, kept_side) = build_attempts(ct, side, opts, first)?;
    polish(ct, opts, kept, kept_trim, kept_side)
}

/// The band builds of one tooth from the crown side `side`: built, and where crossings are
/// left the crown's fringe trimmed and the band built again, up to [`MAX_ATTEMPTS`] builds (fewer
/// once the tooth has spent its builds, [`super::build_budget`]). A
/// build whose band crosses only itself or the root (no crown face to trim: a trim can leave
/// the margin with a notch the band folds over) is first built again on the same crown with
/// other tangent lengths ([`super::polish::reshaped`]). Returns the build with the fewest
/// crossings left (the earliest, least trimmed, on a tie), its trim and its crown side.
fn build_attempts(
    ct: &CutTooth,
    mut side: CrownSide,
    opts: &FuseOptions,
    mut first: Option<Assembled>,
) -> Result<(Assembled, super::fringe::FringeTrim, CrownSide)> {
    let mut trimmed = ct.trimmed;
    // Where the band cannot clear a crown face within the fringe, that face goes (with the faces
    // between it and the margin) and the band is built again on the new margin. Of the attempts,
    // the one with the fewest crossings left is kept (the earliest, least trimmed, on a tie).
    let mut best: Option<(Assembled, super::fringe::FringeTrim, CrownSide)> = None;
    for attempt in 1..=MAX_ATTEMPTS {
        let mut a = match first.take() {
            Some(a) => a,
            // The tooth's builds spent: the best so far is kept.
            None if best.is_some() && !super::build_budget::more() => break,
            None => assemble(ct, &side, opts)?,
        };
        let hits_of = |a: &Assembled| {
            if crossings_left(a) > 0 {
                crown_faces_hit(a, attempt > 2)
            } else {
                Vec::new()
            }
        };
        let mut hits = hits_of(&a);
        if hits.is_empty() && crossings_left(&a) > 0 && opts.fringe_reach_mm > 0.0 {
            // The band crosses only itself or the root: no trim can help, other tangents may.
            a = super::polish::reshaped(ct, &side, opts, a);
            hits = hits_of(&a);
        }
        let next = if hits.is_empty() || opts.fringe_reach_mm <= 0.0 || attempt == MAX_ATTEMPTS {
            None
        } else {
            retrim(ct, &side, &a, &hits, opts.fringe_reach_mm)
        };
        if best
            .as_ref()
            .is_none_or(|(b, _, _)| crossings_left(&a) < crossings_left(b))
        {
            best = Some((a, trimmed, side.clone()));
        }
        let Some((crown, map, t)) = next else {
            break;
        };
        add_trim(&mut trimmed, &t);
        side = trimmed_side(ct, crown, map);
    }
    Ok(best.expect("at least one attempt"))
}

/// The trim of `side`'s crown for a build `a` that left the crown faces `hits` crossed: the
/// crossed faces within the reach; only where nothing within the reach can go, a crossed face
/// whose apex lies beyond it; only where neither can go, the same with the crown faces whose
/// margin edge pierces a crossed face listed too ([`pierced_margin_faces`], looked for only
/// then); and last, listed faces on a margin edge whatever the reach of their corners (none of
/// them is lost: the margin moves, no vertex goes). `None` when nothing can go.
fn retrim(
    ct: &CutTooth,
    side: &CrownSide,
    a: &Assembled,
    hits: &[u32],
    reach: f64,
) -> Option<(TriMesh, Vec<u32>, super::fringe::FringeTrim)> {
    let r = side.trim(ct, reach, hits, &[Listed::Within, Listed::Apex]);
    if r.is_some() {
        return r;
    }
    let mut pierced = hits.to_vec();
    pierced.extend(pierced_margin_faces(a));
    pierced.sort_unstable();
    pierced.dedup();
    let r = if pierced.len() > hits.len() {
        side.trim(ct, reach, &pierced, &[Listed::Within, Listed::Apex])
    } else {
        None
    };
    r.or_else(|| side.trim(ct, reach, &pierced, &[Listed::MarginEdge]))
}

/// The build a tooth keeps after its builds and every remedy for a build left crossed (see
/// [`remedied`]), with what it needs for the report.
pub(super) struct Remedied {
    /// The build kept.
    pub(super) kept: Assembled,
    /// The tooth's whole trim (the cut's and the builds').
    pub(super) trim: super::fringe::FringeTrim,
    /// Narrow slits of the margin closed on the crown the build kept was made from.
    pub(super) inlets_closed: usize,
    /// The tooth's warnings.
    pub(super) warnings: Vec<String>,
    /// The cut tooth the build kept was made on, where a remedy made another one (the root
    /// peeled at the cut, the crown's fold trimmed farther); `None` for the tooth as cut.
    pub(super) tooth: Option<CutTooth>,
}

/// The builds of `ct` ([`super::remedy::first_builds`], [`super::remedy::remedies`]) and, where
/// crossings are left, the remedies that make another tooth or crown: the root peeled at the
/// cut ([`super::root_trim`]), then the margin vertices the band skips collapsed
/// ([`super::skipped`]).
pub(super) fn remedied(ct: &CutTooth, opts: &FuseOptions) -> Result<Remedied> {
    let mut warnings = ct.warnings.clone();
    let first = super::remedy::first_builds(ct, opts, &mut warnings)?;
    let mut inlets_closed = first.inlets_closed;
    let (mut a, mut trimmed) = super::remedy::remedies(ct, opts, first, &mut warnings);
    // Left crossing the root and no crown face: the same builds on a root peeled at the cut.
    let rebuilt = (crossings_left(&a) > 0 && opts.fringe_reach_mm > 0.0)
        .then(|| super::root_trim::rebuilt_on_peeled_root(ct, opts, &a))
        .flatten();
    let mut tooth = None;
    if let Some(r) = rebuilt {
        (a, trimmed, inlets_closed, warnings) = (r.kept, r.trim, r.inlets_closed, r.warnings);
        tooth = Some(r.tooth);
    }
    let on = tooth.as_ref().unwrap_or(ct);
    // Left crossing the crown where the band skips a margin vertex: that vertex collapsed onto
    // a neighbour and the builds made again.
    if crossings_left(&a) > 0
        && opts.fringe_reach_mm > 0.0
        && let Some(c) = super::skipped::rebuilt(on, opts, &a, &trimmed)
    {
        warnings.push(format!(
            "{} margin vertices the band skipped collapsed onto a neighbour (their crown faces re-made on existing vertices)",
            c.vertices
        ));
        (a, trimmed) = (c.kept, c.trim);
    }
    Ok(Remedied {
        kept: a,
        trim: trimmed,
        inlets_closed,
        warnings,
        tooth,
    })
}

fn stitch_inner(ct: &CutTooth, opts: &FuseOptions) -> Result<FusedTooth> {
    let t_start = std::time::Instant::now();
    let builds_before = super::build_budget::all_asked();
    let reused_before = super::build_memo::all_reused();
    let _builds = super::build_budget::Scope::start();
    let mut r = remedied(ct, opts)?;
    // Still crossed after every remedy: the cut's fold trim made again reaching farther.
    if crossings_left(&r.kept) > 0
        && opts.fringe_reach_mm > 0.0
        && let Some(w) = super::fold_wide::rebuilt(ct, opts, crossings_left(&r.kept))
    {
        r = w;
    }
    // Still crossed: the crown cut made again climbing no steeper along the margin's flanks.
    if crossings_left(&r.kept) > 0
        && opts.fringe_reach_mm > 0.0
        && let Some(f) = super::flat_cut::rebuilt(ct, opts, &r.kept)
    {
        r = f;
    }
    let Remedied {
        kept: a,
        trim: trimmed,
        inlets_closed,
        mut warnings,
        tooth,
    } = r;
    let ct = tooth.as_ref().unwrap_or(ct);
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
    q.holes_filled = ct.holes_filled + inlets_closed;
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
    let crown_faces_added =
        super::tooth::faces_added(&mesh.triangles[..band_start], &ios_vertex, &ct.input_faces);
    q.crown_crossings_added = crown_crossings(&mesh, band_start, &crown_faces_added);
    if q.crown_crossings_added > 0 {
        warnings.push(format!(
            "{} intersecting face pairs with a face added to the crown (a hole's cap no shape of which cleared the crown)",
            q.crown_crossings_added
        ));
    }
    let stitch_ms = t_start.elapsed().as_secs_f64() * 1e3;
    let reused = super::build_memo::all_reused() - reused_before;
    Ok(FusedTooth {
        fdi: ct.fdi,
        mesh,
        source,
        ios_vertex,
        band_faces: band_start..band_end,
        crown_faces_added,
        quality: q,
        warnings,
        cut_ms: ct.cut_ms,
        stitch_ms,
        band_builds: super::build_budget::all_asked() - builds_before - reused,
        band_builds_reused: reused,
    })
}

/// Intersecting pairs of two crown faces (below `band_start`) with one of `added` among them.
fn crown_crossings(mesh: &TriMesh, band_start: usize, added: &[u32]) -> usize {
    crate::mesh_check::crossing_pairs(mesh, added)
        .into_iter()
        .filter(|&(f, g)| (f as usize) < band_start && (g as usize) < band_start)
        .count()
}

/// Adds one trim's counts to the tooth's.
pub(super) fn add_trim(total: &mut super::fringe::FringeTrim, t: &super::fringe::FringeTrim) {
    total.faces += t.faces;
    total.vertices += t.vertices;
    total.max_reach_mm = total.max_reach_mm.max(t.max_reach_mm);
    total.rounds += t.rounds;
}

/// The crown side of a trimmed crown (`map`: its vertices' IOS input indices).
pub(super) fn trimmed_side(ct: &CutTooth, crown: TriMesh, map: Vec<u32>) -> CrownSide {
    let margin = boundary_loops(&crown)
        .into_iter()
        .next()
        .unwrap_or_default();
    CrownSide {
        dirs: loop_dirs(&crown, &margin, ct.frame.axis),
        chords: loop_chords(&crown, &margin, BandVertex::Upper),
        crown,
        margin,
        ios_vertex: map,
    }
}

/// Intersecting face pairs with a band face the untangling left (0 without untangling).
pub(super) fn crossings_left(a: &Assembled) -> usize {
    a.untangle.as_ref().map_or(0, |u| u.crossings_after)
}

/// Builds the band between `side`'s margin and the root's cut loop, assembles crown + band +
/// root, and optimises and untangles the band (as `opts.stitch` says). Where the chart band's
/// lift folded over ([`stitch::BuiltBand::folded`]) and the untangling left band faces crossing
/// each other, the loft band is built too and used instead when its faces cross each other less
/// than the chart band's did ([`stitch::less_crossed_loft`]). A folded band the untangling
/// clears of its own crossings needs no loft: only the others pay for one.
/// A build asked for again with the same inputs is the one made before
/// ([`super::build_memo`]).
pub(super) fn assemble(ct: &CutTooth, side: &CrownSide, opts: &FuseOptions) -> Result<Assembled> {
    super::build_budget::count();
    super::build_memo::build(ct, side, opts, || made(ct, side, opts))
}

/// The build [`assemble`] describes, made.
fn made(ct: &CutTooth, side: &CrownSide, opts: &FuseOptions) -> Result<Assembled> {
    let rc = &ct.root;
    let lower_pts = margin_pts_of(&rc.root, &rc.cut_loop);
    let upper_pts = margin_pts_of(&side.crown, &side.margin);
    let chords: Vec<(BandVertex, BandVertex)> = side
        .chords
        .iter()
        .copied()
        .chain(ct.root_chords())
        .collect();
    let loops = BandLoops {
        upper: &upper_pts,
        upper_dir: &side.dirs,
        lower: &lower_pts,
        lower_dir: &ct.root_dirs,
        chords: &chords,
    };
    let built = stitch::build_band(&loops, &ct.frame, &opts.stitch)?;
    let a = assembled_with(ct, side, opts, &built.band)?;
    if !(built.folded && crosses_itself(&a)) {
        return Ok(a);
    }
    match stitch::less_crossed_loft(&loops, &ct.frame, &opts.stitch, &built.band) {
        Some(loft) => assembled_with(ct, side, opts, &loft),
        None => Ok(a),
    }
}

/// Whether the untangling left a pair of two band faces crossing.
fn crosses_itself(a: &Assembled) -> bool {
    a.untangle.as_ref().is_some_and(|u| {
        u.crossing_pairs
            .iter()
            .any(|&(f, g)| a.band.contains(&(f as usize)) && a.band.contains(&(g as usize)))
    })
}

/// Crown + `band` + root assembled into one mesh, the band optimised and untangled (as
/// `opts.stitch` says).
fn assembled_with(
    ct: &CutTooth,
    side: &CrownSide,
    opts: &FuseOptions,
    band: &stitch::Band,
) -> Result<Assembled> {
    let (margin, rc) = (&side.margin, &ct.root);
    let band_off = side.crown.positions.len() as u32;
    let root_off = band_off + band.points.len() as u32;
    let map = |b: BandVertex| match b {
        BandVertex::Upper(i) => margin[i as usize],
        BandVertex::Lower(i) => rc.cut_loop[i as usize] + root_off,
        BandVertex::Interior(i) => i + band_off,
    };
    let mut band_tris: Vec<[u32; 3]> = band.triangles.iter().map(|t| t.map(map)).collect();
    // Orient the band against the crown: the crown holds margin[0] → margin[1].
    let (m0, m1) = (margin[0], margin[1 % margin.len()]);
    debug_assert!(
        EdgeTopology::new(&side.crown)
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
    let (c0, c1) = (rc.cut_loop[0] + root_off, rc.cut_loop[1] + root_off);
    if band_has(c0, c1, &band_tris) {
        return Err(Error::InvalidArgument(
            "CBCT root and IOS crown have opposite orientations after the cut".into(),
        ));
    }
    let mut a = joined(ct, side, &band.points, &band_tris);
    let (mesh, band_faces) = (&mut a.mesh, a.band.clone());
    let band_vertices = band_off..root_off;
    if opts.stitch.optimize {
        super::band_opt::optimize_band(mesh, band_faces.clone(), band_vertices.clone());
    } else if opts.stitch.flips {
        super::band_opt::flip_band(mesh, band_faces.clone(), 6);
    } else {
        super::band_opt::fix_degenerate_band(mesh, band_faces.clone());
    }
    a.untangle = opts
        .stitch
        .untangle
        .then(|| super::untangle::untangle_band(mesh, band_faces, band_vertices, 5.0));
    Ok(a)
}

/// Crown + band vertices `points` + root in one mesh, the band's faces `triangles` (over the
/// joined mesh's vertices) between the crown's and the root's, no untangling report: a build
/// before its band is optimised and untangled, or, given a build's final band, that build.
pub(super) fn joined(
    ct: &CutTooth,
    side: &CrownSide,
    points: &[DVec3],
    triangles: &[[u32; 3]],
) -> Assembled {
    let rc = &ct.root;
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
    // Crown, band interior, then root.
    let band_off = mesh.positions.len();
    mesh.positions.extend_from_slice(points);
    ios_vertex.resize(mesh.positions.len() + rc.root.positions.len(), u32::MAX);
    source.extend(std::iter::repeat_n(VertexSource::Band as u8, points.len()));
    let root_off = mesh.positions.len() as u32;
    mesh.positions.extend_from_slice(&rc.root.positions);
    source.extend(std::iter::repeat_n(
        VertexSource::Cbct as u8,
        rc.root.positions.len(),
    ));
    let band_start = mesh.triangles.len();
    mesh.triangles.extend_from_slice(triangles);
    let band_end = mesh.triangles.len();
    mesh.triangles
        .extend(rc.root.triangles.iter().map(|t| t.map(|v| v + root_off)));
    Assembled {
        mesh,
        source,
        ios_vertex,
        band: band_start..band_end,
        untangle: None,
        crown_vertices: band_off,
    }
}
