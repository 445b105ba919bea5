use super::messages::unsupported;
use super::*;
use crate::params::{DhJoint, DhParams, JointKind, JointModel};
use rand::{RngExt, SeedableRng};

const F: &str = "my-arm.toml";

const GOOD: &str = r#"name = "paper-table-1"
length_unit = "mm"
angle_unit = "deg"

[[joint]]
theta = 0.0
alpha = -90.0
a = 50.0
d = 375.0
limits = [-180.0, 180.0]

[[joint]]
theta = 0.5
beta = 90
a = -55.0
d = 0.0

[[joint]]
theta = 0.0
alpha = -90.0
a = 35.0
d = 250.0

[[joint]]
theta = 0.0
alpha = 90.0
a = -35.0
d = 0.0

[[joint]]
theta = 0.0
alpha = -90.0
a = 35.0
d = 270.0

[[joint]]
theta = 0.0
alpha = 90.0
a = -35.0
d = 0.0

[probe]
x = 0.0
y = 0.0
z = 100.0
"#;

fn err(text: &str) -> InputError {
    parse_arm(text, F).unwrap_err()
}

/// `GOOD` with `from` replaced by `to` (which must occur).
fn edit(from: &str, to: &str) -> String {
    assert!(GOOD.contains(from), "{from}");
    GOOD.replacen(from, to, 1)
}

#[track_caller]
fn assert_at(e: &InputError, line: usize, field: Option<&str>, needle: &str) {
    crate::io::testing::assert_at(e, F, line, field, needle);
}

#[test]
fn parses_good_file() {
    let (arm, warnings) = parse_arm(GOOD, F).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(arm.name, "paper-table-1");
    let j = &arm.params.joints;
    assert_eq!(j.len(), 6);
    assert_eq!(j[0].alpha, -std::f64::consts::FRAC_PI_2);
    assert_eq!((j[0].a, j[0].d, j[0].theta), (50.0, 375.0, 0.0));
    assert_eq!(j[1].alpha, std::f64::consts::FRAC_PI_2); // from `beta`, an integer
    assert_eq!(j[1].theta, 0.5f64.to_radians());
    assert_eq!(arm.params.probe, [0.0, 0.0, 100.0]);
    let pi = std::f64::consts::PI;
    assert_eq!(
        arm.limits,
        vec![Some([-pi, pi]), None, None, None, None, None]
    );
}

#[test]
fn units_convert() {
    let text = edit("length_unit = \"mm\"", "length_unit = \"m\"")
        .replace("angle_unit = \"deg\"", "angle_unit = \"rad\"");
    let (arm, _) = parse_arm(&text, F).unwrap();
    assert_eq!(arm.params.joints[0].d, 375_000.0);
    assert_eq!(arm.params.joints[0].alpha, -90.0);
    assert_eq!(arm.params.probe[2], 100_000.0);
    assert_eq!(arm.limits[0], Some([-180.0, 180.0]));
}

#[test]
fn name_is_optional() {
    let (arm, _) = parse_arm(&edit("name = \"paper-table-1\"\n", ""), F).unwrap();
    assert_eq!(arm.name, "");
    assert_at(
        &err(&edit("\"paper-table-1\"", "7")),
        1,
        Some("name"),
        "expected a string, found an integer",
    );
}

#[test]
fn syntax_errors_are_located() {
    assert_at(
        &err(&edit("d = 375.0", "d = 375.0.0")),
        9,
        None,
        "TOML syntax",
    );
    assert_at(
        &err(&edit("a = -55.0", "a = -55.0\na = 1")),
        16,
        None,
        "TOML syntax: duplicate key",
    );
    assert_at(
        &err(&edit("limits = [-180.0, 180.0]", "limits = [-180.0,")),
        13, // where the parser notices: arrays may span lines
        None,
        "TOML syntax",
    );
    assert_at(&err("x = \"unterminated\n"), 1, None, "TOML syntax");
}

