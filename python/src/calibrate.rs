//! `aacmm.calibrate` and its result, `aacmm.Calibration`: the library's
//! session (`Problem`, `session::run` → `CalibrationReport`) with Python
//! arguments in and the report's figures out. Nothing of the session is
//! rebuilt here, so `to_json()` and `write(dir)` give the command line's
//! bytes.

use std::path::PathBuf;
use std::time::Instant;

use aacmm_core::calibrate::{Context, GlobalOptions};
use aacmm_core::domain::Arm as CoreArm;
use aacmm_core::plan::{MapPoint, UncertaintyMap};
use aacmm_core::residuals::Frame;
use aacmm_core::session::{self, CalibrationReport, HeldOutData, Problem, Request, Sources};
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};

use crate::arm::{Arm, warn_all};
use crate::data::DataSet;
use crate::error::{Error, Kind, detached, interruptible};
use crate::noise::Noise;
use crate::spheres::SphereArg;
use crate::{to_dict, to_python};

/// The result of `aacmm.calibrate`: the problem as checked and the
/// library's report. Immutable.
#[pyclass(frozen, module = "aacmm")]
pub struct Calibration {
    problem: Problem,
    report: CalibrationReport,
    /// Wall time of the session, s (for `timing.json`).
    seconds: f64,
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

/// Checks, before the data sets are copied into the request (the library
/// owns its data; Python keeps its own), room for the copies, the work
/// beyond them and the folds' copy when cross-validating
/// ([`aacmm_core::session::room_to_calibrate`]): a `MemoryError` rather than
/// an abort under a memory limit.
fn room_to_calibrate(
    data: &DataSet,
    validate: Option<&DataSet>,
    cross_validate: Option<usize>,
) -> Result<(), Error> {
    let held_out = validate.map(|v| &v.data);
    let folds = cross_validate.is_some();
    Ok(aacmm_core::session::room_to_calibrate(
        &data.data, held_out, folds, true,
    )?)
}

/// The library's request for these arguments (the library parses and
/// checks every one when the request is built).
fn request(
    arm: &Arm,
    data: &DataSet,
    validate: Option<&DataSet>,
    fix: &str,
    noise: Option<&Noise>,
    prior: Option<&str>,
) -> Request {
    let mut warnings = arm.warnings.clone();
    warnings.extend(data.warnings.iter().cloned());
    let request = Request::new(arm.arm.clone(), data.data.clone())
        .sources(Sources {
            arm_file: arm.source.clone(),
            data_file: data.poses_file.clone(),
            lengths_file: data.lengths_file.clone(),
            warnings,
        })
        .angle_unit(data.unit)
        .fix(fix)
        .noise(noise.map(|n| n.noise).unwrap_or_default())
        .prior(prior);
    match validate {
        Some(v) => request.validate_on(
            HeldOutData {
                data: v.data.clone(),
                data_file: v.poses_file.clone(),
                lengths_file: v.lengths_file.clone(),
            },
            v.warnings.clone(),
        ),
        None => request,
    }
}

/// A refusal of the request in Python's words: a setting names its
/// argument; another joint count names `data` or `validate` (the data set
/// of the arm's joint count is not the one refused).
fn refusal(e: aacmm_core::CalibrationError, data: &DataSet, arm: &Arm) -> Error {
    match e {
        e @ aacmm_core::CalibrationError::Joints { .. } => {
            let which = if data.data.joints() == arm.joints() {
                "validate"
            } else {
                "data"
            };
            Error::from(e).prefixed(which)
        }
        e => Error::from(e),
    }
}

/// Calibrates `arm` (the start, e.g. the nominal arm) on `data`: `aacmm
/// calibrate`'s session. `method`: `"global"` (converges from encoder zeros
/// unknown anywhere in ±180°), `"lm"`, `"sa"` or `"hybrid"`; `fix`:
/// `"auto"` (the identifiability analysis's set), comma-separated names or a
/// list of names (see `param_names`); `noise`: an `aacmm.Noise` (default:
/// not stated, the touch σ is estimated from the fit); `seed`: every random
/// draw; `threads`: workers for the normal equations, 1 to 1024 (default one
/// per core; the result does not depend on it); `cross_validate`: `k` folds over
/// points; `validate`: a held-out `DataSet` (same arm: touches, reference
/// positions or both; positions in a fitted frame are scored in it, others
/// registered in closed form); `robust`:
/// `"huber"` or `"cauchy"` for a robust refit (IRLS, `--robust`), with
/// `robust_scale` its tuning constant (default 1.62 / 2.65); `prior`: stated
/// tolerances of the arm, as the command line's `--prior`
/// (`"length=0.5mm,angle=0.1deg,theta5=0.05deg"`, entry by entry over the
/// arm file's `[prior]`; `"none"` ignores the file's; default: the file's,
/// if any); `accept_poor_fit`: call a poor χ² or a fit worse than nominal
/// usable (never a wrong geometry). `spheres`: points probed on reference
/// spheres (`--spheres`; `data` may then be `None`) — a sphere-surface
/// file's path (readings in `sphere_angle_unit`) or `(labels, q[, tools])` arrays
/// (rad; mm for a slide) —, `sphere_diameter` their stated diameter in mm
/// (`--sphere-diameter`), `validate_spheres` held-out points on spheres
/// (`--validate-spheres`, given as `spheres`); `global_starts`, the
/// global search's most random starts (`--global-starts`, default 100). Models beyond geometry, fitted with
/// it, as the command line's flags: `compliance`, joints (from 1) whose
/// compliance under the gravity torque of the arm file's masses is fitted
/// (`"2,3"`, `--compliance`); `harmonics`, encoder harmonics
/// `JOINT:ORDERS` (`"2:1,5:1-2"`, `--harmonics`); `backlash`, joints
/// (from 1) whose half-play on the gear flank the gravity torque presses
/// is fitted (`"2,3"`, `--backlash`; deg, mm for a slide); `thermal`, a thermal
/// expansion coefficient against the data's `temperature` column
/// (`--thermal`); `drift`, a linear drift of the base against the
/// instrument over the data's `time` column (`--drift`). Their values are
/// in `auxiliary` and `physics`. The report is the command line's bit
/// for bit; readings outside the arm's joint limits are a `UserWarning`
/// (and in the report's warnings). Runs without the GIL.
///
/// Raises `ValueError` for a bad option (naming the argument),
/// `aacmm.CalibrationError` when the data cannot determine the free
/// parameters, `KeyboardInterrupt` on Ctrl-C (the solvers stop at their
/// next check, within milliseconds; no result). A calibration that is not
/// usable still gives a result:
/// check `successful` (the verdict) and `report["verdict"]` for why.
#[pyfunction]
#[pyo3(signature = (arm, data = None, *, method = "global", fix = None, noise = None, seed = 0, threads = None, cross_validate = None, validate = None, robust = None, robust_scale = None, prior = None, accept_poor_fit = false, compliance = None, harmonics = None, thermal = false, drift = false, backlash = None, register_held_out = false, spheres = None, sphere_diameter = None, validate_spheres = None, sphere_angle_unit = "deg", global_starts = None))]
#[allow(clippy::too_many_arguments)]
pub fn calibrate(
    py: Python<'_>,
    arm: &Arm,
    data: Option<&DataSet>,
    method: &str,
    fix: Option<&Bound<'_, PyAny>>,
    noise: Option<&Noise>,
    seed: u64,
    threads: Option<usize>,
    cross_validate: Option<usize>,
    validate: Option<&DataSet>,
    robust: Option<&str>,
    robust_scale: Option<f64>,
    prior: Option<&str>,
    accept_poor_fit: bool,
    compliance: Option<&str>,
    harmonics: Option<&str>,
    thermal: bool,
    drift: bool,
    backlash: Option<&str>,
    register_held_out: bool,
    spheres: Option<&Bound<'_, PyAny>>,
    sphere_diameter: Option<f64>,
    validate_spheres: Option<&Bound<'_, PyAny>>,
    sphere_angle_unit: &str,
    global_starts: Option<usize>,
) -> PyResult<Calibration> {
    if global_starts == Some(0) {
        return Err(Error::value("global_starts = 0: at least 1").into());
    }
    let unit = crate::angle_unit(sphere_angle_unit)?;
    let spheres = (spheres.map(|s| SphereArg::of(py, s, "spheres", arm, unit))).transpose()?;
    let held_spheres = (validate_spheres)
        .map(|s| SphereArg::of(py, s, "validate_spheres", arm, unit))
        .transpose()?;
    let none;
    let data = match (data, &spheres) {
        (Some(d), _) => d,
        (None, Some(s)) => {
            none = DataSet::without_touches(arm, s.name());
            &none
        }
        (None, None) => return Err(Error::value("data: give a DataSet, spheres or both").into()),
    };
    let fix = match fix {
        Some(f) => fix_text(f)?,
        None => "auto".to_string(),
    };
    // The solvers' settings not exposed here keep the library's defaults,
    // which are the command line's.
    room_to_calibrate(data, validate, cross_validate)?;
    let request = request(arm, data, validate, &fix, noise, prior)
        .method(method)
        .seed(seed)
        .threads(threads)
        .cross_validate(cross_validate)
        .robust(robust, robust_scale)
        .accept_poor_fit(accept_poor_fit)
        .beyond(compliance, harmonics, thermal, drift)
        .backlash(backlash)
        .register_held_out(register_held_out);
    let request = match global_starts {
        Some(n) => request.global(GlobalOptions::default().max_starts(n)),
        None => request,
    };
    let request = match spheres {
        Some(s) => s.fitted(request)?,
        None => request,
    };
    let request = match held_spheres {
        Some(s) => s.held_out(request)?,
        None => request,
    }
    .sphere_diameter(sphere_diameter);
    // The readers' warnings were issued when the files were read; the
    // request adds those about the arm and the data together.
    let read: Vec<&String> = (arm.warnings.iter().chain(&data.warnings))
        .chain(validate.iter().flat_map(|v| &v.warnings))
        .collect();
    let added: Vec<String> = (request.warnings().into_iter())
        .filter(|w| !read.contains(&w))
        .collect();
    warn_all(py, &added)?;
    let cancel = aacmm_core::calibrate::Cancel::new();
    interruptible(py, &cancel, || {
        let (problem, settings) = request.build().map_err(|e| refusal(e, data, arm))?;
        let started = Instant::now();
        let solver = settings.method.solver();
        let mut ctx = Context::new().cancelled_by(cancel.clone());
        let report = session::run(&problem, &settings, &*solver, &mut ctx)
            .map_err(|e| Error::from(e).prefixed(&arm.source))?;
        Ok(Calibration {
            problem,
            report,
            seconds: started.elapsed().as_secs_f64(),
        })
    })
}

#[pymethods]
impl Calibration {
    /// The calibrated arm (named `<start>-calibrated`, the start's joint
    /// limits).
    #[getter]
    fn arm(&self) -> PyResult<Arm> {
        // A run's report keeps its start arm (one read back from JSON does
        // not, and never reaches Python).
        let arm: CoreArm = (self.report.calibrated_arm())
            .ok_or_else(|| Error::new(Kind::Internal, "internal: the report has no start arm"))?;
        Ok(Arm::new(arm, "<calibration>".to_string(), Vec::new())?)
    }

