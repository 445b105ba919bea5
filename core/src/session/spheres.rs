//! What a calibration with points probed on reference spheres reports of
//! them: per sphere its fitted centre ± σ, its diameter (stated, or fitted
//! ± σ), and the radial residuals before (the nominal arm, each sphere's
//! centre and size fitted to it) and after (the calibrated arm): their RMS
//! and their range — the sphere's form as the arm sees it.

use serde::{Deserialize, Serialize};

use crate::calibrate::Calibration;
use crate::residuals::spheres::SphereTerm;
use crate::residuals::{At, Layout, TermError};

/// The radial residuals of one sphere at one arm, mm.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RadialErrors {
    /// RMS of `|p − c| − (R + r_ball)` over the sphere's points.
    pub rms: f64,
    /// Their range (largest less smallest): the form error seen.
    pub form: f64,
}

impl RadialErrors {
    fn of(e: &[f64]) -> RadialErrors {
        let n = e.len().max(1) as f64;
        let (lo, hi) = e
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        RadialErrors {
            rms: (e.iter().map(|v| v * v).sum::<f64>() / n).sqrt(),
            form: if e.is_empty() { 0.0 } else { hi - lo },
        }
    }
}

/// One sphere's results.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SphereResult {
    /// Its label.
    pub name: String,
    /// Points probed on it.
    pub points: usize,
    /// The fitted centre in the arm's base frame, mm.
    pub centre: [f64; 3],
    /// Its σ per coordinate, mm, when free.
    pub centre_sigma: Option<[f64; 3]>,
    /// Its diameter, mm: stated, or fitted.
    pub diameter: f64,
    /// The fitted diameter's σ, mm (none when stated).
    pub diameter_sigma: Option<f64>,
    /// The radial residuals at the start arm (its centre and size fitted
    /// with it) and at the calibrated arm.
    pub before: RadialErrors,
    /// After.
    pub after: RadialErrors,
}

/// The spheres of a calibration: `calibration.json`'s `spheres`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SphereReport {
    /// The sphere-surface file.
    pub file: String,
    /// The spheres' stated diameter, mm (none: fitted per sphere).
    pub stated_diameter: Option<f64>,
    /// The probe ball's diameter, mm.
    pub ball_diameter: f64,
    /// Per sphere, in the file's order.
    pub spheres: Vec<SphereResult>,
    /// Per probe the rows name (the default `probe` first), when some row
    /// names a `[[tool]]`: its offset and ball.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub probes: Vec<ProbeResult>,
}

/// One probe of a sphere file whose rows name several.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ProbeResult {
    /// Its name ([`crate::domain::DEFAULT_TOOL`] for the arm's `[probe]`).
    pub name: String,
    /// The spheres it probed.
    pub spheres: Vec<String>,
    /// Its fitted offset, mm (the last joint's frame).
    pub offset: [f64; 3],
    /// Its σ per axis, mm, when fitted.
    pub sigma: Option<[f64; 3]>,
    /// Its ball's diameter, mm.
    pub ball_diameter: f64,
}

/// The term's radial errors at `x` of `layout`.
fn errors_at(term: &SphereTerm, layout: &Layout, x: &[f64]) -> Result<Vec<f64>, TermError> {
    At::with(layout, x, |at| term.radial_errors(at))
}

