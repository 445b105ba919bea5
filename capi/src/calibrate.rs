//! Calibration from files or arrays, and the result handle.

use std::collections::{HashMap, HashSet};
use std::ffi::{CStr, c_char};

use aacmm_core::calibrate::{
    FixSpec, Loss, Method, ModelOptions, Robust, SolverSettings, Termination,
};
use aacmm_core::dataset::{DataSet, MIN_TOUCHES};
use aacmm_core::io::{
    AngleUnit, Arm, Poses, ReferenceLength, read_arm, read_lengths, read_poses, source_name,
};
use aacmm_core::params::ParamId;
use aacmm_core::residuals::{DEFAULT_LENGTH_SIGMA_MM, Noise};
use aacmm_core::session::{CalibrationReport, Problem, Sources};

use crate::arm::{AacmmArm, handle, pose_count, string_out};
use crate::error::{AacmmStatus, Error, guard, guard_value};
use crate::ptr;

/// A solver, for the `method` option: one of the `AACMM_METHOD_…`
/// constants.
pub type AacmmMethod = u32;

/// Levenberg–Marquardt from the start arm (`--method lm`).
pub const AACMM_METHOD_LM: AacmmMethod = 0;

/// The paper's simulated annealing alone (`--method sa`).
pub const AACMM_METHOD_SA: AacmmMethod = 1;

/// The paper's hybrid, annealing then LM (`--method hybrid`).
pub const AACMM_METHOD_HYBRID: AacmmMethod = 2;

/// Converges from encoder zeros unknown in ±180° (`--method global`, the
/// default).
pub const AACMM_METHOD_GLOBAL: AacmmMethod = 3;

/// The library's method of a C constant.
fn method(m: AacmmMethod) -> Option<Method> {
    match m {
        AACMM_METHOD_LM => Some(Method::Lm),
        AACMM_METHOD_SA => Some(Method::Sa),
        AACMM_METHOD_HYBRID => Some(Method::Hybrid),
        AACMM_METHOD_GLOBAL => Some(Method::Global),
        _ => None,
    }
}

/// The C constant of a library method.
fn method_code(m: Method) -> AacmmMethod {
    match m {
        Method::Lm => AACMM_METHOD_LM,
        Method::Sa => AACMM_METHOD_SA,
        Method::Hybrid => AACMM_METHOD_HYBRID,
        Method::Global => AACMM_METHOD_GLOBAL,
        // Never: the C API runs the library's own solvers only.
        Method::External => AacmmMethod::MAX,
    }
}

/// The robust fit of a calibration: `AACMM_ROBUST_NONE`, `_HUBER` or
/// `_CAUCHY` (`--robust`).
pub type AacmmRobust = u32;

/// Plain least squares (the default).
pub const AACMM_ROBUST_NONE: AacmmRobust = 0;

/// A robust refit with the Huber loss.
pub const AACMM_ROBUST_HUBER: AacmmRobust = 1;

/// A robust refit with the Cauchy loss.
pub const AACMM_ROBUST_CAUCHY: AacmmRobust = 2;

/// The unit of the angles in a poses file: `AACMM_ANGLE_DEG` or
/// `AACMM_ANGLE_RAD`.
pub type AacmmAngleUnit = u32;

/// Angles in degrees (the command line's default).
pub const AACMM_ANGLE_DEG: AacmmAngleUnit = 0;

/// Angles in radians.
pub const AACMM_ANGLE_RAD: AacmmAngleUnit = 1;

