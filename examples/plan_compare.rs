//! Does the plan beat random poses and greedy D-optimality? Simulated with a
//! known truth: for each case (touches or positions; 6 or 7 joints; a true
//! arm the fitted model explains, or one with a joint compliance it lacks)
//! and each seed, a pool of candidates is measured on the true arm; `K` of
//! them are chosen by the plan (robust criterion), by greedy D-optimality
//! and at random (10 subsets), each set is calibrated with the session
//! `aacmm calibrate` runs, and the calibrated arm is scored on held-out
//! poses: the RMS distance between its probe positions and the true arm's
//! (compliance included), after the best rigid registration — the arm's
//! error where it will be used, without the instrument's noise.
//!
//! ```text
//! cargo run --release --example plan_compare -- [SEEDS] [CASE-FILTER]
//! cargo run --release --example plan_compare -- ur5
//! ```
//!
//! `ur5`: the shipped laser-tracker data of a UR5 instead — the 1000 grid
//! poses the pool, the 20 random poses the test, the score their mean 3-D
//! error `|R p + t − y|` in the tracker's frame fitted with the arm.
//!
//! Prints one line per case and K: the medians over seeds of the held-out
//! error for the plan, D-optimal and the median random subset, and in how
//! many seeds the plan was no worse than each (within 2 %).

use std::path::Path;

use aacmm_core::calibrate::{Method, ModelOptions, SolverSettings};
use aacmm_core::dataset::DataSet;
use aacmm_core::domain::{Arm, Poses, Positions};
use aacmm_core::io::read_arm;
use aacmm_core::plan::{Criterion, Measure, PlanSettings, plan};
use aacmm_core::residuals::Noise;
use aacmm_core::residuals::positions::register;
use aacmm_core::session::Problem;
use aacmm_core::simulate::{
    CampaignSettings, ErrorModel, PositionSettings, simulate, simulate_positions, true_arm,
};
use anyhow::{Context as _, Result, bail};
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;

/// Joint compliance of the unmodelled cases, rad/(N·m) on joints 2 and 3.
const COMPLIANCE: f64 = 4e-6;
const KS: [usize; 3] = [30, 50, 100];
const RANDOM_SETS: usize = 10;
const POOL: usize = 1000;
const TEST: usize = 300;

struct Case {
    name: String,
    measure: Measure,
    nominal: Arm,
    unmodelled: bool,
}

/// A seed's pool, its measured data, and the truth.
struct World {
    truth: Arm,
    pool: Poses,
    /// Positions: the pool's measured rows; touches: the campaign.
    positions: Option<Positions>,
    lengths: Vec<aacmm_core::domain::ReferenceLength>,
}

fn arm(path: &str) -> Result<Arm> {
    Ok(read_arm(Path::new(path))
        .with_context(|| path.to_string())?
        .0)
}

fn cases(filter: &str) -> Result<Vec<Case>> {
    let ur5 = arm("examples/ur5-tracker/arm.toml")?;
    let panda = arm("examples/mukca/panda-1/arm.toml")?;
    let mut paper = arm("examples/paper-table-1.toml")?;
    // The paper's arm states no masses: a measuring arm's links weigh about
    // a kilogram, its probe a fifth.
    let n = paper.params.joint_count();
    paper.physics.link_masses = vec![
        Some(aacmm_core::corrections::Mass {
            kg: 1.0,
            com_mm: None
        });
        n
    ];
    let mut out = Vec::new();
    for (measure, six, seven) in [
        (Measure::Positions, &ur5, &panda),
        (Measure::Touches, &paper, &panda),
    ] {
        for nominal in [six, seven] {
            for unmodelled in [false, true] {
                let name = format!(
                    "{:?} {}j {}",
                    measure,
                    nominal.params.joint_count(),
                    if unmodelled {
                        "compliance"
                    } else {
                        "geometric"
                    }
                )
                .to_lowercase();
                if name.contains(filter) {
                    out.push(Case {
                        name,
                        measure,
                        nominal: nominal.clone(),
                        unmodelled,
                    });
                }
            }
        }
    }
    Ok(out)
}

