//! What the arm file says is checked against what it is applied to: readings
//! outside its joint limits are a warning; geometry that yields no finite
//! position, or statistics that overflow, is an error naming the arm file.

use crate::util::{aacmm, assert_clean_error, example, stderr, temp_dir, write};

const POSES: &str = "point,q1,q2,q3,q4,q5,q6\n\
    A,0,0,0,0,0,0\nA,0,0,181.2,0,0,1\nA,0,0,-190,0,1,0\n\
    B,10,20,30,40,50,60\nB,10,20,30,40,50,61\nB,10,20,30,40,51,61\n";

/// The paper's nominal arm with `from` replaced by `to` (first occurrence).
fn arm_with(from: &str, to: &str) -> String {
    let text = std::fs::read_to_string(example("paper-table-1.toml")).unwrap();
    assert!(text.contains(from));
    text.replacen(from, to, 1)
}

#[test]
fn readings_outside_the_joint_limits_are_one_warning() {
    let dir = temp_dir("arm-limits");
    // Joint 3 limited to ±180°: rows 3 and 4 (181.2°, −190°) are outside.
    let arm = write(
        &dir,
        "arm.toml",
        &arm_with("d = 250.0", "d = 250.0\nlimits = [-180, 180]"),
    );
    let data = write(&dir, "poses.csv", POSES);
    for cmd in ["points", "evaluate"] {
        let o = aacmm(&[cmd, "--arm", &arm, "--data", &data]);
        assert!(o.status.success(), "{cmd}: {}", stderr(&o));
        assert!(!o.stdout.is_empty());
        assert_eq!(
            stderr(&o),
            format!(
                "warning: {data}:3: field `q3`: 2 readings outside the arm's joint limits \
                 (first: 181.2° > 180°); check the arm file, the angle unit and the encoder \
                 zeros\n"
            ),
            "{cmd}"
        );
    }
    // Within the limits: no warning.
    let inside = write(
        &dir,
        "inside.csv",
        &POSES.replace("181.2", "180").replace("-190", "-180"),
    );
    let o = aacmm(&["points", "--arm", &arm, "--data", &inside]);
    assert!(o.status.success());
    assert_eq!(stderr(&o), "");
}

#[test]
fn non_finite_positions_are_the_arm_files_fault() {
    let dir = temp_dir("arm-inf");
    // Two links of 1e308 mm add up to infinity.
    let text = arm_with("a = 50.0", "a = 1e308").replacen("a = 35.0", "a = 1e308", 1);
    let arm = write(&dir, "huge.toml", &text);
    let data = write(&dir, "poses.csv", POSES);
    for cmd in ["points", "evaluate"] {
        let o = aacmm(&[cmd, "--arm", &arm, "--data", &data]);
        assert_clean_error(
            &o,
            &[
                &format!("{arm}: "),
                "not a finite number",
                &format!("{data}:2"),
            ],
        );
        assert!(o.stdout.is_empty(), "{cmd}");
    }
}

#[test]
fn overflowing_statistics_are_an_error_not_null() {
    let dir = temp_dir("arm-overflow");
    // Finite positions ~1e200 mm, whose squared distances overflow.
    let arm = write(&dir, "big.toml", &arm_with("a = 50.0", "a = 1e200"));
    let data = write(&dir, "poses.csv", POSES);
    let json = dir.join("report.json");
    let o = aacmm(&[
        "evaluate",
        "--arm",
        &arm,
        "--data",
        &data,
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_clean_error(
        &o,
        &[&format!("{arm}: "), "overflows", "`pair_length_summary`"],
    );
    assert!(o.stdout.is_empty());
    assert!(!json.exists());
}
