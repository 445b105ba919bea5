//! The report of a calibration session: drawn from the very numbers of its
//! [`CalibrationReport`] (`calibration.json`), with every table cell shared
//! with that file marked by its JSON Pointer.

use super::{
    Arms, CalibrationInput, Measured, PoseErrors, Report, ReportError, ValidationRow,
    calibration_report,
};
use super::{CALIBRATED_FILE, REPORT_FILE, TIMING_FILE};
use crate::corrections::Physics;
use crate::session::{CalibrationReport, Problem, Validation};

/// The report (page and figures) of `report`, the session run on `problem`.
///
/// # Errors
///
/// As `calibration_report`.
pub fn session_report(
    report: &CalibrationReport,
    problem: &Problem,
) -> Result<Report, ReportError> {
    let cal = &report.calibration;
    let start = &problem.arm().params;
    let data = problem.data();
    let stated: &Physics = &problem.arm().physics;
    let fitted = cal.physics.as_ref().unwrap_or(stated);
    // Each arm sees the touches through its own corrections beyond geometry.
    // Each touch through its tool: at its nominal offset before, at its
    // fitted one after (the fit's tool blocks, among its frames).
    let tools = cal.frames_with_mount();
    let seen = |params, physics, data, tools| -> Result<Vec<[f64; 3]>, ReportError> {
        let seen = crate::calibrate::validate::seen_by(params, physics, data).map_err(Box::new)?;
        Ok(crate::residuals::tools::touch_positions_at(
            params, &seen, tools,
        )?)
    };
    let fitted_before = seen(start, stated, data, &[])?;
    let fitted_after = seen(&cal.params, fitted, data, &tools)?;
    let held = problem
        .held_out()
        .map(|h| {
            Ok::<_, ReportError>((
                &h.data,
                seen(start, stated, &h.data, &[])?,
                seen(&cal.params, fitted, &h.data, &tools)?,
            ))
        })
        .transpose()?;
    let mut measured = vec![Measured {
        data,
        held_out: false,
        before: Some(&fitted_before),
        after: &fitted_after,
    }];
    if let Some((h, before, after)) = &held {
        measured.push(Measured {
            data: h,
            held_out: true,
            before: Some(before),
            after,
        });
    }
    let v = &report.validation;
    let validation = validation_rows(v);
    calibration_report(&CalibrationInput {
        title: format!("Calibration of arm `{}`", report.arm),
        inputs: inputs(report),
        calibration: cal,
        calibration_json: Some("/calibration".to_string()),
        measured,
        arms: Arms {
            before: "nominal".to_string(),
            after: "calibrated".to_string(),
        },
        validation,
        truth: problem.truth(),
        positions: pose_errors(report, problem)?,
        beyond: beyond_effects(report, problem)?,
        uncertainty_map: report.uncertainty_map.as_ref(),
        uncertainty_map_json: Some("/uncertainty_map".to_string()),
        spheres: report.spheres.as_ref(),
        folds: (v.cross_validation.as_ref()).map_or(&[], |cv| cv.folds.as_slice()),
        held_out_spheres: v.held_out_spheres.as_ref(),
        tools: report.tools.as_ref(),
        touch_tools: report.touch_tools.as_ref(),
        uncertainty_maps_in_frames: &report.uncertainty_maps_in_frames,
        uncertainty_maps_at_tools: &report.uncertainty_maps_at_tools,
        verdict: Some(&report.verdict),
        seed: report.seed,
    })
}

/// The validation table's rows: the fitted data, the held-out set, each
/// cross-validation fold that held out touches or positions.
fn validation_rows(v: &Validation) -> Vec<ValidationRow<'_>> {
    let mut rows = vec![ValidationRow {
        name: "fitted".to_string(),
        held_out: false,
        figures: &v.fitted,
        json: Some("/validation/fitted".to_string()),
    }];
    if let Some(h) = &v.held_out {
        rows.push(ValidationRow {
            name: format!("held out ({}{})", h.data_file, registered_note(h)),
            held_out: true,
            figures: &h.figures,
            json: Some("/validation/held_out/figures".to_string()),
        });
    }
    if let Some(cv) = &v.cross_validation {
        // A fold that held out no touch or position (points on spheres
        // alone) has its figures in the spheres' section and the verdict.
        let folds = cv.folds.iter().enumerate();
        for (i, f) in folds.filter(|(_, f)| !f.held_out.is_empty()) {
            rows.push(ValidationRow {
                name: format!("fold {} ({} points)", i + 1, f.held_out.len()),
                held_out: true,
                figures: &f.figures,
                json: Some(format!("/validation/cross_validation/folds/{i}/figures")),
            });
        }
    }
    rows
}

