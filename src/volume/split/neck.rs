//! Where two teeth of a split meet, the narrowest cut of the mask between their crowns. Teeth
//! are separate solids: where a segmentation joins two of them, the join (their contact, a gap
//! the segmentation closed) is a neck of the mask, narrower than either tooth. The narrowest
//! surface that separates one crown's seeds from the other's inside the two teeth's voxels (a
//! minimum cut over voxel faces) therefore runs through that neck. A tooth's voxels beyond it,
//! on the neighbour's side, are the neighbour's: the flood ran through the contact into the
//! neighbour's root, however uncontested its paths were. This confidence does not depend on
//! the flood's costs, so it sees the errors the contested share cannot; [`hand_over`] gives
//! such voxels to the neighbour.

use super::flood::ToothSplit;
use super::mask::{FACES, JawMask};
use std::collections::{BTreeMap, BTreeSet, VecDeque};

/// No neighbour (outside the two teeth).
const NONE: u32 = u32::MAX;

/// Index of the opposite face in [`FACES`].
const fn opposite(d: usize) -> usize {
    d ^ 1
}

/// Two touching teeth's voxels as a graph: per voxel its face neighbours among them, whether it
/// is a seed of the first (source) or of the second tooth (sink), and the net flow across each
/// face (-1, 0 or 1; every face has capacity 1 both ways).
struct Pair {
    nb: Vec<[u32; 6]>,
    source: Vec<bool>,
    sink: Vec<bool>,
    flow: Vec<[i8; 6]>,
}

impl Pair {
    /// Spare capacity from voxel `v` across face `d`.
    fn spare(&self, v: usize, d: usize) -> i8 {
        1 - self.flow[v][d]
    }

    /// Breadth-first levels from the sources over faces with spare capacity; `None` once no
    /// sink can be reached (the flow is maximal).
    fn levels(&self) -> Option<Vec<u32>> {
        let n = self.nb.len();
        let mut level = vec![NONE; n];
        let mut queue: VecDeque<usize> = (0..n).filter(|&v| self.source[v]).collect();
        queue.iter().for_each(|&v| level[v] = 0);
        let mut reached = false;
        while let Some(v) = queue.pop_front() {
            if self.sink[v] {
                reached = true;
                continue;
            }
            for d in 0..6 {
                let u = self.nb[v][d];
                if u != NONE && level[u as usize] == NONE && self.spare(v, d) > 0 {
                    level[u as usize] = level[v] + 1;
                    queue.push_back(u as usize);
                }
            }
        }
        reached.then_some(level)
    }

    /// Pushes one unit along each path of the level graph from `s` to a sink until none is
    /// left (a blocking flow from `s`, Dinic's algorithm; depth-first without recursion).
    fn block(&mut self, s: usize, level: &mut [u32], next: &mut [u8]) {
        let mut path: Vec<(usize, usize)> = Vec::new();
        let mut v = s;
        loop {
            if self.sink[v] {
                for &(x, d) in &path {
                    self.flow[x][d] += 1;
                    self.flow[self.nb[x][d] as usize][opposite(d)] -= 1;
                }
                path.clear();
                v = s;
                continue;
            }
            let mut advanced = false;
            while (next[v] as usize) < 6 {
                let d = next[v] as usize;
                let u = self.nb[v][d];
                if u != NONE && level[u as usize] == level[v] + 1 && self.spare(v, d) > 0 {
                    path.push((v, d));
                    v = u as usize;
                    advanced = true;
                    break;
                }
                next[v] += 1;
            }
            if advanced {
                continue;
            }
            // A dead end: never enter it again in this phase.
            level[v] = NONE;
            match path.pop() {
                Some((x, _)) => {
                    next[x] += 1;
                    v = x;
                }
                None => return,
            }
        }
    }

    /// The maximum flow from the sources to the sinks (its value: the narrowest cut's faces).
    fn max_flow(&mut self) {
        while let Some(mut level) = self.levels() {
            let mut next = vec![0u8; self.nb.len()];
            for s in 0..self.nb.len() {
                if self.source[s] {
                    self.block(s, &mut level, &mut next);
                }
            }
        }
    }

    /// After the maximum flow, the sources' side of the narrowest cut nearest them (voxels a
    /// source still reaches over faces with spare capacity) and the sinks' side of the narrowest
    /// cut nearest them (voxels that still reach a sink): every narrowest cut leaves the first
    /// on the sources' side and the second on the sinks'.
    fn sides(&self) -> (Vec<bool>, Vec<bool>) {
        // Spare capacity from u into v across v's face d: 1 - flow(u → v) = 1 + flow(v → u).
        let from_sources = self.reach(&self.source, |v, d| self.spare(v, d) > 0);
        let to_sinks = self.reach(&self.sink, |v, d| self.flow[v][d] > -1);
        (from_sources, to_sinks)
    }

