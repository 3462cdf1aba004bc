//! Labeled jaws and IOS repair through the C ABI: split by label, all or nothing, the map back
//! to the caller's vertices, and repair on request.

mod ffi_common;

use ffi_common::{Session, cube, square};
use toothfuse::ffi::*;

#[test]
fn labeled_jaw_split_all_or_nothing() {
    let s = Session::new();
    // Two 8 mm cubes (FDI 21, 22; a CBCT jaw of smaller teeth is refused as not millimetres)
    // and a gingiva square, labeled per vertex.
    let (mut v, mut t) = cube(8.0, [0.0; 3]);
    let (v2, t2) = cube(8.0, [12.0, 0.0, 0.0]);
    v.extend(&v2);
    t.extend(t2.iter().map(|i| i + 8));
    let (g, gt) = square();
    v.extend(
        g.iter()
            .enumerate()
            .map(|(k, x)| if k % 3 == 2 { x - 4.0 } else { *x }),
    );
    t.extend(gt.iter().map(|i| i + 16));
    let mut labels = vec![21; 8];
    labels.extend([22; 8]);
    labels.extend([0; 4]);
    let add = |labels: &[i32], domain| {
        // SAFETY: buffers sized as announced.
        unsafe {
            toothfuse_session_add_jaw(
                s.0,
                TOOTHFUSE_MODALITY_CBCT,
                v.as_ptr().cast(),
                v.len() / 3,
                24,
                TOOTHFUSE_SCALAR_FLOAT64,
                t.as_ptr(),
                t.len(),
                labels.as_ptr(),
                labels.len(),
                domain,
            )
        }
    };
    assert_eq!(
        add(&labels, TOOTHFUSE_LABEL_DOMAIN_VERTEX),
        toothfuse_status::Ok
    );
    assert_eq!(s.teeth(TOOTHFUSE_MODALITY_CBCT), vec![21, 22]);
    let p22 = s.positions(TOOTHFUSE_MODALITY_CBCT, 22);
    let mut src = vec![0u32; 8];
    // SAFETY: room for 8.
    let st = unsafe {
        toothfuse_session_copy_source_vertices(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            22,
            src.as_mut_ptr(),
            8,
        )
    };
    assert_eq!(st, toothfuse_status::Ok);
    for (i, &j) in src.iter().enumerate() {
        assert_eq!(
            &p22[3 * i..3 * i + 3],
            &v[3 * j as usize..3 * j as usize + 3]
        );
    }

    // Non-FDI label: rejected, naming it; nothing changes.
    let mut bad = labels.clone();
    bad[9] = 29;
    assert_eq!(
        add(&bad, TOOTHFUSE_LABEL_DOMAIN_VERTEX),
        toothfuse_status::InvalidArgument
    );
    assert!(
        s.error()
            .starts_with("invalid argument: label 29 (on vertex 9) is not an FDI tooth number"),
        "{}",
        s.error()
    );
    // Teeth that are not closed (vertices relabeled open them): all or nothing, the first
    // failing tooth in FDI order is named.
    let mut open = labels.clone();
    open[9] = 0;
    open[3] = 11; // label 11 then carries no whole face: no tooth 11, but 21 opens too
    assert_eq!(
        add(&open, TOOTHFUSE_LABEL_DOMAIN_VERTEX),
        toothfuse_status::NotManifold
    );
    assert!(
        s.error().starts_with("tooth 21: mesh is not closed"),
        "{}",
        s.error()
    );
    // Wrong label count, wrong domain.
    assert_eq!(
        add(&labels[1..], TOOTHFUSE_LABEL_DOMAIN_VERTEX),
        toothfuse_status::InvalidArgument
    );
    assert_eq!(
        s.error(),
        "invalid argument: 19 labels given but the jaw mesh has 20 vertices (one label per vertex)"
    );
    assert_eq!(add(&labels, 2), toothfuse_status::InvalidArgument);
    assert_eq!(s.teeth(TOOTHFUSE_MODALITY_CBCT), vec![21, 22]);
    assert_eq!(s.positions(TOOTHFUSE_MODALITY_CBCT, 22), p22);
    // Per-face labels work too.
    let mut fl = vec![31; 12];
    fl.extend([32; 12]);
    fl.extend([0; 2]);
    assert_eq!(add(&fl, TOOTHFUSE_LABEL_DOMAIN_FACE), toothfuse_status::Ok);
    assert_eq!(s.teeth(TOOTHFUSE_MODALITY_CBCT), vec![21, 22, 31, 32]);
}

