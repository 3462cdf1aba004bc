//! The whole split on a synthetic arch with known truth: six "teeth" (a ball crown on a
//! cylinder root) along a parabola, merged into one lower-teeth class; the IOS crowns are the
//! balls' upper caps, moved by a known rigid transform.

use super::*;
use crate::Rigid;
use crate::volume::Frame;
use glam::{DMat3, DVec3};

const FDIS: [u8; 6] = [33, 32, 31, 41, 42, 43];

fn centre(t: usize) -> DVec3 {
    let x = -20.0 + 8.0 * t as f64;
    DVec3::new(x, 0.03 * x * x, 0.0)
}

/// Crown radius of tooth `t`: all alike, or growing along the arch (teeth that differ).
fn radius(t: usize, alike: bool) -> f64 {
    if alike { 3.0 } else { 2.4 + 0.25 * t as f64 }
}

/// Tooth index of a world point (ball crown, root of radius 1.5 mm down to z = -9).
fn tooth_at(p: DVec3, alike: bool) -> Option<usize> {
    (0..FDIS.len()).find(|&t| {
        let d = p - centre(t);
        d.length() < radius(t, alike) || (d.truncate().length() < 1.5 && d.z < 0.0 && d.z > -9.0)
    })
}

/// The lower-teeth mask (class 4) at 0.3 mm and, per voxel, the true tooth index + 1.
fn arch_volume(alike: bool) -> (LabelVolume, Vec<u8>) {
    let h = 0.3;
    let dims = [165, 70, 50];
    let origin = DVec3::new(-25.0, -4.0, -10.5);
    let mut labels = vec![0u16; dims[0] * dims[1] * dims[2]];
    let mut truth = vec![0u8; labels.len()];
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let p = origin + DVec3::new(i as f64, j as f64, k as f64) * h;
                if let Some(t) = tooth_at(p, alike) {
                    let id = i + dims[0] * (j + dims[1] * k);
                    labels[id] = 4;
                    truth[id] = t as u8 + 1;
                }
            }
        }
    }
    let v = LabelVolume::with_spacing(dims, [h; 3], origin.to_array(), Frame::Lps, labels);
    (v.unwrap(), truth)
}

/// The upper cap (polar angle up to 1.9 rad) of a ball of radius `r`: an open UV mesh.
fn cap(c: DVec3, r: f64) -> TriMesh {
    let (nu, nv) = (32usize, 10usize);
    let mut pos = vec![c + DVec3::new(0.0, 0.0, r)];
    for v in 1..=nv {
        let polar = (v as f64 / nv as f64) * 1.9;
        for u in 0..nu {
            let a = u as f64 / nu as f64 * std::f64::consts::TAU;
            let d = DVec3::new(polar.sin() * a.cos(), polar.sin() * a.sin(), polar.cos());
            pos.push(c + d * r);
        }
    }
    let mut tris = Vec::new();
    let ring = |v: usize, u: usize| (1 + (v - 1) * nu + u % nu) as u32;
    for u in 0..nu {
        tris.push([0, ring(1, u), ring(1, u + 1)]);
    }
    for v in 1..nv {
        for u in 0..nu {
            tris.push([ring(v, u), ring(v + 1, u), ring(v + 1, u + 1)]);
            tris.push([ring(v, u), ring(v + 1, u + 1), ring(v, u + 1)]);
        }
    }
    TriMesh::new(pos, tris)
}

/// The crowns of the arch in an IOS frame `to_ios` away.
fn crowns(alike: bool, to_ios: &Rigid) -> BTreeMap<u8, TriMesh> {
    FDIS.iter()
        .enumerate()
        .map(|(t, &f)| {
            let mut m = cap(centre(t), radius(t, alike));
            m.positions.iter_mut().for_each(|p| *p = to_ios.apply(*p));
            (f, m)
        })
        .collect()
}

#[test]
fn synthetic_arch_is_registered_and_split_into_its_teeth() {
    let (vol, truth) = arch_volume(false);
    let to_ios = Rigid::new(
        DMat3::from_axis_angle(DVec3::new(0.3, -0.5, 1.0).normalize(), 0.7),
        DVec3::new(12.0, -30.0, 5.0),
    );
    let crowns = crowns(false, &to_ios);
    let split = split_teeth(&vol, &crowns, &SplitOptions::default()).expect("split");
    let fit = &split.jaws[0].fit;
    let back = fit.ios_to_volume.compose(&to_ios);
    let worst = (0..FDIS.len())
        .map(|t| (back.apply(centre(t)) - centre(t)).length())
        .fold(0.0, f64::max);
    assert!(worst < 0.1, "registration error {worst} mm, fit {fit:?}");
    assert!(split.refused().is_empty(), "{:?}", split.refused());
    // Every mask voxel labelled with its own tooth (the split volume keeps the input's grid
    // offset by its crop; compare through world positions).
    let inv = vol.voxel_to_world.inverse();
    let [nx, ny, _] = split.volume.dims;
    let mut wrong = 0;
    for (id, &l) in split.volume.labels.iter().enumerate() {
        let ijk = DVec3::new(
            (id % nx) as f64,
            ((id / nx) % ny) as f64,
            (id / (nx * ny)) as f64,
        );
        let q = inv.transform_point3(split.volume.world(ijk)).round();
        let t = truth[vol.idx(q.x as usize, q.y as usize, q.z as usize)];
        let want = if t == 0 {
            0
        } else {
            FDIS[t as usize - 1] as u16
        };
        wrong += (l != want) as usize;
    }
    assert_eq!(wrong, 0);
    assert_eq!(split.jaws[0].unreached_voxels, 0);
}

#[test]
fn an_arch_of_identical_teeth_is_ambiguous_and_refused() {
    // Shifted by one tooth along the arch the crowns fit nearly as well: no trustworthy pose.
    let (vol, _) = arch_volume(true);
    let e = split_teeth(
        &vol,
        &crowns(true, &Rigid::IDENTITY),
        &SplitOptions::default(),
    );
    let e = e.unwrap_err();
    assert!(matches!(e, Error::RegistrationRejected(_)), "{e}");
    assert!(e.to_string().contains("ambiguous"), "{e}");
}

#[test]
fn crowns_of_the_other_jaw_or_none_are_named() {
    let (vol, _) = arch_volume(false);
    let upper: BTreeMap<u8, TriMesh> = [(11u8, cap(centre(0), 3.0))].into_iter().collect();
    let e = split_teeth(&vol, &upper, &SplitOptions::default()).unwrap_err();
    assert!(e.to_string().contains("other jaw"), "{e}");
    let e = split_teeth(&vol, &BTreeMap::new(), &SplitOptions::default()).unwrap_err();
    assert!(e.to_string().contains("no IOS crowns"), "{e}");
    let empty = vol.relabeled(|_| 0);
    let e = split_teeth(&empty, &upper, &SplitOptions::default()).unwrap_err();
    assert!(e.to_string().contains("no teeth class"), "{e}");
}
