//! Real CBCT label volumes (../shared/data/real): the STS 2024 per-tooth FDI mask and the
//! DentalSegmentator per-jaw fixture. Skipped with a message when absent.

mod real_data;

use glam::{DMat3, DVec3};
use toothfuse::TriMesh;
use toothfuse::io::read_label_volume;
use toothfuse::mesh::ValidateOptions;
use toothfuse::volume::{Frame, LabelVolume, SurfaceOptions, VolumeScheme, surface_teeth};

fn check_closed(m: &TriMesh, what: &str) {
    let r = m
        .validate(&ValidateOptions {
            require_closed: true,
            allow_zero_area: false,
        })
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(r.is_closed_manifold(), "{what}: {r:?}");
    assert_eq!(r.components, 1, "{what}");
    assert!(m.signed_volume() > 0.0, "{what}: inward");
}

/// Distance (mm) from each vertex to the 0.5 level of the trilinearly interpolated binary mask
/// of `label`, searched along the vertex normal within ±1 voxel.
fn iso_distances(vol: &LabelVolume, label: u16, m: &TriMesh) -> Vec<f64> {
    let inv = vol.voxel_to_world.inverse();
    let occ = |q: DVec3| -> f64 {
        let f = q.floor();
        let t = q - f;
        let mut s = 0.0;
        for c in 0..8 {
            let (di, dj, dk) = (c & 1, (c >> 1) & 1, c >> 2);
            let (i, j, k) = (f.x as i64 + di, f.y as i64 + dj, f.z as i64 + dk);
            let inside = i >= 0
                && j >= 0
                && k >= 0
                && (i as usize) < vol.dims[0]
                && (j as usize) < vol.dims[1]
                && (k as usize) < vol.dims[2]
                && vol.labels[vol.idx(i as usize, j as usize, k as usize)] == label;
            if inside {
                let w = (if di == 1 { t.x } else { 1.0 - t.x })
                    * (if dj == 1 { t.y } else { 1.0 - t.y })
                    * (if dk == 1 { t.z } else { 1.0 - t.z });
                s += w;
            }
        }
        s
    };
    let normals = m.vertex_normals();
    let h = vol.spacing().iter().cloned().fold(f64::MAX, f64::min);
    m.positions
        .iter()
        .zip(&normals)
        .map(|(p, n)| {
            let f = |t: f64| occ(inv.transform_point3(*p + *n * t)) - 0.5;
            let steps = 200;
            let mut best = h;
            for s in 0..steps {
                let (a, b) = (
                    h * s as f64 / steps as f64,
                    h * (s + 1) as f64 / steps as f64,
                );
                for sign in [1.0, -1.0] {
                    if (f(sign * a) >= 0.0) != (f(sign * b) >= 0.0) {
                        best = best.min(a);
                    }
                }
                if best < h {
                    break;
                }
            }
            best
        })
        .collect()
}

#[test]
fn sts2024_mask_surfaces_every_tooth_closed_on_the_iso_level() {
    let Some(p) = real_data::real("cbct_toothseg_sts2024/Validation_0001_Mask.nii.gz") else {
        return;
    };
    let vf = read_label_volume(&p, Frame::Lps).unwrap();
    assert_eq!(vf.header.full_dims, [640, 640, 400]);
    assert_eq!(vf.header.element, "uint16");
    assert_eq!(vf.header.orientation_source, "sform");
    let v = &vf.volume;
    for s in v.spacing() {
        assert!((s - 0.25).abs() < 1e-6, "spacing {s}");
    }
    // Negative x and y scales in NIfTI's RAS: the voxel axes point L, P, S.
    assert_eq!(v.axis_codes(), "LPS");
    let want: Vec<u16> = vec![
        11, 12, 13, 14, 21, 22, 23, 25, 26, 27, 31, 32, 33, 35, 36, 37, 41, 42, 43, 44,
    ];
    let counts = v.label_counts();
    assert_eq!(counts.keys().copied().collect::<Vec<_>>(), want);
    assert_eq!(counts[&11], 194);
    assert_eq!(counts[&14], 13);
    let t = surface_teeth(v, VolumeScheme::Fdi, &SurfaceOptions::default()).unwrap();
    // 11 and 14 are fragments at the edge of the field of view: skipped and named.
    let skipped: Vec<u16> = t.skipped.iter().map(|s| s.0).collect();
    assert_eq!(skipped, vec![11, 14]);
    assert_eq!(t.teeth.len(), 18);
    let mut all = Vec::new();
    for (fdi, tooth) in &t.teeth {
        check_closed(&tooth.mesh, &format!("tooth {fdi}"));
        toothfuse::units::check_tooth_scale(&tooth.mesh, *fdi, "CBCT").unwrap();
        // Volume of the surface vs the voxel count.
        let vox = tooth.voxels as f64 * 0.25f64.powi(3);
        let vol = tooth.mesh.signed_volume();
        assert!(
            (vol - vox).abs() / vox < 0.05,
            "tooth {fdi}: {vol} vs {vox} mm^3"
        );
        let d = iso_distances(v, tooth.label, &tooth.mesh);
        all.extend(d);
    }
    all.sort_by(f64::total_cmp);
    let mean = all.iter().sum::<f64>() / all.len() as f64;
    let p95 = all[all.len() * 95 / 100];
    let max = all[all.len() - 1];
    eprintln!("distance to the mask's 0.5 level: mean {mean:.3} p95 {p95:.3} max {max:.3} mm");
    assert!(mean < 0.05 && p95 < 0.1, "mean {mean} p95 {p95}");
    // Upper teeth above lower teeth (LPS: +z superior); right teeth (1x, 4x) on -x.
    let c = |f: u8| toothfuse::geom::centroid(&t.teeth[&f].mesh.positions).unwrap();
    assert!(c(21).z > c(31).z && c(12).z > c(42).z);
    // Incisors anterior of molars (LPS: anterior = -y).
    assert!(c(22).y + 15.0 < c(27).y && c(32).y + 15.0 < c(37).y);
    // A fact of this file, not of the reader: its labels are mirrored left-right relative to its
    // own affine: quadrants 2 and 3 (patient's left) lie toward -x in LPS, the patient's right.
    // The affine is a proper rotation (no mirror), so no frame choice undoes it; the teeth are
    // still a consistent arch, which is all the fusion needs.
    assert!(DMat3::from_mat4(v.voxel_to_world).determinant() > 0.0);
    assert!(
        c(12).x > c(22).x + 10.0 && c(42).x > c(32).x + 10.0,
        "{} {}",
        c(12),
        c(22)
    );
}

