//! `toothfuse_session_add_label_volume` exercised as a C caller would: an oblique affine and a
//! spacing grid, every label type, and the error paths (status, message naming the fault, the
//! session unchanged).

mod ffi_common;

mod real_data;

use ffi_common::Session;
use std::ffi::c_void;
use std::ptr;
use toothfuse::ffi::*;

const N: usize = 24;

/// A ball of radius 2.5 mm labelled `label` centred in an N³ grid, i fastest.
fn ball(label: i32) -> Vec<i32> {
    let mut v = vec![0; N * N * N];
    for k in 0..N {
        for j in 0..N {
            for i in 0..N {
                let c = |x: usize| (x as f64 - 11.5) * 0.25;
                if c(i).powi(2) + c(j).powi(2) + c(k).powi(2) < 6.25 {
                    v[i + N * (j + N * k)] = label;
                }
            }
        }
    }
    v
}

#[allow(clippy::too_many_arguments)]
fn add(
    s: &Session,
    dims: &[usize; 3],
    m: Option<&[f64; 16]>,
    labels: *const c_void,
    count: usize,
    ty: toothfuse_label_type,
    scheme: toothfuse_volume_scheme,
    added: &mut usize,
) -> toothfuse_status {
    let sp = [0.25, -0.25, 0.25];
    let or = [0.0, 0.0, 0.0];
    // SAFETY: every buffer holds what it announces.
    unsafe {
        toothfuse_session_add_label_volume(
            s.0,
            dims.as_ptr(),
            m.map_or(ptr::null(), |m| m.as_ptr()),
            sp.as_ptr(),
            or.as_ptr(),
            labels,
            count,
            ty,
            scheme,
            added,
        )
    }
}

#[test]
fn every_label_type_and_both_placements() {
    let s = Session::new();
    let b = ball(36);
    let n = b.len();
    let mut added = 0usize;
    // Oblique: 90° about z then shifted to (50, 60, 70); row-major.
    let c = 11.5 * 0.25;
    let m = [
        0.0,
        -0.25,
        0.0,
        50.0 + c,
        0.25,
        0.0,
        0.0,
        60.0 - c,
        0.0,
        0.0,
        0.25,
        70.0 - c,
        0.0,
        0.0,
        0.0,
        1.0,
    ];
    let st = add(
        &s,
        &[N; 3],
        Some(&m),
        b.as_ptr().cast(),
        n,
        TOOTHFUSE_LABEL_TYPE_INT32,
        0,
        &mut added,
    );
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    assert_eq!(added, 1);
    let p = s.positions(TOOTHFUSE_MODALITY_CBCT, 36);
    for q in p.chunks(3) {
        let d = ((q[0] - 50.0).powi(2) + (q[1] - 60.0).powi(2) + (q[2] - 70.0).powi(2)).sqrt();
        assert!((d - 2.5).abs() < 0.1, "radius {d}");
    }
    // Universal 30 = FDI 46, as u8, u16, i16 on the spacing grid.
    let u8s: Vec<u8> = ball(30).iter().map(|&v| v as u8).collect();
    let st = add(
        &s,
        &[N; 3],
        None,
        u8s.as_ptr().cast(),
        n,
        TOOTHFUSE_LABEL_TYPE_UINT8,
        TOOTHFUSE_VOLUME_SCHEME_UNIVERSAL,
        &mut added,
    );
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    let u16s: Vec<u16> = ball(47).iter().map(|&v| v as u16).collect();
    let st = add(
        &s,
        &[N; 3],
        None,
        u16s.as_ptr().cast(),
        n,
        TOOTHFUSE_LABEL_TYPE_UINT16,
        TOOTHFUSE_VOLUME_SCHEME_TOOTHFAIRY2,
        &mut added,
    );
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    let i16s: Vec<i16> = ball(45).iter().map(|&v| v as i16).collect();
    let st = add(
        &s,
        &[N; 3],
        None,
        i16s.as_ptr().cast(),
        n,
        TOOTHFUSE_LABEL_TYPE_INT16,
        0,
        &mut added,
    );
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    assert_eq!(s.teeth(TOOTHFUSE_MODALITY_CBCT), vec![36, 45, 46, 47]);
    // The spacing grid flips j (negative spacing): the ball's centre lands at y = -11.5 * 0.25.
    let p = s.positions(TOOTHFUSE_MODALITY_CBCT, 45);
    for q in p.chunks(3) {
        let d = ((q[0] - 2.875).powi(2) + (q[1] + 2.875).powi(2) + (q[2] - 2.875).powi(2)).sqrt();
        assert!((d - 2.5).abs() < 0.1, "radius {d}");
    }
}

