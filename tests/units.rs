//! Unit sanity checks: metres / centimetres / micrometres detected, modalities compared.

use glam::{DMat3, DVec3};
use toothfuse::units::{
    SCALE_RATIO_MAX, SCALE_RATIO_MIN, TOOTH_DIAGONAL_MAX_MM, TOOTH_DIAGONAL_MIN_MM,
    check_consistent_scales, check_tooth_scale, median, tooth_width,
};
use toothfuse::{ErrorKind, Rigid, TriMesh};

/// A closed box of the given size, rotated and moved so the axes are not the principal axes.
fn tooth_box(size: DVec3) -> TriMesh {
    let c = |x: f64, y: f64, z: f64| DVec3::new(x, y, z) * size;
    let pos = vec![
        c(0., 0., 0.),
        c(1., 0., 0.),
        c(1., 1., 0.),
        c(0., 1., 0.),
        c(0., 0., 1.),
        c(1., 0., 1.),
        c(1., 1., 1.),
        c(0., 1., 1.),
    ];
    let tris = vec![
        [0, 2, 1],
        [0, 3, 2],
        [4, 5, 6],
        [4, 6, 7],
        [0, 1, 5],
        [0, 5, 4],
        [1, 2, 6],
        [1, 6, 5],
        [2, 3, 7],
        [2, 7, 6],
        [3, 0, 4],
        [3, 4, 7],
    ];
    let rot = DMat3::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
    TriMesh::new(pos, tris).transformed(&Rigid {
        rot,
        trans: DVec3::new(40.0, -12.0, 7.0),
    })
}

fn scaled(m: &TriMesh, s: f64) -> TriMesh {
    TriMesh::new(
        m.positions.iter().map(|p| *p * s).collect(),
        m.triangles.clone(),
    )
}

#[test]
fn tooth_scale_accepts_mm_and_names_the_wrong_unit() {
    const { assert!(TOOTH_DIAGONAL_MIN_MM < 5.0 && TOOTH_DIAGONAL_MAX_MM >= 40.0) };
    let molar = tooth_box(DVec3::new(10.0, 11.0, 20.0)); // rotated: box diagonal ~36 mm
    let incisor_crown = tooth_box(DVec3::new(7.0, 6.0, 9.0));
    let primary_crown = tooth_box(DVec3::new(3.0, 2.5, 4.0));
    for m in [&molar, &incisor_crown, &primary_crown] {
        check_tooth_scale(m, 36, "CBCT").unwrap();
    }
    let e = check_tooth_scale(&scaled(&molar, 0.001), 36, "CBCT").unwrap_err();
    assert_eq!(e.kind(), ErrorKind::UnitMismatch);
    let s = e.to_string();
    assert!(
        s.contains("tooth 36") && s.contains("CBCT") && s.contains("metres"),
        "{s}"
    );
    let diag = toothfuse::units::bbox_diagonal(&scaled(&molar, 0.001)).unwrap();
    assert!(
        s.contains(&format!("{diag:.4}")) && s.contains("convert to millimetres"),
        "{s}"
    );
    let s = check_tooth_scale(&scaled(&incisor_crown, 0.1), 11, "IOS")
        .unwrap_err()
        .to_string();
    assert!(s.contains("centimetres") && s.contains("IOS"), "{s}");
    let s = check_tooth_scale(&scaled(&molar, 1000.0), 36, "IOS")
        .unwrap_err()
        .to_string();
    assert!(s.contains("micrometres"), "{s}");
    let s = check_tooth_scale(&scaled(&molar, 1e-7), 36, "IOS")
        .unwrap_err()
        .to_string();
    assert!(s.contains("far too small"), "{s}");
    let s = check_tooth_scale(&scaled(&molar, 20.0), 36, "IOS")
        .unwrap_err()
        .to_string();
    assert!(s.contains("far too large"), "{s}");
    let e = check_tooth_scale(&TriMesh::default(), 36, "IOS").unwrap_err();
    assert_eq!(e.kind(), ErrorKind::InvalidArgument);
}

