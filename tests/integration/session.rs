//! The command line is a shell around the library's session: the same
//! inputs give the same `calibration.json`, byte for byte, as
//! `aacmm_core::session` run in-process and as the `paper_experiment`
//! example writes it (the C API's test makes the same comparison from C, so
//! the front ends agree).

use aacmm_core::calibrate::{Method, ModelOptions, SolverSettings};
use aacmm_core::io::AngleUnit;
use aacmm_core::residuals::Noise;
use aacmm_core::session::{CalibrationReport, Problem, Request, Sources};
use aacmm_core::{DataSet, read_arm};

use crate::util::{calibrate_shipped, example, shipped, shipped_arm, temp_dir};

/// The shipped campaign as the CLI reads it, with its noise stated.
fn shipped_problem() -> Problem {
    problem_stating(0.005, 0.01)
}

/// The shipped campaign as the CLI reads it, with the noise stated as
/// `encoder_deg` and `probe_mm`.
fn problem_stating(encoder_deg: f64, probe_mm: f64) -> Problem {
    let (arm, _) = read_arm(shipped_arm().as_ref()).unwrap();
    let lengths = shipped("lengths.csv");
    let (data, _) = DataSet::read(
        shipped("poses.csv").as_ref(),
        Some(lengths.as_ref()),
        AngleUnit::Deg,
        6,
    )
    .unwrap();
    let options = ModelOptions {
        noise: Noise {
            encoder_rad: Some(encoder_deg.to_radians()),
            probe_mm: Some(probe_mm),
            ..Noise::default()
        },
        ..ModelOptions::default()
    };
    Problem::new(arm, data, options)
        .unwrap()
        .with_sources(Sources {
            arm_file: shipped_arm(),
            data_file: shipped("poses.csv"),
            lengths_file: Some(shipped("lengths.csv")),
            warnings: Vec::new(),
        })
}

#[test]
fn the_cli_writes_the_library_sessions_report() {
    let dir = temp_dir("session-bytes");
    for (method, seed) in [(Method::Global, 0), (Method::Hybrid, 4)] {
        let out = dir.join(method.name());
        let seed_text = seed.to_string();
        let o = calibrate_shipped(
            &out,
            &[
                "--method",
                method.name(),
                "--seed",
                &seed_text,
                "--cross-validate",
                "3",
            ],
        );
        assert!(o.status.success(), "{}", crate::util::stderr(&o));
        let written = std::fs::read_to_string(out.join("calibration.json")).unwrap();
        let problem = shipped_problem().with_cross_validation(3).unwrap();
        let settings = SolverSettings {
            method,
            seed,
            threads: 1,
            ..SolverSettings::default()
        };
        let expected = problem.run(&settings).unwrap();
        assert_eq!(written, expected.to_json(), "{}", method.name());
        // The file reads back as the same report.
        let back = CalibrationReport::from_json(&written).unwrap();
        let (a, b) = (&back.calibration.solver, &expected.calibration.solver);
        assert_eq!(
            (a.stop, &a.history, a.final_cost),
            (b.stop, &b.history, b.final_cost)
        );
        assert_eq!(back.validation, expected.validation);
        assert_eq!(back.calibration.parameters.len(), 27);
        for (a, b) in back
            .calibration
            .parameters
            .iter()
            .zip(&expected.calibration.parameters)
        {
            assert_eq!(a.id, b.id);
            assert!((a.calibrated - b.calibrated).abs() <= 1e-12 * b.calibrated.abs().max(1.0));
        }
        assert_eq!(back.calibration.solver.method, method);
    }
}

/// The visible, non-empty lines of the first ```rust block of `text`
/// (doc-comment prefixes and hidden `# ` lines removed).
fn rust_block(text: &str, prefix: &str) -> Vec<String> {
    let lines: Vec<String> = text
        .lines()
        .filter_map(|l| l.strip_prefix(prefix).map(str::trim_end))
        .map(str::to_string)
        .collect();
    let start = lines
        .iter()
        .position(|l| l == "```rust" || l == "```")
        .expect("a code block");
    lines[start + 1..]
        .iter()
        .take_while(|l| !l.starts_with("```"))
        .filter(|l| !l.starts_with("# ") && !l.is_empty())
        .cloned()
        .collect()
}

