//! The root side's remedy: where every build of a tooth leaves its band crossing the CBCT root
//! near the cut and no crown face (so no crown trim can help), the root faces the band crosses
//! are peeled from the cut loop (within a short reach of it, as the crown's fringe is) and the
//! tooth is built again on the lower cut loop. The root is the CBCT's, whose surface the output
//! does not have to keep face for face: only the crown side's vertices are held bitwise.

use super::FuseOptions;
use super::assembly::{Assembled, crossings_left};
use super::fringe::{FringeTrim, Listed, edge_distance, trim_fringe};
use super::tooth::CutTooth;
use crate::cut::RootCut;
use crate::mesh::{TriMesh, boundary_loops};

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
    if !super::build_budget::more() {
        return None;
    }
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
    let mut out = ct.with_root(RootCut {
        source_vertex: map
            .iter()
            .map(|&v| ct.root.source_vertex[v as usize])
            .collect(),
        removed_faces: ct.root.removed_faces + t.faces,
        root: TriMesh::new(trimmed.positions, trimmed.triangles),
        cut_loop,
    });
    out.warnings.push(format!(
        "the band crossed the CBCT root near the cut and no crown face: {} root faces peeled from the cut ({} root vertices left out) and the tooth built again",
        t.faces, t.vertices
    ));
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fuse::assembly::{assemble, cut_side};
    use crate::fuse::stitch_tooth;
    use crate::fuse::test_teeth::ellipsoid_tooth;
    use crate::fuse::untangle::UntangleReport;
    use crate::mesh::EdgeTopology;

    /// A build of `ct` whose untangling left its first band face crossing the root faces `hit`
    /// (indices into the root) and, with `crown_face`, crown face 0 too.
    fn crossed_build(ct: &CutTooth, hit: &[u32], crown_face: bool) -> Assembled {
        let mut a = assemble(ct, &cut_side(ct), &FuseOptions::default()).expect("builds");
        let band_face = a.band.start as u32;
        let mut pairs: Vec<(u32, u32)> = hit
            .iter()
            .map(|&r| (band_face, r + a.band.end as u32))
            .collect();
        if crown_face {
            pairs.push((0, band_face));
        }
        a.untangle = Some(UntangleReport {
            crossings_before: pairs.len(),
            crossings_after: pairs.len(),
            crossing_pairs: pairs,
            ..UntangleReport::default()
        });
        a
    }

    /// Root faces a band crosses at the cut go, with nothing beyond the reach: the peeled root
    /// is one disk whose boundary is the new cut loop, every kept vertex is the CBCT's own (by
    /// its source index), the crossed faces are gone, the count of removed faces grows by what
    /// was peeled, and the tooth built on it is closed; a pair with a crown face, or no root
    /// face in any pair, leaves the root as it is.
    #[test]
    fn root_faces_the_band_crosses_are_peeled_from_the_cut() {
        let ct = ellipsoid_tooth(0.0, 4.0);
        let cbct = &ct.cbct;
        let root = &ct.root.root;
        let topo = EdgeTopology::new(root);
        let on_cut: Vec<u32> = (0..root.triangles.len() as u32)
            .filter(|&f| {
                let t = root.triangles[f as usize];
                (0..3).any(|k| topo.edge_face_count(t[k], t[(k + 1) % 3]) == 1)
            })
            .collect();
        assert!(on_cut.len() > 20, "{} faces on the cut", on_cut.len());
        let hit = [on_cut[3], on_cut[on_cut.len() / 2]];
        let key = |m: &TriMesh, src: &[u32], f: usize| {
            crate::mesh::sorted_corners(m.triangles[f].map(|v| src[v as usize]))
        };
        let hit_keys: Vec<[u32; 3]> = hit
            .iter()
            .map(|&f| key(root, &ct.root.source_vertex, f as usize))
            .collect();

        assert!(root_trimmed(&ct, &crossed_build(&ct, &hit, true)).is_none());
        assert!(root_trimmed(&ct, &crossed_build(&ct, &[], false)).is_none());

        let peeled = root_trimmed(&ct, &crossed_build(&ct, &hit, false)).expect("peeled");
        let (r, src) = (&peeled.root.root, &peeled.root.source_vertex);
        let peeled_faces = peeled.root.removed_faces - ct.root.removed_faces;
        assert!(peeled_faces >= hit.len(), "{peeled_faces} faces peeled");
        assert_eq!(r.triangles.len() + peeled_faces, root.triangles.len());
        for f in 0..r.triangles.len() {
            assert!(!hit_keys.contains(&key(r, src, f)), "face {f} was crossed");
        }
        assert_eq!(boundary_loops(r), vec![peeled.root.cut_loop.clone()]);
        assert_eq!(peeled.root_dirs.len(), peeled.root.cut_loop.len());
        assert_eq!(src.len(), r.positions.len());
        for (v, &s) in src.iter().enumerate() {
            assert_eq!(r.positions[v], cbct.positions[s as usize], "vertex {v}");
        }
        // The vertices left out lie within the reach of the first cut loop.
        let dist = edge_distance(root, &ct.root.cut_loop, f64::INFINITY);
        let kept: std::collections::BTreeSet<u32> = src.iter().copied().collect();
        for (v, &s) in ct.root.source_vertex.iter().enumerate() {
            if !kept.contains(&s) {
                assert!(dist[v] <= ROOT_REACH_MM, "vertex {v} at {} mm", dist[v]);
            }
        }
        assert!(
            peeled
                .warnings
                .last()
                .unwrap()
                .contains("root faces peeled")
        );
        let fused = stitch_tooth(&peeled, &FuseOptions::default()).expect("stitches");
        let q = &fused.quality;
        assert!(q.closed && q.manifold && q.components == 1, "{q:?}");
        assert!(q.volume > 0.0);
    }
}
