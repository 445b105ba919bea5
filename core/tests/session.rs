//! The session from Rust, without the command line: every setting out of
//! range is refused by the library naming the setting, and the same seed
//! gives the same report bytes whatever the thread count, on enough points
//! that the work is really split.

use aacmm_core::calibrate::{CalibrationError, FixSpec, ModelOptions, SolverSettings};
use aacmm_core::params::DhParams;
use aacmm_core::session::Problem;
use aacmm_core::simulate::{CampaignSettings, ErrorModel, simulate};
use aacmm_core::{Arm, DataSet};

mod common;

fn nominal() -> Arm {
    Arm::without_limits("nominal", DhParams::paper_nominal())
}

fn small_data() -> DataSet {
    let mut s = CampaignSettings::new(1, ErrorModel::Paper, 5, 6);
    s.reference_lengths = 2;
    simulate(&nominal(), &s).unwrap().data_set().unwrap()
}

/// The field a library refusal names (never a command-line flag).
fn field_of<T>(result: Result<T, CalibrationError>) -> &'static str {
    match result {
        Err(CalibrationError::Option(e)) => {
            assert!(
                !e.to_string().contains("--"),
                "a library error names a flag: {e}"
            );
            e.field()
        }
        Err(e) => panic!("refused for another reason: {e}"),
        Ok(_) => panic!("accepted"),
    }
}

/// The field the library names for `change` applied to the default model:
/// refused when the problem is made.
fn refused(change: impl Fn(&mut ModelOptions)) -> &'static str {
    let mut o = ModelOptions::default();
    change(&mut o);
    field_of(Problem::new(nominal(), small_data(), o))
}

/// The field the library names for `change` applied to the default solver
/// settings: refused before any work when the problem is run.
fn refused_setting(change: impl Fn(&mut SolverSettings)) -> &'static str {
    let mut s = SolverSettings::default();
    change(&mut s);
    let problem = Problem::new(nominal(), small_data(), ModelOptions::default()).unwrap();
    field_of(problem.run(&s))
}

#[test]
fn every_invalid_option_is_refused_by_its_field() {
    type Change = Box<dyn Fn(&mut ModelOptions)>;
    let cases: Vec<(&str, Change)> = vec![
        (
            "noise.encoder_rad",
            Box::new(|o| o.noise.encoder_rad = Some(-1e-4)),
        ),
        (
            "noise.probe_mm",
            Box::new(|o| o.noise.probe_mm = Some(f64::NAN)),
        ),
        (
            "noise.probe_mm",
            Box::new(|o| {
                o.noise.encoder_rad = Some(0.0);
                o.noise.probe_mm = Some(0.0);
            }),
        ),
        (
            "noise.length_default_mm",
            Box::new(|o| o.noise.length_default_mm = -0.1),
        ),
        (
            "noise.length_weight",
            Box::new(|o| o.noise.length_weight = Some(0.0)),
        ),
        ("fix", Box::new(|o| o.fix = FixSpec::Columns(vec![0, 27]))),
        ("fix", Box::new(|o| o.fix = FixSpec::Columns(vec![6, 6]))),
    ];
    for (field, change) in &cases {
        assert_eq!(refused(change), *field);
    }
    type Setting = Box<dyn Fn(&mut SolverSettings)>;
    let settings: Vec<(&str, Setting)> = vec![
        ("threads", Box::new(|o| o.threads = 0)),
        ("lm.max_iterations", Box::new(|o| o.lm.max_iterations = 0)),
        ("lm.ftol", Box::new(|o| o.lm.ftol = -1.0)),
        ("lm.gtol", Box::new(|o| o.lm.gtol = f64::INFINITY)),
        ("anneal.t0", Box::new(|o| o.anneal.t0 = 0.0)),
        ("anneal.cooling", Box::new(|o| o.anneal.cooling = 1.0)),
        ("anneal.chain", Box::new(|o| o.anneal.chain = 0)),
        ("anneal.t_min", Box::new(|o| o.anneal.t_min = -1.0)),
        ("anneal.target", Box::new(|o| o.anneal.target = f64::NAN)),
        ("anneal.step_mm", Box::new(|o| o.anneal.step_mm = 0.0)),
        (
            "anneal.twist_step_deg",
            Box::new(|o| o.anneal.twist_step_deg = -0.1),
        ),
        (
            "anneal.zero_step_deg",
            Box::new(|o| o.anneal.zero_step_deg = f64::NAN),
        ),
        (
            "anneal.max_evaluations",
            Box::new(|o| o.anneal.max_evaluations = 0),
        ),
        ("switch.window", Box::new(|o| o.switch.window = 0)),
        ("switch.epsilon", Box::new(|o| o.switch.epsilon = -1.0)),
        ("global.grid_cells", Box::new(|o| o.global.grid_cells = 0)),
        ("global.max_starts", Box::new(|o| o.global.max_starts = 0)),
        (
            "global.confirmations",
            Box::new(|o| o.global.confirmations = 0),
        ),
        (
            "global.confirmations",
            Box::new(|o| o.global.confirmations = 1000),
        ),
        (
            "global.start_iterations",
            Box::new(|o| o.global.start_iterations = 0),
        ),
        (
            "global.noise_floor_k",
            Box::new(|o| o.global.noise_floor_k = 0.0),
        ),
    ];
    for (field, change) in &settings {
        assert_eq!(refused_setting(change), *field);
    }
    // Folds: 2 up to the groups of points joined by lengths.
    let problem = Problem::new(nominal(), small_data(), ModelOptions::default()).unwrap();
    for k in [0, 1, 6] {
        let e = problem.clone().with_cross_validation(k).unwrap_err();
        assert_eq!(e.field(), "cross_validate", "{k}");
    }
    assert!(problem.with_cross_validation(2).is_ok());
    // Data read for another arm.
    let seven = Arm::without_limits("seven", {
        let mut p = DhParams::paper_nominal();
        p.joints.push(p.joints[5]);
        p
    });
    assert!(matches!(
        Problem::new(seven, small_data(), ModelOptions::default()),
        Err(CalibrationError::Joints { arm: 7, data: 6 })
    ));
}

