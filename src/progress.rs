//! Progress reports and cancellation of a long call (registration, crown cut, stitching, label
//! volume surfacing), for hosts that run the fusion in an interactive session: a progress bar,
//! and a way to abandon a run whose options the user has already changed.
//!
//! [`with_progress`] installs a callback on the calling thread for the duration of a closure.
//! The library's stages report to it ([`Progress`]: the stage, the units done and their total)
//! and it answers whether to go on. The callback is only ever called on the thread that
//! installed it, never on a worker thread, so a host needs no locking in it: the worker threads
//! of a parallel step count the units they finish and look at a shared flag; the calling thread,
//! which works on the step's items beside them, reports between its own items and between the
//! band builds of the tooth it stitches. Once the callback asks to stop, every thread leaves its
//! work at its next check (the next tooth, the next band build) and the call returns
//! [`Error::Cancelled`]; nothing the caller held is changed. Without a callback every check is a
//! thread-local read, and the results never depend on the callback (bit for bit).

use crate::{Error, Result};
use std::cell::RefCell;
use std::ops::ControlFlow;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// A stage of a long call, as [`Progress`] names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Stage {
    /// Registration: its steps (per-tooth preparation, the gate, the coarse stage, the fine
    /// stage, the per-tooth report).
    Register,
    /// Crown removal: the teeth cut.
    Cut,
    /// Stitching: the teeth stitched.
    Stitch,
    /// Surfacing a CBCT label volume's teeth (adding a label volume): the tooth labels
    /// surfaced. A per-jaw teeth mask is first split with the IOS crowns, which is checked for a
    /// cancel when it ends.
    Surface,
}

impl Stage {
    /// Lower-case name (`register`, `cut`, `stitch`, `surface`).
    pub fn name(self) -> &'static str {
        match self {
            Stage::Register => "register",
            Stage::Cut => "cut",
            Stage::Stitch => "stitch",
            Stage::Surface => "surface",
        }
    }
}

/// One progress report: `done` of `total` units of `stage` are finished. Within a stage `done`
/// never decreases; a report may repeat the last one (the calling thread reports between band
/// builds too, so that a cancel is answered within one build).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    /// The stage running.
    pub stage: Stage,
    /// Units finished.
    pub done: usize,
    /// Units in the stage.
    pub total: usize,
}

/// What the threads of one call share: the cancel flag and the stage's finished units.
#[derive(Default)]
pub(crate) struct Shared {
    cancelled: AtomicBool,
    done: AtomicUsize,
}

/// The callback and the stage it is told about; lives on the calling thread only.
struct Watch {
    callback: Box<dyn FnMut(Progress) -> ControlFlow<()>>,
    stage: Stage,
    total: usize,
}

thread_local! {
    /// The call's shared state: on the calling thread and on the workers it spawns.
    static SHARED: RefCell<Option<Arc<Shared>>> = const { RefCell::new(None) };
    /// The callback: on the calling thread only.
    static WATCH: RefCell<Option<Watch>> = const { RefCell::new(None) };
}

/// Runs `f` with `callback` receiving the progress of the library's long calls made inside it
/// on this thread; `ControlFlow::Break(())` from the callback cancels the call, which then
/// returns [`Error::Cancelled`] (a call that has already finished its work returns its result).
/// The callback is called on this thread only. A callback installed earlier on this thread is
/// set aside for the duration of `f` and restored afterwards, also when `f` panics.
pub fn with_progress<R>(
    callback: impl FnMut(Progress) -> ControlFlow<()> + 'static,
    f: impl FnOnce() -> R,
) -> R {
    struct Restore(Option<Watch>, Option<Arc<Shared>>);
    impl Drop for Restore {
        fn drop(&mut self) {
            WATCH.with(|w| *w.borrow_mut() = self.0.take());
            SHARED.with(|s| *s.borrow_mut() = self.1.take());
        }
    }
    let watch = Watch {
        callback: Box::new(callback),
        stage: Stage::Register,
        total: 0,
    };
    let _restore = Restore(
        WATCH.with(|w| w.borrow_mut().replace(watch)),
        SHARED.with(|s| s.borrow_mut().replace(Arc::default())),
    );
    f()
}

