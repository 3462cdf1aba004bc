//! The progress callback through the C ABI on a small synthetic jaw: what it is told and on
//! which thread, that it changes no result, and that a cancel from it in any stage returns
//! CANCELLED with the session's earlier results kept bit for bit.

mod ffi_common;

use ffi_common::{Session, add_phantom, fuse_default, fused_copy, phantom, report_json};
use std::ffi::{CStr, c_void};
use std::ptr;
use std::thread::ThreadId;
use toothfuse::ffi::*;

/// What the callback saw, and when it asks to stop.
struct Log {
    /// Stop at the first report of this stage with at least this many units done.
    stop_at: Option<(toothfuse_stage, usize)>,
    seen: Vec<(toothfuse_stage, usize, usize, ThreadId)>,
}

unsafe extern "C" fn record(
    user_data: *mut c_void,
    stage: toothfuse_stage,
    done: usize,
    total: usize,
) -> i32 {
    // SAFETY: the tests pass a live `Log` they own exclusively for the call.
    let log = unsafe { &mut *user_data.cast::<Log>() };
    log.seen
        .push((stage, done, total, std::thread::current().id()));
    i32::from(log.stop_at.is_some_and(|(s, d)| s == stage && done >= d))
}

fn set(s: &Session, log: Option<&mut Log>) {
    let (cb, data): (toothfuse_progress_fn, *mut c_void) = match log {
        Some(l) => (Some(record), ptr::from_mut(l).cast()),
        None => (None, ptr::null_mut()),
    };
    // SAFETY: live session; the log outlives every call made while it is set.
    let st = unsafe { toothfuse_session_set_progress(s.0, cb, data) };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
}

/// The whole fused jaw (positions as bits, indices), the report JSON and a registered
/// transform: what a cancelled call must leave as it was.
fn held(s: &Session) -> (Vec<u64>, Vec<u32>, String, Vec<u64>) {
    let (v, t) = fused_copy(s, 0);
    let mut teeth = [0i32; 52];
    let (mut n, mut m) = (0usize, [0f64; 16]);
    // SAFETY: live session; room for 52 teeth and 16 doubles.
    unsafe {
        let st = toothfuse_session_fused_teeth(s.0, teeth.as_mut_ptr(), 52, &mut n);
        assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
        let which = TOOTHFUSE_TRANSFORM_CBCT_TO_OUTPUT;
        let st = toothfuse_session_transform(s.0, teeth[0], which, m.as_mut_ptr());
        assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    }
    let bits = |x: &[f64]| x.iter().map(|x| x.to_bits()).collect();
    (bits(&v), t, report_json(s), bits(&m))
}

/// The report JSON with its timings left out.
fn without_timing(json: &str) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_str(json).unwrap();
    v["timing_ms"] = serde_json::Value::Null;
    v
}

#[test]
fn null_session_is_refused_and_a_callback_is_set_and_removed() {
    // SAFETY: NULL is allowed and refused.
    let st =
        unsafe { toothfuse_session_set_progress(ptr::null_mut(), Some(record), ptr::null_mut()) };
    assert_eq!(st, toothfuse_status::NullParameter);
    let s = Session::new();
    let mut log = Log {
        stop_at: None,
        seen: Vec::new(),
    };
    set(&s, Some(&mut log));
    set(&s, None);
    // SAFETY: a NULL-terminated static string.
    let m = unsafe { CStr::from_ptr(toothfuse_status_string(toothfuse_status::Cancelled as u32)) };
    assert!(m.to_str().unwrap().contains("cancelled"));
}

#[test]
fn reports_come_in_stage_order_on_the_calling_thread_and_change_nothing() {
    let p = phantom(5);
    let (plain, watched) = (Session::new(), Session::new());
    let mut log = Log {
        stop_at: None,
        seen: Vec::new(),
    };
    set(&watched, Some(&mut log));
    for s in [&plain, &watched] {
        add_phantom(s, &p);
        fuse_default(s);
    }
    let (a, b) = (held(&plain), held(&watched));
    assert_eq!((&a.0, &a.1, &a.3), (&b.0, &b.1, &b.3));
    assert_eq!(without_timing(&a.2), without_timing(&b.2));
    let me = std::thread::current().id();
    assert!(
        log.seen.iter().all(|r| r.3 == me),
        "a report from another thread"
    );
    let stages: Vec<toothfuse_stage> = log.seen.iter().map(|r| r.0).collect();
    assert!(stages.windows(2).all(|w| w[0] <= w[1]), "{stages:?}");
    for stage in [
        TOOTHFUSE_STAGE_REGISTER,
        TOOTHFUSE_STAGE_CUT,
        TOOTHFUSE_STAGE_STITCH,
    ] {
        let of: Vec<_> = log.seen.iter().filter(|r| r.0 == stage).collect();
        assert!(!of.is_empty(), "stage {stage} not reported");
        assert_eq!(of[0].1, 0, "stage {stage} starts at 0");
        let last = of.last().unwrap();
        assert_eq!(last.1, last.2, "stage {stage} ends at its total");
        assert!(of.windows(2).all(|w| w[0].1 <= w[1].1 && w[0].2 == w[1].2));
    }
}