#[test]
fn units_are_required_and_checked() {
    assert_at(
        &err(&edit("length_unit = \"mm\"\n", "")),
        0,
        Some("length_unit"),
        "missing; add `length_unit = \"mm\"` or `length_unit = \"m\"` (units are never guessed)",
    );
    assert_at(
        &err(&edit("angle_unit = \"deg\"\n", "")),
        0,
        Some("angle_unit"),
        "units are never guessed",
    );
    assert_at(
        &err(&edit("\"mm\"", "\"inch\"")),
        2,
        Some("length_unit"),
        "unknown length unit `inch`; accepted: `mm`, `m`",
    );
    assert_at(
        &err(&edit("\"deg\"", "\"degrees\"")),
        3,
        Some("angle_unit"),
        "unknown angle unit `degrees`; accepted: `deg`, `rad`",
    );
    assert_at(
        &err(&edit("\"deg\"", "1")),
        3,
        Some("angle_unit"),
        "expected a string",
    );
}

#[test]
fn unknown_keys_are_errors() {
    assert_at(
        &err(&edit("alpha", "alpah")),
        7,
        Some("alpah"),
        "unknown key in joint 1 (did you mean `alpha`?)",
    );
    assert_at(
        &err(&edit("theta = 0.5", "theta = 0.5\nbeta_err = 1")),
        14,
        Some("beta_err"),
        "unknown key in joint 2",
    );
    assert_at(
        &err(&edit("z = 100.0", "z = 100.0\nw = 1")),
        46,
        Some("w"),
        "unknown key in [probe]",
    );
    assert_at(
        &err(&format!("units = 1\n{GOOD}")),
        1,
        Some("units"),
        "unknown key at the top level",
    );
    assert_at(
        &err(&format!("{GOOD}[extra]\n")),
        46,
        Some("extra"),
        "unknown key at the top level",
    );
    // The first unknown key in file order is reported.
    assert_at(
        &err(&edit("a = 50.0", "zz = 1\na = 50.0\nbb = 2")),
        8,
        Some("zz"),
        "unknown key",
    );
}

#[test]
fn missing_joint_fields() {
    assert_at(
        &err(&edit("d = 375.0\n", "")),
        5,
        Some("d"),
        "joint 1: missing; every [[joint]] needs",
    );
    assert_at(
        &err(&edit("theta = 0.5\n", "")),
        12,
        Some("theta"),
        "joint 2: missing",
    );
    assert_at(
        &err(&edit("beta = 90\n", "")),
        12,
        Some("alpha"),
        "joint 2: missing",
    );
    assert_at(
        &err(&edit("a = -55.0\n", "")),
        12,
        Some("a"),
        "joint 2: missing",
    );
}

#[test]
fn alpha_and_beta_both() {
    assert_at(
        &err(&edit("alpha = -90.0", "alpha = -90.0\nbeta = -90.0")),
        8,
        Some("beta"),
        "both `alpha` and `beta`",
    );
}

#[test]
fn bad_values() {
    assert_at(
        &err(&edit("a = 50.0", "a = nan")),
        8,
        Some("a"),
        "joint 1: `nan` is not a finite number",
    );
    assert_at(
        &err(&edit("d = 375.0", "d = -inf")),
        9,
        Some("d"),
        "`-inf` is not a finite number",
    );
    assert_at(
        &err(&edit("d = 375.0", "d = 1e400")),
        9,
        Some("d"),
        "`1e400` is not a finite number",
    );
    assert_at(
        &err(&edit("a = 50.0", "a = \"50\"")),
        8,
        Some("a"),
        "expected a number, found a string",
    );
    assert_at(
        &err(&edit("z = 100.0", "z = true")),
        45,
        Some("z"),
        "[probe]: expected a number, found a boolean",
    );
    assert_at(
        &err(&edit("z = 100.0", "z = 99999999999999999999")),
        45,
        Some("z"),
        "[probe]: integer `99999999999999999999` out of range; write it as a float",
    );
    assert_at(
        &err(&edit("theta = 0.5", "theta = 1979-05-27")),
        13,
        Some("theta"),
        "joint 2: expected a number, found a datetime",
    );
    // Integers in other radixes are numbers.
    let (arm, _) = parse_arm(&edit("d = 375.0", "d = 0x10"), F).unwrap();
    assert_eq!(arm.params.joints[0].d, 16.0);
}

