//! Output paths are checked before any work: an output that is an input is
//! refused (the input survives), and one that cannot be written (a
//! directory, a missing directory) is an error naming the flag before
//! anything is printed.

use std::path::Path;

use crate::util::{
    aacmm, assert_clean_error, example, shipped_arm as arm, stdout, temp_dir, write,
};

const POSES: &str = "point,q1,q2,q3,q4,q5,q6\n\
    A,0,0,0,0,0,0\nA,0,0,0,0,0,1\nA,0,0,0,0,1,0\n\
    B,10,20,30,40,50,60\nB,10,20,30,40,50,61\nB,10,20,30,40,51,61\n";

#[test]
fn points_refuses_to_overwrite_its_input() {
    let dir = temp_dir("paths-points-same");
    let data = write(&dir, "poses.csv", POSES);
    // The same path, the same file by another spelling, and by a link.
    let respelled = dir.join(".").join("poses.csv").display().to_string();
    let mut outs = vec![data.clone(), respelled];
    #[cfg(unix)]
    {
        let link = dir.join("link.csv");
        std::os::unix::fs::symlink(&data, &link).unwrap();
        outs.push(link.display().to_string());
    }
    for out in &outs {
        let o = aacmm(&["points", "--arm", &arm(), "--data", &data, "--out", out]);
        assert_clean_error(&o, &["--out", "--data", "overwrite"]);
        assert_eq!(std::fs::read_to_string(&data).unwrap(), POSES, "{out}");
    }
    let arm_copy = write(&dir, "arm.toml", &std::fs::read_to_string(arm()).unwrap());
    let o = aacmm(&[
        "points", "--arm", &arm_copy, "--data", &data, "--out", &arm_copy,
    ]);
    assert_clean_error(&o, &["--out", "--arm"]);
    // A different file is fine.
    let out = dir.join("points.csv").display().to_string();
    let o = aacmm(&["points", "--arm", &arm(), "--data", &data, "--out", &out]);
    assert!(o.status.success());
}

#[test]
fn evaluate_refuses_to_overwrite_its_input() {
    let dir = temp_dir("paths-evaluate-same");
    let data = write(&dir, "poses.csv", POSES);
    let lengths = write(&dir, "lengths.csv", "point_a,point_b,distance\nA,B,500\n");
    for (json, input) in [(&lengths, "--lengths"), (&data, "--data")] {
        let o = aacmm(&[
            "evaluate",
            "--arm",
            &arm(),
            "--data",
            &data,
            "--lengths",
            &lengths,
            "--json",
            json,
        ]);
        assert_clean_error(&o, &["--json", input]);
        assert!(o.stdout.is_empty(), "{}", stdout(&o));
    }
    assert_eq!(std::fs::read_to_string(&data).unwrap(), POSES);
    assert!(
        std::fs::read_to_string(&lengths)
            .unwrap()
            .contains("A,B,500")
    );
}

#[test]
fn simulate_refuses_to_overwrite_its_inputs() {
    // Re-simulating with the sockets of an earlier campaign, into its folder.
    let dir = temp_dir("paths-simulate-same");
    let sockets_text = std::fs::read_to_string(example("paper-campaign/sockets.csv")).unwrap();
    let sockets = write(&dir, "sockets.csv", &sockets_text);
    let o = aacmm(&[
        "simulate",
        "--arm",
        &arm(),
        "--errors",
        "paper",
        "--sockets-file",
        &sockets,
        "--poses",
        "3",
        "--seed",
        "1",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_clean_error(&o, &["--out", "--sockets-file", "sockets.csv"]);
    assert_eq!(std::fs::read_to_string(&sockets).unwrap(), sockets_text);
    assert!(!dir.join("poses.csv").exists(), "no work was done");
}

#[test]
fn unwritable_outputs_fail_before_any_output() {
    let dir = temp_dir("paths-unwritable");
    let data = write(&dir, "poses.csv", POSES);
    let folder = dir.display().to_string();
    let missing = dir.join("no-such-dir").join("report.json");
    let missing = missing.to_str().unwrap();
    let cases: &[(&[&str], &[&str])] = &[
        (
            &["evaluate", "--json", &folder],
            &["--json", &folder, "directory"],
        ),
        (
            &["evaluate", "--json", missing],
            &["--json", "no-such-dir", "does not exist"],
        ),
        (
            &["points", "--out", &folder],
            &["--out", &folder, "directory"],
        ),
    ];
    let arm = arm();
    for (args, expect) in cases {
        let mut all = vec![args[0], "--arm", &arm, "--data", &data];
        all.extend(&args[1..]);
        let o = aacmm(&all);
        assert_clean_error(&o, expect);
        assert!(o.stdout.is_empty(), "{:?}: printed {}", args, stdout(&o));
    }
    // simulate --out on a file: refused at once, not after the simulation.
    let file = Path::new(&data);
    let o = aacmm(&[
        "simulate",
        "--arm",
        &arm,
        "--errors",
        "paper",
        "--sockets",
        "3",
        "--poses",
        "3",
        "--seed",
        "1",
        "--out",
        file.to_str().unwrap(),
    ]);
    assert_clean_error(&o, &["--out", "not a directory"]);
    assert_eq!(std::fs::read_to_string(&data).unwrap(), POSES);
}
