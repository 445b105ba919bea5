//! Points probed on reference spheres (`--spheres`): simulated campaigns
//! with a known truth recovered honestly, the scale fixed by a stated
//! diameter and said to be unfixed without one, the command line's
//! outputs, and bad input refused by file, line and field.

use aacmm_core::domain::Arm;
use aacmm_core::kernel::ArmKernel;
use aacmm_core::params::DhParams;
use aacmm_core::prelude::*;
use aacmm_core::residuals::spheres::{SphereSize, SphereTerm};
use aacmm_core::simulate::{SphereCampaign, SphereSettings, simulate_spheres, true_arm};
use rand::SeedableRng;

use crate::util::{aacmm, assert_clean_error, stderr, stdout, temp_dir, write};

pub(crate) const DIAMETER: f64 = 25.4;
pub(crate) const BALL: f64 = 6.0;
const ENCODER_DEG: f64 = 0.005;
const PROBE_MM: f64 = 0.01;

pub(crate) fn noise() -> Noise {
    Noise {
        encoder_rad: Some(ENCODER_DEG.to_radians()),
        probe_mm: Some(PROBE_MM),
        ..Noise::default()
    }
}

pub(crate) fn nominal() -> Arm {
    Arm {
        ball_diameter_mm: Some(BALL),
        ..Arm::without_limits("paper", DhParams::paper_nominal())
    }
}

pub(crate) fn sphere_settings(placements: usize, seed: u64) -> SphereSettings {
    SphereSettings {
        placements,
        diameter_mm: DIAMETER,
        ball_diameter_mm: BALL,
        encoder_rad: ENCODER_DEG.to_radians(),
        probe_mm: PROBE_MM,
        seed,
    }
}

fn lm() -> SolverSettings {
    SolverSettings::default().with_method(Method::Lm)
}

/// The fit of `c` from `start`: the diameter stated or fitted.
pub(crate) fn fit(start: &Arm, c: &SphereCampaign, size: SphereSize) -> CalibrationReport {
    let data = DataSet::without_touches(6, 0);
    let model = ModelOptions {
        noise: noise(),
        ..ModelOptions::default()
    };
    let mut p = Problem::new(start.clone(), data, model).unwrap();
    let term = SphereTerm::new(
        c.spheres.clone(),
        "spheres.csv",
        &start.params,
        size,
        start.ball_diameter_mm,
        &noise(),
        |b| p.add_boxed_block(b),
    )
    .unwrap();
    p.with_spheres(term).run(&lm()).unwrap()
}

/// The problem of fitting `c` from `start`, the diameter stated.
fn sphere_problem(start: &Arm, c: &SphereCampaign) -> Problem {
    let model = ModelOptions {
        noise: noise(),
        ..ModelOptions::default()
    };
    let mut p = Problem::new(start.clone(), DataSet::without_touches(6, 0), model).unwrap();
    let term = SphereTerm::new(
        c.spheres.clone(),
        "spheres.csv",
        &start.params,
        SphereSize::Known(DIAMETER),
        start.ball_diameter_mm,
        &noise(),
        |b| p.add_boxed_block(b),
    )
    .unwrap();
    p.with_spheres(term)
}