/// Per model beyond geometry the fit switched on, how far its fitted
/// correction alone moves the calibrated arm's probe at every fitted pose
/// (touches and reference positions), against the reach.
fn beyond_effects(
    report: &CalibrationReport,
    problem: &Problem,
) -> Result<Vec<PoseErrors>, ReportError> {
    use crate::corrections::{Beyond, Conditions, Effects};
    let fit = &problem.inputs().model.beyond;
    let (Some(fitted), false) = (&report.calibration.physics, fit.is_empty()) else {
        return Ok(Vec::new());
    };
    let models = each_model_alone(fitted, fit);
    let params = &report.calibration.params;
    let kernel = crate::kernel::ArmKernel::new(params)?;
    let data = problem.data();
    let mut sets: Vec<(Conditions<'_>, &crate::kernel::PreparedPoses)> = Vec::new();
    if !data.is_empty() {
        sets.push((data.conditions(), data.poses()));
    }
    if let Some(p) = data.positions() {
        sets.push((p.conditions(), p.poses()));
    }
    let mut out = Vec::new();
    for (name, physics) in models {
        let (mut reach_mm, mut error_mm) = (Vec::new(), Vec::new());
        for (conditions, plain) in &sets {
            let n = plain.len();
            let seen = Effects::new(params, &physics, &Beyond::default(), plain, *conditions)
                .map_err(|message| {
                    Box::new(crate::calibrate::CalibrationError::Term {
                        term: "beyond".into(),
                        message,
                    })
                })?;
            let (mut a, mut b) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n]);
            kernel.positions(plain, 0..n, &mut a)?;
            kernel.positions(&seen.poses, 0..n, &mut b)?;
            for (p, q) in a.iter().zip(&b) {
                reach_mm.push(p[0].hypot(p[1]));
                error_mm.push(crate::geometry::distance(p, q));
            }
        }
        out.push(PoseErrors {
            name: name.to_string(),
            held_out: false,
            after: true,
            reach_mm,
            error_mm,
            frame: Vec::new(),
            frame_names: Vec::new(),
            orientation_deg: Vec::new(),
        });
    }
    Ok(out)
}

