//! Real dental meshes (../shared/data/real): the Mesh Labeler IOS scan (VTP, base64 appended,
//! zlib) and Open-Full-Jaw CBCT teeth (binary STL). Skipped with a message when absent.

mod real_data;

use std::collections::BTreeMap;
use toothfuse::io::{LabelScheme, read_mesh, read_teeth_with, write_mesh};
use toothfuse::mesh::ValidateOptions;

#[test]
fn example_01_vtp_counts_and_labels() {
    let Some(p) = real_data::real("ios_mesh_labeler/Example_01.vtp") else {
        return;
    };
    let lm = read_mesh(&p).unwrap();
    assert_eq!(lm.mesh.vertex_count(), 50_643);
    assert_eq!(lm.mesh.face_count(), 99_999);
    assert!(lm.vertex_labels.is_none());
    let fl = lm.face_labels.as_ref().expect("cell Label array");
    let mut hist: BTreeMap<i32, usize> = BTreeMap::new();
    for &l in fl {
        *hist.entry(l).or_default() += 1;
    }
    let labels: Vec<i32> = hist.keys().copied().collect();
    let want: Vec<i32> = std::iter::once(0).chain(2..=15).collect();
    assert_eq!(labels, want);
    assert_eq!(hist[&0], 43_450);
    for l in 2..=15 {
        assert!(
            (3000..=5500).contains(&hist[&l]),
            "label {l}: {} faces",
            hist[&l]
        );
    }
    // A real open scan: it has a boundary, and (a fact of this file) a few non-manifold edges.
    let rep = lm.mesh.topology_report();
    eprintln!("Example_01 topology: {rep:?}");
    assert!(rep.boundary_edges > 0 && !rep.is_closed_manifold());
    // Split by label, each crown has one long boundary loop (its margin, 130-250 vertices);
    // the real labels also leave small islands and tiny loops (a fact the fusion must handle).
    let teeth = read_teeth_with(&p, LabelScheme::MeshLabeler).unwrap();
    assert_eq!(teeth.len(), 14);
    for (fdi, m) in &teeth {
        let loops = toothfuse::mesh::boundary_loops(m);
        let sizes: Vec<usize> = loops.iter().map(Vec::len).collect();
        let long = sizes.iter().filter(|&&n| n > 50).count();
        assert_eq!(long, 1, "crown {fdi}: loop sizes {sizes:?}");
        assert!((100..=300).contains(&sizes[0]), "crown {fdi}: {sizes:?}");
        toothfuse::units::check_tooth_scale(m, *fdi, "IOS").unwrap();
    }
}

