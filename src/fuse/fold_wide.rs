//! The last remedy for a tooth whose band still crosses the crown after every other: the cut's
//! fold trim ([`super::fringe::trim_fringe`] of the crown faces that cross other crown faces)
//! made again reaching farther from the margin, and the tooth's builds and remedies made again
//! on that crown.
//!
//! The cut trims folds within the fringe reach (0.3 mm by default). On a coarse crown (edges of
//! 0.3-0.5 mm) a fold at the margin can reach one ring in, past that: crown faces on the margin
//! crossing crown faces whose inner corners lie beyond the reach, with a margin edge through one
//! of them. Every band face on that edge then crosses it, and no trim of the band's builds
//! (which trim the faces the band crosses) nor a collapse of a margin vertex clears it; only
//! taking one side of the fold away does. The fold trim is made again at the wider reaches of
//! [`LAST_RESORT_REACH`] in turn, each kept only when it leaves fewer crossings (warned, the
//! vertices it trims counted with their distance from the margin). It runs only on a tooth left
//! crossed, so every other tooth's fusion is unchanged.
//!
//! These crowns are new cuts of the tooth, whose builds are counted afresh against a cap of
//! their own ([`super::build_budget::Scope`]), as are those of the flatter cut after it
//! ([`super::flat_cut`]): with them a tooth makes at most three times
//! [`super::build_budget::MAX_BUILDS`] builds.

use super::FuseOptions;
use super::assembly::{Remedied, add_trim, crossings_left, remedied, trimmed_side};
use super::fringe::Listed;
use super::remedy::LAST_RESORT_REACH;
use super::tooth::CutTooth;
use crate::mesh::boundary_loops;

/// The builds and remedies of `ct` made again on its crown with the fold trimmed at the wider
/// reaches ([`wider_fold`]), the first that leaves no crossing or else the one that leaves the
/// fewest; `None` when none leaves fewer than `left`.
pub(super) fn rebuilt(ct: &CutTooth, opts: &FuseOptions, left: usize) -> Option<Remedied> {
    let mut best: Option<Remedied> = None;
    let mut least = left;
    // New cuts of the tooth: their builds counted from zero, against a cap of their own.
    let _builds = super::build_budget::Scope::start();
    for &factor in LAST_RESORT_REACH {
        if !super::build_budget::more() {
            break;
        }
        let Some(wide) = wider_fold(ct, opts.fringe_reach_mm * factor) else {
            continue;
        };
        let Ok(mut r) = remedied(&wide, opts) else {
            continue;
        };
        let n = crossings_left(&r.kept);
        if n < least {
            least = n;
            r.tooth = r.tooth.or(Some(wide));
            best = Some(r);
        }
        if least == 0 {
            break;
        }
    }
    best
}

/// `ct` with its crown's fold trimmed within `reach` of the margin ([`Listed::Within`]: the crown
/// faces, every corner within the reach, that cross other crown faces), its margin, directions
/// and chords taken anew and the trim added to the cut's (with a warning). `None` when nothing
/// is trimmed or the trimmed crown has other than one boundary loop.
pub(super) fn wider_fold(ct: &CutTooth, reach: f64) -> Option<CutTooth> {
    let (crown, map, t) = super::fringe::trim_fringe(
        &ct.crown,
        &ct.ios_vertex,
        &ct.dist_in,
        reach,
        &[],
        Listed::Within,
    )?;
    if boundary_loops(&crown).len() != 1 {
        return None;
    }
    let mut tooth = trimmed_side(ct, crown, map).into_tooth(ct);
    add_trim(&mut tooth.trimmed, &t);
    tooth.warnings.push(format!(
        "the band crossed a fold of the crown after every remedy: the fold trimmed again within {reach:.2} mm of the margin ({} more IOS crown vertices, {} faces, at most {:.2} mm from the margin)",
        t.vertices, t.faces, t.max_reach_mm
    ));
    Some(tooth)
}

#[cfg(test)]
mod tests;
