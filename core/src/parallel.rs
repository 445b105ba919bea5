//! Work on several threads with results that do not depend on how many:
//! items are handed out one at a time, and every result is put back in
//! item order, so a sum over them is added in the same order on any
//! machine.

/// The name of the worker threads the library starts: a host that silences
/// the panic messages of library code (the C API does) recognises them by it.
pub const WORKER_THREAD_NAME: &str = "aacmm-worker";

/// `f` over `items` on `threads` scoped threads, results in item order; on
/// the calling thread when one thread (or one item) is all there is.
///
/// A panic in `f` reaches the caller with its own payload (not the scope's
/// "a scoped thread panicked"), so the caller's `catch_unwind` sees what
/// went wrong. A worker the system refuses to start is replaced by the
/// calling thread.
pub(crate) fn parallel_map<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
    use std::sync::{Mutex, PoisonError};
    if threads <= 1 || items.len() <= 1 {
        return items.iter().map(f).collect();
    }
    let next = std::sync::atomic::AtomicUsize::new(0);
    let done = Mutex::new(Vec::new());
    let panicked = Mutex::new(None);
    let work = || {
        let run = catch_unwind(AssertUnwindSafe(|| {
            let mut mine = Vec::new();
            loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                if i >= items.len() {
                    break;
                }
                mine.push((i, f(&items[i])));
            }
            mine
        }));
        // Neither lock is held while `f` runs, so a poisoned one holds
        // complete data.
        match run {
            Ok(mine) => done
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .extend(mine),
            Err(payload) => {
                panicked
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner)
                    .get_or_insert(payload);
            }
        }
    };
    std::thread::scope(|s| {
        let mut all_started = true;
        for _ in 0..threads.min(items.len()) {
            let started = std::thread::Builder::new()
                .name(WORKER_THREAD_NAME.into())
                .spawn_scoped(s, work);
            all_started &= started.is_ok();
        }
        if !all_started {
            work();
        }
    });
    if let Some(payload) = panicked
        .into_inner()
        .unwrap_or_else(PoisonError::into_inner)
    {
        resume_unwind(payload);
    }
    let mut slots: Vec<Option<R>> = (0..items.len()).map(|_| None).collect();
    for (i, r) in done.into_inner().unwrap_or_else(PoisonError::into_inner) {
        slots[i] = Some(r);
    }
    // Every index below `items.len()` was taken by exactly one loop, which
    // either finished it (its result is in `done`) or panicked (resumed
    // above); a refused worker's share is run by the caller.
    slots
        .into_iter()
        .map(|r| r.expect("every item ran"))
        .collect()
}
