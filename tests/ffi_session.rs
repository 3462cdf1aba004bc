//! The C ABI exercised from Rust as a C caller would: success paths, read-back fidelity, and
//! every error path (status, message, and that the session still holds what it held).

use std::ffi::{CStr, c_void};
use std::ptr;
use toothfuse::ffi::*;

/// An axis-aligned cube [0,s]^3 offset by `o`: 8 vertices, 12 outward triangles.
fn cube(s: f64, o: [f64; 3]) -> (Vec<f64>, Vec<u32>) {
    let mut v = Vec::new();
    for (x, y, z) in [
        (0., 0., 0.),
        (1., 0., 0.),
        (1., 1., 0.),
        (0., 1., 0.),
        (0., 0., 1.),
        (1., 0., 1.),
        (1., 1., 1.),
        (0., 1., 1.),
    ] {
        v.extend([o[0] + x * s, o[1] + y * s, o[2] + z * s]);
    }
    let t = vec![
        0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6,
        3, 0, 4, 3, 4, 7,
    ];
    (v, t)
}

/// An open square (2 triangles): a valid IOS crown, an invalid CBCT tooth.
fn square() -> (Vec<f64>, Vec<u32>) {
    (
        vec![0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.],
        vec![0, 1, 2, 0, 2, 3],
    )
}

struct Session(*mut toothfuse_session);

impl Session {
    fn new() -> Self {
        let mut p = ptr::null_mut();
        // SAFETY: valid out pointer.
        let st = unsafe { toothfuse_session_new(&mut p) };
        assert_eq!(st, toothfuse_status::Ok);
        assert!(!p.is_null());
        Session(p)
    }
    fn error(&self) -> String {
        // SAFETY: live session; the string is copied before the next call.
        unsafe { CStr::from_ptr(toothfuse_session_last_error(self.0)) }
            .to_str()
            .unwrap()
            .to_owned()
    }
    fn add(&self, m: toothfuse_modality, fdi: i32, v: &[f64], t: &[u32]) -> toothfuse_status {
        // SAFETY: buffers sized as announced.
        unsafe {
            toothfuse_session_add_tooth(
                self.0,
                m,
                fdi,
                v.as_ptr().cast(),
                v.len() / 3,
                24,
                TOOTHFUSE_SCALAR_FLOAT64,
                t.as_ptr(),
                t.len(),
            )
        }
    }
    fn teeth(&self, m: toothfuse_modality) -> Vec<i32> {
        let mut n = 0usize;
        // SAFETY: live session, valid out pointers.
        unsafe {
            assert_eq!(
                toothfuse_session_tooth_count(self.0, m, &mut n),
                toothfuse_status::Ok
            );
            let mut out = vec![0i32; n];
            let mut written = 0usize;
            assert_eq!(
                toothfuse_session_list_teeth(self.0, m, out.as_mut_ptr(), n, &mut written),
                toothfuse_status::Ok
            );
            assert_eq!(written, n);
            out
        }
    }
    fn positions(&self, m: toothfuse_modality, fdi: i32) -> Vec<f64> {
        let (mut nv, mut ni) = (0usize, 0usize);
        // SAFETY: live session, buffers sized from the size query.
        unsafe {
            assert_eq!(
                toothfuse_session_mesh_size(self.0, m, fdi, &mut nv, &mut ni),
                toothfuse_status::Ok
            );
            let mut out = vec![0f64; 3 * nv];
            assert_eq!(
                toothfuse_session_copy_vertices(
                    self.0,
                    m,
                    fdi,
                    out.as_mut_ptr().cast(),
                    nv,
                    24,
                    TOOTHFUSE_SCALAR_FLOAT64
                ),
                toothfuse_status::Ok
            );
            out
        }
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        // SAFETY: created by toothfuse_session_new, freed once.
        unsafe { toothfuse_session_free(self.0) };
    }
}

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
fn labeled_jaw_split_all_or_nothing() {
    let s = Session::new();
    // Two cubes (FDI 21, 22) and a gingiva square, labeled per vertex.
    let (mut v, mut t) = cube(2.0, [0.0; 3]);
    let (v2, t2) = cube(2.0, [5.0, 0.0, 0.0]);
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
    assert_eq!(
        s.error(),
        "tooth 14: face 2 duplicates face 0 (same three vertices)"
    );
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
