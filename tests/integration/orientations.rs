//! Tool poses: simulated 6-D campaigns (a tracker's 6-D target: position
//! and orientation per row) recovered honestly, and compared with the same
//! poses' positions alone.

use aacmm_core::calibrate::validate::{orientation_errors, position_errors};
use aacmm_core::domain::Arm;
use aacmm_core::residuals::{Frame, MOUNT_BLOCK, Noise};
use aacmm_core::simulate::{
    OrientationSettings, orient_positions, random_arm, random_mount, simulate_positions_from,
};
use aacmm_core::{DataSet, ModelOptions, Problem};

use super::positions::{campaign, lm, normalised_errors, settings, tracker};

/// σ per axis of the simulated orientations: a tracker's 6-D target.
const ORIENTATION_DEG: f64 = 0.01;

fn oriented() -> Noise {
    Noise {
        orientation_rad: Some(ORIENTATION_DEG.to_radians()),
        ..tracker()
    }
}

/// The shipped UR5 (6 joints).
fn ur5() -> Arm {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/ur5-tracker/arm.toml");
    let mut arm = aacmm_core::read_arm(std::path::Path::new(path)).unwrap().0;
    arm.prior = None;
    arm
}

/// An 8-joint arm on a linear track (a slide, then seven turns).
fn track_arm() -> Arm {
    let mut arm = random_arm("PRRRRRRR".parse().unwrap(), 11);
    arm.prior = None;
    arm
}

/// What one seed's fits show.
struct Seed {
    /// `((estimate − truth)/σ)²` of the 6-D fit's free parameters and
    /// frame columns.
    z2: Vec<f64>,
    /// Held-out mean 3-D error, mm: the 6-D fit's, the positions-only fit's.
    position: [f64; 2],
    /// Held-out mean orientation error, degrees: the 6-D fit's, the true
    /// arm's.
    orientation: [f64; 2],
}

/// The true arm of `seed` about `nominal`, its campaign of `poses` poses
/// with orientations, fitted twice — with the orientation rows and with
/// the positions alone — and both judged on 30 new poses from the same
/// station.
fn one_seed(nominal: &Arm, seed: u64, poses: usize) -> Seed {
    let (truth, c) = campaign(nominal, seed, poses, 1);
    // A target mounted any way on the flange (as `simulate --orientation`
    // draws it by default).
    let mount = random_mount(std::f64::consts::PI, seed + 3000);
    let turn = |seed| OrientationSettings {
        mount,
        sigma_rad: ORIENTATION_DEG.to_radians(),
        seed,
    };
    let with = orient_positions(&truth, &c.positions, &c.frames, &turn(seed + 2000)).unwrap();
    let fit = |rows, noise: Noise| {
        let data = DataSet::from_positions(rows, "sim.csv").unwrap();
        let model = ModelOptions {
            noise,
            ..ModelOptions::default()
        };
        let report = Problem::new(nominal.clone(), data, model)
            .unwrap()
            .run(&lm())
            .unwrap();
        let what = format!("{}, seed {seed}", nominal.name);
        assert!(report.is_usable(), "{what}: {:?}", report.verdict);
        report.calibration
    };
    let six = fit(with, oriented());
    let three = fit(c.positions.clone(), tracker());
    let fresh = simulate_positions_from(&truth, &settings(30, 0, seed + 5000), &c.frames).unwrap();
    let fresh = orient_positions(&truth, &fresh, &c.frames, &turn(seed + 6000)).unwrap();
    let held = DataSet::from_positions(fresh, "held.csv").unwrap();
    let held = held.positions().unwrap();
    let mean = |cal: &aacmm_core::Calibration| {
        position_errors(&cal.params, held, &cal.frames())
            .unwrap()
            .mean
    };
    let turned = |params, frames: &[(String, [f64; 6])]| {
        let e = orientation_errors(params, held, frames).unwrap();
        e.expect("orientations held out").mean
    };
    let mut z2 = normalised_errors(&six, &truth, &c);
    z2.extend(mount_errors(&six, &truth, mount));
    let mut true_frames = c.frames.clone();
    true_frames.push((
        MOUNT_BLOCK.into(),
        [mount[0], mount[1], mount[2], 0.0, 0.0, 0.0],
    ));
    Seed {
        z2,
        position: [mean(&six), mean(&three)],
        orientation: [
            turned(&six.params, &six.frames_with_mount()),
            turned(&truth.params, &true_frames),
        ],
    }
}

