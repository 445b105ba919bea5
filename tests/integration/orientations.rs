//! Tool poses: simulated 6-D campaigns (a tracker's 6-D target: position
//! and orientation per row) recovered honestly, and compared with the same
//! poses' positions alone.

use aacmm_core::calibrate::validate::{orientation_errors, position_errors};
use aacmm_core::io::Arm;
use aacmm_core::residuals::Noise;
use aacmm_core::simulate::{orient_positions, random_arm, simulate_positions_from};
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
    let sigma = ORIENTATION_DEG.to_radians();
    let with = orient_positions(&truth, &c.positions, &c.frames, sigma, seed + 2000).unwrap();
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
    let fresh = orient_positions(&truth, &fresh, &c.frames, sigma, seed + 6000).unwrap();
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
    Seed {
        z2: normalised_errors(&six, &truth, &c),
        position: [mean(&six), mean(&three)],
        orientation: [
            turned(&six.params, &six.frames()),
            turned(&truth.params, &c.frames),
        ],
    }
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