    /// The calibrated parameters (mm, rad; zero offsets wrapped to ±π), in
    /// the order of `param_names`.
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        Array1::from(self.report.calibration.params.to_vec()).into_pyarray(py)
    }

    /// Standard uncertainties (k = 1) of the parameters, mm and rad; NaN for
    /// a parameter held fixed.
    #[getter]
    fn sigma<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let v: Vec<f64> = self
            .report
            .calibration
            .parameters
            .iter()
            .map(|e| e.sigma.unwrap_or(f64::NAN))
            .collect();
        Array1::from(v).into_pyarray(py)
    }

    /// The parameters held fixed: name → reason.
    #[getter]
    fn fixed<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for e in &self.report.calibration.parameters {
            if let Some(reason) = &e.fixed {
                d.set_item(e.id.to_string(), reason)?;
            }
        }
        Ok(d)
    }

    /// The names of the fitted (free) parameters, in order: the rows and
    /// columns of `correlation`.
    #[getter]
    fn free(&self) -> Vec<String> {
        let m = &self.report.calibration.correlation_matrix;
        m.parameters.iter().map(ToString::to_string).collect()
    }

    /// The correlation matrix of the free parameters (`free` × `free`).
    #[getter]
    fn correlation<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let rho = &self.report.calibration.correlation_matrix.rho;
        let n = rho.len();
        let flat: Vec<f64> = rho.iter().flatten().copied().collect();
        let m = Array2::from_shape_vec((n, n), flat)
            .map_err(|e| Error::new(Kind::Internal, format!("internal: correlation: {e}")))?;
        Ok(m.into_pyarray(py))
    }

    /// Each instrument frame fitted with the arm (none without reference
    /// positions): name → dict of `rotation_deg` (the rotation vector of
    /// `R`, axis × angle, deg) and `translation_mm` (`t`), mapping the arm's
    /// base coordinates into the instrument's, `y = R p + t`; standard
    /// uncertainties (k = 1; `None` where the data did not determine them)
    /// `small_rotation_sigma_deg`, of small rotations about the
    /// instrument's x, y and z axes (the fit's step `R ← exp(δω) R`, not
    /// the rotation vector's components), and `translation_sigma_mm` —
    /// the `[[frame]]` tables of `calibrated.toml`; and
    /// `rotation_matrix`, `R` (3 × 3).
    #[getter]
    fn frames<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = &self.report.calibration;
        let three = |v: [f64; 3]| Array1::from(v.to_vec()).into_pyarray(py);
        let out = PyDict::new(py);
        for (record, (_, x)) in c.frame_records().into_iter().zip(c.frames()) {
            let rotation = Frame::rotation(&x);
            let r = Array2::from_shape_fn((3, 3), |(i, k)| rotation[(i, k)]);
            let d = PyDict::new(py);
            d.set_item("rotation_deg", three(record.rotation_deg))?;
            d.set_item("translation_mm", three(record.translation_mm))?;
            d.set_item(
                "small_rotation_sigma_deg",
                record.small_rotation_sigma_deg.map(three),
            )?;
            d.set_item(
                "translation_sigma_mm",
                record.translation_sigma_mm.map(three),
            )?;
            d.set_item("rotation_matrix", r.into_pyarray(py))?;
            out.set_item(record.name, d)?;
        }
        Ok(out)
    }

    /// Each tool point fitted with the arm (a `[[tool]]` of the arm file
    /// that rows of the data named): name → dict of `offset_mm` (x, y, z
    /// in the last joint's frame, as `calibrated.toml`'s `[[tool]]`) and
    /// `sigma_mm` (k = 1; `None` where the data did not determine it).
    /// Empty when no row named a tool: the arm's `[probe]` is `params`'
    /// last three.
    #[getter]
    fn tools<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let three = |v: [f64; 3]| Array1::from(v.to_vec()).into_pyarray(py);
        let out = PyDict::new(py);
        for (name, offset, sigma) in self.report.calibration.tool_estimates() {
            let d = PyDict::new(py);
            d.set_item("offset_mm", three(offset))?;
            d.set_item("sigma_mm", sigma.map(three))?;
            out.set_item(name, d)?;
        }
        Ok(out)
    }

    /// Each auxiliary column fitted with the arm, in the report's order
    /// (`report["calibration"]["auxiliary"]`): the corrections beyond
    /// geometry (`compliance2` µrad/(N·m), `harmonic2.sin1` and
    /// `harmonic2.cos1` deg, `thermal.cte` ppm/K, `drift.x` … mm/h), then
    /// each frame's `NAME.rx` … `NAME.tz` (deg, mm): name → dict of `unit`,
    /// `start`, `calibrated`, `sigma` (k = 1; `None` where the data did not
    /// determine it), `sigma_of` (what `sigma` is of when not of the value:
    /// for a frame's `rx`, `ry`, `rz`, a small rotation about its x, y, z
    /// axis; else `None`) and `fixed` (why the column was held at its
    /// start — a correction these data cannot separate — or `None`).
    #[getter]
    fn auxiliary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        for a in &self.report.calibration.auxiliary {
            let d = PyDict::new(py);
            d.set_item("unit", &a.unit)?;
            d.set_item("start", a.start)?;
            d.set_item("calibrated", a.calibrated)?;
            d.set_item("sigma", a.sigma)?;
            d.set_item("sigma_of", &a.sigma_of)?;
            d.set_item("fixed", &a.fixed)?;
            out.set_item(&a.name, d)?;
        }
        Ok(out)
    }

    /// The arm's physics at the fit (`None` when no correction is stated
    /// or fitted — masses alone correct nothing): `link_masses` and `probe_mass` (`kg`, `com_mm`),
    /// `gravity`, and the corrections, fitted or as the arm file states
    /// them — `compliance` per joint (rad/(N·m), `None` for none),
    /// `harmonics` (`joint` 0-based, `order`, `sin`, `cos` rad),
    /// `backlash` per joint (rad, mm for a slide; absent when none),
    /// `cte_per_k` (1/K), `reference_temperature_c` (°C) — as
    /// `report["calibration"]["physics"]`, and `drift_mm_per_h` (x, y, z)
    /// when a drift was fitted.
    #[getter]
    fn physics<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(physics) = &self.report.calibration.physics else {
            return Ok(None);
        };
        let d = to_dict(py, physics)?;
        if let Some(v) = physics.drift_mm_per_h {
            d.set_item("drift_mm_per_h", v.to_vec())?;
        }
        Ok(Some(d))
    }

    /// The predicted position uncertainty over a sampled workspace, as
    /// `report["uncertainty_map"]` (`None` when the calibration's
    /// covariance is not finite): `coverage` (0.95), `k_isotropic` (2.80:
    /// the 95 % radius of an isotropic 3-D error in σ, not 2), `workspace`
    /// (where the poses come from, in words), `poses`, `rms_mm`,
    /// `median_mm` and `max_mm` of the 95 % radius, `regions` (per band of
    /// distance from the shoulder: `reach_from_mm`, `reach_to_mm`, `poses`,
    /// `rms_mm`, `max_mm`), and `points`, the figure's even sample of the
    /// poses as numpy arrays `reach_mm`, `height_mm`, `radius_mm`.
    #[getter]
    fn uncertainty_map<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        (self.report.uncertainty_map.as_ref())
            .map(|m| map_dict(py, m))
            .transpose()
    }

    /// The map in each instrument frame the calibration fitted, as
    /// `report["uncertainty_maps_in_frames"]`: each as
    /// :attr:`uncertainty_map`, with `frame` its name; the radii include
    /// the frame's registration (empty without reference positions).
    #[getter]
    fn uncertainty_maps_in_frames<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Vec<Bound<'py, PyDict>>> {
        (self.report.uncertainty_maps_in_frames.iter())
            .map(|m| map_dict(py, m))
            .collect()
    }

    /// The map at each tool point whose offset was fitted (an arm file's
    /// `[[tool]]`), as `report["uncertainty_maps_at_tools"]`: each as
    /// :attr:`uncertainty_map`, with `tool` its name; the radii include
    /// the offset's own uncertainty (empty without such tools).
    #[getter]
    fn uncertainty_maps_at_tools<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        (self.report.uncertainty_maps_at_tools.iter())
            .map(|m| map_dict(py, m))
            .collect()
    }

    /// Whether the calibration is usable — the verdict (`report["verdict"]`,
    /// exit 0 of `aacmm calibrate`): the solver reached a confirmed minimum,
    /// the arm is the nominal's kind of geometry, and (unless a poor fit was
    /// accepted) the χ² test and the fitted data agree.
    #[getter]
    fn successful(&self) -> bool {
        self.report.is_usable()
    }

    /// The verdict, typed: `usable`, and each reason and note with its
    /// `kind`, its `data` and its `text` in Python's words (a remedy names
    /// the keyword argument: `robust="huber"`, `accept_poor_fit=True`).
    /// `report["verdict"]` has the command line's sentences.
    #[getter]
    fn verdict(&self, py: Python<'_>) -> PyResult<crate::verdict::Verdict> {
        crate::verdict::Verdict::of(py, &self.report.verdict)
    }

    /// The figures a program acts on: `successful` (the verdict, as the
    /// property), method, why it stopped (`stop`, and `stop_text` in
    /// words), whether the solver `converged` (its own criterion, which a
    /// refused calibration may meet), iterations, free parameters, degrees
    /// of freedom, σ0, touch σ (mm; of the positions without touches), costs,
    /// and the before/after figures on the fitted data (and on the held-out
    /// data and per cross-validation fold when asked for); with reference
    /// positions, each figure's `positions` holds the 3-D errors `|R p + t −
    /// y|` (`count`, `mean`, `rms`, `max`, mm).
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = &self.report.calibration;
        let v = &self.report.validation;
        let d = PyDict::new(py);
        d.set_item("method", c.solver.method.name())?;
        d.set_item("stop", to_python(py, &c.solver.stop)?)?;
        d.set_item("stop_text", c.solver.stop.describe())?;
        d.set_item("successful", self.report.is_usable())?;
        d.set_item("converged", c.solver.is_solution_usable())?;
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
        d.set_item("fitted", to_dict(py, &v.fitted)?)?;
        d.set_item(
            "held_out",
            match &v.held_out {
                Some(h) => to_dict(py, &h.figures)?.into_any(),
                None => py.None().into_bound(py),
            },
        )?;
        d.set_item(
            "cross_validation",
            match &v.cross_validation {
                Some(cv) => to_python(py, &cv.folds)?,
                None => PyList::empty(py).into_any(),
            },
        )?;
        Ok(d)
    }

    /// Everything `calibration.json` holds, as a dict (lengths in mm,
    /// angles in degrees, as its `units` says).
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.report)
    }

    /// The text of `calibration.json` (with its final newline) as `aacmm
    /// calibrate` writes it for the same inputs and options: the same bytes
    /// when the arm and data were read from the same paths.
    fn to_json(&self) -> String {
        self.report.to_json()
    }

    /// The summary `aacmm calibrate` prints: the solver, the degrees of
    /// freedom, every parameter with σ (mm, deg), the correlations and the
    /// validation table.
    fn text(&self) -> String {
        self.report.summary()
    }

    /// Writes the files `aacmm calibrate --out dir` writes (created if
    /// missing): `calibrated.toml`, `calibration.json`, `timing.json` (this
    /// call's wall times), `report.html` and its SVG figures. Returns the
    /// paths written. `OSError` when a file cannot be written (each file is
    /// written whole or not at all), or when `dir` holds results of an
    /// earlier run (a calibration's, a campaign's, a report's) and `force`
    /// is not set; `ValueError` for an empty path.
    #[pyo3(signature = (dir, *, force = false))]
    fn write(&self, py: Python<'_>, dir: PathBuf, force: bool) -> PyResult<Vec<PathBuf>> {
        detached(py, || {
            crate::error::check_out_dir(&dir, force)?;
            std::fs::create_dir_all(&dir).map_err(|e| {
                Error::new(Kind::Io, format!("{}: cannot create: {e}", dir.display()))
            })?;
            self.report
                .write(&self.problem, &dir, self.seconds)
                .map_err(|e| match e {
                    aacmm_core::report::WriteError::Report(e) => Error::from(e),
                    e => Error::new(Kind::Io, e.to_string()),
                })
        })
    }

    fn __repr__(&self) -> String {
        let c = &self.report.calibration;
        format!(
            "Calibration(method={:?}, successful={}, free_parameters={}, sigma0={:.4})",
            c.solver.method.name(),
            self.report.is_usable(),
            c.dof.free_parameters,
            c.dof.sigma0
        )
    }
}

