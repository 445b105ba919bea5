//! `aacmm points`: forward kinematics of every row, 6 and 7 joints, and
//! errors that name file, line and field.

use crate::util::{aacmm, assert_clean_error, example, stdout, temp_dir, write};
use aacmm_core::io::read_arm;
use aacmm_core::reference_model;

const POSES: &str = "point,q1,q2,q3,q4,q5,q6\n\
    S1,0,0,0,0,0,0\n\
    S1,10,20,30,40,50,60\n\
    S2,-170,95.5,-30,12,-80,179\n";

fn parse_rows(text: &str) -> Vec<(String, [f64; 3])> {
    text.lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[0].to_string(), [1, 2, 3].map(|i| f[i].parse().unwrap()))
        })
        .collect()
}

#[test]
fn writes_every_row_in_order_matching_the_reference_model() {
    let dir = temp_dir("points-six");
    let data = write(&dir, "poses.csv", POSES);
    let arm = example("paper-table-1.toml");
    let o = aacmm(&["points", "--arm", arm.to_str().unwrap(), "--data", &data]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = stdout(&o);
    assert!(text.starts_with("point,x,y,z\n"));
    let rows = parse_rows(&text);
    let params = read_arm(&arm).unwrap().0.params.to_vec();
    let q_deg: [[f64; 6]; 3] = [
        [0.0; 6],
        [10.0, 20.0, 30.0, 40.0, 50.0, 60.0],
        [-170.0, 95.5, -30.0, 12.0, -80.0, 179.0],
    ];
    assert_eq!(rows.len(), 3);
    for ((label, xyz), (q, want_label)) in rows.iter().zip(q_deg.iter().zip(["S1", "S1", "S2"])) {
        assert_eq!(label, want_label);
        let want = reference_model::position(&params, &q.map(f64::to_radians));
        for k in 0..3 {
            // Output is written to 1e-6 mm.
            assert!((xyz[k] - want[k]).abs() <= 6e-7, "{xyz:?} vs {want:?}");
        }
    }
}

#[test]
fn out_file_and_radians() {
    let dir = temp_dir("points-out");
    let data = write(
        &dir,
        "poses.csv",
        "point,q1,q2,q3,q4,q5,q6\nP,0,0,0,0,0,0\n",
    );
    let out = dir.join("points.csv");
    let arm = example("paper-table-1.toml");
    let o = aacmm(&[
        "points",
        "--arm",
        arm.to_str().unwrap(),
        "--data",
        &data,
        "--angle-unit",
        "rad",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    assert!(o.stdout.is_empty());
    let text = std::fs::read_to_string(out).unwrap();
    assert_eq!(text, "point,x,y,z\nP,-5.000000,0.000000,995.000000\n");
}

#[test]
fn seven_joint_arm_uses_its_own_kernel() {
    let dir = temp_dir("points-seven");
    let mut arm = std::fs::read_to_string(example("paper-table-1.toml")).unwrap();
    arm = arm.replace(
        "[probe]",
        "[[joint]]\ntheta = 0.0\nalpha = -90.0\na = 20.0\nd = 60.0\n\n[probe]",
    );
    let arm = write(&dir, "arm7.toml", &arm);
    let data = write(
        &dir,
        "poses.csv",
        "point,q1,q2,q3,q4,q5,q6,q7\nP,5,10,15,20,25,30,35\n",
    );
    let o = aacmm(&["points", "--arm", &arm, "--data", &data]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = parse_rows(&stdout(&o));
    let params = read_arm(std::path::Path::new(&arm))
        .unwrap()
        .0
        .params
        .to_vec();
    let q = [5.0f64, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0].map(f64::to_radians);
    let want = reference_model::position(&params, &q);
    for (got, want) in rows[0].1.iter().zip(want) {
        assert!((got - want).abs() <= 6e-7);
    }
    // A 6-column poses file does not fit a 7-joint arm.
    let six = write(&dir, "six.csv", POSES);
    let o = aacmm(&["points", "--arm", &arm, "--data", &six]);
    assert_clean_error(&o, &["six.csv:1"]);
}

/// The tool frame of `arm` (D-H rows of its file, rad and mm) at readings
/// `q` (rad) and its probe `b`: the textbook product of 4×4 link matrices,
/// written here independently of the library.
fn tool_frame(arm: &aacmm_core::params::DhParams, q: &[f64]) -> [[f64; 4]; 4] {
    let mut t = [[0.0; 4]; 4];
    for (i, row) in t.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    let product = |x: [[f64; 4]; 4], y: [[f64; 4]; 4]| -> [[f64; 4]; 4] {
        std::array::from_fn(|r| std::array::from_fn(|c| (0..4).map(|k| x[r][k] * y[k][c]).sum()))
    };
    for (j, qj) in arm.joints.iter().zip(q) {
        let (s, c) = (j.theta + qj).sin_cos();
        let (sa, ca) = j.alpha.sin_cos();
        t = product(
            t,
            [
                [c, -ca * s, sa * s, j.a * c],
                [s, ca * c, -sa * c, j.a * s],
                [0.0, sa, ca, j.d],
                [0.0, 0.0, 0.0, 1.0],
            ],
        );
    }
    let b = arm.probe;
    product(
        t,
        [
            [1.0, 0.0, 0.0, b[0]],
            [0.0, 1.0, 0.0, b[1]],
            [0.0, 0.0, 1.0, b[2]],
            [0.0, 0.0, 0.0, 1.0],
        ],
    )
}

/// `--pose` adds the tool's orientation as a unit quaternion: the rotation
/// it stands for is the tool frame of an independent forward kinematics,
/// `w ≥ 0`, and the positions are `points`' own bytes.
#[test]
fn pose_writes_the_tool_orientation() {
    let dir = temp_dir("points-pose");
    let data = write(&dir, "poses.csv", POSES);
    let arm = example("paper-table-1.toml");
    let args = ["points", "--arm", arm.to_str().unwrap(), "--data", &data];
    let plain = aacmm(&args);
    let o = aacmm(&[&args[..], &["--pose"]].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = stdout(&o);
    assert!(text.starts_with("point,x,y,z,qw,qx,qy,qz\n"), "{text}");
    let params = read_arm(&arm).unwrap().0.params;
    let q_deg: [[f64; 6]; 3] = [
        [0.0; 6],
        [10.0, 20.0, 30.0, 40.0, 50.0, 60.0],
        [-170.0, 95.5, -30.0, 12.0, -80.0, 179.0],
    ];
    let plain_rows: Vec<&str> = std::str::from_utf8(&plain.stdout)
        .unwrap()
        .lines()
        .collect();
    for (i, line) in text.lines().skip(1).enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f.len(), 8, "{line}");
        assert_eq!(
            f[..4].join(","),
            plain_rows[i + 1],
            "the positions are points' own"
        );
        assert!(
            f[4..]
                .iter()
                .all(|v| v.split('.').nth(1).unwrap().len() == 9)
        );
        let [w, x, y, z] = [4, 5, 6, 7].map(|k| f[k].parse::<f64>().unwrap());
        assert!(w >= 0.0);
        assert!(((w * w + x * x + y * y + z * z) - 1.0).abs() < 1e-8);
        // The rotation of the quaternion against the frame's axes.
        let r = [
            [
                1.0 - 2.0 * (y * y + z * z),
                2.0 * (x * y - w * z),
                2.0 * (x * z + w * y),
            ],
            [
                2.0 * (x * y + w * z),
                1.0 - 2.0 * (x * x + z * z),
                2.0 * (y * z - w * x),
            ],
            [
                2.0 * (x * z - w * y),
                2.0 * (y * z + w * x),
                1.0 - 2.0 * (x * x + y * y),
            ],
        ];
        let t = tool_frame(&params, &q_deg[i].map(f64::to_radians));
        for (row, want) in r.iter().zip(&t) {
            for c in 0..3 {
                assert!((row[c] - want[c]).abs() < 5e-9, "{r:?} vs {t:?}");
            }
        }
        for k in 0..3 {
            let p: f64 = f[1 + k].parse().unwrap();
            assert!((p - t[k][3]).abs() <= 6e-7);
        }
    }
    // In a frame of the arm file: turned and moved as a rigid body.
    let calibrated = std::fs::read_to_string(&arm).unwrap()
        + "\n[[frame]]\nname = \"tracker\"\nrotation_deg = [0.0, 0.0, 90.0]\ntranslation_mm = [10.0, 0.0, 0.0]\n";
    let framed = write(&dir, "framed.toml", &calibrated);
    let o = aacmm(&[
        "points", "--arm", &framed, "--data", &data, "--pose", "--frame", "tracker",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let first: Vec<f64> = (stdout(&o).lines().nth(1).unwrap().split(',').skip(1))
        .map(|v| v.parse().unwrap())
        .collect();
    let base: Vec<f64> = (text.lines().nth(1).unwrap().split(',').skip(1))
        .map(|v| v.parse().unwrap())
        .collect();
    // A quarter turn about z: (x, y) → (−y, x), then 10 mm along x.
    assert!((first[0] - (10.0 - base[1])).abs() < 2e-6 && (first[1] - base[0]).abs() < 2e-6);
    // q' = q_z(90°)·q: w' = (w − z)/√2 for a tool of (w, 0, 0, z).
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let (w, z) = (base[3], base[6]);
    assert!((first[3] - h * (w - z)).abs() < 1e-8 || (first[3] + h * (w - z)).abs() < 1e-8);
}

#[test]
fn bad_files_name_file_line_and_field() {
    let dir = temp_dir("points-bad");
    let arm = example("paper-table-1.toml");
    let arm = arm.to_str().unwrap();
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "nan.csv",
            "point,q1,q2,q3,q4,q5,q6\nS1,0,0,NaN,0,0,0\n",
            &["nan.csv:2", "q3"],
        ),
        (
            "short.csv",
            "point,q1,q2,q3,q4,q5,q6\nS1,0,0,0\n",
            &["short.csv:2", "q4"],
        ),
        (
            "text.csv",
            "point,q1,q2,q3,q4,q5,q6\nS1,0,0,0,0,zero,0\n",
            &["text.csv:2", "q5"],
        ),
        (
            "header.csv",
            "point,q1,q2,q3,q4,q6,q5\nS1,0,0,0,0,0,0\n",
            &["header.csv:1"],
        ),
    ];
    for (name, text, expect) in cases {
        let data = write(&dir, name, text);
        let o = aacmm(&["points", "--arm", arm, "--data", &data]);
        assert_clean_error(&o, expect);
    }
    let data = write(&dir, "ok.csv", POSES);
    let arms: &[(&str, &str, &[&str])] = &[
        (
            "unit.toml",
            "name = \"x\"\nlength_unit = \"inch\"\nangle_unit = \"deg\"\n",
            &["unit.toml:2", "length_unit"],
        ),
        (
            "missing.toml",
            "name = \"x\"\nlength_unit = \"mm\"\nangle_unit = \"deg\"\n[[joint]]\ntheta = 0.0\nalpha = 0.0\na = 1.0\n[probe]\nx = 0.0\ny = 0.0\nz = 0.0\n",
            &["missing.toml:4", "`d`"],
        ),
    ];
    for (name, text, expect) in arms {
        let bad = write(&dir, name, text);
        let o = aacmm(&["points", "--arm", &bad, "--data", &data]);
        assert_clean_error(&o, expect);
    }
    let o = aacmm(&[
        "points",
        "--arm",
        arm,
        "--data",
        &data,
        "--angle-unit",
        "grad",
    ]);
    assert_clean_error(&o, &["grad"]);
    let o = aacmm(&["points", "--arm", "/nonexistent/arm.toml", "--data", &data]);
    assert_clean_error(&o, &["/nonexistent/arm.toml"]);
}

/// `--uncertainty DIR`: a column `u95_mm` beside the same positions' bytes
/// — in the base from the geometry's covariance, with `--frame` in the
/// frame with the frame's registration (the library's
/// `position_covariances` of `frame_covariance`), and said so on stderr;
/// the directory of another arm's calibration is refused by parameter.
#[test]
fn uncertainty_is_written_in_the_base_and_in_a_frame_with_its_registration() {
    use aacmm_core::CalibrationReport;
    use aacmm_core::kernel::PreparedPoses;
    use aacmm_core::plan::{InFrame, position_covariances};
    use aacmm_core::stats::coverage::{eigenvalues, radius};
    let dir = temp_dir("points-uncertainty");
    let positions = example("ur5-tracker/positions-random.csv");
    let o = aacmm(&[
        "calibrate",
        "--arm",
        example("ur5-tracker/arm.toml").to_str().unwrap(),
        "--positions",
        positions.to_str().unwrap(),
        "--method",
        "lm",
        "--out",
        dir.join("cal").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", crate::util::stderr(&o));
    let text = std::fs::read_to_string(&positions).unwrap();
    let poses: String = (text.lines())
        .map(|l| l.split(',').take(7).collect::<Vec<_>>().join(",") + "\n")
        .collect();
    let data = write(&dir, "poses.csv", &poses);
    let cal = dir.join("cal");
    let arm = cal.join("calibrated.toml");
    let run = |extra: &[&str]| {
        let mut args = vec!["points", "--arm", arm.to_str().unwrap(), "--data", &data];
        args.extend_from_slice(extra);
        let o = aacmm(&args);
        assert!(o.status.success(), "{}", crate::util::stderr(&o));
        (stdout(&o), crate::util::stderr(&o))
    };
    let json = std::fs::read_to_string(cal.join("calibration.json")).unwrap();
    let c = CalibrationReport::from_json(&json).unwrap().calibration;
    let rows: Vec<Vec<f64>> = (text.lines().skip(1))
        .map(|l| {
            (l.split(',').skip(1).take(6))
                .map(|v| v.parse::<f64>().unwrap().to_radians())
                .collect()
        })
        .collect();
    let prepared = PreparedPoses::new(6, &rows).unwrap();
    let u = cal.to_str().unwrap();
    for frame in [None, Some("instrument")] {
        let mut extra = frame.map_or(vec![], |f| vec!["--frame", f]);
        let (plain, _) = run(&extra);
        extra.extend(["--uncertainty", u]);
        let (text, note) = run(&extra);
        let expected = match frame {
            None => {
                let (free, cov) = c.geometry_covariance().unwrap();
                position_covariances(&c.params, &prepared, &free, &cov, None).unwrap()
            }
            Some(name) => {
                let (free, x, cov) = c.frame_covariance(name).unwrap();
                let f = InFrame { name, x };
                position_covariances(&c.params, &prepared, &free, &cov, Some(&f)).unwrap()
            }
        };
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("point,x,y,z,u95_mm"));
        assert_eq!(expected.len(), 20);
        for ((line, before), (_, sigma)) in lines.zip(plain.lines().skip(1)).zip(&expected) {
            let (xyz, u95) = line.rsplit_once(',').unwrap();
            assert_eq!(xyz, before, "the positions' bytes");
            assert_eq!(u95, format!("{:.6}", radius(eigenvalues(*sigma))));
        }
        let says = note.contains("includes the registration of frame `instrument`");
        assert_eq!(says, frame.is_some(), "{note}");
    }
    // The frame's registration counted in changes the radii: here the
    // tracker sees the probe better than the base frame places it.
    let radii = |t: &str| -> Vec<f64> {
        (t.lines().skip(1))
            .map(|l| l.rsplit(',').next().unwrap().parse().unwrap())
            .collect()
    };
    let base = radii(&run(&["--uncertainty", u]).0);
    let framed = radii(&run(&["--frame", "instrument", "--uncertainty", u]).0);
    assert!(
        base.iter().zip(&framed).all(|(b, f)| f < b),
        "{base:?} vs {framed:?}"
    );
    let (posed, _) = run(&["--pose", "--uncertainty", u]);
    assert!(
        posed.starts_with("point,x,y,z,qw,qx,qy,qz,u95_mm\n"),
        "{posed}"
    );
    assert_eq!(radii(&posed), base);
    let nominal = example("ur5-tracker/arm.toml");
    let o = aacmm(&[
        "points",
        "--arm",
        nominal.to_str().unwrap(),
        "--data",
        &data,
        "--uncertainty",
        u,
    ]);
    assert_clean_error(
        &o,
        &[
            "is not this arm file's calibration",
            "differs from the arm file's",
        ],
    );
    // The frame moved by 1 mm in the arm file: not that calibration's.
    let toml = std::fs::read_to_string(&arm).unwrap();
    let moved: String = (toml.lines())
        .map(|l| match l.strip_prefix("translation_mm = [") {
            Some(rest) => {
                let (x, rest) = rest.split_once(',').unwrap();
                format!(
                    "translation_mm = [{},{rest}\n",
                    x.parse::<f64>().unwrap() + 1.0
                )
            }
            None => format!("{l}\n"),
        })
        .collect();
    let moved = write(&dir, "moved.toml", &moved);
    let args = ["--data", &data, "--frame", "instrument", "--uncertainty", u];
    let o = aacmm(&[&["points", "--arm", &moved][..], &args].concat());
    assert_clean_error(
        &o,
        &["--frame instrument:", "registration is not the one in"],
    );
}
