//! The last remedies for a tooth the band builds leave crossed: the narrow slits of its
//! margin closed ([`super::inlet`]), then the fringe reaching farther than the default reach.
//! Each is kept only when it leaves fewer crossings; a remedy that fails to build is skipped.

use super::FuseOptions;
use super::assembly::{Assembled, builds, crossings_left, trimmed_side};
use super::fringe::FringeTrim;
use super::tooth::CutTooth;

/// Factors of the fringe reach for a tooth the builds within the reach left crossed, tried in
/// turn while crossings are left. On coarse crowns (edges of 0.3-0.5 mm) one ring of faces
/// spans more than the 0.3 mm default reach; on rough phantom exports every tooth the first
/// builds leave crossed is clear after these builds, trimmed at most 0.52 mm from the margin.
pub(super) const LAST_RESORT_REACH: &[f64] = &[2.0, 3.0];

/// The remedies for build `a` (trim `trimmed`) of `ct`, tried in turn while crossings are left
/// (none with the fringe off); each one kept adds a warning. Returns the build kept, its trim
/// and the number of slits closed.
pub(super) fn remedies(
    ct: &CutTooth,
    opts: &FuseOptions,
    mut a: Assembled,
    mut trimmed: FringeTrim,
    warnings: &mut Vec<String>,
) -> (Assembled, FringeTrim, usize) {
    if crossings_left(&a) == 0 || opts.fringe_reach_mm <= 0.0 {
        return (a, trimmed, 0);
    }
    let mut start = super::assembly::cut_side(ct);
    let mut inlets_closed = 0;
    // Where the band crosses the crown, a slit in the crown at the margin (the margin running
    // up into the crown and back beside itself) may be what it cannot clear: the slits are
    // closed ([`super::inlet`]) and the builds made again, kept only with fewer crossings.
    let mut crown = ct.crown.clone();
    let r = super::inlet::close_inlets(&mut crown);
    if r.closed > 0 {
        let side = trimmed_side(ct, crown, ct.ios_vertex.clone());
        // A remedy that fails to build is skipped: the tooth keeps the build it has.
        if let Ok((b, t)) = builds(ct, side.clone(), opts)
            && crossings_left(&b) < crossings_left(&a)
        {
            warnings.push(format!(
                "{} narrow inlets of the IOS margin closed ({} faces added on the crown's own vertices; {:.2} mm of margin taken out)",
                r.closed, r.faces, r.length_mm
            ));
            (a, trimmed, start, inlets_closed) = (b, t, side, r.closed);
        }
    }
    // Where the builds within the reach leave the band crossing the crown, the builds are made
    // again with the fringe reaching farther (kept only when fewer crossings are left).
    for &factor in LAST_RESORT_REACH {
        if crossings_left(&a) == 0 {
            break;
        }
        let wide = FuseOptions {
            fringe_reach_mm: opts.fringe_reach_mm * factor,
            ..*opts
        };
        if let Ok((b, t)) = builds(ct, start.clone(), &wide)
            && crossings_left(&b) < crossings_left(&a)
        {
            warnings.push(format!(
                "the band crossed the crown within {:.2} mm of the margin: built again with the fringe reaching {:.2} mm, IOS vertices trimmed up to {:.2} mm from it",
                opts.fringe_reach_mm, wide.fringe_reach_mm, t.max_reach_mm
            ));
            (a, trimmed) = (b, t);
        }
    }
    (a, trimmed, inlets_closed)
}

/// The largest of [`LAST_RESORT_REACH`]: how far from the margin the crown's distances are
/// needed.
pub(super) fn widest_reach_factor() -> f64 {
    LAST_RESORT_REACH.iter().copied().fold(1.0, f64::max)
}
