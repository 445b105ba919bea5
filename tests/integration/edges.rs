//! Edges found by trying the CLI as a new user would: inputs that once
//! panicked, and messages that once blamed the wrong thing.

use crate::util::{aacmm, assert_clean_error, shipped, shipped_arm, stderr, temp_dir, write};

/// The shipped campaign reduced to the first row of each socket, repeated
/// ten times (`jitter`: with ±0.01° added, as encoder noise would).
fn static_campaign(jitter: bool) -> String {
    let text = std::fs::read_to_string(shipped("poses.csv")).unwrap();
    let mut lines = text.lines();
    let mut out = format!("{}\n", lines.next().unwrap());
    let mut seen: Vec<&str> = Vec::new();
    for line in lines {
        let label = line.split(',').next().unwrap();
        if seen.contains(&label) {
            continue;
        }
        seen.push(label);
        for k in 0..10 {
            if jitter {
                let d = [-0.01, -0.005, 0.0, 0.005, 0.01][k % 5];
                let q: Vec<String> = line
                    .split(',')
                    .skip(1)
                    .map(|v| (v.parse::<f64>().unwrap() + d).to_string())
                    .collect();
                out.push_str(&format!("{label},{}\n", q.join(",")));
            } else {
                out.push_str(line);
                out.push('\n');
            }
        }
    }
    out
}

/// `identify` and `calibrate` on a campaign without articulation panicked
/// in the pivoted Cholesky (`rank ≤ columns`); now an error names the file
/// and the problem.
#[test]
fn static_data_is_an_error_not_a_panic() {
    let dir = temp_dir("edges-static");
    for jitter in [false, true] {
        let data = write(&dir, "static.csv", &static_campaign(jitter));
        let o = aacmm(&["identify", "--arm", &shipped_arm(), "--data", &data]);
        assert_clean_error(&o, &[&data, "no articulation"]);
        let out = dir.join("out").display().to_string();
        let o = aacmm(&[
            "calibrate",
            "--arm",
            &shipped_arm(),
            "--data",
            &data,
            "--out",
            &out,
        ]);
        assert_clean_error(&o, &[&data, "no articulation"]);
    }
}

/// A noise σ whose weights overflow once reached the solver, which blamed
/// the arm file ("the start arm gives positions that are not finite
/// numbers"); the error now names the flag and its value.
#[test]
fn overflowing_noise_names_the_flag() {
    let (arm, data) = (shipped_arm(), shipped("poses.csv"));
    let o = aacmm(&[
        "identify",
        "--arm",
        &arm,
        "--data",
        &data,
        "--encoder-noise",
        "1e-300",
    ]);
    assert_clean_error(&o, &["error: --encoder-noise 1e-300: ", "not finite"]);
    assert!(!stderr(&o).contains(".toml"), "{}", stderr(&o));
    // Beyond half a turn an encoder σ is refused as such (the same cap as
    // `simulate --encoder-noise`), its value as typed.
    let o = aacmm(&[
        "identify",
        "--arm",
        &arm,
        "--data",
        &data,
        "--encoder-noise",
        "1e300",
    ]);
    assert_clean_error(
        &o,
        &["error: --encoder-noise 1e300: σ = 1e300° is more than 180°"],
    );
    let lengths = shipped("lengths.csv");
    let o = aacmm(&[
        "identify",
        "--arm",
        &arm,
        "--data",
        &data,
        "--lengths",
        &lengths,
        "--encoder-noise",
        "0.005",
        "--length-uncertainty",
        "1e300",
    ]);
    assert_clean_error(
        &o,
        &["error: --length-uncertainty 1e300: ", "lengths.csv:2"],
    );
}

/// `--flag -0.5` is a value, as `--flag=-0.5` is: clap once read `-0` as
/// an unknown flag.
#[test]
fn negative_numbers_need_no_equals_sign() {
    let (arm, data) = (shipped_arm(), shipped("poses.csv"));
    let o = aacmm(&[
        "identify",
        "--arm",
        &arm,
        "--data",
        &data,
        "--encoder-noise",
        "-0.5",
    ]);
    assert_clean_error(&o, &["--encoder-noise -0.5: must be a finite number ≥ 0"]);
    let dir = temp_dir("edges-negative");
    let out = dir.join("sim").display().to_string();
    let o = aacmm(&[
        "simulate",
        "--arm",
        &arm,
        "--errors",
        "paper",
        "--sockets",
        "2",
        "--poses",
        "4",
        "--seed",
        "1",
        "--probe-noise",
        "-1",
        "--out",
        &out,
    ]);
    assert_clean_error(&o, &["--probe-noise", "-1"]);
    assert!(
        !stderr(&o).contains("unexpected argument"),
        "{}",
        stderr(&o)
    );
}

