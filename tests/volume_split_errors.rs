//! The per-jaw teeth mask split (DentalSegmentator style) under the CBCT surface errors real
//! segmentations carry, on the real-anatomy phantom made from the STS 2024 mask
//! (../shared/data/real): the mask grown or shrunk by a voxel, smoothly warped, streaked by
//! metal, and all of it at once, each split by the IOS and fused; the split is measured against
//! the mask's own tooth labels (Dice) and the fusion against the truth (TRE), next to the
//! per-tooth volume path. Skipped with a message when the real data is absent.

mod real_data;
mod split_support;

use glam::{DMat4, DVec3};
use split_support::{dice, dilate, fuse_gated, lower, surfaced};
use std::collections::BTreeMap;
use toothfuse::phantom::Phantom;
use toothfuse::phantom::rng::Rng;
use toothfuse::volume::{LabelVolume, SplitOptions, split_teeth};

/// The volume with `n` background voxels added on every side (every voxel keeps its world
/// position), room for the surface errors below to grow the teeth.
fn padded(v: &LabelVolume, n: usize) -> LabelVolume {
    let d = v.dims.map(|x| x + 2 * n);
    let mut labels = vec![0u16; d[0] * d[1] * d[2]];
    for k in 0..v.dims[2] {
        for j in 0..v.dims[1] {
            let src = v.idx(0, j, k);
            let dst = n + d[0] * (j + n + d[1] * (k + n));
            labels[dst..dst + v.dims[0]].copy_from_slice(&v.labels[src..src + v.dims[0]]);
        }
    }
    let shift = DMat4::from_translation(DVec3::splat(-(n as f64)));
    LabelVolume::new(d, v.voxel_to_world * shift, v.frame, labels).unwrap()
}

/// Every tooth voxel with a background face neighbour removed: a segmentation threshold biased
/// inwards by one voxel (0.25 mm). Contacts between teeth are kept.
fn erode(v: &LabelVolume) -> LabelVolume {
    let mut out = v.clone();
    let [nx, ny, nz] = v.dims;
    for k in 1..nz - 1 {
        for j in 1..ny - 1 {
            for i in 1..nx - 1 {
                let id = v.idx(i, j, k);
                let nb = [id - 1, id + 1, id - nx, id + nx, id - nx * ny, id + nx * ny];
                if v.labels[id] != 0 && nb.iter().any(|&u| v.labels[u] == 0) {
                    out.labels[id] = 0;
                }
            }
        }
    }
    out
}

/// A smooth displacement field (mm) over the volume's world: along each world axis one plane
/// wave of amplitude `amp_mm`, random direction, wavelength 30–45 mm (the lower arch spans about
/// 50 mm) and phase: a CBCT's low-frequency geometric distortion, not a rigid motion.
struct Warp {
    waves: [(DVec3, f64, f64); 3],
    amp_mm: f64,
}

impl Warp {
    fn new(seed: u64, amp_mm: f64) -> Warp {
        let mut rng = Rng::new(seed);
        let waves = std::array::from_fn(|_| {
            let k = rng.unit_vector();
            let lambda = rng.range(30.0, 45.0);
            let phase = rng.range(0.0, std::f64::consts::TAU);
            (k, lambda, phase)
        });
        Warp { waves, amp_mm }
    }

    fn at(&self, x: DVec3) -> DVec3 {
        let c = |(k, lambda, phase): (DVec3, f64, f64)| {
            self.amp_mm * (std::f64::consts::TAU * k.dot(x) / lambda + phase).sin()
        };
        DVec3::new(c(self.waves[0]), c(self.waves[1]), c(self.waves[2]))
    }

    /// The volume resampled through the field (nearest label): the label at `x` is the one
    /// at `x - d(x)`, so the teeth move by about `d`.
    fn apply(&self, v: &LabelVolume) -> LabelVolume {
        let inv = v.voxel_to_world.inverse();
        let [nx, ny, _] = v.dims;
        let mut out = v.clone();
        for (id, l) in out.labels.iter_mut().enumerate() {
            let ijk = DVec3::new(
                (id % nx) as f64,
                ((id / nx) % ny) as f64,
                (id / (nx * ny)) as f64,
            );
            let x = v.world(ijk);
            let s = inv.transform_point3(x - self.at(x)).round();
            let inside = (0..3).all(|a| s[a] >= 0.0 && (s[a] as usize) < v.dims[a]);
            *l = if inside {
                v.labels[v.idx(s.x as usize, s.y as usize, s.z as usize)]
            } else {
                0
            };
        }
        out
    }

