//! `aacmm.calibrate` and its result, `aacmm.Calibration`.
//!
//! Everything of the calibration session lives in this one file: the options
//! checked, the library's `calibrate`, validation on the fitted and
//! held-out data, cross-validation, and the report — the fields of the
//! command line's `calibration.json`, built as `aacmm calibrate` builds
//! them, so that `to_json()` gives its bytes. When the library owns the
//! session (`Problem`, `session::run` → `CalibrationReport`), this file
//! shrinks to converting the arguments and reading the report.

use aacmm_core::calibrate::validate::{BeforeAfter, Fold, before_after, cross_validate};
use aacmm_core::calibrate::{
    CalibrateOptions, Calibration as CoreCalibration, FixSpec, LmOptions, Method,
    calibrate as core_calibrate,
};
use aacmm_core::io::Arm as CoreArm;
use aacmm_core::params::{ParamId, ParamKind};
use aacmm_core::residuals::Noise as CoreNoise;
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};
use serde::Serialize;

use crate::arm::Arm;
use crate::data::DataSet;
use crate::error::{Error, Kind, Result, detached};
use crate::noise::Noise;
use crate::study::threads;
use crate::{to_dict, to_python};

/// The report: `calibration.json`'s fields, in its order.
#[derive(Serialize)]
struct Report<'a> {
    arm: &'a str,
    arm_file: &'a str,
    data_file: &'a str,
    lengths_file: Option<&'a str>,
    fix: &'a str,
    noise: &'a CoreNoise,
    units: Units,
    touches: usize,
    points: usize,
    reference_lengths: usize,
    calibration: &'a CoreCalibration,
    validation: Validation<'a>,
}

#[derive(Serialize)]
struct Units {
    lengths: &'static str,
    angles: &'static str,
}

#[derive(Serialize)]
struct Validation<'a> {
    fitted: BeforeAfter,
    held_out: Option<HeldOut<'a>>,
    cross_validation: Option<CrossValidation<'a>>,
}

#[derive(Serialize)]
struct HeldOut<'a> {
    data_file: &'a str,
    lengths_file: Option<&'a str>,
    figures: BeforeAfter,
}

#[derive(Serialize)]
struct CrossValidation<'a> {
    folds: &'a [Fold],
    seed: u64,
}

/// The result of `aacmm.calibrate`. Immutable.
#[pyclass(frozen, module = "aacmm")]
pub struct Calibration {
    calibration: CoreCalibration,
    calibrated: CoreArm,
    fitted: BeforeAfter,
    held_out: Option<BeforeAfter>,
    folds: Option<Vec<Fold>>,
    /// `calibration.json`'s text, without the final newline.
    json: String,
}

/// The checked options of a call.
struct Settings {
    options: CalibrateOptions,
    fix: String,
    cross_validate: Option<usize>,
}

/// The `fix=` argument: `"auto"`, comma-separated names, or a list of names.
fn fix_text(fix: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(s) = fix.cast::<PyString>() {
        return Ok(s.to_string());
    }
    let names: Vec<String> = fix
        .extract()
        .map_err(|_| Error::value("fix: 'auto', comma-separated names, or a list of names"))?;
    Ok(names.join(","))
}

fn settings(
    joints: usize,
    method: &str,
    fix: String,
    noise: CoreNoise,
    seed: u64,
    threads: usize,
    cross_validate: Option<usize>,
) -> Result<Settings> {
    let method = Method::parse(method).ok_or_else(|| {
        let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        Error::value(format!("method = {method:?}: one of {}", names.join(", ")))
    })?;
    let spec = FixSpec::parse(&fix, joints).map_err(|e| Error::from(e).prefixed("fix"))?;
    if let Some(k) = cross_validate
        && k < 2
    {
        return Err(Error::value(format!(
            "cross_validate = {k}: None (no cross-validation) or 2 or more folds"
        )));
    }
    Ok(Settings {
        options: CalibrateOptions {
            fix: spec,
            noise,
            method,
            lm: LmOptions::default().threads(threads),
            seed,
            // The solvers' settings not exposed here keep the library's
            // defaults, which are the command line's.
            ..CalibrateOptions::default()
        },
        fix,
        cross_validate,
    })
}