#[test]
fn limits() {
    assert_at(
        &err(&edit("[-180.0, 180.0]", "[180.0, -180.0]")),
        10,
        Some("limits"),
        "min 180 must be less than max -180",
    );
    assert_at(
        &err(&edit("[-180.0, 180.0]", "[10, 10]")),
        10,
        Some("limits"),
        "must be less than",
    );
    assert_at(
        &err(&edit("[-180.0, 180.0]", "[-180.0]")),
        10,
        Some("limits"),
        "expected `[min, max]` in deg, found 1 values",
    );
    assert_at(
        &err(&edit("[-180.0, 180.0]", "180.0")),
        10,
        Some("limits"),
        "expected `[min, max]` in deg, found a float",
    );
    assert_at(
        &err(&edit("[-180.0, 180.0]", "[-180.0, inf]")),
        10,
        Some("limits"),
        "not a finite number",
    );
    assert_at(
        &err(&edit("[-180.0, 180.0]", "[-180.0, \"x\"]")),
        10,
        Some("limits"),
        "expected a number",
    );
}

#[test]
fn joint_count() {
    let no_joints = "length_unit = \"mm\"\nangle_unit = \"deg\"\n[probe]\nx = 0\ny = 0\nz = 0\n";
    assert_at(&err(no_joints), 0, Some("joint"), "no joints");
    assert_at(
        &err(&format!("joint = []\n{no_joints}")),
        1,
        Some("joint"),
        "no joints",
    );
    assert_at(
        &err(&format!("{no_joints}[joint]\na = 1\n")),
        7,
        Some("joint"),
        "expected [[joint]] tables",
    );
    assert_at(
        &err(&format!("joint = [1]\n{no_joints}")),
        1,
        Some("joint"),
        "joint 1: expected a table, found an integer",
    );
    let joint = "[[joint]]\ntheta = 0\nalpha = 0\na = 0\nd = 1\n";
    let twelve = format!("{no_joints}{}", joint.repeat(12));
    assert_eq!(parse_arm(&twelve, F).unwrap().0.params.joint_count(), 12);
    let thirteen = format!("{twelve}{joint}");
    // The thirteenth [[joint]] header is on line 6 + 12 * 5 + 1.
    assert_at(
        &err(&thirteen),
        67,
        Some("joint"),
        "13 joints; at most 12 are supported",
    );
}

#[test]
fn every_joint_count_of_a_chain_is_read() {
    // Five joints and one: chains the kernel computes (they used to be
    // refused, with 6 and 7 the only counts).
    let five = edit(
        "\n[[joint]]\ntheta = 0.0\nalpha = 90.0\na = -35.0\nd = 0.0\n\n[probe]",
        "\n[probe]",
    );
    assert_eq!(parse_arm(&five, F).unwrap().0.params.joint_count(), 5);
    let one = "length_unit = \"mm\"\nangle_unit = \"deg\"\n[[joint]]\ntheta = 0\nalpha = 0\n\
                   a = 0\nd = 1\n[probe]\nx = 0\ny = 0\nz = 0\n";
    assert_eq!(parse_arm(one, F).unwrap().0.params.joint_count(), 1);
    assert_eq!(
        unsupported(13),
        "13 joints; at most 12 are supported (the toolkit computes chains of 1 to 12 joints)"
    );
}

#[test]
fn implausible_units_warn() {
    // Millimetre values declared as metres: |d| = 375 m.
    let text = edit("length_unit = \"mm\"", "length_unit = \"m\"");
    let (_, w) = parse_arm(&text, F).unwrap();
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!((w[0].line, w[0].field.as_deref()), (Some(8), Some("a")));
    assert!(
        w[0].to_string()
            .starts_with("my-arm.toml:8: field `a`: lengths declared in metres"),
        "{}",
        w[0]
    );
    assert!(w[0].message.contains("look like millimetres"), "{}", w[0]);
    // Degree values declared as radians: |alpha| = 90.
    let text = edit("angle_unit = \"deg\"", "angle_unit = \"rad\"");
    let (_, w) = parse_arm(&text, F).unwrap();
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!((w[0].line, w[0].field.as_deref()), (Some(7), Some("alpha")));
    assert!(w[0].message.contains("look like degrees"), "{}", w[0]);
    // Plausible values in m and rad: no warning; the probe counts as a length.
    let arm = Arm::without_limits("n", DhParams::paper_nominal());
    let text = arm_to_toml(&arm, LengthUnit::M, AngleUnit::Rad);
    assert_eq!(parse_arm(&text, F).unwrap().1, vec![]);
    let far = text.replace("z = 0.1\n", "z = -12.5\n");
    let (_, w) = parse_arm(&far, F).unwrap();
    assert_eq!(w[0].field.as_deref(), Some("z"), "{w:?}");
    assert!(w[0].message.contains("|-12.5| m"), "{}", w[0]);
}

