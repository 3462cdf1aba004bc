//! Splitting a jaw's teeth mask into teeth: seeds from the registered IOS crowns (the mask
//! voxels inside each crown), then every other mask voxel goes to the crown it is nearest to
//! along paths inside the mask, with sideways steps (across the arch's occlusal-apical axis)
//! costing `lateral_weight` times their length: a root hangs under its crown, and two teeth
//! meet only where the mask joins them. Later floods also make steps dearer far from the
//! tooth's long-axis line ([`Growth`]), so that a tooth that reaches a neighbour through a
//! contact does not run down the neighbour's root. The plain flood keeps, for every voxel, the
//! best two crowns; a voxel whose two paths there are within `margin` mm of each other is
//! contested (the mask and the crowns do not tell which tooth it belongs to).

use super::arch_fit::Sample;
use super::mask::{FACES, JawMask};
use crate::mesh::{TriMesh, boundary_loops};
use glam::{DMat3, DVec3};
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

/// The long axis of a registered crown: from the centroid of its margin to the centroid of its
/// vertices (a root continues the crown along it); `fallback` when the crown has no margin or
/// the axis leans more than 45° from it.
pub(crate) fn crown_axis(m: &TriMesh, fallback: DVec3) -> DVec3 {
    let margin: Vec<DVec3> = boundary_loops(m)
        .into_iter()
        .flatten()
        .map(|v| m.positions[v as usize])
        .collect();
    let (Some(c), Some(cm)) = (
        crate::geom::centroid(&m.positions),
        crate::geom::centroid(&margin),
    ) else {
        return fallback;
    };
    let axis = (c - cm).normalize_or_zero();
    let fallback = fallback.normalize_or_zero();
    if axis.dot(fallback).abs() < std::f64::consts::FRAC_1_SQRT_2 {
        fallback
    } else {
        axis
    }
}

/// The result of the flood: per box voxel the nearest and the runner-up tooth (0 = none) and
/// their path costs (mm).
pub(crate) struct Flood {
    pub best: Vec<u8>,
    pub best_cost: Vec<f32>,
    pub second: Vec<u8>,
    pub second_cost: Vec<f32>,
}

/// Cost (mm) of a step to each face neighbour: its length with the part across `up` scaled by
/// `lateral_weight` (roots run roughly along the occlusal-apical axis under their crowns, so a
/// path that moves sideways is a path into another tooth).
pub(crate) fn step_costs(mask: &JawMask, up: DVec3, lateral_weight: f64) -> [f32; 6] {
    let lin = DMat3::from_mat4(mask.to_world);
    let up = up.normalize_or_zero();
    FACES.map(|f| {
        let e = lin * DVec3::new(f[0] as f64, f[1] as f64, f[2] as f64);
        let v = e.dot(up);
        let lat = (e.length_squared() - v * v).max(0.0).sqrt();
        (v * v + (lateral_weight * lat).powi(2)).sqrt() as f32
    })
}

/// How a tooth's flood grows: the cost of a step to each face neighbour (see [`step_costs`]),
/// scaled at the voxel stepped to by `1 + axis_weight·(d / radius)²`, `d` the voxel's distance
/// from the tooth's long-axis line and `radius` the tooth's RMS distance from it (both from the
/// previous flood's tooth): a root lies along its tooth's axis, so a path that runs
/// along a neighbour's root, far from its own axis, costs more than the neighbour's own path
/// there.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Growth {
    /// Step costs to the six face neighbours (mm).
    pub steps: [f32; 6],
    /// A point on the long-axis line (world mm).
    pub point: DVec3,
    /// The line's unit direction (zero: no axis prior).
    pub axis: DVec3,
    /// Squared-distance scale: `axis_weight / radius²` (0: no axis prior).
    pub scale: f64,
}

impl Growth {
    /// Plain step costs, without an axis prior.
    pub fn plain(steps: [f32; 6]) -> Growth {
        Growth {
            steps,
            point: DVec3::ZERO,
            axis: DVec3::ZERO,
            scale: 0.0,
        }
    }

