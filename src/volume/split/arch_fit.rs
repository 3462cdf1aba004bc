//! One rigid transform taking a jaw's IOS crowns onto that jaw's CBCT teeth mask surface. No
//! per-tooth correspondence exists (the mask has no tooth numbers), so the arches are aligned
//! first: the principal axes of the crown points against those of the mask surface, every
//! proper rotation between the two axis frames (24), with the crowns at the middle and at
//! either end of the mask along the crowns' thinnest axis (the occlusal-apical direction), each
//! start refined by a short point-to-plane ICP and ranked by the trimmed residual; the best is
//! refined by a longer ICP of crown points to the mask surface.

use crate::Rigid;
use crate::mesh::TriMesh;
use crate::register::icp::{Normal7, Pair, RobustKernel, WeightOptions, step_about, weights};
use crate::{Error, Result};
use glam::{DMat3, DVec3};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::collections::BTreeMap;

/// A crown point with its outward normal and tooth.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sample {
    pub p: DVec3,
    pub n: DVec3,
    pub fdi: u8,
}

/// Every vertex of the crowns (FDI order) with its vertex normal, thinned by a fixed stride to
/// at most `max` points.
pub(crate) fn crown_samples(crowns: &BTreeMap<u8, TriMesh>, max: usize) -> Vec<Sample> {
    let mut all = Vec::new();
    for (&fdi, m) in crowns {
        let normals = m.vertex_normals();
        for (p, n) in m.positions.iter().zip(normals) {
            all.push(Sample { p: *p, n, fdi });
        }
    }
    thin(all, max)
}

fn thin<T: Copy>(v: Vec<T>, max: usize) -> Vec<T> {
    if v.len() <= max || max == 0 {
        return v;
    }
    let stride = v.len().div_ceil(max);
    v.into_iter().step_by(stride).collect()
}

/// The mask surface prepared for closest-point queries.
pub(crate) struct Target {
    pub points: Vec<DVec3>,
    pub normals: Vec<DVec3>,
    tree: ImmutableKdTree<f64, 3>,
}

impl Target {
    /// Builds the k-d tree over the surface points.
    pub fn new(points: Vec<DVec3>, normals: Vec<DVec3>) -> Result<Target> {
        if points.len() < 100 {
            return Err(Error::MissingData(format!(
                "the teeth mask has only {} surface points: too small to be a jaw's teeth",
                points.len()
            )));
        }
        let pts: Vec<[f64; 3]> = points.iter().map(|p| p.to_array()).collect();
        let tree = ImmutableKdTree::<f64, 3>::new_from_slice(&pts)
            .map_err(|e| Error::InvalidArgument(format!("k-d tree construction failed: {e:?}")))?;
        Ok(Target {
            points,
            normals,
            tree,
        })
    }

    /// Index of and distance to the nearest surface point.
    pub fn nearest(&self, q: DVec3) -> (usize, f64) {
        let r = self
            .tree
            .query(&q.to_array())
            .nearest_one::<SquaredEuclidean<f64>>()
            .execute();
        (r.item as usize, r.distance.sqrt())
    }
}

/// The fit of one jaw's crowns to its mask, with the evidence to trust it.
#[derive(Clone, Debug)]
pub struct ArchFit {
    /// IOS frame → volume world frame.
    pub ios_to_volume: Rigid,
    /// Share of the crown points within the inlier distance of the mask surface.
    pub inlier_share: f64,
    /// RMS point-to-plane residual of the inlier points (mm).
    pub rms_mm: f64,
    /// Trimmed residual of the best start whose pose differs from the fit (more than 15° or
    /// 3 mm), over the fit's own (≥ 1; near 1 = two poses fit about as well: ambiguous).
    pub runner_up_ratio: f64,
    /// Per crown, the share of its points within the inlier distance.
    pub crown_inlier_share: BTreeMap<u8, f64>,
    /// The arch's occlusal-apical axis in the volume frame (the crowns' thinnest principal
    /// axis, registered; unit, sign arbitrary).
    pub up: DVec3,
}

