//! Issue 43: where the toolkit refuses, the first line names the true
//! cause, and no refusal recommends an option already in use. Each case as
//! a new user met it: swapped joint columns, another robot's touches
//! (case 1); one mislabelled touch with `--robust` under the default
//! global method (2); reference lengths in metres (3); an arm file in the
//! wrong unit (4); a χ² note beside "Verdict: usable" (8).

use std::process::Output;

use crate::util::{
    aacmm, calibrate_files, calibrate_shipped, example, mislabelled_poses, shipped, shipped_arm,
    stderr, stdout, temp_dir, write,
};

/// The first line of the error a refused command prints.
fn first_error_line(o: &Output) -> String {
    let err = stderr(o);
    (err.lines())
        .find(|l| l.starts_with("error: "))
        .unwrap_or_else(|| panic!("no error line in:\n{err}"))
        .to_string()
}

/// The verdict's reasons in `out`'s calibration.json.
fn reasons(out: &std::path::Path) -> Vec<String> {
    let text = std::fs::read_to_string(out.join("calibration.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    (json["verdict"]["reasons"].as_array().unwrap().iter())
        .map(|r| r.as_str().unwrap().to_string())
        .collect()
}

/// No reason (nor the error) recommends a flag of `args` — an option the
/// user already gave.
fn recommends_nothing_in_use(args: &[&str], said: &[String]) {
    for flag in args.iter().filter(|a| a.starts_with("--")) {
        for s in said {
            assert!(
                !s.contains(flag),
                "`{flag}` is in use, yet recommended: {s}"
            );
        }
    }
}

/// The shipped poses with the columns q1 and q2 swapped (the issue's
/// `awk -F, -v OFS=, 'NR>1{t=$2;$2=$3;$3=t}1'`).
fn swapped_poses(dir: &std::path::Path) -> String {
    let text = std::fs::read_to_string(shipped("poses.csv")).unwrap();
    let lines: Vec<String> = (text.lines().enumerate())
        .map(|(i, l)| {
            if i == 0 {
                return l.to_string();
            }
            let mut f: Vec<&str> = l.split(',').collect();
            f.swap(1, 2);
            f.join(",")
        })
        .collect();
    write(dir, "swapped.csv", &(lines.join("\n") + "\n"))
}

/// Case 1: swapped joint columns, and another robot's touches with this
/// arm: the first cause is that the data and the arm disagree (what to
/// check), not the solver's start budget; no refusal says "more starts".
#[test]
fn data_that_no_arm_of_this_kind_fits_are_named_first() {
    let dir = temp_dir("first-cause-disagree");
    let swapped = swapped_poses(&dir);
    let out = dir.join("swapped");
    let o = calibrate_files(&shipped_arm(), &swapped, &out, &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stdout(&o));
    let first = first_error_line(&o);
    assert!(
        first.starts_with("error: the calibration is not usable: the data and the arm disagree: ")
            && first.contains("times the stated noise")
            && first.contains("columns q1..q6"),
        "{first}"
    );
    let said = reasons(&out);
    assert!(
        said[0].starts_with("the data and the arm disagree"),
        "{said:?}"
    );
    assert!(said.iter().all(|r| !r.contains("more starts")), "{said:?}");
    let summary = stdout(&o);
    assert!(
        summary.contains("Verdict: NOT usable — the data and the arm disagree: "),
        "{summary}"
    );

    // The Kinova's touches (radians) with the paper's arm, noise unstated.
    let kinova = example("mukca/kinova-1/poses.csv").display().to_string();
    let out = dir.join("kinova");
    let args = [
        "calibrate",
        "--arm",
        &shipped_arm(),
        "--data",
        &kinova,
        "--angle-unit",
        "rad",
        "--out",
        out.to_str().unwrap(),
    ];
    let o = aacmm(&args);
    assert_eq!(o.status.code(), Some(1), "{}", stdout(&o));
    let first = first_error_line(&o);
    assert!(
        first.contains("not usable: the data and the arm disagree: none of the ")
            && first.contains("is an arm of the nominal's kind"),
        "{first}"
    );
    let said = reasons(&out);
    assert!(said.iter().all(|r| !r.contains("more starts")), "{said:?}");
    recommends_nothing_in_use(&args, &said);
}

/// Case 2: one mislabelled touch with `--robust` under the default global
/// method: the robust loss weighs it out, the fit is usable (as with
/// `--method lm`), and the touch is reported (robust and outlier lines),
/// not a reason to refuse. A robust fit refused for another cause does
/// not recommend `--robust`.
#[test]
fn a_mislabelled_touch_with_robust_under_global_is_reported_not_refused() {
    let dir = temp_dir("first-cause-robust");
    let poses = mislabelled_poses(&dir);
    for loss in ["huber", "cauchy"] {
        let out = dir.join(loss);
        let o = calibrate_files(&shipped_arm(), &poses, &out, &["--robust", loss]);
        let summary = stdout(&o);
        assert!(o.status.success(), "{loss}:\n{summary}\n{}", stderr(&o));
        assert!(summary.contains("\nVerdict: usable\n"), "{summary}");
        assert!(
            summary.contains("stopped: fit at the stated noise floor once the robust loss"),
            "{summary}"
        );
        let line = |start: &str| {
            (summary.lines())
                .find(|l| l.starts_with(start))
                .unwrap_or_else(|| panic!("no `{start}` in {summary}"))
                .to_string()
        };
        assert!(line("Robust: ").contains(&format!("{poses}:18 (point S1, weight ")));
        assert!(line("Outliers: ").contains(&format!("{poses}:18 (point S1,")));
        assert!(line("Fit quality: ").contains("consistent with the stated noise"));
    }
    // Refused for another cause (the noise stated 100 times too small):
    // the weighed-out touch is not blamed, and --robust not recommended.
    let out = dir.join("tiny-noise");
    let args = [
        "calibrate",
        "--arm",
        &shipped_arm(),
        "--data",
        &poses,
        "--lengths",
        &shipped("lengths.csv"),
        "--encoder-noise",
        "0.00005",
        "--probe-noise",
        "0.0001",
        "--robust",
        "huber",
        "--method",
        "lm",
        "--out",
        out.to_str().unwrap(),
    ];
    let o = aacmm(&args);
    assert_eq!(o.status.code(), Some(1), "{}", stdout(&o));
    let said = reasons(&out);
    assert!(
        said.iter().all(|r| !r.contains("pulls the fit")),
        "{said:?}"
    );
    recommends_nothing_in_use(&args, &said);
    recommends_nothing_in_use(&args, &[stderr(&o)]);
}

/// Lengths in metres (the shipped lengths / 1000), written into `dir`.
fn lengths_in_metres(dir: &std::path::Path) -> String {
    let text = std::fs::read_to_string(shipped("lengths.csv")).unwrap();
    let lines: Vec<String> = (text.lines().enumerate())
        .map(|(i, l)| {
            let mut f: Vec<String> = l.split(',').map(str::to_string).collect();
            if i > 0 {
                f[2] = format!("{}", f[2].parse::<f64>().unwrap() / 1000.0);
            }
            f.join(",")
        })
        .collect();
    write(dir, "lengths-m.csv", &(lines.join("\n") + "\n"))
}

/// `command` (evaluate, identify, calibrate) of `arm` on the shipped poses
/// with `lengths`.
fn with_lengths(command: &str, arm: &str, lengths: &str, out: &std::path::Path) -> Output {
    let data = shipped("poses.csv");
    let mut args = vec![command, "--arm", arm, "--data", &data, "--lengths", lengths];
    if command == "calibrate" {
        args.extend(["--out", out.to_str().unwrap()]);
    }
    aacmm(&args)
}

/// Case 3: every command that reads a lengths file checks its unit the
/// same way: lengths in metres are refused by evaluate (which printed
/// errors of 600–860 mm and exited 0), identify and calibrate, each
/// naming the lengths file and the ratio first.
#[test]
fn lengths_in_metres_are_refused_by_every_command_that_reads_them() {
    let dir = temp_dir("first-cause-lengths-m");
    let lengths = lengths_in_metres(&dir);
    let mut firsts = Vec::new();
    for command in ["evaluate", "identify", "calibrate"] {
        let o = with_lengths(command, &shipped_arm(), &lengths, &dir.join(command));
        assert_eq!(o.status.code(), Some(1), "{command}: {}", stdout(&o));
        let first = first_error_line(&o);
        assert!(
            first.starts_with(&format!(
                "error: {lengths}: the reference lengths are 1.000e-3 times the nominal arm's"
            )),
            "{command}: {first}"
        );
        assert!(stdout(&o).is_empty(), "{command} printed figures");
        firsts.push(first);
    }
    assert!(firsts.windows(2).all(|w| w[0] == w[1]), "{firsts:#?}");
}

/// Case 4: an arm file in the wrong unit (its millimetres declared as
/// metres): the warning and the error both name the arm, in every command
/// that reads lengths — not the lengths file, which is right.
#[test]
fn an_arm_file_in_the_wrong_unit_is_blamed_not_the_lengths() {
    let dir = temp_dir("first-cause-arm-m");
    let text = std::fs::read_to_string(shipped_arm()).unwrap();
    let arm = write(
        &dir,
        "arm-m.toml",
        &text.replace("length_unit = \"mm\"", "length_unit = \"m\""),
    );
    for command in ["evaluate", "identify", "calibrate"] {
        let o = with_lengths(command, &arm, &shipped("lengths.csv"), &dir.join(command));
        assert_eq!(o.status.code(), Some(1), "{command}: {}", stdout(&o));
        let err = stderr(&o);
        assert!(
            err.starts_with(&format!("warning: {arm}:")),
            "{command}: the warning names the arm: {err}"
        );
        let first = first_error_line(&o);
        assert!(
            first.starts_with(&format!("error: {arm}: the arm file's lengths"))
                && first.contains("1240.0 m long")
                && first.contains("the lengths file (mm) is not the cause"),
            "{command}: {first}"
        );
    }
}

/// Case 8: a χ² below the note level but above the refusal level says, in
/// the same sentence, that it is a note and not a refusal, and what it
/// suggests — beside "Verdict: usable".
#[test]
fn a_chi_square_note_says_it_is_not_a_refusal_and_what_it_suggests() {
    let dir = temp_dir("first-cause-note");
    let o = calibrate_shipped(
        &dir.join("tight"),
        &["--prior", "length=0.5mm,angle=0.1deg", "--method", "lm"],
    );
    let summary = stdout(&o);
    assert!(o.status.success(), "{summary}\n{}", stderr(&o));
    let fit = (summary.lines())
        .find(|l| l.starts_with("Fit quality: "))
        .unwrap();
    assert!(
        fit.contains("residuals larger than the stated noise explains (P = ")
            && fit.contains("so a note, not a refusal: the fit is usable); it suggests a noise"),
        "{fit}"
    );
    assert!(
        summary.contains("\nVerdict: usable\n  note: χ² = "),
        "{summary}"
    );
}