/// Settings of a calibration: the command line's flags. Start from
/// `aacmm_calibrate_options_default` and change what you need; a
/// zero-initialised struct is not the default (it states a reference-length
/// uncertainty of 0).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AacmmCalibrateOptions {
    /// The solver: `AACMM_METHOD_GLOBAL` (default), `_LM`, `_SA` or
    /// `_HYBRID`.
    pub method: AacmmMethod,
    /// Parameters held at their start values: `NULL` or `"auto"` (the
    /// recommended set of the identifiability analysis; default), or
    /// comma-separated names in the order's spelling, e.g.
    /// `"theta1,d1,theta6,alpha6,Bx,By"` (`beta…` is accepted for
    /// `alpha…`): the command line's `--fix`. Read during the call only.
    pub fix: *const c_char,
    /// Seed of every random draw: the solvers' moves and starts, the
    /// cross-validation folds. Default 0.
    pub seed: u64,
    /// `k`-fold cross-validation over points for the report (0 = none, the
    /// default; otherwise 2 or more): `--cross-validate`.
    pub cross_validate: usize,
    /// σ of each encoder reading, rad; 0 = not stated (default). With
    /// `probe_noise_mm` these weigh the touches; when both are 0 the touch σ
    /// is estimated from the fit. (`--encoder-noise`, which is in degrees.)
    pub encoder_noise_rad: f64,
    /// σ of the probe seating per axis, mm; 0 = not stated (default).
    /// (`--probe-noise`.)
    pub probe_noise_mm: f64,
    /// σ of a reference length that states none, mm; default 0.001.
    /// (`--length-uncertainty`.)
    pub length_uncertainty_mm: f64,
    /// Weight of every reference-length residual, 1/mm, overriding the
    /// uncertainties; 0 = none (default). (`--length-weight`.)
    pub length_weight: f64,
    /// Worker threads for the normal equations; 0 = one per core (default).
    /// The results do not depend on it.
    pub threads: usize,
    /// A robust refit after the solver (IRLS, per-touch weights in the
    /// report's `/calibration/robust`): `AACMM_ROBUST_NONE` (default),
    /// `_HUBER` or `_CAUCHY` (`--robust`).
    pub robust: AacmmRobust,
    /// Its tuning constant `k`; 0 = the loss's default (1.62 Huber, 2.65
    /// Cauchy). (`--robust-scale`.)
    pub robust_scale: f64,
}

/// One reference length between two touched points, for `aacmm_calibrate`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AacmmReferenceLength {
    /// Id of the first point (as in the `points` array).
    pub point_a: u32,
    /// Id of the second point (different from `point_a`).
    pub point_b: u32,
    /// Distance, mm, > 0.
    pub distance_mm: f64,
    /// Standard uncertainty of the distance, mm, >= 0; `NAN` = not stated
    /// (then `length_uncertainty_mm` of the options applies).
    pub uncertainty_mm: f64,
}

/// Why the solver stopped.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AacmmTermination {
    /// The relative cost reduction fell below its tolerance.
    CostTolerance = 0,
    /// The relative step fell below its tolerance.
    StepTolerance = 1,
    /// The gradient fell below its tolerance.
    GradientTolerance = 2,
    /// The residuals vanished (exact data).
    ZeroResidual = 3,
    /// The iteration limit was reached first: not converged.
    MaxIterations = 4,
    /// No step lowered the cost, yet the gradient is not small: not
    /// converged.
    NoProgress = 5,
    /// No step lowered the cost and the gradient is nil: a minimum to
    /// machine precision.
    MachinePrecision = 6,
    /// No LM ran: annealing alone (`AACMM_METHOD_SA`); its own stop decides
    /// `successful`.
    NoLm = 7,
}

impl From<Option<Termination>> for AacmmTermination {
    fn from(t: Option<Termination>) -> Self {
        match t {
            Some(Termination::CostTolerance) => AacmmTermination::CostTolerance,
            Some(Termination::StepTolerance) => AacmmTermination::StepTolerance,
            Some(Termination::GradientTolerance) => AacmmTermination::GradientTolerance,
            Some(Termination::ZeroResidual) => AacmmTermination::ZeroResidual,
            Some(Termination::MaxIterations) => AacmmTermination::MaxIterations,
            Some(Termination::NoProgress) => AacmmTermination::NoProgress,
            Some(Termination::MachinePrecision) => AacmmTermination::MachinePrecision,
            None => AacmmTermination::NoLm,
        }
    }
}

/// The figures of a calibration a program acts on; the report has the rest.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AacmmCalibrationSummary {
    /// The method that ran (`AACMM_METHOD_…`).
    pub method: AacmmMethod,
    /// Why the final LM stopped.
    pub termination: AacmmTermination,
    /// Whether the result is usable: the final LM converged and the
    /// method's own stop is not a spent budget (an unconfirmed global
    /// search, an annealing out of evaluations).
    pub successful: bool,
    /// Iterations of the final fit.
    pub iterations: usize,
    /// Parameters fitted (the others were held fixed).
    pub free_parameters: usize,
    /// Residual rows minus unknowns.
    pub degrees_of_freedom: usize,
    /// `sqrt(cost / dof)`: 1 when the weights are right.
    pub sigma0: f64,
    /// The touch σ behind the weights, mm.
    pub touch_sigma_mm: f64,
    /// Weighted cost at the start of the final fit.
    pub initial_cost: f64,
    /// Weighted cost at the end.
    pub final_cost: f64,
}

