//! Work on several threads with results that do not depend on how many:
//! items are handed out one at a time, and every result is put back in
//! item order, so a sum over them is added in the same order on any
//! machine.
//!
//! The threads are a pool started once per process (rayon's, its threads
//! named [`WORKER_THREAD_NAME`]) and kept: starting operating-system
//! threads on every call cost more than a small problem's whole work, and
//! on a loaded machine each start waited for the scheduler (a UR5 tracker
//! fit took 350–430 ms on the default threads against 79 ms on one). A
//! problem too small to share ([`threads_for`]) runs on the calling thread
//! alone, and the calling thread always takes items itself: work never
//! waits for a worker to be scheduled when the caller could do it. Inside
//! an item of a call shared so, a call runs on that item's thread alone.

use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, OnceLock, PoisonError};

/// The name of the worker threads the library starts: a host that silences
/// the panic messages of library code (the C API does) recognises them by it.
pub const WORKER_THREAD_NAME: &str = "aacmm-worker";

/// The fewest items each thread must have before a call is shared: callers
/// cut their work into chunks of a fixed size (256 reference positions,
/// 64 points, 1024 touches), each some tens to hundreds of microseconds,
/// and a thread's share must outweigh handing it over — on a loaded
/// machine, waiting for a worker to be scheduled. The UR5 tracker's 1000
/// positions are 4 chunks: one thread.
pub(crate) const MIN_ITEMS_PER_THREAD: usize = 4;

/// The threads a call of `items` work items asked to run on `threads`
/// uses: at most one per `MIN_ITEMS_PER_THREAD` items, at least one. What
/// a test of thread-independence asks, to know that the work really splits
/// (with [`crate::residuals::point_chunks`]).
///
/// ```
/// use aacmm_core::parallel::threads_for;
/// assert_eq!(threads_for(4, 8), 1); // the UR5 tracker's 1000 positions
/// assert_eq!(threads_for(8, 2), 2);
/// ```
pub fn threads_for(items: usize, threads: usize) -> usize {
    threads.min(items / MIN_ITEMS_PER_THREAD).max(1)
}

/// The cores of the machine (at least one): the threads a data file's
/// reading shares its work on, before any setting of the fit's threads
/// exists — the same values on any count, as everything here.
/// Asked once per process: the standard library reads the cgroup's quota
/// files on every call.
pub(crate) fn every_core() -> usize {
    static CORES: OnceLock<usize> = OnceLock::new();
    *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// `f` over `items` on up to `threads` threads (the caller and the pool's
/// workers; fewer for few items, [`threads_for`]), results in item order.
///
/// A panic in `f` reaches the caller with its own payload, so the caller's
/// `catch_unwind` sees what went wrong. Without a pool (the system refused
/// its threads) the calling thread does all the work.
pub(crate) fn parallel_map<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    share(items, threads_for(items.len(), threads), f)
}

/// [`parallel_map`] of items each worth a thread of its own (an LM from
/// one start, milliseconds of work): shared on up to `threads` threads
/// however few there are.
pub(crate) fn parallel_map_each<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    share(items, threads.min(items.len()).max(1), f)
}

