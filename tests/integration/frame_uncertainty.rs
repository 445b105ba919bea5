//! Uncertainty that covers what it predicts: simulated tracker campaigns
//! with one, two and three frames, predictions at held-out poses in the
//! arm's base and in each instrument's frame against the truth, judged by
//! the stated 95 % radius.

use aacmm_core::io::Arm;
use aacmm_core::kernel::{ArmKernel, PreparedPoses};
use aacmm_core::params::DhParams;
use aacmm_core::plan::{InFrame, position_covariances};
use aacmm_core::residuals::Frame;
use aacmm_core::simulate::simulate_positions_from;
use aacmm_core::stats::coverage::{eigenvalues, radius};
use aacmm_core::{DataSet, ModelOptions, Problem};
use nalgebra::{Matrix3, Vector3};

use super::positions::{campaign, lm, settings, tracker};

/// One prediction's error against the truth, in units of what was stated:
/// `|e| / r₉₅` and the squared Mahalanobis distance `eᵀ Σ⁻¹ e`.
#[derive(Clone, Copy, Debug)]
struct Judged {
    ratio: f64,
    mahalanobis: f64,
}

fn judge(estimate: [f64; 3], truth: [f64; 3], sigma: [[f64; 3]; 3]) -> Judged {
    let e = Vector3::from(estimate) - Vector3::from(truth);
    let s = Matrix3::from_fn(|i, j| sigma[i][j]);
    let inv = s.try_inverse().expect("a regular covariance");
    Judged {
        ratio: e.norm() / radius(eigenvalues(sigma)),
        mahalanobis: (e.transpose() * inv * e)[(0, 0)],
    }
}

/// One seed's predictions at held-out poses: in the base frame, and in each
/// instrument's frame with the frame's registration counted in (`framed`)
/// and without it, the arm's covariance alone (`arm_only`, what the map
/// stated before).
#[derive(Default)]
struct Seed {
    base: Vec<Judged>,
    framed: Vec<Judged>,
    arm_only: Vec<Judged>,
    /// Per draw of an exactly honest error (drawn from the stated joint
    /// covariance itself), its predictions' ratios.
    ideal: Vec<Vec<f64>>,
}

/// The campaign of `seed` with `frames` frames of `poses` poses each,
/// calibrated; `held` new poses per frame seen from the same stations.
fn seed(nominal: &Arm, seed: u64, frames: usize, poses: usize, held: usize) -> Seed {
    let (truth, c) = campaign(nominal, seed, poses, frames);
    let data = DataSet::from_positions(c.positions.clone(), "sim.csv").unwrap();
    let model = ModelOptions {
        noise: tracker(),
        ..ModelOptions::default()
    };
    let report = Problem::new(nominal.clone(), data, model)
        .unwrap()
        .run(&lm())
        .unwrap();
    assert!(report.is_usable(), "seed {seed}: {:?}", report.verdict);
    let cal = &report.calibration;
    let fresh = simulate_positions_from(&truth, &settings(held, 0, seed + 5000), &c.frames).unwrap();
    let joints = nominal.params.joint_count();
    let true_kernel = ArmKernel::new(&truth.params).unwrap();
    let (free, cov) = cal.geometry_covariance().unwrap();
    let mut out = Seed::default();
    for (f, (name, x_true)) in c.frames.iter().enumerate() {
        let rows: Vec<&[f64]> = (0..fresh.len())
            .filter(|&i| fresh.frame(i) == f)
            .map(|i| fresh.reading(i))
            .collect();
        assert_eq!(fresh.frames()[f], *name);
        let poses = PreparedPoses::new(joints, &rows).unwrap();
        let base = position_covariances(&cal.params, &poses, &free, &cov, None).unwrap();
        let (free_f, x, joint) = cal.frame_covariance(name).unwrap();
        assert_eq!(free_f, free);
        let frame = InFrame { name, x };
        let framed =
            position_covariances(&cal.params, &poses, &free, &joint, Some(&frame)).unwrap();
        let r = Frame::rotation(&x);
        let draws = honest_draws(&cal.params, &free, &joint, &x, &rows, seed);
        for (d, draw) in draws.iter().enumerate() {
            if out.ideal.len() <= d {
                out.ideal.push(Vec::new());
            }
            out.ideal[d].extend(draw.iter().zip(&framed).map(|(p, (at, s))| {
                let e = Vector3::from(*p) - Vector3::from(*at);
                e.norm() / radius(eigenvalues(*s))
            }));
        }
        for (i, q) in rows.iter().enumerate() {
            let p = true_kernel.position(q).unwrap();
            let seen = Frame::apply(x_true, p);
            out.base.push(judge(base[i].0, p, base[i].1));
            out.framed.push(judge(framed[i].0, seen, framed[i].1));
            // The base covariance turned into the frame: the same radius.
            let m = Matrix3::from_fn(|a, b| base[i].1[a][b]);
            let turned = r.matrix() * m * r.matrix().transpose();
            let turned = std::array::from_fn(|a| std::array::from_fn(|b| turned[(a, b)]));
            out.arm_only.push(judge(framed[i].0, seen, turned));
        }
    }
    out
}

