//! Calibration speed on simulated campaigns (the paper's arm, 0.005° encoder
//! and 0.01 mm probe noise, stated to the solver; one thread):
//!
//! - `lm`: LM from nominal on the paper's errors with the fixed set of
//!   method.md §8.1 given (no identifiability analysis), `lm/100` and
//!   `lm/10000` touches, and with `AACMM_BENCH_LARGE=1` also `lm/100000` and
//!   `lm/1000000` (1000 sockets × 1000 touches, `simulate`'s largest: its
//!   campaign takes about a minute to simulate, once per process, and only
//!   when that bench runs): the problem of the Ceres anchors;
//! - `global`: `--method global` on a newly assembled arm (zeros anywhere in
//!   ±180°) whose LM from nominal fails, 100 touches;
//! - `energy`: annealing energy evaluations (position kernel + the paper's
//!   OA) per second, 100 touches;
//! - `positions`: a laser-tracker calibration — the shipped UR5's arm file
//!   (two Hayati joints), random errors, one tracker frame seeing 1000 or
//!   12000 poses with 15 µm + 6 µm/m noise (stated): LM from nominal with
//!   the identifiability analysis (`--fix auto`), frame and covariance,
//!   `positions/1000` and `positions/12000`;
//! - `beyond`: the models beyond geometry switched on, each against the
//!   same problem without it — `lm-100` (the `lm/100` campaign and fit with
//!   link masses stated, nothing switched on), `compliance-100`
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
use aacmm_core::calibrate::{FixSpec, Method, ModelOptions, SolverSettings, calibrate};
use aacmm_core::dataset::DataSet;
use aacmm_core::io::Arm;
use aacmm_core::kernel::ArmKernel;
use aacmm_core::params::DhParams;
use aacmm_core::residuals::Noise;
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

fn lm(c: &mut Criterion) {
    // (sockets, touches per socket): the bench id is their product.
    let mut sizes = vec![(10, 10), (100, 100)];
    if std::env::var_os("AACMM_BENCH_LARGE").is_some() {
        sizes.extend([(1000, 100), (1000, 1000)]);
    }
    let start = nominal().params;
    let (model, settings) = options(Method::Lm, FixSpec::parse(UNOBSERVABLE, 6).expect("names"));
    let mut g = c.benchmark_group("lm");
    g.sample_size(10);
    for (sockets, touches) in sizes {
        // Simulated when the bench runs (not when a filter skips it), once.
        let data = std::sync::OnceLock::new();
        g.throughput(Throughput::Elements((sockets * touches) as u64));
        g.bench_function(BenchmarkId::from_parameter(sockets * touches), |b| {
            let data = data.get_or_init(|| campaign(7, ErrorModel::Paper, sockets, touches));
            b.iter(|| {
                calibrate(black_box(&start), black_box(data), &model, &settings).expect("fit")
            })
        });
    }
    g.finish();
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
    let mut g = c.benchmark_group("positions");
    g.sample_size(10);
    for poses in [1000, 12000] {
        let data = std::sync::OnceLock::new();
        g.throughput(Throughput::Elements(poses as u64));
        g.bench_function(BenchmarkId::from_parameter(poses), |b| {
            let data = data.get_or_init(|| {
                let s = PositionSettings {
                    poses,
                    frames: 1,
                    noise,
                    seed: 12,
                };
                let rows = simulate_positions(&truth, &s).expect("campaign").positions;
                DataSet::from_positions(rows, "tracker.csv").expect("data set")
            });
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
    use aacmm_core::calibrate::{Context, FitInputs, calibrate_with};
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
    calibrate_with(
        inputs,
        settings,
        &*settings.method.solver(),
        &mut Context::new(),
    )
    .expect("fit")
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
    use aacmm_core::io::Poses;
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
fn positions_pool(arm: &Arm, n: usize) -> aacmm_core::io::Poses {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let joints = arm.params.joint_count();
    let mut pool = aacmm_core::io::Poses::new(joints);
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