/// The mount a fit of arm `fitted` should find for a target mounted as
/// `mount` (rotation vector, rad) on the arm `truth`: the true mount seen
/// from the fitted last frame, `Rx(−α_f) Rz(θ_t − θ_f) Rx(α_t) R_m` (last
/// joint, D-H) — the fitted mount absorbs any constant turn of the last
/// frame, so with the last `alpha`, `theta` held at nominal it is not the
/// true mount but this one.
pub(super) fn equivalent_mount(
    truth: &aacmm_core::DhParams,
    fitted: &aacmm_core::DhParams,
    mount: [f64; 3],
) -> nalgebra::Rotation3<f64> {
    use nalgebra::{Rotation3, Vector3};
    let (t, f) = (truth.joints.last().unwrap(), fitted.joints.last().unwrap());
    let x = |a: f64| Rotation3::from_axis_angle(&Vector3::x_axis(), a);
    let z = Rotation3::from_axis_angle(&Vector3::z_axis(), t.theta - f.theta);
    x(-f.alpha) * z * x(t.alpha) * Frame::rotation(&mount)
}

/// `((estimate − truth)/σ)²` of the fitted mount's three small rotations
/// (its σ are of small rotations about the last frame's axes: the
/// difference is taken as one, `log(R_est R_trueᵀ)`), the truth seen from
/// the fitted last frame ([`equivalent_mount`]).
fn mount_errors(cal: &aacmm_core::Calibration, truth: &Arm, mount: [f64; 3]) -> Vec<f64> {
    let est = cal.mount().expect("a fitted mount").map(f64::to_radians);
    let m = equivalent_mount(&truth.params, &cal.params, mount).scaled_axis();
    let d = Frame::difference(
        &[m[0], m[1], m[2], 0.0, 0.0, 0.0],
        &[est[0], est[1], est[2], 0.0, 0.0, 0.0],
    );
    let record = cal.mount_record().unwrap();
    let sigma = record.small_rotation_sigma_deg.expect("the mount's σ");
    (0..3)
        .map(|k| (d[k] / sigma[k].to_radians()).powi(2))
        .collect()
}

/// Over `seeds`, for the UR5 and the 8-joint track arm: the normalised
/// error RMS of the 6-D fits in 0.8–1.25, their held-out 3-D error no
/// worse than the positions-only fits' on the same poses (mean over the
/// seeds), their held-out orientation error within 5 % of the true arm's.
fn six_d_campaigns_recover_the_truth(seeds: std::ops::Range<u64>, poses: usize) {
    for nominal in [ur5(), track_arm()] {
        let runs: Vec<Seed> = seeds
            .clone()
            .map(|s| one_seed(&nominal, s, poses))
            .collect();
        let z2: Vec<f64> = runs.iter().flat_map(|r| r.z2.iter().copied()).collect();
        let rms = (z2.iter().sum::<f64>() / z2.len() as f64).sqrt();
        let n = runs.len() as f64;
        let position = runs
            .iter()
            .map(|r| r.position[0] / r.position[1])
            .sum::<f64>()
            / n;
        let turned = runs
            .iter()
            .map(|r| r.orientation[0] / r.orientation[1])
            .sum::<f64>()
            / n;
        eprintln!(
            "{}: {} seeds, normalised RMS {rms:.3} over {} estimates; held-out 3-D error \
             {position:.4} × the positions-only fit's, orientation error {turned:.4} × the \
             true arm's",
            nominal.name,
            runs.len(),
            z2.len()
        );
        assert!(
            (0.8..=1.25).contains(&rms),
            "{}: normalised RMS {rms}",
            nominal.name
        );
        assert!(
            position <= 1.0,
            "{}: held-out 3-D error {position} × positions-only",
            nominal.name
        );
        assert!(
            turned <= 1.05,
            "{}: held-out orientation error {turned} × the truth's",
            nominal.name
        );
    }
}

/// A few seeds on every run (debug build: seconds).
#[test]
fn simulated_six_d_campaigns_recover_the_truth() {
    six_d_campaigns_recover_the_truth(0..3, 60);
}

/// 50 seeds each: `cargo test --release --test integration orientations
/// -- --ignored`.
#[test]
#[ignore = "50 seeds: run with --release -- --ignored"]
fn fifty_simulated_six_d_campaigns_recover_the_truth() {
    six_d_campaigns_recover_the_truth(0..50, 200);
}