/// The result of a calibration. Opaque; released by
/// `aacmm_calibration_free`. Never modified after it is made.
pub struct AacmmCalibration {
    report: CalibrationReport,
    calibrated: Arm,
    json: String,
}

/// The defaults of every option (those of `aacmm calibrate`).
#[unsafe(no_mangle)]
pub extern "C" fn aacmm_calibrate_options_default() -> AacmmCalibrateOptions {
    AacmmCalibrateOptions {
        method: AACMM_METHOD_GLOBAL,
        fix: std::ptr::null(),
        seed: 0,
        cross_validate: 0,
        encoder_noise_rad: 0.0,
        probe_noise_mm: 0.0,
        length_uncertainty_mm: DEFAULT_LENGTH_SIGMA_MM,
        length_weight: 0.0,
        threads: 0,
        robust: AACMM_ROBUST_NONE,
        robust_scale: 0.0,
    }
}

/// The options in the library's terms (checked by the library when the
/// problem is made), and the fold count.
struct Settings {
    options: ModelOptions,
    solver: SolverSettings,
    cross_validate: usize,
}

/// # Safety
///
/// `options` is `NULL` or points to an options struct whose `fix` is `NULL`
/// or NUL-terminated.
unsafe fn settings(
    options: *const AacmmCalibrateOptions,
    arm: &aacmm_core::params::DhParams,
) -> Result<Settings, Error> {
    let joints = arm.joint_count();
    let o = if options.is_null() {
        aacmm_calibrate_options_default()
    } else {
        // SAFETY: by the contract.
        *unsafe { ptr::object(options, "options") }?
    };
    let Some(solver) = method(o.method) else {
        return Err(Error::invalid(format!(
            "options.method = {}: one of AACMM_METHOD_LM ({AACMM_METHOD_LM}), _SA \
             ({AACMM_METHOD_SA}), _HYBRID ({AACMM_METHOD_HYBRID}), _GLOBAL ({AACMM_METHOD_GLOBAL})",
            o.method
        )));
    };
    let loss = match o.robust {
        AACMM_ROBUST_NONE => None,
        AACMM_ROBUST_HUBER => Some(Loss::Huber),
        AACMM_ROBUST_CAUCHY => Some(Loss::Cauchy),
        other => {
            return Err(Error::invalid(format!(
                "options.robust = {other}: one of AACMM_ROBUST_NONE ({AACMM_ROBUST_NONE}), \
                 _HUBER ({AACMM_ROBUST_HUBER}), _CAUCHY ({AACMM_ROBUST_CAUCHY})"
            )));
        }
    };
    let fix = if o.fix.is_null() {
        "auto".to_string()
    } else {
        // SAFETY: non-null, NUL-terminated by the contract.
        let s = unsafe { CStr::from_ptr(o.fix) };
        s.to_str()
            .map_err(|_| Error::invalid("options.fix is not valid UTF-8"))?
            .to_string()
    };
    // 0 = not stated; anything else goes to the library, which refuses
    // negative and non-finite values by field.
    let stated = |v: f64| (v != 0.0).then_some(v);
    let threads = match o.threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    };
    // `..default()`: settings the C API does not expose (annealing
    // schedule, start budget) keep the library's defaults, which are the
    // command line's.
    let settings = SolverSettings {
        method: solver,
        seed: o.seed,
        threads,
        ..SolverSettings::default()
    };
    let options = ModelOptions {
        fix: FixSpec::parse_for(&fix, arm)?,
        noise: Noise {
            encoder_rad: stated(o.encoder_noise_rad),
            probe_mm: stated(o.probe_noise_mm),
            length_default_mm: o.length_uncertainty_mm,
            length_weight: stated(o.length_weight),
        },
        robust: loss.map(|loss| Robust {
            loss,
            scale_k: if o.robust_scale == 0.0 {
                loss.default_k()
            } else {
                o.robust_scale
            },
        }),
        ..ModelOptions::default()
    };
    options.check(joints)?;
    settings.check()?;
    if o.cross_validate == 1 {
        return Err(Error::invalid(
            "options.cross_validate = 1: 0 (none) or 2 or more folds",
        ));
    }
    Ok(Settings {
        options,
        solver: settings,
        cross_validate: o.cross_validate,
    })
}

