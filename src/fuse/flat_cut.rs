//! The last remedy for a tooth whose band is still crossed after every other (it is meant for a
//! band crossing itself or the root, which no crown trim helps): the crown cut made again with
//! its climb bounded ([`FLAT_CUT_SLOPE`]), and the tooth's builds and remedies made again on
//! that root.
//!
//! The level-set cut follows the margin's lowest height at each angle, less the offset. Where a
//! labelled crown reaches up a contact (a lower incisor's label can run from the cervix nearly
//! to the incisal edge there), that height climbs the contact's flank as steeply as the margin
//! does, and so does the cut: the band between them is a strip a fraction of the offset wide
//! measured across the flank, and it folds over itself and through the root there (the coarse
//! seed-44 lower incisor 31: 17 pairs left after every other remedy). Cut again no steeper than
//! [`FLAT_CUT_SLOPE`], the root there ends lower and the band is as tall as it needs. It runs
//! only on a tooth left crossed, so every other tooth's fusion is unchanged: made the default
//! for every tooth, it cleared that tooth and left 2 pairs on another (the coarse seed-8 lower
//! molar 46) that its remedies clear with the cut as it is.
//!
//! The tooth is built again only where the flatter cut takes CBCT surface away near a crossing
//! left ([`NEAR_CROSSING_MM`]); the new cut's builds are counted afresh against a cap of their
//! own ([`super::build_budget::Scope`]).

use super::FuseOptions;
use super::assembly::{Assembled, Remedied, crossings_left, remedied};
use super::tooth::{CutTooth, margin_pts_of, winds_once};
use crate::cut::{self, CutMethod, CutOptions};
use glam::DVec3;

/// The steepest climb of the cut made again (height per unit of length around the tooth at the
/// margin: 1 = 45°; see [`crate::cut::MarginHeight::new`]).
pub(super) const FLAT_CUT_SLOPE: f64 = 1.0;

/// How near (mm) to a crossing the build left the flatter cut must take CBCT surface away for
/// the tooth to be built again on it: a cut changed only elsewhere lays the band where it
/// crosses as before (the band reaches from the margin to the cut, ~1-2 mm).
const NEAR_CROSSING_MM: f64 = 2.0;

/// The builds and remedies of `ct` ([`remedied`]) made again on its CBCT tooth cut with the
/// climb bounded ([`flatter_cut`]), for the build `a` left crossed; `None` when the cut is the
/// level-set one already bounded as much, the new cut fails or takes nothing away within
/// [`NEAR_CROSSING_MM`] of a crossing `a` left, or its builds leave no fewer crossings.
pub(super) fn rebuilt(ct: &CutTooth, opts: &FuseOptions, a: &Assembled) -> Option<Remedied> {
    let _builds = super::build_budget::Scope::start();
    if !super::build_budget::more() {
        return None;
    }
    let left = crossings_left(a);
    let flat = flatter_cut(ct, &opts.cut)?;
    if !cut_lower_near(ct, &flat, a) {
        return None;
    }
    let mut r = remedied(&flat, opts).ok()?;
    (crossings_left(&r.kept) < left).then(|| {
        r.tooth = r.tooth.or(Some(flat));
        r
    })
}

/// Whether the root of `flat` leaves out a CBCT vertex the root of `ct` holds within
/// [`NEAR_CROSSING_MM`] of a face of the crossing pairs `a` left.
fn cut_lower_near(ct: &CutTooth, flat: &CutTooth, a: &Assembled) -> bool {
    let Some(u) = &a.untangle else {
        return false;
    };
    let mut kept = flat.root.source_vertex.clone();
    kept.sort_unstable();
    let gone: Vec<DVec3> = ct
        .root
        .source_vertex
        .iter()
        .filter(|v| kept.binary_search(v).is_err())
        .map(|&v| ct.cbct.positions[v as usize])
        .collect();
    let near2 = NEAR_CROSSING_MM * NEAR_CROSSING_MM;
    u.crossing_pairs.iter().flat_map(|&(f, g)| [f, g]).any(|f| {
        let c = a.mesh.corners(f as usize);
        let mid = (c[0] + c[1] + c[2]) / 3.0;
        gone.iter().any(|p| p.distance_squared(mid) <= near2)
    })
}