#[test]
fn probe_required() {
    let text = GOOD[..GOOD.find("[probe]").unwrap()].to_string();
    assert_at(&err(&text), 0, Some("probe"), "missing [probe] table");
    assert_at(
        &err(&edit("y = 0.0\n", "")),
        42,
        Some("y"),
        "[probe]: missing",
    );
    assert_at(
        &err(&format!("probe = 3\n{text}")),
        1,
        Some("probe"),
        "expected a table",
    );
    // Other TOML spellings of the same table are fine.
    let (arm, _) = parse_arm(&format!("probe = {{ x = 1, y = 2, z = 3 }}\n{text}"), F).unwrap();
    assert_eq!(arm.params.probe, [1.0, 2.0, 3.0]);
}

#[test]
fn write_is_deterministic_and_round_trips_bits() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    for n in [1, 5, 6, 7, 12] {
        // Every third joint Hayati: its β round-trips too.
        let joints = (0..n)
            .map(|i| {
                let j = DhJoint {
                    a: rng.random_range(-100.0..100.0),
                    d: rng.random_range(-400.0..400.0),
                    alpha: rng.random_range(-3.2..3.2),
                    theta: rng.random_range(-0.1..0.1),
                    ..DhJoint::default()
                };
                let j = if i % 3 == 1 {
                    DhJoint::hayati(j.a, j.alpha, j.theta, rng.random_range(-0.1..0.1))
                } else {
                    j
                };
                // Every fourth joint slides (some of them Hayati too).
                if i % 4 == 1 {
                    j.with_kind(JointKind::Prismatic)
                } else {
                    j
                }
            })
            .collect();
        let limits = (0..n)
            .map(|i| {
                (i % 2 == 0 || i % 4 == 1).then(|| {
                    let scale = if i % 4 == 1 { 300.0 } else { 1.0 };
                    [-3.0, 1.0].map(|x| scale * rng.random_range(x..x + 2.0))
                })
            })
            .collect();
        let arm = Arm {
            name: "quote \" backslash \\ tab\t nl\n ctl\u{1} é".to_string(),
            params: DhParams {
                joints,
                probe: [rng.random(), rng.random(), 1e-12],
            },
            limits,
            prior: None,
            physics: Box::default(),
            ball_diameter_mm: None,
            tools: Vec::new(),
        };
        let text = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Rad);
        let (back, _) = parse_arm(&text, F).unwrap();
        assert_eq!(back.name, arm.name);
        assert_eq!(back.limits, arm.limits);
        let bits = |a: &Arm| {
            a.params
                .to_vec()
                .iter()
                .map(|x| x.to_bits())
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&back), bits(&arm));
        assert_eq!(back.params, arm.params);
        assert_eq!(arm_to_toml(&back, LengthUnit::Mm, AngleUnit::Rad), text);
        // Through deg and m: within 1 ulp.
        let (back, _) = parse_arm(&arm_to_toml(&arm, LengthUnit::M, AngleUnit::Deg), F).unwrap();
        for (x, y) in back.params.to_vec().iter().zip(arm.params.to_vec()) {
            assert!((x - y).abs() <= y.abs() * f64::EPSILON, "{x} {y}");
        }
        let kinds = |a: &Arm| a.params.joints.iter().map(|j| j.kind).collect::<Vec<_>>();
        assert_eq!(kinds(&back), kinds(&arm));
        // A slide's limits go through metres, a turn's through degrees.
        for (x, y) in back
            .limits
            .iter()
            .flatten()
            .zip(arm.limits.iter().flatten())
        {
            for (x, y) in x.iter().zip(y) {
                assert!((x - y).abs() <= 2.0 * y.abs() * f64::EPSILON, "{x} {y}");
            }
        }
    }
}

