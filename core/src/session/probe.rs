//! Probe qualification: the daily check of a measuring arm's probe (after
//! every probe change too), from points touched on one reference sphere
//! of certified diameter with the arm's geometry held.
//!
//! **What is fitted**: the probe's tip offset (its three coordinates in the
//! last joint's frame: the arm's `[probe]` `Bx, By, Bz`, or a `[[tool]]`'s
//! block), the sphere's centre, and its radius as the probe sees it — from
//! which the *effective* ball diameter follows: the points are ball
//! centres, `|p − c| = D/2 + r_eff`, so `d_eff = 2(R_fit + r_nom) − D` with
//! `R_fit` the fitted sphere radius less the nominal ball radius `r_nom`.
//! The effective diameter takes in the probing's own lobing and the
//! stylus' bending under the probing force, which is why arms qualify it
//! rather than use the ball's certificate. Separating the offset along
//! the stylus from the ball's size needs touches at varied angles between
//! the stylus and the surface (ISO 10360-5's pattern with the wrist
//! turned): the fit's σ says when they were not.
//!
//! **Decisions**: the fit's own verdict refuses as a calibration's does —
//! above all its χ² test: residuals beyond the stated noise (a loose
//! stylus, a dirty ball or sphere, a touch off the surface scatter the
//! points); the sphere's form as the probe sees it (the range of the radial
//! residuals) beyond a limit, when one is set, refuses too; a tip
//! that moved from its stated offset by more than a tolerance is a warning
//! (a changed or bent stylus, or the arm file describes another probe) —
//! the qualified arm is still written, since the fit is then what the
//! probe is.

use serde::{Deserialize, Serialize};

use crate::calibrate::{CalibrationError, FixSpec, Method, ModelOptions, SolverSettings};
use crate::domain::{Arm, DEFAULT_TOOL, Spheres};
use crate::error::OptionError;
use crate::params::param_count;
use crate::residuals::Noise;
use crate::residuals::spheres::{SphereSize, SphereTerm};
use crate::setting::Setting;

/// The default tolerance on the tip's move from its stated offset, mm.
pub const DEFAULT_TOLERANCE_MM: f64 = 0.05;

/// What a probe qualification is asked.
#[derive(Clone, Debug, PartialEq)]
pub struct ProbeSettings {
    /// The probe's name: [`DEFAULT_TOOL`] (the arm's `[probe]`) or a
    /// `[[tool]]`'s.
    pub tool: String,
    /// The reference sphere's certified diameter, mm.
    pub sphere_diameter_mm: f64,
    /// The encoders' and the probing's noise (unstated: estimated).
    pub noise: Noise,
    /// The largest move of the tip from its stated offset not warned of, mm.
    pub tolerance_mm: f64,
    /// The largest form of the sphere as the probe sees it, mm (none: the
    /// form is judged by the stated noise alone, the fit's χ² test).
    pub max_form_mm: Option<f64>,
    /// Whose words the fit's refusals are in (their remedies name the
    /// front end's options: flags, keyword arguments or setters).
    pub spelling: crate::setting::Spelling,
}

/// A probe's qualification: its tip offset and effective ball diameter
/// with their σ, the sphere's form, and the decisions.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ProbeQualification {
    /// The probe qualified.
    pub tool: String,
    /// The points' file.
    pub file: String,
    /// The sphere placement used.
    pub sphere: String,
    /// Points fitted.
    pub points: usize,
    /// The tip offset stated in the arm file, mm (last joint's frame).
    pub nominal_offset: [f64; 3],
    /// The qualified tip offset, mm.
    pub offset: [f64; 3],
    /// Its σ per coordinate, mm.
    pub offset_sigma: [f64; 3],
    /// `|offset − nominal_offset|`, mm.
    pub moved_mm: f64,
    /// The tolerance on that move, mm.
    pub tolerance_mm: f64,
    /// The ball diameter stated in the arm file, mm (none: taken as 0).
    pub nominal_ball_mm: Option<f64>,
    /// The effective ball diameter, mm.
    pub ball_diameter_mm: f64,
    /// Its σ, mm.
    pub ball_sigma_mm: f64,
    /// The reference sphere's certified diameter, mm.
    pub sphere_diameter_mm: f64,
    /// The range of the radial residuals at the qualified probe, mm.
    pub form_mm: f64,
    /// Their RMS, mm.
    pub rms_mm: f64,
    /// The limit on the form, mm, when one was set.
    pub max_form_mm: Option<f64>,
    /// Why the qualification cannot be used (empty: it can).
    pub refusals: Vec<String>,
    /// What the user should know of a usable one.
    pub warnings: Vec<String>,
}

