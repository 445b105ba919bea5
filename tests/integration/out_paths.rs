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

/// Issue 43, case 6: one rule for every command that writes. An output
/// file that exists, or an output directory holding results of any aacmm
/// command, is refused before any work unless `--force`, which writes its
/// own files and deletes nothing. Before, `export` overwrote silently and
/// `simulate --out` mixed a campaign into a calibration's directory.
#[test]
fn no_command_writes_over_earlier_results_without_force() {
    let dir = temp_dir("paths-one-rule");
    let data = write(&dir, "touches.csv", POSES);
    let (arm, poses) = (arm(), crate::util::shipped("poses.csv"));
    let calibrate =
        |out: &Path| crate::util::calibrate_files(&arm, &poses, out, &["--method", "lm"]);
    let simulate = |out: &Path, extra: &[&str]| {
        let out = out.to_str().unwrap();
        let mut a = vec![
            "simulate",
            "--arm",
            &arm,
            "--errors",
            "paper",
            "--sockets",
            "3",
        ];
        a.extend(["--poses", "4", "--seed", "1", "--out", out]);
        a.extend(extra);
        aacmm(&a)
    };
    // A calibration's directory, made once.
    let cal = dir.join("cal");
    assert!(calibrate(&cal).status.success());
    // A campaign written into it: refused, the directory as it was; with
    // --force, written beside the calibration, which stays.
    assert_clean_error(
        &simulate(&cal, &[]),
        &[
            "--out",
            "already holds earlier results (calibrated.toml, calibration.json",
            "--force",
        ],
    );
    assert!(!cal.join("poses.csv").exists());
    assert!(simulate(&cal, &["--force"]).status.success());
    assert!(cal.join("poses.csv").exists() && cal.join("calibrated.toml").exists());
    // A calibration into a campaign's directory: refused the same way.
    let campaign = dir.join("campaign");
    assert!(simulate(&campaign, &[]).status.success());
    let o = calibrate(&campaign);
    assert_clean_error(&o, &["--out", "already holds earlier results (poses.csv"]);
    assert!(!campaign.join("calibrated.toml").exists());
    // Every output file that exists: refused without --force, kept as it
    // was; written with it.
    let calibrated = cal.join("calibrated.toml").display().to_string();
    let file = |name: &str| {
        let path = dir.join(name).display().to_string();
        std::fs::write(&path, "mine\n").unwrap();
        path
    };
    let (points, urdf, table, ev, id, pl) = (
        file("points.csv"),
        file("arm.urdf"),
        file("dh.csv"),
        file("evaluate.json"),
        file("identify.json"),
        file("plan.json"),
    );
    let runs: Vec<(&str, Vec<&str>)> = vec![
        (
            "--out",
            vec!["points", "--arm", &arm, "--data", &data, "--out", &points],
        ),
        (
            "--urdf",
            vec!["export", "--arm", &calibrated, "--urdf", &urdf],
        ),
        (
            "--dh-table",
            vec!["export", "--arm", &calibrated, "--dh-table", &table],
        ),
        (
            "--json",
            vec!["evaluate", "--arm", &arm, "--data", &data, "--json", &ev],
        ),
        (
            "--json",
            vec!["identify", "--arm", &arm, "--data", &poses, "--json", &id],
        ),
        (
            "--json",
            vec![
                "plan",
                "--arm",
                &arm,
                "--sample",
                "40",
                "--count",
                "10",
                "--measure",
                "positions",
                "--json",
                &pl,
            ],
        ),
    ];
    for (flag, args) in &runs {
        let o = aacmm(args);
        assert_clean_error(&o, &[flag, "already exists; give --force to overwrite it"]);
        let out = args.last().unwrap();
        assert_eq!(std::fs::read_to_string(out).unwrap(), "mine\n", "{args:?}");
        let forced = aacmm(&[&args[..], &["--force"]].concat());
        assert!(
            forced.status.success(),
            "{args:?}: {}",
            crate::util::stderr(&forced)
        );
        assert_ne!(std::fs::read_to_string(out).unwrap(), "mine\n", "{args:?}");
    }
    // A report directory that holds a report: refused; other files only: fine.
    let report = dir.join("report");
    let ev = |extra: &[&str]| {
        let mut a = vec![
            "evaluate",
            "--arm",
            &arm,
            "--data",
            &data,
            "--report",
            report.to_str().unwrap(),
        ];
        a.extend(extra);
        aacmm(&a)
    };
    std::fs::create_dir_all(&report).unwrap();
    std::fs::write(report.join("notes.txt"), "mine").unwrap();
    assert!(ev(&[]).status.success());
    assert_clean_error(
        &ev(&[]),
        &["--report", "already holds earlier results (report.html"],
    );
    assert!(ev(&["--force"]).status.success());
    assert_eq!(
        std::fs::read_to_string(report.join("notes.txt")).unwrap(),
        "mine"
    );
    // A device is always written.
    let o = aacmm(&[
        "points",
        "--arm",
        &arm,
        "--data",
        &data,
        "--out",
        "/dev/stdout",
    ]);
    assert!(o.status.success() && stdout(&o).starts_with("point,x,y,z\n"));
}