/// The Mesh Labeler scheme puts FDI 11 at label 8: the four UR1 landmarks of
/// Example_01_UR1.fcsv must lie on (or right next to) the crown labeled 8, and nowhere near
/// the neighbours. Slicer stores RAS; VTK/the file are LPS or RAS, so both are tried.
#[test]
fn mesh_labeler_label_8_is_fdi_11_by_landmarks() {
    let (Some(p), Some(f)) = (
        real_data::real("ios_mesh_labeler/Example_01.vtp"),
        real_data::real("ios_mesh_labeler/Example_01_UR1.fcsv"),
    ) else {
        return;
    };
    let lm = read_mesh(&p).unwrap();
    let fl = lm.face_labels.unwrap();
    let text = std::fs::read_to_string(f).unwrap();
    let marks: Vec<[f64; 3]> = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            let c: Vec<f64> = l
                .split(',')
                .skip(1)
                .take(3)
                .map(|x| x.parse().unwrap())
                .collect();
            [c[0], c[1], c[2]]
        })
        .collect();
    assert_eq!(marks.len(), 4);
    // Distance from each landmark to the nearest vertex of each label.
    let nearest = |q: [f64; 3], label: i32| -> f64 {
        let mut best = f64::INFINITY;
        for (t, &l) in lm.mesh.triangles.iter().zip(&fl) {
            if l != label {
                continue;
            }
            for &v in t {
                let p = lm.mesh.positions[v as usize];
                let d = ((p.x - q[0]).powi(2) + (p.y - q[1]).powi(2) + (p.z - q[2]).powi(2)).sqrt();
                best = best.min(d);
            }
        }
        best
    };
    let best_frame = [1.0, -1.0]
        .into_iter()
        .map(|s| {
            let d8: f64 = marks
                .iter()
                .map(|m| nearest([s * m[0], s * m[1], m[2]], 8))
                .sum();
            (d8, s)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap();
    let s = best_frame.1;
    for m in &marks {
        let q = [s * m[0], s * m[1], m[2]];
        let d8 = nearest(q, 8);
        assert!(d8 < 1.5, "landmark {m:?} is {d8:.2} mm from label 8");
        for other in [7, 9, 10, 6] {
            assert!(
                nearest(q, other) > d8,
                "label {other} nearer than 8 to {m:?}"
            );
        }
    }
    let teeth = read_teeth_with(&p, LabelScheme::MeshLabeler).unwrap();
    let fdi: Vec<u8> = teeth.keys().copied().collect();
    assert_eq!(
        fdi,
        vec![11, 12, 13, 14, 15, 16, 17, 21, 22, 23, 24, 25, 26, 27]
    );
    // Labels are not FDI: reading with the FDI scheme names the offending label.
    let e = toothfuse::io::read_teeth(&p).unwrap_err().to_string();
    assert!(e.contains("label 2 "), "{e}");
}

#[test]
fn openfulljaw_tooth_17_stl_is_closed_manifold_and_round_trips() {
    let Some(p) = real_data::real("cbct_teeth_openfulljaw_p26/mandible/tooth_17.stl") else {
        return;
    };
    let lm = read_mesh(&p).unwrap();
    assert_eq!(lm.mesh.vertex_count(), 17_754);
    assert_eq!(lm.mesh.face_count(), 35_504);
    let rep = lm
        .mesh
        .validate(&ValidateOptions {
            require_closed: true,
            ..Default::default()
        })
        .unwrap();
    assert!(rep.is_closed_manifold());
    assert_eq!(rep.components, 1);
    toothfuse::units::check_tooth_scale(&lm.mesh, 38, "CBCT").unwrap();

    // STL -> PLY (double) -> identical positions; STL -> STL identical too (f32 source).
    let dir = std::env::temp_dir().join(format!("toothfuse_io_real_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for ext in ["ply", "stl", "obj", "vtp"] {
        let q = dir.join(format!("t17.{ext}"));
        write_mesh(&q, &lm.mesh, &[]).unwrap();
        let back = read_mesh(&q).unwrap();
        assert_eq!(back.mesh, lm.mesh, "{ext}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn openfulljaw_mandible_folder_in_universal_numbering() {
    let Some(p) = real_data::real("cbct_teeth_openfulljaw_p26/mandible") else {
        return;
    };
    let teeth = read_teeth_with(&p, LabelScheme::Universal).unwrap();
    let fdi: Vec<u8> = teeth.keys().copied().collect();
    let want: Vec<u8> = (31..=38).chain(41..=48).collect();
    assert_eq!(fdi, want);
    // UNN 17 -> FDI 38 (README table): the same mesh as tooth_17.stl.
    assert_eq!(teeth[&38].face_count(), 35_504);
    assert_eq!(teeth[&31].face_count(), 16_744); // tooth_24
    assert_eq!(teeth[&41].face_count(), 15_916); // tooth_25
    for (&f, m) in &teeth {
        toothfuse::units::check_tooth_scale(m, f, "CBCT").unwrap();
    }
    // FDI scheme: file numbers 17..32 are mostly not FDI -> error naming the number.
    let e = toothfuse::io::read_teeth(&p).unwrap_err().to_string();
    assert!(e.contains("not an FDI tooth number"), "{e}");
}