impl ProbeQualification {
    /// Whether the qualified probe may be used.
    pub fn usable(&self) -> bool {
        self.refusals.is_empty()
    }

    /// `start` with the qualified probe: its offset and ball diameter.
    pub fn qualified_arm(&self, start: &Arm) -> Arm {
        let mut arm = start.clone();
        if self.tool == DEFAULT_TOOL {
            arm.params.probe = self.offset;
            arm.ball_diameter_mm = Some(self.ball_diameter_mm);
        } else if let Some(t) = arm.tools.iter_mut().find(|t| t.name == self.tool) {
            t.offset = self.offset;
            t.ball_diameter_mm = Some(self.ball_diameter_mm);
        }
        arm
    }
}

/// Qualifies the probe `settings.tool` of `arm` on the rows of `rows`
/// (read from `file`) that it probed (every row, when the file names no
/// tool): see the module's documentation.
///
/// # Errors
///
/// A probe the arm does not know, no row of it or rows on more than one
/// sphere placement (named by the field `tool` or the file), a sphere
/// diameter out of range; the fit's own errors.
pub fn qualify_probe(
    arm: &Arm,
    rows: Spheres,
    file: &str,
    settings: &ProbeSettings,
) -> Result<ProbeQualification, CalibrationError> {
    crate::residuals::spheres::check_sphere_diameter(settings.sphere_diameter_mm)?;
    let (nominal_offset, nominal_ball) = stated_probe(arm, &settings.tool)?;
    let rows = rows_of_probe(rows, arm, file, &settings.tool)?;
    let sphere = rows.spheres()[0].clone();
    let points = rows.len();
    let n = arm.params.joint_count();
    let probe = crate::residuals::tools::probe_columns(&arm.params);
    let held: Vec<usize> = (0..param_count(n))
        .filter(|c| settings.tool != DEFAULT_TOOL || !probe.contains(c))
        .collect();
    let model = ModelOptions {
        fix: FixSpec::Columns(held),
        noise: settings.noise,
        ..ModelOptions::default()
    };
    let data = crate::DataSet::without_touches(n, rows.prismatic_mask());
    let mut problem = super::Problem::new(arm.clone(), data, model)?;
    let term = SphereTerm::new(
        rows,
        file,
        &arm.params,
        SphereSize::Fitted,
        nominal_ball,
        &settings.noise,
        |b| problem.add_boxed_block(b),
    )?;
    let report = problem
        .with_spheres(term)
        .run(&SolverSettings::default().with_method(Method::Lm))?;
    Ok(judged(
        &report,
        settings,
        Fitted {
            file,
            sphere,
            points,
            nominal_offset,
            nominal_ball,
        },
    ))
}

/// What the fit started from, for [`judged`].
struct Fitted<'a> {
    file: &'a str,
    sphere: String,
    points: usize,
    nominal_offset: [f64; 3],
    nominal_ball: Option<f64>,
}

