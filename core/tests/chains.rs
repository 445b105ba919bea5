//! Any chain of revolute and prismatic joints (issue 39): the numerical
//! rank of positions, full poses and touches equals the theory's (`4R +
//! 2P + 3` and `4R + 2P + 6`; docs/calibration.md, "Any chain"), and
//! simulated tracker and touch campaigns recover the true arm of a track +
//! 6R robot, a lift + 7R mobile manipulator, a SCARA, a 5R arm and a
//! 9-joint chain.
//!
//! The always-on tests run a few seeds; the 50-seed campaigns are
//! `#[ignore]`d (README, "Any chain"):
//! `cargo test -p aacmm-core --test chains -- --ignored --nocapture`.

use std::f64::consts::PI;

use aacmm_core::calibrate::validate::position_errors;
use aacmm_core::domain::{Positions, ReferenceLength};
use aacmm_core::identify::chain::{Evidence, Seen, kinematic_rank, theory};
use aacmm_core::identify::{Identification, identify};
use aacmm_core::kernel::ArmKernel;
use aacmm_core::params::{ChainShape, DhJoint, DhParams, JointKind, JointModel};
use aacmm_core::residuals::Frame;
use aacmm_core::{
    Calibration, DataSet, FixSpec, Method, ModelOptions, Noise, SolverSettings, calibrate,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The shapes of the issue: a track + 6R robot, a lift + 7R mobile
/// manipulator, a SCARA, a 5R arm and a 9-joint chain with a slide in
/// the middle.
const SHAPES: [(&str, &str); 5] = [
    ("track + 6R", "PRRRRRR"),
    ("lift + 7R", "PRRRRRRR"),
    ("SCARA", "RRPR"),
    ("5R", "RRRRR"),
    ("9 joints", "RRPRRRRRR"),
];

/// A tracker's noise per coordinate, mm.
const SIGMA_MM: f64 = 0.02;

/// Limits of a revolute joint (±170°) and of a slide (mm).
const REVOLUTE_LIMIT: f64 = 170.0 * PI / 180.0;
const SLIDE_RANGE: [f64; 2] = [0.0, 800.0];

fn uniform(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    rng.random_range(lo..hi)
}

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    // Box–Muller: two uniforms, one normal.
    let u: f64 = rng.random_range(f64::EPSILON..1.0);
    let v: f64 = rng.random_range(0.0..1.0);
    (-2.0 * u.ln()).sqrt() * (2.0 * PI * v).cos()
}

/// A random nominal arm of `shape`. A SCARA's axes are parallel (as a
/// SCARA's are), its joints in the Hayati form that parallel axes need;
/// every other chain has twists between 25° and 155°, so no two
/// consecutive axes are nearly parallel.
fn random_arm(shape: ChainShape, rng: &mut ChaCha8Rng) -> DhParams {
    let scara = shape.to_string() == "RRPR";
    let joints = (0..shape.joints())
        .map(|i| {
            let kind = shape.kind(i);
            let a = uniform(rng, 50.0, 400.0);
            let theta = uniform(rng, -PI, PI);
            if scara {
                // Vertical axes; the quill's link keeps its offset in d.
                let alpha = if i == 1 { PI } else { 0.0 };
                let a = if i >= 2 { 0.0 } else { a };
                let beta = 0.0;
                return DhJoint::hayati(a, alpha, theta, beta).with_kind(kind);
            }
            let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            let alpha = sign * uniform(rng, 0.45, PI - 0.45);
            let d = match kind {
                JointKind::Prismatic => uniform(rng, 100.0, 300.0),
                JointKind::Revolute => uniform(rng, -300.0, 300.0),
            };
            DhJoint::dh(a, d, alpha, theta).with_kind(kind)
        })
        .collect();
    DhParams {
        joints,
        probe: [
            uniform(rng, -60.0, 60.0),
            uniform(rng, -60.0, 60.0),
            uniform(rng, 50.0, 200.0),
        ],
    }
}

/// Random readings within the limits: ±170° for a revolute joint, 0–800
/// mm for a slide.
fn random_readings(shape: ChainShape, rng: &mut ChaCha8Rng) -> Vec<f64> {
    (0..shape.joints())
        .map(|j| match shape.kind(j) {
            JointKind::Revolute => uniform(rng, -REVOLUTE_LIMIT, REVOLUTE_LIMIT),
            JointKind::Prismatic => uniform(rng, SLIDE_RANGE[0], SLIDE_RANGE[1]),
        })
        .collect()
}

