//! The degenerate-calibration target: `identify` and `calibrate` on data
//! sets cut from simulated campaigns and bent out of shape.

use std::sync::OnceLock;

use aacmm_core::calibrate::robust::{Loss, Robust};
use aacmm_core::calibrate::{FixSpec, Method, ModelOptions, SolverSettings, calibrate};
use aacmm_core::dataset::DataSet;
use aacmm_core::domain::{Arm, Poses, ReferenceLength};
use aacmm_core::identify::identify;
use aacmm_core::io::{AngleUnit, parse_arm, parse_lengths, parse_poses};
use aacmm_core::params::{DhParams, JointModel, ParamId, ParamKind};
use aacmm_core::residuals::Noise;
use aacmm_core::simulate::{CampaignSettings, ErrorModel, SocketPlan, SocketPoint, simulate};
use aacmm_core::tolerances::Target;
use aacmm_core::tolerances::Tolerances;
use proptest::prelude::*;
use proptest::test_runner::{TestCaseError, TestError};

use crate::{Summary, Violation, no_panic};

/// A campaign to cut data sets from.
#[derive(Clone, Debug)]
pub struct Base {
    /// What it is.
    pub name: String,
    /// The nominal arm (the start of every fit).
    pub nominal: DhParams,
    /// Touches.
    pub poses: Poses,
    /// Reference lengths.
    pub lengths: Vec<ReferenceLength>,
}

/// The campaigns: the shipped one, simulated ones with one, two and three
/// sockets, and one with four collinear sockets.
pub fn bases() -> &'static [Base] {
    static BASES: OnceLock<Vec<Base>> = OnceLock::new();
    BASES.get_or_init(|| {
        let (arm, _) = parse_arm(
            include_str!("../../examples/paper-table-1.toml"),
            "arm.toml",
        )
        .expect("the shipped arm reads");
        let (poses, _) = parse_poses(
            include_str!("../../examples/paper-campaign/poses.csv"),
            "poses.csv",
            AngleUnit::Deg,
            Some(6),
        )
        .expect("the shipped poses read");
        let lengths = parse_lengths(
            include_str!("../../examples/paper-campaign/lengths.csv"),
            "lengths.csv",
        )
        .expect("the shipped lengths read");
        let mut bases = vec![Base {
            name: "shipped".into(),
            nominal: arm.params.clone(),
            poses,
            lengths,
        }];
        for count in 1..=3 {
            let mut s = CampaignSettings::new(count as u64, ErrorModel::Paper, count, 8);
            s.encoder_noise_deg = 0.005;
            s.probe_noise_mm = 0.01;
            bases.extend(simulated(&arm, &s, &format!("{count} socket(s)")));
        }
        // Four sockets on the line through the shipped S1 and S2 (both
        // reachable), a third of the way apart.
        let sockets = aacmm_core::io::parse_points(
            include_str!("../../examples/paper-campaign/sockets.csv"),
            "sockets.csv",
        )
        .expect("the shipped sockets read");
        let (a, b) = (sockets[0].1, sockets[1].1);
        let points = (0..4)
            .map(|k| {
                let t = k as f64 / 3.0;
                let p: [f64; 3] = std::array::from_fn(|i| a[i] + t * (b[i] - a[i]));
                SocketPoint {
                    label: format!("L{k}"),
                    x: p[0],
                    y: p[1],
                    z: p[2],
                }
            })
            .collect();
        let mut s = CampaignSettings::new(5, ErrorModel::Paper, 4, 8);
        s.sockets = SocketPlan::Given { file: None, points };
        bases.extend(simulated(&arm, &s, "collinear"));
        bases
    })
}

fn simulated(arm: &Arm, settings: &CampaignSettings, name: &str) -> Option<Base> {
    let c = simulate(arm, settings).ok()?;
    Some(Base {
        name: name.into(),
        nominal: arm.params.clone(),
        poses: c.poses,
        lengths: c.lengths,
    })
}

/// One degenerate case: which campaign, what is kept, and how it is bent.
#[derive(Clone, Debug)]
pub struct Degenerate {
    /// Index into [`bases`].
    pub base: usize,
    /// Sockets kept (the first ones), at least 1.
    pub sockets: usize,
    /// Touches kept per socket, at least 3.
    pub touches: usize,
    /// 0 none; 1 every touch twice; 2 the first socket's touches all copies
    /// of its first; 3 the first socket split into two labels (coincident
    /// sockets); 4 every socket's touches copies of its first.
    pub duplicates: u8,
    /// Added to every reading (rad), times a pseudo-random factor in
    /// `[-1, 1]`: 0, 1e-12, 1e-4, 10, 1e6.
    pub jitter: f64,
    /// Every reading scaled by this (1 usually; 1e6 for extremes).
    pub scale: f64,
    /// 0 none; 1 as simulated; 2 one ×1e300; 3 one ×1e-300; 4 uncertainty
    /// 1e-300; 5 uncertainty 1e300.
    pub lengths: u8,
    /// Encoder and probe σ (rad, mm), if stated.
    pub noise: (Option<f64>, Option<f64>),
    /// The solver.
    pub method: Method,
    /// 0 auto; 1 the paper's set; 2 nothing fixed; 3 everything but `a2`.
    pub fix: u8,
    /// Seed of the pseudo-random factors and the solver.
    pub seed: u64,
    /// 0 none; 1 a prior (0.5 mm, 0.1°); 2 `--robust huber`; 3 `--robust
    /// cauchy` with the prior; 4 a prior of 1e-300 mm/rad; 5 of 1e300; 6 the
    /// nominal's joint 2 in the Hayati model; 7 Hayati with the prior.
    pub extras: u8,
}

