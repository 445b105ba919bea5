//! Running a problem: the calibration, its validation and cross-validation,
//! and the evidence's sections.

use crate::calibrate::validate::{
    ArmView, before_after_of, cross_validate_cancellable, registered_frames, seen_by,
};
use crate::calibrate::{
    Calibration, CalibrationError, Context, Solver, SolverSettings, calibrate_with,
};

use super::checks::unfitted_frames;
use super::verdict::verdict_of;
use super::{
    CalibrationReport, CrossValidation, HeldOut, Problem, Units, Validation, map,
    room_to_calibrate, spheres, tools,
};

/// Calibrates `problem` with `solver` under `settings` (threads, seed, the
/// solvers' tolerances), validates the result on the fitted and held-out
/// data, and cross-validates when asked (each fold with the same solver's
/// method).
///
/// # Errors
///
/// The calibration's, when it cannot run (the data cannot determine the
/// free parameters, the kernel refuses the arm).
pub fn run(
    problem: &Problem,
    settings: &SolverSettings,
    solver: &dyn Solver,
    ctx: &mut Context,
) -> Result<CalibrationReport, CalibrationError> {
    let start = &problem.arm.params;
    let data = &problem.data;
    let model = &problem.model;
    let held_out = problem.held_out.as_ref().map(|h| &h.data);
    room_to_calibrate(data, held_out, problem.cross_validate.is_some(), false)?;
    let calibration = calibrate_with(problem.inputs(), settings, solver, ctx)?;
    // Each arm's frames: the start's registered to the fitted data, the
    // calibrated arm's fitted with it; held-out positions seen from the
    // same stations are scored in those frames.
    let stated = &problem.arm.physics;
    let start_frames = registered_frames(start, &*seen_by(start, stated, data)?)?;
    let frames = calibration.frames_with_mount();
    let before = ArmView {
        params: start,
        physics: stated,
        frames: &start_frames,
    };
    let after = ArmView {
        params: &calibration.params,
        physics: calibration.physics.as_ref().unwrap_or(stated),
        frames: &frames,
    };
    let fitted = before_after_of(before, after, data)?;
    let Evidence {
        spheres,
        held_out_spheres,
        tools,
        touch_tools,
    } = evidence_reports(problem, &calibration, (before, after))?;
    let held_out = held_out_of(problem, before, after)?;
    // The folds are calibrations of their own: not started once cancelled,
    // and each stops with the run.
    ctx.check()?;
    let cross_validation = cross_validation_of(problem, settings, solver, ctx)?;
    let s = &problem.sources;
    let verdict = verdict_of(problem, &calibration, &fitted);
    let (uncertainty_map, uncertainty_maps_in_frames, uncertainty_maps_at_tools) =
        map::workspace_maps(&problem.arm, data, &calibration, settings.seed);
    Ok(CalibrationReport {
        arm: problem.arm.name.clone(),
        arm_file: s.arm_file.clone(),
        data_file: s.data_file.clone(),
        lengths_file: s.lengths_file.clone(),
        fix: model.fix.describe_for(start),
        noise: model.noise,
        seed: settings.seed,
        units: Units {
            lengths: "mm".to_string(),
            angles: "deg".to_string(),
        },
        touches: data.len(),
        points: data.points().len(),
        reference_lengths: data.references().len(),
        positions_file: data.positions().map(|p| p.file().to_string()),
        positions: data.positions().map_or(0, |p| p.len()),
        calibration,
        validation: Validation {
            fitted,
            held_out,
            cross_validation,
            held_out_spheres,
        },
        warnings: s.warnings.clone(),
        verdict,
        uncertainty_map,
        spheres,
        tools,
        touch_tools,
        uncertainty_maps_in_frames,
        uncertainty_maps_at_tools,
        start: Some(Box::new(problem.arm.clone())),
    })
}

/// The held-out data's figures for both arms, with the frames registered
/// on the held-out data itself (none fitted saw them).
fn held_out_of(
    problem: &Problem,
    before: ArmView<'_>,
    after: ArmView<'_>,
) -> Result<Option<HeldOut>, CalibrationError> {
    let Some(h) = &problem.held_out else {
        return Ok(None);
    };
    Ok(Some(HeldOut {
        data_file: h.data_file.clone(),
        lengths_file: h.lengths_file.clone(),
        figures: before_after_of(before, after, &h.data)?,
        registered_on_itself: (unfitted_frames(&problem.data, &h.data).into_iter())
            .cloned()
            .collect(),
    }))
}

/// The cross-validation the problem asks for: its folds calibrated with the
/// same solver, each stopped with the run.
fn cross_validation_of(
    problem: &Problem,
    settings: &SolverSettings,
    solver: &dyn Solver,
    ctx: &Context,
) -> Result<Option<CrossValidation>, CalibrationError> {
    let Some(k) = problem.cross_validate else {
        return Ok(None);
    };
    Ok(Some(CrossValidation {
        folds: cross_validate_cancellable(
            problem.inputs(),
            settings,
            solver,
            k,
            ctx.cancel_token(),
        )?,
        seed: settings.seed,
    }))
}

/// The sections of the evidence beyond touches and positions that a
/// session's problem holds, each when given.
struct Evidence {
    /// The fitted spheres'.
    spheres: Option<spheres::SphereReport>,
    /// The held-out sphere file's figures.
    held_out_spheres: Option<spheres::HeldOutSpheres>,
    /// The tool points' the positions name.
    tools: Option<tools::ToolReport>,
    /// The tool points' the touches name.
    touch_tools: Option<tools::ToolReport>,
}

/// The sections of the evidence beyond touches and positions that
/// `problem` holds, after `calibration`: its spheres' (fitted and held
/// out) and its tool points' (each arm seeing the data as `views` say).
///
/// # Errors
///
/// The kernel's; a correction whose conditions the data lack.
fn evidence_reports(
    problem: &Problem,
    calibration: &Calibration,
    (before, after): (ArmView<'_>, ArmView<'_>),
) -> Result<Evidence, CalibrationError> {
    let layout = &problem.layout;
    let spheres = (problem.spheres.as_ref())
        .map(|t| spheres::sphere_report(t, layout, calibration))
        .transpose()?;
    let held_out_spheres = (problem.held_out_spheres.as_ref())
        .map(|t| spheres::held_out_spheres(t, layout, calibration))
        .transpose()?;
    let start = (&problem.arm.params, before, after);
    let (tools, touch_tools) = tools::tool_reports(&problem.data, calibration, start)?;
    Ok(Evidence {
        spheres,
        held_out_spheres,
        tools,
        touch_tools,
    })
}