/// A random instrument frame: a rotation vector of normal components (σ 1
/// rad: any orientation), a station up to 3 m off along each axis.
fn random_frame(rng: &mut ChaCha8Rng) -> [f64; 6] {
    std::array::from_fn(|k| {
        if k < 3 {
            gauss(rng)
        } else {
            uniform(rng, -3000.0, 3000.0)
        }
    })
}

/// `poses` positions of `truth`'s probe at random readings, seen through
/// `frame` with `SIGMA_MM` of noise per coordinate.
fn tracker_positions(
    truth: &DhParams,
    frame: &[f64; 6],
    poses: usize,
    rng: &mut ChaCha8Rng,
) -> Positions {
    let shape = truth.shape().unwrap();
    let kernel = ArmKernel::new(truth).unwrap();
    let mut positions = Positions::new(shape.joints());
    for i in 0..poses {
        let q = random_readings(shape, rng);
        let p = Frame::apply(frame, kernel.position(&q).unwrap());
        let seen = p.map(|v| v + SIGMA_MM * gauss(rng));
        positions.push(&format!("P{}", i + 1), "instrument", &q, seen, None, i + 2);
    }
    positions
}

fn data_of(positions: Positions, shape: ChainShape) -> DataSet {
    (DataSet::from_positions(positions, "sim.csv").unwrap())
        .for_shape(shape)
        .unwrap()
}

fn tracker_noise() -> Noise {
    Noise {
        position_mm: Some(SIGMA_MM),
        ..Noise::default()
    }
}

/// The numerical rank of positions and of full poses, in an unknown frame,
/// is the theory's for every shape, with the frame (and the tool's
/// rotation) counted: 33 and 36 for the lift + 7R.
#[test]
fn kinematic_rank_is_the_theorys_for_every_shape() {
    for (seed, (name, text)) in SHAPES.iter().enumerate() {
        let shape: ChainShape = text.parse().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(seed as u64);
        let arm = random_arm(shape, &mut rng);
        let rows: Vec<Vec<f64>> = (0..60).map(|_| random_readings(shape, &mut rng)).collect();
        for seen in [Seen::Positions, Seen::Poses] {
            let k = kinematic_rank(&arm, &rows, seen).unwrap();
            assert!(
                k.agrees(),
                "{name} {text}, {seen:?}: rank {} (arm {}), theory {:?}; singular values {:?}",
                k.rank,
                k.arm_rank,
                k.theory,
                k.singular_values
            );
            // A clear gap: the smallest counted singular value is far above
            // the largest uncounted one.
            let (kept, dropped) = (k.singular_values[k.rank - 1], k.singular_values[k.rank]);
            assert!(
                dropped < 1e-3 * kept,
                "{name}, {seen:?}: {kept} then {dropped}"
            );
        }
    }
    let lift: ChainShape = "PRRRRRRR".parse().unwrap();
    assert_eq!(theory(lift, Evidence::Positions).complete, 33);
    assert_eq!(theory(lift, Evidence::Poses).complete, 36);
}

/// `identify` on positions in a fitted frame finds the theory's rank of
/// the arm's parameters (`4R + 2P − 3`) for every shape, and names a1 of
/// a prismatic first joint with θ1 and d1 as base motion.
#[test]
fn identify_finds_the_theorys_rank_on_positions() {
    for (seed, (name, text)) in SHAPES.iter().enumerate() {
        let shape: ChainShape = text.parse().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(100 + seed as u64);
        let arm = random_arm(shape, &mut rng);
        let frame = random_frame(&mut rng);
        let data = data_of(tracker_positions(&arm, &frame, 80, &mut rng), shape);
        let id = identify(&arm, &data, &tracker_noise(), 1).unwrap();
        let expected = theory(shape, Evidence::Positions).arm;
        assert_eq!(id.rank, expected, "{name} {text}: {:?}", id.fixed);
        assert_eq!(id.free.len(), expected, "{name}");
        let base: Vec<String> = (id.fixed.iter())
            .filter(|f| f.reason.starts_with("base motion"))
            .map(|f| f.id.to_string())
            .collect();
        // A Hayati joint 1 (the SCARA's) has no d1.
        let want: &[&str] = match (shape.is_prismatic(0), arm.joints[0].model) {
            (true, _) => &["a1", "d1", "theta1"],
            (false, JointModel::Hayati) => &["theta1"],
            (false, JointModel::Dh) => &["d1", "theta1"],
        };
        assert_eq!(base, want, "{name}");
        assert!(!id.rules.iter().any(|r| r.name == "scale"), "{name}");
    }
}

