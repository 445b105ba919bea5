//! Calibration from files or arrays, and the result handle.

use std::ffi::c_char;

use aacmm_core::calibrate::Termination;
use aacmm_core::dataset::{ArrayLength, DataSet};
use aacmm_core::domain::Arm;
use aacmm_core::io::AngleUnit;
use aacmm_core::params::ParamId;
use aacmm_core::residuals::Frame;
use aacmm_core::session::{CalibrationReport, Reason, Request, Sources, Spelling};

use crate::arm::{AacmmArm, handle, pose_count, string_args, string_out};
use crate::error::{AacmmStatus, Error, guard, guard_value};
use crate::options::{self, AacmmCalibrateOptions, AacmmMethod, PositionInput, method_code};
use crate::positions::ARRAYS;
use crate::ptr::{self, Args};

/// The unit of the angles in a poses file: `AACMM_ANGLE_DEG` or
/// `AACMM_ANGLE_RAD`.
pub type AacmmAngleUnit = u32;

/// Angles in degrees (the command line's default).
pub const AACMM_ANGLE_DEG: AacmmAngleUnit = 0;

/// Angles in radians.
pub const AACMM_ANGLE_RAD: AacmmAngleUnit = 1;

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
    /// (then the options' length uncertainty applies:
    /// `aacmm_calibrate_options_set_length_uncertainty_mm`).
    pub uncertainty_mm: f64,
}

impl From<&AacmmReferenceLength> for ArrayLength {
    fn from(l: &AacmmReferenceLength) -> ArrayLength {
        ArrayLength {
            point_a: l.point_a,
            point_b: l.point_b,
            distance_mm: l.distance_mm,
            // NAN is C's "not stated"; any other value goes to the
            // library's check.
            uncertainty_mm: (!l.uncertainty_mm.is_nan()).then_some(l.uncertainty_mm),
        }
    }
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
    /// `converged`.
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
    /// Whether the result is usable: the library's verdict, what the
    /// command line's exit status and Python's `Calibration.successful`
    /// say. False when the solver did not converge, when the calibrated
    /// arm is not the nominal arm's geometry (a mirror image, a collapsed
    /// arm, a unit mistake), or when the fit is poor (a χ² far outside the
    /// stated noise, an arm worse than the nominal on its own data) unless
    /// a poor fit was accepted (`aacmm_calibrate_options_set_accept_poor_fit`).
    /// `aacmm_calibration_verdict` says why.
    pub successful: bool,
    /// Whether the solver converged: the final LM converged and the
    /// method's own stop is not a spent budget (an unconfirmed global
    /// search, an annealing out of evaluations). A converged fit may still
    /// be refused (`successful` false).
    pub converged: bool,
    /// Iterations of the final fit.
    pub iterations: usize,
    /// Parameters fitted (the others were held fixed).
    pub free_parameters: usize,
    /// Residual rows minus unknowns.
    pub degrees_of_freedom: usize,
    /// `sqrt(cost / dof)`: 1 when the weights are right.
    pub sigma0: f64,
    /// The touch σ behind the weights, mm (without touches: the position
    /// σ).
    pub touch_sigma_mm: f64,
    /// Weighted cost at the start of the final fit.
    pub initial_cost: f64,
    /// Weighted cost at the end.
    pub final_cost: f64,
}

/// A tool point fitted with the arm (`aacmm_calibration_tool`): its
/// offset in the last joint's frame, like the arm's probe (the `[[tool]]`
/// table of the command line's `calibrated.toml`).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AacmmTool {
    /// The offset `x, y, z`, mm.
    pub offset_mm: [f64; 3],
    /// Their standard uncertainties (k = 1), mm; `NAN` where the data did
    /// not determine them.
    pub sigma_mm: [f64; 3],
}

/// One fitted frame of reference positions, for `aacmm_calibration_frame`:
/// the rigid registration `y = R p + t` that maps the arm's base
/// coordinates `p` into the instrument's `y` (the `[[frame]]` table of the
/// command line's `calibrated.toml`).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AacmmFrame {
    /// The rotation vector of `R` (axis × angle), deg.
    pub rotation_deg: [f64; 3],
    /// `t`, mm.
    pub translation_mm: [f64; 3],
    /// Standard uncertainties (k = 1), deg, of small rotations about the
    /// instrument's x, y and z axes (the fit's step `R ← exp(δω) R`; not
    /// of `rotation_deg`'s components); `NAN` where the data did not
    /// determine them.
    pub small_rotation_sigma_deg: [f64; 3],
    /// Standard uncertainties (k = 1) of `t`, mm; `NAN` where the data did
    /// not determine them.
    pub translation_sigma_mm: [f64; 3],
    /// `R`, row-major: `R[i][k]` at `3·i + k`.
    pub rotation_matrix: [f64; 9],
}

