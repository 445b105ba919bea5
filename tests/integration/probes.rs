//! Several probes on one measuring arm: sphere-surface rows naming their
//! probe (`tool` column, the arm file's `[[tool]]` with its own ball), each
//! probe's offset fitted beside the arm's geometry and recovered honestly.

use aacmm_core::domain::{Arm, Spheres, Tool};
use aacmm_core::io::spheres::{parse_spheres, write_spheres};
use aacmm_core::params::DhParams;
use aacmm_core::prelude::*;
use aacmm_core::residuals::spheres::{SphereSize, SphereTerm};
use aacmm_core::simulate::{SphereSettings, simulate_spheres, true_arm, with_tool_placements};
use rand::SeedableRng;

const DIAMETER: f64 = 25.4;
const BALL: f64 = 6.0;
const LONG_BALL: f64 = 3.0;
const ENCODER_DEG: f64 = 0.005;
const PROBE_MM: f64 = 0.01;
const QUALIFY_ENCODER_DEG: f64 = 0.001;
const QUALIFY_PROBE_MM: f64 = 0.005;

fn noise() -> Noise {
    Noise {
        encoder_rad: Some(ENCODER_DEG.to_radians()),
        probe_mm: Some(PROBE_MM),
        ..Noise::default()
    }
}

/// The paper's arm with a 6 mm ball on its probe and a second, longer
/// stylus `long` (a 3 mm ball, 60 mm further out and 15 mm aside).
fn nominal() -> Arm {
    let params = DhParams::paper_nominal();
    let p = params.probe;
    Arm {
        ball_diameter_mm: Some(BALL),
        tools: vec![Tool {
            name: "long".into(),
            offset: [p[0] + 15.0, p[1], p[2] + 60.0],
            ball_diameter_mm: Some(LONG_BALL),
        }],
        ..Arm::without_limits("paper", params)
    }
}

fn settings(placements: usize, ball: f64, seed: u64) -> SphereSettings {
    SphereSettings {
        placements,
        diameter_mm: DIAMETER,
        ball_diameter_mm: ball,
        encoder_rad: ENCODER_DEG.to_radians(),
        probe_mm: PROBE_MM,
        seed,
    }
}

/// `truth`'s sphere points by its probe (`S1`, …) and by its `long`
/// stylus (`S1.long`, …, the rows naming it), in one file's rows: what
/// `simulate --spheres N --sphere-tools` writes.
fn two_probe_points(truth: &Arm, placements: usize, seed: u64) -> Spheres {
    let s = settings(placements, BALL, seed);
    let by_probe = simulate_spheres(truth, &s).unwrap();
    with_tool_placements(truth, by_probe.spheres, &s)
        .unwrap()
        .spheres
}

/// The fit of `rows` from `start`, the diameter stated.
fn fit(start: &Arm, rows: &Spheres) -> CalibrationReport {
    let model = ModelOptions {
        noise: noise(),
        ..ModelOptions::default()
    };
    let mut p = Problem::new(start.clone(), DataSet::without_touches(6, 0), model).unwrap();
    let term = SphereTerm::new(
        rows.clone(),
        "spheres.csv",
        &start.params,
        SphereSize::Known(DIAMETER),
        start.ball_diameter_mm,
        &noise(),
        |b| p.add_boxed_block(b),
    )
    .unwrap();
    let settings = SolverSettings::default().with_method(Method::Lm);
    p.with_spheres(term).run(&settings).unwrap()
}

/// A true arm of `seed` (geometry errors where the spheres see them; its
/// stylus 0.3 mm per axis off the nominal) and its two probes' points.
fn campaign(seed: u64) -> (Arm, Spheres) {
    let nominal = nominal();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut truth = true_arm(&nominal, &ErrorModel::random(1.0, false), &mut rng).unwrap();
    truth.tools[0].offset =
        aacmm_core::simulate::perturbed_tools(&truth.tools, 0.3, seed + 7)[0].offset;
    // What the spheres cannot see stays nominal, so every free parameter
    // has its truth to compare with.
    let first = fit(&nominal, &two_probe_points(&truth, 4, seed + 1000));
    for e in (first.calibration.parameters.iter()).filter(|e| e.fixed.is_some()) {
        *truth.params.get_mut(e.id) = nominal.params.get(e.id);
    }
    let rows = two_probe_points(&truth, 4, seed + 1000);
    (truth, rows)
}

