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
//!   OA) per second, 100 touches.

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

criterion_group!(benches, lm, global, energy);
criterion_main!(benches);