/// One column of a calibration's auxiliary blocks, for
/// `aacmm_calibration_auxiliary`: an unknown fitted with the arm beyond its
/// parameters — a correction beyond geometry (`--compliance`,
/// `--harmonics`, `--thermal`, `--drift`) or a coordinate of a frame of
/// reference positions — as the report's `calibration.auxiliary` has it.
/// Values are in the column's unit, given by its name: `complianceJ`
/// µrad/(N·m); `harmonicJ.sinK`, `harmonicJ.cosK` deg; `thermal.cte` ppm/K;
/// `drift.x`, `.y`, `.z` mm/h; a frame's `NAME.rx`, `.ry`, `.rz` deg and
/// `NAME.tx`, `.ty`, `.tz` mm.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct AacmmAuxiliary {
    /// The value the fit started from (for a correction, the arm file's
    /// stated value, else 0).
    pub start: f64,
    /// The calibrated value.
    pub calibrated: f64,
    /// Standard uncertainty (k = 1); `NAN` where the data did not
    /// determine it (and for a column held at its start). For a frame's
    /// rotation columns (`NAME.rx`, `.ry`, `.rz`: its rotation vector) the
    /// σ of a small rotation about the frame's x, y, z axis (the report's
    /// `calibration.auxiliary[index].sigma_of`).
    pub sigma: f64,
    /// Whether the column was held at its start value: a correction these
    /// data cannot separate (why: the report's
    /// `calibration.auxiliary[index].fixed`).
    pub fixed: bool,
}

/// The result of a calibration. Opaque; released by
/// `aacmm_calibration_free`. Never modified after it is made.
pub struct AacmmCalibration {
    pub(crate) report: CalibrationReport,
    calibrated: Arm,
    json: String,
}

/// Calibrates and builds the result: the library's request and session
/// (what the command line runs), without held-out validation.
fn run(
    request: Request,
    cancel: Option<&aacmm_core::calibrate::Cancel>,
) -> Result<AacmmCalibration, Error> {
    let arm_file = request.arm_file().to_string();
    let (problem, settings) = request.build().map_err(|e| in_file(e, &arm_file))?;
    let mut ctx = aacmm_core::calibrate::Context::new();
    if let Some(token) = cancel {
        ctx = ctx.cancelled_by(token.clone());
    }
    let solver = settings.method.solver();
    let report = aacmm_core::session::run(&problem, &settings, &*solver, &mut ctx)
        .map_err(|e| in_file(e, &arm_file))?;
    // A run's report keeps its start arm.
    let calibrated = (report.calibrated_arm())
        .ok_or_else(|| Error::new(AacmmStatus::Panic, "internal: the report has no start arm"))?;
    Ok(AacmmCalibration {
        calibrated,
        json: report.to_json(),
        report,
    })
}

/// A calibration error, named after the arm file unless it is a refused
/// option (which names its field) or names the input at fault itself (a
/// unit mistake: the lengths, poses or arm file first).
fn in_file(e: aacmm_core::CalibrationError, arm: &str) -> Error {
    let named = matches!(e, aacmm_core::CalibrationError::Option(_)) || e.names_its_input();
    let e = Error::from(e);
    if named {
        e
    } else {
        Error::new(e.status, format!("{arm}: {}", e.message))
    }
}