/// Per model beyond geometry the fit switched on (`fit`), the fitted arm's
/// physics with that model's fitted values alone: compliance, harmonics,
/// backlash, thermal expansion, drift, in that order.
fn each_model_alone(
    fitted: &Physics,
    fit: &crate::corrections::Beyond,
) -> Vec<(&'static str, Physics)> {
    let bare = Physics {
        compliance: Vec::new(),
        harmonics: Vec::new(),
        backlash: Vec::new(),
        cte_per_k: None,
        drift_mm_per_h: None,
        ..fitted.clone()
    };
    let mut models: Vec<(&'static str, Physics)> = Vec::new();
    if !fit.compliance.is_empty() {
        let only = Physics {
            compliance: fitted.compliance.clone(),
            ..bare.clone()
        };
        models.push(("joint compliance", only));
    }
    if !fit.harmonics.is_empty() {
        let only = Physics {
            harmonics: fitted.harmonics.clone(),
            ..bare.clone()
        };
        models.push(("encoder harmonics", only));
    }
    if !fit.backlash.is_empty() {
        let only = Physics {
            backlash: fitted.backlash.clone(),
            ..bare.clone()
        };
        models.push(("backlash", only));
    }
    if fit.thermal {
        let only = Physics {
            cte_per_k: fitted.cte_per_k,
            ..bare.clone()
        };
        models.push(("thermal expansion", only));
    }
    if fit.drift {
        let only = Physics {
            drift_mm_per_h: fitted.drift_mm_per_h,
            ..bare.clone()
        };
        models.push(("drift", only));
    }
    models
}

/// The 3-D errors at the reference positions of the fitted and held-out
/// data, before (the start arm, registered to the fitted data in closed
/// form) and after (the calibrated arm in the fitted frames).
fn pose_errors(
    report: &CalibrationReport,
    problem: &Problem,
) -> Result<Vec<PoseErrors>, ReportError> {
    use crate::calibrate::validate::{registered_frames, seen_by};
    let cal = &report.calibration;
    let start = &problem.arm().params;
    let stated: &Physics = &problem.arm().physics;
    let fitted = cal.physics.as_ref().unwrap_or(stated);
    let start_frames = registered_frames(
        start,
        &*seen_by(start, stated, problem.data()).map_err(Box::new)?,
    )?;
    let frames = cal.frames_with_mount();
    let mut sets = vec![("fitted", false, problem.data())];
    if let Some(h) = problem.held_out() {
        sets.push(("held out", true, &h.data));
    }
    let mut out = Vec::new();
    for (set, held_out, data) in sets {
        if data.positions().is_none() {
            continue;
        }
        let arms = [
            (false, start, stated, &start_frames),
            (true, &cal.params, fitted, &frames),
        ];
        for (after, params, physics, f) in arms {
            let seen = seen_by(params, physics, data).map_err(Box::new)?;
            let Some(p) = seen.positions() else {
                continue;
            };
            let (reach_mm, error_mm) = per_pose(params, p, f)?;
            let mut orientation_deg =
                crate::calibrate::validate::orientation_errors_per_row(params, p, f)?;
            if orientation_deg.iter().all(Option::is_none) {
                orientation_deg.clear();
            }
            let arm = if after { "calibrated" } else { "nominal" };
            let rows = p.rows();
            out.push(PoseErrors {
                name: format!("{arm}, {set}"),
                held_out,
                after,
                reach_mm,
                error_mm,
                frame: (0..p.len()).map(|i| rows.frame(i)).collect(),
                frame_names: rows.frames().to_vec(),
                orientation_deg,
            });
        }
    }
    Ok(out)
}

/// Per row, the probe's distance from the base axis and its 3-D error,
/// each frame as `frames` registers it (else its closed form).
fn per_pose(
    params: &crate::params::DhParams,
    data: &crate::dataset::PositionData,
    frames: &[crate::calibrate::validate::FrameValues],
) -> Result<(Vec<f64>, Vec<f64>), crate::kernel::KernelError> {
    let (p, error) = crate::calibrate::validate::pose_errors(params, data, frames)?;
    Ok((p.iter().map(|q| q[0].hypot(q[1])).collect(), error))
}

/// What went in, for the page's heading: a line per kind of evidence
/// present, and the noise each was weighed with.
fn inputs(r: &CalibrationReport) -> Vec<(String, String)> {
    let n = r.noise;
    let mut lines = vec![(
        "nominal arm".to_string(),
        format!("`{}` ({})", r.arm, r.arm_file),
    )];
    if r.touches > 0 {
        lines.push((
            "touches".to_string(),
            format!(
                "{}: {} touches of {} points",
                r.data_file, r.touches, r.points
            ),
        ));
        lines.push((
            "reference lengths".to_string(),
            match &r.lengths_file {
                Some(f) => format!("{f}: {}", r.reference_lengths),
                None => "none (scale is not tested)".to_string(),
            },
        ));
    }
    if let Some(file) = &r.positions_file {
        let frames: Vec<String> = (r.calibration.frames().into_iter())
            .map(|(name, _)| name)
            .collect();
        lines.push((
            "reference positions".to_string(),
            format!(
                "{file}: {} positions in {} frame{} ({})",
                r.positions,
                frames.len(),
                if frames.len() == 1 { "" } else { "s" },
                frames.join(", ")
            ),
        ));
    }
    if let Some(h) = &r.validation.held_out {
        lines.push((
            "held out".to_string(),
            match &h.lengths_file {
                Some(l) => format!("{} with lengths {l}", h.data_file),
                None => h.data_file.clone(),
            },
        ));
    }
    if r.touches > 0 {
        lines.push(("noise".to_string(), touch_noise(&n)));
    }
    if let Some(noise) = r.position_noise() {
        lines.push(("position noise".to_string(), noise));
    }
    if let Some(noise) = r.orientation_noise() {
        lines.push(("orientation noise".to_string(), noise));
    }
    lines.push((
        "method, fixed set, seed".to_string(),
        format!(
            "{}; fixed: {}; seed {}",
            r.calibration.solver.method.name(),
            r.fix,
            r.seed
        ),
    ));
    if let Some(cv) = &r.validation.cross_validation {
        lines.push((
            "cross-validation".to_string(),
            format!("{} folds over points, seed {}", cv.folds.len(), cv.seed),
        ));
    }
    lines.push((
        "written beside this page".to_string(),
        format!(
            "{CALIBRATED_FILE}, {REPORT_FILE}, {TIMING_FILE} (every number of the tables below \
             that is also in {REPORT_FILE} is marked with its place there)"
        ),
    ));
    lines
}

/// The touches' noise as stated, or that it was not.
fn touch_noise(n: &crate::residuals::Noise) -> String {
    match (n.encoder_rad, n.probe_mm) {
        (None, None) => "not stated: the touch σ is estimated from the fit".to_string(),
        (e, p) => format!(
            "encoders {} deg, probe seating {} mm per axis; reference lengths {} mm unless the \
             file states one",
            e.map_or("0".to_string(), |v| format!("{}", v.to_degrees())),
            p.map_or("0".to_string(), |v| format!("{v}")),
            n.length_default_mm
        ),
    }
}

/// For held-out positions in frames the fit does not have, registered on
/// themselves because the user asked: `; frame `X` registered on its own
/// positions (--register-held-out): optimistic` (empty otherwise).
pub(crate) fn registered_note(h: &crate::session::HeldOut) -> String {
    let frames = &h.registered_on_itself;
    if frames.is_empty() {
        return String::new();
    }
    let names: Vec<String> = frames.iter().map(|f| format!("`{f}`")).collect();
    format!(
        "; frame{} {} not fitted, registered on {} own positions (--register-held-out): \
         optimistic",
        if frames.len() == 1 { "" } else { "s" },
        names.join(", "),
        if frames.len() == 1 { "its" } else { "their" }
    )
}
