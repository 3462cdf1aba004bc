//! The C ABI exercised from Rust as a C caller would: success paths, read-back fidelity, and
//! every error path (status, message, and that the session still holds what it held).

mod ffi_common;

use ffi_common::{Session, cube, square};
use std::ffi::{CStr, c_void};
use std::ptr;
use toothfuse::ffi::*;

#[test]
fn versions_and_status_strings() {
    // SAFETY: static NUL-terminated strings.
    let v = unsafe { CStr::from_ptr(toothfuse_version()) };
    assert_eq!(v.to_str().unwrap(), env!("CARGO_PKG_VERSION"));
    assert_eq!(toothfuse_abi_version(), TOOTHFUSE_ABI_VERSION);
    let s = |x: u32| {
        // SAFETY: static NUL-terminated strings.
        unsafe { CStr::from_ptr(toothfuse_status_string(x)) }
            .to_str()
            .unwrap()
    };
    assert_eq!(s(0), "ok");
    assert_eq!(s(9), "output buffer too small");
    assert_eq!(s(999), "unknown status");
    // SAFETY: NULL is allowed.
    unsafe { toothfuse_session_free(ptr::null_mut()) };
    // SAFETY: NULL is allowed.
    let st = unsafe { toothfuse_session_new(ptr::null_mut()) };
    assert_eq!(st, toothfuse_status::NullParameter);
}

#[test]
fn add_list_read_back_bitwise_and_float() {
    let s = Session::new();
    let (v, t) = cube(7.25, [10.1, -3.3, 0.7]);
    assert_eq!(
        s.add(TOOTHFUSE_MODALITY_CBCT, 36, &v, &t),
        toothfuse_status::Ok
    );
    assert_eq!(s.error(), "");
    let (sv, st) = square();
    assert_eq!(
        s.add(TOOTHFUSE_MODALITY_IOS, 36, &sv, &st),
        toothfuse_status::Ok
    );
    assert_eq!(
        s.add(TOOTHFUSE_MODALITY_IOS, 35, &sv, &st),
        toothfuse_status::Ok
    );
    assert_eq!(s.teeth(TOOTHFUSE_MODALITY_CBCT), vec![36]);
    assert_eq!(s.teeth(TOOTHFUSE_MODALITY_IOS), vec![35, 36]);
    let back = s.positions(TOOTHFUSE_MODALITY_CBCT, 36);
    assert!(back.iter().zip(&v).all(|(a, b)| a.to_bits() == b.to_bits()));

    // Borrowed view: same bits, same triangles.
    let mut view = toothfuse_mesh_view {
        positions: ptr::null(),
        vertex_count: 0,
        indices: ptr::null(),
        index_count: 0,
    };
    // SAFETY: live session; the view is read before the session changes.
    unsafe {
        assert_eq!(
            toothfuse_session_mesh_view(s.0, TOOTHFUSE_MODALITY_CBCT, 36, &mut view),
            toothfuse_status::Ok
        );
        let p = std::slice::from_raw_parts(view.positions, 3 * view.vertex_count);
        let i = std::slice::from_raw_parts(view.indices, view.index_count);
        assert_eq!(p, &v[..]);
        assert_eq!(i, &t[..]);
    }

    // Float input at a padded stride of 16 bytes: exact conversion to double, and float
    // copy-out with the same stride leaves the padding untouched.
    let f: Vec<f32> = v
        .chunks(3)
        .flat_map(|c| [c[0] as f32, c[1] as f32, c[2] as f32, -1.0])
        .collect();
    // SAFETY: 8 vertices at stride 16 in `f`.
    let st = unsafe {
        toothfuse_session_add_tooth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            46,
            f.as_ptr().cast(),
            8,
            16,
            TOOTHFUSE_SCALAR_FLOAT32,
            t.as_ptr(),
            t.len(),
        )
    };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    let back = s.positions(TOOTHFUSE_MODALITY_CBCT, 46);
    for (k, b) in back.iter().enumerate() {
        assert_eq!(*b, f[(k / 3) * 4 + k % 3] as f64);
    }
    let mut fo = vec![9.5f32; 32];
    // SAFETY: room for 8 vertices at stride 16.
    let st = unsafe {
        toothfuse_session_copy_vertices(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            46,
            fo.as_mut_ptr().cast(),
            8,
            16,
            TOOTHFUSE_SCALAR_FLOAT32,
        )
    };
    assert_eq!(st, toothfuse_status::Ok);
    for (a, b) in fo.chunks(4).zip(f.chunks(4)) {
        assert_eq!(&a[..3], &b[..3]);
        assert_eq!(a[3], 9.5);
    }

    // Info: the cube is closed, the square has one boundary loop of 4 vertices.
    let mut info = toothfuse_mesh_info::default();
    // SAFETY: live session, valid out pointer.
    unsafe {
        assert_eq!(
            toothfuse_session_mesh_info(s.0, TOOTHFUSE_MODALITY_CBCT, 36, &mut info),
            toothfuse_status::Ok
        );
        assert!(info.closed && info.manifold);
        assert_eq!((info.vertex_count, info.triangle_count), (8, 12));
        assert_eq!((info.boundary_loops, info.components), (0, 1));
        assert!((info.signed_volume - 7.25f64.powi(3)).abs() < 1e-9);
        assert_eq!(
            toothfuse_session_mesh_info(s.0, TOOTHFUSE_MODALITY_IOS, 35, &mut info),
            toothfuse_status::Ok
        );
        assert!(!info.closed && info.manifold);
        assert_eq!((info.boundary_loops, info.longest_loop_vertices), (1, 4));
    }

    // Remove.
    // SAFETY: live session.
    unsafe {
        assert_eq!(
            toothfuse_session_remove_tooth(s.0, TOOTHFUSE_MODALITY_IOS, 35),
            toothfuse_status::Ok
        );
        assert_eq!(
            toothfuse_session_remove_tooth(s.0, TOOTHFUSE_MODALITY_IOS, 35),
            toothfuse_status::MissingData
        );
    }
    assert_eq!(
        s.error(),
        "missing data: no IOS tooth 35 in the session (IOS teeth held: 36)"
    );
    assert_eq!(s.teeth(TOOTHFUSE_MODALITY_IOS), vec![36]);
}

