//! Calibration speed on simulated campaigns (the paper's arm, 0.005° encoder
//! and 0.01 mm probe noise, stated to the solver; one thread):
//!
//! - `calibrate-lm`: the whole `calibrate()` with `--method lm` (before
//!   2026-11-29 its id was `lm/N`, which the history in the README
//!   continues) from nominal on the paper's errors with the fixed set of
//!   method.md §8.1 given (no identifiability analysis):
//!   `calibrate-lm/100` and `calibrate-lm/10000` touches, and with
//!   `AACMM_BENCH_LARGE=1` also `/100000` and `/1000000` (1000 sockets ×
//!   1000 touches, `simulate`'s largest: its campaign takes about a minute
//!   to simulate, once per process, and only when that bench runs): the
//!   problem of the Ceres anchors (benches/compare);
//! - `lm-solve`: the same problems' LM alone — the normal equations at the
//!   start and the iterations from there, as weighed at the start — timed
//!   inside `calibrate_with` by a solver that runs the library's LM (what
//!   Ceres' `Solve` does; none of the statistics after it);
//! - `global`: `--method global` on a newly assembled arm (zeros anywhere in
//!   ±180°) whose LM from nominal fails, 100 touches;
//! - `energy`: annealing energy evaluations (position kernel + the paper's
//!   OA) per second, 100 touches;
//! - `calibrate-positions` (before 2026-11-29 `positions`): a laser-tracker
//!   calibration — the shipped UR5's arm file (two Hayati joints), random
//!   errors, one tracker frame seeing 1000 or 12000 poses with 15 µm +
//!   6 µm/m noise (stated): LM from nominal with the identifiability
//!   analysis (`--fix auto`), frame and covariance, `/1000` and `/12000`;
//!   `positions-solve`: their LM alone, as `lm-solve`;
//! - `beyond`: the models beyond geometry switched on, each against the
//!   same problem without it — `lm-100` (the `calibrate-lm/100` campaign and
//!   fit with link masses stated, nothing switched on), `compliance-100`
//!   (`--compliance 2,3`), `harmonics-100` (`--harmonics 2:1,3:1`); and the
//!   UR5 tracker's 1000 poses with temperatures and times, `positions-1000`
//!   without and `thermal-drift-1000` with `--thermal --drift`;
//! - `threads`: the UR5 tracker example as the README runs it (its 1000
//!   measured positions, `global`, `--fix auto`, noise estimated) on one
//!   thread and on the default threads, `idle` and `loaded` (two busy
//!   processes, `sh -c 'while :; do :; done'`, started for the bench and
//!   ended after it): the default threads may cost no more than one
//!   thread's time (1.1×), loaded or not;
//! - `plan`: experiment design — 100 of 2000 candidate poses of the UR5
//!   for a tracker (`positions-100-of-2000`, the robust criterion with its
//!   exchanges, no random baseline or curve beyond the count), and 60 of
//!   1000 touches of 10 sockets of the paper's arm (`touches-60-of-1000`).

use std::hint::black_box;

use aacmm_core::calibrate::energy::Energy;
use aacmm_core::calibrate::{
    CalibrationError, Context, FixSpec, Lm, Method, ModelOptions, Outcome, Solver, SolverSettings,
    Task, calibrate,
};
use aacmm_core::dataset::DataSet;
use aacmm_core::domain::Arm;
use aacmm_core::kernel::ArmKernel;
use aacmm_core::params::DhParams;
use aacmm_core::residuals::{Noise, Normal};
use aacmm_core::simulate::{CampaignSettings, ErrorModel, simulate};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

const UNOBSERVABLE: &str = "theta1,d1,theta6,alpha6,Bx,By";

fn nominal() -> Arm {
    Arm::without_limits("paper-table-1", DhParams::paper_nominal())
}

fn campaign(seed: u64, errors: ErrorModel, sockets: usize, touches: usize) -> DataSet {
    let mut s = CampaignSettings::new(seed, errors, sockets, touches);
    s.reference_lengths = 3;
    s.encoder_noise_deg = 0.005;
    s.probe_noise_mm = 0.01;
    simulate(&nominal(), &s)
        .expect("campaign")
        .data_set()
        .expect("data set")
}

