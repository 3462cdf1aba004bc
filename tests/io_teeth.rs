//! Per-tooth folders and labeled-jaw splitting, with FDI, Universal and Mesh Labeler numbering.

mod io_common;

use glam::DVec3;
use io_common::{grid, grid_f32, put, scratch};
use std::collections::BTreeMap;
use toothfuse::io::{
    LabelScheme, fdi_to_universal, read_teeth, read_teeth_with, universal_to_fdi, write_mesh,
    write_teeth_dir,
};
use toothfuse::{ErrorKind, TriMesh};

fn shifted(m: &TriMesh, dx: f64) -> TriMesh {
    let mut m = m.clone();
    m.positions.iter_mut().for_each(|p| p.x += dx);
    m
}

#[test]
fn folder_round_trip_in_each_format() {
    let base = grid_f32(5, 11);
    let teeth: BTreeMap<u8, TriMesh> = [11u8, 21, 36]
        .into_iter()
        .map(|f| (f, shifted(&base, f as f64)))
        .map(|(f, m)| {
            // keep f32-exact after the shift
            let mut m = m;
            m.positions.iter_mut().for_each(|p| {
                *p = DVec3::new(p.x as f32 as f64, p.y as f32 as f64, p.z as f32 as f64)
            });
            (f, m)
        })
        .collect();
    for ext in ["ply", "stl", "obj", "vtp"] {
        let d = scratch(&format!("teeth_{ext}"));
        write_teeth_dir(&d, &teeth, ext).unwrap();
        assert!(d.join(format!("tooth_36.{ext}")).is_file());
        // Unrelated files are ignored.
        put(&d, "readme.txt", b"hello");
        put(&d, "tooth_x.stl", b"not a tooth");
        put(&d, "tooth_11.bak", b"backup");
        let back = read_teeth(&d).unwrap();
        assert_eq!(
            back.keys().collect::<Vec<_>>(),
            vec![&11, &21, &36],
            "{ext}"
        );
        for (f, m) in &teeth {
            if ext == "stl" {
                // Welded in first-use order: same corners per triangle.
                for t in 0..m.face_count() {
                    assert_eq!(back[f].corners(t), m.corners(t));
                }
            } else {
                assert_eq!(&back[f], m, "{ext} tooth {f}");
            }
        }
    }
}

#[test]
fn folder_errors() {
    let d = scratch("teeth_err");
    let e = read_teeth(&d).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::MissingData);
    assert!(e.to_string().contains("no tooth_"), "{e}");
    let m = grid(3, 1);
    write_mesh(d.join("tooth_19.stl"), &m, &[]).unwrap();
    let e = read_teeth(&d).unwrap_err().to_string();
    assert!(
        e.contains("tooth_19.stl") && e.contains("label 19 is not an FDI"),
        "{e}"
    );
    std::fs::remove_file(d.join("tooth_19.stl")).unwrap();
    write_mesh(d.join("tooth_11.stl"), &m, &[]).unwrap();
    write_mesh(d.join("tooth_11.ply"), &m, &[]).unwrap();
    let e = read_teeth(&d).unwrap_err().to_string();
    assert!(e.contains("two files for tooth 11"), "{e}");
    std::fs::remove_file(d.join("tooth_11.ply")).unwrap();
    put(&d, "tooth_12.stl", b"garbage");
    let e = read_teeth(&d).unwrap_err().to_string();
    assert!(
        e.starts_with("tooth 12: ") && e.contains("tooth_12.stl"),
        "{e}"
    );
}

/// A jaw of three "teeth" (grid patches) plus gingiva, labeled per vertex.
fn labeled_jaw(labels: [i32; 4]) -> (TriMesh, Vec<i32>) {
    let mut jaw = TriMesh::default();
    let mut vl = Vec::new();
    for (k, &l) in labels.iter().enumerate() {
        let part = shifted(&grid(4, k as u64), 10.0 * k as f64);
        jaw.append(&part);
        vl.extend(std::iter::repeat_n(l, part.vertex_count()));
    }
    (jaw, vl)
}

