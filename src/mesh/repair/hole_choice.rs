//! Which boundary loops a pass of [`super::repair_open_surface`] fills: the first pass by size,
//! the later ones (whose holes grew as faces went with them) as the first chose.

use super::RepairOptions;

/// What the first round of [`super::repair_open_surface`] made of an input vertex's boundary
/// loop.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Rim {
    /// On no loop, or on a hole it filled.
    Other,
    /// On the margin.
    Margin,
    /// On a hole left open (too long to fill).
    Open,
}

/// Which loops a pass of [`super::repair_open_surface`] fills.
pub(super) enum Holes<'a> {
    /// Every loop but the longest (the margin) at most `max_hole_fraction` of its length; what
    /// was made of each loop is recorded per input vertex (the first round).
    BySize(&'a mut Vec<Rim>),
    /// As the first round chose: the margin is the loop with the most of its margin's vertices,
    /// a loop through a hole it left open stays open, every other loop is filled (the later
    /// rounds, whose holes grew as faces went with them).
    AsFirst(&'a [Rim]),
}

/// Per loop of `loops` (vertex indices of a mesh whose vertices' input indices are `source`;
/// perimeters `perims`), whether it is filled as `holes` says. The margin is the longest loop
/// (first of equals); in the later rounds the loop through most of the first round's margin
/// (the longest, first of equals, among those). The margin is never filled.
pub(super) fn filled_loops(
    loops: &[Vec<u32>],
    perims: &[f64],
    source: &[u32],
    opts: &RepairOptions,
    holes: Holes,
) -> Vec<bool> {
    let first: Option<&[Rim]> = match &holes {
        Holes::BySize(_) => None,
        Holes::AsFirst(rims) => Some(rims),
    };
    let rim_of = |v: u32| {
        first
            .and_then(|rims| rims.get(source[v as usize] as usize))
            .copied()
            .unwrap_or(Rim::Other)
    };
    let on_margin = |l: &[u32]| l.iter().filter(|&&v| rim_of(v) == Rim::Margin).count();
    let margin = (0..loops.len()).max_by(|&a, &b| {
        on_margin(&loops[a])
            .cmp(&on_margin(&loops[b]))
            .then(perims[a].total_cmp(&perims[b]))
            .then(b.cmp(&a))
    });
    let filled: Vec<bool> = (0..loops.len())
        .map(|i| {
            let Some(mi) = margin.filter(|&mi| mi != i) else {
                return false;
            };
            match first {
                None => perims[i] <= opts.max_hole_fraction * perims[mi],
                Some(_) => !loops[i].iter().any(|&v| rim_of(v) == Rim::Open),
            }
        })
        .collect();
    if let Holes::BySize(rims) = holes {
        let n = source
            .iter()
            .filter(|&&s| s != u32::MAX)
            .max()
            .map_or(0, |&s| s as usize + 1);
        rims.clear();
        rims.resize(n, Rim::Other);
        for (i, l) in loops.iter().enumerate() {
            let rim = if Some(i) == margin {
                Rim::Margin
            } else if filled[i] {
                continue;
            } else {
                Rim::Open
            };
            for &v in l {
                rims[source[v as usize] as usize] = rim;
            }
        }
    }
    filled
}
