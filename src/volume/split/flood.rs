//! Splitting a jaw's teeth mask into teeth: seeds from the registered IOS crowns, then a
//! seeded watershed on the distance transform, run as a widest-path flood that keeps, for every
//! voxel, the best two seeds of different teeth.
//!
//! The level of a path is the smallest distance-to-background along it (its narrowest
//! passage); a voxel goes to the tooth whose seed reaches it by the widest path. Teeth touch
//! through thin contacts, so a voxel inside a tooth is reached from its own crown by a wide
//! path and from a neighbour only through a contact. Where two seeds reach a voxel at nearly
//! the same level (the runner-up's level at least `contested_ratio` of the winner's), the
//! assignment is contested: the mask gives no narrow passage to cut at.

use super::arch_fit::Sample;
use super::mask::{FACES, JawMask};
use crate::mesh::{TriMesh, boundary_loops};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::cmp::Reverse;
use std::collections::{BTreeMap, BinaryHeap};

/// Per box voxel: FDI of the crown whose solid it lies in (0 = none). A mask voxel is a seed
/// when the nearest crown vertex is not on the crown's margin, the voxel lies behind that
/// vertex's outward normal (inside the tooth) and within `depth_mm` of it.
pub(crate) fn seeds(mask: &JawMask, crowns: &BTreeMap<u8, TriMesh>, depth_mm: f64) -> Vec<u8> {
    let mut samples = Vec::new();
    let mut margin = Vec::new();
    for (&fdi, m) in crowns {
        let mut on_margin = vec![false; m.positions.len()];
        for l in boundary_loops(m) {
            for v in l {
                on_margin[v as usize] = true;
            }
        }
        for ((p, n), b) in m.positions.iter().zip(m.vertex_normals()).zip(on_margin) {
            samples.push(Sample { p: *p, n, fdi });
            margin.push(b);
        }
    }
    let mut out = vec![0u8; mask.inside.len()];
    if samples.is_empty() {
        return out;
    }
    let pts: Vec<[f64; 3]> = samples.iter().map(|s| s.p.to_array()).collect();
    let Ok(tree) = ImmutableKdTree::<f64, 3>::new_from_slice(&pts) else {
        return out;
    };
    let slab = mask.dims[0] * mask.dims[1];
    let slices: Vec<usize> = (0..mask.dims[2]).collect();
    let per_slice = crate::par::map_ordered(&slices, |&k| {
        (k * slab..(k + 1) * slab)
            .map(|id| {
                if !mask.inside[id] {
                    return 0;
                }
                let q = mask.world(id);
                let r = tree
                    .query(&q.to_array())
                    .nearest_one::<SquaredEuclidean<f64>>()
                    .execute();
                let s = samples[r.item as usize];
                let behind = (q - s.p).dot(s.n) <= 0.0;
                if !margin[r.item as usize] && behind && r.distance.sqrt() <= depth_mm {
                    s.fdi
                } else {
                    0
                }
            })
            .collect::<Vec<u8>>()
    });
    for (k, v) in per_slice.into_iter().enumerate() {
        out[k * slab..(k + 1) * slab].copy_from_slice(&v);
    }
    out
}

/// The result of the flood: per box voxel the winning and the runner-up tooth (0 = none) and
/// the levels they reach it at.
pub(crate) struct Flood {
    pub best: Vec<u8>,
    pub best_level: Vec<f32>,
    pub second: Vec<u8>,
    pub second_level: Vec<f32>,
}

/// The widest-path flood from `seeds` over the mask (face neighbours), widest first; a voxel
/// is settled twice at most, by two different teeth. Seeds have unlimited width; the level
/// of a path excludes its last voxel's own distance (so a surface voxel's level is that of the
/// tissue behind it). Ties go to the smaller voxel index: the result is deterministic.
pub(crate) fn flood(mask: &JawMask, dist: &[f32], seeds: &[u8]) -> Flood {
    let n = mask.inside.len();
    let mut f = Flood {
        best: vec![0; n],
        best_level: vec![0.0; n],
        second: vec![0; n],
        second_level: vec![0.0; n],
    };
    let mut heap: BinaryHeap<(u32, Reverse<u32>, u8)> = BinaryHeap::new();
    for (id, &s) in seeds.iter().enumerate() {
        if s != 0 {
            heap.push((f32::INFINITY.to_bits(), Reverse(id as u32), s));
        }
    }
    while let Some((bits, Reverse(id), lab)) = heap.pop() {
        let id = id as usize;
        let level = f32::from_bits(bits);
        if f.best[id] == 0 {
            f.best[id] = lab;
            f.best_level[id] = level;
        } else if f.best[id] != lab && f.second[id] == 0 {
            f.second[id] = lab;
            f.second_level[id] = level;
        } else {
            continue;
        }
        let through = if seeds[id] == lab {
            f32::INFINITY
        } else {
            level.min(dist[id])
        };
        for step in FACES {
            let u = mask.step(id, step);
            let open = f.best[u] == 0 || (f.best[u] != lab && f.second[u] == 0);
            if mask.inside[u] && open {
                heap.push((through.to_bits(), Reverse(u as u32), lab));
            }
        }
    }
    f
}

