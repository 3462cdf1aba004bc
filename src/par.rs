//! Deterministic data parallelism for per-tooth work (std threads only), and the cap a caller
//! (a host application, a session, the command line) puts on the threads it uses.

use std::cell::Cell;

/// Most threads one parallel step uses (teeth, hypotheses, volume labels).
const MOST_THREADS: usize = 4;

thread_local! {
    /// The cap [`with_max_threads`] set on this thread (0: none); worker threads get theirs
    /// from the thread that spawns them.
    static CAP: Cell<usize> = const { Cell::new(0) };
}

/// Runs `f` with the library's parallel steps using at most `n` threads in all, the calling
/// thread's included: it works on a step's items beside the threads it spawns (`0`: no cap: as
/// many as the CPUs the process may run on allow, at most 4 per step). With `n = 1` everything
/// runs on the calling thread and no thread is spawned. The results are the same bit for bit
/// whatever `n`: each parallel step computes every item from the item alone and returns the
/// results in the items' order.
///
/// The cap holds on the calling thread for the duration of `f` (other threads of the host are
/// not affected) and is restored afterwards, also when `f` panics.
pub fn with_max_threads<R>(n: usize, f: impl FnOnce() -> R) -> R {
    struct Restore(usize);
    impl Drop for Restore {
        fn drop(&mut self) {
            CAP.with(|c| c.set(self.0));
        }
    }
    let _restore = Restore(CAP.with(|c| c.replace(n)));
    f()
}

/// The cap [`with_max_threads`] put on the calling thread (0: none).
pub fn max_threads() -> usize {
    CAP.with(Cell::get)
}

/// The threads a step over `items` items takes: the CPUs allowed (at most [`MOST_THREADS`]),
/// no more than the cap on this thread, nor than the items.
fn threads_for(items: usize) -> usize {
    let cap = max_threads();
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut threads = cpus.clamp(1, MOST_THREADS).min(items.max(1));
    if cap > 0 {
        threads = threads.min(cap);
    }
    threads
}

/// Maps `f` over `work` on up to 4 threads, results in the order of `work`. Threads take the
/// next item from a shared counter (molars and incisors differ in cost several fold, so a fixed
/// deal would leave one thread last). Each result depends on its item only, so the output is the
/// same bit for bit whatever the thread count or the order the items are taken in.
pub(crate) fn map_ordered<T: Sync, R: Send>(work: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let order: Vec<usize> = (0..work.len()).collect();
    map_in_order(work, &order, f)
}

/// [`map_ordered`], the items taken largest `cost` first (ties in `work` order), results still
/// in the order of `work`: with items whose costs differ several fold, the last item a thread
/// takes is a small one, so the threads finish together.
pub(crate) fn map_ordered_by_cost<T: Sync, R: Send>(
    work: &[T],
    cost: impl Fn(&T) -> usize,
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    let mut order: Vec<usize> = (0..work.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(cost(&work[i])));
    map_in_order(work, &order, f)
}