/// Calibrates the arm of an arm file on a poses file and an optional
/// reference-lengths file: `aacmm calibrate --arm ARM --data POSES
/// [--lengths LENGTHS]` with the flags of `options` (`NULL` = the
/// defaults). The arm file's `[prior]` table, if any, is used as the
/// command line uses it (`aacmm_calibrate_options_set_prior` overrides or
/// drops it). The parameters and the verdict are the command line's, bit
/// for bit; held-out validation (`--validate`) is not part of the C API.
///
/// With a positions file in the options
/// (`aacmm_calibrate_options_set_positions_file`: `--positions`) its
/// reference positions are fitted with the touches, or alone when
/// `poses_path` is `NULL`; the fitted frames are then in
/// `aacmm_calibration_frame`.
///
/// `poses_unit` is the unit of the angles of the poses file and of the
/// positions file (`AACMM_ANGLE_DEG`, `AACMM_ANGLE_RAD`: `--angle-unit`);
/// a prismatic joint's column is mm whatever it says (the arm file's
/// `type`); `lengths_path` may be `NULL`. The result goes to a
/// new handle at `*out`; a calibration the library does not call usable
/// (the solver did not converge, a mirror-image arm, a poor fit) still
/// gives a result: check `successful` in `aacmm_calibration_summary`, and
/// `aacmm_calibration_verdict` for why.
///
/// Errors: `AACMM_STATUS_NULL_POINTER`, `AACMM_STATUS_IO` (a file cannot be
/// read), `AACMM_STATUS_INPUT` (a file's content; the message names file,
/// line and field), `AACMM_STATUS_INVALID_ARGUMENT` (an option, e.g. a
/// fixed parameter or a prior target the arm does not have),
/// `AACMM_STATUS_UNSUPPORTED`, `AACMM_STATUS_CALIBRATION` (the data cannot
/// determine the free parameters); `AACMM_STATUS_NULL_POINTER` for a `NULL`
/// `poses_path` without a positions file, `AACMM_STATUS_INVALID_ARGUMENT`
/// for positions set as arrays. On error `*out` is `NULL`.
///
/// # Safety
///
/// The paths are `NULL` or NUL-terminated strings; `options` is `NULL` or a
/// live options handle that no setter changes during the call; `out` is
/// `NULL` or points to writable memory for one pointer.
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
        // SAFETY: the paths are NULL or NUL-terminated, by the contract.
        let args = unsafe {
            (Args::new().c_str("arm_path", arm_path))
                .c_str("poses_path", poses_path)
                .c_str("lengths_path", lengths_path)
        };
        (args.object("options", options))
            .out("out", out)
            .disjoint()?;
        // SAFETY: by the contract.
        unsafe { ptr::write(out, std::ptr::null_mut(), "out") }?;
        // SAFETY: by the contract.
        let arm_path = unsafe { ptr::path(arm_path, "arm_path") }?;
        let poses_path = match poses_path.is_null() {
            true => None,
            // SAFETY: by the contract.
            false => Some(unsafe { ptr::path(poses_path, "poses_path") }?),
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
        // SAFETY: by the contract.
        let mut o = unsafe { options::read(options) }?;
        let positions = match o.take_positions() {
            None => None,
            Some(PositionInput::File(path)) => Some(path),
            Some(PositionInput::Arrays(_)) => {
                return Err(Error::invalid(
                    "positions set as arrays (aacmm_calibrate_options_set_positions) go with \
                     aacmm_calibrate; give aacmm_calibrate_files a positions file \
                     (aacmm_calibrate_options_set_positions_file)",
                ));
            }
        };
        let spheres = o.spheres().map(std::path::Path::to_path_buf);
        // The command line's order: poses (or positions alone, or spheres
        // alone), lengths, positions, spheres.
        let mut request = match (&poses_path, &positions, &spheres) {
            (Some(poses), _, _) => Request::read(&arm_path, poses, unit)?,
            (None, Some(path), _) => Request::read_positions_only(&arm_path, path, unit)?,
            (None, None, Some(path)) => Request::read_spheres_only(&arm_path, path, unit)?,
            (None, None, None) => {
                return Err(Error::new(
                    AacmmStatus::NullPointer,
                    "`poses_path` is NULL: give a poses file, a positions file \
                     (aacmm_calibrate_options_set_positions_file), a sphere-surface file \
                     (aacmm_calibrate_options_set_spheres_file) or more",
                ));
            }
        };
        if let Some(path) = &lengths_path {
            request = request.read_lengths(path)?;
        }
        if let (Some(_), Some(path)) = (&poses_path, &positions) {
            request = request.read_positions(path)?;
        }
        if let (true, Some(path)) = (poses_path.is_some() || positions.is_some(), &spheres) {
            request = request.read_spheres(path)?;
        }
        let result = run(options::request(&o, request), o.cancel())?;
        // SAFETY: checked writable above.
        unsafe { ptr::hand_out(out, result, "out") }
    })
}