#[test]
fn ios_repair_on_request() {
    let s = Session::new();
    // A crown patch with a duplicated triangle and a stray island triangle.
    let (mut v, mut t) = square();
    t.extend([2, 1, 0]); // reversed duplicate of face 0
    v.extend([5.0, 5.0, 0.0, 6.0, 5.0, 0.0, 5.0, 6.0, 0.0]);
    t.extend([4, 5, 6]);
    assert_eq!(
        s.add(TOOTHFUSE_MODALITY_IOS, 14, &v, &t),
        toothfuse_status::NotManifold
    );
    // Refused as given, with how to have it repaired.
    let e = s.error();
    assert!(
        e.starts_with("tooth 14: face 2 duplicates face 0 (same three vertices); "),
        "{e}"
    );
    assert!(e.contains("toothfuse_session_set_ios_repair"), "{e}");
    // SAFETY: live session.
    let st = unsafe { toothfuse_session_set_ios_repair(s.0, true, f64::NAN) };
    assert_eq!(st, toothfuse_status::InvalidArgument);
    assert_eq!(
        s.error(),
        "invalid argument: max_hole_fraction NaN is not in [0, 1]"
    );
    // SAFETY: live session.
    let st = unsafe { toothfuse_session_set_ios_repair(s.0, true, 0.5) };
    assert_eq!(st, toothfuse_status::Ok);
    assert_eq!(
        s.add(TOOTHFUSE_MODALITY_IOS, 14, &v, &t),
        toothfuse_status::Ok,
        "{}",
        s.error()
    );
    let mut rep = toothfuse_repair_report::default();
    let mut info = toothfuse_mesh_info::default();
    let mut src = [0u32; 4];
    // SAFETY: live session, valid out pointers.
    unsafe {
        assert_eq!(
            toothfuse_session_repair_report(s.0, TOOTHFUSE_MODALITY_IOS, 14, &mut rep),
            toothfuse_status::Ok
        );
        assert_eq!(
            toothfuse_session_mesh_info(s.0, TOOTHFUSE_MODALITY_IOS, 14, &mut info),
            toothfuse_status::Ok
        );
        assert_eq!(
            toothfuse_session_copy_source_vertices(
                s.0,
                TOOTHFUSE_MODALITY_IOS,
                14,
                src.as_mut_ptr(),
                4
            ),
            toothfuse_status::Ok
        );
    }
    assert!(rep.repaired);
    assert_eq!((rep.duplicate_faces, rep.island_faces), (1, 1), "{rep:?}");
    assert_eq!((info.vertex_count, info.triangle_count), (4, 2));
    assert_eq!((info.boundary_loops, info.components), (1, 1));
    let p = s.positions(TOOTHFUSE_MODALITY_IOS, 14);
    for (i, &j) in src.iter().enumerate() {
        assert_eq!(&p[3 * i..3 * i + 3], &v[3 * j as usize..3 * j as usize + 3]);
    }
    // CBCT teeth are not repaired; their report says so.
    let (c, ct) = cube(1.0, [0.0; 3]);
    assert_eq!(
        s.add(TOOTHFUSE_MODALITY_CBCT, 14, &c, &ct),
        toothfuse_status::Ok
    );
    // SAFETY: live session, valid out pointer.
    let st = unsafe { toothfuse_session_repair_report(s.0, TOOTHFUSE_MODALITY_CBCT, 14, &mut rep) };
    assert_eq!(st, toothfuse_status::Ok);
    assert_eq!(rep, toothfuse_repair_report::default());
}
