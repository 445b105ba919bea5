//! The solver comparison of the README: `lm`, `sa`, `hybrid` and `global`
//! over simulated campaigns with a known true arm.
//!
//! ```text
//! cargo run --release --example compare_methods -- [SEEDS] [CASES] [METHODS]
//! cargo run --release --example compare_methods -- 100 paper,random3,assembled,assembled3 lm,sa,hybrid,hybrid@180,global
//! ```
//!
//! Without arguments it prints the README's table: the second line's
//! [`DEFAULT_SEEDS`], [`DEFAULT_CASES`] and [`DEFAULT_METHODS`].
//!
//! Each campaign: the paper's nominal arm, 10 sockets × 10 touches, 3
//! reference lengths, encoder noise 0.005°, probe noise 0.01 mm (stated to
//! the solver). A calibration succeeds when its single-point repeatability
//! `e` on 10 fresh sockets of the same true arm is within 8 % of the true
//! arm's own (a perfect fit sits about 4 % above it: the fit's own noise).
//! It reached the global minimum when its weighted cost is no higher than
//! the true arm's (weights at the calibrated arm): a wrong basin costs
//! orders of magnitude more, so this tells search failures from the
//! estimator's own scatter on held-out data.
//! Times are wall times of `calibrate` on one thread, validation excluded.

use std::time::Instant;

use aacmm_core::calibrate::{Method, ModelOptions, SolverSettings, calibrate, validate};
use aacmm_core::domain::Arm;
use aacmm_core::objective::weighted_cost;
use aacmm_core::params::DhParams;
use aacmm_core::residuals::Noise;
use aacmm_core::simulate::{CampaignSettings, ErrorModel, simulate};

/// Campaigns per case when no argument says otherwise.
const DEFAULT_SEEDS: u64 = 100;
/// The README's cases, in its order.
const DEFAULT_CASES: &str = "paper,random3,assembled,assembled3";
/// The README's methods, in its order (`hybrid@180`: with a 180° zero range).
const DEFAULT_METHODS: &str = "lm,sa,hybrid,hybrid@180,global";

const ENCODER_DEG: f64 = 0.005;
const PROBE_MM: f64 = 0.01;
/// Success: held-out `e` at most this times the true arm's.
const SUCCESS_RATIO: f64 = 1.08;

fn settings(seed: u64, errors: ErrorModel) -> CampaignSettings {
    let mut s = CampaignSettings::new(seed, errors, 10, 10);
    s.reference_lengths = 3;
    s.encoder_noise_deg = ENCODER_DEG;
    s.probe_noise_mm = PROBE_MM;
    s
}

fn case(name: &str) -> Option<ErrorModel> {
    match name {
        "paper" => Some(ErrorModel::Paper),
        "random3" => Some(ErrorModel::random(3.0, false)),
        "assembled" => Some(ErrorModel::random(1.0, true)),
        "assembled3" => Some(ErrorModel::random(3.0, true)),
        _ => None,
    }
}

fn describe(name: &str) -> &'static str {
    match name {
        "paper" => "`--errors paper`",
        "random3" => "`--errors random --error-scale 3`",
        "assembled3" => "`--errors assembled --error-scale 3`",
        _ => "`--errors assembled`",
    }
}