#[test]
fn the_readmes_rust_example_is_the_crates_doc_test() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let section = &readme[readme.find("## From Rust").expect("a Rust section")..];
    let lib = std::fs::read_to_string(root.join("core/src/lib.rs")).unwrap();
    // The Problem example from memory comes first; the README's is the one
    // from files, after it.
    let doc = &lib[lib.find("//! From files, a [`Request`]").unwrap()..];
    let (a, b) = (rust_block(section, ""), rust_block(doc, "//! "));
    assert!(a.len() >= 5 && a.len() <= 10, "{a:?}");
    assert_eq!(a, b);
}

/// The newest modification time of a file under `path`.
fn newest(path: &std::path::Path) -> std::time::SystemTime {
    let meta = std::fs::metadata(path).unwrap();
    if meta.is_dir() {
        std::fs::read_dir(path)
            .unwrap()
            .map(|e| newest(&e.unwrap().path()))
            .max()
            .unwrap_or(std::time::UNIX_EPOCH)
    } else {
        meta.modified().unwrap()
    }
}

/// The example binary `name`, built by `cargo test` beside the test binary
/// (`target/<profile>/examples/`). `cargo test --test integration` alone
/// does not build examples: one missing, or older than its source or the
/// core library's, fails with what to run rather than testing stale code.
fn example_binary(name: &str) -> std::path::PathBuf {
    let exe = std::env::current_exe().unwrap();
    let path = exe
        .parent()
        .and_then(|deps| deps.parent())
        .unwrap()
        .join("examples")
        .join(format!("{name}{}", std::env::consts::EXE_SUFFIX));
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let sources = newest(&root.join("core/src")).max(newest(&example(&format!("{name}.rs"))));
    let built = std::fs::metadata(&path).and_then(|m| m.modified()).ok();
    assert!(
        built.is_some_and(|b| b >= sources),
        "{} is missing or older than its sources: run `cargo test --workspace` (it builds the \
         examples), or `cargo build --example {name}` with this profile",
        path.display()
    );
    path
}

#[test]
fn the_paper_experiment_writes_what_the_cli_writes() {
    // The example fits its simulated campaign in-process; the CLI, given
    // the files it wrote and the same settings, must write the same
    // calibration.json — the example is a shell around the same session.
    let dir = temp_dir("paper-experiment");
    let o = std::process::Command::new(example_binary("paper_experiment"))
        .arg(&dir)
        .output()
        .expect("the paper_experiment example runs (cargo test builds it)");
    assert!(o.status.success(), "{}", crate::util::stderr(&o));
    // The example names its inputs relative to the repository and to its
    // output folder; give the CLI the same names.
    std::fs::create_dir_all(dir.join("examples")).unwrap();
    std::fs::copy(shipped_arm(), dir.join("examples/paper-table-1.toml")).unwrap();
    // The example's solver seed is 0.
    for method in ["hybrid", "global"] {
        let out = format!("cli-{method}");
        let o = crate::util::command(&[
            "calibrate",
            "--arm",
            "examples/paper-table-1.toml",
            "--data",
            "campaign/poses.csv",
            "--lengths",
            "campaign/lengths.csv",
            "--validate",
            "held-out/poses.csv",
            "--validate-lengths",
            "held-out/lengths.csv",
            "--encoder-noise",
            "0.012",
            "--probe-noise",
            "0.024",
            "--method",
            method,
            "--seed",
            "0",
            "--out",
            &out,
        ])
        .current_dir(&dir)
        .output()
        .unwrap();
        assert!(o.status.success(), "{}", crate::util::stderr(&o));
        let cli = std::fs::read_to_string(dir.join(&out).join("calibration.json")).unwrap();
        let example = std::fs::read_to_string(dir.join(method).join("calibration.json")).unwrap();
        assert!(
            cli.contains("\"held_out\": {"),
            "validated on the held-out campaign"
        );
        assert_eq!(cli, example, "{method}");
    }
}