/// Predictions in the frame `x` at `rows` of 100 arms and frames drawn
/// about the calibration from the stated joint covariance `cov`: what an
/// exactly honest uncertainty's errors look like.
fn honest_draws(
    params: &DhParams,
    free: &[usize],
    cov: &nalgebra::DMatrix<f64>,
    x: &[f64; 6],
    rows: &[&[f64]],
    seed: u64,
) -> Vec<Vec<[f64; 3]>> {
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed + 77);
    let l = cov.clone().cholesky().expect("a positive definite covariance").l();
    let q = free.len();
    let r = Frame::rotation(x);
    (0..100)
        .map(|_| {
            let z = nalgebra::DVector::from_fn(q + 6, |_, _| normal(&mut rng));
            let d = &l * z;
            let mut v = params.to_vec();
            for (a, &c) in free.iter().enumerate() {
                v[c] += d[a];
            }
            let k = ArmKernel::new(&DhParams::from_slice(&v).unwrap()).unwrap();
            let turn = Frame::rotation(&[d[q], d[q + 1], d[q + 2]]);
            let t = Vector3::new(x[3] + d[q + 3], x[4] + d[q + 4], x[5] + d[q + 5]);
            rows.iter()
                .map(|row| {
                    let p = Vector3::from(k.position(row).unwrap());
                    (turn * (r * p) + t).into()
                })
                .collect()
        })
        .collect()
}

fn normal(rng: &mut rand_chacha::ChaCha8Rng) -> f64 {
    use rand::RngExt;
    let (u, v): (f64, f64) = (rng.random(), rng.random());
    (-2.0 * (1.0 - u).ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// The `p`-quantile of `v` (nearest rank).
fn quantile(v: &[f64], p: f64) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[((p * s.len() as f64).ceil() as usize).clamp(1, s.len()) - 1]
}

/// Over the seeds: the share whose 95th percentile of `|e| / r₉₅` is within
/// 1, that percentile's mean and largest, and the normalised RMS
/// `sqrt(mean(eᵀ Σ⁻¹ e) / 3)` over every prediction.
#[derive(Debug)]
struct Summary {
    within: f64,
    /// Share of every prediction within its radius.
    covered: f64,
    p95_mean: f64,
    p95_max: f64,
    nrms: f64,
}

fn summary(seeds: &[Vec<Judged>]) -> Summary {
    let p95: Vec<f64> = (seeds.iter())
        .map(|s| quantile(&s.iter().map(|j| j.ratio).collect::<Vec<_>>(), 0.95))
        .collect();
    let all: Vec<f64> = seeds.iter().flatten().map(|j| j.mahalanobis).collect();
    let ratios: Vec<f64> = seeds.iter().flatten().map(|j| j.ratio).collect();
    Summary {
        covered: ratios.iter().filter(|&&v| v <= 1.0).count() as f64 / ratios.len() as f64,
        within: p95.iter().filter(|&&v| v <= 1.0).count() as f64 / p95.len() as f64,
        p95_mean: p95.iter().sum::<f64>() / p95.len() as f64,
        p95_max: p95.iter().copied().fold(0.0, f64::max),
        nrms: (all.iter().sum::<f64>() / (3.0 * all.len() as f64)).sqrt(),
    }
}

fn measure(seeds: std::ops::Range<u64>, poses: usize) -> Vec<(usize, Summary, Summary, Summary)> {
    let nominal = match std::env::var("ARM").as_deref() {
        Ok("panda") => super::positions::panda(),
        Ok("ur5") => aacmm_core::read_arm(&super::util::example("ur5-tracker/arm.toml"))
            .unwrap()
            .0,
        _ => Arm::without_limits("paper", DhParams::paper_nominal()),
    };
    let mut out = Vec::new();
    for frames in 1..=3 {
        let runs: Vec<Seed> = (seeds.clone())
            .map(|s| seed(&nominal, s, frames, poses, 40))
            .collect();
        let pick = |f: fn(&Seed) -> &Vec<Judged>| -> Vec<Vec<Judged>> {
            runs.iter().map(|r| f(r).clone()).collect()
        };
        let base = summary(&pick(|s| &s.base));
        let framed = summary(&pick(|s| &s.framed));
        let arm_only = summary(&pick(|s| &s.arm_only));
        eprintln!(
            "{frames} frame(s): base {base:?}\n  in the frame, with its registration \
             {framed:?}\n  in the frame, the arm's covariance alone {arm_only:?}"
        );
        let ideal: Vec<f64> = (runs.iter())
            .flat_map(|r| r.ideal.iter().map(|d| quantile(d, 0.95)))
            .collect();
        let share = ideal.iter().filter(|&&v| v <= 1.0).count() as f64 / ideal.len() as f64;
        eprintln!("  an exactly honest covariance: 95th percentile within in {share:.3} of draws");
        out.push((frames, base, framed, arm_only));
    }
    out
}

#[test]
#[ignore = "experiment"]
fn experiment() {
    let poses = std::env::var("POSES").map_or(200, |p| p.parse().unwrap());
    measure(0..50, poses);
}