/// Calibrates `start` on touches and reference lengths given as arrays.
///
/// `q` holds the readings (rad; a prismatic joint's mm, whatever unit the
/// files of `aacmm_calibrate_files` are in) of `n = q_len / joints` touches, row-major
/// as in `aacmm_positions`; `points[i]` is the id of the point touch `i`
/// touched (`points_len = n`; touches with the same id touch the same
/// point, which needs at least 3 touches); `lengths` holds `lengths_len`
/// reference lengths between point ids (may be `NULL` when `lengths_len`
/// is 0). Same solver and options as `aacmm_calibrate_files`, and the
/// prior of `start`'s arm file if it was read from one
/// (`aacmm_arm_from_file`); on the same data (point ids in place of
/// labels) it gives the same parameters.
///
/// With reference positions in the options
/// (`aacmm_calibrate_options_set_positions`, for an arm of `start`'s joint
/// count) they are fitted with the touches, or alone when there are no
/// touches (`q_len`, `points_len` and `lengths_len` 0; `q`, `points` and
/// `lengths` may then be `NULL`); the fitted frames are then in
/// `aacmm_calibration_frame`.
///
/// Errors: as `aacmm_calibrate_files`; `AACMM_STATUS_LENGTH` for `q_len`
/// or `points_len` that do not match, or positions of another joint count
/// than `start`'s; `AACMM_STATUS_INVALID_ARGUMENT` for a positions file in
/// the options (`aacmm_calibrate_files` reads it); `AACMM_STATUS_INPUT` for a
/// non-finite reading, a point with fewer than 3 touches, touches without
/// articulation, or a length that joins a point to itself, names an
/// unknown point, repeats a pair, or has a distance <= 0 or a negative
/// uncertainty: the message names the array and the index
/// (`points[6]: point 9 has 2 touches; …`, `lengths[0]: …`);
/// `AACMM_STATUS_LENGTH` also for lengths too large to calibrate in memory,
/// and `AACMM_STATUS_OUT_OF_MEMORY` when the memory the calibration needs
/// (about 256 bytes per touch) cannot be allocated, checked before any
/// work.
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
        // What the lengths imply first: a length error, not an overlap of
        // a span no memory holds.
        // For 7 joints, the most a kernel has, before the arm is read.
        let bytes = calibration_bytes(points_len, lengths_len, 7)?;
        (Args::new().object("start", start))
            .input("q", q, q_len)?
            .input("points", points, points_len)?
            .input("lengths", lengths, lengths_len)?
            .object("options", options)
            .out("out", out)
            .disjoint()?;
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
        ptr::room_for("aacmm_calibrate", bytes)?;
        // SAFETY: by the contract.
        let (q, points, lengths) = unsafe {
            (
                ptr::input(q, q_len, "q")?,
                ptr::input(points, points_len, "points")?,
                ptr::input(lengths, lengths_len, "lengths")?,
            )
        };
        // SAFETY: by the contract.
        let mut o = unsafe { options::read(options) }?;
        let positions = match o.take_positions() {
            None => None,
            Some(PositionInput::Arrays(rows)) if rows.joints() != joints => {
                return Err(Error::length(format!(
                    "the options' positions (aacmm_calibrate_options_set_positions) have {} \
                     joints per row; the start arm has {joints}",
                    rows.joints()
                )));
            }
            Some(PositionInput::Arrays(rows)) => Some(*rows),
            Some(PositionInput::File(_)) => {
                return Err(Error::invalid(
                    "a positions file (aacmm_calibrate_options_set_positions_file) goes with \
                     aacmm_calibrate_files; give aacmm_calibrate positions as arrays \
                     (aacmm_calibrate_options_set_positions)",
                ));
            }
        };
        if o.spheres().is_some() {
            return Err(Error::invalid(
                "a sphere-surface file (aacmm_calibrate_options_set_spheres_file) goes with \
                 aacmm_calibrate_files",
            ));
        }
        let mut converted = ptr::try_vec("lengths_len", lengths.len())?;
        converted.extend(lengths.iter().map(ArrayLength::from));
        let lengths = converted;
        let data = match positions {
            Some(rows) if n == 0 && lengths.is_empty() => DataSet::from_positions(rows, ARRAYS)?,
            Some(rows) => {
                DataSet::from_arrays(joints, q, points, &lengths)?.with_positions(rows, ARRAYS)?
            }
            None => DataSet::from_arrays(joints, q, points, &lengths)?,
        };
        let sources = Sources {
            arm_file: start.source.clone(),
            data_file: ARRAYS.to_string(),
            lengths_file: (!lengths.is_empty()).then(|| ARRAYS.to_string()),
            // The arm's warnings, and the rows counted once (a point's
            // repeated row), which the report keeps.
            warnings: (start.warnings.iter().cloned())
                .chain(data.repeat_warnings().iter().map(ToString::to_string))
                .collect(),
        };
        let request = Request::new(start.arm.clone(), data).sources(sources);
        let result = run(options::request(&o, request), o.cancel())?;
        // SAFETY: checked writable above.
        unsafe { ptr::hand_out(out, result, "out") }
    })
}

/// About what a calibration of `touches` touches of a `joints`-joint arm
/// and `lengths` reference lengths allocates inside the library (the data
/// set, the Jacobian blocks, the report), where a failed allocation would
/// abort the host: the library's bound of the measured peak
/// ([`aacmm_core::memory::calibration_bytes`]), checked up front by
/// `aacmm_calibrate` before the arrays are copied (the library checks again
/// once the data set is built). A size past the address space is
/// `AACMM_STATUS_LENGTH`, naming the argument.
fn calibration_bytes(touches: usize, lengths: usize, joints: usize) -> Result<usize, Error> {
    let too_many = |name: &str, n: usize| {
        Error::length(format!("{name} = {n}: too many to calibrate in memory"))
    };
    match aacmm_core::memory::calibration_bytes(touches, lengths, joints) {
        b if b <= isize::MAX as usize => Ok(b),
        _ if lengths
            .checked_mul(aacmm_core::memory::WORK_BYTES_PER_LENGTH)
            .is_none() =>
        {
            Err(too_many("lengths_len", lengths))
        }
        _ => Err(too_many("points_len", touches)),
    }
}

/// The result behind `cal`.
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle.
pub(crate) unsafe fn result<'a>(
    cal: *const AacmmCalibration,
) -> Result<&'a AacmmCalibration, Error> {
    // SAFETY: forwarded contract.
    unsafe { ptr::object(cal, "cal") }
}

/// A count accessor's body: `of` the value behind the handle `handle`
/// (named `name` in messages) into `*count`, or `of`'s refusal of the
/// arguments.
///
/// # Safety
///
/// `handle` is `NULL` or a live handle of a `T`; `count` is `NULL` or
/// writable.
pub(crate) unsafe fn count_out<T>(
    (handle, name): (*const T, &str),
    count: *mut usize,
    of: impl FnOnce(&T) -> Result<usize, Error>,
) -> AacmmStatus {
    guard(|| {
        Args::new()
            .object(name, handle)
            .out("count", count)
            .disjoint()?;
        // SAFETY: forwarded contract.
        let n = of(unsafe { ptr::object(handle, name) }?)?;
        // SAFETY: forwarded contract.
        unsafe { ptr::write(count, n, "count") }
    })
}

