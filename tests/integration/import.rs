//! `aacmm import`: a URDF's chain as an arm file — exact against the URDF's
//! own transforms in position and orientation, through `export` and back
//! within 1 nm, the shipped MUKCa arm files byte for byte, and bad input
//! refused with its file, line and field.

use std::path::Path;

use aacmm_core::domain::Arm;
use aacmm_core::io::read_arm;
use aacmm_core::kernel::ArmKernel;
use aacmm_core::params::{JointKind, JointModel};
use aacmm_core::urdf::{Chain, UrdfOptions, parse_urdf};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::util::{aacmm, assert_clean_error, example, stderr, temp_dir, write};

const LIFT: &str = "urdf/mobile-manipulator.urdf";

/// Runs `aacmm import` with `args` and `--out out`; the arm it wrote.
fn import(args: &[&str], out: &Path) -> Arm {
    let mut all = vec!["import"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--out", out.to_str().unwrap(), "--force"]);
    let o = aacmm(&all);
    assert!(o.status.success(), "{}", stderr(&o));
    read_arm(out).unwrap().0
}

/// `aacmm import` of the shipped mobile manipulator from `base_footprint`
/// to `ball_link`, with `extra` flags; the arm it wrote to `out`.
fn import_lift(extra: &[&str], out: &Path) -> Arm {
    let urdf = example(LIFT);
    let mut args = vec![
        "--urdf",
        urdf.to_str().unwrap(),
        "--base",
        "base_footprint",
        "--tip",
        "ball_link",
    ];
    args.extend_from_slice(extra);
    import(&args, out)
}

/// Random readings in the URDF's units (rad; m for a slide) and the arm's
/// (rad; mm).
fn readings(kinds: &[JointKind], rng: &mut ChaCha8Rng) -> (Vec<f64>, Vec<f64>) {
    kinds
        .iter()
        .map(|k| match k {
            JointKind::Revolute => {
                let q = rng.random_range(-3.1..3.1);
                (q, q)
            }
            JointKind::Prismatic => {
                let q = rng.random_range(-0.4..0.4);
                (q, q * 1000.0)
            }
        })
        .unzip()
}

/// The largest difference of two rotation matrices (about the angle
/// between them, rad).
fn rotation_gap(a: &[[f64; 3]; 3], b: &nalgebra::UnitQuaternion<f64>) -> f64 {
    let m = b.to_rotation_matrix();
    (0..3)
        .flat_map(|r| (0..3).map(move |c| (r, c)))
        .map(|(r, c)| (a[r][c] - m[(r, c)]).abs())
        .fold(0.0, f64::max)
}

/// The imported mobile manipulator (a lift, a Hayati joint, parallel axes,
/// fixed joints, a tool offset) is the URDF's own forward kinematics: at
/// random readings the arm file's probe is the tip (plus the tool point)
/// within 1 nm, and its tool frame's orientation the tip link's within
/// 1e-9, up to the base frame and the tool rotation the converter reports.
#[test]
fn the_imported_arm_is_the_urdfs_kinematics_in_position_and_orientation() {
    let dir = temp_dir("import-pose");
    let urdf_path = example(LIFT);
    let tool = [4.0, -3.0, -25.0];
    let arm = import_lift(&["--tool", "4,-3,-25"], &dir.join("lift.toml"));
    let kinds: Vec<JointKind> = arm.params.joints.iter().map(|j| j.kind).collect();
    assert_eq!(kinds[0], JointKind::Prismatic);
    assert!(kinds[1..].iter().all(|k| *k == JointKind::Revolute));
    assert_eq!(arm.params.joints[3].model, JointModel::Hayati);
    assert_eq!(arm.limits[0], Some([0.0, 350.0]), "a slide's limits in mm");
    assert_eq!(arm.limits[6], None, "a continuous joint has none");
    assert_eq!(arm.physics.link_masses.len(), 8);
    // The URDF's own transforms, walked joint by joint.
    let text = std::fs::read_to_string(&urdf_path).unwrap();
    let urdf = parse_urdf(&text, "lift.urdf", UrdfOptions::default()).unwrap();
    let chain: Chain = urdf.chain(Some("base_footprint"), "ball_link").unwrap();
    let conversion = chain
        .clone()
        .with_tool(tool.map(|v| v / 1000.0))
        .to_dh()
        .unwrap();
    let kernel = ArmKernel::new(&arm.params).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(39);
    for _ in 0..500 {
        let (q_urdf, q_arm) = readings(&kinds, &mut rng);
        let tip = chain.transform(&q_urdf);
        let want = tip * nalgebra::Point3::from(nalgebra::Vector3::from(tool) / 1000.0);
        let pose = kernel.pose(&q_arm).unwrap();
        let p = nalgebra::Point3::from(nalgebra::Vector3::from(pose.position) / 1000.0);
        let got = conversion.base * p;
        let gap_mm = (got - want).norm() * 1000.0;
        assert!(gap_mm < 1e-6, "{gap_mm} mm at {q_urdf:?}");
        // The tool frame in the root: base · R(q) · tool is the tip link's.
        let tip_in_base =
            conversion.base.rotation.inverse() * tip.rotation * conversion.tool.inverse();
        let gap = rotation_gap(&pose.rotation, &tip_in_base);
        assert!(gap < 1e-9, "orientation off by {gap} at {q_urdf:?}");
    }
}

/// `import` → `export` → `import` of the mobile manipulator (prismatic,
/// fixed and continuous joints, parallel and nearly parallel axes): the
/// two arms' probes agree within 1 nm at random readings, and the kinds,
/// models, limits and masses come back.
#[test]
fn import_export_import_agrees_within_a_nanometre() {
    let dir = temp_dir("import-round-trip");
    let first = import_lift(&[], &dir.join("first.toml"));
    let exported = dir.join("exported.urdf");
    let o = aacmm(&[
        "export",
        "--arm",
        dir.join("first.toml").to_str().unwrap(),
        "--urdf",
        exported.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&exported).unwrap();
    assert!(text.contains("type=\"prismatic\""), "{text}");
    assert!(
        text.contains("<limit lower=\"0.0\" upper=\"0.35\""),
        "{text}"
    );
    assert!(text.contains("type=\"continuous\""), "{text}");
    let second = import(
        &[
            "--urdf",
            exported.to_str().unwrap(),
            "--base",
            "base_link",
            "--tip",
            "probe",
            "--snap-rad",
            "0",
        ],
        &dir.join("second.toml"),
    );
    let kinds = |a: &Arm| -> Vec<(JointKind, JointModel)> {
        a.params.joints.iter().map(|j| (j.kind, j.model)).collect()
    };
    assert_eq!(kinds(&first), kinds(&second));
    assert_eq!(first.limits.len(), second.limits.len());
    for (a, b) in first.limits.iter().zip(&second.limits) {
        match (a, b) {
            (Some(a), Some(b)) => assert!((0..2).all(|i| (a[i] - b[i]).abs() < 1e-9)),
            _ => assert_eq!(a, b),
        }
    }
    let (k1, k2) = (
        ArmKernel::new(&first.params).unwrap(),
        ArmKernel::new(&second.params).unwrap(),
    );
    let all: Vec<JointKind> = first.params.joints.iter().map(|j| j.kind).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut worst: f64 = 0.0;
    for _ in 0..1000 {
        let (_, q) = readings(&all, &mut rng);
        let (a, b) = (k1.position(&q).unwrap(), k2.position(&q).unwrap());
        worst = worst.max((0..3).map(|i| (a[i] - b[i]).abs()).fold(0.0, f64::max));
    }
    // 1 nm = 1e-6 mm.
    assert!(worst < 1e-6, "{worst} mm");
}

/// The shipped MUKCa arm files are what `aacmm import` writes, byte for
/// byte, up to their hand-written `[prior]` table.
#[test]
fn mukca_arm_files_are_what_import_writes() {
    let dir = temp_dir("import-mukca");
    let kinova = [
        "--base",
        "kinova_base_link",
        "--tip",
        "ball_link",
        "--no-limits",
        "--name",
        "kinova-gen3-lite (MUKCa gen3lite.urdf)",
    ];
    let panda = [
        "--base",
        "panda_link0",
        "--tip",
        "ball_link",
        "--name",
        "franka-panda (MUKCa panda.urdf, ball guessed)",
    ];
    for (arm, urdf, flags) in [
        ("kinova-1", "gen3lite.urdf", &kinova[..]),
        ("kinova-2", "gen3lite.urdf", &kinova[..]),
        ("panda-1", "panda.urdf", &panda[..]),
    ] {
        let out = dir.join(format!("{arm}.toml"));
        // Relative paths, as the files' headers name them.
        let urdf = format!("examples/mukca/urdf/{urdf}");
        let mut args = vec!["import", "--urdf", &urdf];
        args.extend_from_slice(flags);
        args.extend_from_slice(&["--out", out.to_str().unwrap()]);
        let o = crate::util::command(&args)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        let written = std::fs::read_to_string(&out).unwrap();
        let shipped = std::fs::read_to_string(example("mukca").join(arm).join("arm.toml")).unwrap();
        let (body, prior) = shipped
            .split_once("\n# Stated tolerances")
            .expect("a [prior] table after the conversion");
        assert_eq!(written, body, "{arm}");
        assert!(prior.contains("[prior]"), "{arm}");
    }
}

/// A chain that does not join `--base` to `--tip`, a floating or planar
/// joint on it, a slide along a zero axis, limits that are not numbers, a
/// tool that is not three numbers, an output that exists: each refused,
/// naming the file, line and field (or the flag).
#[test]
fn bad_input_is_refused_with_its_place() {
    let dir = temp_dir("import-bad");
    let lift = example(LIFT);
    let lift = lift.to_str().unwrap();
    let out = dir.join("arm.toml");
    let out = out.to_str().unwrap();
    let run = |urdf: &str, base: &str, tip: &str, extra: &[&str]| {
        let mut args = vec!["import", "--urdf", urdf, "--base", base, "--tip", tip];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", out]);
        aacmm(&args)
    };
    assert_clean_error(
        &run(lift, "shoulder_link", "torso_link", &[]),
        &[
            "mobile-manipulator.urdf:58: field `parent`: the chain does not connect base link \
             `shoulder_link` to tip link `torso_link`: going up from `torso_link` through joints \
             `torso_lift_joint`, `base_joint` ends at `base_footprint`",
        ],
    );
    assert_clean_error(
        &run(lift, "base_footprint", "hand", &[]),
        &["no link `hand` is joined to the robot (the tip must be a link's name)"],
    );
    assert_clean_error(
        &run(lift, "base_footprint", "ball_link", &["--tool", "1,2"]),
        &["--tool `1,2`: expected X,Y,Z"],
    );
    let text = std::fs::read_to_string(example(LIFT)).unwrap();
    for (kind, line) in [("floating", 62), ("planar", 62)] {
        let bad = text.replacen("type=\"prismatic\"", &format!("type=\"{kind}\""), 1);
        let path = write(&dir, &format!("{kind}.urdf"), &bad);
        assert_clean_error(
            &run(&path, "base_footprint", "ball_link", &[]),
            &[&format!(
                "{kind}.urdf:{line}: field `type`: joint `torso_lift_joint` on the way to \
                 `ball_link` is `{kind}`"
            )],
        );
    }
    let zero = text.replacen("<axis xyz=\"0 0 1\"/>", "<axis xyz=\"0 0 0\"/>", 1);
    let path = write(&dir, "zero.urdf", &zero);
    assert_clean_error(
        &run(&path, "base_footprint", "ball_link", &[]),
        &["zero.urdf:65: field `axis`: joint `torso_lift_joint` slides along a zero axis"],
    );
    let limits = text.replacen("upper=\"0.35\"", "upper=\"0.35m\"", 1);
    let path = write(&dir, "limits.urdf", &limits);
    assert_clean_error(
        &run(&path, "base_footprint", "ball_link", &[]),
        &["limits.urdf:66: field `upper`: joint `torso_lift_joint`: `0.35m` is not a limit"],
    );
    assert!(!Path::new(out).exists(), "nothing written on an error");
    // An output that exists is kept unless --force.
    std::fs::write(out, "keep").unwrap();
    assert_clean_error(
        &run(lift, "base_footprint", "ball_link", &[]),
        &["--out", "already exists; give --force to overwrite it"],
    );
    assert_eq!(std::fs::read_to_string(out).unwrap(), "keep");
}