/// Maps `f` over `work`, the threads taking the items in the order `order` (a permutation of
/// the indices), results in the order of `work`.
fn map_in_order<T: Sync, R: Send>(
    work: &[T],
    order: &[usize],
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    let threads = threads_for(work.len());
    if threads <= 1 {
        return work.iter().map(f).collect();
    }
    // Under a cap, the workers already use the threads it allows: a parallel step inside a
    // worker runs on that worker alone.
    let worker_cap = max_threads().min(1);
    let counter = std::sync::atomic::AtomicUsize::new(0);
    // Each worker takes the next item until none is left; the calling thread is one of them.
    let take = || {
        let mut out = Vec::new();
        loop {
            let k = counter.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let Some(&i) = order.get(k) else { break };
            out.push((i, f(&work[i])));
        }
        out
    };
    // The workers see the call's cancel flag and count their finished items (`progress`).
    let progress = crate::progress::shared();
    std::thread::scope(|s| {
        let take = &take;
        let handles: Vec<_> = (1..threads)
            .map(|_| {
                let progress = progress.clone();
                s.spawn(move || {
                    crate::progress::with_shared(progress, || with_max_threads(worker_cap, take))
                })
            })
            .collect();
        let mut all = with_max_threads(worker_cap, take);
        for h in handles {
            match h.join() {
                Ok(r) => all.extend(r),
                Err(p) => std::panic::resume_unwind(p),
            }
        }
        all.sort_by_key(|r| r.0);
        all.into_iter().map(|r| r.1).collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// The most threads running `f` at once over `work`, nested steps included, under `cap`.
    fn most_at_once(cap: usize, nested: bool) -> (usize, Vec<usize>) {
        let (now, most) = (AtomicUsize::new(0), AtomicUsize::new(0));
        let work: Vec<usize> = (0..24).collect();
        let step = |w: &usize| {
            let k = now.fetch_add(1, Ordering::SeqCst) + 1;
            most.fetch_max(k, Ordering::SeqCst);
            std::thread::sleep(std::time::Duration::from_millis(2));
            now.fetch_sub(1, Ordering::SeqCst);
            w * 3
        };
        let out = with_max_threads(cap, || {
            map_ordered(&work, |w| {
                if nested {
                    map_ordered(&[*w, *w + 1], step).iter().sum::<usize>() / 2
                } else {
                    step(w)
                }
            })
        });
        (most.load(Ordering::SeqCst), out)
    }

    /// A cap bounds the threads of a step and of the steps nested in it, and changes no result;
    /// it is lifted when the call returns.
    #[test]
    fn a_cap_bounds_the_threads_and_changes_no_result() {
        let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
        let expected: Vec<usize> = (0..24).map(|w| w * 3).collect();
        let nested_expected: Vec<usize> = (0..24).map(|w| (w * 3 + (w + 1) * 3) / 2).collect();
        for cap in [1, 2, 3] {
            let (most, out) = most_at_once(cap, false);
            assert!(most <= cap, "cap {cap}: {most} at once");
            assert_eq!(out, expected);
            let (most, out) = most_at_once(cap, true);
            assert!(most <= cap, "cap {cap}, nested: {most} at once");
            assert_eq!(out, nested_expected);
        }
        let (most, _) = most_at_once(0, false);
        assert!(most <= cpus.min(MOST_THREADS));
        if cpus > 1 {
            assert!(most > 1, "without a cap the step runs on {most} thread(s)");
        }
        assert_eq!(CAP.with(Cell::get), 0, "the cap is lifted after the call");
        let caught = std::panic::catch_unwind(|| with_max_threads(1, || panic!("inside")));
        assert!(caught.is_err());
        assert_eq!(CAP.with(Cell::get), 0, "the cap is lifted after a panic");
    }

    /// Whatever order the items are taken in (by cost, either way), the results come back in
    /// the order of the work, each computed from its own item, and each item is taken once.
    #[test]
    fn results_keep_the_work_order_whatever_the_cost_order() {
        let work: Vec<u64> = (0..37).map(|i| (i * 7919) % 101).collect();
        let expected: Vec<u64> = work.iter().map(|w| w * w + 1).collect();
        let taken = std::sync::atomic::AtomicUsize::new(0);
        let f = |w: &u64| {
            taken.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            w * w + 1
        };
        assert_eq!(map_ordered(&work, f), expected);
        assert_eq!(map_ordered_by_cost(&work, |&w| w as usize, f), expected);
        assert_eq!(
            map_ordered_by_cost(&work, |&w| 1000 - w as usize, f),
            expected
        );
        assert_eq!(map_ordered_by_cost(&work, |_| 0, f), expected);
        assert!(map_ordered_by_cost(&Vec::<u64>::new(), |_| 0, f).is_empty());
        assert_eq!(
            taken.load(std::sync::atomic::Ordering::Relaxed),
            4 * work.len()
        );
    }
}
