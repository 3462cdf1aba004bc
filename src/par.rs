//! Deterministic data parallelism for per-tooth work (std threads only).

/// [`map_ordered`], with the items taken largest `cost` first (ties in the order of `work`):
/// the last item a thread takes is then a short one, so no thread is left running a long
/// one alone. Results in the order of `work`, the same bit for bit as [`map_ordered`]'s.
pub(crate) fn map_ordered_by_cost<T: Sync, R: Send>(
    work: &[T],
    cost: impl Fn(&T) -> usize,
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    let mut order: Vec<usize> = (0..work.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(cost(&work[i])));
    let done = map_ordered(&order, |&i| (i, f(&work[i])));
    let mut out: Vec<Option<R>> = (0..work.len()).map(|_| None).collect();
    for (i, r) in done {
        out[i] = Some(r);
    }
    out.into_iter()
        .map(|r| r.expect("every item mapped once"))
        .collect()
}

/// Maps `f` over `work` on up to 4 threads, results in the order of `work`. Threads take the
/// next item from a shared counter (molars and incisors differ in cost several fold, so a fixed
/// deal would leave one thread last). Each result depends on its item only, so the output is the
/// same bit for bit whatever the thread count or the order the items are taken in.
pub(crate) fn map_ordered<T: Sync, R: Send>(work: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .clamp(1, 4)
        .min(work.len().max(1));
    if threads <= 1 {
        return work.iter().map(f).collect();
    }
    let counter = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|s| {
        let f = &f;
        let next = &counter;
        let handles: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(move || {
                    let mut out = Vec::new();
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(w) = work.get(i) else { break };
                        out.push((i, f(w)));
                    }
                    out
                })
            })
            .collect();
        let mut all = Vec::with_capacity(work.len());
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

    /// Taken largest cost first, the results still come in the order of the work, each the
    /// item's own.
    #[test]
    fn cost_order_keeps_the_result_order() {
        let work: Vec<u64> = (0..37).map(|i| (i * 7919) % 101).collect();
        let by_cost = map_ordered_by_cost(&work, |&w| w as usize, |&w| w * w + 1);
        let plain: Vec<u64> = work.iter().map(|&w| w * w + 1).collect();
        assert_eq!(by_cost, plain);
        assert_eq!(map_ordered(&work, |&w| w * w + 1), plain);
    }
}