/// The true arm of `seed`, with the unmodelled compliance if asked.
fn truth_of(case: &Case, seed: u64) -> Result<Arm> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut truth = true_arm(&case.nominal, &ErrorModel::random(1.0, false), &mut rng)?;
    truth.physics.compliance = vec![None; truth.params.joint_count()];
    if case.unmodelled {
        truth.physics.compliance[1] = Some(COMPLIANCE);
        truth.physics.compliance[2] = Some(COMPLIANCE);
    }
    Ok(truth)
}

fn world(case: &Case, seed: u64) -> Result<World> {
    let truth = truth_of(case, seed)?;
    let n = truth.params.joint_count();
    match case.measure {
        Measure::Positions => {
            let noise = Noise {
                position_mm: Some(0.01),
                position_mm_per_m: Some(0.0),
                ..Noise::default()
            };
            let s = PositionSettings {
                poses: POOL,
                frames: 1,
                noise,
                seed: seed + 1000,
            };
            let c = simulate_positions(&truth, &s)?;
            let mut pool = Poses::new(n);
            for i in 0..c.positions.len() {
                pool.push(&format!("P{}", i + 1), c.positions.reading(i), i + 2);
            }
            Ok(World {
                truth,
                pool,
                positions: Some(c.positions),
                lengths: Vec::new(),
            })
        }
        Measure::Touches => {
            let mut s = CampaignSettings::new(
                seed + 1000,
                ErrorModel::File { arm: truth.clone() },
                10,
                POOL / 10,
            );
            s.probe_noise_mm = 0.01;
            s.encoder_noise_deg = 0.0005;
            s.reference_lengths = 10;
            s.length_uncertainty_mm = Some(0.001);
            s.min_pose_separation_deg = 2.0;
            let c = simulate(&case.nominal, &s)?;
            Ok(World {
                truth,
                pool: c.poses,
                positions: None,
                lengths: c.lengths,
            })
        }
        other => bail!("plan_compare compares positions and touches, not {other:?}"),
    }
}

/// The data set of the pool rows `rows`: positions as measured, touches of
/// sockets touched at least three times (fewer is refused) with the lengths between them.
fn subset(world: &World, rows: &[usize]) -> Result<DataSet> {
    let n = world.pool.joints();
    if let Some(p) = &world.positions {
        return Ok(DataSet::from_positions(p.subset(rows), "pool")?);
    }
    let count = |l: &str| rows.iter().filter(|&&i| world.pool.label(i) == l).count();
    let mut poses = Poses::new(n);
    for &i in rows {
        if count(world.pool.label(i)) >= 3 {
            poses.push(world.pool.label(i), world.pool.reading(i), i + 2);
        }
    }
    let lengths: Vec<_> = world
        .lengths
        .iter()
        .filter(|l| count(&l.a) >= 3 && count(&l.b) >= 3)
        .cloned()
        .collect();
    let data = DataSet::from_poses(&poses, "pool")?;
    Ok(if lengths.is_empty() {
        data
    } else {
        data.with_lengths(&lengths, "lengths")?
    })
}

/// The calibrated arm's held-out error (mm), or `None` when it failed.
fn score(case: &Case, world: &World, rows: &[usize], test: &Positions) -> Option<f64> {
    let debug = std::env::var("PLAN_DEBUG").is_ok();
    let say = |e: String| {
        if debug {
            eprintln!("{}: {e}", case.name);
        }
    };
    let data = subset(world, rows).map_err(|e| say(e.to_string())).ok()?;
    let problem = Problem::new(case.nominal.clone(), data, ModelOptions::default())
        .map_err(|e| say(e.to_string()))
        .ok()?;
    let settings = SolverSettings {
        method: Method::Lm,
        ..SolverSettings::default()
    };
    let report = problem
        .run(&settings)
        .map_err(|e| say(e.to_string()))
        .ok()?;
    let data = DataSet::from_positions(test.clone(), "test").ok()?;
    let reg = register(&report.calibration.params, data.positions()?).ok()?;
    Some(reg[0].rms_mm)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        f64::NAN
    } else {
        v[v.len() / 2]
    }
}