/// A map as a dict: its figures, `frame` or `tool` when it is in a frame
/// or at a tool point, and the figure's sample as numpy columns.
fn map_dict<'py>(py: Python<'py>, m: &UncertaintyMap) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("coverage", m.coverage)?;
    d.set_item("k_isotropic", m.k_isotropic)?;
    d.set_item("workspace", &m.workspace)?;
    if let Some(f) = &m.frame {
        d.set_item("frame", f)?;
    }
    if let Some(t) = &m.tool {
        d.set_item("tool", t)?;
    }
    d.set_item("poses", m.poses)?;
    d.set_item("rms_mm", m.rms_mm)?;
    d.set_item("median_mm", m.median_mm)?;
    d.set_item("max_mm", m.max_mm)?;
    d.set_item("regions", to_python(py, &m.regions)?)?;
    // Columns rather than a list of dicts: what a plot takes.
    let column = |f: fn(&MapPoint) -> f64| Array1::from_iter(m.points.iter().map(f));
    let points = PyDict::new(py);
    points.set_item("reach_mm", column(|p| p.reach_mm).into_pyarray(py))?;
    points.set_item("height_mm", column(|p| p.height_mm).into_pyarray(py))?;
    points.set_item("radius_mm", column(|p| p.radius_mm).into_pyarray(py))?;
    d.set_item("points", points)?;
    Ok(d)
}
