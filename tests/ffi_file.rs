//! The C ABI file reader (`toothfuse_session_read_file` and the `toothfuse_mesh_file_*`
//! accessors): a PLY with a `UniversalID` vertex property read into FDI labels, the description
//! JSON, NULL and bad-argument checks, and failures that leave the message on the session and
//! the session's teeth untouched.

mod ffi_common;

use ffi_common::{Session, cube};
use std::ffi::{CStr, CString};
use std::ptr;
use toothfuse::TriMesh;
use toothfuse::ffi::*;

fn write_labeled_cube(dir: &std::path::Path, name: &str, prop: &str, labels: &[i32]) -> CString {
    let (v, t) = cube(2.0, [0.0; 3]);
    let pos = v
        .chunks(3)
        .map(|c| glam::DVec3::new(c[0], c[1], c[2]))
        .collect();
    let tris = t.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
    let p = dir.join(name);
    toothfuse::io::write_mesh(&p, &TriMesh::new(pos, tris), &[(prop, labels)]).unwrap();
    CString::new(p.to_str().unwrap()).unwrap()
}

fn read(
    s: &Session,
    path: &CString,
    array: Option<&CStr>,
    n: u32,
) -> (toothfuse_status, *mut toothfuse_mesh_file) {
    let mut f = ptr::null_mut();
    // SAFETY: live session, NUL-terminated strings, valid out pointer.
    let st = unsafe {
        toothfuse_session_read_file(
            s.0,
            path.as_ptr(),
            array.map_or(ptr::null(), CStr::as_ptr),
            n,
            &mut f,
        )
    };
    (st, f)
}

#[test]
fn reads_universal_ids_as_fdi_and_reports_how() {
    let d = std::env::temp_dir().join(format!("toothfuse_ffi_file_{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let labels = [3, 3, 3, 3, 33, 33, 33, 33];
    let path = write_labeled_cube(&d, "cube.ply", "UniversalID", &labels);
    let s = Session::new();
    let (st, f) = read(&s, &path, None, TOOTHFUSE_NUMBERING_AUTO);
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    let mut view = toothfuse_mesh_view {
        positions: ptr::null(),
        vertex_count: 0,
        indices: ptr::null(),
        index_count: 0,
    };
    let (mut lp, mut ln) = (ptr::null::<i32>(), 0usize);
    // SAFETY: `f` is a live handle; the views are read before it is freed.
    unsafe {
        assert_eq!(toothfuse_mesh_file_view(f, &mut view), toothfuse_status::Ok);
        assert_eq!((view.vertex_count, view.index_count), (8, 36));
        assert_eq!(
            toothfuse_mesh_file_labels(f, TOOTHFUSE_LABEL_DOMAIN_VERTEX, &mut lp, &mut ln),
            toothfuse_status::Ok
        );
        let got = std::slice::from_raw_parts(lp, ln);
        assert_eq!(
            got,
            &[16, 16, 16, 16, 0, 0, 0, 0],
            "Universal 3 = FDI 16, 33 = gingiva"
        );
        assert_eq!(
            toothfuse_mesh_file_labels(f, TOOTHFUSE_LABEL_DOMAIN_FACE, &mut lp, &mut ln),
            toothfuse_status::Ok
        );
        assert!(lp.is_null() && ln == 0, "no face labels");
        assert_eq!(
            toothfuse_mesh_file_labels(f, 7, &mut lp, &mut ln),
            toothfuse_status::InvalidArgument
        );
        assert_eq!(
            toothfuse_mesh_file_labels(f, TOOTHFUSE_LABEL_DOMAIN_VERTEX, ptr::null_mut(), &mut ln),
            toothfuse_status::NullParameter
        );
        let desc: serde_json::Value = serde_json::from_str(
            CStr::from_ptr(toothfuse_mesh_file_description(f))
                .to_str()
                .unwrap(),
        )
        .unwrap();
        assert_eq!(desc["label_array"], "UniversalID");
        assert_eq!(desc["numbering"], "universal");
        toothfuse_mesh_file_free(f);
        toothfuse_mesh_file_free(ptr::null_mut());
        assert_eq!(
            toothfuse_mesh_file_view(ptr::null(), &mut view),
            toothfuse_status::NullParameter
        );
        assert!(toothfuse_mesh_file_description(ptr::null()).is_null());
    }
    // Failures: the status, the message on the session, nothing written, the teeth kept.
    let (v, t) = cube(1.0, [0.0; 3]);
    assert_eq!(
        s.add(TOOTHFUSE_MODALITY_CBCT, 46, &v, &t),
        toothfuse_status::Ok
    );
    let (st, f) = read(&s, &path, Some(c"PredictedID"), TOOTHFUSE_NUMBERING_AUTO);
    assert_eq!(st, toothfuse_status::MissingData);
    assert!(f.is_null());
    assert!(
        s.error().contains("PredictedID") && s.error().contains("UniversalID"),
        "{}",
        s.error()
    );
    let amb = write_labeled_cube(&d, "amb.ply", "label", &[11, 11, 11, 11, 12, 12, 12, 12]);
    let (st, _) = read(&s, &amb, None, TOOTHFUSE_NUMBERING_AUTO);
    assert_eq!(st, toothfuse_status::InvalidArgument);
    assert!(s.error().contains("ambiguous"), "{}", s.error());
    let (st, f) = read(&s, &amb, None, TOOTHFUSE_NUMBERING_UNIVERSAL);
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    // SAFETY: live handle, freed once.
    unsafe { toothfuse_mesh_file_free(f) };
    assert_eq!(read(&s, &amb, None, 9).0, toothfuse_status::InvalidArgument);
    let missing = CString::new(d.join("nope.vtp").to_str().unwrap()).unwrap();
    assert_eq!(read(&s, &missing, None, 0).0, toothfuse_status::Io);
    assert!(s.error().contains("nope.vtp"), "{}", s.error());
    let mut f = ptr::null_mut();
    // SAFETY: NULL path and NULL out pointer are what is checked.
    unsafe {
        assert_eq!(
            toothfuse_session_read_file(s.0, ptr::null(), ptr::null(), 0, &mut f),
            toothfuse_status::NullParameter
        );
        assert_eq!(
            toothfuse_session_read_file(s.0, path.as_ptr(), ptr::null(), 0, ptr::null_mut()),
            toothfuse_status::NullParameter
        );
    }
    assert_eq!(s.teeth(TOOTHFUSE_MODALITY_CBCT), vec![46]);
    let _ = std::fs::remove_dir_all(&d);
}