    /// Over the tooth voxels of `v`: the RMS and largest displacement, and the RMS of what a
    /// rigid motion leaves of it (least squares, small angles), in mm.
    fn measure(&self, v: &LabelVolume) -> (f64, f64, f64) {
        let [nx, ny, _] = v.dims;
        let pts: Vec<DVec3> = (0..v.labels.len())
            .filter(|&id| v.labels[id] != 0)
            .step_by(7)
            .map(|id| {
                v.world(DVec3::new(
                    (id % nx) as f64,
                    ((id / nx) % ny) as f64,
                    (id / (nx * ny)) as f64,
                ))
            })
            .collect();
        let c = pts.iter().copied().sum::<DVec3>() / pts.len() as f64;
        // d(x) ≈ t + w × (x - c): rows [I | -[r]×] per point.
        let mut ata = nalgebra::SMatrix::<f64, 6, 6>::zeros();
        let mut atb = nalgebra::SVector::<f64, 6>::zeros();
        let rows = |r: DVec3| -> [[f64; 6]; 3] {
            [
                [1.0, 0.0, 0.0, 0.0, r.z, -r.y],
                [0.0, 1.0, 0.0, -r.z, 0.0, r.x],
                [0.0, 0.0, 1.0, r.y, -r.x, 0.0],
            ]
        };
        for &p in &pts {
            let d = self.at(p);
            for (a, row) in rows(p - c).iter().enumerate() {
                let row = nalgebra::SVector::<f64, 6>::from_row_slice(row);
                ata += row * row.transpose();
                atb += row * d[a];
            }
        }
        let sol = ata.cholesky().expect("rigid fit").solve(&atb);
        let (mut all, mut max, mut rest) = (0.0, 0f64, 0.0);
        for &p in &pts {
            let d = self.at(p);
            let r = p - c;
            let fit =
                DVec3::new(sol[0], sol[1], sol[2]) + DVec3::new(sol[3], sol[4], sol[5]).cross(r);
            all += d.length_squared();
            max = max.max(d.length());
            rest += (d - fit).length_squared();
        }
        let n = pts.len() as f64;
        ((all / n).sqrt(), max, (rest / n).sqrt())
    }
}

/// Metal streaks through the crowns of `teeth`: `per_tooth` thin slabs (0.5 mm thick along the
/// arch's occlusal direction, 0.5 mm wide, 16 mm long, in the axial plane 2 mm below the crown's
/// top, through the crown's centre there, at evenly spread angles) in which every voxel is
/// flipped: tooth voxels (of any tooth) become background, background voxels become the
/// streaked tooth (slots through the crown, spurs out of it, bridges to its neighbours).
fn streaked(v: &LabelVolume, p: &Phantom, teeth: &[u8], per_tooth: usize) -> LabelVolume {
    let w2c = p.truth.world_to_cbct;
    // The arch's occlusal direction: the mean of the teeth's true long axes.
    let up = w2c
        .apply_vector(p.truth.teeth.values().map(|t| t.axis).sum::<DVec3>())
        .normalize();
    let mut out = v.clone();
    let [nx, ny, _] = v.dims;
    for &fdi in teeth {
        let surface: Vec<DVec3> = p.truth.teeth[&fdi]
            .surface
            .positions
            .iter()
            .map(|&q| w2c.apply(q))
            .collect();
        let top = surface.iter().map(|q| q.dot(up)).fold(f64::MIN, f64::max);
        let ring: Vec<DVec3> = surface
            .iter()
            .copied()
            .filter(|q| (q.dot(up) - (top - 2.0)).abs() < 0.5)
            .collect();
        let centre = ring.iter().copied().sum::<DVec3>() / ring.len() as f64;
        let e1 = up.any_orthonormal_vector();
        let e2 = up.cross(e1);
        for s in 0..per_tooth {
            let a = std::f64::consts::PI * (s as f64 + 0.5) / per_tooth as f64;
            let along = e1 * a.cos() + e2 * a.sin();
            let across = up.cross(along);
            for (id, l) in out.labels.iter_mut().enumerate() {
                let ijk = DVec3::new(
                    (id % nx) as f64,
                    ((id / nx) % ny) as f64,
                    (id / (nx * ny)) as f64,
                );
                let r = v.world(ijk) - centre;
                if r.dot(up).abs() <= 0.25
                    && r.dot(across).abs() <= 0.25
                    && r.dot(along).abs() <= 8.0
                {
                    *l = if *l == 0 { fdi as u16 } else { 0 };
                }
            }
        }
    }
    out
}

