//! What the arm file says is checked against what it is applied to: readings
//! outside its joint limits are a warning.

use crate::util::{aacmm, example, stderr, temp_dir, write};

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
