//! Uncertainty that covers what it predicts: simulated tracker campaigns
//! with one, two and three frames, predictions at held-out poses in the
//! arm's base and in each instrument's frame against the truth, judged by
//! the stated 95 % radius.

use aacmm_core::domain::Arm;
use aacmm_core::kernel::{ArmKernel, PreparedPoses};
use aacmm_core::params::DhParams;
use aacmm_core::plan::{InFrame, position_covariances};
use aacmm_core::residuals::Frame;
use aacmm_core::simulate::{PositionCampaign, simulate_positions_from};
use aacmm_core::stats::coverage::{eigenvalues, radius};
use aacmm_core::{CalibrationReport, DataSet, ModelOptions, Problem};
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
    /// covariance itself), its predictions judged.
    ideal: Vec<Vec<Judged>>,
}

/// The true arm and campaign of `seed` with `frames` frames of `poses`
/// poses each, its problem and the calibration (usable).
fn fitted(
    nominal: &Arm,
    seed: u64,
    poses: usize,
    frames: usize,
) -> (Arm, PositionCampaign, Problem, CalibrationReport) {
    let (truth, c) = campaign(nominal, seed, poses, frames);
    let data = DataSet::from_positions(c.positions.clone(), "sim.csv").unwrap();
    let model = ModelOptions {
        noise: tracker(),
        ..ModelOptions::default()
    };
    let problem = Problem::new(nominal.clone(), data, model).unwrap();
    let report = problem.run(&lm()).unwrap();
    assert!(report.is_usable(), "seed {seed}: {:?}", report.verdict);
    (truth, c, problem, report)
}

/// The campaign of `seed` with `frames` frames of `poses` poses each,
/// calibrated; `held` new poses per frame seen from the same stations.
fn seed(nominal: &Arm, seed: u64, frames: usize, poses: usize, held: usize) -> Seed {
    let (truth, c, _, report) = fitted(nominal, seed, poses, frames);
    let cal = &report.calibration;
    let fresh =
        simulate_positions_from(&truth, &settings(held, 0, seed + 5000), &c.frames).unwrap();
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
            let judged = draw
                .iter()
                .zip(&framed)
                .map(|(p, (at, s))| judge(*p, *at, *s));
            out.ideal[d].extend(judged);
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
    let l = cov
        .clone()
        .cholesky()
        .expect("a positive definite covariance")
        .l();
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

/// Over the seeds: the share of every prediction within its 95 % radius
/// (`covered`), the normalised RMS `sqrt(mean(eᵀ Σ⁻¹ e) / 3)` over them,
/// and per seed the 95th percentile of `|e| / r₉₅` — its mean, largest and
/// the share of seeds where it is within 1 (`within`: the figure).
struct Summary {
    covered: f64,
    nrms: f64,
    within: f64,
    p95_mean: f64,
    p95_max: f64,
}

impl std::fmt::Debug for Summary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "covered {:.3}, normalised RMS {:.3}; per seed the 95th percentile of |e|/r95 \
             within 1 in {:.2} of the seeds, mean {:.3}, max {:.3}",
            self.covered, self.nrms, self.within, self.p95_mean, self.p95_max
        )
    }
}

fn ratios(judged: &[Judged]) -> Vec<f64> {
    judged.iter().map(|j| j.ratio).collect()
}

fn summary<'a>(seeds: impl Iterator<Item = &'a [Judged]>) -> Summary {
    let seeds: Vec<&[Judged]> = seeds.collect();
    let p95: Vec<f64> = (seeds.iter()).map(|s| quantile(&ratios(s), 0.95)).collect();
    let all: Vec<&Judged> = seeds.iter().copied().flatten().collect();
    let share = |v: &mut dyn Iterator<Item = f64>, n: usize| {
        v.filter(|&r| r <= 1.0).count() as f64 / n as f64
    };
    Summary {
        covered: share(&mut all.iter().map(|j| j.ratio), all.len()),
        nrms: (all.iter().map(|j| j.mahalanobis).sum::<f64>() / (3.0 * all.len() as f64)).sqrt(),
        within: share(&mut p95.iter().copied(), p95.len()),
        p95_mean: p95.iter().sum::<f64>() / p95.len() as f64,
        p95_max: p95.iter().copied().fold(0.0, f64::max),
    }
}

/// One count of frames over the seeds: predictions in the base, in the
/// frames with their registration, in the frames with the arm's covariance
/// alone (before), and the share of draws of an exactly honest error whose
/// 95th percentile of `|e| / r₉₅` is within 1.
struct Measured {
    frames: usize,
    base: Summary,
    framed: Summary,
    arm_only: Summary,
    honest_within: f64,
    /// The exactly honest errors' own summary: the linear propagation
    /// against the nonlinear draws.
    honest: Summary,
}

