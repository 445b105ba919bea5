//! Plans of points probed on reference spheres (`plan --measure spheres`):
//! the predicted uncertainty is what a calibration of the chosen points
//! reports, a sphere is opened with more points than its own unknowns,
//! the scale is a parameter only with a stated diameter, and the command
//! line writes a sphere file the calibration reads.

use aacmm_core::domain::Spheres;
use aacmm_core::kernel::PreparedPoses;
use aacmm_core::plan::{Measure, Plan, PlanSettings, plan, sample_sphere_points, uncertainty_map};
use aacmm_core::prelude::*;
use aacmm_core::residuals::spheres::{SphereSize, SphereTerm};
use aacmm_core::simulate::SphereCampaign;

use super::spheres::{BALL, DIAMETER, arm_file, nominal};
use crate::util::{aacmm, assert_clean_error, stderr, stdout, temp_dir, write};

const SIGMA: f64 = 0.01;

/// The plan of `count` of `pool`'s points at σ = [`SIGMA`].
fn sphere_plan(pool: &aacmm_core::domain::Poses, count: usize, stated: bool) -> Plan {
    let mut s = PlanSettings::new(count, Measure::Spheres);
    s.sigma_mm = SIGMA;
    s.sphere_diameter_stated = stated;
    plan(&nominal().params, pool, None, None, &s).unwrap()
}

/// The chosen rows as a campaign on the nominal arm (exact readings).
fn chosen(pool: &aacmm_core::domain::Poses, plan: &Plan) -> SphereCampaign {
    let mut spheres = Spheres::new(6, 0);
    for (line, i) in plan.chosen().into_iter().enumerate() {
        spheres.push(pool.label(i), pool.reading(i), line + 2, None);
    }
    SphereCampaign {
        spheres,
        centres: Vec::new(),
    }
}

/// 60 of 150 candidate points on 6 spheres, the diameter stated: a
/// calibration of exactly the chosen points (on the nominal arm, so that
/// its Jacobians are the plan's; the probe's σ stated, the encoders'
/// nothing) predicts over the candidates the RMS 95 % radius the plan
/// predicted, to 1e-6 (the plan's weak prior and rounding; measured
/// 1 + 9e-14); the plan beats
/// the median of its random subsets, and every sphere it opens has more
/// points than its centre's 3 unknowns and 2 more.
#[test]
fn a_sphere_plan_predicts_what_its_calibration_reports() {
    let arm = nominal();
    let pool = sample_sphere_points(&arm, 150, DIAMETER, 3).unwrap().poses;
    assert_eq!(pool.len(), 150);
    let plan = sphere_plan(&pool, 60, true);
    let planned = plan.planned.expect("a determined plan");
    assert!(
        plan.sockets.iter().all(|(_, n)| *n >= 5),
        "{:?}",
        plan.sockets
    );
    let campaign = chosen(&pool, &plan);
    let noise = Noise {
        encoder_rad: Some(0.0),
        probe_mm: Some(SIGMA),
        ..Noise::default()
    };
    let mut p = Problem::new(
        arm.clone(),
        DataSet::without_touches(6, 0),
        ModelOptions {
            noise,
            ..ModelOptions::default()
        },
    )
    .unwrap();
    let term = SphereTerm::new(
        campaign.spheres.clone(),
        "chosen.csv",
        &arm.params,
        SphereSize::Known(DIAMETER),
        Some(BALL),
        &noise,
        |b| p.add_boxed_block(b),
    )
    .unwrap();
    let report = p
        .with_spheres(term)
        .run(&SolverSettings::default().with_method(Method::Lm))
        .unwrap();
    let (free, cov) = report.calibration.geometry_covariance().unwrap();
    let geometry = plan.parameters.iter().filter(|n| !n.starts_with("sphere."));
    assert_eq!(free.len(), geometry.count(), "{:?}", plan.parameters);
    let rows: Vec<&[f64]> = (0..pool.len()).map(|i| pool.reading(i)).collect();
    let ws = PreparedPoses::for_shape(arm.params.shape().unwrap(), &rows).unwrap();
    let map = uncertainty_map(&report.calibration.params, &ws, &free, &cov, "candidates").unwrap();
    // The calibration's covariance is scaled by its σ̂₀² (here rounding's:
    // the readings are exact); the plan's is at the stated σ.
    let sigma0 = report.calibration.dof.sigma0;
    let ratio = planned.rms_mm() * sigma0 / map.rms_mm;
    assert!(
        (ratio - 1.0).abs() < 1e-6,
        "plan {} mm, calibration {} mm at σ̂₀ {sigma0}",
        planned.rms_mm(),
        map.rms_mm / sigma0
    );
    let random = plan.random_median().expect("random subsets determined");
    assert!(planned.rms_mm() < random.rms_mm(), "{planned:?} {random:?}");
}

/// With the diameter fitted a sphere has 4 unknowns and opens with 6
/// points, and the scale is no parameter the points determine: one free
/// geometry column fewer than with the diameter stated. Fewer rows than a
/// sphere opens with are refused by the count.
#[test]
fn a_fitted_diameter_leaves_the_scale_and_asks_more_points() {
    let pool = sample_sphere_points(&nominal(), 100, DIAMETER, 5)
        .unwrap()
        .poses;
    let stated = sphere_plan(&pool, 40, true);
    let fitted = sphere_plan(&pool, 40, false);
    let geometry = |p: &Plan| {
        p.parameters
            .iter()
            .filter(|n| !n.starts_with("sphere."))
            .count()
    };
    assert_eq!(
        geometry(&fitted) + 1,
        geometry(&stated),
        "{:?}",
        fitted.parameters
    );
    assert!(fitted.parameters.iter().any(|n| n.ends_with(".radius")));
    assert!(!stated.parameters.iter().any(|n| n.ends_with(".radius")));
    assert!(
        fitted.sockets.iter().all(|(_, n)| *n >= 6),
        "{:?}",
        fitted.sockets
    );
    let mut s = PlanSettings::new(5, Measure::Spheres);
    s.sphere_diameter_stated = false;
    let e = plan(&nominal().params, &pool, None, None, &s).unwrap_err();
    assert!(e.to_string().contains("at least 6"), "{e}");
}