/// Calibrates and builds the result: the library's session (what the
/// command line runs), without held-out validation.
fn run(
    start: &Arm,
    data: DataSet,
    s: Settings,
    sources: Sources,
) -> Result<AacmmCalibration, Error> {
    let mut problem = Problem::new(start.clone(), data, s.options)
        .map_err(|e| in_file(e, &sources.arm_file))?
        .with_sources(sources);
    if s.cross_validate != 0 {
        problem = problem.with_cross_validation(s.cross_validate)?;
    }
    let report = problem
        .run(&s.solver)
        .map_err(|e| in_file(e, &problem.sources().arm_file))?;
    Ok(AacmmCalibration {
        calibrated: report.calibrated_arm(start),
        json: report.to_json(),
        report,
    })
}

/// A calibration error, named after the arm file unless it is a refused
/// option (which names its field).
fn in_file(e: aacmm_core::CalibrationError, arm: &str) -> Error {
    let option = matches!(e, aacmm_core::CalibrationError::Option(_));
    let e = Error::from(e);
    if option {
        e
    } else {
        Error::new(e.status, format!("{arm}: {}", e.message))
    }
}

/// Calibrates the arm of an arm file on a poses file and an optional
/// reference-lengths file: `aacmm calibrate --arm ARM --data POSES
/// [--lengths LENGTHS]` with the flags of `options` (`NULL` = defaults).
/// The parameters are the command line's, bit for bit; held-out validation
/// (`--validate`) is not part of the C API.
///
/// `poses_unit` is the unit of the poses file's angles (`AACMM_ANGLE_DEG`,
/// `AACMM_ANGLE_RAD`); `lengths_path` may be `NULL`. The result goes to a
/// new handle at `*out`; a solver that did not converge still gives a
/// result (check `successful` in `aacmm_calibration_summary`).
///
/// Errors: `AACMM_STATUS_NULL_POINTER`, `AACMM_STATUS_IO` (a file cannot be
/// read), `AACMM_STATUS_INPUT` (a file's content; the message names file,
/// line and field), `AACMM_STATUS_INVALID_ARGUMENT` (an option),
/// `AACMM_STATUS_UNSUPPORTED`, `AACMM_STATUS_CALIBRATION` (the data cannot
/// determine the free parameters). On error `*out` is `NULL`.
///
/// # Safety
///
/// The paths are `NULL` or NUL-terminated strings; `options` is `NULL` or
/// points to an options struct (its `fix` `NULL` or NUL-terminated); `out`
/// is `NULL` or points to writable memory for one pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_files(
    arm_path: *const c_char,
    poses_path: *const c_char,
    lengths_path: *const c_char,
    poses_unit: AacmmAngleUnit,
    options: *const AacmmCalibrateOptions,
    out: *mut *mut AacmmCalibration,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        unsafe { ptr::write(out, std::ptr::null_mut(), "out") }?;
        // SAFETY: by the contract.
        let (arm_path, poses_path) = unsafe {
            (
                ptr::path(arm_path, "arm_path")?,
                ptr::path(poses_path, "poses_path")?,
            )
        };
        let lengths_path = match lengths_path.is_null() {
            true => None,
            // SAFETY: by the contract.
            false => Some(unsafe { ptr::path(lengths_path, "lengths_path") }?),
        };
        let unit = match poses_unit {
            AACMM_ANGLE_DEG => AngleUnit::Deg,
            AACMM_ANGLE_RAD => AngleUnit::Rad,
            u => {
                return Err(Error::invalid(format!(
                    "poses_unit = {u}: AACMM_ANGLE_DEG (0) or AACMM_ANGLE_RAD (1)"
                )));
            }
        };
        let (arm, mut warnings) = read_arm(&arm_path)?;
        let (arm_file, data_file) = (source_name(&arm_path), source_name(&poses_path));
        // SAFETY: by the contract.
        let s = unsafe { settings(options, &arm.params) }?;
        let (poses, poses_warnings) =
            read_poses(&poses_path, unit, Some(arm.params.joint_count()))?;
        warnings.extend(poses_warnings);
        let mut data = DataSet::from_poses(&poses, &data_file)?;
        let lengths_file = lengths_path.as_deref().map(source_name);
        if let (Some(path), Some(file)) = (&lengths_path, &lengths_file) {
            data = data.with_lengths(&read_lengths(path)?, file)?;
        }
        let sources = Sources {
            arm_file,
            data_file,
            lengths_file,
            warnings: warnings.iter().map(ToString::to_string).collect(),
        };
        let result = run(&arm, data, s, sources)?;
        // SAFETY: checked writable above.
        unsafe { ptr::write(out, Box::into_raw(Box::new(result)), "out") }
    })
}