/// Over seeds, each probe's offset (the arm's `B` and the stylus' block)
/// recovered within its σ: the normalised errors' RMS near 1, none beyond
/// 4σ; the calibrated arm file carries the stylus' fitted offset and ball.
#[test]
fn two_probes_on_spheres_are_each_recovered() {
    let mut z2 = Vec::new();
    for seed in 0..6 {
        let (truth, rows) = campaign(seed);
        let report = fit(&nominal(), &rows);
        assert!(report.verdict.usable, "seed {seed}: {:?}", report.verdict);
        let c = &report.calibration;
        let long = (c.tool_estimates().into_iter())
            .find(|(n, _, _)| n == "long")
            .expect("the stylus' offset fitted");
        let sigma = long.2.expect("its σ");
        for ((x, t), s) in long.1.iter().zip(truth.tools[0].offset).zip(sigma) {
            z2.push(((x - t) / s).powi(2));
        }
        for e in (c.parameters.iter()).filter(|e| e.fixed.is_none() && e.id.kind.is_length()) {
            z2.push(((e.calibrated - truth.params.get(e.id)) / e.sigma.unwrap()).powi(2));
        }
        let spheres = report.spheres.as_ref().expect("the spheres' report");
        let names: Vec<&str> = spheres.probes.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, ["probe", "long"]);
        assert_eq!(spheres.probes[1].offset, long.1);
        assert_eq!(
            spheres.probes[1].spheres,
            ["S1.long", "S2.long", "S3.long", "S4.long"]
        );
        assert_eq!(
            (
                spheres.probes[0].ball_diameter,
                spheres.probes[1].ball_diameter
            ),
            (BALL, LONG_BALL)
        );
        assert!(report.summary().contains("\nlong "), "{}", report.summary());
        let arm = report.calibrated_arm().unwrap();
        assert_eq!(arm.tools[0].offset, long.1, "seed {seed}");
        assert_eq!(arm.tools[0].ball_diameter_mm, Some(LONG_BALL));
    }
    let rms = (z2.iter().sum::<f64>() / z2.len() as f64).sqrt();
    let worst = z2.iter().copied().fold(0.0, f64::max).sqrt();
    assert!(
        (0.6..1.4).contains(&rms),
        "normalised RMS {rms} over {}",
        z2.len()
    );
    assert!(worst < 4.5, "worst {worst}σ");
}

/// A file's `tool` column round-trips, and what is refused is named by
/// line and field: a tool the arm does not know, a placement probed by two
/// tools, a stated diameter with a stylus that gives no ball.
#[test]
fn the_tool_column_is_read_written_and_checked() {
    let arm = nominal();
    let rows = two_probe_points(&arm, 1, 3);
    let mut text = Vec::new();
    write_spheres(&mut text, &rows, AngleUnit::Deg).unwrap();
    let text = String::from_utf8(text).unwrap();
    assert!(
        text.starts_with("sphere,q1,q2,q3,q4,q5,q6,tool\n"),
        "{text}"
    );
    assert!(text.lines().nth(1).unwrap().ends_with(",probe"), "{text}");
    assert!(text.lines().last().unwrap().ends_with(",long"), "{text}");
    let (back, _) = parse_spheres(&text, "s.csv", AngleUnit::Deg, &arm).unwrap();
    assert_eq!(back.len(), rows.len());
    assert_eq!((back.tool(0), back.tool(rows.len() - 1)), (0, 1));
    assert_eq!(back.tools()[1], arm.tools[0]);
    // An unknown tool, named with the known ones.
    let unknown = text.replacen(",long\n", ",short\n", 1);
    let e = parse_spheres(&unknown, "s.csv", AngleUnit::Deg, &arm)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("s.csv:27: field `tool`: `short`"), "{e}");
    assert!(e.contains("`probe`, `long`"), "{e}");
    // One placement, two tools.
    let mixed = text.replacen(",probe\n", ",long\n", 1);
    let e = parse_spheres(&mixed, "s.csv", AngleUnit::Deg, &arm)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(
            "s.csv:3: field `tool`: sphere `S1` is probed by `long` (line 2) and by `probe`"
        ),
        "{e}"
    );
    // A stylus without its ball, the diameter stated.
    let mut bare = arm.clone();
    bare.tools[0].ball_diameter_mm = None;
    let (rows, _) = parse_spheres(&text, "s.csv", AngleUnit::Deg, &bare).unwrap();
    let mut layout = aacmm_core::residuals::Layout::new(bare.params.clone());
    let e = SphereTerm::new(
        rows,
        "s.csv",
        &bare.params,
        SphereSize::Known(DIAMETER),
        bare.ball_diameter_mm,
        &noise(),
        aacmm_core::residuals::spheres::add_to(&mut layout),
    )
    .map(|_| ())
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("tool `long`") && e.contains("ball_diameter_mm"),
        "{e}"
    );
}