#[test]
fn a_cancel_in_any_stage_returns_cancelled_and_keeps_the_earlier_results() {
    let p = phantom(5);
    let s = Session::new();
    add_phantom(&s, &p);
    fuse_default(&s);
    let before = held(&s);
    type Call =
        unsafe extern "C" fn(*mut toothfuse_session, *const toothfuse_options) -> toothfuse_status;
    let calls: [(&str, Call, toothfuse_stage); 5] = [
        ("fuse", toothfuse_session_fuse, TOOTHFUSE_STAGE_REGISTER),
        ("fuse", toothfuse_session_fuse, TOOTHFUSE_STAGE_CUT),
        ("fuse", toothfuse_session_fuse, TOOTHFUSE_STAGE_STITCH),
        (
            "fuse_registered",
            toothfuse_session_fuse_registered,
            TOOTHFUSE_STAGE_STITCH,
        ),
        (
            "register",
            toothfuse_session_register,
            TOOTHFUSE_STAGE_REGISTER,
        ),
    ];
    let names = ["", "register", "cut", "stitch"];
    for (name, call, stage) in calls {
        let mut log = Log {
            stop_at: Some((stage, 1)),
            seen: Vec::new(),
        };
        set(&s, Some(&mut log));
        // SAFETY: live session, NULL options = defaults; the log outlives the call.
        let st = unsafe { call(s.0, ptr::null()) };
        let tag = format!("{name} cancelled in stage {stage}");
        assert_eq!(st, toothfuse_status::Cancelled, "{tag}: {}", s.error());
        assert!(
            s.error().contains(names[stage as usize]),
            "{tag}: {}",
            s.error()
        );
        set(&s, None);
        // Not asked again after it asked to stop.
        assert_eq!(
            log.seen.iter().filter(|r| r.0 == stage && r.1 >= 1).count(),
            1,
            "{tag}"
        );
        let after = held(&s);
        assert_eq!(
            (&before.0, &before.1, &before.3),
            (&after.0, &after.1, &after.3),
            "{tag}"
        );
        assert_eq!(before.2, after.2, "{tag}: report");
    }
    // The separate stages: a cancelled cut, then a cut held and its stitching cancelled.
    for (call, stage) in [
        (toothfuse_session_cut as Call, TOOTHFUSE_STAGE_CUT),
        (toothfuse_session_stitch as Call, TOOTHFUSE_STAGE_STITCH),
    ] {
        if stage == TOOTHFUSE_STAGE_STITCH {
            // SAFETY: live session, NULL options = defaults.
            let st = unsafe { toothfuse_session_cut(s.0, ptr::null()) };
            assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
        }
        let mut log = Log {
            stop_at: Some((stage, 0)),
            seen: Vec::new(),
        };
        set(&s, Some(&mut log));
        // SAFETY: live session, NULL options = defaults; the log outlives the call.
        let st = unsafe { call(s.0, ptr::null()) };
        assert_eq!(
            st,
            toothfuse_status::Cancelled,
            "stage {stage}: {}",
            s.error()
        );
        set(&s, None);
        assert_eq!(log.seen.len(), 1, "stage {stage}: {:?}", log.seen);
        let after = held(&s);
        assert_eq!(
            (&before.0, &before.1, &before.3),
            (&after.0, &after.1, &after.3)
        );
        assert_eq!(before.2, after.2, "stage {stage}: report");
    }
    // The session still works, without the callback.
    fuse_default(&s);
    let again = held(&s);
    assert_eq!(
        (&before.0, &before.1, &before.3),
        (&again.0, &again.1, &again.3)
    );
}

/// A ball of radius 2.5 mm labelled 11 centred in a 24³ grid of 0.25 mm voxels (i fastest).
fn ball_volume() -> Vec<u8> {
    const N: usize = 24;
    let mut v = vec![0u8; N * N * N];
    for k in 0..N {
        for j in 0..N {
            for i in 0..N {
                let c = |x: usize| (x as f64 - 11.5) * 0.25;
                if c(i).powi(2) + c(j).powi(2) + c(k).powi(2) < 6.25 {
                    v[i + N * (j + N * k)] = 11;
                }
            }
        }
    }
    v
}

/// Adds the ball volume; returns the status and the teeth added.
fn add_ball(s: &Session, labels: &[u8]) -> (toothfuse_status, usize) {
    let (dims, sp, or) = ([24usize; 3], [0.25; 3], [0.0; 3]);
    let mut added = 0usize;
    // SAFETY: every buffer holds what it announces.
    let st = unsafe {
        toothfuse_session_add_label_volume(
            s.0,
            dims.as_ptr(),
            ptr::null(),
            sp.as_ptr(),
            or.as_ptr(),
            labels.as_ptr().cast(),
            labels.len(),
            TOOTHFUSE_LABEL_TYPE_UINT8,
            TOOTHFUSE_VOLUME_SCHEME_FDI,
            &mut added,
        )
    };
    (st, added)
}

#[test]
fn a_label_volume_reports_its_surfacing_and_a_cancel_adds_nothing() {
    let labels = ball_volume();
    let s = Session::new();
    let mut log = Log {
        stop_at: Some((TOOTHFUSE_STAGE_SURFACE, 0)),
        seen: Vec::new(),
    };
    set(&s, Some(&mut log));
    let (st, added) = add_ball(&s, &labels);
    assert_eq!(st, toothfuse_status::Cancelled, "{}", s.error());
    assert!(s.error().contains("surface"), "{}", s.error());
    assert_eq!(added, 0);
    assert!(s.teeth(TOOTHFUSE_MODALITY_CBCT).is_empty());
    let mut log = Log {
        stop_at: None,
        seen: Vec::new(),
    };
    set(&s, Some(&mut log));
    let (st, added) = add_ball(&s, &labels);
    set(&s, None);
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    assert_eq!(added, 1);
    assert_eq!(s.teeth(TOOTHFUSE_MODALITY_CBCT), vec![11]);
    let reports: Vec<(toothfuse_stage, usize, usize)> =
        log.seen.iter().map(|r| (r.0, r.1, r.2)).collect();
    assert_eq!(reports.first(), Some(&(TOOTHFUSE_STAGE_SURFACE, 0, 1)));
    assert_eq!(reports.last(), Some(&(TOOTHFUSE_STAGE_SURFACE, 1, 1)));
}