/// Asserts that the session still holds CBCT tooth 11 as `v`, and nothing else.
fn still_holds(s: &Session, v: &[f64]) {
    assert_eq!(s.teeth(TOOTHFUSE_MODALITY_CBCT), vec![11]);
    assert!(s.teeth(TOOTHFUSE_MODALITY_IOS).is_empty());
    assert_eq!(s.positions(TOOTHFUSE_MODALITY_CBCT, 11), v);
}

#[test]
fn error_paths_name_the_fault_and_change_nothing() {
    let s = Session::new();
    let (v, t) = cube(5.0, [0.0; 3]);
    assert_eq!(
        s.add(TOOTHFUSE_MODALITY_CBCT, 11, &v, &t),
        toothfuse_status::Ok
    );

    // NaN coordinate: replacing 11 fails, 11 stays.
    let mut bad = v.clone();
    bad[3 * 5 + 1] = f64::NAN;
    assert_eq!(
        s.add(TOOTHFUSE_MODALITY_CBCT, 11, &bad, &t),
        toothfuse_status::NonFinite
    );
    assert_eq!(
        s.error(),
        "tooth 11: vertex 5 has a non-finite coordinate (NaN or infinity)"
    );
    still_holds(&s, &v);

    // Out-of-range index.
    let mut bt = t.clone();
    bt[7] = 8;
    assert_eq!(
        s.add(TOOTHFUSE_MODALITY_CBCT, 11, &v, &bt),
        toothfuse_status::IndexOutOfBounds
    );
    assert_eq!(
        s.error(),
        "tooth 11: face 2 refers to vertex 8, but the mesh has only 8 vertices"
    );
    still_holds(&s, &v);

    // Open CBCT tooth.
    assert_eq!(
        s.add(TOOTHFUSE_MODALITY_CBCT, 11, &v, &t[6..]),
        toothfuse_status::NotManifold
    );
    assert!(
        s.error()
            .starts_with("tooth 11: mesh is not closed: 4 boundary edges"),
        "{}",
        s.error()
    );
    still_holds(&s, &v);

    // Non-FDI number and unknown enum values.
    assert_eq!(
        s.add(TOOTHFUSE_MODALITY_CBCT, 19, &v, &t),
        toothfuse_status::InvalidArgument
    );
    assert!(
        s.error().contains("19 is not an FDI tooth number"),
        "{}",
        s.error()
    );
    assert_eq!(s.add(7, 11, &v, &t), toothfuse_status::InvalidArgument);
    assert!(s.error().contains("modality 7"), "{}", s.error());
    still_holds(&s, &v);

    // SAFETY: every buffer below is either NULL with a zero count or sized as announced.
    unsafe {
        // Wrong stride: 20 bytes < 3 doubles.
        let st = toothfuse_session_add_tooth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            11,
            v.as_ptr().cast(),
            8,
            20,
            TOOTHFUSE_SCALAR_FLOAT64,
            t.as_ptr(),
            t.len(),
        );
        assert_eq!(st, toothfuse_status::InvalidArgument);
        assert!(
            s.error()
                .contains("vertex stride 20 bytes is smaller than one vertex"),
            "{}",
            s.error()
        );
        // Overflowing count * stride.
        let st = toothfuse_session_add_tooth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            11,
            v.as_ptr().cast(),
            usize::MAX / 2,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
            t.as_ptr(),
            t.len(),
        );
        assert_eq!(st, toothfuse_status::InvalidArgument);
        assert!(s.error().contains("overflow"), "{}", s.error());
        // Unknown scalar type.
        let st = toothfuse_session_add_tooth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            11,
            v.as_ptr().cast(),
            8,
            24,
            5,
            t.as_ptr(),
            t.len(),
        );
        assert_eq!(st, toothfuse_status::InvalidArgument);
        // NULL pointers with non-zero counts.
        let st = toothfuse_session_add_tooth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            11,
            ptr::null(),
            8,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
            t.as_ptr(),
            t.len(),
        );
        assert_eq!(st, toothfuse_status::NullParameter);
        assert_eq!(
            s.error(),
            "tooth 11: parameter `vertices` is NULL but 192 elements were announced"
        );
        let st = toothfuse_session_add_tooth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            11,
            v.as_ptr().cast(),
            8,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
            ptr::null(),
            36,
        );
        assert_eq!(st, toothfuse_status::NullParameter);
        // Empty mesh.
        let st = toothfuse_session_add_tooth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            11,
            ptr::null(),
            0,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
            ptr::null(),
            0,
        );
        assert_eq!(st, toothfuse_status::InvalidArgument);
        assert_eq!(
            s.error(),
            "tooth 11: invalid argument: CBCT tooth mesh has no triangles"
        );
        // Index count not a multiple of 3.
        let st = toothfuse_session_add_tooth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            11,
            v.as_ptr().cast(),
            8,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
            t.as_ptr(),
            35,
        );
        assert_eq!(st, toothfuse_status::InvalidArgument);
        // Misaligned index pointer.
        let raw: Vec<u8> = t[..3].iter().flat_map(|x| x.to_ne_bytes()).collect();
        let mut shifted = [0u8; 24];
        let off = (0..8)
            .find(|o| (shifted.as_ptr() as usize + o) % 4 == 1)
            .unwrap();
        shifted[off..off + 12].copy_from_slice(&raw);
        let st = toothfuse_session_add_tooth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            11,
            v.as_ptr().cast(),
            8,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
            shifted.as_ptr().add(off).cast(),
            3,
        );
        assert_eq!(st, toothfuse_status::InvalidArgument);
        assert!(s.error().contains("not aligned"), "{}", s.error());
        // NULL session.
        let st = toothfuse_session_add_tooth(
            ptr::null_mut(),
            TOOTHFUSE_MODALITY_CBCT,
            11,
            v.as_ptr().cast(),
            8,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
            t.as_ptr(),
            t.len(),
        );
        assert_eq!(st, toothfuse_status::NullParameter);
        assert_eq!(
            CStr::from_ptr(toothfuse_session_last_error(ptr::null()))
                .to_str()
                .unwrap(),
            "session is NULL"
        );
    }
    still_holds(&s, &v);
}