/// Calibrates `start` on touches and reference lengths given as arrays.
///
/// `q` holds the readings (rad) of `n = q_len / joints` touches, row-major
/// as in `aacmm_positions`; `points[i]` is the id of the point touch `i`
/// touched (`points_len = n`; touches with the same id touch the same
/// point, which needs at least 3 touches); `lengths` holds `lengths_len`
/// reference lengths between point ids (may be `NULL` when `lengths_len`
/// is 0). Same solver and options as `aacmm_calibrate_files`; on the same
/// data (point ids in place of labels) it gives the same parameters.
///
/// Errors: as `aacmm_calibrate_files`; `AACMM_STATUS_LENGTH` for `q_len`
/// or `points_len` that do not match; `AACMM_STATUS_INPUT` for a point with
/// fewer than 3 touches, or a length that joins a point to itself, names an
/// unknown point, repeats a pair, or has a distance <= 0 or a negative
/// uncertainty.
///
/// # Safety
///
/// `start` is `NULL` or a live arm handle; `q`, `points`, `lengths` point to
/// their stated lengths of values (each may be `NULL` when its length is
/// 0); `options` and `out` as in `aacmm_calibrate_files`.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn aacmm_calibrate(
    start: *const AacmmArm,
    q: *const f64,
    q_len: usize,
    points: *const u32,
    points_len: usize,
    lengths: *const AacmmReferenceLength,
    lengths_len: usize,
    options: *const AacmmCalibrateOptions,
    out: *mut *mut AacmmCalibration,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        unsafe { ptr::write(out, std::ptr::null_mut(), "out") }?;
        // SAFETY: by the contract.
        let start = unsafe { handle(start) }?;
        let joints = start.joints();
        let n = pose_count(q_len, joints)?;
        if points_len != n {
            return Err(Error::length(format!(
                "points_len = {points_len}, expected {n} (one point id per touch)"
            )));
        }
        // SAFETY: by the contract.
        let (q, points, lengths) = unsafe {
            (
                ptr::input(q, q_len, "q")?,
                ptr::input(points, points_len, "points")?,
                ptr::input(lengths, lengths_len, "lengths")?,
            )
        };
        // SAFETY: by the contract.
        let s = unsafe { settings(options, &start.arm.params) }?;
        let data = array_data(joints, q, points, lengths)?;
        let sources = Sources {
            arm_file: start.source.clone(),
            data_file: "<arrays>".to_string(),
            lengths_file: (!lengths.is_empty()).then(|| "<arrays>".to_string()),
            warnings: start.warnings.clone(),
        };
        let result = run(&start.arm, data, s, sources)?;
        // SAFETY: checked writable above.
        unsafe { ptr::write(out, Box::into_raw(Box::new(result)), "out") }
    })
}