/// The stylus `long` of the nominal arm qualified on one sphere its true
/// twin (offset `moved` mm off along x, effective ball `ball`) probed with
/// the probing noise `probe_mm`.
fn qualification(
    seed: u64,
    moved: f64,
    ball: f64,
    probe_mm: f64,
    max_form_mm: Option<f64>,
) -> (Tool, aacmm_core::session::probe::ProbeQualification) {
    use aacmm_core::session::probe::{ProbeSettings, qualify_probe};
    let nominal = nominal();
    let mut truth = nominal.tools[0].clone();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let jitter = aacmm_core::simulate::perturbed_tools(&[truth.clone()], 0.01, seed + 11)[0].offset;
    truth.offset = [jitter[0] + moved, jitter[1], jitter[2]];
    truth.ball_diameter_mm = Some(ball);
    let stylus = Arm {
        params: DhParams {
            probe: truth.offset,
            ..nominal.params.clone()
        },
        ball_diameter_mm: Some(ball),
        ..nominal.clone()
    };
    // A good arm's noise: the tip's σ (≈ 0.005 mm) well below the
    // tolerance a bent stylus is told by.
    let s = SphereSettings {
        probe_mm,
        encoder_rad: QUALIFY_ENCODER_DEG.to_radians(),
        ..settings(1, ball, rand::RngExt::random(&mut rng))
    };
    let points = simulate_spheres(&stylus, &s).unwrap().spheres;
    let q = qualify_probe(
        &nominal,
        points,
        "ring.csv",
        &ProbeSettings {
            tool: "long".into(),
            sphere_diameter_mm: DIAMETER,
            noise: Noise {
                encoder_rad: Some(QUALIFY_ENCODER_DEG.to_radians()),
                probe_mm: Some(QUALIFY_PROBE_MM),
                ..Noise::default()
            },
            tolerance_mm: 0.05,
            max_form_mm,
            spelling: aacmm_core::session::Spelling::Cli,
        },
    )
    .unwrap();
    (truth, q)
}

/// Over 50 seeds the stylus' tip offset and effective ball diameter are
/// recovered within their σ (normalised RMS near 1, none beyond 4.5σ), a
/// clean probe qualifies without a warning, and the qualified arm carries
/// them.
#[test]
fn probe_qualification_recovers_the_tip_and_the_ball() {
    let mut z2 = Vec::new();
    for seed in 0..50 {
        let (truth, q) = qualification(seed, 0.0, 2.996, QUALIFY_PROBE_MM, None);
        assert!(
            q.usable() && q.warnings.is_empty(),
            "seed {seed}: {}",
            q.summary()
        );
        for k in 0..3 {
            z2.push(((q.offset[k] - truth.offset[k]) / q.offset_sigma[k]).powi(2));
        }
        z2.push(((q.ball_diameter_mm - 2.996) / q.ball_sigma_mm).powi(2));
        let arm = q.qualified_arm(&nominal());
        assert_eq!(
            (arm.tools[0].offset, arm.tools[0].ball_diameter_mm),
            (q.offset, Some(q.ball_diameter_mm))
        );
    }
    let rms = (z2.iter().sum::<f64>() / z2.len() as f64).sqrt();
    let worst = z2.iter().copied().fold(0.0, f64::max).sqrt();
    assert!(
        (0.7..1.3).contains(&rms),
        "normalised RMS {rms} over {}",
        z2.len()
    );
    assert!(worst < 4.5, "worst {worst}σ");
}

/// A stylus bent by 0.1 mm is flagged (qualified, with the move named); a
/// loose one — probing scatter five times the stated — is refused by the
/// χ² test, and a form beyond a limit set by the form.
#[test]
fn a_bent_stylus_is_flagged_and_a_loose_one_refused() {
    let (_, bent) = qualification(3, 0.1, 3.0, QUALIFY_PROBE_MM, None);
    assert!(bent.usable(), "{}", bent.summary());
    assert!((bent.moved_mm - 0.1).abs() < 0.02, "{}", bent.summary());
    assert!(
        bent.warnings
            .iter()
            .any(|w| w.contains(&format!("the tip moved {:.4} mm", bent.moved_mm))),
        "{}",
        bent.summary()
    );
    let (_, loose) = qualification(3, 0.0, 3.0, 5.0 * QUALIFY_PROBE_MM, None);
    assert!(!loose.usable(), "{}", loose.summary());
    assert!(
        loose.summary().contains("NOT QUALIFIED"),
        "{}",
        loose.summary()
    );
    assert!(loose.refusals[0].contains("χ²"), "{}", loose.summary());
    let (_, limited) = qualification(3, 0.0, 3.0, QUALIFY_PROBE_MM, Some(0.01));
    assert!(!limited.usable(), "{}", limited.summary());
    assert!(
        limited.refusals.iter().any(|r| r.contains("form")),
        "{}",
        limited.summary()
    );
}

