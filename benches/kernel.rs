//! Kernel speed: batches of 1000 seeded random poses of the paper's arm with a
//! perturbed parameter set, grouped by operation. Ids compare the generated
//! kernel with the reference nalgebra model (id `generic`: position) and with
//! num-dual autodiff and central differences on the reference model
//! (Jacobian), and the extended chain (`generated-hayati`: the same arm with
//! joint 2 in the Hayati parameterisation) with the D-H one.
//!
//! `chain-positions` and `chain-jacobians` compare shapes: the generated
//! 7R kernel, the generated 8-joint `PRRRRRRR` (a 7-joint arm on a lift),
//! and the generic kernel on an unshipped 8-joint shape (`RPRRRRRR`) and on
//! `PRRRRRRR` itself — the bounds are generated 8-joint ≤ 1.3 ×
//! 8/7 × 7R, generic ≤ 3 × generated of the same length. `pose` is the tool
//! frame's 6-row Jacobian beside the 3-row one.

use aacmm_core::kernel::{self, ArmKernel, Generic, Pose, PreparedPoses};
use aacmm_core::params::{ChainShape, DhJoint, DhParams, JointKind, JointModel};
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

/// A perturbed arm of `shape`: the paper's joints (a wrist link for a
/// seventh revolute one), a slide where the shape has a `P`.
fn arm_of(shape: &str, rng: &mut ChaCha8Rng) -> DhParams {
    let shape: ChainShape = shape.parse().expect("a shape");
    let paper = DhParams::paper_nominal();
    let wrist = DhJoint::dh(20.0, 60.0, -PI / 2.0, 0.0);
    let mut revolute = paper.joints.iter().copied().chain([wrist]);
    let joints = shape
        .kinds()
        .map(|kind| match kind {
            JointKind::Prismatic => {
                DhJoint::dh(0.0, 300.0, PI / 2.0, PI / 2.0).with_kind(JointKind::Prismatic)
            }
            JointKind::Revolute => revolute.next().expect("at most 7 revolute joints"),
        })
        .collect();
    let arm = DhParams {
        joints,
        probe: paper.probe,
    };
    let v: Vec<f64> = arm
        .to_vec()
        .iter()
        .map(|x| x + rng.random_range(-0.01..0.01))
        .collect();
    arm.with_values(&v).expect("4n + 3 values")
}

/// Seeded readings of `shape`: ±π rad turning, ±500 mm sliding.
fn readings_of(shape: ChainShape, rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
    (0..POSES)
        .map(|_| {
            (0..shape.joints())
                .map(|j| {
                    if shape.is_prismatic(j) {
                        rng.random_range(-500.0..500.0)
                    } else {
                        rng.random_range(-PI..PI)
                    }
                })
                .collect()
        })
        .collect()
}

/// The kernels the `chain-*` groups compare: (id, kernel, its poses).
fn chains() -> Vec<(&'static str, ArmKernel, PreparedPoses)> {
    let mut rng = ChaCha8Rng::seed_from_u64(2021);
    let mut out = Vec::new();
    for (id, shape, generic) in [
        ("7R-generated", "RRRRRRR", false),
        ("PRRRRRRR-generated", "PRRRRRRR", false),
        ("PRRRRRRR-generic", "PRRRRRRR", true),
        ("RPRRRRRR-generic", "RPRRRRRR", true),
    ] {
        let arm = arm_of(shape, &mut rng);
        let k = match (generic, arm.joint_count()) {
            (true, 8) => ArmKernel::with_chain::<Generic, 8>(&arm).expect("8 joints"),
            _ => ArmKernel::new(&arm).expect("a chain"),
        };
        let q = readings_of(k.shape(), &mut rng);
        let poses = PreparedPoses::for_shape(k.shape(), &q).expect("readings of the shape");
        out.push((id, k, poses));
    }
    out
}

fn chain(c: &mut Criterion) {
    let chains = chains();
    let mut g = c.benchmark_group("chain-positions");
    g.throughput(Throughput::Elements(POSES as u64));
    let mut out = vec![[0.0; 3]; POSES];
    for (id, k, poses) in &chains {
        g.bench_function(BenchmarkId::from_parameter(id), |b| {
            b.iter(|| black_box(k).positions(black_box(poses), 0..POSES, &mut out))
        });
    }
    g.finish();
    let mut g = c.benchmark_group("chain-jacobians");
    g.throughput(Throughput::Elements(POSES as u64));
    for (id, k, poses) in &chains {
        let mut out = kernel::Jacobians::new(POSES, k.param_count());
        g.bench_function(BenchmarkId::from_parameter(id), |b| {
            b.iter(|| black_box(k).jacobians(black_box(poses), &mut out))
        });
    }
    g.finish();
}

/// The tool pose's 6-row parameter Jacobian beside the position's 3-row
/// one, both through the per-pose callback a solver uses.
fn pose(c: &mut Criterion) {
    let (params, q) = inputs();
    let k = ArmKernel::new(&params).expect("6 joints");
    let poses = PreparedPoses::new(6, &q).expect("6 readings per pose");
    let mut g = c.benchmark_group("pose");
    g.throughput(Throughput::Elements(POSES as u64));
    g.bench_function(BenchmarkId::from_parameter("position-jacobian"), |b| {
        b.iter(|| {
            let mut sum = 0.0;
            k.for_each_jacobian(black_box(&poses), 0..POSES, |_, p, jac| {
                sum += p[0] + jac[0][0];
            })
            .expect("6 joints");
            sum
        })
    });
    g.bench_function(BenchmarkId::from_parameter("pose-jacobian"), |b| {
        b.iter(|| {
            let mut sum = 0.0;
            k.for_each_pose_jacobian(black_box(&poses), 0..POSES, |_, t: &Pose, jac| {
                sum += t.position[0] + jac[0][0];
            })
            .expect("6 joints");
            sum
        })
    });
    g.finish();
}

criterion_group!(benches, position, jacobian, chain, pose);
criterion_main!(benches);