#[test]
fn errors_name_the_fault_and_keep_the_session() {
    let s = Session::new();
    let b = ball(36);
    let n = b.len();
    let mut added = 0usize;
    assert_eq!(
        add(&s, &[N; 3], None, b.as_ptr().cast(), n, 3, 0, &mut added),
        toothfuse_status::Ok
    );
    let check = |st: toothfuse_status, want: toothfuse_status, msg: &str| {
        assert_eq!(st, want, "{}", s.error());
        assert!(
            s.error().contains(msg),
            "{:?} should say {msg:?}",
            s.error()
        );
        assert_eq!(
            s.teeth(TOOTHFUSE_MODALITY_CBCT),
            vec![36],
            "session unchanged"
        );
    };
    let b2 = ball(37);
    check(
        add(&s, &[N; 3], None, ptr::null(), n, 3, 0, &mut added),
        toothfuse_status::NullParameter,
        "labels",
    );
    check(
        add(
            &s,
            &[N, N, N - 1],
            None,
            b2.as_ptr().cast(),
            n,
            3,
            0,
            &mut added,
        ),
        toothfuse_status::InvalidArgument,
        "does not match dims",
    );
    check(
        add(&s, &[N; 3], None, b2.as_ptr().cast(), n, 9, 0, &mut added),
        toothfuse_status::InvalidArgument,
        "label type 9",
    );
    check(
        add(&s, &[N; 3], None, b2.as_ptr().cast(), n, 3, 7, &mut added),
        toothfuse_status::InvalidArgument,
        "volume scheme 7",
    );
    let mut neg = b2.clone();
    neg[5] = -1;
    check(
        add(&s, &[N; 3], None, neg.as_ptr().cast(), n, 3, 0, &mut added),
        toothfuse_status::InvalidArgument,
        "label -1 at voxel 5",
    );
    let mut two = b2.clone();
    two[0] = 3;
    check(
        add(&s, &[N; 3], None, two.as_ptr().cast(), n, 3, 0, &mut added),
        toothfuse_status::InvalidArgument,
        "label 3 is not an FDI",
    );
    let zeros = vec![0i32; n];
    check(
        add(
            &s,
            &[N; 3],
            None,
            zeros.as_ptr().cast(),
            n,
            3,
            0,
            &mut added,
        ),
        toothfuse_status::MissingData,
        "no tooth label",
    );
    let singular = [0.0; 16];
    check(
        add(
            &s,
            &[N; 3],
            Some(&singular),
            b2.as_ptr().cast(),
            n,
            3,
            0,
            &mut added,
        ),
        toothfuse_status::InvalidArgument,
        "not affine",
    );
    // SAFETY: NULL dims and NULL session are refused, not read.
    let st = unsafe {
        toothfuse_session_add_label_volume(
            s.0,
            ptr::null(),
            ptr::null(),
            ptr::null(),
            ptr::null(),
            b2.as_ptr().cast(),
            n,
            3,
            0,
            ptr::null_mut(),
        )
    };
    check(st, toothfuse_status::NullParameter, "dims");
    // SAFETY: as above.
    let st = unsafe {
        toothfuse_session_add_label_volume(
            ptr::null_mut(),
            [N; 3].as_ptr(),
            ptr::null(),
            ptr::null(),
            ptr::null(),
            b2.as_ptr().cast(),
            n,
            3,
            0,
            ptr::null_mut(),
        )
    };
    assert_eq!(st, toothfuse_status::NullParameter);
    assert_eq!(added, 1, "written only on success");
}

#[test]
fn per_jaw_volume_needs_the_ios_first() {
    let s = Session::new();
    let mut v = ball(0);
    for x in v.iter_mut().step_by(7) {
        *x = 4;
    }
    let mut added = 0usize;
    let st = add(
        &s,
        &[N; 3],
        None,
        v.as_ptr().cast(),
        v.len(),
        3,
        3,
        &mut added,
    );
    assert_eq!(st, toothfuse_status::MissingData);
    assert!(
        s.error().contains("add the IOS teeth first"),
        "{}",
        s.error()
    );
    let st = add(
        &s,
        &[N; 3],
        None,
        v.as_ptr().cast(),
        v.len(),
        3,
        4,
        &mut added,
    );
    assert_eq!(st, toothfuse_status::InvalidArgument);
    assert!(s.error().contains("DENTALSEGMENTATOR (3)"), "{}", s.error());
    assert!(s.teeth(TOOTHFUSE_MODALITY_CBCT).is_empty());
}

/// The STS 2024 mask's lower teeth merged into DentalSegmentator's lower teeth class, added
/// after the IOS crowns of a phantom built on them: every tooth split and added, and after a
/// registration each tooth's split among its warnings. Skipped when the real data is absent.
#[test]
fn per_jaw_volume_split_with_the_held_ios_crowns() {
    let Some(vol) = real_data::sts_lower_teeth() else {
        return;
    };
    let ph = real_data::phantom_on(&vol, toothfuse::arch::Jaw::Lower, 5);
    let s = Session::new();
    for (fdi, m) in ph.ios_crowns() {
        let v: Vec<f64> = m.positions.iter().flat_map(|p| p.to_array()).collect();
        let t: Vec<u32> = m.triangles.iter().flatten().copied().collect();
        assert_eq!(
            s.add(TOOTHFUSE_MODALITY_IOS, fdi as i32, &v, &t),
            toothfuse_status::Ok
        );
    }
    let labels: Vec<u16> = vol
        .labels
        .iter()
        .map(|&l| if l != 0 { 4 } else { 0 })
        .collect();
    let m = vol.voxel_to_world.transpose().to_cols_array();
    let mut added = 0usize;
    let st = add(
        &s,
        &vol.dims,
        Some(&m),
        labels.as_ptr().cast(),
        labels.len(),
        1,
        3,
        &mut added,
    );
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    assert_eq!(added, 10);
    // SAFETY: a live session; NULL options = defaults.
    let st = unsafe { toothfuse_session_register(s.0, ptr::null()) };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    let mut warnings = Vec::new();
    for i in 0.. {
        let mut w: *const std::ffi::c_char = ptr::null();
        // SAFETY: a live session and a writable pointer.
        if unsafe { toothfuse_session_tooth_warning(s.0, 36, i, &mut w) } != toothfuse_status::Ok {
            break;
        }
        // SAFETY: a NUL-terminated string borrowed from the session.
        warnings.push(
            unsafe { std::ffi::CStr::from_ptr(w) }
                .to_string_lossy()
                .into_owned(),
        );
    }
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("split from the per-jaw teeth mask") && w.contains("contested")),
        "{warnings:?}"
    );
}