/// `aacmm probe` on a stylus' sphere points: the summary, the qualified
/// arm file (its [[tool]] at the fitted offset and ball) and exit 0; a
/// probe the arm does not know is named; a refused qualification writes
/// nothing and exits 1.
#[test]
fn the_probe_command_qualifies_and_refuses() {
    use crate::util::{aacmm, assert_clean_error, stdout, temp_dir, write};
    let dir = temp_dir("probe-cli");
    let arm = write(
        &dir,
        "arm.toml",
        &aacmm_core::io::arm_to_toml(&nominal(), aacmm_core::io::LengthUnit::Mm, AngleUnit::Deg),
    );
    let file = |name: &str, probe_mm: f64| {
        let nominal = nominal();
        let stylus = Arm {
            params: DhParams {
                probe: nominal.tools[0].offset,
                ..nominal.params.clone()
            },
            ..nominal.clone()
        };
        let s = SphereSettings {
            probe_mm,
            encoder_rad: QUALIFY_ENCODER_DEG.to_radians(),
            ..settings(1, LONG_BALL, 5)
        };
        let mut text = Vec::new();
        write_spheres(
            &mut text,
            &simulate_spheres(&stylus, &s).unwrap().spheres,
            AngleUnit::Deg,
        )
        .unwrap();
        write(&dir, name, &String::from_utf8(text).unwrap())
    };
    let (good, loose) = (
        file("good.csv", QUALIFY_PROBE_MM),
        file("loose.csv", 5.0 * QUALIFY_PROBE_MM),
    );
    let out = dir.join("qualified.toml");
    let run = |points: &str, tool: &str| {
        aacmm(&[
            "probe",
            "--arm",
            &arm,
            "--spheres",
            points,
            "--sphere-diameter",
            "25.4",
            "--tool",
            tool,
            "--encoder-noise",
            "0.001",
            "--probe-noise",
            "0.005",
            "--out",
            out.to_str().unwrap(),
            "--force",
        ])
    };
    let o = run(&good, "long");
    assert!(o.status.success(), "{}", crate::util::stderr(&o));
    assert!(stdout(&o).contains("Verdict: QUALIFIED"), "{}", stdout(&o));
    let (qualified, _) = aacmm_core::io::read_arm(&out).unwrap();
    let t = &qualified.tools[0];
    assert!(
        aacmm_core::geometry::distance(&t.offset, &nominal().tools[0].offset) < 0.03,
        "{t:?}"
    );
    assert!(
        (t.ball_diameter_mm.unwrap() - LONG_BALL).abs() < 0.03,
        "{t:?}"
    );
    assert_ne!(t.offset, nominal().tools[0].offset);
    std::fs::remove_file(&out).unwrap();
    assert_clean_error(
        &run(&good, "short"),
        &["--tool short: the arm has no such tool", "`probe`, `long`"],
    );
    let o = run(&loose, "long");
    assert_eq!(o.status.code(), Some(1));
    assert!(
        crate::util::stderr(&o).contains("nothing was written"),
        "{}",
        crate::util::stderr(&o)
    );
    assert!(!out.exists());
    // A full stdout loses no result: the qualified arm is written, then
    // the failed summary reported.
    #[cfg(unix)]
    {
        let full = std::fs::File::create("/dev/full").unwrap();
        let o = crate::util::command(&[
            "probe",
            "--arm",
            &arm,
            "--spheres",
            &good,
            "--sphere-diameter",
            "25.4",
            "--tool",
            "long",
            "--encoder-noise",
            "0.001",
            "--probe-noise",
            "0.005",
            "--out",
            out.to_str().unwrap(),
        ])
        .stdout(full)
        .output()
        .unwrap();
        assert_eq!(o.status.code(), Some(1));
        assert!(
            crate::util::stderr(&o).contains("stdout"),
            "{}",
            crate::util::stderr(&o)
        );
        assert!(out.exists());
    }
}

