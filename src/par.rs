//! Deterministic data parallelism for per-tooth work (std threads only).

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