/// Cross-validation deals each sphere's points to the folds (every point
/// held out once, every fold's training keeping every sphere), and scores
/// the held-out points against the fold's spheres: far better than the
/// nominal arm, and as good as the fitted points within noise (honest:
/// not the fit's own residuals).
#[test]
fn cross_validation_deals_sphere_points_and_scores_the_held_out_ones() {
    let (_, c) = campaign(5, 6);
    let report = sphere_problem(&nominal(), &c)
        .with_cross_validation(3)
        .unwrap()
        .run(&lm())
        .unwrap();
    let cv = report.validation.cross_validation.as_ref().unwrap();
    let mut seen: Vec<String> = (cv.folds.iter())
        .flat_map(|f| f.terms[0].held_out.clone())
        .collect();
    assert_eq!(seen.len(), c.spheres.len());
    seen.sort();
    seen.dedup();
    assert_eq!(seen.len(), c.spheres.len(), "a point held out twice");
    let spheres = report.spheres.as_ref().unwrap();
    let n = spheres.spheres.len() as f64;
    let fitted = (spheres
        .spheres
        .iter()
        .map(|s| s.after.rms.powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    for f in &cv.folds {
        assert!(f.successful);
        assert!(
            f.held_out.is_empty(),
            "no touch, no position: {:?}",
            f.held_out
        );
        let t = &f.terms[0];
        assert_eq!(
            (t.term.as_str(), t.after.count),
            ("spheres", t.held_out.len())
        );
        assert!(
            t.held_out[0].starts_with("spheres.csv:"),
            "{:?}",
            t.held_out
        );
        eprintln!(
            "fold: before {:.4} after {:.4} fitted {fitted:.4} mm",
            t.before.rms, t.after.rms
        );
        assert!(t.after.rms < 0.5 * t.before.rms, "{t:?}");
        assert!(
            t.after.rms > 0.7 * fitted && t.after.rms < 2.0 * fitted,
            "{t:?} against the fitted {fitted}"
        );
    }
    // Three folds of 50 points each, the deal even.
    assert!(cv.folds.iter().all(|f| f.terms[0].held_out.len() == 50));
}

/// The deal is the seed's: the same seed the same folds, another seed
/// others; and a fold count that leaves a sphere fewer than 4 training
/// points, or a fold nothing to hold out, is refused by name.
#[test]
fn sphere_folds_follow_the_seed_and_refuse_too_many_folds() {
    use aacmm_core::residuals::{At, Layout, Term};
    let start = nominal();
    let c = simulate_spheres(&start, &sphere_settings(2, 4)).unwrap();
    let mut layout = Layout::new(start.params.clone());
    let make = |spheres, layout: &mut Layout| {
        SphereTerm::new(
            spheres,
            "s.csv",
            &start.params,
            SphereSize::Fitted,
            Some(BALL),
            &noise(),
            aacmm_core::residuals::spheres::add_to(layout),
        )
        .unwrap()
    };
    let term = make(c.spheres.clone(), &mut layout);
    let x = layout.start();
    let labels = |k: usize, seed: u64| -> Result<Vec<Vec<String>>, String> {
        let folds = At::with(&layout, &x, |at| term.split(at, k, seed))
            .map_err(|e| e.to_string())?
            .unwrap();
        Ok(folds.iter().map(|f| f.held_out.labels()).collect())
    };
    assert_eq!(labels(4, 1).unwrap(), labels(4, 1).unwrap());
    assert_ne!(labels(4, 1).unwrap(), labels(4, 2).unwrap());
    let e = labels(51, 1).unwrap_err();
    assert!(e.contains("51 folds for 50 points"), "{e}");
    // Six points a sphere: 2 folds leave 3 in a training share.
    let few: Vec<usize> = (0..c.spheres.len())
        .filter(|i| i % 25 < 24 && i % 4 == 0)
        .collect();
    let mut small = Layout::new(start.params.clone());
    let term = make(c.spheres.subset(&few), &mut small);
    let x = small.start();
    let e = At::with(&small, &x, |at| term.split(at, 2, 1))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("sphere `S1` has 6 points: 2 folds leave fewer than 4"),
        "{e}"
    );
}

/// A held-out sphere file (new placements of the same true arm) is scored
/// with each sphere refitted on its own points, the arm fixed: the
/// calibrated arm's radial errors near the fit's own, far below the
/// nominal's; a stated diameter held, a refitted one recovered.
#[test]
fn a_held_out_sphere_file_is_scored_with_its_spheres_refitted() {
    use aacmm_core::residuals::Layout;
    let (truth, c) = campaign(6, 6);
    let held = simulate_spheres(&truth, &sphere_settings(3, 77)).unwrap();
    let start = nominal();
    for size in [SphereSize::Known(DIAMETER), SphereSize::Fitted] {
        let mut own = Layout::new(start.params.clone());
        let term = SphereTerm::new(
            held.spheres.clone(),
            "held.csv",
            &start.params,
            size,
            Some(BALL),
            &noise(),
            aacmm_core::residuals::spheres::add_to(&mut own),
        )
        .unwrap();
        let report = sphere_problem(&start, &c)
            .with_held_out_spheres(term)
            .unwrap()
            .run(&lm())
            .unwrap();
        let fitted = report.spheres.as_ref().unwrap().spheres[0].after.rms;
        let h = report.validation.held_out_spheres.as_ref().unwrap();
        eprintln!(
            "{size:?}: held out before {:.4} after {:.4}, fitted {fitted:.4} mm",
            h.before.rms, h.after.rms
        );
        assert_eq!((h.file.as_str(), h.spheres.len()), ("held.csv", 3));
        assert_eq!(h.after.count, 75);
        assert!(h.after.rms < 0.2 * h.before.rms, "{h:?}");
        assert!(h.after.rms < 2.0 * fitted, "{h:?} against {fitted}");
        for s in &h.spheres {
            match size {
                SphereSize::Known(d) => {
                    assert_eq!((s.diameter_before, s.diameter_after), (d, d));
                    assert_eq!(h.stated_diameter, Some(d));
                }
                SphereSize::Fitted => {
                    assert!((s.diameter_after - DIAMETER).abs() < 0.05, "{s:?}");
                    assert_eq!(h.stated_diameter, None);
                }
            }
        }
        let summary = report.summary();
        assert!(
            summary.contains("Held-out points on spheres (held.csv): each sphere's centre"),
            "{summary}"
        );
    }
}

/// The true arm of `seed` — random errors about the nominal in the
/// parameters the sphere campaign identifies (those `--fix auto` fixes stay
/// nominal, so every free parameter has a true value to compare with) —
/// and its campaign of `placements` spheres.
fn campaign(seed: u64, placements: usize) -> (Arm, SphereCampaign) {
    let nominal = nominal();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut truth = true_arm(&nominal, &ErrorModel::random(1.0, false), &mut rng).unwrap();
    let s = sphere_settings(placements, seed + 1000);
    let first = simulate_spheres(&truth, &s).unwrap();
    let report = fit(&nominal, &first, SphereSize::Known(DIAMETER));
    for e in report
        .calibration
        .parameters
        .iter()
        .filter(|e| e.fixed.is_some())
    {
        *truth.params.get_mut(e.id) = nominal.params.get(e.id);
    }
    (truth.clone(), simulate_spheres(&truth, &s).unwrap())
}

/// `((estimate − truth)/σ)²` of every free geometry parameter and sphere
/// centre coordinate.
fn normalised_errors(cal: &Calibration, truth: &Arm, c: &SphereCampaign) -> Vec<f64> {
    let mut out = Vec::new();
    for e in cal.parameters.iter().filter(|e| e.fixed.is_none()) {
        let mut d = e.calibrated - truth.params.get(e.id);
        if !e.id.kind.is_length() {
            d = aacmm_core::simulate::wrap(d);
        }
        out.push((d / e.sigma.expect("a free parameter's σ")).powi(2));
    }
    for (name, centre) in &c.centres {
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            let column = format!("sphere.{name}.{axis}");
            let e = cal.auxiliary.iter().find(|a| a.name == column).unwrap();
            out.push(((e.calibrated - centre[k]) / e.sigma.unwrap()).powi(2));
        }
    }
    out
}