/// What the flood gave one tooth.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ToothSplit {
    /// Voxels assigned to the tooth.
    pub voxels: usize,
    /// Of them, voxels inside its registered IOS crown (seeds).
    pub seed_voxels: usize,
    /// Of them, voxels whose assignment is contested (see the module doc).
    pub contested_voxels: usize,
    /// The tooth contesting most of them, if any.
    pub contested_with: Option<u8>,
}

impl ToothSplit {
    /// Share of the tooth's voxels whose assignment is contested (0 = a clean split).
    pub fn contested_share(&self) -> f64 {
        self.contested_voxels as f64 / self.voxels.max(1) as f64
    }
}

/// Per tooth, its voxel counts (contested voxels among those off the mask surface); and the
/// number of mask voxels no seed reached.
pub(crate) fn tally(
    mask: &JawMask,
    f: &Flood,
    seeds: &[u8],
    contested_ratio: f32,
) -> (BTreeMap<u8, ToothSplit>, usize) {
    let mut teeth: BTreeMap<u8, ToothSplit> = BTreeMap::new();
    let mut rivals: BTreeMap<(u8, u8), usize> = BTreeMap::new();
    let mut unreached = 0;
    for id in 0..mask.inside.len() {
        if !mask.inside[id] {
            continue;
        }
        let a = f.best[id];
        if a == 0 {
            unreached += 1;
            continue;
        }
        let t = teeth.entry(a).or_default();
        t.voxels += 1;
        if seeds[id] == a {
            t.seed_voxels += 1;
            continue;
        }
        // A surface voxel's level is capped by the surface layer it sits in, not by the
        // tissue its label came through: judged by the voxels behind it.
        if FACES.iter().any(|&s| !mask.inside[mask.step(id, s)]) {
            continue;
        }
        let b = f.second[id];
        if b != 0 && f.second_level[id] >= contested_ratio * f.best_level[id] {
            t.contested_voxels += 1;
            *rivals.entry((a, b)).or_default() += 1;
        }
    }
    for (fdi, t) in teeth.iter_mut() {
        t.contested_with = rivals
            .range((*fdi, 0)..=(*fdi, u8::MAX))
            .max_by_key(|(k, c)| (**c, Reverse(k.1)))
            .map(|(k, _)| k.1);
    }
    (teeth, unreached)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{Frame, LabelVolume};

    /// Two boxes 10 voxels wide joined by a one-voxel bridge: seeded in each box, the flood
    /// splits at the bridge and nothing is contested; with a thick join, voxels are contested.
    fn two_boxes(bridge: usize) -> (JawMask, Vec<u8>) {
        let dims = [24, 12, 12];
        let mut labels = vec![0u16; 24 * 12 * 12];
        for k in 1..11 {
            for j in 1..11 {
                for i in 1..23 {
                    let in_box = !(11..=12).contains(&i);
                    let half = bridge / 2;
                    let in_bridge = (5 - half.min(5)..=5 + half.min(5)).contains(&j)
                        && (5 - half.min(5)..=5 + half.min(5)).contains(&k);
                    if in_box || in_bridge {
                        labels[i + 24 * (j + 12 * k)] = 4;
                    }
                }
            }
        }
        let v = LabelVolume::with_spacing(dims, [0.25; 3], [0.0; 3], Frame::Lps, labels).unwrap();
        let m = JawMask::from_volume(&v, 4).unwrap();
        let mut s = vec![0u8; m.inside.len()];
        s[m.idx(4, 6, 6)] = 41;
        s[m.idx(20, 6, 6)] = 42;
        (m, s)
    }

    #[test]
    fn flood_cuts_at_the_narrow_passage() {
        let (m, s) = two_boxes(0);
        let d = m.distance_mm();
        let f = flood(&m, &d, &s);
        assert_eq!(f.best[m.idx(2, 6, 6)], 41);
        assert_eq!(f.best[m.idx(22, 6, 6)], 42);
        assert_eq!(f.best[m.idx(10, 2, 2)], 41);
        let (teeth, unreached) = tally(&m, &f, &s, 0.8);
        assert_eq!(unreached, 0);
        assert_eq!(teeth[&41].voxels + teeth[&42].voxels, m.count());
        assert!(teeth[&41].contested_share() < 0.02, "{:?}", teeth[&41]);
        // A join as thick as the boxes: no passage to cut at, much of it contested.
        let (m, s) = two_boxes(10);
        let f = flood(&m, &m.distance_mm(), &s);
        let (teeth, _) = tally(&m, &f, &s, 0.8);
        assert!(teeth[&41].contested_share() > 0.2, "{:?}", teeth[&41]);
        assert_eq!(teeth[&41].contested_with, Some(42));
    }
}