#[test]
fn a_prismatic_joint_reads_its_limits_as_lengths() {
    let text = edit(
        "theta = 0.5\nbeta = 90\na = -55.0\nd = 0.0\n",
        "type = \"prismatic\"\ntheta = 0.5\nbeta = 90\na = -55.0\nd = 0.0\n\
             limits = [-200, 650]\n",
    );
    let (arm, _) = parse_arm(&text, F).unwrap();
    let j = &arm.params.joints;
    assert_eq!(j[1].kind, JointKind::Prismatic);
    assert!(
        j.iter()
            .enumerate()
            .all(|(i, j)| i == 1 || j.kind == JointKind::Revolute)
    );
    assert_eq!(arm.limits[1], Some([-200.0, 650.0]));
    let written = arm_to_toml(&arm, LengthUnit::M, AngleUnit::Deg);
    assert!(written.contains("type = \"prismatic\""), "{written}");
    assert!(written.contains("limits = [-0.2, 0.65]"), "{written}");
    // Revolute joints are written as before: no `type` key.
    assert_eq!(written.matches("type =").count(), 1, "{written}");
    let bad = text.replace("\"prismatic\"", "\"sliding\"");
    assert_at(
        &err(&bad),
        13,
        Some("type"),
        "joint 2: unknown type `sliding`; expected \"revolute\"",
    );
}

/// A joint's `backlash` is in angle_unit (a slide's in length_unit),
/// kept on writing; it needs a mass to press a flank (refused at its
/// line without); a fit's negative value reads back.
#[test]
fn a_backlash_reads_writes_and_needs_masses() {
    let joint2 = "theta = 0.5\nbeta = 90\na = -55.0\nd = 0.0\n";
    let text = edit(joint2, &format!("{joint2}backlash = 0.02\nmass_kg = 3.0\n"));
    let (arm, _) = parse_arm(&text, F).unwrap();
    assert_eq!(arm.physics.backlash.len(), 6);
    assert!((arm.physics.backlash_of(1) - 0.02f64.to_radians()).abs() < 1e-18);
    assert_eq!(arm.physics.backlash_of(0), 0.0);
    let written = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg);
    assert!(written.contains("backlash = 0.02"), "{written}");
    let back = parse_arm(&written, F).unwrap().0;
    assert_eq!(back.physics.backlash, arm.physics.backlash);
    // A slide's play is a length.
    let slide = text.replacen("theta = 0.5", "type = \"prismatic\"\ntheta = 0.5", 1);
    let (arm, _) = parse_arm(&slide.replacen("backlash = 0.02", "backlash = 0.05", 1), F).unwrap();
    assert_eq!(arm.physics.backlash_of(1), 0.05);
    let no_mass = edit(joint2, &format!("{joint2}backlash = 0.02\n"));
    assert_at(
        &err(&no_mass),
        17,
        Some("backlash"),
        "joint 2: a backlash needs masses",
    );
    let negative = text.replacen("backlash = 0.02", "backlash = -0.02", 1);
    let arm = parse_arm(&negative, F).unwrap().0;
    assert!((arm.physics.backlash_of(1) + 0.02f64.to_radians()).abs() < 1e-18);
    // A slide's limits and play in metres, written back in metres and
    // radians: lengths both ways, never angles.
    let limited = slide.replacen("d = 0.0\n", "d = 0.0\nlimits = [0.0, 1500.0]\n", 1);
    let (arm, _) = parse_arm(&limited, F).unwrap();
    assert_eq!(arm.limits[1], Some([0.0, 1500.0]));
    let metres = arm_to_toml(&arm, LengthUnit::M, AngleUnit::Rad);
    assert!(metres.contains("limits = [0.0, 1.5]"), "{metres}");
    assert!(metres.contains("backlash = 0.00002"), "{metres}");
    let back = parse_arm(&metres, F).unwrap().0;
    assert_eq!(back.limits[1], arm.limits[1]);
    assert_eq!(back.physics.backlash_of(1), 0.02);
}