/// Aligns the crowns to the target surface; `inlier_mm` is the distance below which a crown
/// point counts as lying on the mask.
pub(crate) fn fit_arch(
    crowns: &BTreeMap<u8, TriMesh>,
    target: &Target,
    inlier_mm: f64,
) -> Result<ArchFit> {
    let rough = crown_samples(crowns, 500);
    let coarse = crown_samples(crowns, 1500);
    let fine = crown_samples(crowns, 12000);
    if rough.len() < 30 {
        return Err(Error::MissingData(format!(
            "the IOS crowns have only {} points: too few to register the arch",
            rough.len()
        )));
    }
    let starts = starts(&coarse, &target.points);
    let mut tried = crate::par::map_ordered(&starts, |s| {
        let pose = icp(&rough, target, *s, 8, f64::INFINITY);
        (pose, trimmed_rms(&rough, target, &pose, 0.8))
    });
    // The most promising starts refined further, then ranked again.
    let mut order: Vec<usize> = (0..tried.len()).collect();
    order.sort_by(|&a, &b| tried[a].1.total_cmp(&tried[b].1).then(a.cmp(&b)));
    let refined = crate::par::map_ordered(&order[..4.min(order.len())], |&i| {
        let pose = icp(&coarse, target, tried[i].0, 20, 3.0);
        (i, pose, trimmed_rms(&coarse, target, &pose, 0.8))
    });
    for (i, pose, _) in &refined {
        tried[*i] = (*pose, trimmed_rms(&rough, target, pose, 0.8));
    }
    let best = refined
        .iter()
        .min_by(|a, b| a.2.total_cmp(&b.2).then(a.0.cmp(&b.0)))
        .map_or(0, |r| r.0);
    let pose = icp(&fine, target, tried[best].0, 30, 1.5).orthonormalized();
    let own = trimmed_rms(&rough, target, &pose, 0.8);
    let centre = mean(coarse.iter().map(|s| s.p));
    let runner_up = tried
        .iter()
        .filter(|(p, _)| {
            p.compose(&pose.inverse()).angle() > 15f64.to_radians()
                || (p.apply(centre) - pose.apply(centre)).length() > 3.0
        })
        .map(|t| t.1)
        .fold(f64::INFINITY, f64::min);
    let mut fit = evidence(&fine, target, pose, inlier_mm, runner_up / own.max(1e-9));
    let pts: Vec<DVec3> = coarse.iter().map(|s| s.p).collect();
    fit.up = pose.rot * principal_frame(&pts).1.z_axis;
    Ok(fit)
}

fn evidence(
    samples: &[Sample],
    target: &Target,
    pose: Rigid,
    inlier_mm: f64,
    runner_up_ratio: f64,
) -> ArchFit {
    let mut per: BTreeMap<u8, (usize, usize)> = BTreeMap::new();
    let (mut inl, mut rr) = (0usize, 0f64);
    for s in samples {
        let p = pose.apply(s.p);
        let (j, d) = target.nearest(p);
        let e = per.entry(s.fdi).or_default();
        e.1 += 1;
        if d <= inlier_mm {
            e.0 += 1;
            inl += 1;
            rr += (p - target.points[j]).dot(target.normals[j]).powi(2);
        }
    }
    ArchFit {
        ios_to_volume: pose,
        inlier_share: inl as f64 / samples.len().max(1) as f64,
        rms_mm: (rr / inl.max(1) as f64).sqrt(),
        runner_up_ratio,
        crown_inlier_share: per
            .into_iter()
            .map(|(f, (a, n))| (f, a as f64 / n.max(1) as f64))
            .collect(),
        up: DVec3::Z,
    }
}

fn mean(it: impl Iterator<Item = DVec3>) -> DVec3 {
    let (s, n) = it.fold((DVec3::ZERO, 0usize), |(s, n), p| (s + p, n + 1));
    s / n.max(1) as f64
}

/// Centroid and principal axes (columns, by decreasing variance, right-handed) of points.
fn principal_frame(points: &[DVec3]) -> (DVec3, DMat3) {
    let c = mean(points.iter().copied());
    let eig = crate::geom::scatter(points, c).symmetric_eigen();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let col = |a: usize| {
        let v = eig.eigenvectors.column(order[a]);
        DVec3::new(v[0], v[1], v[2]).normalize()
    };
    let (x, y) = (col(0), col(1));
    (c, DMat3::from_cols(x, y, x.cross(y)))
}