/// Touches of sockets of unknown position: with reference lengths they
/// identify what positions in a fitted frame do (`4R + 2P − 3`); without
/// one, a chain of revolute joints loses its size (the scale rule), while
/// a slide moving among the touches of a point fixes it.
#[test]
fn touches_see_what_the_theory_says() {
    for (seed, (name, text)) in SHAPES.iter().enumerate() {
        let shape: ChainShape = text.parse().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(200 + seed as u64);
        let arm = random_arm(shape, &mut rng);
        let (labels, readings, centres) = touches(&arm, (8, 6), 0.0, &mut rng);
        let lengths: Vec<ReferenceLength> = (1..3)
            .map(|b| ReferenceLength {
                a: "S0".into(),
                b: format!("S{b}"),
                distance: distance(centres[0], centres[b]),
                uncertainty: None,
                line: b,
            })
            .collect();
        let noise = Noise::default();
        // A slide moves when its reading differs between touches of a
        // socket (a SCARA's quill cannot: it alone sets the height).
        let moves = (0..shape.joints())
            .filter(|&j| shape.is_prismatic(j))
            .any(|j| {
                (labels.iter().zip(&readings)).any(|(l, q)| {
                    let first = labels.iter().position(|m| m == l).unwrap();
                    (q[j] - readings[first][j]).abs() > 1e-6
                })
            });
        assert_eq!(
            moves,
            *text != "RRPR" && shape.prismatic_mask() != 0,
            "{name}"
        );
        let touches_alone = Evidence::Touches { slides_move: moves };
        for (with_lengths, evidence) in
            [(true, Evidence::TouchesAndLengths), (false, touches_alone)]
        {
            let given = if with_lengths { &lengths[..] } else { &[] };
            let data = (DataSet::from_touches(&labels, &readings, given).unwrap())
                .for_shape(shape)
                .unwrap();
            let id = identify(&arm, &data, &noise, 1).unwrap();
            let expected = theory(shape, evidence).arm;
            assert_eq!(id.rank, expected, "{name} {text}, {evidence:?}");
            let scale = id.rules.iter().any(|r| r.name == "scale");
            assert_eq!(scale, !with_lengths && !moves, "{name}, {evidence:?}");
        }
    }
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt()
}

/// `sockets` sockets touched `per` times each by `arm` in different
/// readings within the limits (damped least squares from random starts),
/// each touch `probe_mm` (1σ per coordinate) off its socket's centre:
/// their labels, readings and the sockets' centres.
#[allow(clippy::type_complexity)]
fn touches(
    arm: &DhParams,
    (sockets, per): (usize, usize),
    probe_mm: f64,
    rng: &mut ChaCha8Rng,
) -> (Vec<String>, Vec<Vec<f64>>, Vec<[f64; 3]>) {
    let shape = arm.shape().unwrap();
    let kernel = ArmKernel::new(arm).unwrap();
    let (mut labels, mut rows, mut centres) = (Vec::new(), Vec::new(), Vec::new());
    for s in 0..sockets {
        let centre = kernel.position(&random_readings(shape, rng)).unwrap();
        centres.push(centre);
        let mut found = 0;
        for _ in 0..10_000 {
            let target: [f64; 3] = std::array::from_fn(|i| centre[i] + probe_mm * gauss(rng));
            let start = random_readings(shape, rng);
            let q = reach(&kernel, target, start).map(|q| wrapped(shape, q));
            if let Some(q) = q.filter(|q| within_limits(shape, q)) {
                labels.push(format!("S{s}"));
                rows.push(q);
                found += 1;
                if found == per {
                    break;
                }
            }
        }
        assert_eq!(
            found, per,
            "socket {s} of {shape}: too few touches within the limits"
        );
    }
    (labels, rows, centres)
}

/// Readings with every revolute joint's wrapped to ±180°.
fn wrapped(shape: ChainShape, q: Vec<f64>) -> Vec<f64> {
    (q.into_iter().enumerate())
        .map(|(j, v)| match shape.kind(j) {
            JointKind::Revolute => aacmm_core::simulate::wrap(v),
            JointKind::Prismatic => v,
        })
        .collect()
}