fn measure(nominal: &Arm, seeds: std::ops::Range<u64>, poses: usize, held: usize) -> Vec<Measured> {
    (1..=3)
        .map(|frames| {
            let runs: Vec<Seed> = (seeds.clone())
                .map(|s| seed(nominal, s, frames, poses, held))
                .collect();
            let ideal: Vec<f64> = (runs.iter())
                .flat_map(|r| r.ideal.iter().map(|d| quantile(&ratios(d), 0.95)))
                .collect();
            let m = Measured {
                frames,
                base: summary(runs.iter().map(|r| r.base.as_slice())),
                framed: summary(runs.iter().map(|r| r.framed.as_slice())),
                arm_only: summary(runs.iter().map(|r| r.arm_only.as_slice())),
                honest_within: ideal.iter().filter(|&&v| v <= 1.0).count() as f64
                    / ideal.len() as f64,
                honest: summary(runs.iter().flat_map(|r| r.ideal.iter().map(Vec::as_slice))),
            };
            eprintln!(
                "{}, {frames} frame(s), {} seeds:\n  base {:?}\n  in the frame, with its \
                 registration {:?}\n  in the frame, the arm's covariance alone {:?}\n  an \
                 exactly honest error: 95th percentile within in {:.3} of draws",
                nominal.name,
                seeds.end - seeds.start,
                m.base,
                m.framed,
                m.arm_only,
                m.honest_within
            );
            m
        })
        .collect()
}

/// 6 and 7 joints, 1, 2 and 3 frames (200 poses each), 50 seeds, 40
/// held-out poses per frame: predictions in the instrument's frame are
/// covered by their stated 95 % radius — at least 93 % of them, the
/// normalised RMS 0.9–1.1 — and so are those in the base; with the arm's
/// covariance alone (what the map stated before) they are not. Per seed
/// the 95th percentile of `|e| / r₉₅` is within 1 about as often as for an
/// exactly honest error (the draws of the stated covariance itself): not
/// in 93 % of the seeds, which no honest radius gives — one seed's errors
/// at every pose come from the same estimate's error, so they exceed
/// together. `cargo test --release --test integration frame_uncertainty
/// -- --ignored` (about 10 s).
#[test]
#[ignore = "50 seeds: run with --release -- --ignored"]
fn fifty_seeds_of_predictions_in_a_frame_are_covered() {
    for nominal in [
        Arm::without_limits("paper", DhParams::paper_nominal()),
        super::positions::panda(),
    ] {
        for m in measure(&nominal, 0..50, 200, 40) {
            let what = format!("{}, {} frame(s)", nominal.name, m.frames);
            for (kind, s) in [("base", &m.base), ("frame", &m.framed)] {
                assert!(s.covered >= 0.93, "{what}, {kind}: {s:?}");
                assert!((0.9..=1.1).contains(&s.nrms), "{what}, {kind}: {s:?}");
            }
            // Binomial: 50 seeds, p about 2/3, three standard deviations.
            assert!(
                m.framed.within >= m.honest_within - 0.2,
                "{what}: {:?}",
                m.framed
            );
            assert!(m.arm_only.covered < 0.93, "{what}: {:?}", m.arm_only);
        }
    }
}

/// The same on three seeds, what a debug suite affords (about 3 s): over
/// the 1, 2 and 3 frames' 720 held-out predictions in the frame, the stated
/// 95 % radius covers at least 92 % (with the arm's covariance alone it
/// covered 80 %) and the normalised RMS is 0.85–1.15; and the stated
/// covariance is what the predictions of arms and frames drawn from the
/// fit's joint covariance spread by (normalised RMS 0.95–1.05: the
/// frame's Jacobian, its turn and its step, right).
#[test]
fn predictions_in_a_frame_are_covered() {
    let nominal = Arm::without_limits("paper", DhParams::paper_nominal());
    let runs = measure(&nominal, 0..3, 200, 40);
    let pooled = |f: fn(&Measured) -> &Summary| {
        let n = runs.len() as f64;
        let mean = |g: fn(&Summary) -> f64| runs.iter().map(|m| g(f(m))).sum::<f64>() / n;
        (mean(|s| s.covered), mean(|s| s.nrms.powi(2)).sqrt())
    };
    let (covered, nrms) = pooled(|m| &m.framed);
    assert!(covered >= 0.92, "covered {covered}");
    assert!((0.85..=1.15).contains(&nrms), "normalised RMS {nrms}");
    let (covered, nrms) = pooled(|m| &m.base);
    assert!(covered >= 0.92, "base: covered {covered}");
    assert!((0.85..=1.15).contains(&nrms), "base: normalised RMS {nrms}");
    let (_, nrms) = pooled(|m| &m.honest);
    assert!(
        (0.95..=1.05).contains(&nrms),
        "honest draws: normalised RMS {nrms}"
    );
}