/// `simulate --positions N --orientation` writes the `qw,qx,qy,qz`
/// columns; `calibrate` refuses them without their σ (naming the file,
/// line and fields, and the flag), and with `--orientation-noise` fits
/// them consistently with the stated noise, states that noise, and shows
/// the orientation errors before and after beside the 3-D errors (summary
/// and `calibration.json`). A file without orientations says nothing of
/// them.
#[test]
fn simulate_orientations_then_calibrate() {
    use crate::util::{aacmm, shipped_arm, stderr, stdout, temp_dir};
    let dir = temp_dir("simulate-orientations");
    let d = dir.to_str().unwrap();
    let arm = shipped_arm();
    let o = aacmm(&[
        "simulate",
        "--arm",
        &arm,
        "--errors",
        "random",
        "--positions",
        "60",
        "--frames",
        "2",
        "--orientation",
        "--seed",
        "4",
        "--out",
        d,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let positions = dir.join("positions.csv");
    let text = std::fs::read_to_string(&positions).unwrap();
    assert!(
        text.starts_with("point,q1,q2,q3,q4,q5,q6,x,y,z,qw,qx,qy,qz,frame\n"),
        "{text}"
    );
    let p = positions.to_str().unwrap();
    let calibrate = |positions: &str, extra: &[&str], out: &str| {
        let out = dir.join(out);
        let mut args = vec!["calibrate", "--arm", &arm, "--positions", positions];
        args.extend(["--position-noise", "0.015+0.006/m"]);
        args.extend(extra);
        args.extend(["--out", out.to_str().unwrap()]);
        (aacmm(&args), out)
    };
    let (o, _) = calibrate(p, &[], "refused");
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("positions.csv:2: fields `qw,qx,qy,qz`"), "{e}");
    assert!(e.contains("--orientation-noise"), "{e}");
    let (o, out) = calibrate(p, &["--orientation-noise", "0.01"], "out");
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("consistent with the stated noise"), "{text}");
    assert!(
        text.contains("Orientation noise: stated: σ = 0.01° per axis"),
        "{text}"
    );
    assert!(text.contains("orientations 360 rows"), "{text}");
    let table = text
        .split("Tool orientations (deg)")
        .nth(1)
        .expect("the table");
    let figure = |row: &str| -> f64 {
        let line = table
            .lines()
            .find(|l| l.trim_start().starts_with(row))
            .unwrap();
        line.split_whitespace().nth(4).unwrap().parse().unwrap()
    };
    let (before, after) = (figure("fitted, before"), figure("fitted, after"));
    // The RMS: a random true arm's tool turned by tenths of a degree, the
    // fitted one's within a few times the 0.01° of the noise.
    assert!(before > 0.1 && after < 0.03, "{before} → {after}\n{text}");
    let json = std::fs::read_to_string(out.join("calibration.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&json).unwrap();
    let after = &json["validation"]["fitted"]["after"]["orientations"];
    assert_eq!(after["count"], 120);
    assert!(after["rms"].as_f64().unwrap() < 0.03, "{after}");
    // The page: the noise among the inputs, and a table of the orientation
    // errors beside the 3-D errors' — per frame (two here), each cell
    // marked with its place in calibration.json.
    let page = text_of(&out.join("report.html"));
    assert!(page.contains("orientation noise"), "no noise line");
    let table = page
        .split("Tool orientation errors at the reference positions (deg)")
        .nth(1)
        .expect("the orientation table");
    let table = table.split("</table>").next().unwrap();
    for row in [
        "fitted, nominal",
        "fitted, calibrated",
        "station1",
        "station2",
    ] {
        assert!(table.contains(row), "{row}: {table}");
    }
    assert!(
        table.contains("/validation/fitted/after/orientations"),
        "{table}"
    );
    // Without orientations (the columns dropped): no word of them.
    let plain: String = (text_of(&positions).lines())
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            [&f[..10], &f[14..]].concat().join(",") + "\n"
        })
        .collect();
    let plain_path = dir.join("plain.csv");
    std::fs::write(&plain_path, plain).unwrap();
    let (o, _) = calibrate(plain_path.to_str().unwrap(), &[], "plain");
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    for word in ["Orientation noise", "Tool orientations", "orientations "] {
        assert!(!text.contains(word), "{word}: {text}");
    }
    let page = text_of(&dir.join("plain").join("report.html"));
    assert!(!page.contains("Tool orientation errors"));
}

fn text_of(path: &std::path::Path) -> String {
    std::fs::read_to_string(path).unwrap()
}