/// What the split and the fusion give on a per-tooth volume degraded by a CBCT surface error,
/// merged into one lower-teeth class.
struct Degraded {
    inlier_share: f64,
    rms_mm: f64,
    runner_up_ratio: f64,
    refused: Vec<(u8, String)>,
    dice: BTreeMap<u16, f64>,
    tre_split: f64,
    tre_tooth: f64,
    n_fused: usize,
    watertight: bool,
    /// The registration gate's mismatch score, the larger of the split's and the per-tooth
    /// volume's.
    mismatch: f64,
    /// The CBCT surface offset the gate estimated on the split (mm, positive when larger).
    offset_mm: f64,
}

fn split_degraded(p: &Phantom, truth: &LabelVolume, what: &str) -> Degraded {
    let merged = truth.relabeled(|l| if l != 0 { 4 } else { 0 });
    let split = split_teeth(&merged, &p.ios_crowns(), &SplitOptions::default())
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    let fit = &split.jaws[0].fit;
    for line in split.summary() {
        eprintln!("{what}: {line}");
    }
    let tooth = fuse_gated(p, surfaced(truth), &format!("{what}, per tooth"));
    let split_fused = fuse_gated(p, surfaced(&split.volume), &format!("{what}, split"));
    let d = Degraded {
        inlier_share: fit.inlier_share,
        rms_mm: fit.rms_mm,
        runner_up_ratio: fit.runner_up_ratio,
        refused: split.refused(),
        dice: dice(&split.volume, truth),
        tre_split: split_fused.0.0,
        tre_tooth: tooth.0.0,
        n_fused: split_fused.0.1,
        watertight: tooth.0.2 && split_fused.0.2,
        mismatch: split_fused.1.mismatch.max(tooth.1.mismatch),
        offset_mm: split_fused.1.surface_offset_mm,
    };
    let dmin = d.dice.values().copied().fold(1.0, f64::min);
    let dmean = d.dice.values().sum::<f64>() / d.dice.len().max(1) as f64;
    eprintln!(
        "{what}: arch fit {:.1}% inliers, RMS {:.3} mm, runner-up {:.2}; {} refused; Dice \
         {dmin:.4}-1 (mean {dmean:.4}) over {} teeth; mean TRE split {:.3} mm, per-tooth {:.3} \
         mm, {} fused, watertight {}; gate mismatch {:.2}, offset {:+.3} mm",
        100.0 * d.inlier_share,
        d.rms_mm,
        d.runner_up_ratio,
        d.refused.len(),
        d.dice.len(),
        d.tre_split,
        d.tre_tooth,
        d.n_fused,
        d.watertight,
        d.mismatch,
        d.offset_mm
    );
    d
}

/// Measured on one degraded mask: arch fit RMS (mm) and runner-up ratio, the lowest and mean
/// Dice, the fused mean TRE (mm) from the split, the registration gate's largest mismatch score
/// and its CBCT surface offset (mm).
struct Expected {
    rms_mm: f64,
    runner_up: f64,
    dice_min: f64,
    dice_mean: f64,
    tre_mm: f64,
    mismatch: f64,
    offset_mm: f64,
}