/// Whether (wrapped) readings are within the limits of [`random_readings`].
fn within_limits(shape: ChainShape, q: &[f64]) -> bool {
    q.iter().enumerate().all(|(j, &v)| match shape.kind(j) {
        JointKind::Revolute => v.abs() <= REVOLUTE_LIMIT,
        JointKind::Prismatic => (SLIDE_RANGE[0]..=SLIDE_RANGE[1]).contains(&v),
    })
}

/// Readings that put `kernel`'s probe at `target` (within 1 nm), by
/// damped least squares from `q`; `None` if they do not converge.
fn reach(kernel: &ArmKernel, target: [f64; 3], mut q: Vec<f64>) -> Option<Vec<f64>> {
    let n = q.len();
    let mut jac = vec![[0.0; 3]; n];
    for _ in 0..200 {
        let p = kernel.joint_jacobian(&q, &mut jac).ok()?;
        let e: [f64; 3] = std::array::from_fn(|i| target[i] - p[i]);
        if e.iter().all(|v| v.abs() < 1e-9) {
            return Some(q);
        }
        // (J Jᵀ + λ²I) y = e, then δq = Jᵀ y.
        let lambda2 = 1.0;
        let a = nalgebra::Matrix3::from_fn(|r, c| {
            (0..n).map(|j| jac[j][r] * jac[j][c]).sum::<f64>() + if r == c { lambda2 } else { 0.0 }
        });
        let y = a.cholesky()?.solve(&nalgebra::Vector3::from(e));
        for j in 0..n {
            q[j] += (0..3).map(|r| jac[j][r] * y[r]).sum::<f64>();
        }
    }
    None
}

/// One simulated tracker campaign's figures.
struct Outcome {
    /// `((estimate − truth)/σ)²` of every free parameter and frame column.
    z2: Vec<f64>,
    /// Held-out mean error of the calibrated arm over the true arm's.
    ratio: f64,
    /// `identify`'s rank and the theory's.
    rank: (usize, usize),
}

/// A tracker campaign of `shape` and `seed`: a random nominal arm; the
/// true arm off it ([`perturbed`]); positions ([`tracker_poses`]) seen
/// from a random tracker station with 0.02 mm of noise; a fit from the nominal; 60
/// held-out positions from the same station, drawn apart from the fit's.
fn tracker_campaign(shape: ChainShape, seed: u64) -> Outcome {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let nominal = random_arm(shape, &mut rng);
    let frame = random_frame(&mut rng);
    let poses = tracker_poses(shape);
    let first = data_of(tracker_positions(&nominal, &frame, poses, &mut rng), shape);
    let id = identify(&nominal, &first, &tracker_noise(), 1).unwrap();
    let truth = perturbed(&nominal, &id, &mut rng);
    let data = data_of(tracker_positions(&truth, &frame, poses, &mut rng), shape);
    let cal = fit(&nominal, &data, tracker_noise(), &id, seed);
    let held = data_of(tracker_positions(&truth, &frame, 60, &mut rng), shape);
    let held = held.positions().unwrap();
    let true_frame = vec![("instrument".to_string(), frame)];
    let after = position_errors(&cal.params, held, &cal.frames()).unwrap();
    let ideal = position_errors(&truth, held, &true_frame).unwrap();
    Outcome {
        z2: normalised_errors(&cal, &truth, Some(&frame)),
        ratio: after.mean / ideal.mean,
        rank: (id.rank, theory(shape, Evidence::Positions).arm),
    }
}

/// A touch campaign of `shape` and `seed`: a random nominal arm; the true
/// arm off it ([`perturbed`]); sockets ([`touch_data`]) touched 10 times
/// each within the limits, 0.01 mm of probe noise, 4 reference lengths; a
/// fit from the nominal; held out: as many fresh sockets, the mean single-point error (a
/// touch's distance from its socket's centroid) of the calibrated arm
/// against the true arm's.
fn touch_campaign(shape: ChainShape, seed: u64) -> Outcome {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let nominal = random_arm(shape, &mut rng);
    let first = touch_data(&nominal, &mut rng);
    let id = identify(&nominal, &first, &probe_noise(), 1).unwrap();
    let truth = perturbed(&nominal, &id, &mut rng);
    let data = touch_data(&truth, &mut rng);
    let cal = fit(&nominal, &data, probe_noise(), &id, seed);
    let held = touch_data(&truth, &mut rng);
    Outcome {
        z2: normalised_errors(&cal, &truth, None),
        ratio: single_point(&cal.params, &held) / single_point(&truth, &held),
        rank: (id.rank, theory(shape, Evidence::TouchesAndLengths).arm),
    }
}