/// The report of `term`'s spheres after `calibration` on `layout`.
///
/// # Errors
///
/// The kernel's.
pub(crate) fn sphere_report(
    term: &SphereTerm,
    layout: &Layout,
    calibration: &Calibration,
) -> Result<SphereReport, TermError> {
    let x0 = layout.start();
    let x1 = calibration.point_in(layout);
    let (e0, e1) = (errors_at(term, layout, &x0)?, errors_at(term, layout, &x1)?);
    let rows = term.spheres();
    let estimate = |name: &str| calibration.auxiliary.iter().find(|e| e.name == name);
    let spheres = (rows.spheres().iter().enumerate())
        .map(|(s, name)| {
            let of = rows.rows_of(s);
            let pick = |e: &[f64]| of.iter().map(|&i| e[i]).collect::<Vec<f64>>();
            let block = format!("sphere.{name}");
            let axis = |k: &str| estimate(&format!("{block}.{k}"));
            let coords = ["x", "y", "z"].map(axis);
            let centre = coords.map(|e| e.map_or(f64::NAN, |e| e.calibrated));
            let centre_sigma = match coords.map(|e| e.and_then(|e| e.sigma)) {
                [Some(a), Some(b), Some(c)] => Some([a, b, c]),
                _ => None,
            };
            let radius = estimate(&format!("{block}.radius"));
            SphereResult {
                name: name.clone(),
                points: of.len(),
                centre,
                centre_sigma,
                diameter: match radius {
                    Some(r) => 2.0 * r.calibrated,
                    None => 2.0 * term.stated_radius().unwrap_or(f64::NAN),
                },
                diameter_sigma: radius.and_then(|r| r.sigma).map(|s| 2.0 * s),
                before: RadialErrors::of(&pick(&e0)),
                after: RadialErrors::of(&pick(&e1)),
            }
        })
        .collect();
    Ok(SphereReport {
        file: term.file().to_string(),
        stated_diameter: term.stated_radius().map(|r| 2.0 * r),
        ball_diameter: 2.0 * term.ball_radius(),
        spheres,
        probes: probes_of(term, calibration),
    })
}

/// Per probe `term`'s rows name, its spheres, fitted offset ± σ and ball;
/// empty when every row is the default probe's.
fn probes_of(term: &SphereTerm, calibration: &Calibration) -> Vec<ProbeResult> {
    let rows = term.spheres();
    if !rows.has_tools() {
        return Vec::new();
    }
    let fitted = calibration.tool_estimates();
    let (probe, probe_sigma) = super::tools::probe_estimate(calibration);
    (rows.tools().iter().enumerate())
        .filter_map(|(k, tool)| {
            let of: Vec<usize> = (0..rows.spheres().len())
                .filter(|&s| rows.tool_of_sphere(s) == k)
                .collect();
            let first = *of.first()?;
            let (offset, sigma) = match k {
                0 => (probe, probe_sigma),
                _ => (fitted.iter().find(|(n, _, _)| *n == tool.name))
                    .map_or((tool.offset, None), |(_, x, s)| (*x, *s)),
            };
            Some(ProbeResult {
                name: tool.name.clone(),
                spheres: of.iter().map(|&s| rows.spheres()[s].clone()).collect(),
                offset,
                sigma,
                ball_diameter: 2.0 * term.ball_radius_of(first),
            })
        })
        .collect()
}

/// One sphere of a held-out sphere file, refitted at each arm.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HeldOutSphere {
    /// Its label.
    pub name: String,
    /// Points probed on it.
    pub points: usize,
    /// Its diameter, mm, as refitted at the start arm (the stated one when
    /// stated).
    pub diameter_before: f64,
    /// The same at the calibrated arm.
    pub diameter_after: f64,
    /// The radial residuals at the start arm, the sphere refitted with it.
    pub before: RadialErrors,
    /// The same at the calibrated arm.
    pub after: RadialErrors,
}

/// Points on reference spheres held out from the fit
/// (`--validate-spheres`): each sphere's centre — and its diameter unless
/// stated — refitted on its own points with the arm held fixed, the
/// points scored by their radial error (`calibration.json`'s
/// `validation.held_out_spheres`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HeldOutSpheres {
    /// The sphere-surface file.
    pub file: String,
    /// The spheres' diameter the refit held, mm; none: refitted per sphere.
    pub stated_diameter: Option<f64>,
    /// Per sphere, in the file's order.
    pub spheres: Vec<HeldOutSphere>,
    /// `|radial error|` of every point at the start arm, mm.
    pub before: crate::calibrate::validate::PositionErrors,
    /// The same at the calibrated arm.
    pub after: crate::calibrate::validate::PositionErrors,
}

