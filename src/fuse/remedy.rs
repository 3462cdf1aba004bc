//! The first builds of a tooth: from its crown as cut, or, where the first build crosses the
//! crown and the margin has narrow slits, from the crown with them closed ([`super::inlet`]);
//! and the last remedy for a tooth those builds leave crossed: the fringe reaching farther than
//! the default reach, kept only when it leaves fewer crossings (a remedy that fails to build is
//! skipped).

use super::FuseOptions;
use super::assembly::{
    Assembled, CrownSide, assemble, builds_from, crossings_left, cut_side, trimmed_side,
};
use super::fringe::FringeTrim;
use super::tooth::CutTooth;
use crate::Result;

/// Factors of the fringe reach for a tooth the builds within the reach left crossed, tried in
/// turn while crossings are left. On coarse crowns (edges of 0.3-0.5 mm) one ring of faces
/// spans more than the 0.3 mm default reach; on rough phantom exports every tooth the first
/// builds leave crossed is clear after these builds, trimmed at most 0.52 mm from the margin.
pub(super) const LAST_RESORT_REACH: &[f64] = &[2.0, 3.0];

/// What [`first_builds`] made: the build kept, its trim, the crown side the builds started
/// from, the number of slits closed on it, and the first build from that side when it left
/// crossings (the remedies start from the same build: the band does not depend on the reach).
pub(super) struct FirstBuilds {
    pub(super) kept: Assembled,
    pub(super) trim: FringeTrim,
    pub(super) start: CrownSide,
    pub(super) inlets_closed: usize,
    start_first: Option<Assembled>,
}

/// The first build from `side`, with a copy kept when it leaves crossings (only then can the
/// remedies need it).
fn first_build(
    ct: &CutTooth,
    side: &CrownSide,
    opts: &FuseOptions,
) -> Result<(Assembled, Option<Assembled>)> {
    let a = assemble(ct, side, opts)?;
    let copy = (crossings_left(&a) > 0).then(|| a.clone());
    Ok((a, copy))
}

/// The builds of `ct` ([`builds_from`]) from its crown as cut. Where the first build leaves the band
/// crossing the crown and the margin has narrow slits ([`super::inlet`]; with the fringe on),
/// the builds from the crown with those slits closed come first, since no band laid from a
/// slit's margin can clear the crown wall below it: kept when they leave no crossing, else
/// when they leave fewer than the builds from the crown as cut (a closed crown that fails to
/// build is skipped). A closure kept adds a warning.
pub(super) fn first_builds(
    ct: &CutTooth,
    opts: &FuseOptions,
    warnings: &mut Vec<String>,
) -> Result<FirstBuilds> {
    let side = cut_side(ct);
    let (first, first_copy) = first_build(ct, &side, opts)?;
    if crossings_left(&first) > 0 && opts.fringe_reach_mm > 0.0 {
        let mut crown = ct.crown.clone();
        let r = super::inlet::close_inlets(&mut crown);
        if r.closed > 0 && super::build_budget::more() {
            let closed = trimmed_side(ct, crown, ct.ios_vertex.clone());
            let from_closed = first_build(ct, &closed, opts).ok().and_then(|(f, copy)| {
                let built = builds_from(ct, closed.clone(), opts, Some(f)).ok()?;
                Some((built, copy))
            });
            let from_cut = match from_closed {
                Some(((ref b, _), _)) if crossings_left(b) == 0 => None,
                _ => Some(builds_from(ct, side.clone(), opts, Some(first))?),
            };
            let use_closed = from_closed.as_ref().is_some_and(|((b, _), _)| {
                from_cut
                    .as_ref()
                    .is_none_or(|(a, _)| crossings_left(b) < crossings_left(a))
            });
            if use_closed && let Some(((kept, trim), start_first)) = from_closed {
                warnings.push(format!(
                    "{} narrow inlets of the IOS margin closed ({} faces added on the crown's own vertices; {:.2} mm of margin taken out)",
                    r.closed, r.faces, r.length_mm
                ));
                return Ok(FirstBuilds {
                    kept,
                    trim,
                    start: closed,
                    inlets_closed: r.closed,
                    start_first,
                });
            }
            let (kept, trim) =
                from_cut.expect("built from the cut crown unless the closed one won");
            return Ok(FirstBuilds {
                kept,
                trim,
                start: side,
                inlets_closed: 0,
                start_first: first_copy,
            });
        }
    }
    let (kept, trim) = builds_from(ct, side.clone(), opts, Some(first))?;
    Ok(FirstBuilds {
        kept,
        trim,
        start: side,
        inlets_closed: 0,
        start_first: first_copy,
    })
}

/// The last remedy for the builds `b` of `ct`, while crossings are left (none with the fringe
/// off): the builds made again from the same crown side and the same first build with the
/// fringe reaching farther ([`LAST_RESORT_REACH`]), each kept only when it leaves fewer
/// crossings and then warned. Returns the build kept and its trim.
pub(super) fn remedies(
    ct: &CutTooth,
    opts: &FuseOptions,
    b: FirstBuilds,
    warnings: &mut Vec<String>,
) -> (Assembled, FringeTrim) {
    let (mut a, mut trimmed) = (b.kept, b.trim);
    if opts.fringe_reach_mm <= 0.0 {
        return (a, trimmed);
    }
    for &factor in LAST_RESORT_REACH {
        if crossings_left(&a) == 0 || !super::build_budget::more() {
            break;
        }
        let wide = FuseOptions {
            fringe_reach_mm: opts.fringe_reach_mm * factor,
            ..*opts
        };
        // A remedy that fails to build is skipped: the tooth keeps the build it has.
        if let Ok((w, t)) = builds_from(ct, b.start.clone(), &wide, b.start_first.clone())
            && crossings_left(&w) < crossings_left(&a)
        {
            warnings.push(format!(
                "the band crossed the crown within {:.2} mm of the margin: built again with the fringe reaching {:.2} mm, IOS vertices trimmed up to {:.2} mm from it",
                opts.fringe_reach_mm, wide.fringe_reach_mm, t.max_reach_mm
            ));
            (a, trimmed) = (w, t);
        }
    }
    (a, trimmed)
}

/// The largest of [`LAST_RESORT_REACH`]: how far from the margin the crown's distances are
/// needed.
pub(super) fn widest_reach_factor() -> f64 {
    LAST_RESORT_REACH.iter().copied().fold(1.0, f64::max)
}