/// Standard input can be read once: `-` for two inputs is refused before
/// either is read (the second once reported `<stdin>: empty file`).
#[test]
fn two_inputs_from_stdin_are_refused_up_front() {
    let arm = shipped_arm();
    let o = aacmm(&["identify", "--arm", &arm, "--data", "-", "--lengths", "-"]);
    assert_clean_error(
        &o,
        &["--data and --lengths: each is `-` (standard input), which can be read once"],
    );
    let o = aacmm(&["points", "--arm", "-", "--data", "-"]);
    assert_clean_error(&o, &["--arm and --data"]);
    // One input from standard input is fine.
    let poses = std::fs::read_to_string(shipped("poses.csv")).unwrap();
    let mut child = crate::util::command(&["points", "--arm", &arm, "--data", "-"])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    use std::io::Write;
    child
        .stdin
        .take()
        .unwrap()
        .write_all(poses.as_bytes())
        .unwrap();
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A probe noise far beyond any seating noise is the flag's fault, not the
/// sockets' ("may be out of reach").
#[test]
fn huge_probe_noise_blames_the_noise() {
    let dir = temp_dir("edges-probe-noise");
    let out = dir.join("sim").display().to_string();
    let o = aacmm(&[
        "simulate",
        "--arm",
        &shipped_arm(),
        "--errors",
        "paper",
        "--sockets",
        "3",
        "--poses",
        "5",
        "--seed",
        "1",
        "--probe-noise",
        "1e6",
        "--out",
        &out,
    ]);
    assert_clean_error(&o, &["--probe-noise: σ = 1000000 mm", "reach"]);
    assert!(!stderr(&o).contains("out of reach"), "{}", stderr(&o));
}

/// `--out a/b/c` with `a/b` missing is refused before any work (it once
/// created the whole tree, although the README says a missing directory is
/// refused); `--out c` in an existing directory is created.
#[test]
fn out_creates_only_its_last_directory() {
    let dir = temp_dir("edges-out-parents");
    let deep = dir.join("a").join("b").join("c");
    let o = crate::util::calibrate_shipped(&deep, &[]);
    assert_clean_error(&o, &["--out", "does not exist", "only the last directory"]);
    assert!(
        !dir.join("a").exists(),
        "created {}",
        dir.join("a").display()
    );
    let shallow = dir.join("c");
    let o = crate::util::calibrate_shipped(&shallow, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(shallow.join("calibrated.toml").is_file());
}

/// An earlier calibration in `--out` is kept unless `--force` (it was
/// overwritten silently, and `--help` did not say so).
#[test]
fn earlier_calibration_is_kept_without_force() {
    let dir = temp_dir("edges-out-force");
    let out = dir.join("cal");
    let o = crate::util::calibrate_shipped(&out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let marker = "# an earlier calibration\n";
    let calibrated = out.join("calibrated.toml");
    let first = std::fs::read_to_string(&calibrated).unwrap();
    std::fs::write(&calibrated, format!("{marker}{first}")).unwrap();
    let o = crate::util::calibrate_shipped(&out, &[]);
    assert_clean_error(
        &o,
        &[
            "--out",
            "earlier results (calibrated.toml, calibration.json,",
            "--force",
        ],
    );
    assert!(
        std::fs::read_to_string(&calibrated)
            .unwrap()
            .starts_with(marker)
    );
    let o = crate::util::calibrate_shipped(&out, &["--force"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&calibrated).unwrap(), first);
    let help = crate::util::stdout(&aacmm(&["calibrate", "--help"]));
    assert!(
        help.contains("--force") && help.contains("Write over earlier results"),
        "{help}"
    );
}

/// The shipped campaign written in radians (angles as typed in rad).
fn shipped_in_radians() -> String {
    use aacmm_core::io::{AngleUnit, read_poses, write_poses};
    let (poses, _) = read_poses(
        std::path::Path::new(&shipped("poses.csv")),
        AngleUnit::Deg,
        None,
    )
    .unwrap();
    let mut rad = Vec::new();
    write_poses(&mut rad, &poses, AngleUnit::Rad).unwrap();
    String::from_utf8(rad).unwrap()
}

/// Poses in radians read as degrees (the default unit): the reader's
/// warning was right, then the error blamed the lengths file ("1.747e2
/// times the nominal arm's distances"); the error now names the angle unit
/// and the flag.
#[test]
fn radians_read_as_degrees_blame_the_angle_unit() {
    let dir = temp_dir("edges-radians");
    let data = write(&dir, "rad.csv", &shipped_in_radians());
    let (arm, lengths) = (shipped_arm(), shipped("lengths.csv"));
    let out = dir.join("out").display().to_string();
    let o = aacmm(&[
        "calibrate",
        "--arm",
        &arm,
        "--data",
        &data,
        "--lengths",
        &lengths,
        "--out",
        &out,
    ]);
    assert_clean_error(
        &o,
        &[
            "look like radians; pass --angle-unit rad",
            &format!("error: {data}: every joint reading"),
            "look like radians read as degrees",
            "`--angle-unit rad`",
            "the lengths file is not the cause",
        ],
    );
    assert!(!stderr(&o).contains("different units"), "{}", stderr(&o));
    // Read as radians, the same files calibrate: the lengths were right.
    let o = crate::util::calibrate_files(&arm, &data, &dir.join("rad"), &["--angle-unit", "rad"]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Where the lengths pass (kinova-1's, in rad, read as degrees) the fit
    // fails later: its verdict leads with the angle unit, not with the
    // solver's minimum.
    let kinova = |f: &str| {
        crate::util::example("mukca/kinova-1")
            .join(f)
            .display()
            .to_string()
    };
    let out = dir.join("kinova").display().to_string();
    let o = aacmm(&[
        "calibrate",
        "--arm",
        &kinova("arm.toml"),
        "--data",
        &kinova("poses.csv"),
        "--lengths",
        &kinova("lengths.csv"),
        "--out",
        &out,
    ]);
    let text = crate::util::stdout(&o);
    let verdict = text
        .lines()
        .find(|l| l.starts_with("Verdict:"))
        .expect("a verdict");
    assert!(
        verdict.starts_with("Verdict: NOT usable — every joint reading of")
            && verdict.contains("look like radians read as degrees")
            && verdict.contains("`--angle-unit rad`"),
        "{verdict}"
    );
    assert!(!o.status.success());
}

/// A socket's row repeated (a logger that wrote a line again) is counted
/// once, with a warning naming the lines and the point: the figures are
/// those of the file without the repeats (counted, the repeats lowered e).
#[test]
fn repeated_rows_of_a_point_are_counted_once_and_said() {
    let dir = temp_dir("edges-repeats");
    let text = std::fs::read_to_string(shipped("poses.csv")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    // Line 2 is S1's first row: lines 3-5 repeat it.
    let mut repeated = vec![lines[0], lines[1], lines[1], lines[1], lines[1]];
    repeated.extend(&lines[2..]);
    let data = write(&dir, "repeated.csv", &(repeated.join("\n") + "\n"));
    let arm = shipped_arm();
    let evaluate = |data: &str| aacmm(&["evaluate", "--arm", &arm, "--data", data]);
    let o = evaluate(&data);
    assert!(o.status.success(), "{}", stderr(&o));
    let warning = stderr(&o);
    assert!(
        warning.contains(&format!(
            "{data}:3: field `point`: point `S1`: 3 rows repeat"
        )),
        "{warning}"
    );
    assert!(
        warning.contains("(lines 3–5; the first repeats line 2)"),
        "{warning}"
    );
    assert!(
        warning.contains("each counted once: 3 rows not used"),
        "{warning}"
    );
    let figures = |o: &std::process::Output| {
        let text = crate::util::stdout(o);
        text.lines().skip(1).collect::<Vec<_>>().join("\n")
    };
    let original = evaluate(&shipped("poses.csv"));
    assert!(stderr(&original).is_empty(), "{}", stderr(&original));
    assert_eq!(figures(&o), figures(&original));
    // A fit says it too (the request's warnings, which `calibrate` shares).
    let o = aacmm(&["identify", "--arm", &arm, "--data", &data]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("point `S1`: 3 rows repeat"),
        "{}",
        stderr(&o)
    );
}

/// `--help` lists the units `--angle-unit` takes, and what it applies to,
/// for every command that has it (it showed only its default).
#[test]
fn angle_unit_help_lists_its_values() {
    for command in ["calibrate", "identify", "evaluate", "points", "plan"] {
        let o = aacmm(&[command, "--help"]);
        let help = crate::util::stdout(&o);
        let at = help.find("--angle-unit <ANGLE_UNIT>").expect(command);
        let section = &help[at..];
        let section = &section[..section[2..]
            .find("\n      --")
            .map_or(section.len(), |e| e + 2)];
        for want in [
            "joint readings",
            "Possible values:",
            "- deg: degrees",
            "- rad: radians",
            "[default: deg]",
        ] {
            assert!(
                section.contains(want),
                "{command}: `{want}` not in {section}"
            );
        }
    }
    let short = crate::util::stdout(&aacmm(&["calibrate", "-h"]));
    assert!(short.contains("[possible values: deg, rad]"), "{short}");
}