/// `ct` with its CBCT tooth cut again about the same frame and margin, no steeper than
/// [`FLAT_CUT_SLOPE`]; its root, loop directions and chords made anew (with a warning). `None`
/// for another cut method, a climb bounded as much already, a cut that fails, does not go
/// around the tooth, or removes no more of the CBCT tooth than the cut as it is.
fn flatter_cut(ct: &CutTooth, cut_opts: &CutOptions) -> Option<CutTooth> {
    let bounded = cut_opts.max_slope > 0.0 && cut_opts.max_slope <= FLAT_CUT_SLOPE;
    if cut_opts.method != CutMethod::LevelSet || bounded {
        return None;
    }
    let flat_opts = CutOptions {
        max_slope: FLAT_CUT_SLOPE,
        ..*cut_opts
    };
    let margin = margin_pts_of(&ct.crown, &ct.margin);
    let rc = cut::cut_crown(&ct.cbct, &margin, &ct.frame, &flat_opts).ok()?;
    if !winds_once(&ct.frame, &rc) || rc.removed_faces <= ct.root.removed_faces {
        return None;
    }
    let more = rc.removed_faces - ct.root.removed_faces;
    let mut out = ct.with_root(rc);
    out.warnings.push(format!(
        "the band was still crossed after every remedy: the crown cut made again climbing no steeper than {:.0}° along the margin ({} more CBCT faces removed) and the tooth built again",
        FLAT_CUT_SLOPE.atan().to_degrees(),
        more
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

    /// Where the margin climbs 3.5 mm up a 50° notch, the cut made again climbs no steeper: it
    /// removes more of the CBCT tooth, its loop goes once around the tooth, it says so, and the
    /// tooth built on it is closed and manifold with no crossing left.
    #[test]
    fn steep_margin_is_cut_again_lower() {
        let ct = ellipsoid_tooth(25.0, 7.5);
        let opts = FuseOptions::default();
        let flat = flatter_cut(&ct, &opts.cut).expect("a flatter cut");
        assert!(flat.root.removed_faces > ct.root.removed_faces);
        assert!(winds_once(&flat.frame, &flat.root));
        assert!(
            flat.warnings
                .last()
                .is_some_and(|w| w.contains("climbing no steeper than 45°")),
            "{:?}",
            flat.warnings
        );
        let fused = stitch_tooth(&flat, &opts).expect("stitched on the flatter cut");
        let q = &fused.quality;
        assert!(q.closed && q.manifold && q.components == 1, "{q:?}");
        assert_eq!(q.band_crossings_left, 0, "{q:?}");
    }

    /// A build of `ct` whose untangling left one pair: the band face whose centre lies nearest
    /// the angle `at` (radians about z) with itself.
    fn crossed_at(ct: &CutTooth, at: f64) -> Assembled {
        let mut a = assemble(ct, &cut_side(ct), &FuseOptions::default()).expect("builds");
        let off = |f: usize| {
            let c = a.mesh.corners(f);
            let m = (c[0] + c[1] + c[2]) / 3.0;
            let d = (m.y.atan2(m.x) - at).rem_euclid(std::f64::consts::TAU);
            d.min(std::f64::consts::TAU - d)
        };
        let f = a
            .band
            .clone()
            .min_by(|&f, &g| off(f).total_cmp(&off(g)))
            .expect("a band") as u32;
        a.untangle = Some(UntangleReport {
            crossings_before: 1,
            crossings_after: 1,
            crossing_pairs: vec![(f, f)],
            ..UntangleReport::default()
        });
        a
    }

    /// The flatter cut of the notched tooth takes CBCT surface away only about the notch: a
    /// crossing left there calls for its builds, one half a turn away does not.
    #[test]
    fn flatter_cut_is_built_only_for_crossings_where_it_changes_the_root() {
        let ct = ellipsoid_tooth(25.0, 7.5);
        let flat = flatter_cut(&ct, &FuseOptions::default().cut).expect("a flatter cut");
        assert!(cut_lower_near(&ct, &flat, &crossed_at(&ct, 0.0)));
        assert!(!cut_lower_near(
            &ct,
            &flat,
            &crossed_at(&ct, std::f64::consts::PI)
        ));
    }

    /// No flatter cut where there is nothing to flatten (a level margin: the cut removes no
    /// more), for the paper's Dijkstra cut, or for a cut bounded as much already.
    #[test]
    fn no_flatter_cut_where_it_changes_nothing() {
        let opts = FuseOptions::default();
        assert!(flatter_cut(&ellipsoid_tooth(0.0, 4.0), &opts.cut).is_none());
        let ct = ellipsoid_tooth(25.0, 7.5);
        let dijkstra = CutOptions {
            method: CutMethod::Dijkstra,
            ..opts.cut
        };
        assert!(flatter_cut(&ct, &dijkstra).is_none());
        let bounded = CutOptions {
            max_slope: FLAT_CUT_SLOPE,
            ..opts.cut
        };
        assert!(flatter_cut(&ct, &bounded).is_none());
    }
}