#[test]
fn tooth_width_is_comparable_between_crown_and_whole_tooth() {
    // Whole tooth 10 × 9 × 22 (long axis 22) and its crown 10 × 9 × 7: the middle principal
    // extent is 10 for the whole tooth and 9 for the crown (its height 7 is the smallest), so
    // the widths agree within ~10%, while bounding-box diagonals differ by 2×.
    let whole = tooth_box(DVec3::new(10.0, 9.0, 22.0));
    let crown = tooth_box(DVec3::new(10.0, 9.0, 7.0));
    let (w, c) = (tooth_width(&whole).unwrap(), tooth_width(&crown).unwrap());
    assert!((w - 10.0).abs() < 1e-6, "{w}");
    assert!((c - 9.0).abs() < 1e-6, "{c}");
    assert_eq!(tooth_width(&TriMesh::default()), None);
}

#[test]
fn consistent_scales_compare_medians() {
    assert!((SCALE_RATIO_MIN..=SCALE_RATIO_MAX).contains(&1.0));
    assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
    assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), Some(2.5));
    assert_eq!(median(&[f64::NAN]), None);
    let ios = [8.1, 9.0, 10.2, 7.5, 11.0];
    let cbct = [8.4, 9.3, 10.0, 7.9, 10.6, 9.9];
    check_consistent_scales(&ios, &cbct).unwrap();
    check_consistent_scales(&ios, &[]).unwrap();
    // CBCT in metres: error naming both medians.
    let cbct_m: Vec<f64> = cbct.iter().map(|x| x * 0.001).collect();
    let e = check_consistent_scales(&ios, &cbct_m).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::UnitMismatch);
    let s = e.to_string();
    assert!(s.contains("9.0000") && s.contains("0.0096"), "{s}");
    // Ratio bounds.
    let times = |f: f64| ios.iter().map(|x| x * f).collect::<Vec<_>>();
    check_consistent_scales(&ios, &times(1.9)).unwrap();
    check_consistent_scales(&ios, &times(0.55)).unwrap();
    assert!(check_consistent_scales(&ios, &times(2.1)).is_err());
    assert!(check_consistent_scales(&ios, &times(0.45)).is_err());
    assert!(check_consistent_scales(&[0.0], &[1.0]).is_err());
}

/// Real data: IOS crowns of Example_01 (Mesh Labeler) and Open-Full-Jaw CBCT teeth (another
/// patient, other jaw) have comparable widths; the metres version of the CBCT is caught.
#[test]
fn real_crowns_and_cbct_teeth_have_consistent_widths() {
    let Some(dir) = toothfuse::io::real_data_dir() else {
        eprintln!(
            "SKIPPED: real data folder not found (set TOOTHFUSE_REAL_DATA or provide ../shared/data/real)"
        );
        return;
    };
    let ios = toothfuse::io::read_teeth_with(
        dir.join("ios_mesh_labeler/Example_01.vtp"),
        toothfuse::io::LabelScheme::MeshLabeler,
    )
    .unwrap();
    let cbct = toothfuse::io::read_teeth_with(
        dir.join("cbct_teeth_openfulljaw_p26/mandible"),
        toothfuse::io::LabelScheme::Universal,
    )
    .unwrap();
    let iw: Vec<f64> = ios.values().map(|m| tooth_width(m).unwrap()).collect();
    let cw: Vec<f64> = cbct.values().map(|m| tooth_width(m).unwrap()).collect();
    let (mi, mc) = (median(&iw).unwrap(), median(&cw).unwrap());
    eprintln!("median width: IOS crowns {mi:.2} mm, CBCT teeth {mc:.2} mm");
    assert!((5.0..=12.0).contains(&mi) && (5.0..=12.0).contains(&mc));
    check_consistent_scales(&iw, &cw).unwrap();
    let cw_m: Vec<f64> = cw.iter().map(|w| w / 1000.0).collect();
    assert!(check_consistent_scales(&iw, &cw_m).is_err());
}