/// How far an arm puts the probe from where the true arm puts it over 500
/// random poses, after the best rigid motion (mm, RMS): what a calibration
/// leaves of the arm's error wherever it is used.
fn held_out_error(params: &DhParams, truth: &DhParams, seed: u64) -> f64 {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let rows: Vec<Vec<f64>> = (0..500)
        .map(|_| {
            use rand::RngExt;
            (0..6).map(|_| rng.random_range(-3.0..3.0)).collect()
        })
        .collect();
    let xyz = |p: &DhParams| ArmKernel::new(p).unwrap().positions_of(&rows).unwrap();
    aacmm_core::geometry::rigid_distance(&xyz(params), &xyz(truth), false)
}

/// The same true arm calibrated from a touch campaign of about the same
/// size in residual rows (a touch gives 3, a sphere point 1: 8 sockets × 8
/// touches, 192 rows, and 3 reference lengths, against 8 spheres × 25
/// points, 200 rows): its held-out error.
fn touches_held_out(truth: &Arm, seed: u64) -> f64 {
    let errors = ErrorModel::File { arm: truth.clone() };
    let mut s = CampaignSettings::new(seed + 2000, errors, 8, 8);
    s.reference_lengths = 3;
    s.encoder_noise_deg = ENCODER_DEG;
    s.probe_noise_mm = PROBE_MM;
    let c = simulate(&nominal(), &s).unwrap();
    let model = ModelOptions {
        noise: noise(),
        ..ModelOptions::default()
    };
    let report = Problem::new(nominal(), c.data_set().unwrap(), model)
        .unwrap()
        .run(&lm())
        .unwrap();
    held_out_error(&report.calibration.params, &truth.params, seed + 3000)
}