/// The figures of the held-out `term` (its own blocks unused: each sphere
/// is refitted on its points) at the start of `layout` and after
/// `calibration`.
///
/// # Errors
///
/// The kernel's; a sphere whose points fix none at an arm.
pub(crate) fn held_out_spheres(
    term: &SphereTerm,
    layout: &Layout,
    calibration: &Calibration,
) -> Result<HeldOutSpheres, TermError> {
    let refit = |x: &[f64]| {
        At::with(layout, x, |at| {
            Ok((term.refitted_spheres(at)?, term.refitted_errors(term, at)?))
        })
    };
    let (s0, e0) = refit(&layout.start())?;
    let (s1, e1) = refit(&calibration.point_in(layout))?;
    let rows = term.spheres();
    let spheres = (rows.spheres().iter().enumerate())
        .map(|(s, name)| {
            let of = rows.rows_of(s);
            let pick = |e: &[f64]| of.iter().map(|&i| e[i]).collect::<Vec<f64>>();
            let diameter = |r: f64| 2.0 * (r - term.ball_radius_of(s));
            HeldOutSphere {
                name: name.clone(),
                points: of.len(),
                diameter_before: diameter(s0[s].1),
                diameter_after: diameter(s1[s].1),
                before: RadialErrors::of(&pick(&e0)),
                after: RadialErrors::of(&pick(&e1)),
            }
        })
        .collect();
    let abs = |e: &[f64]| {
        crate::calibrate::validate::PositionErrors::of(
            &e.iter().map(|v| v.abs()).collect::<Vec<_>>(),
        )
    };
    Ok(HeldOutSpheres {
        file: term.file().to_string(),
        stated_diameter: term.stated_radius().map(|r| 2.0 * r),
        spheres,
        before: abs(&e0),
        after: abs(&e1),
    })
}

/// One arm on a sphere-surface file (`aacmm evaluate --spheres`): each
/// sphere's centre — and its diameter unless stated — fitted on its points
/// with the arm held fixed, the points' radial errors.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SphereEvaluation {
    /// The sphere-surface file.
    pub file: String,
    /// The stated diameter, mm; none: fitted per sphere.
    pub(crate) stated_diameter: Option<f64>,
    /// Per sphere: its label, points, diameter (fitted or stated) and
    /// radial residuals.
    pub spheres: Vec<(String, usize, f64, RadialErrors)>,
    /// `|radial error|` of every point, mm.
    pub errors: crate::calibrate::validate::PositionErrors,
}

impl SphereEvaluation {
    /// `arm` (through the corrections its file states) on the points
    /// `rows` of `file`, of spheres `diameter_mm` across (stated) or fitted.
    ///
    /// # Errors
    ///
    /// A stated diameter out of range or without the arm file's ball;
    /// points that fix no sphere where the arm puts them; the kernel's.
    pub fn new(
        arm: &crate::domain::Arm,
        rows: crate::domain::Spheres,
        file: &str,
        diameter_mm: Option<f64>,
    ) -> Result<SphereEvaluation, crate::calibrate::CalibrationError> {
        use crate::residuals::spheres::SphereSize;
        let empty = crate::DataSet::without_touches(rows.joints(), rows.prismatic_mask());
        let beyond = crate::corrections::Beyond::default();
        let mut layout =
            crate::residuals::positions::layout_with(&arm.params, &empty, &arm.physics, &beyond)?;
        let size = diameter_mm.map_or(SphereSize::Fitted, SphereSize::Known);
        let term = SphereTerm::new(
            rows,
            file,
            &arm.params,
            size,
            arm.ball_diameter_mm,
            &crate::residuals::Noise::default(),
            crate::residuals::spheres::add_to(&mut layout),
        )?;
        let (fitted, e) = At::with(&layout, &layout.start(), |at| {
            Ok((term.refitted_spheres(at)?, term.refitted_errors(&term, at)?))
        })?;
        let r = term.spheres();
        let spheres = (r.spheres().iter().enumerate())
            .map(|(s, name)| {
                let of = r.rows_of(s);
                let pick: Vec<f64> = of.iter().map(|&i| e[i]).collect();
                let d = 2.0 * (fitted[s].1 - term.ball_radius_of(s));
                (name.clone(), of.len(), d, RadialErrors::of(&pick))
            })
            .collect();
        let abs: Vec<f64> = e.iter().map(|v| v.abs()).collect();
        Ok(SphereEvaluation {
            file: file.to_string(),
            stated_diameter: diameter_mm,
            spheres,
            errors: crate::calibrate::validate::PositionErrors::of(&abs),
        })
    }
}
