//! Every write is checked: a reader that goes away early ends the run
//! quietly with success, a stream that cannot be written (`/dev/full`) is an
//! error naming it — never a panic.

#![cfg(unix)]

use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Output, Stdio};

use crate::util::{command, shipped_arm as arm, stderr, temp_dir, write};

/// A poses file of `points` points touched 3 times each: `3 × points` rows.
fn many_poses(dir: &Path, points: usize) -> String {
    let mut text = String::from("point,q1,q2,q3,q4,q5,q6\n");
    for i in 0..points {
        for t in 0..3 {
            let q1 = (i % 340) as f64 - 170.0;
            text += &format!("P{i},{q1},{},30,40,50,{}\n", (i / 340) * 10, t * 5);
        }
    }
    write(dir, "many.csv", &text)
}

fn dev_full() -> Stdio {
    File::options()
        .write(true)
        .open("/dev/full")
        .expect("/dev/full")
        .into()
}

/// Runs `c` with stdout read for one line and then closed; returns the
/// first line and the finished run.
fn read_one_line_of_stdout(mut c: Command) -> (String, Output) {
    let mut child = c
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the aacmm binary runs");
    let mut first = String::new();
    {
        let mut out = BufReader::new(child.stdout.take().unwrap());
        out.read_line(&mut first).unwrap();
        // Dropped here: the reader goes away with most of the output unread.
    }
    (first, child.wait_with_output().unwrap())
}

#[track_caller]
fn assert_quiet_success(o: &Output) {
    let err = stderr(o);
    assert!(!err.contains("panicked"), "panic: {err}");
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert_eq!(err, "", "a closed pipe is not worth a message");
}

#[test]
fn points_stops_quietly_when_its_reader_goes_away() {
    let dir = temp_dir("streams-points-pipe");
    // ~1 MB of points: far more than a pipe buffers.
    let data = many_poses(&dir, 8000);
    let (first, o) =
        read_one_line_of_stdout(command(&["points", "--arm", &arm(), "--data", &data]));
    assert_eq!(first, "point,x,y,z\n");
    assert_quiet_success(&o);
}

#[test]
fn evaluate_stops_quietly_when_its_reader_goes_away_and_still_writes_json() {
    let dir = temp_dir("streams-evaluate-pipe");
    // 150 points make a table of ~0.7 MB (every pair of points has a row):
    // far more than a pipe buffers.
    let data = many_poses(&dir, 150);
    let json = dir.join("report.json");
    let args = [
        "evaluate",
        "--arm",
        &arm(),
        "--data",
        &data,
        "--json",
        json.to_str().unwrap(),
    ];
    let (first, o) = read_one_line_of_stdout(command(&args));
    assert!(first.starts_with("arm `paper-table-1`"), "{first}");
    assert_quiet_success(&o);
    // What was asked for besides stdout is still done.
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(
        report["evaluation"]["points"].as_array().unwrap().len(),
        150
    );
}

#[test]
fn simulate_stops_quietly_when_its_reader_goes_away() {
    // simulate reports on stderr: close that before it writes a word.
    let dir = temp_dir("streams-simulate-pipe");
    let out = dir.join("campaign");
    let args = [
        "simulate",
        "--arm",
        &arm(),
        "--errors",
        "paper",
        "--sockets",
        "2",
        "--poses",
        "3",
        "--seed",
        "1",
        "--out",
        out.to_str().unwrap(),
    ];
    let mut child = command(&args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stderr.take());
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(0));
    assert!(o.stdout.is_empty());
    assert!(out.join("campaign.toml").exists());
}

#[cfg(target_os = "linux")]
#[test]
fn a_full_stdout_is_an_error_naming_stdout() {
    let dir = temp_dir("streams-full-stdout");
    let data = many_poses(&dir, 10);
    let arm = arm();
    for cmd in ["points", "evaluate"] {
        let o = command(&[cmd, "--arm", &arm, "--data", &data])
            .stdout(dev_full())
            .output()
            .unwrap();
        let err = stderr(&o);
        assert!(!err.contains("panicked"), "{cmd}: panic: {err}");
        assert_eq!(o.status.code(), Some(1), "{cmd}: {err}");
        assert!(
            err.starts_with("error: stdout: cannot write:") && err.lines().count() == 1,
            "{cmd}: {err}"
        );
    }
}

#[cfg(target_os = "linux")]
#[test]
fn a_full_stderr_fails_without_a_panic() {
    let dir = temp_dir("streams-full-stderr");
    let arm = arm();
    let run = |args: &[&str]| command(args).stderr(dev_full()).output().unwrap();
    // simulate reports on stderr: the campaign is written, the run fails.
    let out = dir.join("campaign");
    let o = run(&[
        "simulate",
        "--arm",
        &arm,
        "--errors",
        "paper",
        "--sockets",
        "2",
        "--poses",
        "3",
        "--seed",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(out.join("campaign.toml").exists());
    // A warning that cannot be written (20 rows of radian-sized degrees).
    let mut text = String::from("point,q1,q2,q3,q4,q5,q6\n");
    for i in 0..21 {
        text += &format!("P{},0,0.{i},0,0,0,0\n", i / 3);
    }
    let data = write(&dir, "radians.csv", &text);
    for cmd in ["points", "evaluate"] {
        let o = run(&[cmd, "--arm", &arm, "--data", &data]);
        assert_eq!(o.status.code(), Some(1), "{cmd}");
    }
    // An error that cannot be written.
    let o = run(&["points", "--arm", &arm, "--data", "/nonexistent/poses.csv"]);
    assert_eq!(o.status.code(), Some(1));
}