/// Poses of a tracker campaign: a fit of `p` parameters on `m` residual
/// degrees of freedom predicts new positions about `p/2m` worse than the
/// true arm does, so the campaign has `m ≥ 20p` (3 per pose; `p` the
/// arm's identifiable combinations and the frame's 6), for half the 5 %
/// the issue allows, and at least 150 poses.
fn tracker_poses(shape: ChainShape) -> usize {
    let p = theory(shape, Evidence::Positions).arm + 6;
    (20 * p).div_ceil(3).max(150)
}

/// The probe's noise of the touch campaigns, mm.
const PROBE_MM: f64 = 0.01;

fn probe_noise() -> Noise {
    Noise {
        probe_mm: Some(PROBE_MM),
        ..Noise::default()
    }
}

/// Sockets touched 10 times by `arm`, with the distances between four
/// pairs of their centres as reference lengths. The sockets grow with the
/// parameters: a fit of `p` parameters on `m` residual degrees of freedom
/// predicts new touches about `p/2m` worse than the true arm does, so the
/// campaign has `m ≥ 20p` (a socket of 10 touches gives 27), for half the
/// 5 % the issue allows, and at least 12 sockets.
fn touch_data(arm: &DhParams, rng: &mut ChaCha8Rng) -> DataSet {
    let p = theory(arm.shape().unwrap(), Evidence::TouchesAndLengths).arm;
    let sockets = (20 * p).div_ceil(27).max(12);
    let (labels, readings, centres) = touches(arm, (sockets, 10), PROBE_MM, rng);
    let lengths: Vec<ReferenceLength> = (0..4)
        .map(|k| ReferenceLength {
            a: format!("S{}", 2 * k),
            b: format!("S{}", 2 * k + 1),
            distance: distance(centres[2 * k], centres[2 * k + 1]),
            uncertainty: None,
            line: k + 2,
        })
        .collect();
    (DataSet::from_touches(&labels, &readings, &lengths).unwrap())
        .for_shape(arm.shape().unwrap())
        .unwrap()
}

/// The mean distance of every touch of `data` from its point's centroid,
/// computed with `arm`.
fn single_point(arm: &DhParams, data: &DataSet) -> f64 {
    let kernel = ArmKernel::new(arm).unwrap();
    let mut sum = 0.0;
    for point in data.points() {
        let p: Vec<[f64; 3]> = (point.touches.clone())
            .map(|i| kernel.position(data.reading(i)).unwrap())
            .collect();
        let c: [f64; 3] =
            std::array::from_fn(|k| p.iter().map(|v| v[k]).sum::<f64>() / p.len() as f64);
        sum += p.iter().map(|v| distance(*v, c)).sum::<f64>();
    }
    sum / data.len() as f64
}

/// The true arm: `nominal` off by random errors (0.3 mm, 0.02°, 1σ) in
/// the parameters `id` leaves free; the fixed ones stay nominal, so that
/// every free parameter has a true value to be compared with.
fn perturbed(nominal: &DhParams, id: &Identification, rng: &mut ChaCha8Rng) -> DhParams {
    let mut truth = nominal.clone();
    for f in &id.free {
        let step = if f.id.kind.is_length() {
            0.3
        } else {
            0.02_f64.to_radians()
        };
        *truth.get_mut(f.id) += step * gauss(rng);
    }
    truth
}

/// A fit of `data` from `nominal` with LM, fixing what `id` fixed (the
/// truth's fixed parameters are nominal, its free ones all free; the
/// pivoting's choice among equals could differ on other data).
fn fit(
    nominal: &DhParams,
    data: &DataSet,
    noise: Noise,
    id: &Identification,
    seed: u64,
) -> Calibration {
    let n = nominal.joint_count();
    let model = ModelOptions {
        noise,
        fix: FixSpec::Columns(id.fixed.iter().map(|f| f.id.column(n)).collect()),
        ..ModelOptions::default()
    };
    let settings = SolverSettings {
        method: Method::Lm,
        ..SolverSettings::default()
    };
    let cal = calibrate(nominal, data, &model, &settings).unwrap();
    let shape = nominal.shape().unwrap();
    assert!(
        cal.solver.is_solution_usable(),
        "{shape} seed {seed}: {:?}",
        cal.solver
    );
    cal
}