    /// Step costs with the axis prior of a tooth whose voxels (world mm) are `pts`: the line
    /// through their centroid along their principal axis, or along `axis` (the crown's long
    /// axis) when the principal axis leans more than 45° from it; weighted by `axis_weight`
    /// (0 disables the prior).
    pub fn of_tooth(steps: [f32; 6], pts: &[DVec3], axis: DVec3, axis_weight: f64) -> Growth {
        let Some((point, pca)) = crate::geom::principal_axis(pts) else {
            return Growth::plain(steps);
        };
        let axis = axis.normalize_or_zero();
        let along = if pca.dot(axis).abs() < std::f64::consts::FRAC_1_SQRT_2 {
            axis
        } else {
            pca
        };
        let mut g = Growth {
            steps,
            point,
            axis: along,
            scale: 0.0,
        };
        let r2 = pts.iter().map(|p| g.dist2(*p)).sum::<f64>() / pts.len() as f64;
        if r2 > 1e-6 && along != DVec3::ZERO {
            g.scale = axis_weight / r2;
        }
        g
    }

    /// Squared distance of `p` from the axis line.
    fn dist2(&self, p: DVec3) -> f64 {
        let d = p - self.point;
        let v = d.dot(self.axis);
        (d.length_squared() - v * v).max(0.0)
    }

    /// The cost multiplier at world point `p`.
    fn factor(&self, p: DVec3) -> f32 {
        if self.scale == 0.0 {
            1.0
        } else {
            (1.0 + self.scale * self.dist2(p)) as f32
        }
    }
}