#[derive(Default)]
struct Tally {
    ok: usize,
    global_minimum: usize,
    runs: usize,
    ms: Vec<f64>,
    evaluations: Vec<f64>,
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let seeds: u64 = args.first().map_or(Ok(DEFAULT_SEEDS), |s| s.parse())?;
    let cases: Vec<String> = args
        .get(1)
        .map_or(DEFAULT_CASES, String::as_str)
        .split(',')
        .map(str::to_string)
        .collect();
    // `hybrid@180`: the method with the annealing's zero-offset range set
    // to 180° (the default 2° suits the paper's small errors).
    let methods: Vec<(Method, Option<f64>, String)> = args
        .get(2)
        .map_or(DEFAULT_METHODS, String::as_str)
        .split(',')
        .map(|m| {
            let (name, range) = m.split_once('@').map_or((m, None), |(n, r)| (n, Some(r)));
            let method = Method::parse(name).ok_or(format!("unknown method `{m}`"))?;
            let range = range
                .map(|r| r.parse::<f64>().map_err(|e| format!("`{m}`: {e}")))
                .transpose()?;
            let label = match range {
                Some(r) => format!("`{name}`, zero range {r}°"),
                None => format!("`{name}`"),
            };
            Ok::<_, String>((method, range, label))
        })
        .collect::<Result<_, _>>()?;
    let nominal = Arm::without_limits("paper-table-1", DhParams::paper_nominal());
    let noise = Noise {
        encoder_rad: Some(ENCODER_DEG.to_radians()),
        probe_mm: Some(PROBE_MM),
        ..Noise::default()
    };
    println!(
        "| case | method | success (held-out e ≤ 1.08 × true) | global minimum (cost ≤ true arm's) | median time | max time | median evaluations (cost + Jacobian) |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|");
    for name in &cases {
        let errors = case(name).ok_or(format!("unknown case `{name}`"))?;
        let mut tallies: Vec<Tally> = methods.iter().map(|_| Tally::default()).collect();
        for seed in 0..seeds {
            let campaign = simulate(&nominal, &settings(1 + seed, errors.clone()))?;
            let data = campaign.data_set()?;
            let fresh_arm = ErrorModel::File {
                arm: campaign.true_arm.clone(),
            };
            let fresh = simulate(&nominal, &settings(1_000_000 + seed, fresh_arm))?.data_set()?;
            let truth = validate::figures(&campaign.true_arm.params, &fresh)?.e_mean;
            for ((method, range, label), tally) in methods.iter().zip(&mut tallies) {
                let model = ModelOptions {
                    noise,
                    ..ModelOptions::default()
                };
                let mut options = SolverSettings {
                    method: *method,
                    threads: 1,
                    seed,
                    ..SolverSettings::default()
                };
                if let Some(r) = range {
                    options.anneal.zero_step_deg = *r;
                }
                if let Some(cells) = std::env::var("COMPARE_GRID_CELLS")
                    .ok()
                    .and_then(|v| v.parse().ok())
                {
                    options.global.grid_cells = cells;
                }
                let started = Instant::now();
                let result = calibrate(&nominal.params, &data, &model, &options);
                let ms = started.elapsed().as_secs_f64() * 1e3;
                tally.runs += 1;
                tally.ms.push(ms);
                let Ok(cal) = result else { continue };
                tally
                    .evaluations
                    .push((cal.solver.cost_evaluations + cal.solver.jacobian_evaluations) as f64);
                // Both arms under the weights at the fit.
                let fit_cost = weighted_cost(&cal.params, &cal.params, &data, &noise)?;
                let true_cost =
                    weighted_cost(&campaign.true_arm.params, &cal.params, &data, &noise)?;
                if fit_cost <= true_cost * (1.0 + 1e-6) {
                    tally.global_minimum += 1;
                }
                let e = validate::figures(&cal.params, &fresh)?.e_mean;
                if e <= SUCCESS_RATIO * truth {
                    tally.ok += 1;
                } else if std::env::var_os("COMPARE_VERBOSE").is_some() {
                    eprintln!(
                        "{name} seed {seed} {}: held-out e {e:.4} vs true {truth:.4}",
                        label
                    );
                }
            }
        }
        for ((_, _, label), t) in methods.iter().zip(&mut tallies) {
            let max = t.ms.iter().copied().fold(0.0, f64::max);
            println!(
                "| {} | {} | {}/{} | {}/{} | {:.1} ms | {:.1} ms | {:.0} |",
                describe(name),
                label,
                t.ok,
                t.runs,
                t.global_minimum,
                t.runs,
                median(&mut t.ms),
                max,
                median(&mut t.evaluations)
            );
        }
    }
    Ok(())
}