/// The split's arch fit thresholds (85 % inliers, 0.4 mm RMS, runner-up 1.5×) were set on masks
/// whose surface is the very truth the IOS is simulated from (RMS 0.05 mm). A real CBCT
/// segmentation's surface is off the true tooth by 0.2-0.3 mm: here the threshold biased by one
/// voxel either way (0.25 mm along the grid axes, 0.20-0.23 mm mean surface distance to the
/// truth), a smooth distortion (0.20 mm RMS, 0.29 mm largest over the teeth, 0.16 mm RMS beyond
/// a rigid motion), metal streaks through the crowns of 36 and 37, and the three together. The
/// truth of the split's Dice is the per-tooth volume degraded the same way; the TRE is against
/// the undegraded truth (the distortion moves each tooth, which no registration can undo).
#[test]
fn realistic_cbct_surface_errors_are_split_and_fused() {
    let Some((p, placed)) = lower() else { return };
    let base = padded(&placed, 4);
    let warp = Warp::new(17, 0.17);
    let (rms, max, non_rigid) = warp.measure(&base);
    eprintln!(
        "warp over the teeth: RMS {rms:.3} mm, max {max:.3} mm, {non_rigid:.3} mm RMS beyond a \
         rigid motion"
    );
    assert!((rms - 0.201).abs() < 0.001 && (max - 0.290).abs() < 0.001);
    assert!((non_rigid - 0.160).abs() < 0.001);
    let streak = |v: &LabelVolume| streaked(v, &p, &[36, 37], 3);
    let e = |rms_mm, runner_up, dice_min, dice_mean, tre_mm, mismatch, offset_mm| Expected {
        rms_mm,
        runner_up,
        dice_min,
        dice_mean,
        tre_mm,
        mismatch,
        offset_mm,
    };
    // Measured (mask as segmented: RMS 0.051 mm, runner-up 5.88, Dice 0.9998, TRE 0.030 mm).
    let cases: Vec<(&str, LabelVolume, Expected)> = vec![
        (
            "grown 1 voxel",
            dilate(&base, 1),
            e(0.148, 3.84, 0.9963, 0.9985, 0.045, 1.44, 0.210),
        ),
        (
            "shrunk 1 voxel",
            erode(&base),
            e(0.138, 4.22, 0.9999, 1.0, 0.032, 1.43, -0.223),
        ),
        (
            "warped",
            warp.apply(&base),
            e(0.116, 3.67, 0.9998, 1.0, 0.153, 1.12, -0.021),
        ),
        (
            "streaked",
            streak(&base),
            e(0.052, 4.81, 0.9998, 0.9999, 0.030, 0.24, -0.001),
        ),
        (
            "grown, warped, streaked",
            streak(&warp.apply(&dilate(&base, 1))),
            e(0.164, 3.12, 0.9966, 0.9983, 0.134, 1.73, 0.190),
        ),
        (
            "shrunk, warped, streaked",
            streak(&warp.apply(&erode(&base))),
            e(0.180, 3.85, 0.9974, 0.9996, 0.164, 2.10, -0.245),
        ),
    ];
    for (what, truth, x) in &cases {
        let d = split_degraded(&p, truth, what);
        // Every crown point on the mask, the residual well under the 0.4 mm limit (another
        // patient's: 0.44 mm), no second pose near: no threshold is approached.
        assert!(d.inlier_share > 0.999, "{what}: {}", d.inlier_share);
        assert!((d.rms_mm - x.rms_mm).abs() < 0.005, "{what}: {}", d.rms_mm);
        assert!(
            (d.runner_up_ratio - x.runner_up).abs() < 0.05,
            "{what}: {}",
            d.runner_up_ratio
        );
        assert!(d.refused.is_empty(), "{what}: {:?}", d.refused);
        assert_eq!(d.dice.len(), 10, "{what}");
        let dmin = d.dice.values().copied().fold(1.0, f64::min);
        let dmean = d.dice.values().sum::<f64>() / 10.0;
        assert!(dmin > x.dice_min - 0.0005, "{what}: {:?}", d.dice);
        assert!(dmean > x.dice_mean - 0.0005, "{what}: {:?}", d.dice);
        // All 10 fused watertight; the split costs at most 0.002 mm of TRE over the per-tooth
        // volume degraded the same way (grown 0.045 against 0.043 mm, else within 0.001 mm).
        assert_eq!(d.n_fused, 10, "{what}");
        assert!(d.watertight, "{what}");
        assert!(
            (d.tre_split - x.tre_mm).abs() < 0.005,
            "{what}: {}",
            d.tre_split
        );
        assert!(d.tre_split < d.tre_tooth + 0.003, "{what}");
        // The registration gate passes every case (refused above 2.23) and finds the threshold
        // bias as its CBCT surface offset: +0.21 mm grown, -0.22 mm shrunk (0.20-0.23 mm mean
        // distance from the true surface). Its mismatch score, the larger of the split's and the
        // per-tooth volume's, counts the bias in its fit (0.21-0.26 mm of 1.41-2.10).
        assert!(
            (d.mismatch - x.mismatch).abs() < 0.01,
            "{what}: {}",
            d.mismatch
        );
        assert!(
            (d.offset_mm - x.offset_mm).abs() < 0.005,
            "{what}: {}",
            d.offset_mm
        );
    }
}