/// The data set of the array interface, checked as the file readers check
/// files (messages name the array and index).
fn array_data(
    joints: usize,
    q: &[f64],
    points: &[u32],
    lengths: &[AacmmReferenceLength],
) -> Result<DataSet, Error> {
    let input = |m: String| Error::new(AacmmStatus::Input, m);
    if points.is_empty() {
        return Err(input("no touches (q_len = 0)".into()));
    }
    if let Some(i) = q.iter().position(|v| !v.is_finite()) {
        return Err(input(format!("q[{i}] = {}: readings must be finite", q[i])));
    }
    let mut touches: HashMap<u32, (usize, usize)> = HashMap::new();
    for (i, &id) in points.iter().enumerate() {
        touches.entry(id).or_insert((i, 0)).1 += 1;
    }
    let mut few: Vec<(usize, u32, usize)> = (touches.iter())
        .filter(|(_, (_, count))| *count < MIN_TOUCHES)
        .map(|(&id, &(first, count))| (first, id, count))
        .collect();
    few.sort_unstable();
    if let Some(&(first, id, count)) = few.first() {
        return Err(input(format!(
            "points[{first}]: point {id} has {count} touch{}; at least {MIN_TOUCHES} are needed",
            if count == 1 { "" } else { "es" }
        )));
    }
    let mut poses = Poses::with_capacity(joints, points.len());
    for (i, (id, row)) in points.iter().zip(q.chunks_exact(joints)).enumerate() {
        poses.push(&id.to_string(), row, i + 1);
    }
    let data = DataSet::from_poses(&poses, "points")?;
    if lengths.is_empty() {
        return Ok(data);
    }
    let mut pairs = HashSet::new();
    let mut refs = Vec::with_capacity(lengths.len());
    for (i, l) in lengths.iter().enumerate() {
        let at = |m: String| input(format!("lengths[{i}]: {m}"));
        for id in [l.point_a, l.point_b] {
            if !touches.contains_key(&id) {
                return Err(at(format!("unknown point {id}: no touch has this id")));
            }
        }
        if l.point_a == l.point_b {
            return Err(at(format!(
                "point_b = point_a = {}: a length needs two points",
                l.point_a
            )));
        }
        if !(l.distance_mm.is_finite() && l.distance_mm > 0.0) {
            return Err(at(format!(
                "distance_mm = {}: must be a positive number",
                l.distance_mm
            )));
        }
        let u = l.uncertainty_mm;
        if !(u.is_nan() || (u.is_finite() && u >= 0.0)) {
            return Err(at(format!(
                "uncertainty_mm = {u}: must be >= 0, or NAN for not stated"
            )));
        }
        let pair = (l.point_a.min(l.point_b), l.point_a.max(l.point_b));
        if !pairs.insert(pair) {
            return Err(at(format!(
                "the pair {}–{} is given twice",
                l.point_a, l.point_b
            )));
        }
        refs.push(ReferenceLength {
            a: l.point_a.to_string(),
            b: l.point_b.to_string(),
            distance: l.distance_mm,
            uncertainty: (!u.is_nan()).then_some(u),
            line: i + 1,
        });
    }
    Ok(data.with_lengths(&refs, "lengths")?)
}

/// The result behind `cal`.
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle.
unsafe fn result<'a>(cal: *const AacmmCalibration) -> Result<&'a AacmmCalibration, Error> {
    // SAFETY: forwarded contract.
    unsafe { ptr::object(cal, "cal") }
}

/// Releases a calibration result. `NULL` is allowed (nothing happens).
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle, which must not be used
/// afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_free(cal: *mut AacmmCalibration) {
    guard_value((), || {
        if !cal.is_null() {
            // SAFETY: a live handle made by `Box::into_raw`, given up by
            // the caller.
            drop(unsafe { Box::from_raw(cal) });
        }
    })
}

/// Copies one value per parameter into `out` (`len = 4·joints + 3`).
///
/// # Safety
///
/// As the accessors below.
unsafe fn per_parameter<T: Copy>(
    cal: *const AacmmCalibration,
    out: *mut T,
    len: usize,
    value: impl Fn(&AacmmCalibration, usize, ParamId) -> T,
) -> Result<(), Error> {
    // SAFETY: by the contract.
    let cal = unsafe { result(cal) }?;
    let count = cal.calibrated.params.param_count();
    if len != count {
        return Err(Error::length(format!(
            "len = {len}, expected {count} (4 · joints + 3)"
        )));
    }
    // SAFETY: by the contract.
    let out = unsafe { ptr::output(out, len, "out") }?;
    // The arm's own names: a Hayati joint's d-slot holds β.
    for (c, id) in cal.calibrated.params.param_ids().enumerate() {
        out[c].write(value(cal, c, id));
    }
    Ok(())
}