/// The 24 rotations that map the coordinate axes onto signed coordinate axes.
fn axis_rotations() -> Vec<DMat3> {
    let mut out = Vec::new();
    let perms = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    for p in perms {
        for signs in 0..8u32 {
            let cols: [DVec3; 3] = std::array::from_fn(|a| {
                let s = if signs >> a & 1 == 1 { -1.0 } else { 1.0 };
                DVec3::AXES[p[a]] * s
            });
            let m = DMat3::from_cols(cols[0], cols[1], cols[2]);
            if m.determinant() > 0.0 {
                out.push(m);
            }
        }
    }
    out
}

/// Start poses: each axis-frame rotation, with the crowns' centroid at the mask's centroid and
/// shifted to either end of the mask along the crowns' thinnest axis.
fn starts(samples: &[Sample], target: &[DVec3]) -> Vec<Rigid> {
    let src: Vec<DVec3> = samples.iter().map(|s| s.p).collect();
    let (cs, fs) = principal_frame(&src);
    let (ct, ft) = principal_frame(target);
    let extent = |pts: &[DVec3], c: DVec3, u: DVec3| {
        pts.iter()
            .map(|p| (*p - c).dot(u))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            })
    };
    let mut out = Vec::new();
    for m in axis_rotations() {
        let rot = ft * m * fs.transpose();
        let u = rot * fs.z_axis;
        let (s0, s1) = extent(&src, cs, fs.z_axis);
        let (t0, t1) = extent(target, ct, u);
        let slack = 0.5 * ((t1 - t0) - (s1 - s0)).max(0.0);
        for k in [-1.0, 0.0, 1.0] {
            let shift = u * (k * slack + 0.5 * (t0 + t1) - 0.5 * (s0 + s1));
            out.push(Rigid::new(rot, ct + shift - rot * cs));
        }
    }
    out
}

/// Point-to-plane ICP of the samples to the target from `pose` (Huber weights, pairs beyond
/// `max_mm` or 3 MADs of the distances, or with normals more than 60° apart, rejected).
fn icp(samples: &[Sample], target: &Target, mut pose: Rigid, iters: usize, max_mm: f64) -> Rigid {
    let opts = WeightOptions {
        kernel: RobustKernel::Huber,
        kernel_k: 1.5,
        min_scale_mm: 0.05,
        max_normal_angle_deg: Some(60.0),
        distance_mads: Some(3.0),
        max_distance_mm: max_mm,
    };
    for _ in 0..iters {
        let pairs: Vec<Pair> = samples
            .iter()
            .map(|s| {
                let p = pose.apply(s.p);
                let (j, _) = target.nearest(p);
                Pair {
                    p,
                    q: target.points[j],
                    n: target.normals[j],
                    n_other: pose.rot * s.n,
                }
            })
            .collect();
        let w = weights(&pairs, 0.0, &opts);
        let center = mean(pairs.iter().map(|p| p.p));
        let mut ne = Normal7::new();
        ne.add_pairs(&pairs, &w, center, 0.0);
        if ne.wsum < 12.0 {
            break;
        }
        let Some((rw, t, _)) = ne.solve(false) else {
            break;
        };
        pose = step_about(rw, t, center).compose(&pose);
        if t.length() + rw.length() * 20.0 < 1e-4 {
            break;
        }
    }
    pose
}

/// RMS of the smallest `keep` share of the sample-to-surface distances at `pose`.
fn trimmed_rms(samples: &[Sample], target: &Target, pose: &Rigid, keep: f64) -> f64 {
    let mut d: Vec<f64> = samples
        .iter()
        .map(|s| target.nearest(pose.apply(s.p)).1)
        .collect();
    d.sort_by(f64::total_cmp);
    let n = ((d.len() as f64 * keep) as usize).max(1);
    (d[..n].iter().map(|x| x * x).sum::<f64>() / n as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_rotations_are_the_24_proper_ones() {
        let r = axis_rotations();
        assert_eq!(r.len(), 24);
        for (i, a) in r.iter().enumerate() {
            assert!((a.determinant() - 1.0).abs() < 1e-12);
            assert!(
                r[..i]
                    .iter()
                    .all(|b| !(*a - *b).abs_diff_eq(DMat3::ZERO, 1e-9))
            );
        }
    }
}