/// `GOOD` with joint 2 (α = 90°) written as a Hayati joint.
fn hayati_text() -> String {
    edit(
        "theta = 0.5\nbeta = 90\na = -55.0\nd = 0.0\n",
        "model = \"hayati\"\ntheta = 0.5\nalpha = 90\na = -55.0\nhbeta = 0.25\n",
    )
}

#[test]
fn hayati_joints_read_and_write_back() {
    let (arm, _) = parse_arm(&hayati_text(), F).unwrap();
    let j = arm.params.joints[1];
    assert_eq!(j.model, JointModel::Hayati);
    assert_eq!((j.beta, j.d), (0.25f64.to_radians(), 0.0));
    assert_eq!(arm.params.joints[0].model, JointModel::Dh);
    let text = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg);
    assert!(
        text.contains("model = \"hayati\"\ntheta = 0.5\nalpha = 90.0\na = -55.0\nhbeta = 0.25\n"),
        "{text}"
    );
    assert_eq!(
        text.matches("model").count(),
        1,
        "D-H joints write no model"
    );
    assert_eq!(parse_arm(&text, F).unwrap().0, arm);
    // `model = "dh"` is the default, spelled out.
    let dh = edit("theta = 0.5\n", "model = \"dh\"\ntheta = 0.5\n");
    assert_eq!(parse_arm(&dh, F).unwrap().0, parse_arm(GOOD, F).unwrap().0);
}

#[test]
fn hayati_mistakes_are_located() {
    let h = hayati_text();
    let bad = |from: &str, to: &str| {
        assert!(h.contains(from), "{from}");
        err(&h.replacen(from, to, 1))
    };
    assert_at(
        &bad("model = \"hayati\"", "model = \"hayat\""),
        13,
        Some("model"),
        "joint 2: unknown model `hayat`; expected \"dh\" or \"hayati\"",
    );
    assert_at(
        &bad("hbeta = 0.25\n", "hbeta = 0.25\nd = 1.0\n"),
        18,
        Some("d"),
        "joint 2: a Hayati joint (model = \"hayati\") has no `d`",
    );
    assert_at(
        &bad("hbeta = 0.25\n", ""),
        12,
        Some("hbeta"),
        "joint 2: missing; a Hayati joint",
    );
    assert_at(
        &bad("model = \"hayati\"\n", ""),
        12,
        Some("d"),
        "joint 2: missing; every [[joint]] needs",
    );
    assert_at(
        &err(&edit("d = 375.0\n", "d = 375.0\nhbeta = 1.0\n")),
        10,
        Some("hbeta"),
        "joint 1: `hbeta` is the Hayati rotation: it needs `model = \"hayati\"`",
    );
    assert_at(
        &bad("hbeta = 0.25", "hbeta = inf"),
        17,
        Some("hbeta"),
        "joint 2: `inf` is not a finite number",
    );
}

#[test]
fn user_file_round_trips_in_its_units() {
    let (arm, _) = parse_arm(GOOD, F).unwrap();
    let text = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg);
    // The user's numbers come back as written (integers as floats, `beta` as `alpha`).
    let expected = GOOD.replace("beta = 90", "alpha = 90.0");
    assert_eq!(text, expected);
    assert_eq!(parse_arm(&text, F).unwrap().0, arm);
}

#[test]
fn nominal_in_metres() {
    let arm = Arm::without_limits("nominal", DhParams::paper_nominal());
    let text = arm_to_toml(&arm, LengthUnit::M, AngleUnit::Deg);
    assert!(text.contains("a = 0.05\nd = 0.375\n"), "{text}");
    assert!(text.contains("z = 0.1\n"), "{text}");
    assert_eq!(parse_arm(&text, F).unwrap(), (arm, vec![]));
}

