//! The polish of a tooth's kept build when the band still crosses the crown after the
//! rebuilds: the crown loses the faces on its pierced margin edges (or only the crossed ones)
//! while that leaves fewer crossings, then the band is built again with other tangent lengths.

use super::FuseOptions;
use super::assembly::{Assembled, CrownSide, add_trim, assemble, crossings_left, trimmed_side};
use super::crossed::{crown_faces_hit, pierced_margin_faces};
use super::fringe::{FringeTrim, Listed};
use super::tooth::CutTooth;
use crate::Result;

/// Rounds of trimming the kept build's pierced margin faces after the builds, at most.
const POLISH_ROUNDS: usize = 3;

/// After the builds, for a kept build still crossed: its crown loses the faces on its pierced
/// margin edges, or else only the crown faces the band still crosses, while that leaves fewer
/// crossings (up to [`POLISH_ROUNDS`] steps, [`polish_step`]), then the band is built again
/// with other tangent lengths ([`reshaped`]). Returns the build and the tooth's trim.
pub(super) fn polish(
    ct: &CutTooth,
    opts: &FuseOptions,
    kept: Assembled,
    kept_trim: FringeTrim,
    kept_side: CrownSide,
) -> Result<(Assembled, FringeTrim)> {
    let (mut a, mut trimmed, mut best_side) = (kept, kept_trim, kept_side.clone());
    let mut kept_build: Option<Assembled> = None;
    // The later builds may have fared worse than the kept one: from the kept crown, only the
    // faces on its pierced margin edges go, while that leaves fewer crossings.
    for _ in 0..POLISH_ROUNDS {
        if crossings_left(&a) == 0 || opts.fringe_reach_mm <= 0.0 {
            break;
        }
        let Some((b, next, t)) = polish_step(ct, opts, &a, &best_side)? else {
            break;
        };
        if kept_build.is_none() {
            kept_build = Some(std::mem::replace(&mut a, b));
        } else {
            a = b;
        }
        add_trim(&mut trimmed, &t);
        best_side = next;
    }
    if crossings_left(&a) > 0 {
        a = reshaped(ct, &best_side, opts, a);
        // The kept build reshaped may still beat the polished one (then its smaller trim).
        if let Some(k) = kept_build.filter(|k| crossings_left(k) > 0) {
            let k = reshaped(ct, &kept_side, opts, k);
            if crossings_left(&k) <= crossings_left(&a) {
                a = k;
                trimmed = kept_trim;
            }
        }
    }
    Ok((a, trimmed))
}

/// One polishing step of build `a` on `side`: its crown loses the faces on its pierced margin
/// edges ([`pierced_margin_faces`], [`Listed::MarginEdge`]); where that leaves no fewer
/// crossings, only the crown faces the band still crosses (within the reach, else with an
/// apex beyond it, else on a margin edge whatever the reach: no vertex beyond the reach is
/// lost). Returns the first of these builds with fewer crossings left, its crown side and trim.
fn polish_step(
    ct: &CutTooth,
    opts: &FuseOptions,
    a: &Assembled,
    side: &CrownSide,
) -> Result<Option<(Assembled, CrownSide, FringeTrim)>> {
    let reach = opts.fringe_reach_mm;
    for stage in 0..2 {
        let cut = if stage == 0 {
            side.trim(ct, reach, &pierced_margin_faces(a), &[Listed::MarginEdge])
        } else {
            let hit = crown_faces_hit(a, false);
            side.trim(
                ct,
                reach,
                &hit,
                &[Listed::Within, Listed::Apex, Listed::MarginEdge],
            )
        };
        let Some((crown, map, t)) = cut else {
            continue;
        };
        if !super::build_budget::more() {
            break;
        }
        let next = trimmed_side(ct, crown, map);
        let b = assemble(ct, &next, opts)?;
        if crossings_left(&b) < crossings_left(a) {
            return Ok(Some((b, next, t)));
        }
    }
    Ok(None)
}

/// Hermite tangent lengths (fractions of the loop-to-loop distance) of the band builds tried
/// again on the best attempt's crown where crossings are left, and on a crown whose band
/// crosses only itself or the root: a band leaving the margin steeper or flatter than the
/// default passes a fold at the margin on another side.
const RESHAPE_TANGENTS: [f64; 4] = [0.4, 1.2, 0.0, 1.6];

/// Builds the band on `side` again with other tangent lengths ([`RESHAPE_TANGENTS`]) and keeps
/// the build with the fewest crossings left (`best`, the default's, on a tie; a build that
/// fails is skipped). Only teeth still crossed after the trimming attempts, or whose band
/// crosses no crown face but itself or the root, pay for it.
pub(super) fn reshaped(
    ct: &CutTooth,
    side: &CrownSide,
    opts: &FuseOptions,
    mut best: Assembled,
) -> Assembled {
    for t in RESHAPE_TANGENTS {
        if crossings_left(&best) == 0 || !super::build_budget::more() {
            break;
        }
        let mut o = *opts;
        o.stitch.tangent_scale = t;
        let Ok(a) = assemble(ct, side, &o) else {
            continue;
        };
        if crossings_left(&a) < crossings_left(&best) {
            best = a;
        }
    }
    best
}
