//! Robust fitting (issue 15): touches displaced on purpose in simulated
//! campaigns are named by where they were read, and a robust fit (Huber or
//! Cauchy) measures fresh sockets of the true arm about as well as the true
//! arm does, where plain least squares does not.

use aacmm_core::calibrate::robust::{DOWNWEIGHTED, Loss, Robust};
use aacmm_core::calibrate::validate::figures;
use aacmm_core::calibrate::{CalibrationError, ModelOptions, SolverSettings};
use aacmm_core::kernel::ArmKernel;
use aacmm_core::params::DhParams;
use aacmm_core::residuals::Noise;
use aacmm_core::session::{CalibrationReport, Problem};
use aacmm_core::simulate::{Campaign, CampaignSettings, ErrorModel, simulate};
use aacmm_core::{Arm, DataSet, read_arm};

mod common;

fn nominal() -> Arm {
    let path = format!(
        "{}/../examples/paper-table-1.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    read_arm(path.as_ref()).unwrap().0
}

fn settings(seed: u64) -> CampaignSettings {
    let mut s = CampaignSettings::new(seed, ErrorModel::Paper, 10, 10);
    s.encoder_noise_deg = 0.005;
    s.probe_noise_mm = 0.01;
    s.reference_lengths = 3;
    s
}

fn options(robust: Option<Loss>) -> ModelOptions {
    ModelOptions {
        noise: Noise {
            encoder_rad: Some(0.005f64.to_radians()),
            probe_mm: Some(0.01),
            ..Noise::default()
        },
        robust: robust.map(Robust::new),
        ..ModelOptions::default()
    }
}

/// Moves touch `i` (its readings in `q`) so that the true arm puts the
/// probe `mm` further off, by turning the joint with the longest lever
/// among the first three.
fn displace(q: &mut [Vec<f64>], i: usize, mm: f64, truth: &DhParams) {
    let k = ArmKernel::new(truth).unwrap();
    let q0 = q[i].clone();
    let p0 = k.position(&q0).unwrap();
    let moved = |j: usize, d: f64| {
        let mut r = q0.clone();
        r[j] += d;
        aacmm_core::geometry::distance(&k.position(&r).unwrap(), &p0)
    };
    let j = (0..3)
        .max_by(|&a, &b| moved(a, 1e-6).total_cmp(&moved(b, 1e-6)))
        .unwrap();
    let mut d = mm * 1e-6 / moved(j, 1e-6);
    for _ in 0..3 {
        d *= mm / moved(j, d);
    }
    assert!((moved(j, d) - mm).abs() < 1e-6 * mm, "{} mm", moved(j, d));
    q[i][j] += d;
}

struct Case {
    campaign: Campaign,
    data: DataSet,
    /// Touch indices displaced (their file line is index + 1).
    moved: Vec<usize>,
}

fn case(seed: u64, moved: &[usize], mm: f64) -> Case {
    let campaign = simulate(&nominal(), &settings(seed)).unwrap();
    let labels: Vec<String> = campaign.poses.labels().map(str::to_string).collect();
    let mut q: Vec<Vec<f64>> = campaign.poses.rows().map(<[f64]>::to_vec).collect();
    for &i in moved {
        displace(&mut q, i, mm, &campaign.true_arm.params);
    }
    let data = DataSet::from_touches(&labels, &q, &campaign.lengths).unwrap();
    Case {
        campaign,
        data,
        moved: moved.to_vec(),
    }
}

fn run(data: &DataSet, robust: Option<Loss>) -> CalibrationReport {
    Problem::new(nominal(), data.clone(), options(robust))
        .unwrap()
        .run(&SolverSettings::default())
        .unwrap()
}

/// Held-out repeatability of `params` over that of the true arm, on fresh
/// sockets of the same true arm.
fn held_out_ratio(c: &Case, params: &DhParams, fresh: &DataSet) -> f64 {
    figures(params, fresh).unwrap().e_mean
        / figures(&c.campaign.true_arm.params, fresh).unwrap().e_mean
}

/// One case: every displaced touch named (plain and robust), the robust
/// fits within 15 % of the true arm on fresh sockets, plain least squares
/// worse than both. Returns the ratios (plain, huber, cauchy).
fn check(c: &Case, fresh_seed: u64) -> [f64; 3] {
    let fresh = simulate(&nominal(), &settings(fresh_seed))
        .unwrap()
        .data_set()
        .unwrap();
    let mut ratios = [0.0; 3];
    for (slot, robust) in [None, Some(Loss::Huber), Some(Loss::Cauchy)]
        .into_iter()
        .enumerate()
    {
        let report = run(&c.data, robust);
        let cal = &report.calibration;
        let named: Vec<&str> = cal.checks.outliers.iter().map(|o| o.at.as_str()).collect();
        for &i in &c.moved {
            let at = format!("<arrays>:{}", i + 1);
            assert!(
                named.contains(&at.as_str()),
                "{robust:?}: {at} not in {named:?}"
            );
        }
        ratios[slot] = held_out_ratio(c, &cal.params, &fresh);
        if let Some(loss) = robust {
            let fit = cal.robust.as_ref().expect("a robust fit reports itself");
            assert_eq!(fit.loss, loss);
            assert!(fit.converged, "{loss:?}: {} passes", fit.passes);
            assert_eq!(fit.weights.len(), c.data.len());
            // Every displaced touch is downweighted, by its file:line.
            let low: Vec<&str> = fit.downweighted().iter().map(|t| t.at.as_str()).collect();
            for &i in &c.moved {
                let at = format!("<arrays>:{}", i + 1);
                assert!(low.contains(&at.as_str()), "{loss:?}: {at} not in {low:?}");
            }
            // Not a poor fit for the outliers it downweighted.
            assert!(report.is_usable(), "{loss:?}: {:?}", report.verdict);
            assert!(cal.checks.chi_square.is_none());
            assert!(
                report
                    .summary()
                    .contains(&format!("weighed below {DOWNWEIGHTED}: <arrays>:"))
            );
        } else {
            assert!(cal.robust.is_none());
        }
    }
    println!(
        "moved {:?}: held-out e / true arm's: plain {:.3}, huber {:.3}, cauchy {:.3}",
        c.moved, ratios[0], ratios[1], ratios[2]
    );
    ratios
}

#[test]
fn one_touch_displaced_2_mm() {
    let c = case(7, &[16], 2.0);
    let [plain, huber, cauchy] = check(&c, 10_007);
    assert!(huber <= 1.15 && cauchy <= 1.15, "{huber} {cauchy}");
    assert!(plain > huber.max(cauchy) && plain > 1.15, "plain {plain}");
}

#[test]
fn five_percent_of_touches_displaced_1_mm() {
    let c = case(8, &[3, 23, 47, 68, 91], 1.0);
    let [plain, huber, cauchy] = check(&c, 10_008);
    assert!(huber <= 1.15 && cauchy <= 1.15, "{huber} {cauchy}");
    assert!(plain > huber.max(cauchy) && plain > 1.15, "plain {plain}");
}

#[test]
fn clean_campaigns_keep_their_weights_and_verdict() {
    for seed in [21u64, 22, 23] {
        let c = case(seed, &[], 0.0);
        let plain = run(&c.data, None);
        for loss in Loss::ALL {
            let report = run(&c.data, Some(loss));
            assert!(
                report.is_usable(),
                "seed {seed} {loss:?}: {:?}",
                report.verdict
            );
            let fit = report.calibration.robust.as_ref().unwrap();
            assert!(fit.downweighted().is_empty(), "seed {seed} {loss:?}");
            assert!(
                (fit.scale - 1.0).abs() < 0.25,
                "seed {seed} {loss:?}: {}",
                fit.scale
            );
            // The robust arm is the plain one within its uncertainty.
            for (p, r) in plain
                .calibration
                .parameters
                .iter()
                .zip(&report.calibration.parameters)
            {
                if let (Some(sp), Some(sr)) = (p.sigma, r.sigma) {
                    assert!(
                        (p.calibrated - r.calibrated).abs() < sp.max(sr),
                        "seed {seed} {loss:?} {}: {} vs {} (σ {sp})",
                        p.id,
                        p.calibrated,
                        r.calibrated
                    );
                }
            }
        }
    }
}

#[test]
fn robust_fits_work_for_every_solver_and_are_deterministic() {
    use aacmm_core::calibrate::Method;
    let c = case(9, &[40], 2.0);
    for method in [Method::Lm, Method::Sa, Method::Hybrid, Method::Global] {
        let o = options(Some(Loss::Cauchy));
        let settings = SolverSettings::default().with_method(method);
        let a = Problem::new(nominal(), c.data.clone(), o.clone())
            .unwrap()
            .run(&settings)
            .unwrap();
        let fit = a.calibration.robust.as_ref().unwrap();
        let low: Vec<&str> = fit.downweighted().iter().map(|t| t.at.as_str()).collect();
        assert_eq!(low, ["<arrays>:41"], "{method:?}");
        // The refits are LM whatever ran before: the stop names it.
        assert!(
            a.calibration.solver.stop.lm().is_some(),
            "{method:?}: {}",
            a.calibration.solver.stop.describe()
        );
        assert!(a.is_usable(), "{method:?}: {:?}", a.verdict);
        let b = Problem::new(nominal(), c.data.clone(), o)
            .unwrap()
            .run(&settings)
            .unwrap();
        assert_eq!(a.to_json(), b.to_json(), "{method:?}");
    }
}

#[test]
fn a_bad_tuning_constant_is_refused_by_its_field() {
    let c = case(1, &[], 0.0);
    for k in [-1.0, 0.0, f64::NAN, f64::INFINITY] {
        let o = ModelOptions {
            robust: Some(Robust {
                loss: Loss::Huber,
                scale_k: k,
            }),
            ..options(None)
        };
        match Problem::new(nominal(), c.data.clone(), o) {
            Err(CalibrationError::Option(e)) => assert_eq!(e.field(), "robust.scale_k"),
            other => panic!("k = {k} accepted: {:?}", other.map(|_| ())),
        }
    }
}

/// The same bytes at 1, 2 and 4 threads: 512 points (8 chunks), so the normal
/// equations of every refit split across 2 threads.
#[test]
fn a_robust_report_is_the_same_at_1_2_and_4_threads() {
    use aacmm_core::parallel::threads_for;
    use aacmm_core::residuals::point_chunks;
    let data = common::many_points(512);
    assert_eq!(threads_for(point_chunks(data.points().len()), 2), 2);
    let report = |threads: usize| {
        common::lm_report_on_threads(&nominal(), &data, threads, |o, _| {
            o.robust = Some(Robust::new(Loss::Cauchy))
        })
    };
    let one = report(1);
    assert!(one.contains("\"robust\""));
    assert_eq!(one, report(2), "2 threads");
    assert_eq!(one, report(4), "4 threads");
}

/// Without stated noise, with a prior: the touch σ estimated with the
/// outliers in weighs the touches too little against the prior, so the
/// refits run at σ·σ̂ until the robust scale settles — σ̂ ends near 1 and the
/// touch σ near the campaign's own (one touch in 20 moved 1 mm).
#[test]
fn with_a_prior_and_no_stated_noise_the_robust_scale_settles() {
    use aacmm_core::tolerances::Tolerances;
    let moved: Vec<usize> = (0..100).step_by(20).collect();
    let c = case(3, &moved, 1.0);
    let o = ModelOptions {
        robust: Some(Robust::new(Loss::Huber)),
        prior: Tolerances::parse("length=1mm,angle=0.5deg", 6).unwrap(),
        ..ModelOptions::default()
    };
    let plain = ModelOptions {
        robust: None,
        ..o.clone()
    };
    let fit = |o: &ModelOptions| {
        Problem::new(nominal(), c.data.clone(), o.clone())
            .unwrap()
            .run(&SolverSettings::default())
            .unwrap()
            .calibration
    };
    let (robust, plain) = (fit(&o), fit(&plain));
    let scale = robust.robust.as_ref().unwrap().scale;
    assert!((scale - 1.0).abs() <= 0.05, "robust scale {scale}");
    // The campaign's touch scatter (0.01 mm probe, 0.005° encoders) is
    // ≈ 0.035 mm; the plain fit's estimate holds the 1 mm outliers.
    let (r, p) = (robust.dof.touch_sigma_mm, plain.dof.touch_sigma_mm);
    assert!(r < 0.05 && p > 2.0 * r, "robust {r} mm, plain {p} mm");
}
