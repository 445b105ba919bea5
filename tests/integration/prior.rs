//! `--prior` and the arm file's `[prior]` on the command line: the prior is
//! used and reported, `--prior none` gives today's result, bad tolerances
//! name the flag or the file's line, `identify` reports the rank it adds.

use crate::util::{aacmm, calibrate_files, calibrate_shipped, shipped, shipped_arm, temp_dir};

fn json(dir: &std::path::Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("calibration.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

#[test]
fn the_arm_files_prior_is_used_and_none_switches_it_off() {
    let dir = temp_dir("prior-file");
    let arm = dir.join("arm.toml");
    let text = std::fs::read_to_string(shipped_arm()).unwrap();
    std::fs::write(
        &arm,
        format!("{text}\n[prior]\nlength_mm = 1\nangle_deg = 0.5\n"),
    )
    .unwrap();
    let poses = shipped("poses.csv");
    let run = |out: &str, extra: &[&str]| {
        let out = dir.join(out);
        let o = calibrate_files(arm.to_str().unwrap(), &poses, &out, extra);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (String::from_utf8(o.stdout).unwrap(), json(&out))
    };
    let (summary, with) = run("with", &[]);
    assert!(
        summary.contains("Prior: length=1mm, angle=0.5deg; 21 pseudo-observation rows"),
        "{summary}"
    );
    assert!(summary.contains("data share"), "{summary}");
    assert_eq!(with["calibration"]["dof"]["prior_rows"], 21);
    assert_eq!(
        with["calibration"]["prior"]["parameters"]
            .as_array()
            .unwrap()
            .len(),
        21
    );
    // The HTML parameter table shows tolerance and data share, tied to the JSON.
    let html = std::fs::read_to_string(dir.join("with/report.html")).unwrap();
    assert!(html.contains("data share"));
    assert!(
        html.contains("prior/parameters/0/data_share\""),
        "no JSON-tied data share cell"
    );
    assert!(crate::report::assert_agrees_with_json(&html, &with) > 0);
    // `--prior none`: the calibration of the arm without a prior, exactly.
    let (summary, off) = run("off", &["--prior", "none"]);
    assert!(!summary.contains("Prior:"), "{summary}");
    let plain_dir = dir.join("plain");
    let o = calibrate_shipped(&plain_dir, &[]);
    assert!(o.status.success());
    let plain = json(&plain_dir);
    assert!(off["calibration"].get("prior").is_none());
    assert!(off["calibration"]["dof"].get("prior_rows").is_none());
    assert_eq!(off["calibration"], plain["calibration"]);
    // `--prior` overrides the file entry by entry.
    let (summary, _) = run("override", &["--prior", "theta2=0.2deg"]);
    assert!(
        summary.contains("Prior: length=1mm, angle=0.5deg, theta2=0.2deg;"),
        "{summary}"
    );
}

#[test]
fn bad_tolerances_name_the_flag_or_the_line() {
    let dir = temp_dir("prior-bad");
    let o = calibrate_shipped(&dir.join("a"), &["--prior", "theta5=0.05mm"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--prior theta5=0.05mm: `theta5=0.05mm`: theta5 is an angle"),
        "{err}"
    );
    let arm = dir.join("arm.toml");
    let text = std::fs::read_to_string(shipped_arm()).unwrap();
    let full = format!("{text}\n[prior]\nlength_mm = 0\n");
    let line = full.lines().count();
    std::fs::write(&arm, full).unwrap();
    let o = aacmm(&[
        "identify",
        "--arm",
        arm.to_str().unwrap(),
        "--data",
        &shipped("poses.csv"),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&format!("arm.toml:{line}: field `length_mm`: [prior]: tolerance of length must be a finite number > 0")),
        "{err}"
    );
}

#[test]
fn identify_reports_rank_and_condition_with_and_without_the_prior() {
    let o = aacmm(&[
        "identify",
        "--arm",
        &shipped_arm(),
        "--data",
        &shipped("poses.csv"),
        "--lengths",
        &shipped("lengths.csv"),
        "--encoder-noise",
        "0.005",
        "--probe-noise",
        "0.01",
        "--prior",
        "length=0.5mm,angle=0.1deg",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8(o.stdout).unwrap();
    assert!(
        out.contains(
            "With the prior (length=0.5mm, angle=0.1deg; 27 of 27 parameters; touches weighed \
             from the stated noise)"
        ),
        "{out}"
    );
    assert!(
        out.contains("rank 27 of 27 (data alone: 21 after the rules)"),
        "{out}"
    );
}