/// Over `seeds`: the arm recovered honestly (normalised error RMS within
/// `band` over every free parameter and centre), and predicting new poses
/// within 4 times the error of a touch campaign of as many rows (a sphere
/// point sees only the radial direction; the numbers are printed and in
/// the README).
fn sphere_campaigns_recover_the_truth(
    seeds: std::ops::Range<u64>,
    band: std::ops::RangeInclusive<f64>,
) {
    let (mut z2, mut spheres, mut touches) = (Vec::new(), Vec::new(), Vec::new());
    for seed in seeds.clone() {
        let (truth, c) = campaign(seed, 8);
        let report = fit(&nominal(), &c, SphereSize::Known(DIAMETER));
        assert!(report.is_usable(), "seed {seed}: {:?}", report.verdict);
        z2.extend(normalised_errors(&report.calibration, &truth, &c));
        spheres.push(held_out_error(
            &report.calibration.params,
            &truth.params,
            seed + 3000,
        ));
        touches.push(touches_held_out(&truth, seed));
    }
    let rms = (z2.iter().sum::<f64>() / z2.len() as f64).sqrt();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (s, t) = (mean(&spheres), mean(&touches));
    eprintln!(
        "spheres, {} seeds: normalised RMS {rms:.3} over {} estimates; held-out shape error \
         {s:.4} mm (8 spheres × 25 points, 200 rows) vs {t:.4} mm (8 sockets × 8 touches + 3 lengths, 195 rows)",
        seeds.end - seeds.start,
        z2.len()
    );
    assert!(band.contains(&rms), "normalised error RMS {rms}");
    assert!(s <= 4.0 * t, "held-out {s} vs touches {t}");
}

/// Three seeds: the ~45 estimates of one campaign are strongly correlated
/// (the centres with the lengths), so one seed's RMS ranges 0.5–1.8 (12
/// seeds measured); three seeds are held to 0.5–1.6, fifty to 0.8–1.25.
#[test]
fn simulated_sphere_campaigns_recover_the_truth() {
    sphere_campaigns_recover_the_truth(0..3, 0.5..=1.6);
}

/// 50 seeds: `cargo test --release --test integration spheres --
/// --ignored --nocapture`.
#[test]
#[ignore = "50 seeds: run with --release -- --ignored"]
fn fifty_simulated_sphere_campaigns_recover_the_truth() {
    sphere_campaigns_recover_the_truth(0..50, 0.8..=1.25);
}

