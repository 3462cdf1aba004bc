//! The progress callback of a session's long calls, and cancelling them from it.

use super::boundary::ffi_panic_boundary;
use super::session::{toothfuse_session, with_settings};
use super::status::toothfuse_status;
use crate::progress::{Progress, Stage};
use std::ffi::c_void;
use std::ops::ControlFlow;

/// A stage of a long call, as the progress callback is told it: one of the
/// `TOOTHFUSE_STAGE_*` values.
#[allow(non_camel_case_types)]
pub type toothfuse_stage = u32;
/// Registration (`toothfuse_session_register`, and the first part of `toothfuse_session_fuse`):
/// its 5 steps (per-tooth preparation, the gate, the coarse stage, the fine stage, the report).
pub const TOOTHFUSE_STAGE_REGISTER: toothfuse_stage = 1;
/// Crown removal: the teeth cut.
pub const TOOTHFUSE_STAGE_CUT: toothfuse_stage = 2;
/// Stitching: the teeth stitched.
pub const TOOTHFUSE_STAGE_STITCH: toothfuse_stage = 3;
/// Surfacing the teeth of a CBCT label volume (`toothfuse_session_add_label_volume`): the tooth
/// labels surfaced (a per-jaw teeth mask is first split with the IOS crowns: a cancel during the
/// split is answered when the split ends).
pub const TOOTHFUSE_STAGE_SURFACE: toothfuse_stage = 4;

/// The progress callback: `done` of `total` units of `stage` (a `TOOTHFUSE_STAGE_*` value) are
/// finished. Return 0 to go on, any other value to cancel the call, which then returns
/// TOOTHFUSE_STATUS_CANCELLED and leaves the session as it was before the call.
///
/// It is called on the thread that called the library function, never on one of the library's
/// worker threads and never twice at once: at each stage's start (`done` 0) and end (`done` =
/// `total`), when a unit ends on the calling thread, and between the band builds of the tooth
/// that thread stitches (a report may repeat the last one), so a cancel is answered within one
/// band build of a tooth or one registration step (measured: a median of 5-50 ms, at most
/// ~0.2 s, on the phantom, rough and foreign jaws). Within a stage `done` never decreases.
/// It must not call `toothfuse_*` functions on the same session and must not throw or unwind
/// (a C++ exception out of it is undefined behaviour).
#[allow(non_camel_case_types)]
pub type toothfuse_progress_fn = Option<
    unsafe extern "C" fn(
        user_data: *mut c_void,
        stage: toothfuse_stage,
        done: usize,
        total: usize,
    ) -> i32,
>;

/// A session's progress callback and the pointer it is given back.
#[derive(Clone, Copy)]
pub(crate) struct Hook {
    callback: unsafe extern "C" fn(*mut c_void, toothfuse_stage, usize, usize) -> i32,
    user_data: *mut c_void,
}

fn stage_value(stage: Stage) -> toothfuse_stage {
    match stage {
        Stage::Register => TOOTHFUSE_STAGE_REGISTER,
        Stage::Cut => TOOTHFUSE_STAGE_CUT,
        Stage::Stitch => TOOTHFUSE_STAGE_STITCH,
        Stage::Surface => TOOTHFUSE_STAGE_SURFACE,
    }
}

/// Runs `f` with `hook` (if any) receiving its progress on this thread.
pub(super) fn with_hook<R>(hook: Option<Hook>, f: impl FnOnce() -> R) -> R {
    let Some(h) = hook else {
        return f();
    };
    let callback = move |p: Progress| {
        // SAFETY: the host's callback with the pointer it gave, on the thread that called the
        // library (documented contract of `toothfuse_session_set_progress`).
        let answer = unsafe { (h.callback)(h.user_data, stage_value(p.stage), p.done, p.total) };
        if answer == 0 {
            ControlFlow::Continue(())
        } else {
            ControlFlow::Break(())
        }
    };
    crate::progress::with_progress(callback, f)
}

/// Sets the progress callback of this session's long calls (`_register`, `_fuse`,
/// `_fuse_registered`, `_cut`, `_stitch`, `_add_label_volume`), with `user_data` passed back to it unchanged; a NULL
/// `callback` removes it. See `toothfuse_progress_fn` for when it is called and how a cancel
/// works. The results are the same bit for bit with or without a callback. The session does not
/// own `user_data`: it must stay valid while the callback is set. Other sessions are not
/// affected.
///
/// # Safety
/// `session` must be NULL or a live session; `callback` NULL or a function with the signature
/// of `toothfuse_progress_fn` that is safe to call with `user_data` on the threads that call
/// this session's functions.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn toothfuse_session_set_progress(
    session: *mut toothfuse_session,
    callback: toothfuse_progress_fn,
    user_data: *mut c_void,
) -> toothfuse_status {
    ffi_panic_boundary! {
        let hook = callback.map(|callback| Hook { callback, user_data });
        // SAFETY: forwarded contract on `session`.
        unsafe { with_settings(session, |s| s.progress.set(hook)) }
    }
}