/// The model (stated noise, `fix`) and `method` on one thread.
fn options(method: Method, fix: FixSpec) -> (ModelOptions, SolverSettings) {
    let model = ModelOptions {
        fix,
        noise: Noise {
            encoder_rad: Some(0.005f64.to_radians()),
            probe_mm: Some(0.01),
            ..Noise::default()
        },
        ..ModelOptions::default()
    };
    let settings = SolverSettings {
        method,
        threads: 1,
        ..SolverSettings::default()
    };
    (model, settings)
}

/// (sockets, touches per socket) of `calibrate-lm` and `lm-solve`: the
/// bench id is their product.
fn lm_sizes() -> Vec<(usize, usize)> {
    let mut sizes = vec![(10, 10), (100, 100)];
    if std::env::var_os("AACMM_BENCH_LARGE").is_some() {
        sizes.extend([(1000, 100), (1000, 1000)]);
    }
    sizes
}

fn lm(c: &mut Criterion) {
    let start = nominal().params;
    let (model, settings) = options(Method::Lm, FixSpec::parse(UNOBSERVABLE, 6).expect("names"));
    let mut g = c.benchmark_group("calibrate-lm");
    g.sample_size(10);
    let mut solve = Vec::new();
    for (sockets, touches) in lm_sizes() {
        // Simulated when the bench runs (not when a filter skips it), once.
        let data = std::sync::OnceLock::new();
        g.throughput(Throughput::Elements((sockets * touches) as u64));
        g.bench_function(BenchmarkId::from_parameter(sockets * touches), |b| {
            let data = data.get_or_init(|| campaign(7, ErrorModel::Paper, sockets, touches));
            b.iter(|| {
                calibrate(black_box(&start), black_box(data), &model, &settings).expect("fit")
            })
        });
        solve.push((sockets, touches, data));
    }
    g.finish();
    let mut g = c.benchmark_group("lm-solve");
    g.sample_size(10);
    for (sockets, touches, data) in solve {
        g.throughput(Throughput::Elements((sockets * touches) as u64));
        g.bench_function(BenchmarkId::from_parameter(sockets * touches), |b| {
            let data = data.get_or_init(|| campaign(7, ErrorModel::Paper, sockets, touches));
            let arm = Arm::without_limits("paper-table-1", start.clone());
            b.iter_custom(|iters| solve_only(&arm, data, &model, &settings, iters))
        });
    }
    g.finish();
}

/// A solver that times the library's LM alone: `iters` times the normal
/// equations at the start and the LM from there, on the task
/// `calibrate_with` made (the identifiability checks before and the
/// statistics after are not timed).
struct TimedLm {
    iters: u64,
    elapsed: std::cell::Cell<std::time::Duration>,
}

impl Solver for TimedLm {
    fn method(&self) -> Method {
        Method::Lm
    }

    fn solve(
        &self,
        task: Task<'_, '_>,
        ctx: &mut Context<'_>,
    ) -> Result<Outcome, CalibrationError> {
        let timer = std::time::Instant::now();
        let mut last = None;
        for _ in 0..self.iters {
            let start_normal = task.objective.normal(task.x, task.free)?;
            last = Some(Lm.solve(black_box(task_from(&task, start_normal)), ctx)?);
        }
        self.elapsed.set(timer.elapsed());
        last.ok_or(CalibrationError::Shape)
    }
}

/// `task` with the normal equations at its start `start_normal`.
fn task_from<'a, 'o>(task: &Task<'a, 'o>, start_normal: Normal) -> Task<'a, 'o> {
    Task {
        start: task.start,
        x: task.x,
        data: task.data,
        objective: task.objective,
        free: task.free,
        model: task.model,
        settings: task.settings,
        stated_dof: task.stated_dof,
        dof: task.dof,
        start_normal,
    }
}

/// The time of `iters` LM solves of `data` from `arm` ([`TimedLm`]).
fn solve_only(
    arm: &Arm,
    data: &DataSet,
    model: &ModelOptions,
    settings: &SolverSettings,
    iters: u64,
) -> std::time::Duration {
    let timed = TimedLm {
        iters,
        elapsed: std::cell::Cell::new(std::time::Duration::ZERO),
    };
    fit_with(arm, data, model, settings, &timed);
    timed.elapsed.get()
}