/// The command line: 80 of a simulated campaign's 200 points (8 spheres),
/// the diameter stated; the chosen rows are lines of the candidates file
/// in a sphere file calibrate reads, and its calibration is usable. A
/// stated diameter for touches, a `tool` column and a sphere whose
/// points fix no sphere are refused by flag, file and line.
#[test]
fn a_planned_sphere_file_calibrates() {
    let dir = temp_dir("plan-spheres");
    let arm = arm_file(&dir);
    let sim = dir.join("sim");
    let noise = ["--encoder-noise", "0.005", "--probe-noise", "0.01"];
    let mut args = vec![
        "simulate",
        "--arm",
        &arm,
        "--errors",
        "paper",
        "--spheres",
        "8",
    ];
    args.extend(noise);
    args.extend(["--seed", "3", "--out", sim.to_str().unwrap()]);
    let o = aacmm(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let pool = sim.join("spheres.csv");
    let (pool, chosen) = (pool.to_str().unwrap(), dir.join("chosen.csv"));
    let plan = |extra: &[&str]| {
        let mut args = vec!["plan", "--arm", &arm, "--measure", "spheres"];
        args.extend(["--candidates", pool]);
        args.extend(extra);
        aacmm(&args)
    };
    let o = plan(&[
        "--count",
        "80",
        "--sphere-diameter",
        "25.4",
        "--out",
        chosen.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(
        text.contains("Plan: 80 of 200 candidate sphere points"),
        "{text}"
    );
    assert!(text.contains("the spheres' own 24"), "{text}");
    let per = text
        .lines()
        .find(|l| l.starts_with("Points per sphere: "))
        .unwrap();
    let counts: Vec<usize> = per["Points per sphere: ".len()..]
        .split(", ")
        .map(|s| s.split(' ').nth(1).unwrap().parse().unwrap())
        .collect();
    assert!(
        counts.iter().all(|&n| n >= 5) && counts.iter().sum::<usize>() == 80,
        "{per}"
    );
    let written = std::fs::read_to_string(&chosen).unwrap();
    let candidates = std::fs::read_to_string(pool).unwrap();
    assert_eq!(written.lines().count(), 81);
    assert_eq!(written.lines().next(), candidates.lines().next());
    for line in written.lines().skip(1) {
        assert!(
            candidates.lines().any(|c| c == line),
            "not a candidate: {line}"
        );
    }
    let out = dir.join("cal");
    let mut args = vec![
        "calibrate",
        "--arm",
        &arm,
        "--spheres",
        chosen.to_str().unwrap(),
    ];
    args.extend(["--sphere-diameter", "25.4"]);
    args.extend(noise);
    args.extend(["--out", out.to_str().unwrap()]);
    let o = aacmm(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("Verdict: usable"), "{}", stdout(&o));
    // The next points, added to that calibration: its stated diameter is
    // the plan's, so each sphere has 3 unknowns of its own.
    let o = plan(&["--given", out.to_str().unwrap(), "--count", "12"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("the spheres' own 24"), "{text}");
    assert!(text.contains("Adding to the calibration in"), "{text}");

    // Refusals.
    let o = aacmm(&[
        "plan",
        "--arm",
        &arm,
        "--measure",
        "touches",
        "--sample",
        "30",
        "--count",
        "10",
        "--sphere-diameter",
        "25.4",
    ]);
    assert_clean_error(&o, &["--sphere-diameter 25.4", "--measure spheres"]);
    let mut tooled: Vec<String> = candidates.lines().map(|l| format!("{l},probe")).collect();
    tooled[0] = format!("{},tool", candidates.lines().next().unwrap());
    for line in tooled.iter_mut().filter(|l| l.starts_with("S1,")) {
        *line = line.replace(",probe", ",long");
    }
    let long = "[[tool]]\nname = \"long\"\noffset_mm = [0.0, 0.0, 100.0]\n";
    let tool_arm = write(
        &dir,
        "tool_arm.toml",
        &(std::fs::read_to_string(&arm).unwrap() + long),
    );
    let tooled = write(&dir, "tooled.csv", &(tooled.join("\n") + "\n"));
    let o = aacmm(&[
        "plan",
        "--arm",
        &tool_arm,
        "--measure",
        "spheres",
        "--candidates",
        &tooled,
        "--count",
        "80",
    ]);
    assert_clean_error(&o, &["tooled.csv", "`tool` column", "--tool NAME"]);
    let row = candidates.lines().nth(1).unwrap().replacen("S1", "X", 1);
    let flat = format!("{candidates}{row}\n{row}\n{row}\n{row}\n");
    let flat = write(&dir, "flat.csv", &flat);
    let o = aacmm(&[
        "plan",
        "--arm",
        &arm,
        "--measure",
        "spheres",
        "--candidates",
        &flat,
        "--count",
        "80",
    ]);
    assert_clean_error(&o, &["flat.csv:202", "sphere `X`", "fix no sphere"]);
}