/// Calibrates, validates and builds the report: `aacmm calibrate`'s work
/// without its files.
fn run(start: &Arm, data: &DataSet, held: Option<&DataSet>, s: &Settings) -> Result<Calibration> {
    let params = &start.arm.params;
    let cal = core_calibrate(params, &data.data, &s.options)
        .map_err(|e| Error::from(e).prefixed(&start.source))?;
    let fitted = before_after(params, &cal.params, &data.data)?;
    let held_out = match held {
        Some(h) => Some(before_after(params, &cal.params, &h.data)?),
        None => None,
    };
    let folds = match s.cross_validate {
        Some(k) => Some(
            cross_validate(params, &data.data, &s.options, k, s.options.seed).map_err(|e| {
                let e = Error::from(e);
                Error::new(
                    e.kind,
                    e.message.replace("--cross-validate", "cross_validate ="),
                )
            })?,
        ),
        None => None,
    };
    let report = Report {
        arm: &start.arm.name,
        arm_file: &start.source,
        data_file: &data.poses_file,
        lengths_file: data.lengths_file.as_deref(),
        fix: &s.fix,
        noise: &s.options.noise,
        units: Units {
            lengths: "mm",
            angles: "deg",
        },
        touches: data.data.len(),
        points: data.data.points().len(),
        reference_lengths: data.data.references().len(),
        calibration: &cal,
        validation: Validation {
            fitted,
            held_out: match (held, held_out) {
                (Some(h), Some(figures)) => Some(HeldOut {
                    data_file: &h.poses_file,
                    lengths_file: h.lengths_file.as_deref(),
                    figures,
                }),
                _ => None,
            },
            cross_validation: folds.as_deref().map(|f| CrossValidation {
                folds: f,
                seed: s.options.seed,
            }),
        },
    };
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| Error::new(Kind::Internal, format!("report: {e}")))?;
    let calibrated = CoreArm {
        name: format!("{}-calibrated", start.arm.name),
        params: cal.params.clone(),
        limits: start.arm.limits.clone(),
    };
    Ok(Calibration {
        calibration: cal,
        calibrated,
        fitted,
        held_out,
        folds,
        json,
    })
}

/// Calibrates `arm` (the start, e.g. the nominal arm) on `data`: `aacmm
/// calibrate` without its files. `method`: `"global"` (converges from
/// encoder zeros unknown anywhere in ±180°), `"lm"`, `"sa"` or `"hybrid"`;
/// `fix`: `"auto"` (the identifiability analysis's set), comma-separated
/// names or a list of names (see `param_names`); `noise`: an `aacmm.Noise`
/// (default: not stated, the touch σ is estimated from the fit); `seed`:
/// every random draw; `threads`: workers for the normal equations (default
/// one per core; the result does not depend on it); `cross_validate`: `k`
/// folds over points; `validate`: a held-out `DataSet` (same arm). The
/// parameters are the command line's bit for bit. Runs without the GIL.
///
/// Raises `aacmm.CalibrationError` when the data cannot determine the free
/// parameters, `ValueError` for a bad option. A solver that did not
/// converge still gives a result: check `successful`.
#[pyfunction]
#[pyo3(signature = (arm, data, *, method = "global", fix = None, noise = None, seed = 0, threads = None, cross_validate = None, validate = None))]
#[allow(clippy::too_many_arguments)]
pub fn calibrate(
    py: Python<'_>,
    arm: &Arm,
    data: &DataSet,
    method: &str,
    fix: Option<&Bound<'_, PyAny>>,
    noise: Option<&Noise>,
    seed: u64,
    threads: Option<usize>,
    cross_validate: Option<usize>,
    validate: Option<&DataSet>,
) -> PyResult<Calibration> {
    let fix = match fix {
        Some(f) => fix_text(f)?,
        None => "auto".to_string(),
    };
    let noise = noise.map_or_else(Noise::default_noise, |n| n.noise);
    let s = settings(
        arm.joints(),
        method,
        fix,
        noise,
        seed,
        self::threads(threads)?,
        cross_validate,
    )?;
    for (name, d) in [("data", Some(data)), ("validate", validate)] {
        if let Some(d) = d
            && d.data.joints() != arm.joints()
        {
            return Err(Error::value(format!(
                "{name}: {} joints, the arm has {}",
                d.data.joints(),
                arm.joints()
            ))
            .into());
        }
    }
    detached(py, || run(arm, data, validate, &s))
}

#[pymethods]
impl Calibration {
    /// The calibrated arm (named `<start>-calibrated`, the start's joint
    /// limits).
    #[getter]
    fn arm(&self) -> PyResult<Arm> {
        Ok(Arm::new(
            self.calibrated.clone(),
            "<calibration>".to_string(),
            Vec::new(),
        )?)
    }