/// An assembled arm whose LM from nominal ends in a wrong minimum.
const ASSEMBLED_SEED: u64 = 4;

fn global(c: &mut Criterion) {
    let start = nominal().params;
    let data = campaign(ASSEMBLED_SEED, ErrorModel::random(1.0, true), 10, 10);
    let (model, settings) = options(Method::Global, FixSpec::Auto);
    let lm = settings.clone().with_method(Method::Lm);
    let lm = calibrate(&start, &data, &model, &lm).expect("lm");
    let global = calibrate(&start, &data, &model, &settings).expect("global");
    assert!(
        lm.dof.sigma0 > 10.0 * global.dof.sigma0,
        "the bench campaign should defeat LM from nominal (sigma0 {} vs {})",
        lm.dof.sigma0,
        global.dof.sigma0
    );
    let mut g = c.benchmark_group("global");
    g.sample_size(10);
    g.bench_function(BenchmarkId::from_parameter("assembled-100"), |b| {
        b.iter(|| calibrate(black_box(&start), black_box(&data), &model, &settings).expect("fit"))
    });
    g.finish();
}

fn energy(c: &mut Criterion) {
    let start = nominal().params;
    let data = campaign(7, ErrorModel::Paper, 10, 10);
    let mut energy = Energy::new(&data);
    let mut g = c.benchmark_group("energy");
    g.throughput(Throughput::Elements(1));
    g.bench_function(BenchmarkId::from_parameter("evaluation-100"), |b| {
        b.iter(|| {
            let k = ArmKernel::new(black_box(&start)).expect("6 joints");
            energy.of_kernel(&k, black_box(&data))
        })
    });
    g.finish();
}

fn positions(c: &mut Criterion) {
    use aacmm_core::simulate::{PositionSettings, simulate_positions, true_arm};
    use rand::SeedableRng;
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/ur5-tracker/arm.toml");
    let nominal = aacmm_core::read_arm(std::path::Path::new(path))
        .expect("the shipped UR5")
        .0;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let truth = true_arm(&nominal, &ErrorModel::random(1.0, false), &mut rng).expect("truth");
    let noise = Noise {
        position_mm: Some(0.015),
        position_mm_per_m: Some(0.006),
        ..Noise::default()
    };
    let (mut model, settings) = options(Method::Lm, FixSpec::Auto);
    model.noise = noise;
    let mut g = c.benchmark_group("calibrate-positions");
    g.sample_size(10);
    let mut solve = Vec::new();
    for poses in [1000, 12000] {
        let data = std::sync::OnceLock::new();
        let truth = truth.clone();
        let make = move || {
            let s = PositionSettings {
                poses,
                frames: 1,
                noise,
                seed: 12,
            };
            let rows = simulate_positions(&truth, &s).expect("campaign").positions;
            DataSet::from_positions(rows, "tracker.csv").expect("data set")
        };
        g.throughput(Throughput::Elements(poses as u64));
        g.bench_function(BenchmarkId::from_parameter(poses), |b| {
            let data = data.get_or_init(make.clone());
            b.iter(|| {
                calibrate(
                    black_box(&nominal.params),
                    black_box(data),
                    &model,
                    &settings,
                )
                .expect("fit")
            })
        });
        solve.push((poses, data, make));
    }
    g.finish();
    let mut g = c.benchmark_group("positions-solve");
    g.sample_size(10);
    for (poses, data, make) in solve {
        g.throughput(Throughput::Elements(poses as u64));
        g.bench_function(BenchmarkId::from_parameter(poses), |b| {
            let data = data.get_or_init(make.clone());
            b.iter_custom(|iters| solve_only(&nominal, data, &model, &settings, iters))
        });
    }
    g.finish();
}

/// The paper's arm with link masses (a portable arm's: a few kg in all) and
/// a 0.3 kg probe.
fn with_masses() -> Arm {
    use aacmm_core::corrections::{Mass, Physics};
    let mut arm = nominal();
    arm.physics = Box::new(Physics {
        link_masses: [0.8, 1.2, 0.9, 0.6, 0.4, 0.2]
            .map(|kg| Some(Mass::at_middle(kg)))
            .to_vec(),
        probe_mass: Some(Mass::at_middle(0.3)),
        ..Physics::default()
    });
    arm
}

