//! Fuzzing on the stable toolchain, driven by proptest.
//!
//! Two kinds of target:
//!
//! - **Readers** ([`Reader`]): the arm TOML, the campaign TOML, and the
//!   poses, lengths and points CSV readers get the shipped example files
//!   mutated by a list of [`Op`]s (byte flips, inserted tokens such as
//!   `nan`, `1e309` or a quote, deleted, duplicated and swapped lines,
//!   truncation, splices). Each must return `Ok` with finite values, or an
//!   error that starts with the file's name and, when it has a line, names
//!   `file:line`. A panic or an unlocated error is a [`Violation`].
//! - **Degenerate calibrations** ([`Degenerate`]): `identify` and
//!   `calibrate` on data sets cut from simulated campaigns — one to three
//!   sockets, collinear sockets, duplicated touches, zero or huge noise,
//!   extreme but finite readings and lengths, every method. Each must not
//!   panic, and a calibration that succeeds has finite parameters.
//!
//! [`run_readers`] and [`run_degenerate`] run `N` cases from a seed, and
//! keep going after a violation (each is shrunk by proptest to a small
//! reproducer first). The binary `aacmm-fuzz` runs them from the command
//! line; the crate's test runs a seconds-long smoke in `cargo test`.

pub mod degenerate;
pub mod readers;

use std::cell::Cell;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Once;

pub use degenerate::{Degenerate, check_degenerate, run_degenerate};
pub use readers::{Op, Reader, check_reader, run_readers};

/// A broken rule found by a target: what input, and what went wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct Violation {
    /// The target (`poses`, `calibrate`, …).
    pub target: String,
    /// The (shrunk) input, printable.
    pub input: String,
    /// What went wrong: the panic's message, or the rule broken.
    pub problem: String,
}

/// What a run did: cases run, violations found (shrunk), and notes (e.g.
/// the distinct kinds of file-level error seen), for the report.
#[derive(Clone, Debug, Default)]
pub struct Summary {
    /// Cases run.
    pub cases: u64,
    /// Violations, each shrunk.
    pub violations: Vec<Violation>,
    /// Counts by outcome (`ok`, `error at a line`, …).
    pub outcomes: std::collections::BTreeMap<String, u64>,
}

impl Summary {
    pub(crate) fn count(&mut self, outcome: &str) {
        *self.outcomes.entry(outcome.to_string()).or_default() += 1;
    }
}

thread_local! {
    static QUIET: Cell<bool> = const { Cell::new(false) };
}

/// Runs `f`, turning a panic into `Err(message with location)` without
/// printing it (a panic hook, installed once, stays quiet inside).
pub fn no_panic<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    static HOOK: Once = Once::new();
    thread_local! {
        static WHERE: std::cell::RefCell<String> = const { std::cell::RefCell::new(String::new()) };
    }
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if QUIET.with(Cell::get) || std::thread::current().name() == Some("aacmm-worker") {
                let at = info.location().map(|l| l.to_string()).unwrap_or_default();
                WHERE.with(|w| *w.borrow_mut() = at);
            } else {
                previous(info);
            }
        }));
    });
    QUIET.with(|q| q.set(true));
    let result = catch_unwind(AssertUnwindSafe(f));
    QUIET.with(|q| q.set(false));
    result.map_err(|payload| {
        let what = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "a panic without a message".into());
        let at = WHERE.with(|w| w.borrow().clone());
        format!("panic at {at}: {what}")
    })
}

/// The number of cases from the environment variable `name`, else `default`.
pub fn cases_from_env(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}