fn degenerate() -> impl Strategy<Value = Degenerate> {
    let n = bases().len();
    (
        (0..n, 1..=10usize, 3..=10usize, 0..=4u8),
        (
            prop::sample::select(vec![0.0, 1e-12, 1e-4, 10.0, 1e6]),
            prop::sample::select(vec![1.0, 1.0, 1.0, -1.0, 1e6, 1e-9]),
            0..=5u8,
        ),
        prop::sample::select(vec![
            (None, None),
            (Some(0.0), Some(0.0)),
            (Some(1e-300), None),
            (None, Some(1e300)),
            (Some(1e-4), Some(0.01)),
            (Some(1.0), Some(1e3)),
        ]),
        (
            prop::sample::select(vec![Method::Lm, Method::Global, Method::Hybrid, Method::Sa]),
            0..=3u8,
            any::<u64>(),
            prop::sample::select(vec![0u8, 0, 0, 1, 2, 3, 4, 5, 6, 7]),
        ),
    )
        .prop_map(
            |(
                (base, sockets, touches, duplicates),
                (jitter, scale, lengths),
                noise,
                (method, fix, seed, extras),
            )| {
                Degenerate {
                    base,
                    sockets,
                    touches,
                    duplicates,
                    jitter,
                    scale,
                    lengths,
                    noise,
                    method,
                    fix,
                    seed,
                    extras,
                }
            },
        )
}

