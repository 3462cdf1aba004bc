//! The progress callback on a whole fuse of the phantom jaw: what it is told, on which thread,
//! that it changes no result, and that a cancel stops the call with nothing returned.

use super::*;
use crate::phantom::{Phantom, PhantomOptions};
use crate::pipeline::{PipelineOptions, PipelineResult, fuse};
use std::cell::RefCell;
use std::rc::Rc;
use std::thread::ThreadId;

fn jaw() -> Phantom {
    Phantom::generate(&PhantomOptions::default()).expect("phantom")
}

/// Every fused vertex and triangle, the positions as bits.
fn fingerprint(r: &PipelineResult) -> (Vec<[u64; 3]>, Vec<[u32; 3]>) {
    let m = &r.jaw.mesh;
    (
        m.positions
            .iter()
            .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
            .collect(),
        m.triangles.clone(),
    )
}

/// Runs `f` under a callback recording each report and its thread; the callback stops the
/// call at the first report `stop_at` accepts.
fn watched<R>(
    stop_at: impl Fn(&Progress) -> bool + 'static,
    f: impl FnOnce() -> R,
) -> (R, Vec<(Progress, ThreadId)>) {
    let seen = Rc::new(RefCell::new(Vec::new()));
    let log = Rc::clone(&seen);
    let r = with_progress(
        move |p| {
            log.borrow_mut().push((p, std::thread::current().id()));
            if stop_at(&p) {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        },
        f,
    );
    let seen = seen.borrow().clone();
    (r, seen)
}

#[test]
fn every_stage_is_reported_in_order_on_the_calling_thread_and_nothing_changes() {
    let p = jaw();
    let opts = PipelineOptions::default();
    let plain = fuse(&p.ios, &p.cbct, &opts).expect("fuse");
    let (r, seen) =
        crate::with_max_threads(2, || watched(|_| false, || fuse(&p.ios, &p.cbct, &opts)));
    let r = r.expect("fuse under a callback");
    assert_eq!(fingerprint(&plain), fingerprint(&r));
    let me = std::thread::current().id();
    assert!(seen.iter().all(|(_, t)| *t == me), "a report from a worker");
    let teeth = r.jaw.teeth.len();
    for (stage, total) in [
        (Stage::Register, 5),
        (Stage::Cut, teeth),
        (Stage::Stitch, teeth),
    ] {
        let of: Vec<&Progress> = seen
            .iter()
            .map(|(p, _)| p)
            .filter(|p| p.stage == stage)
            .collect();
        assert!(!of.is_empty(), "{stage:?} not reported");
        assert!(of.iter().all(|p| p.total == total), "{stage:?}: {of:?}");
        assert!(of.windows(2).all(|w| w[0].done <= w[1].done), "{stage:?}");
        assert_eq!(of[0].done, 0, "{stage:?} starts at 0");
        assert_eq!(of.last().map(|p| p.done), Some(total), "{stage:?} ends");
    }
    // The stages come in order: no report of an earlier stage after a later one.
    let rank = |s: Stage| {
        [Stage::Register, Stage::Cut, Stage::Stitch]
            .iter()
            .position(|&x| x == s)
    };
    assert!(
        seen.windows(2)
            .all(|w| rank(w[0].0.stage) <= rank(w[1].0.stage))
    );
    // Without a callback nothing is left behind on this thread.
    assert!(shared().is_none() && go_on() && !cancelled());
}

#[test]
fn a_cancel_in_any_stage_returns_cancelled_naming_it_and_ends_the_reports() {
    let p = jaw();
    let opts = PipelineOptions::default();
    for threads in [1, 2] {
        for (stage, at) in [(Stage::Register, 2), (Stage::Cut, 1), (Stage::Stitch, 3)] {
            let (r, seen) = crate::with_max_threads(threads, || {
                watched(
                    move |p| p.stage == stage && p.done >= at,
                    || fuse(&p.ios, &p.cbct, &opts),
                )
            });
            let tag = format!("{stage:?} at {at}, {threads} threads");
            match r {
                Err(Error::Cancelled(m)) => assert!(m.contains(stage.name()), "{tag}: {m}"),
                other => panic!("{tag}: {:?}", other.map(|r| r.jaw.teeth.len())),
            }
            // The callback is not asked again once it has asked to stop.
            let last = seen.last().expect("reports").0;
            assert!(last.stage == stage && last.done >= at, "{tag}: {last:?}");
            assert_eq!(
                seen.iter()
                    .filter(|(p, _)| p.stage == stage && p.done >= at)
                    .count(),
                1,
                "{tag}"
            );
        }
    }
}

#[test]
fn a_stitch_cancelled_on_one_thread_stitches_no_further_tooth() {
    let p = jaw();
    let opts = crate::fuse::FuseOptions::default();
    let cut = crate::fuse::cut_jaw(&p.ios, &p.cbct, &crate::eval::true_transforms(&p), &opts)
        .expect("cut");
    let teeth = cut.teeth.len();
    assert!(teeth > 2);
    // The calling thread stitches every tooth, and reports a tooth's end before it starts the
    // next one: the cancel after the second leaves the others unstitched, each failed as
    // cancelled.
    let (jaw, _) = crate::with_max_threads(1, || {
        watched(
            |p| p.stage == Stage::Stitch && p.done == 2,
            || crate::fuse::stitch_jaw(&cut, &opts),
        )
    });
    assert_eq!(jaw.teeth.len(), 2);
    let cancelled: Vec<u8> = jaw
        .failed
        .iter()
        .filter(|(_, e)| matches!(e, Error::Cancelled(_)))
        .map(|(f, _)| *f)
        .collect();
    assert_eq!(cancelled.len(), teeth - 2, "{:?}", jaw.failed);
    // Without the callback the same cut stitches every tooth.
    assert_eq!(crate::fuse::stitch_jaw(&cut, &opts).teeth.len(), teeth);
}

#[test]
fn the_callback_is_restored_after_a_nested_one_and_after_a_panic() {
    let outer = Rc::new(RefCell::new(0usize));
    let count = Rc::clone(&outer);
    with_progress(
        move |_| {
            *count.borrow_mut() += 1;
            ControlFlow::Continue(())
        },
        || {
            start(Stage::Cut, 2);
            let before = *outer.borrow();
            // A nested callback that cancels leaves the outer call going on.
            with_progress(
                |_| ControlFlow::Break(()),
                || {
                    start(Stage::Stitch, 1);
                    assert!(cancelled() && check(Stage::Stitch).is_err());
                },
            );
            assert!(!cancelled() && check(Stage::Cut).is_ok());
            let panicked = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                with_progress(|_| ControlFlow::Break(()), || panic!("inside"))
            }));
            assert!(panicked.is_err());
            advance();
            assert_eq!(
                *outer.borrow(),
                before + 1,
                "the outer callback asked again"
            );
        },
    );
    assert!(shared().is_none() && go_on());
}