/// The in-mask shortest-path flood from `seeds` (face neighbours, step costs `growth[tooth]`,
/// cheapest first); a voxel is settled twice at most, by two different teeth. Ties go to the
/// smaller voxel index: the result is deterministic.
pub(crate) fn flood(mask: &JawMask, growth: &[Growth], seeds: &[u8]) -> Flood {
    let n = mask.inside.len();
    let mut f = Flood {
        best: vec![0; n],
        best_cost: vec![0.0; n],
        second: vec![0; n],
        second_cost: vec![0.0; n],
    };
    let mut heap: BinaryHeap<Reverse<(u32, u32, u8)>> = BinaryHeap::new();
    for (id, &s) in seeds.iter().enumerate() {
        if s != 0 {
            heap.push(Reverse((0f32.to_bits(), id as u32, s)));
        }
    }
    while let Some(Reverse((bits, id, lab))) = heap.pop() {
        let id = id as usize;
        let cost = f32::from_bits(bits);
        if f.best[id] == 0 {
            f.best[id] = lab;
            f.best_cost[id] = cost;
        } else if f.best[id] != lab && f.second[id] == 0 {
            f.second[id] = lab;
            f.second_cost[id] = cost;
        } else {
            continue;
        }
        let g = &growth[lab as usize];
        for (step, c) in FACES.iter().zip(&g.steps) {
            let u = mask.step(id, *step);
            let open = f.best[u] == 0 || (f.best[u] != lab && f.second[u] == 0);
            if mask.inside[u] && open {
                let c = c * g.factor(mask.world(u));
                heap.push(Reverse(((cost + c).to_bits(), u as u32, lab)));
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
    /// Of them, voxels the long-axis prior moved to this tooth from the tooth the plain flood
    /// gave them.
    pub moved_voxels: usize,
    /// The tooth contesting most of them, if any.
    pub contested_with: Option<u8>,
    /// Of them, voxels not under its crown (farther across the occlusal-apical axis than the
    /// footprint allowance from every crown vertex).
    pub outside_voxels: usize,
    /// Faces of its voxels on its boundary: to a voxel outside the mask or of another tooth.
    pub boundary_faces: usize,
    /// Of them, faces to a voxel of another tooth: boundary the split drew, not the mask.
    pub interface_faces: usize,
    /// Of its voxels, those beyond the narrowest cut of the mask between its crown and a
    /// touching neighbour's (on the neighbour's side of it; see `neck`), summed over its
    /// neighbours: voxels of the neighbour its flood ran into.
    pub overrun_voxels: usize,
    /// The neighbour it overran most, if any.
    pub overrun_into: Option<u8>,
    /// Voxels its flood took beyond the narrowest cut to a neighbour that were handed to that
    /// neighbour (see `neck::hand_over`; not counted in `voxels`).
    pub handed_over_voxels: usize,
    /// The neighbour handed most of them, if any.
    pub handed_over_to: Option<u8>,
    /// Voxels handed to it by neighbours whose floods ran beyond the narrowest cut into it
    /// (counted in `voxels`).
    pub received_voxels: usize,
}

impl ToothSplit {
    /// Share of the tooth's voxels whose assignment is contested (0 = a clean split).
    pub fn contested_share(&self) -> f64 {
        self.contested_voxels as f64 / self.voxels.max(1) as f64
    }

    /// Share of the tooth's voxels not under its crown.
    pub fn outside_share(&self) -> f64 {
        self.outside_voxels as f64 / self.voxels.max(1) as f64
    }

    /// Share of the tooth's voxels the long-axis prior moved to it.
    pub fn moved_share(&self) -> f64 {
        self.moved_voxels as f64 / self.voxels.max(1) as f64
    }

    /// Share of the tooth's voxels beyond the narrowest cut to a neighbour (0 = the split's
    /// boundaries run through the necks where the mask joins the teeth).
    pub fn overrun_share(&self) -> f64 {
        self.overrun_voxels as f64 / self.voxels.max(1) as f64
    }

    /// Share of the voxels its flood gave the tooth that were handed to a neighbour (beyond the
    /// narrowest cut to it).
    pub fn handed_over_share(&self) -> f64 {
        let flooded = (self.voxels + self.handed_over_voxels).saturating_sub(self.received_voxels);
        self.handed_over_voxels as f64 / flooded.max(1) as f64
    }

    /// Share of the tooth's boundary drawn by the split (faces to another tooth's voxels)
    /// rather than by the mask: where the teeth touch, the split's boundary is a guess the mask
    /// cannot confirm, however uncontested the flood was.
    pub fn interface_share(&self) -> f64 {
        self.interface_faces as f64 / self.boundary_faces.max(1) as f64
    }
}

/// Per box voxel, true when it lies more than `limit_mm` across `up` (horizontally) from
/// every vertex of the crown of the tooth `best` gave it: mask not under its crown, such as a
/// CBCT tooth without an IOS crown joined to a neighbour.
pub(crate) fn outside_footprint(
    mask: &JawMask,
    best: &[u8],
    crowns: &BTreeMap<u8, TriMesh>,
    up: DVec3,
    limit_mm: f64,
) -> Vec<bool> {
    let up = up.normalize_or_zero();
    let flat = |p: DVec3| p - up * p.dot(up);
    let trees: BTreeMap<u8, ImmutableKdTree<f64, 3>> = crowns
        .iter()
        .filter_map(|(f, m)| {
            let pts: Vec<[f64; 3]> = m.positions.iter().map(|p| flat(*p).to_array()).collect();
            ImmutableKdTree::<f64, 3>::new_from_slice(&pts)
                .ok()
                .map(|t| (*f, t))
        })
        .collect();
    let slab = mask.dims[0] * mask.dims[1];
    let slices: Vec<usize> = (0..mask.dims[2]).collect();
    crate::par::map_ordered(&slices, |&k| {
        (k * slab..(k + 1) * slab)
            .map(|id| {
                let Some(tree) = trees.get(&best[id]) else {
                    return false;
                };
                let q = flat(mask.world(id)).to_array();
                let d = tree
                    .query(&q)
                    .nearest_one::<SquaredEuclidean<f64>>()
                    .execute();
                d.distance > limit_mm * limit_mm
            })
            .collect::<Vec<bool>>()
    })
    .concat()
}

/// Per tooth, its voxel counts; and the number of mask voxels no seed reached. `best` is the
/// final assignment, `plain` the flood without the long-axis prior (whose path costs are mm): a
/// voxel is contested when that flood ranks its tooth first or second and the two paths are
/// within `margin_mm` of each other; it is moved when that flood gave it another tooth.
pub(crate) fn tally(
    mask: &JawMask,
    best: &[u8],
    plain: &Flood,
    seeds: &[u8],
    outside: &[bool],
    margin_mm: f32,
) -> (BTreeMap<u8, ToothSplit>, usize) {
    let mut teeth: BTreeMap<u8, ToothSplit> = BTreeMap::new();
    let mut rivals: BTreeMap<(u8, u8), usize> = BTreeMap::new();
    let mut unreached = 0;
    for (id, (&inside, &a)) in mask.inside.iter().zip(best).enumerate() {
        if !inside {
            continue;
        }
        if a == 0 {
            unreached += 1;
            continue;
        }
        let t = teeth.entry(a).or_default();
        t.voxels += 1;
        t.outside_voxels += outside[id] as usize;
        for step in FACES {
            let u = mask.step(id, step);
            let other = mask.inside[u] && best[u] != a && best[u] != 0;
            t.boundary_faces += (!mask.inside[u] || other) as usize;
            t.interface_faces += other as usize;
        }
        if seeds[id] == a {
            t.seed_voxels += 1;
            continue;
        }
        t.moved_voxels += (plain.best[id] != a) as usize;
        let rival = if plain.best[id] == a {
            plain.second[id]
        } else {
            plain.best[id]
        };
        let close = plain.second_cost[id] - plain.best_cost[id] <= margin_mm;
        let ranked = plain.best[id] == a || plain.second[id] == a;
        if plain.second[id] == 0 || !close || !ranked {
            continue;
        }
        t.contested_voxels += 1;
        *rivals.entry((a, rival)).or_default() += 1;
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

    /// Two boxes 10 voxels wide side by side along i (up = k), joined by a bridge `bridge`
    /// voxels across; seeded at the top of each box.
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
        for j in 2..10 {
            s[m.idx(5, j, 10)] = 41;
            s[m.idx(18, j, 10)] = 42;
        }
        (m, s)
    }

    #[test]
    fn flood_follows_the_up_axis_and_flags_ties() {
        let (m, s) = two_boxes(0);
        let c1 = step_costs(&m, DVec3::Z, 3.0);
        assert_eq!(c1[4], 0.25);
        assert!((c1[0] - 0.75).abs() < 1e-6);
        let c = vec![Growth::plain(c1); 256];
        let f = flood(&m, &c, &s);
        assert_eq!(f.best[m.idx(2, 6, 1)], 41);
        assert_eq!(f.best[m.idx(22, 6, 1)], 42);
        // The bridge voxel on 41's side is 41's.
        assert_eq!(f.best[m.idx(11, 5, 5)], 41);
        let none = vec![false; m.inside.len()];
        let (teeth, unreached) = tally(&m, &f.best, &f, &s, &none, 1.0);
        assert_eq!(unreached, 0);
        assert_eq!(teeth[&41].voxels + teeth[&42].voxels, m.count());
        assert!(teeth[&41].contested_share() < 0.02, "{:?}", teeth[&41]);
        // One solid block seeded at both ends of its top: the middle is contested.
        let (m, s) = two_boxes(10);
        let f = flood(&m, &c, &s);
        let (teeth, _) = tally(&m, &f.best, &f, &s, &none, 1.0);
        let share = teeth[&41].contested_share();
        assert!(share > 0.03 && share < 0.3, "{:?}", teeth[&41]);
        assert_eq!(teeth[&41].contested_with, Some(42));
    }
}
