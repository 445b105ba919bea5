//! The acceptance tests predicted from a calibration (`verify
//! --calibration`): a true arm with known errors calibrated on sphere
//! points, then verified on its own acceptance placements — the measured
//! figures lie within the predicted spread (2σ) as often as a spread
//! promises; a calibration on fewer placements predicts a wider spread;
//! the same seed gives the same bytes; a calibration of another arm, of
//! unknown covariance or not usable is refused by file and cause.

use aacmm_core::acceptance::{
    Acceptance, Calibrated, Draws, LDiaRadius, Measured, Mpe, ReadingNoise, Settings, SpherePoints,
    TestKind, predict, verify,
};
use aacmm_core::domain::Arm;
use aacmm_core::kernel::{ArmKernel, PreparedPoses};
use aacmm_core::prelude::*;
use aacmm_core::residuals::spheres::SphereSize;
use aacmm_core::simulate::{
    AcceptanceCampaign, AcceptanceSettings, simulate_spheres, true_arm, with_acceptance,
};
use rand::SeedableRng;

use crate::spheres::{BALL, DIAMETER, fit, nominal, sphere_settings};
use crate::util::{aacmm, stderr, temp_dir};

/// The calibration of `truth` from `placements` sphere placements of
/// `seed` (the sphere tests' noise: 0.005° encoders, 0.01 mm probing),
/// starting at the nominal arm.
fn calibrate(truth: &Arm, placements: usize, seed: u64) -> CalibrationReport {
    let c = simulate_spheres(truth, &sphere_settings(placements, seed).for_campaign()).unwrap();
    fit(&nominal(), &c, SphereSize::Known(DIAMETER))
}

/// A true arm of `seed` with errors where sphere points see them: what a
/// calibration of 12 placements fixes is nominal (the prediction's model,
/// "the true arm is the calibrated one plus δ over the free parameters",
/// then holds).
fn truth(seed: u64) -> Arm {
    let nominal = nominal();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut truth = true_arm(&nominal, &ErrorModel::random(1.0, false), &mut rng).unwrap();
    let first = calibrate(&truth, 12, seed + 500);
    for e in (first.calibration.parameters.iter()).filter(|e| e.fixed.is_some()) {
        *truth.params.get_mut(e.id) = nominal.params.get(e.id);
    }
    truth
}

/// `truth`'s acceptance placements: 2 probing, 2 `L_Dia`, 4 ball-bar
/// positions of 500 mm.
fn acceptance_campaign(truth: &Arm, seed: u64) -> AcceptanceCampaign {
    let s = sphere_settings(2, seed);
    let base = simulate_spheres(truth, &s.for_campaign()).unwrap();
    let more = AcceptanceSettings {
        articulated: 2,
        bar_positions: 4,
        bar_length_mm: 500.0,
    };
    with_acceptance(truth, base, &s, &more).unwrap()
}

fn settings() -> Settings {
    Settings {
        sphere_diameter: DIAMETER,
        sphere_uncertainty: 0.0,
        ball_diameter: BALL,
        l_dia_radius: LDiaRadius::Held,
        mpe: Mpe::default(),
    }
}

/// The campaign verified with the calibrated arm of `report`, each test
/// predicted from it (`draws` draws).
fn verified(report: &CalibrationReport, c: &AcceptanceCampaign, draws: usize) -> Acceptance {
    let cal = &report.calibration;
    let rows: Vec<&[f64]> = (0..c.spheres.len()).map(|i| c.spheres.reading(i)).collect();
    let poses = PreparedPoses::new(6, &rows).unwrap();
    let mut xyz = vec![[0.0; 3]; rows.len()];
    let kernel = ArmKernel::new(&cal.params).unwrap();
    kernel.positions(&poses, 0..rows.len(), &mut xyz).unwrap();
    let measured = Measured {
        points: SpherePoints {
            rows: &c.spheres,
            file: "spheres.csv",
            centres: &xyz,
        },
        poses: &poses,
        lengths: Some((&c.lengths, "bar.csv")),
    };
    let mut a = verify(&settings(), measured.points, measured.lengths, None).unwrap();
    let (free, covariance) = cal.geometry_covariance().unwrap();
    let calibrated = Calibrated {
        params: &cal.params,
        free: &free,
        covariance: &covariance,
        noise: ReadingNoise::of_calibration(&report.noise, cal.dof.touch_sigma_mm),
    };
    let draws = Draws {
        count: draws,
        seed: 1,
        threads: 2,
    };
    predict(&mut a, &settings(), measured, calibrated, draws, "cal").unwrap();
    a
}