/// The calibrated parameters (mm, rad; the order of
/// `aacmm_arm_from_params`; zero offsets `theta` wrapped to ±π) into
/// `params` (`params_len = 4·joints + 3`).
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `params` is `NULL` or points to
/// `params_len` writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_params(
    cal: *const AacmmCalibration,
    params: *mut f64,
    params_len: usize,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: forwarded contract.
        unsafe {
            per_parameter(cal, params, params_len, |c, _, id| {
                c.calibrated.params.get(id)
            })
        }
    })
}

/// The standard uncertainties (k = 1) of the calibrated parameters (mm,
/// rad) into `sigma` (`sigma_len = 4·joints + 3`); `NAN` for a parameter
/// held fixed (or one the data do not determine).
///
/// # Safety
///
/// As `aacmm_calibration_params`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_sigmas(
    cal: *const AacmmCalibration,
    sigma: *mut f64,
    sigma_len: usize,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: forwarded contract.
        unsafe {
            per_parameter(cal, sigma, sigma_len, |c, i, _| {
                c.report.calibration.parameters[i].sigma.unwrap_or(f64::NAN)
            })
        }
    })
}

/// Whether each parameter was held fixed (`true`) or fitted, into `fixed`
/// (`fixed_len = 4·joints + 3`).
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `fixed` is `NULL` or points to
/// `fixed_len` writable `bool`s.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_fixed(
    cal: *const AacmmCalibration,
    fixed: *mut bool,
    fixed_len: usize,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: forwarded contract.
        unsafe {
            per_parameter(cal, fixed, fixed_len, |c, i, _| {
                c.report.calibration.parameters[i].fixed.is_some()
            })
        }
    })
}

/// The solver's outcome and the fit's figures into `*summary`.
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `summary` is `NULL` or points to
/// writable memory for the struct.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_summary(
    cal: *const AacmmCalibration,
    summary: *mut AacmmCalibrationSummary,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let c = &unsafe { result(cal) }?.report.calibration;
        let value = AacmmCalibrationSummary {
            method: method_code(c.solver.method),
            termination: c.solver.stop.lm().into(),
            successful: c.solver.successful,
            iterations: c.solver.iterations,
            free_parameters: c.dof.free_parameters,
            degrees_of_freedom: c.dof.degrees_of_freedom,
            sigma0: c.dof.sigma0,
            touch_sigma_mm: c.dof.touch_sigma_mm,
            initial_cost: c.solver.initial_cost,
            final_cost: c.solver.final_cost,
        };
        // SAFETY: by the contract.
        unsafe { ptr::write(summary, value, "summary") }
    })
}

/// The calibrated arm as a new arm handle at `*out` (release it with
/// `aacmm_arm_free`; it outlives the result).
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `out` is `NULL` or points to
/// writable memory for one pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_arm(
    cal: *const AacmmCalibration,
    out: *mut *mut AacmmArm,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        unsafe { ptr::write(out, std::ptr::null_mut(), "out") }?;
        // SAFETY: by the contract.
        let c = unsafe { result(cal) }?;
        let arm = AacmmArm::new(c.calibrated.clone(), "<calibration>".into(), Vec::new())?;
        // SAFETY: checked writable above.
        unsafe { ptr::write(out, arm.into_raw(), "out") }
    })
}