#[test]
fn split_labeled_jaw_by_vertex_and_face_labels() {
    let d = scratch("teeth_split");
    let (jaw, vl) = labeled_jaw([0, 11, 21, 22]);
    let p = d.join("jaw.ply");
    write_mesh(&p, &jaw, &[("label", &vl)]).unwrap();
    let teeth = read_teeth(&p).unwrap();
    assert_eq!(teeth.keys().copied().collect::<Vec<_>>(), vec![11, 21, 22]);
    // Same triangles (corner positions, bitwise), vertices renumbered in first-use order.
    let want = shifted(&grid(4, 2), 20.0);
    assert_eq!(teeth[&21].face_count(), want.face_count());
    assert_eq!(teeth[&21].vertex_count(), want.vertex_count());
    for f in 0..want.face_count() {
        assert_eq!(teeth[&21].corners(f), want.corners(f));
    }

    // Per-face labels (VTP cell data) win over vertex labels.
    let fl: Vec<i32> = jaw
        .triangles
        .iter()
        .map(|t| {
            if vl[t[0] as usize] == 22 {
                0
            } else {
                vl[t[0] as usize]
            }
        })
        .collect();
    let mut b = Vec::new();
    toothfuse::io::write_vtp(
        &mut b,
        &jaw,
        &[("label", &vl)],
        &[("label", &fl)],
        toothfuse::io::VtpEncoding::Ascii,
    )
    .unwrap();
    let teeth = read_teeth(put(&d, "jaw.vtp", &b)).unwrap();
    assert_eq!(teeth.keys().copied().collect::<Vec<_>>(), vec![11, 21]);

    // Ordinal labels: an error naming the label with FDI, converted with a scheme.
    let (jaw, vl) = labeled_jaw([0, 8, 9, 24]);
    write_mesh(&p, &jaw, &[("label", &vl)]).unwrap();
    let e = read_teeth(&p).unwrap_err().to_string();
    assert!(e.contains("label 8 is not an FDI tooth number"), "{e}");
    let teeth = read_teeth_with(&p, LabelScheme::MeshLabeler).unwrap();
    assert_eq!(teeth.keys().copied().collect::<Vec<_>>(), vec![11, 21, 31]);
    // Universal: 33 is the DCBIA tools' gingiva (dropped), 34 is no tooth.
    let (jaw, vl) = labeled_jaw([0, 8, 9, 33]);
    write_mesh(&p, &jaw, &[("label", &vl)]).unwrap();
    let teeth = read_teeth_with(&p, LabelScheme::Universal).unwrap();
    assert_eq!(teeth.keys().copied().collect::<Vec<_>>(), vec![11, 21]);
    let (jaw, vl) = labeled_jaw([0, 8, 9, 34]);
    write_mesh(&p, &jaw, &[("label", &vl)]).unwrap();
    let e = read_teeth_with(&p, LabelScheme::Universal)
        .unwrap_err()
        .to_string();
    assert!(e.contains("label 34 is outside 1-32"), "{e}");

    // No labels at all, or only gingiva.
    write_mesh(&p, &jaw, &[]).unwrap();
    assert!(
        read_teeth(&p)
            .unwrap_err()
            .to_string()
            .contains("no per-vertex or per-face labels")
    );
    write_mesh(&p, &jaw, &[("label", &vec![0; jaw.vertex_count()])]).unwrap();
    assert_eq!(read_teeth(&p).unwrap_err().kind(), ErrorKind::MissingData);
}

#[test]
fn universal_numbering_matches_the_open_full_jaw_table() {
    // README of the real data: mandible 17→38 … 24→31, 25→41 … 32→48; maxilla n→1(9−n), 9..16→2(n−8).
    let mandible = [
        (17, 38),
        (18, 37),
        (19, 36),
        (20, 35),
        (21, 34),
        (22, 33),
        (23, 32),
        (24, 31),
        (25, 41),
        (26, 42),
        (27, 43),
        (28, 44),
        (29, 45),
        (30, 46),
        (31, 47),
        (32, 48),
    ];
    for (n, f) in mandible {
        assert_eq!(universal_to_fdi(n), Some(f), "{n}");
    }
    for (n, f) in [
        (1, 18),
        (3, 16),
        (4, 15),
        (6, 13),
        (8, 11),
        (9, 21),
        (16, 28),
    ] {
        assert_eq!(universal_to_fdi(n), Some(f), "{n}");
    }
    for n in [0, 33, -1] {
        assert_eq!(universal_to_fdi(n), None);
    }
    // A bijection onto the 32 permanent teeth.
    let mut seen: Vec<u8> = (1..=32).filter_map(universal_to_fdi).collect();
    seen.sort_unstable();
    seen.dedup();
    assert_eq!(seen.len(), 32);
    for n in 1..=32 {
        assert_eq!(fdi_to_universal(universal_to_fdi(n).unwrap()), Some(n));
    }
    assert_eq!(fdi_to_universal(55), None);
    assert_eq!(LabelScheme::MeshLabeler.to_fdi(2).unwrap(), 17);
    assert_eq!(LabelScheme::Fdi.to_fdi(47).unwrap(), 47);
}

/// A Teeth3DS-style OBJ + JSON (FDI per vertex) splits into its teeth.
#[test]
fn teeth3ds_obj_with_json_splits() {
    let d = scratch("teeth3ds");
    let (jaw, vl) = labeled_jaw([0, 36, 37, 0]);
    let p = d.join("ABC_lower.obj");
    write_mesh(&p, &jaw, &[]).unwrap();
    let json = serde_json::json!({"jaw": "lower", "labels": vl, "instances": []});
    put(&d, "ABC_lower.json", json.to_string().as_bytes());
    let teeth = read_teeth(&p).unwrap();
    assert_eq!(teeth.keys().copied().collect::<Vec<_>>(), vec![36, 37]);
    assert_eq!(teeth[&36].face_count(), 18);
}