#[test]
fn non_finite_written_as_toml_and_rejected() {
    let mut arm = Arm::without_limits("x", DhParams::paper_nominal());
    arm.params.joints[2].a = f64::NAN;
    arm.params.probe[0] = f64::NEG_INFINITY;
    let text = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg);
    assert!(
        text.contains("a = nan\n") && text.contains("x = -inf\n"),
        "{text}"
    );
    let e = parse_arm(&text, F).unwrap_err();
    assert_eq!(e.field_name(), Some("a"));
    assert!(
        e.to_string()
            .contains("joint 3: `nan` is not a finite number"),
        "{e}"
    );
}

#[test]
fn files_on_disk() {
    let dir = std::env::temp_dir().join(format!("aacmm-io-arm-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("arm.toml");
    let arm = Arm::without_limits("nominal", DhParams::paper_nominal());
    write_arm(&path, &arm, LengthUnit::Mm, AngleUnit::Deg).unwrap();
    assert_eq!(read_arm(&path).unwrap(), (arm.clone(), vec![]));
    std::fs::write(
        &path,
        "length_unit = \"mm\"\nangle_unit = \"deg\"\n[[joint]]\nalpah = 1\n",
    )
    .unwrap();
    let e = read_arm(&path).unwrap_err();
    assert!(
        e.to_string()
            .starts_with(&format!("{}:4: field `alpah`", path.display())),
        "{e}"
    );
    let e = read_arm(&dir.join("nope.toml")).unwrap_err();
    assert!(matches!(e, InputError::Io { .. }), "{e}");
    let e = write_arm(
        &dir.join("no/such/dir.toml"),
        &arm,
        LengthUnit::Mm,
        AngleUnit::Deg,
    )
    .unwrap_err();
    assert!(e.to_string().contains("no/such/dir.toml"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `[probe] ball_diameter_mm`: read in mm whatever `length_unit` says,
/// written back only when stated (a file without it reads and writes as
/// before), and refused by line and field when it cannot be a ball's.
#[test]
fn the_probe_ball_diameter_round_trips_and_is_checked() {
    let (plain, _) = parse_arm(GOOD, F).unwrap();
    assert_eq!(plain.ball_diameter_mm, None);
    assert!(!arm_to_toml(&plain, LengthUnit::Mm, AngleUnit::Deg).contains("ball"));
    let with = |v: &str| GOOD.replace("[probe]\n", &format!("[probe]\nball_diameter_mm = {v}\n"));
    let (arm, _) = parse_arm(&with("6.0"), F).unwrap();
    assert_eq!(arm.ball_diameter_mm, Some(6.0));
    // In a file in metres the field is still mm.
    let metres = with("6.0").replace("length_unit = \"mm\"", "length_unit = \"m\"");
    assert_eq!(parse_arm(&metres, F).unwrap().0.ball_diameter_mm, Some(6.0));
    for unit in [LengthUnit::Mm, LengthUnit::M] {
        let text = arm_to_toml(&arm, unit, AngleUnit::Deg);
        assert!(text.contains("ball_diameter_mm = 6.0"), "{text}");
        assert_eq!(parse_arm(&text, F).unwrap().0.ball_diameter_mm, Some(6.0));
    }
    let line = GOOD[..GOOD.find("[probe]").unwrap()].lines().count() + 2;
    for (v, why) in [
        ("0.006", "in metres?"),
        ("0", "positive"),
        ("-2", "positive"),
        ("150", "more than any probe"),
    ] {
        let e = parse_arm(&with(v), F).unwrap_err();
        assert_at(&e, line, Some("ball_diameter_mm"), why);
    }
    let e = parse_arm(&with("nan"), F).unwrap_err();
    assert_at(&e, line, Some("ball_diameter_mm"), "not a finite number");
}

#[test]
fn a_harmonic_of_no_whole_order_is_refused_in_one_line() {
    let text = edit(
        "a = 35.0\nd = 250.0\n",
        "a = 35.0\nd = 250.0\nharmonics = [[1.5, 0.01, 0.0]]\n",
    );
    let e = err(&text).to_string();
    let max = crate::corrections::MAX_HARMONIC_ORDER;
    let want = format!(
        "field `harmonics`: joint 3: expected [order, sin, cos] with a whole order from 1 to {max} \
         and amplitudes in deg"
    );
    assert!(e.ends_with(&want), "{e}");
}