/// The report as JSON (UTF-8), copied into `buf` like
/// `aacmm_last_error_message`; `*len` gets its full length in bytes without
/// the NUL. Returns `AACMM_STATUS_BUFFER_TOO_SMALL` when the copy was
/// truncated (`buf` may be `NULL` with `buf_len` 0 to ask for the length).
///
/// The report is the command line's `calibration.json`, byte for byte on
/// the same inputs and options (parameters in mm and deg there, as its
/// `units` says; `validation.held_out` is null, as the C API does not
/// validate on held-out data; `warnings` holds the readers' warnings).
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `buf` is `NULL` or points to
/// `buf_len` writable bytes; `len` is `NULL` or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_report(
    cal: *const AacmmCalibration,
    buf: *mut c_char,
    buf_len: usize,
    len: *mut usize,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let c = unsafe { result(cal) }?;
        // SAFETY: by the contract.
        unsafe { string_out(&c.json, buf, buf_len, len) }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use aacmm_core::params::DhParams;

    fn length(a: u32, b: u32, distance_mm: f64, uncertainty_mm: f64) -> AacmmReferenceLength {
        AacmmReferenceLength {
            point_a: a,
            point_b: b,
            distance_mm,
            uncertainty_mm,
        }
    }

    /// Three points of three touches each, 6 joints.
    fn touches() -> (Vec<f64>, Vec<u32>) {
        let points = vec![7, 7, 7, 3, 3, 3, 9, 9, 9];
        let q = (0..points.len() * 6)
            .map(|i| (i as f64 * 0.3).sin())
            .collect();
        (q, points)
    }

    fn message(e: Error) -> (AacmmStatus, String) {
        (e.status, e.message)
    }

    #[test]
    fn arrays_are_checked_like_files() {
        let (q, points) = touches();
        let ok = array_data(6, &q, &points, &[length(7, 9, 500.0, f64::NAN)]).unwrap();
        assert_eq!(ok.points()[1].label, "3");
        assert_eq!((ok.references()[0].a, ok.references()[0].b), (0, 2));
        assert_eq!(ok.references()[0].uncertainty, None);
        let cases = [
            (
                length(7, 7, 500.0, f64::NAN),
                "lengths[0]: point_b = point_a = 7",
            ),
            (length(7, 4, 500.0, f64::NAN), "lengths[0]: unknown point 4"),
            (length(7, 3, -1.0, f64::NAN), "lengths[0]: distance_mm = -1"),
            (length(7, 3, 1.0, -0.1), "lengths[0]: uncertainty_mm = -0.1"),
        ];
        for (l, expected) in cases {
            let (status, m) = message(array_data(6, &q, &points, &[l]).unwrap_err());
            assert_eq!(status, AacmmStatus::Input);
            assert!(m.starts_with(expected), "{m}");
        }
        let twice = [length(7, 3, 1.0, 0.0), length(3, 7, 1.0, 0.0)];
        let (_, m) = message(array_data(6, &q, &points, &twice).unwrap_err());
        assert!(
            m.starts_with("lengths[1]: the pair 3–7 is given twice"),
            "{m}"
        );
        let (_, m) = message(array_data(6, &q[..48], &points[..8], &[]).unwrap_err());
        assert!(m.starts_with("points[6]: point 9 has 2 touches"), "{m}");
        let mut nan = q.clone();
        nan[4] = f64::NAN;
        let (_, m) = message(array_data(6, &nan, &points, &[]).unwrap_err());
        assert!(m.starts_with("q[4] = NaN"), "{m}");
    }

    #[test]
    fn options_are_checked_like_flags() {
        let mut o = aacmm_calibrate_options_default();
        // SAFETY: `o` is a live options struct with a NULL `fix`.
        let s = unsafe { settings(&o, &DhParams::paper_nominal()) }.unwrap();
        assert_eq!(s.options.fix, FixSpec::Auto);
        assert_eq!(s.options.noise.encoder_rad, None);
        assert_eq!(s.options.noise.length_default_mm, DEFAULT_LENGTH_SIGMA_MM);
        o.probe_noise_mm = -1.0;
        // SAFETY: as above.
        let e = unsafe { settings(&o, &DhParams::paper_nominal()) }
            .err()
            .unwrap();
        assert_eq!(e.status, AacmmStatus::InvalidArgument);
        assert_eq!(
            e.message,
            "options.probe_noise_mm = -1: must be a finite number ≥ 0"
        );
        o.probe_noise_mm = 0.0;
        o.threads = 0;
        o.length_uncertainty_mm = f64::NAN;
        // SAFETY: as above.
        let e = unsafe { settings(&o, &DhParams::paper_nominal()) }
            .err()
            .unwrap();
        assert!(
            e.message.starts_with("options.length_uncertainty_mm = NaN"),
            "{}",
            e.message
        );
        o = aacmm_calibrate_options_default();
        o.fix = c"theta1, d1".as_ptr();
        // SAFETY: `fix` points to a NUL-terminated literal.
        let s = unsafe { settings(&o, &DhParams::paper_nominal()) }.unwrap();
        assert_eq!(s.options.fix, FixSpec::Columns(vec![18, 6]));
        o.cross_validate = 1;
        // SAFETY: as above.
        assert!(unsafe { settings(&o, &DhParams::paper_nominal()) }.is_err());
        // SAFETY: NULL options are the defaults.
        assert!(unsafe { settings(std::ptr::null(), &DhParams::paper_nominal()) }.is_ok());
    }
}
