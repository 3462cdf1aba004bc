//! The root side's remedy: where every build of a tooth leaves its band crossing the CBCT root
//! near the cut and no crown face (so no crown trim can help), the root faces the band crosses
//! are peeled from the cut loop (within a short reach of it, as the crown's fringe is) and the
//! tooth is built again on the lower cut loop. The root is the CBCT's, whose surface the output
//! does not have to keep face for face: only the crown side's vertices are held bitwise.

use super::FuseOptions;
use super::assembly::{Assembled, crossings_left};
use super::fringe::{FringeTrim, Listed, edge_distance, trim_fringe};
use super::tooth::{CutTooth, loop_chords, loop_dirs};
use crate::mesh::{TriMesh, boundary_loops};
use crate::stitch::BandVertex;

/// The builds of a tooth made again on its root peeled at the cut ([`rebuilt_on_peeled_root`]).
pub(super) struct Rebuilt {
    /// The tooth with its root peeled.
    pub(super) tooth: CutTooth,
    /// The build kept, its trim and the number of slits closed on its crown.
    pub(super) kept: Assembled,
    pub(super) trim: FringeTrim,
    pub(super) inlets_closed: usize,
    /// The tooth's warnings, the peeling's among them.
    pub(super) warnings: Vec<String>,
}

/// The builds of `ct` ([`super::remedy::first_builds`], [`super::remedy::remedies`]) made again
/// on its root peeled at the cut for the build `a` ([`root_trimmed`]); `None` where no root can
/// be peeled, the builds fail, or they leave no fewer crossings than `a`.
pub(super) fn rebuilt_on_peeled_root(
    ct: &CutTooth,
    opts: &FuseOptions,
    a: &Assembled,
) -> Option<Rebuilt> {
    let tooth = root_trimmed(ct, a)?;
    let mut warnings = tooth.warnings.clone();
    let first = super::remedy::first_builds(&tooth, opts, &mut warnings).ok()?;
    let inlets_closed = first.inlets_closed;
    let (kept, trim) = super::remedy::remedies(&tooth, opts, first, &mut warnings);
    (crossings_left(&kept) < crossings_left(a)).then_some(Rebuilt {
        tooth,
        kept,
        trim,
        inlets_closed,
        warnings,
    })
}

/// How far (mm, along the root surface from the cut loop) root faces may be peeled.
const ROOT_REACH_MM: f64 = 0.6;

/// The root faces (indices into the cut tooth's root) in the crossing pairs the build `a`
/// left, when no pair has a crown face; empty otherwise.
fn root_faces_hit(a: &Assembled) -> Vec<u32> {
    let Some(u) = &a.untangle else {
        return Vec::new();
    };
    let faces = u.crossing_pairs.iter().flat_map(|&(f, g)| [f, g]);
    if faces.clone().any(|f| (f as usize) < a.band.start) {
        return Vec::new();
    }
    let mut hit: Vec<u32> = faces
        .filter(|&f| f as usize >= a.band.end)
        .map(|f| f - a.band.end as u32)
        .collect();
    hit.sort_unstable();
    hit.dedup();
    hit
}

/// `ct` with the root faces the build `a` left crossed (and the faces between them and the cut
/// loop) peeled from its root, the cut loop and its directions and chords made anew; `None`
/// when `a` crosses a crown face, crosses no root face, or nothing within the reach can go.
fn root_trimmed(ct: &CutTooth, a: &Assembled) -> Option<CutTooth> {
    let hit = root_faces_hit(a);
    if hit.is_empty() {
        return None;
    }
    let root = &ct.root.root;
    let n = root.positions.len();
    let ids: Vec<u32> = (0..n as u32).collect();
    let dist = edge_distance(root, &ct.root.cut_loop, 2.0 * ROOT_REACH_MM);
    let (trimmed, map, t) = [Listed::Within, Listed::Apex, Listed::MarginEdge]
        .iter()
        .find_map(|&mode| trim_fringe(root, &ids, &dist, ROOT_REACH_MM, &hit, mode))?;
    let cut_loop = boundary_loops(&trimmed).into_iter().next()?;
    let mut out = ct.clone();
    out.root.source_vertex = map
        .iter()
        .map(|&v| ct.root.source_vertex[v as usize])
        .collect();
    out.root.removed_faces += t.faces;
    out.root_dirs = loop_dirs(&trimmed, &cut_loop, ct.frame.axis);
    out.chords = ct
        .chords
        .iter()
        .copied()
        .filter(|c| matches!(c.0, BandVertex::Upper(_)))
        .chain(loop_chords(&trimmed, &cut_loop, BandVertex::Lower))
        .collect();
    out.root.root = TriMesh::new(trimmed.positions, trimmed.triangles);
    out.root.cut_loop = cut_loop;
    out.warnings.push(format!(
        "the band crossed the CBCT root near the cut and no crown face: {} root faces peeled from the cut ({} root vertices left out) and the tooth built again",
        t.faces, t.vertices
    ));
    Some(out)
}
