//! Kernel speed: batches of 1000 seeded random poses of the paper's arm with a
//! perturbed parameter set, grouped by operation. Ids compare the generated
//! kernel with the reference nalgebra model (id `generic`: position) and with
//! num-dual autodiff and central differences on the reference model
//! (Jacobian), and the extended chain (`generated-hayati`: the same arm with
//! joint 2 in the Hayati parameterisation) with the D-H one.

use aacmm_core::kernel::{self, ArmKernel, PreparedPoses};
use aacmm_core::params::{DhParams, JointModel};
use aacmm_core::reference_model;
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;
use std::hint::black_box;

const POSES: usize = 1000;

fn inputs() -> (DhParams, Vec<[f64; 6]>) {
    let mut rng = ChaCha8Rng::seed_from_u64(2021);
    let mut v = DhParams::paper_nominal().to_vec();
    for x in &mut v {
        *x += rng.random_range(-0.01..0.01);
    }
    let params = DhParams::from_slice(&v).expect("27 values");
    let q = (0..POSES)
        .map(|_| std::array::from_fn(|_| rng.random_range(-PI..PI)))
        .collect();
    (params, q)
}

/// The same arm with joint 2 Hayati (β = 0.001 rad): what runs the extended chain.
fn hayati(params: &DhParams) -> ArmKernel {
    let mut h = params.clone();
    h.joints[1].model = JointModel::Hayati;
    h.joints[1].beta = 0.001;
    ArmKernel::new(&h).expect("6 joints")
}

fn position(c: &mut Criterion) {
    let (params, q) = inputs();
    let k = ArmKernel::new(&params).expect("6 joints");
    let poses = PreparedPoses::new(6, &q).expect("6 readings per pose");
    let flat = params.to_vec();
    let mut out = vec![[0.0; 3]; POSES];
    let mut g = c.benchmark_group("position");
    g.throughput(Throughput::Elements(POSES as u64));
    g.bench_function(BenchmarkId::from_parameter("generated"), |b| {
        b.iter(|| black_box(&k).positions(black_box(&poses), 0..POSES, &mut out))
    });
    let kh = hayati(&params);
    g.bench_function(BenchmarkId::from_parameter("generated-hayati"), |b| {
        b.iter(|| black_box(&kh).positions(black_box(&poses), 0..POSES, &mut out))
    });
    g.bench_function(BenchmarkId::from_parameter("generic"), |b| {
        b.iter(|| {
            for (o, q) in out.iter_mut().zip(&q) {
                *o = reference_model::position(black_box(&flat), q);
            }
        })
    });
    g.finish();
}

fn jacobian(c: &mut Criterion) {
    let (params, q) = inputs();
    let k = ArmKernel::new(&params).expect("6 joints");
    let poses = PreparedPoses::new(6, &q).expect("6 readings per pose");
    let mut out = kernel::Jacobians::new(POSES, 27);
    let mut g = c.benchmark_group("jacobian");
    g.throughput(Throughput::Elements(POSES as u64));
    g.bench_function(BenchmarkId::from_parameter("generated"), |b| {
        b.iter(|| black_box(&k).jacobians(black_box(&poses), &mut out))
    });
    let kh = hayati(&params);
    g.bench_function(BenchmarkId::from_parameter("generated-hayati"), |b| {
        b.iter(|| black_box(&kh).jacobians(black_box(&poses), &mut out))
    });
    g.bench_function(BenchmarkId::from_parameter("num-dual"), |b| {
        b.iter(|| {
            for q in &q {
                black_box(
                    reference_model::param_jacobian_dual::<27>(black_box(&params), q)
                        .expect("6 joints"),
                );
            }
        })
    });
    g.bench_function(BenchmarkId::from_parameter("finite-diff"), |b| {
        b.iter(|| {
            for q in &q {
                black_box(
                    reference_model::param_jacobian_central(black_box(&params), q, 1e-6)
                        .expect("6 joints"),
                );
            }
        })
    });
    g.finish();
}

criterion_group!(benches, position, jacobian);
criterion_main!(benches);