/// A 6-D campaign simulated with a target mounted turned on the flange:
/// the fitted mount (`[mount]` of calibrated.toml) is the true one
/// (true_arm.toml) seen from the fitted last frame within 5σ; `evaluate
/// --positions` scores the orientations with it (or, from the nominal arm
/// file, a closed-form mount, said so); an orientation displaced by 0.5° is named
/// by `file:line` as an orientation, not a position; an orientation noise
/// stated ten times too small is refused with the advice to scale
/// `--orientation-noise`, not only `--position-noise`.
#[test]
fn the_mount_is_fitted_and_orientation_outliers_are_named_so() {
    use crate::util::{aacmm, shipped_arm, stderr, stdout, temp_dir};
    use aacmm_core::io::frames::parse_mount;
    let dir = temp_dir("orientation-outliers");
    let d = dir.to_str().unwrap();
    let arm = shipped_arm();
    let o = aacmm(&[
        "simulate",
        "--arm",
        &arm,
        "--errors",
        "random",
        "--positions",
        "40",
        "--orientation",
        "--mount-deg",
        "120",
        "--seed",
        "7",
        "--out",
        d,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let true_arm = dir.join("true_arm.toml");
    let truth = parse_mount(&text_of(&true_arm), "t").unwrap();
    let truth = truth.expect("the true mount").rotation_deg;
    let true_params = aacmm_core::read_arm(&true_arm).unwrap().0.params;
    let positions = dir.join("positions.csv");
    let calibrate = |positions: &std::path::Path, noise: &str, out: &str| {
        let out = dir.join(out);
        let args = [
            "calibrate",
            "--arm",
            &arm,
            "--positions",
            positions.to_str().unwrap(),
            "--position-noise",
            "0.015+0.006/m",
            "--orientation-noise",
            noise,
            "--out",
            out.to_str().unwrap(),
        ];
        (aacmm(&args), out)
    };
    let (o, out) = calibrate(&positions, "0.01", "fit");
    assert!(o.status.success(), "{}", stderr(&o));
    let fitted = parse_mount(&text_of(&out.join("calibrated.toml")), "c").unwrap();
    let fitted = fitted.expect("the fitted mount");
    let sigma = fitted.small_rotation_sigma_deg.expect("its σ");
    let r = |v: [f64; 3]| {
        let v = v.map(f64::to_radians);
        aacmm_core::residuals::Frame::rotation(&v)
    };
    let calibrated = aacmm_core::read_arm(&out.join("calibrated.toml"))
        .unwrap()
        .0;
    let expected = equivalent_mount(&true_params, &calibrated.params, truth.map(f64::to_radians));
    let apart = (r(fitted.rotation_deg) * expected.inverse())
        .angle()
        .to_degrees();
    let largest = sigma.iter().copied().fold(0.0, f64::max);
    assert!(apart < 5.0 * largest, "{apart}° apart, σ {sigma:?}");
    assert!(
        truth.iter().map(|v| v * v).sum::<f64>().sqrt() > 1.0,
        "{truth:?}"
    );
    // `evaluate --positions`: the orientation errors too, with the mount
    // the calibrated arm file states, or in closed form (and said so).
    let evaluate = |arm: &str| {
        let o = aacmm(&[
            "evaluate",
            "--arm",
            arm,
            "--positions",
            positions.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        stdout(&o)
    };
    let text = evaluate(out.join("calibrated.toml").to_str().unwrap());
    assert!(
        text.contains("mount as the arm file states it ([mount])"),
        "{text}"
    );
    let rms = |text: &str| -> f64 {
        let table = text.split("Orientation error (deg)").nth(1).expect(text);
        let line = table
            .lines()
            .find(|l| l.trim_start().starts_with("instrument"));
        let line = line.expect("the frame's row");
        line.split_whitespace().nth(3).unwrap().parse().unwrap()
    };
    assert!(rms(&text) < 0.03, "{text}");
    let text = evaluate(&arm);
    assert!(
        text.contains("in closed form on these orientations"),
        "{text}"
    );
    assert!(rms(&text) > 0.1, "{text}");
    // Row 6's orientation turned by a further 0.5° about its x axis.
    let text = text_of(&positions);
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut f: Vec<String> = lines[6].split(',').map(str::to_string).collect();
    let q: Vec<f64> = f[10..14].iter().map(|v| v.parse().unwrap()).collect();
    let h = 0.25f64.to_radians();
    let (c, s) = (h.cos(), h.sin());
    // q ⊗ (c, s, 0, 0).
    let turned = [
        q[0] * c - q[1] * s,
        q[1] * c + q[0] * s,
        q[2] * c + q[3] * s,
        q[3] * c - q[2] * s,
    ];
    for (k, v) in turned.iter().enumerate() {
        f[10 + k] = format!("{v:.17}");
    }
    let label = f[0].clone();
    lines[6] = f.join(",");
    let gross = dir.join("gross.csv");
    std::fs::write(&gross, lines.join("\n") + "\n").unwrap();
    let (o, _) = calibrate(&gross, "0.01", "gross");
    let text = stdout(&o);
    assert!(text.contains("Outliers: 1 orientation(s) beyond"), "{text}");
    assert!(
        text.contains(&format!("gross.csv:7 (point {label}, orientation, ")),
        "{text}"
    );
    // Ten times too small a σ: refused, with the orientation's flag.
    let (o, _) = calibrate(&positions, "0.001", "small");
    assert!(!o.status.success());
    let all = stdout(&o) + &stderr(&o);
    assert!(all.contains("--orientation-noise 0.0"), "{all}");
}
