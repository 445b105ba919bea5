//! `aacmm-fuzz readers|calibrate CASES [SEED] [CHUNK]`: runs a fuzz target
//! and prints what it did (cases, outcomes, violations with their shrunk
//! inputs). Exit status 1 when a rule broke.

use std::io::Write;
use std::process::ExitCode;

use aacmm_fuzz::{Summary, run_degenerate, run_readers};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: aacmm-fuzz readers|calibrate CASES [SEED] [CHUNK]";
    let (Some(target), Some(cases)) = (args.first(), args.get(1).and_then(|c| c.parse().ok()))
    else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let seed = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(0);
    let chunk = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(100_000);
    let started = std::time::Instant::now();
    let summary: Summary = match target.as_str() {
        "readers" => run_readers(cases, seed, chunk),
        "calibrate" => run_degenerate(cases, seed, chunk),
        _ => {
            eprintln!("{usage}");
            return ExitCode::from(2);
        }
    };
    let mut out = std::io::stdout().lock();
    let report = (|| -> std::io::Result<()> {
        writeln!(
            out,
            "{target}: {} inputs (shrinking included), seed {seed}, {:.1} s",
            summary.cases,
            started.elapsed().as_secs_f64()
        )?;
        for (outcome, n) in &summary.outcomes {
            writeln!(out, "  {n:>10}  {outcome}")?;
        }
        writeln!(out, "violations: {}", summary.violations.len())?;
        for v in &summary.violations {
            writeln!(out, "- {}: {}\n  input: {}", v.target, v.problem, v.input)?;
        }
        out.flush()
    })();
    if report.is_err() {
        return ExitCode::from(2);
    }
    if summary.violations.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