/// A string accessor's body: the text `of` the value behind the handle
/// `handle` (named `name` in messages), or `of`'s refusal of the
/// arguments, copied into `buf` like `aacmm_last_error_message`, its full
/// length into `*len`.
///
/// # Safety
///
/// `handle` is `NULL` or a live handle of a `T`; `buf` is `NULL` or points
/// to `buf_len` writable bytes; `len` is `NULL` or writable.
pub(crate) unsafe fn text_out<T>(
    (handle, name): (*const T, &str),
    (buf, buf_len, len): (*mut c_char, usize, *mut usize),
    of: impl FnOnce(&T) -> Result<std::borrow::Cow<'_, str>, Error>,
) -> AacmmStatus {
    guard(|| {
        string_args(Args::new().object(name, handle), buf, buf_len, len)?;
        // SAFETY: forwarded contract.
        let text = of(unsafe { ptr::object(handle, name) }?)?;
        // SAFETY: forwarded contract.
        unsafe { string_out(&text, buf, buf_len, len) }
    })
}

/// Releases a calibration result. `NULL` is allowed (nothing happens).
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle, which must not be used
/// afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_free(cal: *mut AacmmCalibration) {
    // SAFETY: by the contract.
    guard_value((), || unsafe { ptr::release(cal) })
}

/// Copies one value per parameter into `out`, the caller's array `name`
/// whose length `len_name` must be `4·joints + 3` (messages name both as
/// the caller wrote them).
///
/// # Safety
///
/// As the accessors below.
unsafe fn per_parameter<T: Copy>(
    cal: *const AacmmCalibration,
    (name, len_name): (&str, &str),
    out: *mut T,
    len: usize,
    value: impl Fn(&AacmmCalibration, usize, ParamId) -> T,
) -> Result<(), Error> {
    (Args::new().object("cal", cal))
        .output(name, out, len)?
        .disjoint()?;
    // SAFETY: by the contract.
    let cal = unsafe { result(cal) }?;
    let count = cal.calibrated.params.param_count();
    if len != count {
        return Err(Error::length(format!(
            "{len_name} = {len}, expected {count} (4 · joints + 3)"
        )));
    }
    // SAFETY: by the contract.
    let out = unsafe { ptr::output(out, len, name) }?;
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
            per_parameter(
                cal,
                ("params", "params_len"),
                params,
                params_len,
                |c, _, id| c.calibrated.params.get(id),
            )
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
            per_parameter(cal, ("sigma", "sigma_len"), sigma, sigma_len, |c, i, _| {
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
            per_parameter(cal, ("fixed", "fixed_len"), fixed, fixed_len, |c, i, _| {
                c.report.calibration.parameters[i].fixed.is_some()
            })
        }
    })
}

/// The verdict, the solver's outcome and the fit's figures into
/// `*summary`.
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
        Args::new()
            .object("cal", cal)
            .out("summary", summary)
            .disjoint()?;
        // SAFETY: by the contract.
        let report = &unsafe { result(cal) }?.report;
        let c = &report.calibration;
        let value = AacmmCalibrationSummary {
            method: method_code(c.solver.method),
            termination: c.solver.stop.lm().into(),
            successful: report.verdict.usable,
            converged: c.solver.is_solution_usable(),
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
        Args::new().object("cal", cal).out("out", out).disjoint()?;
        // SAFETY: by the contract.
        unsafe { ptr::write(out, std::ptr::null_mut(), "out") }?;
        // SAFETY: by the contract.
        let c = unsafe { result(cal) }?;
        let arm = AacmmArm::new(c.calibrated.clone(), "<calibration>".into(), Vec::new())?;
        // SAFETY: checked writable above.
        unsafe { ptr::hand_out(out, arm, "out") }
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
    // SAFETY: by the contract.
    unsafe {
        text_out((cal, "cal"), (buf, buf_len, len), |c| {
            Ok(c.json.as_str().into())
        })
    }
}

/// `items` one per line, for a C caller to split at `\n`: an item's own
/// line breaks (none today) become spaces, so that lines and items stay
/// one to one.
fn lines(items: &[String]) -> String {
    let items: Vec<String> = items.iter().map(|s| s.replace('\n', " ")).collect();
    items.join("\n")
}

