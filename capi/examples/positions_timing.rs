//! Batch positions of 10⁶ poses called from C (the program
//! `tests/c/bench.c`, compiled with `cc` against the static library) and
//! from Rust (`PreparedPoses::new` + `ArmKernel::positions`, what the C API
//! runs), alternating, in one run:
//!
//! ```sh
//! cargo run --release -p aacmm-capi --example positions_timing
//! ```
//!
//! Both sides are the same program, one in C and one in Rust (this
//! example re-run as `positions_timing --rust N REPS`): a fresh process that
//! fills the same buffers in the same order and times the same calls on its
//! main thread, so that the allocator sees the same history (the Rust side
//! allocates the poses' sin/cos, 96 MB for 10⁶ poses, and page-faults it in
//! on each call: a different heap history alone moves the timing by several
//! percent). The C API prepares the poses 4096 at a time instead (memory
//! that does not grow with the batch, issue 29), which also keeps them in
//! cache: since then it is the faster side (C/Rust 0.70 on the 2-core
//! machine, from 1.02 before).
//! Prints, per side, the median and the fastest wall-clock call and the
//! processor time per call (user + system: on a loaded machine the steadiest
//! figure), and the C/Rust ratios. A timing, not a test: CI does not run it.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use aacmm_core::kernel::{ArmKernel, PreparedPoses};
use aacmm_core::params::DhParams;

const POSES: usize = 1_000_000;
const REPS: usize = 15;
const ROUNDS: usize = 5;

/// Median, fastest and processor time per call, ns.
#[derive(Clone, Copy)]
struct Timing {
    median: f64,
    fastest: f64,
    cpu: f64,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// This thread's processor time so far, ns (Linux; `None` elsewhere): the
/// same clock as C's `clock()` in a one-thread process.
fn cpu_ns() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

/// One side's run: a fresh process printing
/// `<tag> N MEDIAN_NS MIN_NS CPU_NS CHECKSUM`.
fn side(cmd: &mut Command) -> Timing {
    let out = cmd
        .args([POSES.to_string(), REPS.to_string()])
        .output()
        .expect("run a timing process");
    assert!(out.status.success(), "{out:?}");
    let text = String::from_utf8(out.stdout).unwrap();
    let f: Vec<f64> = text
        .split_whitespace()
        .skip(2)
        .map(|v| v.parse().unwrap())
        .collect();
    Timing {
        median: f[0],
        fastest: f[1],
        cpu: f[2],
    }
}

/// The Rust side: what `tests/c/bench.c` does, through the Rust API.
fn rust_child(n: usize, reps: usize) {
    let q: Vec<f64> = (0..n * 6)
        .map(|i| 3.0 * (0.37 * i as f64 + 0.1).sin())
        .collect();
    let mut p = vec![0.0; n * 3];
    let mut times = Vec::with_capacity(reps);
    let kernel = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    let call = |p: &mut [f64]| {
        let poses = PreparedPoses::new(6, q.as_chunks::<6>().0).unwrap();
        kernel
            .positions(&poses, 0..n, p.as_chunks_mut::<3>().0)
            .unwrap();
    };
    call(&mut p);
    let mut checksum = 0.0;
    let cpu0 = cpu_ns();
    for _ in 0..reps {
        let t0 = Instant::now();
        call(&mut p);
        times.push(t0.elapsed().as_secs_f64() * 1e9);
        checksum += p[0] + p[n * 3 - 1];
    }
    let cpu = match (cpu0, cpu_ns()) {
        (Some(a), Some(b)) => (b - a) / reps as f64,
        _ => f64::NAN,
    };
    let fastest = times.iter().copied().fold(f64::INFINITY, f64::min);
    println!(
        "rust_positions {n} {:.0} {fastest:.0} {cpu:.0} {checksum:.17}",
        median(times)
    );
}

/// The static library cargo built with this example: in `deps/` (cargo
/// copies it up to the profile directory only for `cargo build -p
/// aacmm-capi`, so a copy there may be stale).
fn static_lib() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let profile = exe.parent().and_then(Path::parent).unwrap();
    let lib = profile.join("deps/libaacmm_capi.a");
    assert!(lib.is_file(), "{} not found", lib.display());
    lib
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let [_, flag, n, reps] = args.as_slice()
        && flag == "--rust"
    {
        return rust_child(n.parse().unwrap(), reps.parse().unwrap());
    }
    if cfg!(debug_assertions) {
        eprintln!("note: a debug build; time with --release");
    }
    let capi = Path::new(env!("CARGO_MANIFEST_DIR"));
    let exe = std::env::temp_dir().join(format!("aacmm-capi-bench-{}", std::process::id()));
    let status = Command::new(std::env::var("CC").unwrap_or_else(|_| "cc".into()))
        .args(["-std=c11", "-O2", "-I"])
        .arg(capi.join("include"))
        .arg(capi.join("tests/c/bench.c"))
        .arg(static_lib())
        .args(["-lm", "-lpthread", "-ldl", "-o"])
        .arg(&exe)
        .status()
        .expect("run cc");
    assert!(status.success(), "cc failed");
    let this = std::env::current_exe().unwrap();
    let (mut c, mut rust) = (Vec::new(), Vec::new());
    for _ in 0..ROUNDS {
        c.push(side(&mut Command::new(&exe)));
        rust.push(side(Command::new(&this).arg("--rust")));
    }
    let _ = std::fs::remove_file(&exe);
    let summary = |t: &[Timing]| Timing {
        median: median(t.iter().map(|t| t.median).collect()),
        fastest: t.iter().map(|t| t.fastest).fold(f64::INFINITY, f64::min),
        cpu: median(t.iter().map(|t| t.cpu).collect()),
    };
    let (c, r) = (summary(&c), summary(&rust));
    let ms = |ns: f64| ns / 1e6;
    println!("batch positions, 10^6 poses, {ROUNDS} rounds x {REPS} calls per side:");
    println!("                 C (C API)   Rust      C/Rust");
    for (name, a, b) in [
        ("median wall", c.median, r.median),
        ("fastest wall", c.fastest, r.fastest),
        ("cpu per call", c.cpu, r.cpu),
    ] {
        println!(
            "  {name:<13} {:>8.1} ms {:>8.1} ms  {:>6.3}",
            ms(a),
            ms(b),
            a / b
        );
    }
}
