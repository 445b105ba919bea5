//! A refused calibration (one mislabelled touch) read through every output
//! of the command line says NOT usable and why: the summary, the JSON, the
//! report's first section, and `calibrated.toml`, which `points` and
//! `evaluate` refuse unless asked. A usable calibration's file says so and
//! is read without a word.

use crate::util::{
    aacmm, calibrate_files, calibrate_shipped, mislabelled_poses, shipped, shipped_arm, stderr,
    stdout, temp_dir,
};

#[test]
fn a_refused_calibration_says_so_in_every_output() {
    let dir = temp_dir("verdict-refused");
    let poses = mislabelled_poses(&dir);
    let out = dir.join("out");
    let o = calibrate_files(&shipped_arm(), &poses, &out, &[]);
    assert!(!o.status.success(), "{}", stdout(&o));
    let summary = stdout(&o);
    let line = (summary.lines())
        .find(|l| l.starts_with("Verdict: "))
        .unwrap_or_else(|| panic!("{summary}"));
    assert!(line.starts_with("Verdict: NOT usable — "), "{line}");
    assert!(
        stderr(&o).contains("calibrated.toml ([verdict]"),
        "{}",
        stderr(&o)
    );

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("calibration.json")).unwrap())
            .unwrap();
    let reasons: Vec<&str> = (json["verdict"]["reasons"].as_array().unwrap().iter())
        .map(|r| r.as_str().unwrap())
        .collect();
    assert_eq!(json["verdict"]["usable"], false);
    // The cause first: the mislabelled touch, by file:line, and the remedy.
    assert!(
        reasons[0].contains(&format!("{poses}:18 (point S1,"))
            && reasons[0].contains("mislabelled or displaced touch? Check"),
        "{reasons:?}"
    );

    // The page opens with the verdict, before any figure, with every reason.
    let page = std::fs::read_to_string(out.join("report.html")).unwrap();
    let verdict = page
        .find("<section id=\"verdict\">")
        .expect("a verdict section");
    let first = page.find("<section").unwrap();
    assert_eq!(verdict, first, "the verdict is the first section");
    assert!(page.contains("data-json=\"/verdict/usable\" data-value=\"false\""));
    assert!(page.contains("Verdict: NOT usable."));
    for r in &reasons {
        let start: String = r.chars().take(40).collect();
        let start = start.replace('&', "&amp;").replace('\'', "&#39;");
        assert!(page.contains(&start), "the page lacks the reason `{r}`");
    }
    assert!(page.contains("χ² test") && page.contains("Outliers"));

    // The arm file: marked at its top and by its [verdict] table.
    let arm = out.join("calibrated.toml");
    let text = std::fs::read_to_string(&arm).unwrap();
    assert!(text.starts_with("# NOT USABLE"), "{text}");
    assert!(text.contains("[verdict]\nusable = false\n"), "{text}");
    let arm = arm.display().to_string();
    for command in ["points", "evaluate"] {
        let refused = aacmm(&[command, "--arm", &arm, "--data", &poses]);
        assert!(!refused.status.success(), "{command} read a refused arm");
        let err = stderr(&refused);
        assert!(
            err.contains(
                "field `verdict`: this arm file was written by a calibration that was NOT usable"
            ) && err.contains("--accept-rejected"),
            "{err}"
        );
        let asked = aacmm(&[
            command,
            "--arm",
            &arm,
            "--data",
            &poses,
            "--accept-rejected",
        ]);
        assert!(asked.status.success(), "{}", stderr(&asked));
        assert!(stderr(&asked).contains("NOT usable"), "{}", stderr(&asked));
    }
}

#[test]
fn a_usable_calibrations_arm_file_says_so_and_is_read_without_a_word() {
    let dir = temp_dir("verdict-usable");
    let out = dir.join("out");
    let o = calibrate_shipped(&out, &["--method", "lm", "--cross-validate", "3"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(out.join("calibrated.toml")).unwrap();
    assert!(text.contains("[verdict]\nusable = true\n"), "{text}");
    assert!(!text.contains("NOT USABLE"));
    let page = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(page.contains("Verdict: usable."));
    // The cross-validation folds are held-out data: the page says so.
    assert!(!page.contains("No held-out data were given"));
    assert!(page.contains("Held out, fold 1"), "no fold in the verdict");
    let arm = out.join("calibrated.toml").display().to_string();
    let read = aacmm(&["points", "--arm", &arm, "--data", &shipped("poses.csv")]);
    assert!(read.status.success(), "{}", stderr(&read));
    assert_eq!(
        stderr(&read),
        "",
        "a usable arm file is read without a warning"
    );
}