#[test]
fn output_errors_write_nothing() {
    let s = Session::new();
    let (v, t) = cube(5.0, [0.0; 3]);
    assert_eq!(
        s.add(TOOTHFUSE_MODALITY_CBCT, 11, &v, &t),
        toothfuse_status::Ok
    );
    // SAFETY: buffers sized as announced (or NULL where the test says so).
    unsafe {
        let mut out = vec![-1.0f64; 21];
        let st = toothfuse_session_copy_vertices(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            11,
            out.as_mut_ptr().cast(),
            7,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
        );
        assert_eq!(st, toothfuse_status::BufferTooSmall);
        assert_eq!(
            s.error(),
            "tooth 11: 8 vertices to copy but the buffer has room for 7"
        );
        assert!(out.iter().all(|&x| x == -1.0));
        let mut idx = vec![7u32; 35];
        let st =
            toothfuse_session_copy_indices(s.0, TOOTHFUSE_MODALITY_CBCT, 11, idx.as_mut_ptr(), 35);
        assert_eq!(st, toothfuse_status::BufferTooSmall);
        assert!(idx.iter().all(|&x| x == 7));
        let mut fdis = [0i32; 1];
        let mut n = 99usize;
        let st = toothfuse_session_list_teeth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            fdis.as_mut_ptr(),
            0,
            &mut n,
        );
        assert_eq!(st, toothfuse_status::BufferTooSmall);
        assert_eq!(n, 99);
        assert_eq!(s.error(), "1 CBCT teeth held but `fdi_out` has room for 0");
        let st = toothfuse_session_list_teeth(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            fdis.as_mut_ptr(),
            1,
            ptr::null_mut(),
        );
        assert_eq!(st, toothfuse_status::NullParameter);
        assert_eq!(s.error(), "parameter `count_out` is NULL");
        assert_eq!(fdis[0], 0);
        let st = toothfuse_session_mesh_view(s.0, TOOTHFUSE_MODALITY_CBCT, 11, ptr::null_mut());
        assert_eq!(st, toothfuse_status::NullParameter);
        let mut nv = 5usize;
        let mut ni = 5usize;
        let st = toothfuse_session_mesh_size(s.0, TOOTHFUSE_MODALITY_IOS, 11, &mut nv, &mut ni);
        assert_eq!(st, toothfuse_status::MissingData);
        assert_eq!((nv, ni), (5, 5));
        let st = toothfuse_session_mesh_size(s.0, TOOTHFUSE_MODALITY_CBCT, 11, &mut nv, &mut ni);
        assert_eq!(st, toothfuse_status::Ok);
        assert_eq!((nv, ni), (8, 36));
        assert_eq!(s.error(), "");
        let mut src = vec![0u32; 8];
        let st = toothfuse_session_copy_source_vertices(
            s.0,
            TOOTHFUSE_MODALITY_CBCT,
            11,
            src.as_mut_ptr(),
            8,
        );
        assert_eq!(st, toothfuse_status::Ok);
        assert_eq!(src, (0..8).collect::<Vec<u32>>());
        // Null session on a query.
        let st = toothfuse_session_tooth_count(ptr::null(), TOOTHFUSE_MODALITY_CBCT, &mut n);
        assert_eq!(st, toothfuse_status::NullParameter);
    }
    still_holds(&s, &v);
}

#[test]
fn unused_pointer_type_is_void() {
    // Compile-time check that the vertex parameters take untyped memory.
    let _: unsafe extern "C" fn(
        *mut toothfuse_session,
        u32,
        i32,
        *const c_void,
        usize,
        usize,
        u32,
        *const u32,
        usize,
    ) -> toothfuse_status = toothfuse_session_add_tooth;
}