/// `calibrate` of `arm` (its physics) with the models `beyond` on.
fn fit_beyond(
    arm: &Arm,
    data: &DataSet,
    model: &ModelOptions,
    settings: &SolverSettings,
) -> aacmm_core::Calibration {
    fit_with(arm, data, model, settings, &*settings.method.solver())
}

/// `calibrate_with` of `arm` (its physics), the models `model.beyond` on,
/// by `solver`.
fn fit_with(
    arm: &Arm,
    data: &DataSet,
    model: &ModelOptions,
    settings: &SolverSettings,
    solver: &dyn Solver,
) -> aacmm_core::Calibration {
    use aacmm_core::calibrate::{FitInputs, calibrate_with};
    let layout = aacmm_core::residuals::positions::layout_with(
        &arm.params,
        data,
        &arm.physics,
        &model.beyond,
    )
    .expect("layout");
    let inputs = FitInputs {
        layout: &layout,
        data,
        model,
        terms: &[],
    };
    calibrate_with(inputs, settings, solver, &mut Context::new()).expect("fit")
}

fn beyond(c: &mut Criterion) {
    use aacmm_core::corrections::Beyond;
    let arm = with_masses();
    let (model, settings) = options(Method::Lm, FixSpec::parse(UNOBSERVABLE, 6).expect("names"));
    let mut g = c.benchmark_group("beyond");
    g.sample_size(10);
    let data = std::sync::OnceLock::new();
    let cases = [
        ("lm-100", Beyond::default()),
        (
            "compliance-100",
            Beyond {
                compliance: vec![1, 2],
                ..Beyond::default()
            },
        ),
        (
            "harmonics-100",
            Beyond {
                harmonics: vec![(1, 1), (2, 1)],
                ..Beyond::default()
            },
        ),
    ];
    for (name, beyond) in cases {
        let model = ModelOptions {
            beyond,
            ..model.clone()
        };
        g.bench_function(BenchmarkId::from_parameter(name), |b| {
            let data = data.get_or_init(|| campaign(7, ErrorModel::Paper, 10, 10));
            b.iter(|| fit_beyond(&arm, black_box(data), &model, &settings))
        });
    }
    beyond_positions(&mut g);
    g.finish();
}

/// The UR5 tracker's 1000 poses at 15–30 °C over 4 h, without and with
/// `--thermal --drift`.
fn beyond_positions(g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>) {
    use aacmm_core::corrections::Beyond;
    use aacmm_core::simulate::{ConditionSettings, PositionSettings, simulate_session, true_arm};
    use rand::SeedableRng;
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/ur5-tracker/arm.toml");
    let nominal = aacmm_core::read_arm(std::path::Path::new(path))
        .expect("the shipped UR5")
        .0;
    let noise = Noise {
        position_mm: Some(0.015),
        position_mm_per_m: Some(0.006),
        ..Noise::default()
    };
    let (mut model, settings) = options(Method::Lm, FixSpec::Auto);
    model.noise = noise;
    let data = std::sync::OnceLock::new();
    for (name, thermal) in [("positions-1000", false), ("thermal-drift-1000", true)] {
        let model = ModelOptions {
            beyond: Beyond {
                thermal,
                drift: thermal,
                ..Beyond::default()
            },
            ..model.clone()
        };
        g.bench_function(BenchmarkId::from_parameter(name), |b| {
            let data = data.get_or_init(|| {
                let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
                let truth =
                    true_arm(&nominal, &ErrorModel::random(1.0, false), &mut rng).expect("truth");
                let s = PositionSettings {
                    poses: 1000,
                    frames: 1,
                    noise,
                    seed: 12,
                };
                let conditions = ConditionSettings {
                    temperature_c: Some([15.0, 30.0]),
                    session_h: Some(4.0),
                    approach: false,
                };
                let rows = simulate_session(&truth, &s, &conditions, None)
                    .expect("campaign")
                    .positions;
                DataSet::from_positions(rows, "tracker.csv").expect("data set")
            });
            b.iter(|| fit_beyond(&nominal, black_box(data), &model, &settings))
        });
    }
}

