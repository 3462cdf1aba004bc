//! Deterministic data parallelism for per-tooth work (std threads only).

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
                        let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(&i) = order.get(k) else { break };
                        out.push((i, f(&work[i])));
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