/// `aacmm points --tool NAME`: the positions of the stylus' ball centre —
/// the kernel's with the probe at the tool's offset; a tool the arm does
/// not list is named with those it does.
#[test]
fn points_computes_a_named_probe() {
    use crate::util::{aacmm, assert_clean_error, stdout, temp_dir, write};
    let dir = temp_dir("probe-points");
    let arm = nominal();
    let arm_file = write(
        &dir,
        "arm.toml",
        &aacmm_core::io::arm_to_toml(&arm, aacmm_core::io::LengthUnit::Mm, AngleUnit::Deg),
    );
    let poses = write(
        &dir,
        "poses.csv",
        "point,q1,q2,q3,q4,q5,q6\nA,10,20,30,40,50,60\n",
    );
    let o = aacmm(&[
        "points", "--arm", &arm_file, "--data", &poses, "--tool", "long",
    ]);
    assert!(o.status.success(), "{}", crate::util::stderr(&o));
    let stylus = DhParams {
        probe: arm.tools[0].offset,
        ..arm.params.clone()
    };
    let q: Vec<f64> = [10.0, 20.0, 30.0, 40.0, 50.0, 60.0]
        .map(f64::to_radians)
        .to_vec();
    let p = aacmm_core::kernel::ArmKernel::new(&stylus)
        .unwrap()
        .positions_of(&[&q[..]])
        .unwrap()[0];
    let line = stdout(&o).lines().nth(1).unwrap().to_string();
    let got: Vec<f64> = line
        .split(',')
        .skip(1)
        .map(|v| v.parse().unwrap())
        .collect();
    for k in 0..3 {
        assert!((got[k] - p[k]).abs() < 1e-6, "{line} vs {p:?}");
    }
    let plain = aacmm(&["points", "--arm", &arm_file, "--data", &poses]);
    assert_ne!(stdout(&plain), stdout(&o));
    assert_clean_error(
        &aacmm(&[
            "points", "--arm", &arm_file, "--data", &poses, "--tool", "short",
        ]),
        &["--tool short: the arm has no such tool", "`probe`, `long`"],
    );
    // evaluate --tool: the point's centroid is the stylus' positions' mean.
    let rows = [
        [10.0, 20.0, 30.0, 40.0, 50.0, 60.0],
        [12.0, 18.0, 33.0, 41.0, 48.0, 65.0],
        [8.0, 22.0, 29.0, 37.0, 52.0, 55.0],
    ];
    let text: String = (rows.iter())
        .map(|r| format!("A,{}\n", r.map(|v| v.to_string()).join(",")))
        .collect();
    let touches = write(
        &dir,
        "touches.csv",
        &format!("point,q1,q2,q3,q4,q5,q6\n{text}"),
    );
    let json = dir.join("evaluation.json");
    let o = aacmm(&[
        "evaluate",
        "--arm",
        &arm_file,
        "--data",
        &touches,
        "--tool",
        "long",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", crate::util::stderr(&o));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let kernel = aacmm_core::kernel::ArmKernel::new(&stylus).unwrap();
    let q: Vec<Vec<f64>> = rows
        .iter()
        .map(|r| r.map(f64::to_radians).to_vec())
        .collect();
    let refs: Vec<&[f64]> = q.iter().map(|r| &r[..]).collect();
    let p = kernel.positions_of(&refs).unwrap();
    let centroid = &v["evaluation"]["points"][0]["centroid"];
    for k in 0..3 {
        let mean = p.iter().map(|x| x[k]).sum::<f64>() / 3.0;
        assert!(
            (centroid[k].as_f64().unwrap() - mean).abs() < 1e-9,
            "{centroid} vs {mean}"
        );
    }
}

/// `aacmm verify --tool NAME` verifies one probe: its offset and ball
/// (the stylus' P_Size is its own sphere's, not off by the balls'
/// difference); a file with another probe's rows is refused by line.
#[test]
fn verify_takes_one_probe_at_a_time() {
    use crate::util::{aacmm, assert_clean_error, stdout, temp_dir, write};
    let dir = temp_dir("probe-verify");
    let arm = nominal();
    let arm_file = write(
        &dir,
        "arm.toml",
        &aacmm_core::io::arm_to_toml(&arm, aacmm_core::io::LengthUnit::Mm, AngleUnit::Deg),
    );
    let rows = two_probe_points(&arm, 1, 3);
    let csv = |rows: &Spheres| {
        let mut text = Vec::new();
        write_spheres(&mut text, rows, AngleUnit::Deg).unwrap();
        String::from_utf8(text).unwrap()
    };
    let both = write(&dir, "both.csv", &csv(&rows));
    let long: Vec<usize> = (0..rows.len()).filter(|&i| rows.tool(i) == 1).collect();
    let long = write(&dir, "long.csv", &csv(&rows.subset(&long)));
    let verify = |file: &str, tool: &str| {
        let json = dir.join(format!("{tool}.json"));
        let o = aacmm(&[
            "verify",
            "--arm",
            &arm_file,
            "--spheres",
            file,
            "--sphere-diameter",
            "25.4",
            "--tool",
            tool,
            "--json",
            json.to_str().unwrap(),
            "--force",
        ]);
        (o, json)
    };
    let (o, json) = verify(&long, "long");
    assert!(o.status.success(), "{}", crate::util::stderr(&o));
    assert!(stdout(&o).contains("P_Size"), "{}", stdout(&o));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    let size = (v["tests"].as_array().unwrap().iter())
        .find(|t| t["figure"].as_str().unwrap().starts_with("P_Size"))
        .map(|t| t["value"].as_f64().unwrap())
        .unwrap();
    // The noise-driven size error of 25 points, not the 3 mm of a wrong ball.
    assert!(size.abs() < 0.1, "P_Size {size}");
    assert_clean_error(
        &verify(&both, "probe").0,
        &["both.csv:27: field `tool`", "`long`"],
    );
}

/// `simulate --spheres N --sphere-tools`: each `[[tool]]` stylus probes N
/// placements of its own (`S1.long`, …, the `tool` column), the same bytes
/// for the same seed, the probe's rows those of the run without the flag;
/// the true stylus (0.3 mm off) is in true_arm.toml, and a calibration of
/// the file recovers it within 4σ. An arm without `[[tool]]` is refused by
/// the flag.
#[test]
fn simulate_sphere_tools_then_calibrate() {
    use crate::util::{aacmm, assert_clean_error, temp_dir, write};
    let dir = temp_dir("sphere-tools");
    let text =
        aacmm_core::io::arm_to_toml(&nominal(), aacmm_core::io::LengthUnit::Mm, AngleUnit::Deg);
    let arm = write(&dir, "arm.toml", &text);
    let run = |out: &str, tools: bool| {
        let out = dir.join(out);
        let mut args = vec![
            "simulate",
            "--arm",
            &arm,
            "--errors",
            "paper",
            "--spheres",
            "4",
            "--seed",
            "6",
            "--encoder-noise",
            "0.001",
            "--probe-noise",
            "0.003",
        ];
        if tools {
            args.push("--sphere-tools");
        }
        let out_s = out.to_str().unwrap().to_string();
        args.extend(["--out", &out_s]);
        let o = aacmm(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let read = |f: &str| std::fs::read_to_string(out.join(f)).unwrap();
        (read("spheres.csv"), read("true_arm.toml"), out)
    };
    let (with, truth, out) = run("with", true);
    let (again, _, _) = run("again", true);
    let (plain, _, _) = run("plain", false);
    assert_eq!(with, again, "the same seed, the same bytes");
    let lines: Vec<&str> = with.lines().collect();
    assert_eq!(lines[0], "sphere,q1,q2,q3,q4,q5,q6,tool");
    assert_eq!(lines.len(), 1 + 2 * 4 * 25);
    for (a, b) in plain.lines().skip(1).zip(&lines[1..]) {
        assert_eq!(format!("{a},probe"), *b);
    }
    assert!(lines[101].starts_with("S1.long,") && lines[101].ends_with(",long"));
    let (true_arm, _) = aacmm_core::io::parse_arm(&truth, "true_arm.toml").unwrap();
    let true_long = true_arm.tools[0].offset;
    let shift: f64 = (true_long.iter().zip(nominal().tools[0].offset))
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(shift > 0.1, "the true stylus is off its nominal: {shift}");

    let fitted = dir.join("fit");
    let spheres = out.join("spheres.csv");
    let o = aacmm(&[
        "calibrate",
        "--arm",
        &arm,
        "--spheres",
        spheres.to_str().unwrap(),
        "--sphere-diameter",
        "25.4",
        "--encoder-noise",
        "0.001",
        "--probe-noise",
        "0.003",
        "--method",
        "lm",
        "--out",
        fitted.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json = std::fs::read_to_string(fitted.join("calibration.json")).unwrap();
    let report = CalibrationReport::from_json(&json).unwrap();
    let (name, x, sigma) = report.calibration.tool_estimates().remove(0);
    assert_eq!(name, "long");
    let sigma = sigma.expect("the stylus' σ");
    for k in 0..3 {
        let z = (x[k] - true_long[k]) / sigma[k];
        assert!(
            z.abs() < 4.0,
            "long[{k}]: {} vs {} (σ {})",
            x[k],
            true_long[k],
            sigma[k]
        );
    }

    let bare = aacmm_core::io::arm_to_toml(
        &Arm {
            tools: Vec::new(),
            ..nominal()
        },
        aacmm_core::io::LengthUnit::Mm,
        AngleUnit::Deg,
    );
    let bare = write(&dir, "bare.toml", &bare);
    let o = aacmm(&[
        "simulate",
        "--arm",
        &bare,
        "--spheres",
        "2",
        "--sphere-tools",
        "--errors",
        "paper",
        "--seed",
        "1",
        "--out",
        dir.join("bare").to_str().unwrap(),
    ]);
    assert_clean_error(
        &o,
        &["--sphere-tools: an arm whose file lists styli as [[tool]]"],
    );
}

/// `calibrate --tool NAME`: a file without a `tool` column probed with one
/// of the arm's styli calibrates as the same file whose every row names it
/// (the same parameters and offsets, the stylus' written to the calibrated
/// arm's `[[tool]]`, the probe's held as unseen), for points on spheres
/// and touches alike; a file that names its probes already is refused by
/// the flag.
#[test]
fn calibrate_tool_is_the_tool_column_of_every_row() {
    use crate::util::{aacmm, assert_clean_error, stdout, temp_dir, write};
    let dir = temp_dir("calibrate-tool");
    let text =
        aacmm_core::io::arm_to_toml(&nominal(), aacmm_core::io::LengthUnit::Mm, AngleUnit::Deg);
    let arm = write(&dir, "arm.toml", &text);
    let (_, rows) = campaign(2);
    let long: Vec<usize> = (0..rows.len()).filter(|&i| rows.tool(i) == 1).collect();
    let named = rows.subset(&long);
    let mut bare = Spheres::new(named.joints(), named.prismatic_mask());
    for i in 0..named.len() {
        bare.push(
            &named.spheres()[named.sphere(i)],
            named.reading(i),
            named.line(i),
            None,
        );
    }
    let csv = |rows: &Spheres| {
        let mut text = Vec::new();
        write_spheres(&mut text, rows, AngleUnit::Deg).unwrap();
        String::from_utf8(text).unwrap()
    };
    let named_file = write(&dir, "named.csv", &csv(&named));
    let bare_file = write(&dir, "bare.csv", &csv(&bare));
    assert!(!csv(&bare).starts_with("sphere,q1,q2,q3,q4,q5,q6,tool"));
    let fit = |file: &str, tool: &[&str], out: &str| {
        let out = dir.join(out);
        let args = [
            &[
                "calibrate",
                "--arm",
                &arm,
                "--spheres",
                file,
                "--sphere-diameter",
                "25.4",
            ][..],
            &[
                "--encoder-noise",
                "0.005",
                "--probe-noise",
                "0.01",
                "--method",
                "lm",
            ][..],
            &["--out", out.to_str().unwrap()][..],
            tool,
        ]
        .concat();
        let o = aacmm(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let json = std::fs::read_to_string(out.join("calibration.json")).unwrap();
        let toml = std::fs::read_to_string(out.join("calibrated.toml")).unwrap();
        (
            CalibrationReport::from_json(&json).unwrap(),
            toml,
            stdout(&o),
        )
    };
    let (by_flag, toml, text) = fit(&bare_file, &["--tool", "long"], "flag");
    let (by_column, _, _) = fit(&named_file, &[], "column");
    assert_eq!(by_flag.calibration.params, by_column.calibration.params);
    assert_eq!(
        by_flag.calibration.tool_estimates(),
        by_column.calibration.tool_estimates()
    );
    assert!(
        text.contains("unseen: no row is measured with the arm's [probe]"),
        "{text}"
    );
    let (back, _) = aacmm_core::io::parse_arm(&toml, "calibrated.toml").unwrap();
    let (_, x, _) = by_flag.calibration.tool_estimates().remove(0);
    assert_eq!(back.tools[0].offset, x);
    assert_eq!(
        back.params.probe,
        nominal().params.probe,
        "the probe is held"
    );

    let o = aacmm(&[
        "calibrate",
        "--arm",
        &arm,
        "--spheres",
        &named_file,
        "--sphere-diameter",
        "25.4",
        "--tool",
        "long",
        "--out",
        dir.join("named-flag").to_str().unwrap(),
    ]);
    assert_clean_error(
        &o,
        &["--tool long", "named.csv: the rows name their probes"],
    );
    // Touches: the shipped campaign without a column and --tool, as the
    // same file whose every row names the stylus (here at the probe's own
    // offset and ball, so that the shipped touches fit it).
    let mut same = nominal();
    same.tools[0].offset = same.params.probe;
    let same_arm = write(
        &dir,
        "same.toml",
        &aacmm_core::io::arm_to_toml(&same, aacmm_core::io::LengthUnit::Mm, AngleUnit::Deg),
    );
    let poses = crate::util::shipped("poses.csv");
    let text = std::fs::read_to_string(&poses).unwrap();
    let mut lines = text.lines();
    let mut named = format!("{},tool\n", lines.next().unwrap());
    for l in lines {
        named += &format!("{l},long\n");
    }
    let named_poses = write(&dir, "named-poses.csv", &named);
    let lengths = crate::util::shipped("lengths.csv");
    let touches = |data: &str, tool: &[&str], out: &str| {
        let out = dir.join(out);
        let args = [
            &[
                "calibrate",
                "--arm",
                &same_arm,
                "--data",
                data,
                "--method",
                "lm",
            ][..],
            &["--lengths", &lengths][..],
            &["--out", out.to_str().unwrap()][..],
            tool,
        ]
        .concat();
        let o = aacmm(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let json = std::fs::read_to_string(out.join("calibration.json")).unwrap();
        CalibrationReport::from_json(&json).unwrap().calibration
    };
    let by_flag = touches(&poses, &["--tool", "long"], "touches-flag");
    let by_column = touches(&named_poses, &[], "touches-column");
    assert_eq!(by_flag.params, by_column.params);
    assert_eq!(by_flag.tool_estimates(), by_column.tool_estimates());
    assert_eq!(by_flag.tool_estimates()[0].0, "long");
    let o = aacmm(&[
        "calibrate",
        "--arm",
        &same_arm,
        "--data",
        &named_poses,
        "--tool",
        "long",
        "--out",
        dir.join("touches-both").to_str().unwrap(),
    ]);
    assert_clean_error(
        &o,
        &[
            "--tool long",
            "named-poses.csv: the touches name their probes",
        ],
    );
    // Reference positions: a tracker campaign of the stylus (simulate
    // names it on every row), and the same rows without the column.
    let sim = dir.join("sim");
    let o = aacmm(&[
        "simulate",
        "--arm",
        &arm,
        "--errors",
        "paper",
        "--positions",
        "40",
        "--seed",
        "3",
        "--out",
        sim.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let named = std::fs::read_to_string(sim.join("positions.csv")).unwrap();
    assert!(named.lines().skip(1).all(|l| l.ends_with(",long")));
    let bare: String = (named.lines())
        .map(|l| format!("{}\n", l.rsplit_once(',').unwrap().0))
        .collect();
    let bare_positions = write(&dir, "bare-positions.csv", &bare);
    let tracked = |file: &str, tool: &[&str], out: &str| {
        let out = dir.join(out);
        let args = [
            &["calibrate", "--arm", &arm, "--positions", file][..],
            &["--method", "lm", "--out", out.to_str().unwrap()][..],
            tool,
        ]
        .concat();
        let o = aacmm(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let json = std::fs::read_to_string(out.join("calibration.json")).unwrap();
        CalibrationReport::from_json(&json).unwrap()
    };
    let by_flag = tracked(&bare_positions, &["--tool", "long"], "positions-flag");
    let named_file = sim.join("positions.csv");
    let by_column = tracked(named_file.to_str().unwrap(), &[], "positions-column");
    assert_eq!(by_flag.calibration.params, by_column.calibration.params);
    assert_eq!(
        by_flag.calibration.tool_estimates(),
        by_column.calibration.tool_estimates()
    );
    assert_eq!(by_flag.calibration.tool_estimates()[0].0, "long");
    let tools = by_flag.tools.as_ref().expect("the positions' tool table");
    assert!(tools.file.ends_with("bare-positions.csv"), "{}", tools.file);
    assert_eq!(
        (tools.tools.iter().map(|t| (t.name.as_str(), t.rows))).collect::<Vec<_>>(),
        [("long", 40)]
    );
}