/// Seeds of the agreement count: `AACMM_ACCEPTANCE_SEEDS` (50–200 for the
/// release measurement), 3 by default.
fn seeds() -> u64 {
    std::env::var("AACMM_ACCEPTANCE_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3)
}

#[test]
fn measured_figures_lie_within_the_predicted_spread() {
    let n = seeds();
    let draws = if n > 10 { 200 } else { 60 };
    let (mut within, mut tests, mut seeds_all_within) = (0, 0, 0);
    let mut by_kind: std::collections::BTreeMap<TestKind, (usize, usize)> = Default::default();
    for seed in 0..n {
        let truth = truth(seed);
        let report = calibrate(&truth, 12, seed + 1000);
        assert!(report.is_usable(), "seed {seed}: {:?}", report.verdict);
        let a = verified(&report, &acceptance_campaign(&truth, seed + 2000), draws);
        let judged: Vec<_> = (a.tests.iter())
            .filter_map(|t| t.predicted.map(|p| (t, p)))
            .collect();
        assert_eq!(judged.len(), a.tests.len(), "every test predicted");
        let ok = judged.iter().filter(|(_, p)| p.agrees).count();
        for (t, p) in &judged {
            let e = by_kind.entry(t.test).or_default();
            e.0 += usize::from(p.agrees);
            e.1 += 1;
            if !p.agrees {
                eprintln!(
                    "seed {seed}: {} at {}: {:.4} against {:.4} ± {:.4}",
                    t.figure, t.at, t.value, p.value, p.spread
                );
            }
        }
        within += ok;
        tests += judged.len();
        seeds_all_within += usize::from(ok == judged.len());
    }
    let share = within as f64 / tests as f64;
    eprintln!(
        "{n} seeds, {draws} draws: {within} of {tests} figures within 2 spreads ({:.1} %); every \
         figure within in {seeds_all_within} seeds; per test {by_kind:?}",
        100.0 * share
    );
    // A spread that holds its promise: 2σ covers some 95 % of Gaussian
    // figures; ≥ 90 % of them, over every test of every seed. Each kind of
    // test on its own, where there are enough to count (50 seeds or more):
    // its count consistent with 95 % coverage — no more than 3 binomial σ
    // below it (a count of 100 at 95 % scatters by 2.2 %).
    assert!(share >= 0.9, "{within} of {tests}");
    if n >= 50 {
        for (kind, (ok, all)) in &by_kind {
            let expected = 0.95 * *all as f64;
            let sigma = (expected * 0.05).sqrt();
            assert!(
                *ok as f64 >= expected - 3.0 * sigma,
                "{kind:?}: {ok} of {all}"
            );
        }
    }
}

#[test]
fn fewer_placements_in_the_calibration_predict_a_wider_spread() {
    let truth = truth(7);
    let c = acceptance_campaign(&truth, 77);
    let spread = |placements: usize| {
        let a = verified(&calibrate(&truth, placements, 700), &c, 60);
        let of = |kind: TestKind| -> f64 {
            (a.tests.iter())
                .filter(|t| t.test == kind)
                .map(|t| t.predicted.unwrap().spread)
                .sum()
        };
        (of(TestKind::EUni), of(TestKind::LDia))
    };
    let (few, many) = (spread(5), spread(24));
    eprintln!("E_Uni and L_Dia spreads: 5 placements {few:?}, 24 placements {many:?}");
    assert!(few.0 > 1.2 * many.0, "E_Uni {few:?} {many:?}");
    assert!(few.1 > many.1, "L_Dia {few:?} {many:?}");
}

/// `simulate` and `calibrate` of the shipped arm into `dir`: the true
/// arm's sphere files, and the calibration from touches and lengths in
/// `dir/cal` whose calibrated.toml states the probe ball.
fn calibrated_on_disk(dir: &std::path::Path) -> (String, String) {
    let out = dir.display().to_string();
    let arm = crate::util::shipped_arm();
    let mut sim = vec![
        "simulate",
        "--arm",
        &arm,
        "--errors",
        "paper",
        "--spheres",
        "2",
        "--articulated",
        "1",
    ];
    sim.extend([
        "--ball-bar",
        "2",
        "--sockets",
        "6",
        "--poses",
        "10",
        "--seed",
        "3",
        "--encoder-noise",
        "0.002",
        "--probe-noise",
        "0.005",
        "--out",
        &out,
    ]);
    let o = aacmm(&sim);
    assert!(o.status.success(), "{}", stderr(&o));
    let cal = dir.join("cal").display().to_string();
    let poses = dir.join("poses.csv").display().to_string();
    let lengths = dir.join("lengths.csv").display().to_string();
    let o = aacmm(&[
        "calibrate",
        "--arm",
        &arm,
        "--data",
        &poses,
        "--lengths",
        &lengths,
        "--encoder-noise",
        "0.002",
        "--probe-noise",
        "0.005",
        "--out",
        &cal,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let toml = dir.join("cal/calibrated.toml");
    let text = std::fs::read_to_string(&toml).unwrap();
    let text = text.replacen("[probe]\n", "[probe]\nball_diameter_mm = 6\n", 1);
    std::fs::write(&toml, text).unwrap();
    (toml.display().to_string(), cal)
}

#[test]
fn the_command_predicts_the_same_bytes_and_refuses_what_predicts_nothing() {
    let dir = temp_dir("verify-predict");
    let (arm, cal) = calibrated_on_disk(&dir);
    let spheres = dir.join("spheres.csv").display().to_string();
    let bar = dir.join("bar_lengths.csv").display().to_string();
    let base = [
        "verify",
        "--arm",
        &arm,
        "--spheres",
        &spheres,
        "--sphere-diameter",
        "25.4",
        "--lengths",
        &bar,
    ];
    let json = |name: &str, extra: &[&str]| {
        let path = dir.join(name);
        let p = path.display().to_string();
        let mut args = base.to_vec();
        args.extend(["--calibration", &cal, "--draws", "50", "--json", &p]);
        args.extend(extra);
        let o = aacmm(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        (crate::util::stdout(&o), std::fs::read(&path).unwrap())
    };
    let (printed, a) = json("a.json", &["--seed", "5"]);
    let (_, b) = json("b.json", &["--seed", "5"]);
    let (_, c) = json("c.json", &["--seed", "6"]);
    assert_eq!(a, b, "the same seed, the same bytes");
    assert_ne!(a, c, "another seed, other draws");
    assert!(printed.contains("predicted (mm)"), "{printed}");
    assert!(
        printed.contains("measured values within 2 spreads"),
        "{printed}"
    );
    let back: Acceptance = serde_json::from_slice(&a).unwrap();
    assert_eq!(back.prediction.as_ref().unwrap().draws, 50);
    assert!((back.tests.iter()).all(|t| t.predicted.is_some_and(|p| p.spread > 0.0)));
    // Without --calibration: no column, no note, no prediction in the JSON.
    let plain = aacmm(&base);
    assert!(plain.status.success());
    let text = crate::util::stdout(&plain);
    assert!(
        !text.contains("predicted") && !text.contains("spreads"),
        "{text}"
    );
    // The true arm's file is not the calibration's arm.
    let truth = dir.join("true_arm.toml").display().to_string();
    let mut wrong = base.to_vec();
    wrong[2] = &truth;
    wrong.extend(["--calibration", &cal]);
    let e = stderr(&aacmm(&wrong));
    assert!(
        e.contains("calibration.json is not this arm file's calibration"),
        "{e}"
    );
    // A free parameter's σ unknown: no covariance to draw from.
    let report = dir.join("cal/calibration.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let free = (v["calibration"]["parameters"]
        .as_array_mut()
        .unwrap()
        .iter_mut())
    .find(|p| p["fixed"].is_null())
    .unwrap();
    free["sigma"] = serde_json::Value::Null;
    let unknown = dir.join("unknown");
    std::fs::create_dir_all(&unknown).unwrap();
    std::fs::write(unknown.join("calibration.json"), v.to_string()).unwrap();
    let u = unknown.display().to_string();
    let mut args = base.to_vec();
    args.extend(["--calibration", &u]);
    let e = stderr(&aacmm(&args));
    assert!(e.contains("covariance is unknown"), "{e}");
    // A calibration not usable.
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    v["verdict"]["usable"] = serde_json::Value::Bool(false);
    std::fs::write(unknown.join("calibration.json"), v.to_string()).unwrap();
    let e = stderr(&aacmm(&args));
    assert!(e.contains("the calibration is not usable"), "{e}");
    // Too few draws, through the setting's flag.
    let mut args = base.to_vec();
    args.extend(["--calibration", &cal, "--draws", "1"]);
    let e = stderr(&aacmm(&args));
    assert!(e.contains("--draws 1"), "{e}");
}