/// `((estimate − truth)/σ)²` of every free parameter and, with a frame,
/// of its six columns (its rotation as the local step `log(R_true R̂ᵀ)`).
fn normalised_errors(cal: &Calibration, truth: &DhParams, frame: Option<&[f64; 6]>) -> Vec<f64> {
    let mut out: Vec<f64> = (cal.parameters.iter())
        .filter(|e| e.fixed.is_none())
        .map(|e| {
            let mut d = e.calibrated - truth.get(e.id);
            if !e.id.kind.is_length() {
                d = aacmm_core::simulate::wrap(d);
            }
            (d / e.sigma.unwrap()).powi(2)
        })
        .collect();
    let Some(frame) = frame else {
        return out;
    };
    let (_, fitted) = &cal.frames()[0];
    let d = Frame::difference(fitted, frame);
    for (k, aux) in cal.auxiliary.iter().take(6).enumerate() {
        let sigma = aux.sigma.unwrap();
        let sigma = if k < 3 { sigma.to_radians() } else { sigma };
        out.push((d[k] / sigma).powi(2));
    }
    out
}

/// Runs `seeds` campaigns of every shape, of tracker positions and of
/// touches with lengths: identify's rank the theory's on every seed and,
/// when the run is the `claim` (50 seeds), the figures — the
/// normalised error RMS within 0.8–1.25, the held-out error within 5 % of
/// the true arm's (mean over the seeds); a run of a few seeds checks the
/// RMS against its own sampling spread and every seed's held-out error
/// within 15 %. Prints a line per shape and evidence for the README's table.
fn campaigns(seeds: std::ops::Range<u64>, claim: bool) {
    type Run = fn(ChainShape, u64) -> Outcome;
    let kinds: [(&str, Run); 2] = [
        ("tracker positions", tracker_campaign),
        ("touches + lengths", touch_campaign),
    ];
    for (name, text) in SHAPES {
        let shape: ChainShape = text.parse().unwrap();
        for (evidence, run) in kinds {
            let (mut z2, mut ratios) = (Vec::new(), Vec::new());
            for seed in seeds.clone() {
                let o = run(shape, seed);
                assert_eq!(o.rank.0, o.rank.1, "{name}, {evidence}, seed {seed}: rank");
                z2.extend(o.z2);
                ratios.push(o.ratio);
            }
            let rms = (z2.iter().sum::<f64>() / z2.len() as f64).sqrt();
            let ratio = ratios.iter().sum::<f64>() / ratios.len() as f64;
            let worst = ratios.iter().copied().fold(0.0, f64::max);
            eprintln!(
                "{name} ({text}), {evidence}, {} seeds: normalised RMS {rms:.3} over {} \
                 estimates; held-out error {ratio:.4} × the true arm's (worst seed {worst:.4}); \
                 rank = theory on every seed",
                ratios.len(),
                z2.len()
            );
            if claim {
                let rms_ok = (0.8..=1.25).contains(&rms);
                assert!(rms_ok, "{name}, {evidence}: normalised RMS {rms}");
                assert!(ratio <= 1.05, "{name}, {evidence}: held-out ratio {ratio}");
            } else {
                // A few seeds: the mean square of k normalised errors has a
                // standard deviation of √(2/k); 4 of them either way.
                let band = 4.0 * (2.0 / z2.len() as f64).sqrt();
                let ms = rms * rms;
                assert!((ms - 1.0).abs() <= band, "{name}, {evidence}: RMS {rms}");
                assert!(worst <= 1.15, "{name}, {evidence}: held-out ratio {worst}");
            }
        }
    }
}

/// Two seeds of every shape, always on (the figures' spread over two seeds
/// is wide; the 50-seed run below is the claim).
#[test]
fn campaigns_recover_the_true_arm() {
    campaigns(0..2, false);
}

/// The 50 seeds of every shape and both kinds of evidence (a few
/// minutes in a debug build).
#[test]
#[ignore]
fn campaigns_recover_the_true_arm_over_50_seeds() {
    campaigns(0..50, true);
}