#[test]
fn the_same_seed_gives_the_same_report_at_1_2_and_4_threads() {
    // 1200 points: enough that the normal equations and the metrics split
    // across threads.
    let data = common::many_points(1200);
    assert!(data.points().len() >= 1000);
    let report = |threads: usize| {
        common::lm_report_on_threads(&nominal(), &data, threads, |_, s| s.seed = 5)
    };
    let one = report(1);
    assert_eq!(one, report(2), "2 threads");
    assert_eq!(one, report(4), "4 threads");
}

/// The report answers by parameter and gives the calibrated arm on its own:
/// a front end passes neither a name to search for nor the start arm back.
#[test]
fn a_report_looks_up_estimates_and_builds_the_calibrated_arm() {
    use aacmm_core::{CalibrationReport, ParamId};
    let mut start = nominal();
    start.name = "mine".into();
    let model = ModelOptions {
        fix: FixSpec::parse("theta1,d1,theta6,alpha6,Bx,By", 6).unwrap(),
        ..ModelOptions::default()
    };
    let settings = SolverSettings {
        method: aacmm_core::Method::Lm,
        ..SolverSettings::default()
    };
    let report = (Problem::new(start.clone(), small_data(), model).unwrap())
        .run(&settings)
        .unwrap();
    let cal = &report.calibration;
    let theta5: ParamId = "theta5".parse().unwrap();
    let e = cal.estimate(theta5).unwrap();
    assert_eq!(e.id, theta5);
    assert!(
        cal.estimate("theta1".parse().unwrap())
            .unwrap()
            .fixed
            .is_some()
    );
    assert!(
        cal.estimate("theta7".parse().unwrap()).is_none(),
        "a sixth joint"
    );
    let arm = report.calibrated_arm().unwrap();
    assert_eq!(arm.name, "mine-calibrated");
    assert_eq!(arm.params, cal.params);
    assert_eq!(arm, report.calibrated_arm_from(&start));
    // Read back from calibration.json the start arm is not there: asked for
    // by name, it is refused rather than guessed.
    let back = CalibrationReport::from_json(&report.to_json()).unwrap();
    assert!(back.calibrated_arm().is_none());
    assert_eq!(back.calibrated_arm_from(&start).name, "mine-calibrated");
}