    /// The calibrated parameters (mm, rad; zero offsets wrapped to ±π), in
    /// the order of `param_names`.
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        Array1::from(self.calibrated.params.to_vec()).into_pyarray(py)
    }

    /// Standard uncertainties (k = 1) of the parameters, mm and rad; NaN for
    /// a parameter held fixed.
    #[getter]
    fn sigma<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let joints = self.calibrated.params.joint_count();
        let v: Vec<f64> = ParamId::all(joints)
            .zip(&self.calibration.parameters)
            .map(|(id, e)| {
                let s = e.sigma.unwrap_or(f64::NAN);
                match id.kind {
                    ParamKind::Alpha | ParamKind::Theta => s.to_radians(),
                    _ => s,
                }
            })
            .collect();
        Array1::from(v).into_pyarray(py)
    }

    /// The parameters held fixed: name → reason.
    #[getter]
    fn fixed<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for e in &self.calibration.parameters {
            if let Some(reason) = &e.fixed {
                d.set_item(&e.name, reason)?;
            }
        }
        Ok(d)
    }

    /// The names of the fitted (free) parameters, in order: the rows and
    /// columns of `correlation`.
    #[getter]
    fn free(&self) -> Vec<String> {
        self.calibration.correlation_matrix.parameters.clone()
    }

    /// The correlation matrix of the free parameters (`free` × `free`).
    #[getter]
    fn correlation<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let rho = &self.calibration.correlation_matrix.rho;
        let n = rho.len();
        let flat: Vec<f64> = rho.iter().flatten().copied().collect();
        let m = Array2::from_shape_vec((n, n), flat)
            .map_err(|e| Error::new(Kind::Internal, format!("internal: correlation: {e}")))?;
        Ok(m.into_pyarray(py))
    }

    /// Whether the solver converged.
    #[getter]
    fn successful(&self) -> bool {
        self.calibration.solver.successful
    }

    /// The figures a program acts on: method, termination, iterations,
    /// free parameters, degrees of freedom, σ0, touch σ (mm), costs, and the
    /// before/after figures on the fitted data (and on the held-out data
    /// and per cross-validation fold when asked for).
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = &self.calibration;
        let d = PyDict::new(py);
        d.set_item("method", c.solver.method.name())?;
        d.set_item("termination", to_python(py, &c.solver.termination)?)?;
        d.set_item("termination_text", c.solver.termination.describe())?;
        d.set_item("successful", c.solver.successful)?;
        d.set_item("iterations", c.solver.iterations)?;
        d.set_item("cost_evaluations", c.solver.cost_evaluations)?;
        d.set_item("jacobian_evaluations", c.solver.jacobian_evaluations)?;
        d.set_item("initial_cost", c.solver.initial_cost)?;
        d.set_item("final_cost", c.solver.final_cost)?;
        d.set_item("free_parameters", c.dof.free_parameters)?;
        d.set_item("degrees_of_freedom", c.dof.degrees_of_freedom)?;
        d.set_item("sigma0", c.dof.sigma0)?;
        d.set_item("touch_sigma_mm", c.dof.touch_sigma_mm)?;
        d.set_item("touch_sigma_estimated", c.dof.touch_sigma_estimated)?;
        d.set_item("fitted", to_dict(py, &self.fitted)?)?;
        d.set_item(
            "held_out",
            match &self.held_out {
                Some(h) => to_dict(py, h)?.into_any(),
                None => py.None().into_bound(py),
            },
        )?;
        d.set_item(
            "cross_validation",
            match &self.folds {
                Some(f) => to_python(py, f)?,
                None => PyList::empty(py).into_any(),
            },
        )?;
        Ok(d)
    }

    /// Everything `calibration.json` holds, as a dict (lengths in mm,
    /// angles in degrees, as its `units` says).
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        py.import("json")?
            .call_method1("loads", (self.json.as_str(),))
    }

    /// The text of `calibration.json` as `aacmm calibrate` writes it for the
    /// same inputs and options (without its final newline): the same bytes
    /// when the arm and data were read from the same paths.
    fn to_json(&self) -> &str {
        &self.json
    }

    fn __repr__(&self) -> String {
        let c = &self.calibration;
        format!(
            "Calibration(method={:?}, successful={}, free_parameters={}, sigma0={:.4})",
            c.solver.method.name(),
            c.solver.successful,
            c.dof.free_parameters,
            c.dof.sigma0
        )
    }
}