#[test]
fn dentalsegmentator_fixture_classes_and_teeth_in_place() {
    let Some(p) = real_data::real("cbct_dentalsegmentator/PostDentalSurgery_Segmentation.nii.gz")
    else {
        return;
    };
    let vf = read_label_volume(&p, Frame::Lps).unwrap();
    assert_eq!(vf.header.full_dims, [360, 360, 330]);
    let v = &vf.volume;
    assert_eq!(v.axis_codes(), "LPS");
    for s in v.spacing() {
        assert!((s - 0.5).abs() < 1e-6, "spacing {s}");
    }
    let counts = v.label_counts();
    let got: Vec<(u16, usize)> = counts.into_iter().collect();
    assert_eq!(
        got,
        vec![
            (1, 1_446_339),
            (2, 309_911),
            (3, 75_300),
            (4, 63_081),
            (5, 6_655)
        ]
    );
    // Per-tooth surfacing refuses it, naming the classes.
    let e = surface_teeth(v, VolumeScheme::Fdi, &SurfaceOptions::default()).unwrap_err();
    assert!(e.to_string().contains("DentalSegmentator"), "{e}");
    // Each teeth class surfaces to one closed mesh (its largest component).
    let boxes = v.label_boxes();
    let world_box = |l: u16| {
        let (lo, hi) = boxes[&l];
        let a = v.world(DVec3::new(lo[0] as f64, lo[1] as f64, lo[2] as f64));
        let b = v.world(DVec3::new(hi[0] as f64, hi[1] as f64, hi[2] as f64));
        (a.min(b), a.max(b))
    };
    let upper = toothfuse::volume::surface_label(v, 3, 1).unwrap();
    let lower = toothfuse::volume::surface_label(v, 4, 1).unwrap();
    check_closed(&upper, "upper teeth");
    check_closed(&lower, "lower teeth");
    let voxel = DMat3::from_mat4(v.voxel_to_world).determinant().abs();
    eprintln!(
        "upper teeth {:.0} mm^3 (mask {:.0}), lower {:.0} mm^3 (mask {:.0})",
        upper.signed_volume(),
        75_300.0 * voxel,
        lower.signed_volume(),
        63_081.0 * voxel
    );
    let cu = toothfuse::geom::centroid(&upper.positions).unwrap();
    let cl = toothfuse::geom::centroid(&lower.positions).unwrap();
    // Upper teeth above the lower (LPS +z superior), both within their bone's box, the upper
    // in the maxilla's and the lower in the mandible's.
    assert!(cu.z > cl.z + 5.0, "upper {cu} lower {cl}");
    let inside = |p: DVec3, (lo, hi): (DVec3, DVec3)| p.cmpge(lo).all() && p.cmple(hi).all();
    assert!(
        inside(cu, world_box(1)),
        "upper teeth centroid {cu} outside the maxilla box"
    );
    assert!(
        inside(cl, world_box(2)),
        "lower teeth centroid {cl} outside the mandible box"
    );
    // Teeth are anterior of the canal's mean (LPS: anterior = -y).
    let canal = toothfuse::volume::surface_label(v, 5, 1).unwrap();
    let cc = toothfuse::geom::centroid(&canal.positions).unwrap();
    assert!(
        cl.y < cc.y,
        "lower teeth {cl} should be anterior of the canal {cc}"
    );
}

/// The DentalSegmentator fixture's lower teeth with the IOS of another patient (a phantom built
/// on the STS 2024 mask's lower teeth): the arch fit is refused, naming the measures.
#[test]
fn dentalsegmentator_fixture_refuses_another_patients_ios() {
    let (Some(ds), Some(sts)) = (
        real_data::real("cbct_dentalsegmentator/PostDentalSurgery_Segmentation.nii.gz"),
        real_data::real(real_data::STS_MASK),
    ) else {
        return;
    };
    let lower = real_data::lower_teeth(&read_label_volume(&sts, Frame::Lps).unwrap().volume);
    let p = real_data::phantom_on(&lower, toothfuse::arch::Jaw::Lower, 5);
    let v = read_label_volume(&ds, Frame::Lps).unwrap().volume;
    let opts = toothfuse::volume::SplitOptions::default();
    let e = toothfuse::volume::split_teeth(&v, &p.ios_crowns(), &opts).unwrap_err();
    eprintln!("{e}");
    assert!(
        matches!(e, toothfuse::Error::RegistrationRejected(_)),
        "{e}"
    );
    assert!(e.to_string().contains("lower IOS crowns do not fit"), "{e}");
}