/// `f` over `items` on exactly `threads` threads (the caller's and the
/// pool's), results in item order.
///
/// Inside an item shared so, every call runs on its own thread
/// ([`Sharing`]): a caller that is not one of the pool's workers waits at
/// the end of a nested call until a worker has run the helper it handed
/// over, and a worker busy with the outer items does not take it until
/// they are done — the caller would sit idle. The items already keep
/// every thread busy.
fn share<T: Sync, R: Send>(items: &[T], threads: usize, f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let Some(pool) = (threads > 1 && !Sharing::inside()).then(pool).flatten() else {
        return items.iter().map(f).collect();
    };
    let f = |item: &T| {
        let _inside = Sharing::enter();
        f(item)
    };
    let next = AtomicUsize::new(0);
    let done = Mutex::new(Vec::with_capacity(items.len()));
    let panicked = Mutex::new(None);
    let work = || {
        let run = catch_unwind(AssertUnwindSafe(|| {
            let mut mine = Vec::new();
            loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
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
    // The caller works too: the helpers take what it has not yet taken, and
    // one that starts after the items are gone returns at once.
    pool.in_place_scope(|s| {
        for _ in 1..threads {
            s.spawn(|_| work());
        }
        work();
    });
    if let Some(payload) = panicked
        .into_inner()
        .unwrap_or_else(PoisonError::into_inner)
    {
        resume_unwind(payload);
    }
    in_item_order(
        items.len(),
        done.into_inner().unwrap_or_else(PoisonError::into_inner),
    )
}

/// [`parallel_map`] handing `f` each item to change (a slice of an output
/// the caller split into disjoint parts, say); each item is handed out
/// once, so its lock is never contended.
pub(crate) fn parallel_map_mut<T: Send, R: Send>(
    items: &mut [T],
    threads: usize,
    f: impl Fn(&mut T) -> R + Sync,
) -> Vec<R> {
    let cells: Vec<Mutex<&mut T>> = items.iter_mut().map(Mutex::new).collect();
    parallel_map(&cells, threads, |cell| {
        f(&mut cell.lock().unwrap_or_else(PoisonError::into_inner))
    })
}

/// The results `(item, result)` in item order.
fn in_item_order<R>(len: usize, done: Vec<(usize, R)>) -> Vec<R> {
    let mut slots: Vec<Option<R>> = (0..len).map(|_| None).collect();
    for (i, r) in done {
        slots[i] = Some(r);
    }
    // Every index below `len` was taken by exactly one loop, which either
    // finished it (its result is in `done`) or panicked (resumed before
    // this).
    slots
        .into_iter()
        .map(|r| r.expect("every item ran"))
        .collect()
}

/// Whether this thread is running an item of a call shared between
/// threads ([`share`]).
struct Sharing {
    /// Whether it was before this item (a call on one thread inside one
    /// shared: nothing changes).
    was: bool,
}

thread_local! {
    static INSIDE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

impl Sharing {
    fn inside() -> bool {
        INSIDE.with(std::cell::Cell::get)
    }

    /// Marks this thread as inside a shared item until the guard drops
    /// (a panic included).
    fn enter() -> Sharing {
        Sharing {
            was: INSIDE.with(|c| c.replace(true)),
        }
    }
}

impl Drop for Sharing {
    fn drop(&mut self) {
        INSIDE.with(|c| c.set(self.was));
    }
}

/// The process's pool, started on first use with a worker per core beyond
/// the caller's own (at least one); `None` when the system refuses its
/// threads (every call then runs on its caller), and in a child forked
/// after the pool started (Python's `multiprocessing` on Linux): a fork
/// copies the pool but not its threads, so work handed to it would wait
/// forever.
fn pool() -> Option<&'static rayon::ThreadPool> {
    static POOL: OnceLock<(u32, Option<rayon::ThreadPool>)> = OnceLock::new();
    let (started_in, pool) = POOL.get_or_init(|| {
        let cores = every_core();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(cores.saturating_sub(1).max(1))
            .thread_name(|_| WORKER_THREAD_NAME.to_string())
            .build()
            .ok();
        (std::process::id(), pool)
    });
    pool.as_ref().filter(|_| *started_in == std::process::id())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::{BTreeSet, HashSet};
    use std::thread::ThreadId;

    #[test]
    fn few_items_run_on_one_thread_many_on_those_asked_for() {
        assert_eq!(threads_for(0, 4), 1);
        assert_eq!(threads_for(4, 8), 1);
        assert_eq!(threads_for(7, 2), 1);
        assert_eq!(threads_for(8, 2), 2);
        assert_eq!(threads_for(16, 4), 4);
        assert_eq!(threads_for(1000, 3), 3);
        assert_eq!(threads_for(1000, 0), 1);
    }

    /// Held by the tests that count the pool's threads: the pool has one
    /// worker on two cores, and another such test keeping it busy would
    /// leave a caller to do all its items itself.
    static POOL: Mutex<()> = Mutex::new(());

    /// Waits, up to 10 s from `start`, until `n` threads have been `seen`
    /// (this one added): which threads share a call must not depend on how
    /// soon the OS schedules the pool's worker, which on a loaded machine
    /// once took longer than a test's 64 ms of work.
    fn meet(seen: &Mutex<HashSet<ThreadId>>, start: std::time::Instant, n: usize) {
        let lock = || seen.lock().unwrap_or_else(PoisonError::into_inner);
        lock().insert(std::thread::current().id());
        while lock().len() < n && start.elapsed() < std::time::Duration::from_secs(10) {
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
    }

    /// Which threads ran the items (`items` of `each` on up to `threads`),
    /// each item first [`meet`]ing `n` threads; the results checked in item
    /// order.
    fn traced(
        items: usize,
        threads: usize,
        each: std::time::Duration,
        n: usize,
    ) -> HashSet<ThreadId> {
        let _pool = POOL.lock().unwrap_or_else(PoisonError::into_inner);
        let v: Vec<usize> = (0..items).collect();
        let (seen, start) = (Mutex::new(HashSet::new()), std::time::Instant::now());
        let out = parallel_map(&v, threads, |&i| {
            meet(&seen, start, n);
            std::thread::sleep(each);
            (i * i, std::thread::current().id())
        });
        let squares: Vec<usize> = out.iter().map(|r| r.0).collect();
        assert_eq!(squares, v.iter().map(|i| i * i).collect::<Vec<_>>());
        out.into_iter().map(|r| r.1).collect()
    }

    #[test]
    fn a_small_problem_runs_on_the_calling_thread() {
        let me = std::thread::current().id();
        let ran = traced(MIN_ITEMS_PER_THREAD, 8, std::time::Duration::ZERO, 1);
        assert_eq!(ran, HashSet::from([me]));
    }

    /// 64 items of a millisecond each on 2 threads: the pool's worker takes
    /// some of them while the caller works (each item waits for it to have
    /// taken one, up to 10 s).
    #[test]
    fn a_large_problem_is_shared_with_the_pool() {
        let ran = traced(64, 2, std::time::Duration::from_millis(1), 2);
        assert_eq!(ran.len(), 2, "{ran:?}");
    }

    /// A call inside an item of a shared call runs on that item's thread
    /// alone, and the caller goes on to further items: shared, its first
    /// item's nested call would wait at its end for the worker to run the
    /// helper it handed over, which the worker does only once it has run
    /// every other outer item. Once the outer call is done a call is
    /// shared again.
    ///
    /// Which thread takes which outer item must not depend on how soon the
    /// OS schedules the worker (on a loaded machine the caller once took
    /// all four before it ran): each item [`meet`]s two threads, and the
    /// worker's items take 30 ms longer, so that a caller that is not stuck
    /// takes a further item even if it is itself descheduled for a while.
    /// Stuck, it still takes one only.
    #[test]
    fn a_call_inside_a_shared_item_runs_on_its_thread() {
        let caller = std::thread::current().id();
        let outer: Vec<usize> = (0..4).collect();
        let inner: Vec<usize> = (0..16).collect();
        let each = std::time::Duration::from_millis(1);
        let pool = POOL.lock().unwrap_or_else(PoisonError::into_inner);
        let (seen, start) = (Mutex::new(HashSet::new()), std::time::Instant::now());
        let runs = parallel_map_each(&outer, 2, |_| {
            let me = std::thread::current().id();
            meet(&seen, start, 2);
            let threads: HashSet<ThreadId> = parallel_map(&inner, 2, |_| {
                std::thread::sleep(each);
                std::thread::current().id()
            })
            .into_iter()
            .collect();
            if me != caller {
                std::thread::sleep(30 * each);
            }
            (me, threads)
        });
        for (me, threads) in &runs {
            assert_eq!(threads, &HashSet::from([*me]));
        }
        let outer_threads: HashSet<ThreadId> = runs.iter().map(|r| r.0).collect();
        assert_eq!(outer_threads.len(), 2, "the outer items were shared");
        let by_caller = runs.iter().filter(|r| r.0 == caller).count();
        assert!(by_caller >= 2, "the caller ran {by_caller} of 4 items");
        drop(pool);
        assert_eq!(traced(64, 2, each, 2).len(), 2, "shared again after it");
    }

    /// The pool's threads carry the name the C API's panic hook looks for,
    /// and a panic in one reaches the caller with its own payload.
    #[test]
    fn a_workers_panic_reaches_the_caller_with_its_payload() {
        let v: Vec<usize> = (0..64).collect();
        let names = Mutex::new(BTreeSet::new());
        let caught = catch_unwind(AssertUnwindSafe(|| {
            parallel_map(&v, 2, |&i| {
                std::thread::sleep(std::time::Duration::from_millis(1));
                let name = std::thread::current().name().map(str::to_string);
                names.lock().unwrap().insert(name);
                if i == 40 {
                    panic!("item forty");
                }
            })
        }))
        .unwrap_err();
        assert_eq!(caught.downcast_ref::<&str>(), Some(&"item forty"));
        let names = names.into_inner().unwrap();
        assert!(
            names.contains(&Some(WORKER_THREAD_NAME.to_string())),
            "{names:?}"
        );
    }
}