/// A stated diameter fixes the scale without a reference length: no scale
/// rule, the lengths' σ finite and small. A fitted one does not, and the
/// identification and the verdict say so.
#[test]
fn a_stated_diameter_fixes_the_scale_a_fitted_one_does_not() {
    let (_, c) = campaign(7, 6);
    let rules = |r: &CalibrationReport| -> Vec<String> {
        let id = r.calibration.identification.as_ref().unwrap();
        id.rules.iter().map(|r| r.name.clone()).collect()
    };
    let known = fit(&nominal(), &c, SphereSize::Known(DIAMETER));
    assert!(known.is_usable(), "{:?}", known.verdict);
    assert!(
        !rules(&known).contains(&"scale".to_string()),
        "{:?}",
        rules(&known)
    );
    let lengths = (known.calibration.parameters.iter())
        .filter(|e| e.id.kind.is_length() && e.fixed.is_none());
    let sigmas: Vec<f64> = lengths.map(|e| e.sigma.unwrap()).collect();
    assert!(
        sigmas.len() >= 8 && sigmas.iter().all(|s| s.is_finite() && *s < 0.1),
        "{sigmas:?}"
    );
    let fitted = fit(&nominal(), &c, SphereSize::Fitted);
    assert!(
        rules(&fitted).contains(&"scale".to_string()),
        "{:?}",
        rules(&fitted)
    );
    let notes = fitted
        .verdict
        .words(aacmm_core::session::Spelling::Cli)
        .notes
        .join("; ");
    assert!(notes.contains("only up to scale"), "{notes}");
    let spheres = fitted.spheres.as_ref().unwrap();
    assert!(spheres.stated_diameter.is_none() && spheres.spheres[0].diameter_sigma.is_some());
}

/// An arm file with a probe ball (the shipped arm, a 6 mm ball).
pub(crate) fn arm_file(dir: &std::path::Path) -> String {
    let text = std::fs::read_to_string(crate::util::shipped_arm()).unwrap();
    write(
        dir,
        "arm.toml",
        &text.replace("[probe]\n", "[probe]\nball_diameter_mm = 6.0\n"),
    )
}

