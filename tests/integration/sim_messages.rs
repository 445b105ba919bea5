//! `aacmm simulate` fails fast and blames the right input: too many touches
//! per socket, two sockets at one place, a socket out of reach.

use std::path::Path;
use std::process::{Output, Stdio};
use std::time::{Duration, Instant};

use crate::util::{assert_clean_error, command, example, stderr, temp_dir, write};

/// Runs `aacmm simulate` on the paper's nominal arm with the paper's errors;
/// a run longer than `limit` is killed and fails the test.
fn simulate(extra: &[&str], out: &Path, limit: Duration) -> Output {
    let arm = example("paper-table-1.toml");
    let mut args = vec![
        "simulate",
        "--arm",
        arm.to_str().unwrap(),
        "--errors",
        "paper",
        "--seed",
        "1",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    let mut child = command(&args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("`aacmm simulate {extra:?}` still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// A point the paper's arm reaches in many articulations (socket S1 of the
/// shipped campaign).
const REACHABLE: &str = "143.413053,63.660416,861.184613";

#[test]
fn too_many_poses_per_socket_fail_at_once_with_the_reason() {
    let dir = temp_dir("sim-many-poses");
    let o = simulate(
        &["--sockets", "1", "--poses", "10000"],
        &dir,
        Duration::from_secs(10),
    );
    assert_clean_error(
        &o,
        &["--poses: at most 1000 touches per socket, got 10000", "20°"],
    );
    assert!(!dir.join("poses.csv").exists());
    // The maximum itself is within reach.
    let o = simulate(
        &["--sockets", "1", "--poses", "1000"],
        &dir,
        Duration::from_secs(120),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("1000 poses"), "{}", stderr(&o));
}

#[test]
fn sockets_at_the_same_place_are_blamed_on_the_sockets_file() {
    let dir = temp_dir("sim-same-place");
    let sockets = write(
        &dir,
        "sockets.csv",
        &format!("# twins\npoint,x,y,z\nA,{REACHABLE}\nB,{REACHABLE}\n"),
    );
    let o = simulate(
        &["--sockets-file", &sockets, "--poses", "3"],
        &dir.join("out"),
        Duration::from_secs(60),
    );
    assert_clean_error(
        &o,
        &[&format!(
            "{sockets}:4: field `point`: socket `B` is at the same place as socket `A` (line 3)"
        )],
    );
    assert!(
        !stderr(&o).contains("--length-uncertainty"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn an_unreachable_socket_names_the_file_and_line() {
    let dir = temp_dir("sim-unreachable");
    let sockets = write(
        &dir,
        "sockets.csv",
        &format!("point,x,y,z\nA,{REACHABLE}\nFar,5000,0,0\n"),
    );
    let o = simulate(
        &["--sockets-file", &sockets, "--poses", "3"],
        &dir.join("out"),
        Duration::from_secs(60),
    );
    assert_clean_error(&o, &[&format!("{sockets}:3: socket `Far`: found 0 of 3")]);
}

/// A 10 000-character socket label is echoed cut to 80 characters with its
/// length said, in the command line's own check (two sockets at one place)
/// and in the simulator's (a socket out of reach).
#[test]
fn a_hostile_socket_label_gives_a_bounded_message() {
    let dir = temp_dir("sim-hostile-label");
    let label = "L".repeat(10_000);
    for (name, rows) in [
        ("twins.csv", format!("A,{REACHABLE}\n{label},{REACHABLE}\n")),
        ("far.csv", format!("A,{REACHABLE}\n{label},5000,0,0\n")),
    ] {
        let sockets = write(&dir, name, &format!("point,x,y,z\n{rows}"));
        let o = simulate(
            &["--sockets-file", &sockets, "--poses", "3"],
            &dir.join("out"),
            Duration::from_secs(60),
        );
        assert_clean_error(&o, &["(10000 characters)"]);
        let err = stderr(&o);
        let own = err.len() - sockets.len();
        assert!(own < 600, "{own} characters besides the path: {err:.700}");
    }
}

/// Issue 43, case 5: a true arm with encoder harmonics puts its touches
/// exactly on their sockets, and the summary's "largest residual" is that
/// of what was simulated — the readings through the true arm's
/// corrections — not of the chain without them (1.2e-1 mm before).
#[test]
fn the_largest_residual_is_the_simulated_arms_with_its_harmonics() {
    let dir = temp_dir("sim-harmonics-residual");
    let nominal = std::fs::read_to_string(example("paper-table-1.toml")).unwrap();
    // Joint 2 and joint 5 with a first and a second harmonic of 0.01°.
    let mut joints = nominal.split("[[joint]]\n");
    let mut text = joints.next().unwrap().to_string();
    for (j, joint) in joints.enumerate() {
        text += "[[joint]]\n";
        if j == 1 || j == 4 {
            text += "harmonics = [[1, 0.01, -0.005], [2, 0.0, 0.008]]\n";
        }
        text += joint;
    }
    let truth = write(&dir, "true.toml", &text);
    let arm = example("paper-table-1.toml");
    let out = dir.join("campaign");
    let o = command(&[
        "simulate",
        "--arm",
        arm.to_str().unwrap(),
        "--true",
        &truth,
        "--sockets",
        "3",
        "--poses",
        "5",
        "--seed",
        "1",
        "--out",
        out.to_str().unwrap(),
    ])
    .output()
    .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    let largest = err
        .split("largest residual ")
        .nth(1)
        .and_then(|r| r.split(" mm").next())
        .and_then(|r| r.parse::<f64>().ok())
        .unwrap_or_else(|| panic!("no largest residual in:\n{err}"));
    assert!(largest < 1e-9, "largest residual {largest:e} mm:\n{err}");
    // The true arm's harmonics are in its file and move the readings.
    let written = std::fs::read_to_string(out.join("true_arm.toml")).unwrap();
    assert!(written.contains("harmonics"), "{written}");
}

/// Issue 43, case 7: progress is drawn only on a terminal. A pipe (as
/// here) gets the summary lines and nothing else: no bar, no carriage
/// return, no escape sequence, in `simulate` and in `plan` (which samples
/// its candidates by the simulator, then chooses).
#[test]
fn no_progress_is_drawn_when_stderr_is_not_a_terminal() {
    let dir = temp_dir("sim-no-progress");
    let o = simulate(
        &["--sockets", "4", "--poses", "5"],
        &dir.join("campaign"),
        Duration::from_secs(60),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let arm = example("paper-table-1.toml");
    let plan = command(&[
        "plan",
        "--arm",
        arm.to_str().unwrap(),
        "--sample",
        "40",
        "--count",
        "10",
        "--measure",
        "touches",
    ])
    .output()
    .unwrap();
    assert!(plan.status.success(), "{}", stderr(&plan));
    for (what, err) in [("simulate", stderr(&o)), ("plan", stderr(&plan))] {
        assert!(
            !err.contains(['\r', '\u{1b}']) && !err.contains("] ") && !err.contains('%'),
            "{what} drew progress into a pipe:\n{err:?}"
        );
    }
    let err = stderr(&o);
    let lines: Vec<&str> = err.lines().collect();
    assert!(
        lines[0].starts_with("nominal arm ") && lines.len() == 9,
        "{lines:#?}"
    );
}