/// The library's verdict on the calibration: whether it is usable into
/// `*usable` (the summary's `successful`), and why not into `buf`: the
/// reasons, one per line (UTF-8; empty when usable), copied like
/// `aacmm_last_error_message`; `*len` gets the full length in bytes
/// without the NUL. The same reasons as the report's `verdict.reasons`
/// and the command line's `Verdict: NOT usable — …` (exiting non-zero),
/// in C's words: a remedy names the C setter (`…_set_robust`), not the
/// command line's flag. Each reason's kind: `aacmm_calibration_reason`.
///
/// Returns `AACMM_STATUS_BUFFER_TOO_SMALL` when the copy was truncated
/// (`buf` may be `NULL` with `buf_len` 0 to ask for the length; `*usable`
/// is written all the same).
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `usable` is `NULL` or
/// writable; `buf` is `NULL` or points to `buf_len` writable bytes; `len`
/// is `NULL` or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_verdict(
    cal: *const AacmmCalibration,
    usable: *mut bool,
    buf: *mut c_char,
    buf_len: usize,
    len: *mut usize,
) -> AacmmStatus {
    guard(|| {
        let args = Args::new().object("cal", cal).out("usable", usable);
        string_args(args, buf, buf_len, len)?;
        // SAFETY: by the contract.
        let verdict = &unsafe { result(cal) }?.report.verdict;
        // SAFETY: by the contract.
        unsafe { ptr::write(usable, verdict.usable, "usable") }?;
        // SAFETY: by the contract.
        unsafe {
            string_out(
                &lines(&verdict.words(Spelling::C).reasons),
                buf,
                buf_len,
                len,
            )
        }
    })
}

/// What a metrologist should know although the calibration may be usable
/// (a χ² outside its range, a poor fit accepted on request, data that
/// determine the arm weakly, a joint better modelled by Hayati's
/// parameters): the verdict's notes, one per line (empty when there are
/// none), in C's words, copied like `aacmm_calibration_verdict`'s reasons.
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `buf` is `NULL` or points to
/// `buf_len` writable bytes; `len` is `NULL` or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_verdict_notes(
    cal: *const AacmmCalibration,
    buf: *mut c_char,
    buf_len: usize,
    len: *mut usize,
) -> AacmmStatus {
    // SAFETY: by the contract.
    unsafe {
        text_out((cal, "cal"), (buf, buf_len, len), |c| {
            Ok(lines(&c.report.verdict.words(Spelling::C).notes).into())
        })
    }
}

/// The kind of a reason a calibration is refused
/// (`aacmm_calibration_reason`): one of the `AACMM_REASON_…` constants;
/// new kinds may be added.
pub type AacmmReasonKind = u32;

/// A kind the library added after this header (its text says it).
pub const AACMM_REASON_OTHER: AacmmReasonKind = 0;
/// Every joint reading looks like radians read as degrees.
pub const AACMM_REASON_RADIANS_AS_DEGREES: AacmmReasonKind = 1;
/// The data and the arm disagree (columns in another order, another
/// arm's data, another unit).
pub const AACMM_REASON_DATA_DISAGREE_WITH_ARM: AacmmReasonKind = 2;
/// A few outlying observations pull the fit (named by `file:line`).
pub const AACMM_REASON_OUTLIERS: AacmmReasonKind = 3;
/// The solver did not reach a confirmed minimum.
pub const AACMM_REASON_UNCONFIRMED: AacmmReasonKind = 4;
/// The calibrated arm is not the nominal arm's geometry.
pub const AACMM_REASON_NOT_NOMINAL_GEOMETRY: AacmmReasonKind = 5;
/// Parameters the data barely determine moved implausibly far.
pub const AACMM_REASON_UNDETERMINED: AacmmReasonKind = 6;
/// An auxiliary block's values are physically impossible.
pub const AACMM_REASON_IMPLAUSIBLE_BLOCKS: AacmmReasonKind = 7;
/// The χ² test refuses the fit.
pub const AACMM_REASON_CHI_SQUARE: AacmmReasonKind = 8;
/// The robust scale's test refuses the fit.
pub const AACMM_REASON_ROBUST_SCALE: AacmmReasonKind = 9;
/// Worse than the nominal at its own reference positions.
pub const AACMM_REASON_WORSE_AT_POSITIONS: AacmmReasonKind = 10;
/// Worse than the nominal on its own data.
pub const AACMM_REASON_WORSE_ON_DATA: AacmmReasonKind = 11;

/// The C code of `reason`'s kind.
fn reason_kind(reason: &Reason) -> AacmmReasonKind {
    match reason {
        Reason::RadiansAsDegrees { .. } => AACMM_REASON_RADIANS_AS_DEGREES,
        Reason::DataDisagreeWithArm { .. } => AACMM_REASON_DATA_DISAGREE_WITH_ARM,
        Reason::Outliers { .. } => AACMM_REASON_OUTLIERS,
        Reason::Unconfirmed { .. } => AACMM_REASON_UNCONFIRMED,
        Reason::NotNominalGeometry { .. } => AACMM_REASON_NOT_NOMINAL_GEOMETRY,
        Reason::Undetermined { .. } => AACMM_REASON_UNDETERMINED,
        Reason::ImplausibleBlocks { .. } => AACMM_REASON_IMPLAUSIBLE_BLOCKS,
        Reason::ChiSquare { .. } => AACMM_REASON_CHI_SQUARE,
        Reason::RobustScale { .. } => AACMM_REASON_ROBUST_SCALE,
        Reason::WorseAtPositions { .. } => AACMM_REASON_WORSE_AT_POSITIONS,
        Reason::WorseOnData { .. } => AACMM_REASON_WORSE_ON_DATA,
        _ => AACMM_REASON_OTHER,
    }
}