/// The UR5 comparison on real data.
fn ur5() -> Result<()> {
    use aacmm_core::io::{AngleUnit, read_positions};
    use aacmm_core::residuals::Frame;
    let nominal = arm("examples/ur5-tracker/arm.toml")?;
    let read = |f: &str| read_positions(Path::new(f), AngleUnit::Deg, Some(6));
    let grid = read("examples/ur5-tracker/positions-grid.csv")?;
    let test = read("examples/ur5-tracker/positions-random.csv")?;
    let mut pool = Poses::new(6);
    for i in 0..grid.len() {
        pool.push(grid.label(i), grid.reading(i), i + 2);
    }
    // Both scores: the 20 random poses, and the grid poses not chosen.
    let score = |rows: &[usize]| -> Option<[f64; 2]> {
        let data = DataSet::from_positions(grid.subset(rows), "grid").ok()?;
        let settings = SolverSettings {
            method: Method::Lm,
            ..SolverSettings::default()
        };
        let report = Problem::new(nominal.clone(), data, ModelOptions::default())
            .ok()?
            .run(&settings)
            .ok()?;
        let c = &report.calibration;
        let frame = c.frames().first()?.1;
        let k = aacmm_core::kernel::ArmKernel::new(&c.params).ok()?;
        let error = |set: &Positions, i: usize| {
            let p = Frame::apply(&frame, k.position(set.reading(i)).unwrap_or([f64::NAN; 3]));
            let y = set.position(i);
            (0..3).map(|a| (p[a] - y[a]).powi(2)).sum::<f64>().sqrt()
        };
        let e = (0..test.len()).map(|i| error(&test, i)).sum::<f64>() / test.len() as f64;
        let rest: Vec<usize> = (0..grid.len()).filter(|i| !rows.contains(i)).collect();
        let r = rest.iter().map(|&i| error(&grid, i)).sum::<f64>() / rest.len().max(1) as f64;
        (e.is_finite() && r.is_finite()).then_some([e, r])
    };
    let all: Vec<usize> = (0..pool.len()).collect();
    let whole = score(&all).unwrap_or([f64::NAN; 2]);
    println!(
        "UR5 tracker data: all {} grid poses → held-out mean error {:.4} mm",
        pool.len(),
        whole[0]
    );
    println!(
        "mean 3-D error, mm, on the 20 random poses | on the grid poses not chosen \
         (plan: median over 10 seeds of its strata; random: median of 10 subsets)"
    );
    println!("  K   plan            free I          D-opt           random");
    let hedge: f64 = std::env::var("PLAN_HEDGE").map_or(Ok(0.0), |s| s.parse())?;
    let both = |v: &mut Vec<[f64; 2]>| {
        let mut a: Vec<f64> = v.iter().map(|x| x[0]).collect();
        let mut b: Vec<f64> = v.iter().map(|x| x[1]).collect();
        format!("{:.4} | {:.4}", median(&mut a), median(&mut b))
    };
    for k in KS {
        let mut s = PlanSettings::new(k, Measure::Positions);
        s.random_sets = 0;
        s.curve_to = k;
        s.hedge = hedge;
        let mut planned: Vec<[f64; 2]> = (1..=10)
            .filter_map(|seed| {
                s.seed = seed;
                score(&plan(&nominal.params, &pool, None, None, &s).ok()?.chosen())
            })
            .collect();
        s.criterion = Criterion::Prediction;
        let i = score(&plan(&nominal.params, &pool, None, None, &s)?.chosen());
        s.criterion = Criterion::Determinant;
        let d = score(&plan(&nominal.params, &pool, None, None, &s)?.chosen());
        let mut rng = ChaCha8Rng::seed_from_u64(k as u64);
        let mut rows = all.clone();
        let mut random: Vec<[f64; 2]> = (0..RANDOM_SETS)
            .filter_map(|_| {
                rows.shuffle(&mut rng);
                score(&rows[..k])
            })
            .collect();
        println!(
            "{k:>3}  {}  {}  {}  {}",
            both(&mut planned),
            both(&mut i.into_iter().collect()),
            both(&mut d.into_iter().collect()),
            both(&mut random)
        );
    }
    Ok(())
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).is_some_and(|a| a == "ur5") {
        return ur5();
    }
    let seeds: u64 = args.get(1).map_or(Ok(20), |s| s.parse())?;
    let filter = args.get(2).cloned().unwrap_or_default();
    let hedge: f64 = std::env::var("PLAN_HEDGE").map_or(Ok(0.0), |s| s.parse())?;
    let cases = cases(&filter)?;
    if cases.is_empty() {
        bail!("no case matches `{filter}`");
    }
    println!(
        "case                        K  plan    D-opt   random   (median held-out RMS, mm; median \
         per-seed ratios plan/D, plan/random; seeds where the plan is within 2 % or better)"
    );
    for case in &cases {
        // [K][method] per seed.
        let mut results = vec![vec![Vec::new(); 3]; KS.len()];
        for seed in 0..seeds {
            let world = world(case, seed)?;
            // Held-out: the true arm (compliance included), noise-free.
            let test = simulate_positions(
                &world.truth,
                &PositionSettings {
                    poses: TEST,
                    frames: 1,
                    noise: Noise {
                        position_mm: Some(0.0),
                        ..Noise::default()
                    },
                    seed: seed + 5000,
                },
            )?
            .positions;
            for (ki, &k) in KS.iter().enumerate() {
                let mut s = PlanSettings::new(k, case.measure);
                s.random_sets = 0;
                s.curve_to = k;
                s.hedge = hedge;
                let planned = plan(&case.nominal.params, &world.pool, None, None, &s)?;
                s.criterion = Criterion::Determinant;
                let d = plan(&case.nominal.params, &world.pool, None, None, &s)?;
                let mut rng = ChaCha8Rng::seed_from_u64(seed * 7 + k as u64);
                let mut all: Vec<usize> = (0..world.pool.len()).collect();
                let mut random: Vec<f64> = (0..RANDOM_SETS)
                    .map(|_| {
                        all.shuffle(&mut rng);
                        score(case, &world, &all[..k], &test).unwrap_or(f64::INFINITY)
                    })
                    .collect();
                let p = score(case, &world, &planned.chosen(), &test).unwrap_or(f64::INFINITY);
                let dd = score(case, &world, &d.chosen(), &test).unwrap_or(f64::INFINITY);
                results[ki][0].push(p);
                results[ki][1].push(dd);
                results[ki][2].push(median(&mut random));
            }
        }
        for (ki, &k) in KS.iter().enumerate() {
            let r = &results[ki];
            let no_worse = |other: usize| {
                (0..r[0].len())
                    .filter(|&s| r[0][s] <= 1.02 * r[other][s])
                    .count()
            };
            let (a, b) = (no_worse(1), no_worse(2));
            let m: Vec<f64> = r.iter().map(|v| median(&mut v.clone())).collect();
            let ratio = |other: usize| {
                let mut v: Vec<f64> = (0..r[0].len()).map(|s| r[0][s] / r[other][s]).collect();
                median(&mut v)
            };
            println!(
                "{:<25} {:>3}  {:.4}  {:.4}  {:.4}   {:.3}  {:.3}   {:>2}/{}     {:>2}/{}",
                case.name,
                k,
                m[0],
                m[1],
                m[2],
                ratio(1),
                ratio(2),
                a,
                seeds,
                b,
                seeds
            );
        }
    }
    Ok(())
}