/// The call's shared state on this thread, for the workers a parallel step spawns.
pub(crate) fn shared() -> Option<Arc<Shared>> {
    SHARED.with(|s| s.borrow().clone())
}

/// Runs `f` (a worker's share of a parallel step) with the call's shared state `shared`.
pub(crate) fn with_shared<R>(shared: Option<Arc<Shared>>, f: impl FnOnce() -> R) -> R {
    struct Restore(Option<Arc<Shared>>);
    impl Drop for Restore {
        fn drop(&mut self) {
            SHARED.with(|s| *s.borrow_mut() = self.0.take());
        }
    }
    let _restore = Restore(SHARED.with(|s| std::mem::replace(&mut *s.borrow_mut(), shared)));
    f()
}

/// Starts `stage` of `total` units (on the calling thread; a worker has no callback and starts
/// nothing) and reports it.
pub(crate) fn start(stage: Stage, total: usize) {
    let started = WATCH.with(|w| match w.try_borrow_mut() {
        Ok(mut w) => w.as_mut().map(|w| {
            w.stage = stage;
            w.total = total;
        }),
        Err(_) => None,
    });
    if started.is_some() {
        SHARED.with(|s| {
            if let Some(s) = s.borrow().as_ref() {
                s.done.store(0, Ordering::Relaxed);
            }
        });
        go_on();
    }
}

/// One unit of the current stage finished (on any thread); reports it when on the calling
/// thread.
pub(crate) fn advance() {
    SHARED.with(|s| {
        if let Some(s) = s.borrow().as_ref() {
            s.done.fetch_add(1, Ordering::Relaxed);
        }
    });
    go_on();
}

/// Whether the call goes on: on the calling thread the callback is asked (with the stage's
/// units done so far); on a worker, whether the calling thread's callback has asked to stop.
/// Always true without a callback.
pub(crate) fn go_on() -> bool {
    let Some(shared) = shared() else {
        return true;
    };
    if shared.cancelled.load(Ordering::Relaxed) {
        return false;
    }
    // A callback that calls back into the library finds the watch borrowed: not asked again.
    let flow = WATCH.with(|w| match w.try_borrow_mut() {
        Ok(mut w) => w.as_mut().map(|w| {
            (w.callback)(Progress {
                stage: w.stage,
                done: shared.done.load(Ordering::Relaxed).min(w.total),
                total: w.total,
            })
        }),
        Err(_) => None,
    });
    if flow == Some(ControlFlow::Break(())) {
        shared.cancelled.store(true, Ordering::Relaxed);
        return false;
    }
    true
}

/// The end of a parallel step: the calling thread reports the units its workers finished after
/// its own last one (a host's progress bar reaches the stage's end).
pub(crate) fn ended() {
    go_on();
}

/// Whether the callback has asked to stop (no callback asked).
pub(crate) fn cancelled() -> bool {
    shared().is_some_and(|s| s.cancelled.load(Ordering::Relaxed))
}

/// One unit of `stage` (a tooth, a label) as a parallel step's item runs it: `work` is not
/// started once the callback has asked to stop ([`Error::Cancelled`] instead), and the unit is
/// counted ([`advance`]) either way.
pub(crate) fn unit<T>(stage: Stage, work: impl FnOnce() -> Result<T>) -> Result<T> {
    let r = check(stage).and_then(|()| work());
    advance();
    r
}

/// One unit of `stage` finished ([`advance`]), then [`check`].
pub(crate) fn step(stage: Stage) -> Result<()> {
    advance();
    check(stage)
}

/// `Err(Error::Cancelled)` naming `stage` once the callback has asked to stop.
pub(crate) fn check(stage: Stage) -> Result<()> {
    if cancelled() {
        return Err(Error::Cancelled(format!(
            "the progress callback asked to stop during the {} stage; nothing was changed",
            stage.name()
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