/// The command line: simulate writes spheres.csv; calibrate takes it alone
/// with a stated diameter (the summary's, the JSON's and the report's
/// sphere sections), and a file without it has none of them.
#[test]
fn simulate_spheres_then_calibrate() {
    let dir = temp_dir("spheres-cli");
    let arm = arm_file(&dir);
    let sim = dir.join("sim");
    let s = sim.to_str().unwrap();
    let simulate = |out: &str| {
        let args = [
            "simulate",
            "--arm",
            &arm,
            "--errors",
            "paper",
            "--spheres",
            "6",
            "--encoder-noise",
            "0.005",
            "--probe-noise",
            "0.01",
            "--seed",
            "3",
            "--out",
            out,
        ];
        aacmm(&args)
    };
    let o = simulate(s);
    assert!(o.status.success(), "{}", stderr(&o));
    let file = sim.join("spheres.csv");
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.starts_with("sphere,q1,q2,q3,q4,q5,q6\nS1,"), "{text}");
    assert_eq!(text.lines().count(), 1 + 6 * 25);
    // Same seed, same bytes.
    let again = dir.join("again");
    let o = simulate(again.to_str().unwrap());
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(again.join("spheres.csv")).unwrap(),
        text
    );
    // New placements of the same true arm, to hold out.
    let held = dir.join("held");
    let truth = sim.join("true_arm.toml");
    let o = aacmm(&[
        "simulate",
        "--arm",
        &arm,
        "--true",
        truth.to_str().unwrap(),
        "--spheres",
        "2",
        "--encoder-noise",
        "0.005",
        "--probe-noise",
        "0.01",
        "--seed",
        "8",
        "--out",
        held.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let held = held.join("spheres.csv");
    let out = dir.join("cal");
    let f = file.to_str().unwrap();
    // The spheres and their noise, as calibrate and identify take them.
    let with_spheres = |command: &str, extra: &[&str]| {
        let mut args = vec![command, "--arm", &arm, "--spheres", f];
        args.extend(["--sphere-diameter", "25.4"]);
        args.extend(["--encoder-noise", "0.005", "--probe-noise", "0.01"]);
        args.extend(extra);
        aacmm(&args)
    };
    let o = with_spheres(
        "calibrate",
        &[
            "--cross-validate",
            "3",
            "--validate-spheres",
            held.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let summary = stdout(&o);
    assert!(summary.contains("Verdict: usable"), "{summary}");
    // The folds' held-out points, per fold beside the spheres' fit.
    assert!(
        summary.contains("Held-out points on spheres (")
            && summary.contains("fold 3, after")
            && summary.contains("data                            count"),
        "{summary}"
    );
    assert!(
        summary.contains("diameter 25.4 mm (stated); probe ball 6 mm"),
        "{summary}"
    );
    assert!(summary.contains("\nS6 "), "{summary}");
    assert!(!stderr(&o).contains("look like radians"), "{}", stderr(&o));
    let json = std::fs::read_to_string(out.join("calibration.json")).unwrap();
    assert!(json.contains("\"spheres\"") && json.contains("\"stated_diameter\": 25.4"));
    let value: serde_json::Value = serde_json::from_str(&json).unwrap();
    let fold = &value["validation"]["cross_validation"]["folds"][2]["terms"][0];
    assert_eq!(fold["term"], "spheres");
    assert_eq!(fold["after"]["count"], 50);
    let page = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(page.contains("Sphere surfaces"), "no sphere section");
    assert!(page.contains("Cross-validation: held-out points on spheres"));
    // The verdict names the folds' held-out points, not empty touch folds.
    assert!(
        page.contains("Held out, fold 3, spheres (50 held out): RMS |error|")
            && page.contains("points on spheres): RMS radial error (each sphere refitted)")
            && !page.contains("(0 points)"),
        "{page}"
    );
    // `identify` sees the spheres (their centres eliminated): the fixed
    // set and rank of the calibration's own analysis.
    let id_json = dir.join("identify.json");
    let o = with_spheres("identify", &["--json", id_json.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("150 points on 6 spheres of")
            && stdout(&o).contains("its diameter stated as 25.4 mm"),
        "{}",
        stdout(&o)
    );
    let id: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&id_json).unwrap()).unwrap();
    let names = |v: &serde_json::Value| -> Vec<String> {
        (v["fixed"].as_array().unwrap().iter())
            .map(|f| f["name"].as_str().unwrap().to_string())
            .collect()
    };
    let own = &value["calibration"]["identification"];
    assert!(!names(own).is_empty());
    assert_eq!(names(&id["identification"]), names(own));
    assert_eq!(id["identification"]["rank"], own["rank"]);
    assert_eq!(id["spheres"]["points"], 150);
    // The held-out file, its spheres refitted at each arm.
    assert!(
        summary.contains("Held-out points on spheres (")
            && summary.contains("(its diameter stated, 25.4 mm) refitted on its own points"),
        "{summary}"
    );
    assert_eq!(
        value["validation"]["held_out_spheres"]["after"]["count"],
        50
    );
    assert!(
        page.contains("Held out (") && page.contains("its diameter held at the stated 25.4 mm")
    );
    // `evaluate --spheres` of the calibrated arm on the held-out file: the
    // calibration's held-out figures; the nominal arm's far worse.
    let evaluate = |arm: &str| {
        let o = aacmm(&[
            "evaluate",
            "--arm",
            arm,
            "--spheres",
            held.to_str().unwrap(),
            "--sphere-diameter",
            "25.4",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        stdout(&o)
    };
    let calibrated = evaluate(out.join("calibrated.toml").to_str().unwrap());
    let after = &value["validation"]["held_out_spheres"]["after"];
    let rms = format!("RMS {:.4}", after["rms"].as_f64().unwrap());
    assert!(
        calibrated.contains("(its diameter stated, 25.4 mm) fitted on its points")
            && calibrated.contains(&rms)
            && calibrated.contains("(50 points)"),
        "{calibrated} {rms}"
    );
    let before = &value["validation"]["held_out_spheres"]["before"];
    let rms = format!("RMS {:.4}", before["rms"].as_f64().unwrap());
    assert!(evaluate(&arm).contains(&rms), "{rms}");
    // `sa` anneals the touches alone: refused, naming the spheres.
    let o = aacmm(&[
        "calibrate",
        "--arm",
        &arm,
        "--spheres",
        f,
        "--sphere-diameter",
        "25.4",
        "--method",
        "sa",
        "--out",
        dir.join("sa").to_str().unwrap(),
    ]);
    assert_clean_error(&o, &["--method", "spheres"]);
    // One point displaced (1° on joint 2 of line 40, about 13σ in this
    // campaign): named by file and line as the outlier, and weighed down by
    // a robust fit.
    let displaced: String = (text.lines().enumerate())
        .map(|(i, l)| {
            let mut cells: Vec<String> = l.split(',').map(str::to_string).collect();
            if i + 1 == 40 {
                cells[2] = (cells[2].parse::<f64>().unwrap() + 1.0).to_string();
            }
            cells.join(",") + "\n"
        })
        .collect();
    let bad = write(&dir, "displaced.csv", &displaced);
    // The displaced file calibrated with the stated noise by LM, into `out`.
    let calibrate_displaced = |out: &str, extra: &[&str]| {
        let out = dir.join(out);
        let mut args = vec![
            "calibrate",
            "--arm",
            &arm,
            "--spheres",
            &bad,
            "--sphere-diameter",
            "25.4",
            "--encoder-noise",
            "0.005",
            "--probe-noise",
            "0.01",
            "--method",
            "lm",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        aacmm(&args)
    };
    let o = calibrate_displaced("robust", &["--robust", "huber"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let summary = stdout(&o);
    assert!(
        summary.contains("Outliers: 1 ") && summary.contains("displaced.csv:40 (point S2"),
        "{summary}"
    );
    // Plain least squares refuses it, naming it as a point on a sphere
    // (not a touch) and the σ as a sphere point's.
    let o = calibrate_displaced("plain-displaced", &[]);
    assert!(!o.status.success());
    let (summary, error) = (stdout(&o), stderr(&o));
    assert!(
        error.contains("displaced.csv:40 (point S2")
            && error.contains("a mislabelled or displaced point on its sphere?"),
        "{error}"
    );
    assert!(
        summary.contains("(the spheres' included)")
            && summary.contains("sphere point sigma")
            && summary.contains("sphere point(s) beyond")
            && !summary.contains("touch"),
        "{summary}"
    );
    // Without spheres, no word of them.
    let plain = dir.join("plain");
    let o = crate::util::calibrate_shipped(&plain, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json = std::fs::read_to_string(plain.join("calibration.json")).unwrap();
    assert!(!json.contains("spheres") && !stdout(&o).contains("Spheres"));
    let page = std::fs::read_to_string(plain.join("report.html")).unwrap();
    assert!(!page.contains("Sphere surfaces"));
}

/// Bad input, each named by file, line and field (or flag).
#[test]
fn bad_sphere_input_is_refused_by_name() {
    let dir = temp_dir("spheres-bad");
    let arm = arm_file(&dir);
    let nominal = nominal();
    let c = simulate_spheres(&nominal, &sphere_settings(2, 9)).unwrap();
    let mut good = Vec::new();
    aacmm_core::io::spheres::write_spheres(&mut good, &c.spheres, AngleUnit::Deg).unwrap();
    let good = String::from_utf8(good).unwrap();
    let lines: Vec<&str> = good.lines().collect();
    let calibrate = |file: &str, extra: &[&str]| {
        let mut args = vec!["calibrate", "--arm", &arm, "--spheres", file];
        args.extend(extra);
        let out = dir.join("out");
        let o = out.to_str().unwrap().to_string();
        args.extend(["--out", &o, "--force"]);
        aacmm(&args)
    };
    // Fewer than 4 points of S2 (its first at line 27).
    let three = write(&dir, "three.csv", &(lines[..29].join("\n") + "\n"));
    assert_clean_error(
        &calibrate(&three, &[]),
        &["three.csv:27: field `sphere`", "3 points"],
    );
    // S2's equator only (its rows 17–24, lines 44–51): one circle.
    let ring: Vec<&str> = std::iter::once(lines[0])
        .chain(lines[1..26].iter().copied())
        .chain(lines[43..51].iter().copied())
        .collect();
    let ring = write(&dir, "ring.csv", &(ring.join("\n") + "\n"));
    assert_clean_error(
        &calibrate(&ring, &[]),
        &["ring.csv:27: field `sphere`", "one circle"],
    );
    // A diameter in metres.
    let f = write(&dir, "good.csv", &good);
    assert_clean_error(
        &calibrate(&f, &["--sphere-diameter", "0.0254"]),
        &["--sphere-diameter", "metres"],
    );
    // A stated diameter with an arm file that gives no ball.
    let plain = crate::util::shipped_arm();
    let o = aacmm(&[
        "calibrate",
        "--arm",
        &plain,
        "--spheres",
        &f,
        "--sphere-diameter",
        "25.4",
        "--out",
        dir.join("o2").to_str().unwrap(),
    ]);
    assert_clean_error(&o, &["--sphere-diameter", "ball_diameter_mm"]);
    // A ball in metres in the arm file.
    let text = std::fs::read_to_string(&arm)
        .unwrap()
        .replace("= 6.0", "= 0.006");
    let metres = write(&dir, "metres.toml", &text);
    let o = aacmm(&[
        "calibrate",
        "--arm",
        &metres,
        "--spheres",
        &f,
        "--out",
        dir.join("o3").to_str().unwrap(),
    ]);
    assert_clean_error(
        &o,
        &["metres.toml", "field `ball_diameter_mm`", "in metres?"],
    );
    // More folds than points: refused by the flag and the term.
    assert_clean_error(
        &calibrate(&f, &["--sphere-diameter", "25.4", "--cross-validate", "51"]),
        &["--cross-validate", "spheres", "51 folds for 50 points"],
    );
    // A tool the arm does not know, an empty file.
    let named: String = (good.lines().enumerate())
        .map(|(i, l)| format!("{l},{}\n", if i == 0 { "tool" } else { "long" }))
        .collect();
    let tool = write(&dir, "tool.csv", &named);
    assert_clean_error(
        &calibrate(&tool, &[]),
        &[
            "tool.csv:2: field `tool`",
            "`long`: a tool the arm does not know",
        ],
    );
    let empty = write(&dir, "empty.csv", "");
    assert_clean_error(&calibrate(&empty, &[]), &["empty.csv"]);
}

/// A sphere campaign simulated from an arm file that states no probe ball:
/// spheres.csv is probed with the default 6 mm ball, and true_arm.toml
/// says so (a calibration from the true arm file uses the ball the points
/// were made with); the note tells the user to state it in theirs.
#[test]
fn simulate_spheres_writes_the_ball_it_probed_with() {
    let dir = temp_dir("spheres-ball");
    let d = dir.to_str().unwrap();
    let arm = crate::util::shipped_arm();
    let nominal = std::fs::read_to_string(&arm).unwrap();
    assert!(!nominal.contains("ball_diameter_mm"), "{nominal}");
    let o = aacmm(&[
        "simulate",
        "--arm",
        &arm,
        "--errors",
        "paper",
        "--spheres",
        "2",
        "--seed",
        "1",
        "--out",
        d,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("add `ball_diameter_mm = 6` to its [probe]"),
        "{}",
        stderr(&o)
    );
    let truth = aacmm_core::read_arm(&dir.join("true_arm.toml")).unwrap().0;
    assert_eq!(truth.ball_diameter_mm, Some(6.0));
}