fn plan(c: &mut Criterion) {
    use aacmm_core::domain::Poses;
    use aacmm_core::plan::{Measure, PlanSettings, plan};
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/ur5-tracker/arm.toml");
    let ur5 = aacmm_core::read_arm(std::path::Path::new(path))
        .expect("the shipped UR5")
        .0;
    let mut g = c.benchmark_group("plan");
    g.sample_size(10);
    let pool = positions_pool(&ur5, 2000);
    let mut s = PlanSettings::new(100, Measure::Positions);
    s.random_sets = 0;
    s.curve_to = 100;
    g.bench_function(BenchmarkId::from_parameter("positions-100-of-2000"), |b| {
        b.iter(|| plan(&ur5.params, black_box(&pool), None, None, &s).expect("plan"))
    });
    let nominal = Arm::without_limits("paper", DhParams::paper_nominal());
    let touches: Poses = simulate(
        &nominal,
        &CampaignSettings::new(5, ErrorModel::Paper, 10, 100),
    )
    .expect("campaign")
    .poses;
    let mut s = PlanSettings::new(60, Measure::Touches);
    s.random_sets = 0;
    s.curve_to = 60;
    g.bench_function(BenchmarkId::from_parameter("touches-60-of-1000"), |b| {
        b.iter(|| plan(&nominal.params, black_box(&touches), None, None, &s).expect("plan"))
    });
    g.finish();
}

/// `n` random poses of `arm` within its limits, as a poses file holds them.
fn positions_pool(arm: &Arm, n: usize) -> aacmm_core::domain::Poses {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let joints = arm.params.joint_count();
    let mut pool = aacmm_core::domain::Poses::new(joints);
    for i in 0..n {
        let q: Vec<f64> = (0..joints)
            .map(|j| match arm.limits.get(j).copied().flatten() {
                Some([lo, hi]) => rng.random_range(lo..=hi),
                None => rng.random_range(-3.0..3.0),
            })
            .collect();
        pool.push(&format!("P{}", i + 1), &q, i + 2);
    }
    pool
}

/// Busy processes that load the machine while they live (killed and
/// reaped on drop, a failed bench included).
struct Load(Vec<std::process::Child>);

impl Load {
    fn start(processes: usize) -> Load {
        Load(
            (0..processes)
                .map(|_| {
                    std::process::Command::new("sh")
                        .args(["-c", "while :; do :; done"])
                        .spawn()
                        .expect("a busy process")
                })
                .collect(),
        )
    }
}

impl Drop for Load {
    fn drop(&mut self) {
        for child in &mut self.0 {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

fn threads(c: &mut Criterion) {
    use aacmm_core::io::{AngleUnit, read_positions};
    let file = |f: &str| format!("{}/examples/ur5-tracker/{f}", env!("CARGO_MANIFEST_DIR"));
    let arm = aacmm_core::read_arm(std::path::Path::new(&file("arm.toml")))
        .expect("the shipped UR5")
        .0;
    let rows = read_positions(
        std::path::Path::new(&file("positions-grid.csv")),
        AngleUnit::Deg,
        Some(6),
    )
    .expect("the shipped positions");
    let data = DataSet::from_positions(rows, "positions-grid.csv").expect("data set");
    let model = ModelOptions::default();
    let default = SolverSettings::default();
    let one = SolverSettings {
        threads: 1,
        ..SolverSettings::default()
    };
    let mut g = c.benchmark_group("threads");
    g.sample_size(10);
    for (name, busy) in [("idle", 0), ("loaded", 2)] {
        let _load = Load::start(busy);
        for (count, settings) in [("1", &one), ("default", &default)] {
            let id = format!("ur5-tracker/{name}/{count}");
            g.bench_function(BenchmarkId::from_parameter(id), |b| {
                b.iter(|| {
                    calibrate(black_box(&arm.params), black_box(&data), &model, settings)
                        .expect("fit")
                })
            });
        }
    }
    g.finish();
}

criterion_group!(
    benches, lm, global, energy, positions, beyond, threads, plan
);
criterion_main!(benches);