    /// Voxels reached from `start` through faces `open(v, d)` lets through.
    fn reach(&self, start: &[bool], open: impl Fn(usize, usize) -> bool) -> Vec<bool> {
        let mut seen = start.to_vec();
        let mut queue: VecDeque<usize> = (0..seen.len()).filter(|&v| seen[v]).collect();
        while let Some(v) = queue.pop_front() {
            for d in 0..6 {
                let u = self.nb[v][d];
                if u != NONE && !seen[u as usize] && open(v, d) {
                    seen[u as usize] = true;
                    queue.push_back(u as usize);
                }
            }
        }
        seen
    }
}

/// For touching teeth `a` and `b`: the voxels (box ids, ascending) of `a` beyond the narrowest
/// cut between the seeds of `a` and of `b` inside the two teeth's voxels (on `b`'s side of every
/// such cut), and those of `b` beyond it. `best`: the tooth per box voxel; `local`: a scratch
/// index per box voxel, all `NONE` (left so).
fn beyond(
    mask: &JawMask,
    best: &[u8],
    seeds: &[u8],
    (a, b): (u8, u8),
    local: &mut [u32],
) -> (Vec<usize>, Vec<usize>) {
    let ids: Vec<usize> = (0..best.len())
        .filter(|&id| mask.inside[id] && (best[id] == a || best[id] == b))
        .collect();
    for (l, &id) in ids.iter().enumerate() {
        local[id] = l as u32;
    }
    let nb = ids
        .iter()
        .map(|&id| FACES.map(|f| local[mask.step(id, f)]))
        .collect();
    for &id in &ids {
        local[id] = NONE;
    }
    let mut pair = Pair {
        nb,
        source: ids.iter().map(|&id| seeds[id] == a).collect(),
        sink: ids.iter().map(|&id| seeds[id] == b).collect(),
        flow: vec![[0; 6]; ids.len()],
    };
    if !pair.source.contains(&true) || !pair.sink.contains(&true) {
        return (Vec::new(), Vec::new());
    }
    pair.max_flow();
    let (a_side, b_side) = pair.sides();
    let held = |side: &[bool], t: u8| -> Vec<usize> {
        ids.iter()
            .zip(side)
            .filter(|(id, s)| **s && best[**id] == t)
            .map(|(id, _)| *id)
            .collect()
    };
    (held(&b_side, a), held(&a_side, b))
}

/// The pairs of teeth of `best` whose voxels share a face inside the mask, as (smaller,
/// larger) FDI numbers in ascending order.
fn touching(mask: &JawMask, best: &[u8]) -> BTreeSet<(u8, u8)> {
    let mut pairs = BTreeSet::new();
    for (id, &a) in best.iter().enumerate() {
        if a == 0 || !mask.inside[id] {
            continue;
        }
        for f in FACES {
            let u = mask.step(id, f);
            let b = best[u];
            if mask.inside[u] && b != 0 && b != a {
                pairs.insert((a.min(b), a.max(b)));
            }
        }
    }
    pairs
}

/// Per tooth and touching neighbour, keyed `(tooth, neighbour)`: the tooth's voxels (box ids,
/// ascending) beyond the narrowest cut between their crowns' seeds, on the neighbour's side.
/// Pairs with nothing beyond the cut are left out. `best`: the tooth per box voxel; `seeds`:
/// the crown seeds per box voxel.
pub(crate) fn overruns(mask: &JawMask, best: &[u8], seeds: &[u8]) -> Overruns {
    let mut out = BTreeMap::new();
    let mut local = vec![NONE; best.len()];
    for (a, b) in touching(mask, best) {
        let (in_b, in_a) = beyond(mask, best, seeds, (a, b), &mut local);
        for (key, ids) in [((a, b), in_b), ((b, a), in_a)] {
            if !ids.is_empty() {
                out.insert(key, ids);
            }
        }
    }
    out
}

/// Per `(tooth, neighbour)`, the tooth's voxels beyond the narrowest cut to the neighbour (see
/// [`overruns`]).
pub(crate) type Overruns = BTreeMap<(u8, u8), Vec<usize>>;

/// Sets each tooth's voxels beyond the narrowest cut to a touching neighbour
/// ([`ToothSplit::overrun_voxels`], summed over its neighbours, and the neighbour it overran
/// most) from `found` ([`overruns`]).
pub(crate) fn count(found: &Overruns, teeth: &mut BTreeMap<u8, ToothSplit>) {
    let mut most: BTreeMap<u8, (usize, u8)> = BTreeMap::new();
    for (&(x, y), ids) in found {
        if let Some(t) = teeth.get_mut(&x) {
            t.overrun_voxels += ids.len();
        }
        let m = most.entry(x).or_default();
        if ids.len() > m.0 {
            *m = (ids.len(), y);
        }
    }
    for (fdi, (_, y)) in most {
        if let Some(t) = teeth.get_mut(&fdi) {
            t.overrun_into = Some(y);
        }
    }
}