/// A pseudo-random factor in `[-1, 1]` (SplitMix64).
fn factor(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// The case's data: its poses and lengths.
pub fn build(case: &Degenerate) -> (Poses, Vec<ReferenceLength>) {
    let base = &bases()[case.base % bases().len()];
    let mut labels: Vec<&str> = Vec::new();
    for l in base.poses.labels() {
        if !labels.contains(&l) {
            labels.push(l);
        }
    }
    labels.truncate(case.sockets.max(1));
    let mut rng = case.seed;
    let mut poses = Poses::new(base.poses.joints());
    for (k, label) in labels.iter().enumerate() {
        let rows: Vec<usize> = (0..base.poses.len())
            .filter(|&r| base.poses.label(r) == *label)
            .take(case.touches)
            .collect();
        for (i, &r) in rows.iter().enumerate() {
            let from = match case.duplicates {
                2 if k == 0 => rows[0],
                4 => rows[0],
                _ => r,
            };
            let name = if case.duplicates == 3 && k == 0 && i % 2 == 1 {
                format!("{label}'")
            } else {
                label.to_string()
            };
            let times = if case.duplicates == 1 { 2 } else { 1 };
            for _ in 0..times {
                let q: Vec<f64> = base
                    .poses
                    .reading(from)
                    .iter()
                    .map(|&x| x * case.scale + case.jitter * factor(&mut rng))
                    .collect();
                let line = poses.len() + 2;
                poses.push(&name, &q, line);
            }
        }
    }
    let kept = |l: &str| labels.contains(&l);
    let mut lengths: Vec<ReferenceLength> = if case.lengths == 0 {
        Vec::new()
    } else {
        base.lengths
            .iter()
            .filter(|l| kept(&l.a) && kept(&l.b))
            .cloned()
            .collect()
    };
    if let Some(first) = lengths.first_mut() {
        match case.lengths {
            2 => first.distance *= 1e300,
            3 => first.distance *= 1e-300,
            4 => first.uncertainty = Some(1e-300),
            5 => first.uncertainty = Some(1e300),
            _ => {}
        }
    }
    (poses, lengths)
}

/// The kind of an error, for the summary: its message past the location,
/// digits blanked, cut short.
fn kind(message: &str) -> String {
    let past = message
        .split_once(".csv: ")
        .or_else(|| message.split_once(".csv:"))
        .map_or(message, |(_, m)| m);
    past.chars()
        .map(|c| if c.is_ascii_digit() { '#' } else { c })
        .take(60)
        .collect()
}

/// Runs `identify` and `calibrate` on the case: `Ok(outcome)` when no rule
/// broke (no panic; a successful calibration has finite parameters and
/// cost), else what broke.
pub fn check_degenerate(case: &Degenerate) -> Result<String, String> {
    let base = &bases()[case.base % bases().len()];
    let (poses, lengths) = build(case);
    no_panic(|| {
        let data = match DataSet::from_poses(&poses, "poses.csv")
            .and_then(|d| d.with_lengths(&lengths, "lengths.csv"))
        {
            Ok(d) => d,
            Err(e) => return Ok(format!("data refused: {}", kind(&e.to_string()))),
        };
        let noise = Noise {
            encoder_rad: case.noise.0,
            probe_mm: case.noise.1,
            length_default_mm: 0.001,
            length_weight: None,
            ..Noise::default()
        };
        let hayati;
        let nominal = if case.extras >= 6 {
            // The exact conversion where joint 2 allows it, else joint 2
            // simply declared Hayati (β = 0, its d dropped): a poorer start,
            // still an arm.
            hayati = base.nominal.with_hayati(1).unwrap_or_else(|_| {
                let mut p = base.nominal.clone();
                if let Some(j) = p.joints.get_mut(1) {
                    j.model = JointModel::Hayati;
                    (j.d, j.beta) = (0.0, 0.0);
                }
                p
            });
            &hayati
        } else {
            &base.nominal
        };
        let _ = identify(nominal, &data, &noise, 1);
        let mut options = ModelOptions {
            noise,
            ..ModelOptions::default()
        };
        let mut settings = SolverSettings {
            method: case.method,
            seed: case.seed,
            threads: 1,
            ..SolverSettings::default()
        };
        settings.anneal.max_evaluations = settings.anneal.max_evaluations.min(3000);
        options.fix = match case.fix {
            0 => FixSpec::Auto,
            1 => FixSpec::Columns(
                [
                    (ParamKind::Theta, 0),
                    (ParamKind::D, 0),
                    (ParamKind::Theta, 5),
                    (ParamKind::Alpha, 5),
                    (ParamKind::Probe, 0),
                    (ParamKind::Probe, 1),
                ]
                .map(|(kind, index)| ParamId { kind, index }.column(6))
                .to_vec(),
            ),
            2 => FixSpec::Columns(Vec::new()),
            _ => FixSpec::Columns(
                (0..base.nominal.param_count())
                    .filter(|&c| c != 1)
                    .collect(),
            ),
        };
        let prior = |length_mm: f64, angle_rad: f64| {
            let mut t = Tolerances::new();
            t.set(Target::Length, length_mm, "mm")
                .and(t.set(Target::Angle, angle_rad, "rad"))
                .map(|()| t)
        };
        let tolerances = match case.extras {
            1 | 3 | 7 => Some(prior(0.5, 0.1f64.to_radians())),
            4 => Some(prior(1e-300, 1e-300)),
            5 => Some(prior(1e300, 1e300)),
            _ => None,
        };
        match tolerances {
            Some(Ok(t)) => options.prior = Some(t),
            Some(Err(e)) => return Ok(format!("prior refused: {}", kind(&e))),
            None => {}
        }
        options.robust = match case.extras {
            2 => Some(Robust::new(Loss::Huber)),
            3 => Some(Robust::new(Loss::Cauchy)),
            _ => None,
        };
        match calibrate(nominal, &data, &options, &settings) {
            Ok(c) => {
                if let Some(v) = c.params.to_vec().into_iter().find(|v| !v.is_finite()) {
                    return Err(format!("calibrated a non-finite parameter {v}"));
                }
                if !c.solver.final_cost.is_finite() {
                    return Err(format!("final cost {}", c.solver.final_cost));
                }
                Ok("calibrated".into())
            }
            Err(e) if e.to_string().is_empty() => Err("an empty error message".into()),
            Err(e) => Ok(format!("calibration refused: {}", kind(&e.to_string()))),
        }
    })
    .and_then(|r| r)
}

/// Runs `cases` degenerate calibrations from `seed`, in chunks (see
/// [`crate::run_readers`]).
pub fn run_degenerate(cases: u64, seed: u64, chunk: u64) -> Summary {
    let mut summary = Summary::default();
    let chunk = chunk.max(1);
    let mut done = 0;
    let mut k = 0;
    while done < cases {
        let n = chunk.min(cases - done);
        let mut runner = crate::readers::runner(n, seed.wrapping_mul(1_000_003).wrapping_add(k));
        let outcomes = std::cell::RefCell::new(Summary::default());
        let trace = std::env::var_os("AACMM_FUZZ_TRACE").is_some();
        let result = runner.run(&degenerate(), |case| {
            if trace {
                eprintln!("{case:?}");
            }
            let started = std::time::Instant::now();
            let mut o = outcomes.borrow_mut();
            o.cases += 1;
            let checked = check_degenerate(&case);
            if trace {
                eprintln!(
                    "  {:?} in {:.2} s",
                    checked,
                    started.elapsed().as_secs_f64()
                );
            }
            match checked {
                Ok(outcome) => {
                    o.count(&format!("{:?}: {outcome}", case.method));
                    Ok(())
                }
                Err(problem) => Err(TestCaseError::fail(problem)),
            }
        });
        let o = outcomes.into_inner();
        summary.cases += o.cases;
        for (key, v) in o.outcomes {
            *summary.outcomes.entry(key).or_default() += v;
        }
        if let Err(TestError::Fail(problem, case)) = result {
            summary.violations.push(Violation {
                target: "calibrate".into(),
                input: format!("{case:?}"),
                problem: problem.to_string(),
            });
        }
        done += n;
        k += 1;
    }
    summary
}