/// `aacmm calibrate` and the library's `Request` given the same intent —
/// the command line's flags, the request's settings as text — write the
/// same `calibration.json`: on a real robot's campaign whose arm file has a
/// `[prior]`, used as it is and overridden entry by entry.
#[test]
fn a_request_gives_the_clis_calibration_with_the_arm_files_prior() {
    let dir = temp_dir("request-prior");
    let m = example("mukca/kinova-1");
    let path = |f: &str| m.join(f).display().to_string();
    let (arm, poses, lengths) = (path("arm.toml"), path("poses.csv"), path("lengths.csv"));
    for (name, prior) in [("file", None), ("override", Some("theta2=0.1deg,d6=1mm"))] {
        let out = dir.join(name);
        let mut args = vec![
            "calibrate",
            "--arm",
            &arm,
            "--data",
            &poses,
            "--lengths",
            &lengths,
            "--angle-unit",
            "rad",
            "--method",
            "lm",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend(prior.iter().flat_map(|p| ["--prior", p]));
        let o = crate::util::aacmm(&args);
        assert!(o.status.success(), "{}", crate::util::stderr(&o));
        let written = std::fs::read_to_string(out.join("calibration.json")).unwrap();
        let (problem, report) = Request::read(path("arm.toml"), path("poses.csv"), AngleUnit::Rad)
            .unwrap()
            .read_lengths(path("lengths.csv"))
            .unwrap()
            .method("lm")
            .prior(prior)
            .threads(Some(1))
            .run()
            .unwrap();
        assert_eq!(report.to_json(), written, "{name}");
        let used = report.calibration.prior.as_ref().expect("a prior is used");
        assert_eq!(
            Some(&used.tolerances),
            problem
                .model()
                .prior
                .as_ref()
                .map(|t| t.describe(6))
                .as_ref()
        );
        let file = problem
            .arm()
            .prior
            .as_ref()
            .expect("the arm file's [prior]");
        match prior {
            None => assert_eq!(problem.model().prior.as_ref(), Some(file)),
            Some(_) => assert!(
                used.tolerances.ends_with("theta2=0.1deg, d6=1mm"),
                "{}",
                used.tolerances
            ),
        }
    }
}

/// A search that would run for minutes: the noise stated a thousand times
/// too small (no start reaches its floor) and as many confirmations asked
/// as there are starts.
fn endless_search() -> (Problem, SolverSettings) {
    let problem = problem_stating(0.000_005, 0.000_01);
    let settings = SolverSettings {
        method: Method::Global,
        threads: 1,
        global: aacmm_core::calibrate::GlobalOptions {
            max_starts: 100_000,
            confirmations: 100_000,
            ..Default::default()
        },
        ..SolverSettings::default()
    };
    (problem, settings)
}

/// Every solver checks the cancellation token: set before the run, each
/// method returns `Cancelled` (no result), and a run without the token set
/// is untouched by having one.
#[test]
fn every_solver_stops_on_a_set_token() {
    use aacmm_core::CalibrationError;
    use aacmm_core::calibrate::{Cancel, Context};
    let problem = shipped_problem();
    for method in Method::ALL {
        let settings = SolverSettings {
            method,
            threads: 1,
            ..SolverSettings::default()
        };
        let token = Cancel::new();
        token.cancel();
        let mut ctx = Context::new().cancelled_by(token);
        let r = aacmm_core::session::run(&problem, &settings, &*method.solver(), &mut ctx);
        assert!(
            matches!(r, Err(CalibrationError::Cancelled)),
            "{}: {:?}",
            method.name(),
            r.map(|_| ())
        );
    }
    let settings = SolverSettings {
        method: Method::Lm,
        threads: 1,
        ..SolverSettings::default()
    };
    let mut ctx = Context::new().cancelled_by(Cancel::new());
    let with = aacmm_core::session::run(&problem, &settings, &*Method::Lm.solver(), &mut ctx);
    let without = problem.run(&settings).unwrap();
    assert_eq!(with.unwrap().to_json(), without.to_json());
}

/// Sets `token` 300 ms from now on another thread, which returns when.
fn cancel_after_300_ms(
    token: &aacmm_core::calibrate::Cancel,
) -> std::thread::JoinHandle<std::time::Instant> {
    let stopper = token.clone();
    std::thread::spawn(move || {
        std::thread::sleep(std::time::Duration::from_millis(300));
        let at = std::time::Instant::now();
        stopper.cancel();
        at
    })
}

/// The folds of a cross-validation stop with the run: each fold's
/// calibration checks the run's token (a fold of the endless search set
/// from another thread returns promptly, not after its own search).
#[test]
fn the_folds_stop_with_the_run() {
    use aacmm_core::CalibrationError;
    use aacmm_core::calibrate::validate::cross_validate_cancellable;
    use std::time::{Duration, Instant};
    let (problem, settings) = endless_search();
    let token = aacmm_core::calibrate::Cancel::new();
    let canceller = cancel_after_300_ms(&token);
    let solver = Method::Global.solver();
    let r = cross_validate_cancellable(problem.inputs(), &settings, &*solver, 3, Some(&token));
    let ended = Instant::now();
    let cancelled_at = canceller.join().unwrap();
    assert!(
        matches!(r, Err(CalibrationError::Cancelled)),
        "{:?}",
        r.map(|_| ())
    );
    assert!(ended.saturating_duration_since(cancelled_at) < Duration::from_millis(100));
}

/// A global search that would run for minutes, cancelled from another
/// thread after 300 ms, returns `Cancelled` promptly: every LM of the
/// search checks the token before each iteration, and its torus grid every
/// 64 cells. The issue asks 50 ms; the bound here is twice that, for a
/// debug build beside other tests on a loaded machine (23 ms measured so,
/// at load 7).
#[test]
fn a_global_search_cancelled_from_another_thread_returns_promptly() {
    use aacmm_core::CalibrationError;
    use aacmm_core::calibrate::Context;
    use std::time::{Duration, Instant};
    let (problem, settings) = endless_search();
    let token = aacmm_core::calibrate::Cancel::new();
    let canceller = cancel_after_300_ms(&token);
    let mut ctx = Context::new().cancelled_by(token);
    let r = aacmm_core::session::run(&problem, &settings, &*Method::Global.solver(), &mut ctx);
    let ended = Instant::now();
    let cancelled_at = canceller.join().unwrap();
    assert!(
        matches!(r, Err(CalibrationError::Cancelled)),
        "{:?}",
        r.map(|_| ())
    );
    let latency = ended.saturating_duration_since(cancelled_at);
    eprintln!("cancelled global search returned {latency:?} after the token was set");
    assert!(latency < Duration::from_millis(100), "{latency:?}");
}

/// Ctrl-C during `calibrate`: a search that would run for minutes stops at
/// the solver's next check, says it was interrupted and that nothing was
/// written, exits non-zero, and leaves no result behind.
#[cfg(unix)]
#[test]
fn ctrl_c_stops_the_cli_calibration_and_writes_nothing() {
    use std::time::{Duration, Instant};
    let dir = temp_dir("session-interrupt");
    let out = dir.join("out");
    let mut child = crate::util::command(&[
        "calibrate",
        "--arm",
        &shipped_arm(),
        "--data",
        &shipped("poses.csv"),
        "--lengths",
        &shipped("lengths.csv"),
        "--encoder-noise",
        "0.000005",
        "--probe-noise",
        "0.00001",
        "--global-starts",
        "100000",
        "--global-confirmations",
        "100000",
        "--threads",
        "1",
        "--out",
        out.to_str().unwrap(),
    ])
    .stdout(std::process::Stdio::piped())
    .stderr(std::process::Stdio::piped())
    .spawn()
    .unwrap();
    // Well into the search (the data read, the handler installed).
    std::thread::sleep(Duration::from_millis(1500));
    assert!(child.try_wait().unwrap().is_none(), "it ended by itself");
    let pid = child.id().to_string();
    let sent = Instant::now();
    let kill = std::process::Command::new("kill")
        .args(["-INT", &pid])
        .status()
        .unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    let took = sent.elapsed();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("interrupted (Ctrl-C): nothing was written")
            && err.contains("cancelled before the calibration finished"),
        "{err}"
    );
    assert!(!out.join("calibration.json").exists());
    assert!(took < Duration::from_secs(5), "{took:?}");
}
