//! `calibrate --robust`: a touch moved on purpose is downweighted and named
//! by file:line, the weights go to calibration.json, bad flags are refused
//! by name.

use crate::util::{calibrate_files, shipped, shipped_arm, temp_dir};

/// The shipped campaign with touch 17 (file line 18) turned by 0.2° on
/// joint 2 (about 2 mm at the probe), written into `dir`.
fn displaced_poses(dir: &std::path::Path) -> String {
    let text = std::fs::read_to_string(shipped("poses.csv")).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut cells: Vec<String> = lines[17].split(',').map(str::to_string).collect();
    let q2: f64 = cells[2].parse().unwrap();
    cells[2] = format!("{}", q2 + 0.2);
    lines[17] = cells.join(",");
    let path = dir.join("poses.csv");
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
    path.display().to_string()
}

fn calibrate(poses: &str, out: &std::path::Path, extra: &[&str]) -> std::process::Output {
    calibrate_files(&shipped_arm(), poses, out, extra)
}

#[test]
fn robust_cauchy_writes_the_weights_and_names_the_downweighted_touch() {
    let dir = temp_dir("robust-cauchy");
    let poses = displaced_poses(&dir);
    // Plain least squares names the touch but the fit is poor: exit 1.
    let plain = calibrate(&poses, &dir.join("plain"), &[]);
    assert!(!plain.status.success());
    let json = std::fs::read_to_string(dir.join("plain/calibration.json")).unwrap();
    assert!(
        !json.contains("\"robust\""),
        "a plain fit reports no robust section"
    );
    let o = calibrate(&poses, &dir.join("robust"), &["--robust", "cauchy"]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let at = format!("{poses}:18");
    let robust_line = stdout
        .lines()
        .find(|l| l.starts_with("Robust: cauchy (k = 2.65)"))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(
        robust_line.contains(&format!("1 touch(es) weighed below 0.25: {at} (point S2")),
        "{robust_line}"
    );
    assert!(
        stdout.contains("Fit quality: robust cauchy fit"),
        "{stdout}"
    );
    let json = std::fs::read_to_string(dir.join("robust/calibration.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let fit = &v["calibration"]["robust"];
    assert_eq!(fit["loss"], "cauchy");
    let weights = fit["weights"].as_array().unwrap();
    assert_eq!(weights.len(), 100);
    for w in weights {
        let (here, weight) = (w["at"].as_str().unwrap(), w["weight"].as_f64().unwrap());
        assert!(weight > 0.0 && weight <= 1.0, "{w}");
        assert_eq!(here == at, weight < 0.25, "{w}");
    }
    // The χ² test gives way to the robust scale's.
    assert!(v["calibration"]["checks"]["chi_square"].is_null());
}

#[test]
fn bad_robust_flags_are_refused_by_name() {
    let dir = temp_dir("robust-flags");
    let poses = shipped("poses.csv");
    let o = calibrate(&poses, &dir.join("a"), &["--robust", "bogus"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("'bogus'") && err.contains("--robust"), "{err}");
    let o = calibrate(
        &poses,
        &dir.join("b"),
        &["--robust", "huber", "--robust-scale", "-1"],
    );
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--robust-scale -1: must be a finite number > 0"),
        "{err}"
    );
    assert!(!dir.join("b/calibration.json").exists());
    let o = calibrate(&poses, &dir.join("c"), &["--robust-scale", "2"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--robust <LOSS>"), "{err}");
}

/// One touch labelled with another socket pulls the plain fit so far that
/// every touch lies beyond the outlier threshold; the summary lists the
/// one a robust refit weighs down, and says how many the plain fit had.
#[test]
fn a_mislabelled_touch_is_the_one_outlier_listed() {
    let dir = temp_dir("robust-mislabelled");
    let text = std::fs::read_to_string(shipped("poses.csv")).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    assert!(lines[17].starts_with("S2,"), "{}", lines[17]);
    lines[17] = lines[17].replacen("S2,", "S7,", 1);
    let poses = dir.join("poses.csv");
    std::fs::write(&poses, lines.join("\n") + "\n").unwrap();
    let poses = poses.display().to_string();
    let o = calibrate(&poses, &dir.join("plain"), &[]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    let line = (stdout.lines())
        .find(|l| l.starts_with("Outliers:"))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(
        line.starts_with("Outliers: 1 touch(es) beyond")
            && line.contains("that a robust cauchy refit weighs below 0.25 (of 100 beyond it"),
        "{line}"
    );
    assert!(
        line.contains(&format!(": {poses}:18 (point S7, ")),
        "{line}"
    );
}