/// The qualification of the fit `report`: the offset and effective ball
/// with σ, the form, and the decisions.
fn judged(
    report: &super::CalibrationReport,
    settings: &ProbeSettings,
    f: Fitted<'_>,
) -> ProbeQualification {
    let c = &report.calibration;
    let (offset, offset_sigma) = fitted_offset(report, &settings.tool);
    let radius = (c.auxiliary.iter()).find(|e| e.name == format!("sphere.{}.radius", f.sphere));
    let r = radius.map_or(f64::NAN, |e| e.calibrated);
    let r_sigma = radius.and_then(|e| e.sigma).unwrap_or(f64::NAN);
    let ball = 2.0 * (r + f.nominal_ball.unwrap_or(0.0) / 2.0) - settings.sphere_diameter_mm;
    let after = (report.spheres.as_ref()).and_then(|s| s.spheres.first().map(|s| s.after));
    let (form, rms) = after.map_or((f64::NAN, f64::NAN), |a| (a.form, a.rms));
    let moved = crate::geometry::distance(&offset, &f.nominal_offset);
    // The fit's own refusals in the caller's front end's words.
    let mut refusals = report.verdict.words(settings.spelling).reasons;
    if let Some(limit) = settings.max_form_mm.filter(|&m| form.is_nan() || form > m) {
        refusals.push(format!(
            "the sphere's form as the probe sees it is {form:.4} mm, beyond the limit of {} mm: \
             a loose or bent stylus, a dirty ball or sphere, or a touch off the surface — clean, \
             tighten and probe the sphere again",
            crate::error::short(limit)
        ));
    }
    if ball.is_nan() || ball <= 0.0 {
        refusals.push(format!(
            "the effective ball diameter {ball:.4} mm is not positive: the sphere's diameter \
             ({} mm) or the ball's is misstated",
            crate::error::short(settings.sphere_diameter_mm)
        ));
    }
    let mut warnings = Vec::new();
    if moved > settings.tolerance_mm {
        warnings.push(format!(
            "the tip moved {moved:.4} mm from the offset the arm file states (tolerance {} mm): a \
             changed or bent stylus, or the arm file describes another probe — the qualified \
             offset is written",
            crate::error::short(settings.tolerance_mm)
        ));
    }
    ProbeQualification {
        tool: settings.tool.clone(),
        file: f.file.to_string(),
        sphere: f.sphere,
        points: f.points,
        nominal_offset: f.nominal_offset,
        offset,
        offset_sigma,
        moved_mm: moved,
        tolerance_mm: settings.tolerance_mm,
        nominal_ball_mm: f.nominal_ball,
        ball_diameter_mm: ball,
        ball_sigma_mm: 2.0 * r_sigma,
        sphere_diameter_mm: settings.sphere_diameter_mm,
        form_mm: form,
        rms_mm: rms,
        max_form_mm: settings.max_form_mm,
        refusals,
        warnings,
    }
}

/// The fitted tip offset of `tool` and its σ (NaN where not determined):
/// the probe's `B` or the tool's block, as the tools' report reads them.
fn fitted_offset(report: &super::CalibrationReport, tool: &str) -> ([f64; 3], [f64; 3]) {
    let c = &report.calibration;
    let (offset, sigma) = if tool == DEFAULT_TOOL {
        super::tools::probe_estimate(c)
    } else {
        (c.tool_estimates().into_iter())
            .find(|(n, _, _)| n == tool)
            .map_or(([f64::NAN; 3], None), |(_, x, s)| (x, s))
    };
    (offset, sigma.unwrap_or([f64::NAN; 3]))
}

/// The stated offset and ball of the probe `tool` of `arm`.
fn stated_probe(arm: &Arm, tool: &str) -> Result<([f64; 3], Option<f64>), OptionError> {
    let seen = crate::domain::arm_with_tool(arm, tool)?;
    Ok((seen.params.probe, seen.ball_diameter_mm))
}

/// The rows of `rows` the probe `tool` touched (each of them, when the
/// file names no tool), on one sphere placement.
fn rows_of_probe(
    rows: Spheres,
    arm: &Arm,
    file: &str,
    tool: &str,
) -> Result<Spheres, CalibrationError> {
    let rows = if rows.has_tools() {
        let keep: Vec<usize> = (0..rows.len())
            .filter(|&i| rows.tools()[rows.tool(i)].name == tool)
            .collect();
        rows.subset(&keep)
    } else if tool == DEFAULT_TOOL {
        rows
    } else {
        match arm.tools.iter().find(|t| t.name == tool) {
            Some(t) => rows.as_tool(t),
            None => rows,
        }
    };
    let refuse = |why: String| OptionError::new(Setting::Tool, tool, format!("{file}: {why}"));
    match rows.spheres().len() {
        0 => Err(refuse("no point of this file was probed with it".to_string()).into()),
        1 => Ok(rows),
        k => Err(refuse(format!(
            "it probed {k} sphere placements ({}): a qualification uses one — give the points \
             on one sphere",
            rows.spheres().join(", ")
        ))
        .into()),
    }
}
