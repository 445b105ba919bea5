//! The command line is a shell around the library's session: the same
//! inputs give the same `calibration.json`, byte for byte, as
//! `aacmm_core::session` run in-process (the C API's test makes the same
//! comparison from C, so the three front ends agree).

use aacmm_core::calibrate::{CalibrateOptions, LmOptions, Method};
use aacmm_core::residuals::Noise;
use aacmm_core::session::{CalibrationReport, Problem, Sources};
use aacmm_core::{DataSet, read_arm};

use crate::util::{calibrate_shipped, shipped, shipped_arm, temp_dir};

/// The shipped campaign as the CLI reads it, with its noise stated.
fn shipped_problem(method: Method, seed: u64) -> Problem {
    let (arm, _) = read_arm(shipped_arm().as_ref()).unwrap();
    let data = DataSet::from_files(shipped("poses.csv"), Some(shipped("lengths.csv")), 6).unwrap();
    let options = CalibrateOptions {
        method,
        seed,
        noise: Noise {
            encoder_rad: Some(0.005f64.to_radians()),
            probe_mm: Some(0.01),
            ..Noise::default()
        },
        lm: LmOptions::default().threads(1),
        ..CalibrateOptions::default()
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
        let problem = shipped_problem(method, seed)
            .with_cross_validation(3)
            .unwrap();
        let expected = problem.run().unwrap();
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
    let doc = &lib[lib.find("//! The front door").unwrap()..];
    let (a, b) = (rust_block(section, ""), rust_block(doc, "//! "));
    assert!(a.len() >= 5 && a.len() <= 10, "{a:?}");
    assert_eq!(a, b);
}