/// The number of reasons the calibration is refused (0 when usable) into
/// `*count`.
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `count` is `NULL` or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_reason_count(
    cal: *const AacmmCalibration,
    count: *mut usize,
) -> AacmmStatus {
    // SAFETY: by the contract.
    unsafe { count_out((cal, "cal"), count, |c| Ok(c.report.verdict.reasons.len())) }
}

/// Reason `index` (from 0, the first cause first) of a refused
/// calibration: its kind (`AACMM_REASON_…`) into `*kind`, and its sentence
/// in C's words (a remedy names the C setter) into `buf`, copied like
/// `aacmm_last_error_message`; `*len` gets the full length in bytes
/// without the NUL. `AACMM_STATUS_INVALID_ARGUMENT` for an index at or
/// beyond `aacmm_calibration_reason_count`.
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `kind` is `NULL` or writable;
/// `buf` is `NULL` or points to `buf_len` writable bytes; `len` is `NULL`
/// or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_reason(
    cal: *const AacmmCalibration,
    index: usize,
    kind: *mut AacmmReasonKind,
    buf: *mut c_char,
    buf_len: usize,
    len: *mut usize,
) -> AacmmStatus {
    guard(|| {
        let args = Args::new().object("cal", cal).out("kind", kind);
        string_args(args, buf, buf_len, len)?;
        // SAFETY: by the contract.
        let reasons = &unsafe { result(cal) }?.report.verdict.reasons;
        let reason = reasons.get(index).ok_or_else(|| {
            Error::invalid(format!(
                "index = {index}: the calibration has {} reason(s)",
                reasons.len()
            ))
        })?;
        // SAFETY: by the contract.
        unsafe { ptr::write(kind, reason_kind(reason), "kind") }?;
        let text = reason.describe(Spelling::C).replace('\n', " ");
        // SAFETY: by the contract.
        unsafe { string_out(&text, buf, buf_len, len) }
    })
}

/// The number of frames fitted with the arm (one per frame of the
/// reference positions; 0 without positions) into `*count`.
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `count` is `NULL` or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_frame_count(
    cal: *const AacmmCalibration,
    count: *mut usize,
) -> AacmmStatus {
    // SAFETY: by the contract.
    unsafe {
        count_out((cal, "cal"), count, |c| {
            Ok(c.report.calibration.frames().len())
        })
    }
}

/// Frame `index` (`0 ≤ index < aacmm_calibration_frame_count`, in order of
/// first appearance in the positions) into `*frame`, and its name (UTF-8)
/// into `buf`, copied like `aacmm_last_error_message`; `*len` gets the
/// name's full length in bytes without the NUL. Returns
/// `AACMM_STATUS_BUFFER_TOO_SMALL` when the name was truncated (`buf` may
/// be `NULL` with `buf_len` 0 to ask for the length; `*frame` is written
/// all the same), `AACMM_STATUS_INVALID_ARGUMENT` for an index out of
/// range.
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `frame` is `NULL` or points to
/// writable memory for the struct; `buf` is `NULL` or points to `buf_len`
/// writable bytes; `len` is `NULL` or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_frame(
    cal: *const AacmmCalibration,
    index: usize,
    frame: *mut AacmmFrame,
    buf: *mut c_char,
    buf_len: usize,
    len: *mut usize,
) -> AacmmStatus {
    guard(|| {
        let args = Args::new().object("cal", cal).out("frame", frame);
        string_args(args, buf, buf_len, len)?;
        // SAFETY: by the contract.
        let c = &unsafe { result(cal) }?.report.calibration;
        let values = c.frames();
        let records = c.frame_records();
        let (Some((_, x)), Some(record)) = (values.get(index), records.get(index)) else {
            return Err(Error::invalid(format!(
                "index = {index}: the calibration has {} frame(s)",
                values.len()
            )));
        };
        let rotation = Frame::rotation(x);
        // Each σ on its own (`frame_records` has all three or none): the
        // frame's columns `NAME.rx … NAME.tz`, in deg and mm.
        let sigma = |axis: &str| {
            let column = format!("{}.{axis}", record.name);
            (c.auxiliary.iter())
                .find(|a| a.name == column)
                .and_then(|a| a.sigma)
                .unwrap_or(f64::NAN)
        };
        let value = AacmmFrame {
            rotation_deg: record.rotation_deg,
            translation_mm: record.translation_mm,
            small_rotation_sigma_deg: ["rx", "ry", "rz"].map(sigma),
            translation_sigma_mm: ["tx", "ty", "tz"].map(sigma),
            rotation_matrix: std::array::from_fn(|m| rotation[(m / 3, m % 3)]),
        };
        // SAFETY: by the contract.
        unsafe { ptr::write(frame, value, "frame") }?;
        // SAFETY: by the contract.
        unsafe { string_out(&record.name, buf, buf_len, len) }
    })
}