/// Sets each tooth's voxels beyond the narrowest cut to a touching neighbour
/// ([`ToothSplit::overrun_voxels`], summed over its neighbours, and the neighbour it overran
/// most). `best`: the tooth per box voxel; `seeds`: the crown seeds per box voxel.
#[cfg(test)]
pub(crate) fn overrun(
    mask: &JawMask,
    best: &[u8],
    seeds: &[u8],
    teeth: &mut BTreeMap<u8, ToothSplit>,
) {
    count(&overruns(mask, best, seeds), teeth);
}

/// What [`hand_over`] moved for one tooth.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Handed {
    /// Its voxels given to neighbours.
    pub given: usize,
    /// The neighbour given most, if any.
    pub to: Option<u8>,
    /// Voxels it received from neighbours.
    pub received: usize,
}

/// Gives each tooth's voxels beyond the narrowest cut to a touching neighbour (`found`, from
/// [`overruns`] on `best`) to that neighbour, in `best`: they lie on the neighbour's side of
/// every narrowest cut between the two crowns, so they join the neighbour's voxels.
/// Deterministic: the pairs are taken in ascending `(tooth, neighbour)` order, and a voxel
/// beyond the cuts to two neighbours (both say it is not the tooth's) goes to the first, the
/// lower-numbered neighbour. Returns what each tooth gave and received.
pub(crate) fn hand_over(best: &mut [u8], found: &Overruns) -> BTreeMap<u8, Handed> {
    let mut out: BTreeMap<u8, Handed> = BTreeMap::new();
    let mut to: BTreeMap<u8, (usize, u8)> = BTreeMap::new();
    for (&(x, y), ids) in found {
        let mut n = 0;
        for &id in ids {
            if best[id] == x {
                best[id] = y;
                n += 1;
            }
        }
        out.entry(x).or_default().given += n;
        out.entry(y).or_default().received += n;
        let m = to.entry(x).or_default();
        if n > m.0 {
            *m = (n, y);
        }
    }
    for (x, (n, y)) in to {
        if let Some(h) = out.get_mut(&x)
            && n > 0
        {
            h.to = Some(y);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::flood::{Growth, flood, step_costs, tally};
    use super::*;
    use crate::volume::{Frame, LabelVolume};
    use glam::DVec3;

    /// Two teeth 2.75 mm wide and 5.5 mm tall (0.25 mm voxels, up = k), tooth 41 at i 1..=11 and
    /// tooth 42 at i 14..=26, joined only by a contact 0.75 mm wide (j 4..=6) over their upper
    /// part (k 12..=20); the true tooth per box voxel (the contact split at its middle).
    fn touching() -> (JawMask, Vec<u8>) {
        let dims = [28, 12, 24];
        let mut labels = vec![0u16; dims[0] * dims[1] * dims[2]];
        let mut truth = vec![0u8; labels.len()];
        for k in 1..=22 {
            for j in 1..=10 {
                for i in 1..=26 {
                    let contact = (4..=6).contains(&j) && (12..=20).contains(&k);
                    let t = match i {
                        1..=12 if i <= 11 || contact => 41,
                        13..=26 if i >= 14 || contact => 42,
                        _ => 0,
                    };
                    let id = i + dims[0] * (j + dims[1] * k);
                    labels[id] = if t == 0 { 0 } else { 4 };
                    truth[id] = t;
                }
            }
        }
        let v = LabelVolume::with_spacing(dims, [0.25; 3], [0.0; 3], Frame::Lps, labels).unwrap();
        (JawMask::from_volume(&v, 4).unwrap(), truth)
    }

    /// Crown seeds on [`touching`]: the whole top of 41, and only the far end of 42's top (42's
    /// crown is reached from 41 through the contact before 42's own paths get there).
    fn seeds_through_contact(m: &JawMask) -> Vec<u8> {
        let mut seeds = vec![0u8; m.inside.len()];
        for j in 1..=10 {
            for i in 1..=11 {
                seeds[m.idx(i, j, 22)] = 41;
            }
            for i in 23..=26 {
                seeds[m.idx(i, j, 22)] = 42;
            }
        }
        seeds
    }

    #[test]
    fn a_flood_through_a_contact_into_the_neighbour_is_beyond_the_narrowest_cut() {
        let (m, truth) = touching();
        let seeds = seeds_through_contact(&m);
        let growth = vec![Growth::plain(step_costs(&m, DVec3::Z, 3.0)); 256];
        let f = flood(&m, &growth, &seeds);
        let none = vec![false; m.inside.len()];
        let (mut teeth, _) = tally(&m, &f.best, &f, &seeds, &none, 1.0);
        let wrong = (0..truth.len())
            .filter(|&id| f.best[id] == 41 && truth[id] == 42)
            .count();
        let t41 = &teeth[&41];
        let wrong_share = wrong as f64 / t41.voxels as f64;
        eprintln!(
            "41 holds {wrong} voxels of 42 ({:.1}%), {:.1}% contested",
            100.0 * wrong_share,
            100.0 * t41.contested_share()
        );
        // The flood ran into 42 by a good share of 41's voxels, and its paths there are so much
        // shorter than 42's that few of them are contested.
        assert!(wrong_share > 0.15, "{wrong} of {t41:?}");
        assert!(t41.contested_share() < 0.5 * wrong_share, "{t41:?}");
        let limit = super::super::SplitOptions::default().max_contested_share;
        assert!(t41.contested_share() < limit, "{t41:?}");
        overrun(&m, &f.best, &seeds, &mut teeth);
        // The narrowest cut is the contact (27 faces; a cut across 42 would need 220): every
        // voxel 41 holds of 42 beyond the contact lies beyond it (the contact's own voxels lie
        // on either side of a narrowest cut), and none of 42's.
        let past_contact = (0..truth.len())
            .filter(|&id| f.best[id] == 41 && m.ijk(id)[0] >= 14)
            .count();
        assert!(past_contact + 27 >= wrong, "{past_contact} {wrong}");
        assert_eq!(teeth[&41].overrun_voxels, past_contact);
        eprintln!(
            "41: {:.1}% beyond the narrowest cut",
            100.0 * teeth[&41].overrun_share()
        );
        assert_eq!(teeth[&41].overrun_into, Some(42));
        assert_eq!(teeth[&42].overrun_voxels, 0);
        // The same with the teeth's numbers swapped (the overrunning tooth is then the pair's
        // second, whose side is found from the other end of the flow).
        let swap =
            |v: &[u8]| -> Vec<u8> { v.iter().map(|&l| if l == 0 { 0 } else { 83 - l }).collect() };
        let (best_sw, seeds_sw) = (swap(&f.best), swap(&seeds));
        let (mut swapped, _) = tally(&m, &best_sw, &f, &seeds_sw, &none, 1.0);
        overrun(&m, &best_sw, &seeds_sw, &mut swapped);
        assert_eq!(swapped[&42].overrun_voxels, past_contact);
        assert_eq!(swapped[&42].overrun_into, Some(41));
        assert_eq!(swapped[&41].overrun_voxels, 0);
        // The true split overruns nothing.
        let (mut right, _) = tally(&m, &truth, &f, &seeds, &none, 1.0);
        overrun(&m, &truth, &seeds, &mut right);
        assert!(right.values().all(|t| t.overrun_voxels == 0), "{right:?}");
    }

    #[test]
    fn voxels_beyond_the_narrowest_cut_are_handed_to_the_neighbour() {
        let (m, truth) = touching();
        let seeds = seeds_through_contact(&m);
        let growth = vec![Growth::plain(step_costs(&m, DVec3::Z, 3.0)); 256];
        let mut best = flood(&m, &growth, &seeds).best;
        let wrong = |best: &[u8]| {
            (0..truth.len())
                .filter(|&id| best[id] != 0 && best[id] != truth[id])
                .count()
        };
        let before = wrong(&best);
        let found = overruns(&m, &best, &seeds);
        assert_eq!(found.keys().copied().collect::<Vec<_>>(), [(41, 42)]);
        let crossed: Vec<usize> = (0..best.len())
            .filter(|&id| best[id] == 41 && m.ijk(id)[0] >= 14)
            .collect();
        let handed = hand_over(&mut best, &found);
        // Every voxel 41 took past the contact is 42's again, and nothing else moved.
        assert_eq!(crossed.len(), 644);
        assert!(crossed.iter().all(|&id| best[id] == 42));
        assert_eq!(handed[&41].given, found[&(41, 42)].len());
        assert_eq!(handed[&41].to, Some(42));
        assert_eq!(handed[&42].received, handed[&41].given);
        assert_eq!(handed[&42].given, 0);
        // What is left wrong lies in the contact, whose 27 voxels may sit on either side of a
        // narrowest cut (measured: 671 voxels of another tooth as flooded, the 27 of the
        // contact's half on 42's side after).
        let after = wrong(&best);
        eprintln!("wrong voxels: {before} as flooded, {after} handed over");
        assert_eq!((before, after), (671, 27));
        // Nothing lies beyond a cut any more.
        assert!(overruns(&m, &best, &seeds).is_empty());
    }
}