/// The map in an instrument's frame: each pose's radius that of
/// `position_covariances` in the frame, the bands of reach the base map's
/// (the same poses, the same places), and it says which frame and that
/// the frame's registration is in it; the base map says neither and its
/// JSON has no `frame`.
#[test]
fn the_map_in_a_frame_includes_the_registration_and_says_so() {
    use aacmm_core::plan::{sample_poses, uncertainty_map, uncertainty_map_in_frame};
    let nominal = Arm::without_limits("paper", DhParams::paper_nominal());
    let (_, c, _, report) = fitted(&nominal, 3, 100, 2);
    let cal = &report.calibration;
    let poses = sample_poses(&[None; 6], 0, 300, 5);
    let (free, cov) = cal.geometry_covariance().unwrap();
    let base = uncertainty_map(&cal.params, &poses, &free, &cov, "full turns").unwrap();
    let name = c.frames[1].0.as_str();
    let (free, x, joint) = cal.frame_covariance(name).unwrap();
    let frame = InFrame { name, x };
    let map =
        uncertainty_map_in_frame(&cal.params, &poses, &free, &joint, &frame, "full turns").unwrap();
    let seen = position_covariances(&cal.params, &poses, &free, &joint, Some(&frame)).unwrap();
    assert_eq!(map.points.len(), 300);
    for ((p, b), (_, s)) in map.points.iter().zip(&base.points).zip(&seen) {
        assert_eq!(p.radius_mm, radius(eigenvalues(*s)));
        assert!((p.reach_mm - b.reach_mm).abs() < 1e-9 && (p.height_mm - b.height_mm).abs() < 1e-9);
    }
    assert_ne!(map.rms_mm, base.rms_mm);
    assert_eq!(map.frame.as_deref(), Some(name));
    // The arm's covariance alone where the joint one belongs: an error.
    let wrong = position_covariances(&cal.params, &poses, &free, &cov, Some(&frame));
    assert!(wrong.is_err());
    let says = format!("in frame `{name}`, which includes the registration of frame `{name}`");
    assert!(map.describe().contains(&says), "{}", map.describe());
    assert!(
        !base.describe().contains("registration"),
        "{}",
        base.describe()
    );
    assert!(!serde_json::to_string(&base).unwrap().contains("\"frame\""));
}

/// A calibration against two frames reports the map in each frame beside
/// the base one: in `calibration.json` (`uncertainty_maps_in_frames`), the
/// summary and the page (a table each, its cells pointing into the JSON),
/// each saying that the frame's registration is in it.
#[test]
fn a_calibration_with_frames_reports_a_map_in_each() {
    let nominal = Arm::without_limits("paper", DhParams::paper_nominal());
    let (_, c, problem, report) = fitted(&nominal, 4, 100, 2);
    let base = report.uncertainty_map.as_ref().unwrap();
    let maps = &report.uncertainty_maps_in_frames;
    let names: Vec<&str> = maps.iter().map(|m| m.frame.as_deref().unwrap()).collect();
    let frames: Vec<&str> = c.frames.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, frames);
    let summary = report.summary();
    let page = aacmm_core::report::session_report(&report, &problem)
        .unwrap()
        .html;
    for (i, m) in maps.iter().enumerate() {
        assert_eq!(
            (m.poses, m.workspace.as_str()),
            (base.poses, base.workspace.as_str())
        );
        assert_ne!(m.rms_mm, base.rms_mm);
        let line = format!("Uncertainty map: {}\n", m.describe());
        assert!(
            line.contains("includes the registration of frame"),
            "{line}"
        );
        assert!(summary.contains(&line), "{summary}");
        let caption = format!(
            "in frame `{}`, its registration included</caption>",
            names[i]
        );
        assert!(page.contains(&caption), "no {caption}");
        assert!(page.contains(&format!("/uncertainty_maps_in_frames/{i}/rms_mm")));
    }
    let json = report.to_json();
    let back = aacmm_core::CalibrationReport::from_json(&json).unwrap();
    assert_eq!(&back.uncertainty_maps_in_frames, maps);
}