/// The number of tool points fitted with the arm (each `[[tool]]` of the
/// arm file some reference position names: `aacmm_calibrate_options_set_position_tools`,
/// or a positions or sphere file's `tool` column; 0 when none does) into
/// `*count`.
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `count` is `NULL` or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_tool_count(
    cal: *const AacmmCalibration,
    count: *mut usize,
) -> AacmmStatus {
    // SAFETY: by the contract.
    unsafe {
        count_out((cal, "cal"), count, |c| {
            Ok(c.report.calibration.tool_estimates().len())
        })
    }
}

/// Tool `index` (`0 ≤ index < aacmm_calibration_tool_count`, in the
/// order of the report's auxiliary columns `tool.NAME.x` …) into `*tool`,
/// and its name (UTF-8, as the arm file's `[[tool]]`) into `buf`, copied
/// like `aacmm_last_error_message`; `*len` gets the name's full length in
/// bytes without the NUL. Returns `AACMM_STATUS_BUFFER_TOO_SMALL` when the
/// name was truncated (`buf` may be `NULL` with `buf_len` 0 to ask for the
/// length; `*tool` is written all the same), `AACMM_STATUS_INVALID_ARGUMENT`
/// for an index out of range.
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `tool` is `NULL` or points to
/// writable memory for the struct; `buf` is `NULL` or points to `buf_len`
/// writable bytes; `len` is `NULL` or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_tool(
    cal: *const AacmmCalibration,
    index: usize,
    tool: *mut AacmmTool,
    buf: *mut c_char,
    buf_len: usize,
    len: *mut usize,
) -> AacmmStatus {
    guard(|| {
        let args = Args::new().object("cal", cal).out("tool", tool);
        string_args(args, buf, buf_len, len)?;
        // SAFETY: by the contract.
        let tools = unsafe { result(cal) }?.report.calibration.tool_estimates();
        let count = tools.len();
        let Some((name, offset_mm, sigma)) = tools.into_iter().nth(index) else {
            return Err(Error::invalid(format!(
                "index = {index}: the calibration has {count} tool(s)"
            )));
        };
        let value = AacmmTool {
            offset_mm,
            sigma_mm: sigma.unwrap_or([f64::NAN; 3]),
        };
        // SAFETY: by the contract.
        unsafe { ptr::write(tool, value, "tool") }?;
        // SAFETY: by the contract.
        unsafe { string_out(&name, buf, buf_len, len) }
    })
}

/// The number of auxiliary columns fitted with the arm (0 without
/// corrections beyond geometry and without reference positions) into
/// `*count`: the corrections' columns first, then six per frame.
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `count` is `NULL` or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_auxiliary_count(
    cal: *const AacmmCalibration,
    count: *mut usize,
) -> AacmmStatus {
    // SAFETY: by the contract.
    unsafe {
        count_out((cal, "cal"), count, |c| {
            Ok(c.report.calibration.auxiliary.len())
        })
    }
}

/// Auxiliary column `index` (`0 ≤ index < aacmm_calibration_auxiliary_count`,
/// the order of the report's `calibration.auxiliary`) into `*column`, and
/// its name (UTF-8: `compliance2`, `harmonic5.sin1`, `thermal.cte`,
/// `drift.x`, `tracker.rx`, …) into `buf`, copied like
/// `aacmm_last_error_message`; `*len` gets the name's full length in bytes
/// without the NUL. Returns `AACMM_STATUS_BUFFER_TOO_SMALL` when the name
/// was truncated (`buf` may be `NULL` with `buf_len` 0 to ask for the
/// length; `*column` is written all the same),
/// `AACMM_STATUS_INVALID_ARGUMENT` for an index out of range. The physics
/// at the fit (masses, and every correction fitted or stated: rad/(N·m),
/// rad, 1/K, mm/h) is the report's `calibration.physics`.
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `column` is `NULL` or points
/// to writable memory for the struct; `buf` is `NULL` or points to
/// `buf_len` writable bytes; `len` is `NULL` or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_auxiliary(
    cal: *const AacmmCalibration,
    index: usize,
    column: *mut AacmmAuxiliary,
    buf: *mut c_char,
    buf_len: usize,
    len: *mut usize,
) -> AacmmStatus {
    guard(|| {
        let args = Args::new().object("cal", cal).out("column", column);
        string_args(args, buf, buf_len, len)?;
        // SAFETY: by the contract.
        let auxiliary = &unsafe { result(cal) }?.report.calibration.auxiliary;
        let Some(a) = auxiliary.get(index) else {
            return Err(Error::invalid(format!(
                "index = {index}: the calibration has {} auxiliary column(s)",
                auxiliary.len()
            )));
        };
        let value = AacmmAuxiliary {
            start: a.start,
            calibrated: a.calibrated,
            sigma: a.sigma.unwrap_or(f64::NAN),
            fixed: a.fixed.is_some(),
        };
        // SAFETY: by the contract.
        unsafe { ptr::write(column, value, "column") }?;
        // SAFETY: by the contract.
        unsafe { string_out(&a.name, buf, buf_len, len) }
    })
}
