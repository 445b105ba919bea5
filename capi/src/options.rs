//! The options of a calibration: an opaque builder with one setter per
//! option, so that an option added later changes no struct a compiled
//! caller allocated (the ABI stays), and each value is checked where it is
//! set. [`settings`] turns the options into the library's terms.

use std::ffi::c_char;
use std::path::PathBuf;

use aacmm_core::calibrate::{
    FixSpec, GlobalOptions, Loss, MAX_THREADS, Method, ModelOptions, Robust, SolverSettings,
    check_threads,
};
use aacmm_core::corrections::Beyond;
use aacmm_core::domain::Positions;
use aacmm_core::error::OptionError;
use aacmm_core::params::{MAX_JOINTS, supported_joints_text};
use aacmm_core::residuals::Noise;
use aacmm_core::session::Request;
use aacmm_core::tolerances::Tolerances;

use crate::error::{AacmmStatus, Error, guard, guard_value};
use crate::positions;
use crate::ptr::{self, Args};

/// A solver, for `aacmm_calibrate_options_set_method`: one of the
/// `AACMM_METHOD_…` constants.
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
pub(crate) fn method_code(m: Method) -> AacmmMethod {
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

/// Reference positions to fit with the arm (`--positions`).
#[derive(Clone, Debug)]
pub(crate) enum PositionInput {
    /// Rows copied from arrays (`aacmm_calibrate_options_set_positions`),
    /// checked.
    Arrays(Box<Positions>),
    /// A positions file (`aacmm_calibrate_options_set_positions_file`),
    /// read when calibrating.
    File(PathBuf),
}

/// Settings of a calibration: the command line's flags. Opaque; made with
/// the defaults of `aacmm calibrate` by `aacmm_calibrate_options_new`,
/// changed by its setters (`aacmm_calibrate_options_set_method` and the
/// others of that prefix, one per option), released by
/// `aacmm_calibrate_options_free`. The calibration functions only read it:
/// one options object may serve several calibrations, also at once on
/// several threads, as long as no setter runs on it meanwhile.
#[derive(Clone, Debug)]
pub struct AacmmCalibrateOptions {
    method: Method,
    /// `--fix` as given; `None`: `auto`.
    fix: Option<String>,
    seed: u64,
    /// 0: none.
    cross_validate: usize,
    noise: Noise,
    /// 0: one per core.
    threads: usize,
    robust: Option<Robust>,
    /// `--prior` as given; `None`: the arm file's `[prior]`.
    prior: Option<String>,
    accept_poor_fit: bool,
    /// `--compliance` as given; `None`: none.
    compliance: Option<String>,
    /// `--harmonics` as given; `None`: none.
    harmonics: Option<String>,
    /// `--backlash` as given; `None`: none.
    backlash: Option<String>,
    /// `--thermal`.
    thermal: bool,
    /// `--drift`.
    drift: bool,
    /// `--positions`; `None`: no reference positions.
    positions: Option<PositionInput>,
    /// `--spheres`: a sphere-surface file; `None`: none.
    spheres: Option<std::path::PathBuf>,
    /// `--sphere-diameter`, mm; `None`: fitted per sphere.
    sphere_diameter_mm: Option<f64>,
    /// The token that stops its calibrations (Ctrl-C's, for the CLI).
    cancel: Option<aacmm_core::calibrate::Cancel>,
    /// `--global-starts`: the global search's random starts.
    global_starts: usize,
}

impl AacmmCalibrateOptions {
    /// The reference positions, if any were set, taken out of these
    /// options (a copy [`read`] made: the caller's stay).
    pub(crate) fn take_positions(&mut self) -> Option<PositionInput> {
        self.positions.take()
    }

    /// The sphere-surface file, if one was set.
    pub(crate) fn spheres(&self) -> Option<&std::path::Path> {
        self.spheres.as_deref()
    }

    /// The token that stops its calibrations, if one was set.
    pub(crate) fn cancel(&self) -> Option<&aacmm_core::calibrate::Cancel> {
        self.cancel.as_ref()
    }

    /// Sets (or clears) the token that stops its calibrations.
    pub(crate) fn set_cancel(&mut self, token: Option<aacmm_core::calibrate::Cancel>) {
        self.cancel = token;
    }
}

impl Default for AacmmCalibrateOptions {
    /// The command line's defaults (the library's, which are the same).
    fn default() -> Self {
        let model = ModelOptions::default();
        AacmmCalibrateOptions {
            method: SolverSettings::default().method,
            fix: None,
            seed: 0,
            cross_validate: 0,
            noise: model.noise,
            threads: 0,
            robust: None,
            prior: None,
            accept_poor_fit: model.accept_poor_fit,
            compliance: None,
            harmonics: None,
            backlash: None,
            thermal: model.beyond.thermal,
            drift: model.beyond.drift,
            positions: None,
            spheres: None,
            sphere_diameter_mm: None,
            cancel: None,
            global_starts: GlobalOptions::default().max_starts,
        }
    }
}

/// `request` with the options of `o`: the library's request path turns
/// them into the problem and the run's settings (the prior over the arm
/// file's `[prior]`, the fixed set and the loss by name, every check and
/// warning), as it does the command line's flags and Python's arguments.
pub(crate) fn request(o: &AacmmCalibrateOptions, request: Request) -> Request {
    let threads = (o.threads != 0).then_some(o.threads);
    let folds = (o.cross_validate != 0).then_some(o.cross_validate);
    request
        .fix(o.fix.as_deref().unwrap_or("auto"))
        .noise(o.noise)
        .robust(o.robust.map(|r| r.loss.name()), o.robust.map(|r| r.scale_k))
        .prior(o.prior.as_deref())
        .accept_poor_fit(o.accept_poor_fit)
        .beyond(
            o.compliance.as_deref(),
            o.harmonics.as_deref(),
            o.thermal,
            o.drift,
        )
        .backlash(o.backlash.as_deref())
        .method(o.method.name())
        .threads(threads)
        .seed(o.seed)
        .cross_validate(folds)
        .sphere_diameter(o.sphere_diameter_mm)
        .global(GlobalOptions::default().max_starts(o.global_starts))
}

/// The options behind `options`, or the defaults for `NULL`.
///
/// # Safety
///
/// `options` is `NULL` or a live options handle that no setter changes
/// meanwhile.
pub(crate) unsafe fn read(
    options: *const AacmmCalibrateOptions,
) -> Result<AacmmCalibrateOptions, Error> {
    if options.is_null() {
        return Ok(AacmmCalibrateOptions::default());
    }
    // SAFETY: forwarded contract.
    Ok(unsafe { ptr::object(options, "options") }?.clone())
}

/// The builder behind `options`, for a setter given the string `s`
/// (named `name`): refused (`AACMM_STATUS_INVALID_ARGUMENT`) when the
/// string lies in the builder's memory, which the setter writes.
///
/// # Safety
///
/// `options` is `NULL` or a live options handle that nothing else uses
/// meanwhile; `s` is `NULL` or a NUL-terminated string.
unsafe fn builder_with_text<'a>(
    options: *mut AacmmCalibrateOptions,
    s: *const c_char,
    name: &str,
) -> Result<&'a mut AacmmCalibrateOptions, Error> {
    // SAFETY: `s` is NULL or NUL-terminated, by the contract.
    unsafe { Args::new().c_str(name, s) }
        .out("options", options)
        .disjoint()?;
    // SAFETY: by the contract.
    unsafe { ptr::object_mut(options, "options") }
}

/// The text option `name` as given, checked as UTF-8.
///
/// # Safety
///
/// `s` is `NULL` or a NUL-terminated string.
unsafe fn text(s: *const c_char, name: &str) -> Result<Option<String>, Error> {
    if s.is_null() {
        return Ok(None);
    }
    // SAFETY: non-null, so NUL-terminated by the contract.
    let s = unsafe { ptr::c_str(s, name) }?;
    let s = s
        .to_str()
        .map_err(|_| Error::invalid(format!("{name} is not valid UTF-8")))?;
    Ok(Some(s.to_string()))
}

/// Whether `parse` accepts the text for an arm of some joint count the
/// toolkit has kernels for: what can be checked before the arm is known.
/// The error is the one for the largest count (its names are a superset).
fn for_some_arm<T>(parse: impl Fn(usize) -> Result<T, OptionError>) -> Result<(), Error> {
    let largest = parse(MAX_JOINTS);
    if largest.is_ok() || (1..MAX_JOINTS).rev().any(|n| parse(n).is_ok()) {
        return Ok(());
    }
    largest.map(|_| ()).map_err(Error::from)
}

/// Refuses a joint (0-based, of a model beyond geometry set as `field`)
/// that no arm the toolkit has kernels for has: what can be checked before
/// the arm is known (the arm at hand's count is checked when calibrating).
fn on_some_arm(field: &str, joints: impl IntoIterator<Item = usize>) -> Result<(), Error> {
    match joints.into_iter().find(|&j| j >= MAX_JOINTS) {
        Some(j) => Err(Error::invalid(format!(
            "{field} = {}: joint {}: the toolkit computes {}",
            j + 1,
            j + 1,
            supported_joints_text()
        ))),
        None => Ok(()),
    }
}

/// New options with the defaults of `aacmm calibrate`, at `*out` (release
/// them with `aacmm_calibrate_options_free`). Passing `NULL` options to a
/// calibration means these defaults too.
///
/// Errors: `AACMM_STATUS_NULL_POINTER` (`out`).
///
/// # Safety
///
/// `out` is `NULL` or points to writable memory for one pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_new(
    out: *mut *mut AacmmCalibrateOptions,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        unsafe { ptr::hand_out(out, AacmmCalibrateOptions::default(), "out") }
    })
}

/// Releases options. `NULL` is allowed (nothing happens).
///
/// # Safety
///
/// `options` is `NULL` or a live options handle, which must not be used
/// afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_free(options: *mut AacmmCalibrateOptions) {
    // SAFETY: by the contract.
    guard_value((), || unsafe { ptr::release(options) })
}

/// The solver: `AACMM_METHOD_GLOBAL` (default), `_LM`, `_SA` or `_HYBRID`
/// (`--method`).
///
/// Errors (for every setter): `AACMM_STATUS_NULL_POINTER` (`options`),
/// `AACMM_STATUS_INVALID_ARGUMENT` for a value out of range; the message
/// names the option (`method = 7: …`) and the options keep their earlier
/// value.
///
/// # Safety
///
/// `options` is `NULL` or a live options handle that no other thread uses
/// during the call (the same for every setter).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_method(
    options: *mut AacmmCalibrateOptions,
    method: AacmmMethod,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        o.method = self::method(method).ok_or_else(|| {
            Error::invalid(format!(
                "method = {method}: one of AACMM_METHOD_LM ({AACMM_METHOD_LM}), _SA \
                     ({AACMM_METHOD_SA}), _HYBRID ({AACMM_METHOD_HYBRID}), _GLOBAL \
                     ({AACMM_METHOD_GLOBAL})"
            ))
        })?;
        Ok(())
    })
}

/// Parameters held at their start values (`--fix`): `NULL` or `"auto"`
/// (the recommended set of the identifiability analysis; default), or
/// comma-separated names in the order's spelling, e.g.
/// `"theta1,d1,theta6,alpha6,Bx,By"` (`beta…` is accepted for `alpha…`,
/// `hbeta…` names a Hayati joint's d-slot). Copied; names that no arm has
/// are refused here, names the arm at hand lacks when calibrating.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`; `fix` is `NULL` or a
/// NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_fix(
    options: *mut AacmmCalibrateOptions,
    fix: *const c_char,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { builder_with_text(options, fix, "fix") }?;
        // SAFETY: by the contract.
        let fix = unsafe { text(fix, "fix") }?;
        if let Some(f) = &fix {
            for_some_arm(|n| FixSpec::parse(f, n))?;
        }
        o.fix = fix;
        Ok(())
    })
}

/// Seed of every random draw: the solvers' moves and starts, the
/// cross-validation folds (`--seed`; default 0).
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_seed(
    options: *mut AacmmCalibrateOptions,
    seed: u64,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        o.seed = seed;
        Ok(())
    })
}

/// Most random starts of the global search (`--global-starts`; default
/// 100), ≥ 1: more when a refused calibration's reason says its search
/// did not confirm a minimum.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_global_starts(
    options: *mut AacmmCalibrateOptions,
    starts: usize,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        if starts == 0 {
            return Err(Error::invalid("global_starts = 0: at least 1"));
        }
        o.global_starts = starts;
        Ok(())
    })
}

/// `k`-fold cross-validation over points for the report
/// (`--cross-validate`): 0 = none (the default), otherwise 2 or more (and
/// at most the number of points, checked when calibrating).
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_cross_validate(
    options: *mut AacmmCalibrateOptions,
    k: usize,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        if k == 1 {
            return Err(Error::invalid(
                "cross_validate = 1: 0 (none) or 2 or more folds",
            ));
        }
        o.cross_validate = k;
        Ok(())
    })
}

/// Sets one noise figure on a copy of `o`'s and keeps it if the library
/// accepts it (its refusal names the C option: see `crate::error`).
fn set_noise(o: &mut AacmmCalibrateOptions, change: impl FnOnce(&mut Noise)) -> Result<(), Error> {
    let mut noise = o.noise;
    change(&mut noise);
    noise.check()?;
    o.noise = noise;
    Ok(())
}

/// σ of each encoder reading, rad (`--encoder-noise`, which is in
/// degrees); 0 = not stated (the default). With the probe noise these
/// weigh the touches; when neither is stated the touch σ is estimated from
/// the fit. Finite and ≥ 0.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_encoder_noise_rad(
    options: *mut AacmmCalibrateOptions,
    sigma: f64,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        set_noise(o, |n| n.encoder_rad = stated(sigma))
    })
}

/// σ of the probe seating per axis, mm (`--probe-noise`); 0 = not stated
/// (the default). Finite and ≥ 0.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_probe_noise_mm(
    options: *mut AacmmCalibrateOptions,
    sigma: f64,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        set_noise(o, |n| n.probe_mm = stated(sigma))
    })
}

/// σ of a reference length that states none, mm (`--length-uncertainty`;
/// default 0.001). Finite and ≥ 0.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_length_uncertainty_mm(
    options: *mut AacmmCalibrateOptions,
    sigma: f64,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        set_noise(o, |n| n.length_default_mm = sigma)
    })
}

/// Weight of every reference-length residual, 1/mm, overriding the
/// uncertainties (`--length-weight`); 0 = none (the default). Finite and
/// ≥ 0.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_length_weight(
    options: *mut AacmmCalibrateOptions,
    weight: f64,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        set_noise(o, |n| n.length_weight = stated(weight))
    })
}

/// σ per coordinate of a reference position whose uncertainty is not
/// stated (`NAN` in `aacmm_calibrate_options_set_positions`, an empty cell
/// in a positions file), as an instrument's specification gives it:
/// `a_mm + b_mm_per_m · distance`, the distance from the instrument in
/// metres (`--position-noise A+B/m`; a laser tracker's 0.015 mm +
/// 0.006 mm/m). `a_mm` finite and > 0, or 0 = not stated (the default: the
/// position σ is then estimated from the fit); `b_mm_per_m` finite and
/// ≥ 0 (0: σ does not grow with the distance), and 0 when `a_mm` is.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_position_noise_mm(
    options: *mut AacmmCalibrateOptions,
    a_mm: f64,
    b_mm_per_m: f64,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        set_noise(o, |n| {
            n.position_mm = stated(a_mm);
            n.position_mm_per_m = stated(b_mm_per_m);
        })
    })
}

/// σ per axis of a tool orientation seen (the `qw,qx,qy,qz` columns of a
/// positions file: a 6-D target's orientation), rad, as the encoder's
/// (`--orientation-noise`, which is in degrees; a tracker's about 0.01°).
/// Finite and > 0, or
/// 0 = not stated (the default: a positions file with orientations is then
/// refused when calibrating, naming its first oriented row).
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_orientation_noise_rad(
    options: *mut AacmmCalibrateOptions,
    rad: f64,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        set_noise(o, |n| n.orientation_rad = stated(rad))
    })
}

/// 0 = not stated; anything else is left to the library's check (which
/// refuses negative and non-finite values).
pub(crate) fn stated(v: f64) -> Option<f64> {
    (v != 0.0).then_some(v)
}

// The bound the setter's documentation (and so the header) states.
const _: () = assert!(MAX_THREADS == 1024);

/// Worker threads for the normal equations (`--threads`); 0 = one per
/// core (the default), otherwise at most 1024 (`AACMM_STATUS_INVALID_ARGUMENT`
/// above, the options unchanged). The results do not depend on it.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_threads(
    options: *mut AacmmCalibrateOptions,
    threads: usize,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        if threads != 0 {
            check_threads(threads)?;
        }
        o.threads = threads;
        Ok(())
    })
}

/// A robust refit after the solver (IRLS; per-touch weights in the
/// report's `/calibration/robust`; `--robust`, `--robust-scale`): `loss`
/// `AACMM_ROBUST_NONE` (the default), `_HUBER` or `_CAUCHY`, and its tuning
/// constant `scale` (> 0; 0 = the loss's default: 1.62 Huber, 2.65 Cauchy;
/// ignored with `_NONE`).
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_robust(
    options: *mut AacmmCalibrateOptions,
    loss: AacmmRobust,
    scale: f64,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        let loss = match loss {
            AACMM_ROBUST_NONE => None,
            AACMM_ROBUST_HUBER => Some(Loss::Huber),
            AACMM_ROBUST_CAUCHY => Some(Loss::Cauchy),
            other => {
                return Err(Error::invalid(format!(
                    "robust = {other}: one of AACMM_ROBUST_NONE ({AACMM_ROBUST_NONE}), \
                         _HUBER ({AACMM_ROBUST_HUBER}), _CAUCHY ({AACMM_ROBUST_CAUCHY})"
                )));
            }
        };
        let robust = loss.map(|loss| Robust {
            loss,
            scale_k: if scale == 0.0 {
                loss.default_k()
            } else {
                scale
            },
        });
        if let Some(r) = &robust {
            r.check()?;
        }
        o.robust = robust;
        Ok(())
    })
}

/// Stated tolerances of the start arm: a prior, as the command line's
/// `--prior`. `NULL` (the default): the arm file's `[prior]` table, if
/// any; `"none"`: no prior, whatever the file says; otherwise
/// comma-separated `TARGET=VALUEUNIT`, e.g.
/// `"length=0.5mm,angle=0.1deg,theta5=0.05deg"` (targets `length`,
/// `angle`, `a`, `d`, `alpha`, `theta`, `probe` or a parameter; units `mm`,
/// `m`, `deg`, `rad`), each replacing or adding to the file's entry for
/// its target. Copied; the syntax and values are checked here, the
/// parameters against the arm when calibrating.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`; `prior` is `NULL` or a
/// NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_prior(
    options: *mut AacmmCalibrateOptions,
    prior: *const c_char,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { builder_with_text(options, prior, "prior") }?;
        // SAFETY: by the contract.
        let prior = unsafe { text(prior, "prior") }?;
        if let Some(p) = &prior {
            for_some_arm(|n| Tolerances::parse(p, n))?;
        }
        o.prior = prior;
        Ok(())
    })
}

/// Whether a poor fit may be called usable (`--accept-poor-fit`; default
/// `false`): a χ² far outside the stated noise, or a calibrated arm worse
/// than the nominal on its own data, then becomes a note of the verdict
/// instead of a reason to refuse it. A mirror-image or collapsed arm, or a
/// solver that did not converge, is refused all the same.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_accept_poor_fit(
    options: *mut AacmmCalibrateOptions,
    accept: bool,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        o.accept_poor_fit = accept;
        Ok(())
    })
}

/// Joint compliance under gravity, fitted for the listed joints
/// (`--compliance`): comma-separated joints numbered from 1, e.g. `"2,3"`;
/// each joint deflects by its compliance times the gravity torque of the
/// masses outboard of it, from the arm file's `mass_kg` (links and
/// `[probe]`) and `gravity`. `NULL` (the default): none. Copied; the
/// syntax and joints no arm has are refused here (`compliance = 0: a joint
/// is a number from 1 …`), a joint the arm at hand lacks, or an arm file
/// without masses, when calibrating. The fitted compliances are the
/// auxiliary columns `compliance2`, … (µrad/(N·m);
/// `aacmm_calibration_auxiliary`), and in the report's
/// `calibration.physics`.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`; `joints` is `NULL` or a
/// NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_compliance(
    options: *mut AacmmCalibrateOptions,
    joints: *const c_char,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { builder_with_text(options, joints, "compliance") }?;
        // SAFETY: by the contract.
        let joints = unsafe { text(joints, "compliance") }?;
        if let Some(j) = &joints {
            on_some_arm("compliance", Beyond::parse_compliance(j)?)?;
        }
        o.compliance = joints;
        Ok(())
    })
}

/// Encoder harmonics `s·sin(k q) + c·cos(k q)` added to the listed joints'
/// readings, fitted (`--harmonics`): comma-separated `JOINT:ORDERS`, joints
/// numbered from 1, orders a number or a range from 1 to 16, e.g.
/// `"2:1,5:1-2"` (order 1 is the disc's eccentricity). `NULL` (the
/// default): none. Copied; the syntax and joints no arm has are refused
/// here (`harmonics = 2:: an order is a whole number …`), a joint the arm
/// at hand lacks when calibrating. The fitted amplitudes are the auxiliary
/// columns `harmonic2.sin1`, `harmonic2.cos1`, … (deg;
/// `aacmm_calibration_auxiliary`).
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`; `spec` is `NULL` or a
/// NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_harmonics(
    options: *mut AacmmCalibrateOptions,
    spec: *const c_char,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { builder_with_text(options, spec, "harmonics") }?;
        // SAFETY: by the contract.
        let spec = unsafe { text(spec, "harmonics") }?;
        if let Some(s) = &spec {
            let harmonics = Beyond::parse_harmonics(s)?;
            on_some_arm("harmonics", harmonics.iter().map(|&(j, _)| j))?;
        }
        o.harmonics = spec;
        Ok(())
    })
}

/// Backlash, fitted for the listed joints (`--backlash`): comma-separated
/// joints numbered from 1, e.g. `"2,3"`; each joint reads off by a
/// half-play `b` on the gear flank that the gravity torque of the arm
/// file's masses (`mass_kg` of the links and `[probe]`, `gravity`)
/// presses: `q + b·sgn τ`. `NULL` (the default): none. Copied; the syntax
/// and joints no arm has are refused here (`backlash = 0: a joint is a
/// number from 1 …`), a joint the arm at hand lacks, or an arm file
/// without masses, when calibrating. A joint whose torque keeps one sign
/// over every pose cannot tell its play from its zero offset: its column
/// is held, with why. The fitted plays are the auxiliary columns
/// `backlash2`, … (deg, mm for a prismatic joint;
/// `aacmm_calibration_auxiliary`), and in the report's
/// `calibration.physics`.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`; `joints` is `NULL` or a
/// NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_backlash(
    options: *mut AacmmCalibrateOptions,
    joints: *const c_char,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { builder_with_text(options, joints, "backlash") }?;
        // SAFETY: by the contract.
        let joints = unsafe { text(joints, "backlash") }?;
        if let Some(j) = &joints {
            on_some_arm("backlash", Beyond::parse_backlash(j)?)?;
        }
        o.backlash = joints;
        Ok(())
    })
}

/// Whether a thermal expansion coefficient of the lengths is fitted
/// (`--thermal`; default `false`) against the temperature (°C) of every
/// pose: the `temperature` column of the poses and positions files of
/// `aacmm_calibrate_files` (the calibrated lengths are at 20 °C; arrays
/// carry no temperatures). Data without temperatures are refused when
/// calibrating (`thermal = on: … needs the temperature of every pose …`). The fitted coefficient is the auxiliary column `thermal.cte`
/// (ppm/K; `aacmm_calibration_auxiliary`).
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_thermal(
    options: *mut AacmmCalibrateOptions,
    thermal: bool,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        o.thermal = thermal;
        Ok(())
    })
}

/// Whether a linear drift of the arm's base against the instrument is
/// fitted (`--drift`; default `false`) against the time (s) of every pose:
/// the `time` column of the poses and positions files of
/// `aacmm_calibrate_files` (arrays carry no times). Data without times are
/// refused when calibrating (`drift = on: … needs the time of every
/// pose …`). The fitted drift is the auxiliary columns `drift.x`,
/// `drift.y`, `drift.z` (mm/h; `aacmm_calibration_auxiliary`).
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_drift(
    options: *mut AacmmCalibrateOptions,
    drift: bool,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        o.drift = drift;
        Ok(())
    })
}

/// Reference positions an instrument saw, fitted with the arm as the
/// command line's `--positions` file is (copied; they replace positions set
/// before, also a file). Row `i` of `n = q_len / joints` rows holds the
/// readings `q[i·joints ..]` (rad, a prismatic joint's mm: row-major as in
/// `aacmm_positions`) of a
/// pose, and `xyz[3·i ..]`, where the instrument saw the probe: x, y, z in
/// mm in the instrument's own frame. Each frame (a station of a tracker,
/// a placement of an artefact) gets its own unknown rigid registration,
/// fitted with the arm (`aacmm_calibration_frame`): `frames[i]` is row
/// `i`'s frame, an index into the `frame_names` (`frames_len` = `n`;
/// every name used); without `frames` (`frames_len` = 0) every row is in
/// one frame, named `frame_names[0]` if `frame_names_len` is 1, else
/// `"instrument"`. `uncertainty[i]` is row `i`'s standard uncertainty per
/// coordinate, mm, > 0, or `NAN` for not stated, when the options'
/// position noise applies (`aacmm_calibrate_options_set_position_noise_mm`);
/// `uncertainty_len` = 0 states none. Each row is its own point, named
/// `P1`, `P2`, … in file order by the report.
///
/// With positions, `aacmm_calibrate` fits them with its touches, or alone
/// when it has none (`q_len` = 0 there); `aacmm_calibrate_files` takes a
/// positions file instead (`aacmm_calibrate_options_set_positions_file`)
/// and refuses these. Every array length 0 removes the positions (the
/// default: none).
///
/// Errors: `AACMM_STATUS_NULL_POINTER` (`options`, or an array or a frame
/// name that is `NULL`), `AACMM_STATUS_UNSUPPORTED` (`joints` not 1
/// to 12), `AACMM_STATUS_LENGTH` (a length that does not match `n`),
/// `AACMM_STATUS_INVALID_ARGUMENT` (a frame name that is not UTF-8),
/// `AACMM_STATUS_INPUT` — the message names the array and index — for a
/// reading or position that is not a finite number, an uncertainty that is
/// neither `NAN` nor > 0, a frame index out of range, a frame name empty,
/// given twice or unused, and a frame with fewer than 3 distinct positions
/// or all of them on one line (its registration would not be determined).
/// On error the options keep their earlier positions.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`; each array is `NULL` or points
/// to its stated length of values (it may be `NULL` when its length is 0);
/// each of the `frame_names_len` names is `NULL` or a NUL-terminated
/// string.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_positions(
    options: *mut AacmmCalibrateOptions,
    joints: usize,
    q: *const f64,
    q_len: usize,
    xyz: *const f64,
    xyz_len: usize,
    frames: *const u32,
    frames_len: usize,
    frame_names: *const *const c_char,
    frame_names_len: usize,
    uncertainty: *const f64,
    uncertainty_len: usize,
) -> AacmmStatus {
    guard(|| {
        (Args::new().out("options", options))
            .input("q", q, q_len)?
            .input("xyz", xyz, xyz_len)?
            .input("frames", frames, frames_len)?
            .input("frame_names", frame_names, frame_names_len)?
            .input("uncertainty", uncertainty, uncertainty_len)?
            .disjoint()?;
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        let lengths = positions::Lengths {
            joints,
            q: q_len,
            xyz: xyz_len,
            frames: frames_len,
            frame_names: frame_names_len,
            uncertainty: uncertainty_len,
        };
        if lengths.none() {
            o.positions = None;
            return Ok(());
        }
        lengths.rows()?;
        // SAFETY: by the contract.
        let (q, xyz, frames, names, uncertainty) = unsafe {
            (
                ptr::input(q, q_len, "q")?,
                ptr::input(xyz, xyz_len, "xyz")?,
                ptr::input(frames, frames_len, "frames")?,
                ptr::input(frame_names, frame_names_len, "frame_names")?,
                ptr::input(uncertainty, uncertainty_len, "uncertainty")?,
            )
        };
        // SAFETY: each name is NULL or NUL-terminated, by the contract.
        let names = unsafe { positions::frame_names(names) }?;
        let rows = positions::rows(joints, q, xyz, frames, &names, uncertainty)?;
        o.positions = Some(PositionInput::Arrays(Box::new(rows)));
        Ok(())
    })
}

/// The tool's orientation seen at the reference positions set by
/// `aacmm_calibrate_options_set_positions` (a 6-D target's, as a positions
/// file's `qw,qx,qy,qz` columns): `quaternions[4·i ..]` is row `i`'s unit
/// quaternion `w, x, y, z` (scalar first; the target's frame in the row's
/// frame), or four `NAN` for a row without one (a target that lost its
/// lock); `quaternions_len` = 4·n for the n rows set, or 0 to remove them.
/// Weighed by the orientation noise
/// (`aacmm_calibrate_options_set_orientation_noise_rad`, required when
/// calibrating), with the target's mount on the flange fitted
/// (`mount.rx` … in the calibration's auxiliary columns). Setting the
/// positions again removes them.
///
/// Errors: `AACMM_STATUS_NULL_POINTER` (`options`, or `quaternions` with a
/// length), `AACMM_STATUS_INVALID_ARGUMENT` (no positions set as arrays),
/// `AACMM_STATUS_LENGTH` (a length other than 0 or 4·n),
/// `AACMM_STATUS_INPUT` — naming the array and index — for a value that is
/// not finite in a row not all `NAN`, and a quaternion whose length is not
/// 1 within 1e-6. On error the options keep their earlier orientations.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`; `quaternions` is `NULL` or
/// points to `quaternions_len` values (it may be `NULL` when that is 0).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_position_orientations(
    options: *mut AacmmCalibrateOptions,
    quaternions: *const f64,
    quaternions_len: usize,
) -> AacmmStatus {
    guard(|| {
        (Args::new().out("options", options))
            .input("quaternions", quaternions, quaternions_len)?
            .disjoint()?;
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        let Some(PositionInput::Arrays(rows)) = &mut o.positions else {
            return Err(Error::invalid(
                "no positions set as arrays: set them first \
                 (aacmm_calibrate_options_set_positions)",
            ));
        };
        // SAFETY: by the contract.
        let q = unsafe { ptr::input(quaternions, quaternions_len, "quaternions") }?;
        let orientations = positions::orientations(q, rows.len())?;
        **rows = (**rows).clone().with_orientations(orientations);
        Ok(())
    })
}

/// The tool point seen at each reference position set by
/// `aacmm_calibrate_options_set_positions` (a positions file's `tool`
/// column): `tools[i]` is row `i`'s tool, 0 for the arm's `[probe]`, `k`
/// for `tool_names[k - 1]` — a `[[tool]]` of the arm file, whose offset is
/// fitted with the arm (`aacmm_calibration_tool`); `tools_len` = n for the
/// n rows set, or 0 (with `tool_names_len` 0) for every row the probe.
/// Setting the positions again removes them.
///
/// Errors: `AACMM_STATUS_NULL_POINTER` (`options`, or an array or a name
/// that is `NULL`), `AACMM_STATUS_INVALID_ARGUMENT` (no positions set as
/// arrays, a name that is not UTF-8), `AACMM_STATUS_LENGTH` (`tools_len`
/// other than 0 or n), `AACMM_STATUS_INPUT` — naming the array and index —
/// for an index beyond `tool_names_len`, a name empty, given twice or
/// unused. A name the arm file does not list is refused when calibrating,
/// as a file's (`<arrays>:ROW: field \`tool\``). On error the options keep
/// their earlier tools.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`; each array is `NULL` or points
/// to its stated length of values (it may be `NULL` when its length is 0);
/// each of the `tool_names_len` names is `NULL` or a NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_position_tools(
    options: *mut AacmmCalibrateOptions,
    tools: *const u32,
    tools_len: usize,
    tool_names: *const *const c_char,
    tool_names_len: usize,
) -> AacmmStatus {
    guard(|| {
        (Args::new().out("options", options))
            .input("tools", tools, tools_len)?
            .input("tool_names", tool_names, tool_names_len)?
            .disjoint()?;
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        let Some(PositionInput::Arrays(rows)) = &mut o.positions else {
            return Err(Error::invalid(
                "no positions set as arrays: set them first \
                 (aacmm_calibrate_options_set_positions)",
            ));
        };
        // SAFETY: by the contract.
        let (of, names) = unsafe {
            (
                ptr::input(tools, tools_len, "tools")?,
                ptr::input(tool_names, tool_names_len, "tool_names")?,
            )
        };
        // SAFETY: each name is NULL or NUL-terminated, by the contract.
        let names = unsafe { positions::tool_names(names) }?;
        **rows = positions::with_tools((**rows).clone(), of, &names)?;
        Ok(())
    })
}

/// A reference-positions file (`--positions`: CSV
/// `point,q1,…,qn,x,y,z[,frame][,uncertainty]`, the readings in the unit
/// `aacmm_calibrate_files` is given for the poses file), fitted with the
/// arm; `NULL` removes the positions (the default: none). The path is
/// copied, the file read when calibrating; it replaces positions set
/// before, also arrays. With a positions file `aacmm_calibrate_files` may
/// be given no poses file (`poses_path` `NULL`): a calibration on the
/// positions alone. `aacmm_calibrate` takes arrays instead
/// (`aacmm_calibrate_options_set_positions`) and refuses a file.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`; `path` is `NULL` or a
/// NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_positions_file(
    options: *mut AacmmCalibrateOptions,
    path: *const c_char,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { builder_with_text(options, path, "path") }?;
        o.positions = match path.is_null() {
            true => None,
            // SAFETY: by the contract.
            false => Some(PositionInput::File(unsafe { ptr::path(path, "path") }?)),
        };
        Ok(())
    })
}

/// A sphere-surface file (`--spheres`: CSV `sphere,q1,…,qn[,articulation]`,
/// the readings in the unit `aacmm_calibrate_files` is given for the poses
/// file): points probed on reference spheres, fitted with the arm, each
/// sphere's centre (and diameter, unless
/// `aacmm_calibrate_options_set_sphere_diameter_mm` states it) fitted with
/// it; `NULL` removes it (the default: none). The path is copied, the file
/// read when calibrating by `aacmm_calibrate_files`, which may then be
/// given no poses file (`poses_path` `NULL`): a calibration on the spheres
/// alone (or with a positions file). With cross-validation each sphere's
/// points are dealt to the folds. `aacmm_calibrate` refuses it.
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`; `path` is `NULL` or a
/// NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_spheres_file(
    options: *mut AacmmCalibrateOptions,
    path: *const c_char,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { builder_with_text(options, path, "path") }?;
        o.spheres = match path.is_null() {
            true => None,
            // SAFETY: by the contract.
            false => Some(unsafe { ptr::path(path, "path") }?),
        };
        Ok(())
    })
}

/// The reference spheres' diameter, mm (`--sphere-diameter`): it fixes the
/// arm's scale without reference lengths, and needs the arm file's
/// `[probe] ball_diameter_mm`; `NAN` (the default) fits each sphere's.
///
/// Errors: `AACMM_STATUS_NULL_POINTER`, `AACMM_STATUS_INVALID_ARGUMENT`
/// for a diameter that is not `NAN` nor 1 to 1000 mm (below 1, most
/// likely metres: the message says so).
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_sphere_diameter_mm(
    options: *mut AacmmCalibrateOptions,
    diameter_mm: f64,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        if diameter_mm.is_nan() {
            o.sphere_diameter_mm = None;
            return Ok(());
        }
        aacmm_core::residuals::spheres::check_sphere_diameter(diameter_mm)
            .map_err(|e| Error::invalid(format!("sphere_diameter_mm: {e}")))?;
        o.sphere_diameter_mm = Some(diameter_mm);
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::aacmm_last_error_message;
    use aacmm_core::dataset::DataSet;
    use aacmm_core::domain::Arm;
    use aacmm_core::io::read_arm;
    use aacmm_core::params::DhParams;

    /// What the library's request makes of `o` for `arm`.
    struct Settings {
        model: ModelOptions,
        solver: SolverSettings,
        cross_validate: usize,
    }

    /// [`request`]'s model and settings for `o` on `arm` (on three
    /// articulated touches of one point: the options do not look at them).
    fn settings(o: &AacmmCalibrateOptions, arm: &Arm) -> Result<Settings, Error> {
        let n = arm.params.joint_count();
        let q: Vec<Vec<f64>> = (0..3).map(|i| vec![0.1 * i as f64; n]).collect();
        let labels = vec!["P".to_string(); 3];
        let data = DataSet::from_touches(&labels, &q, &[]).unwrap();
        let r = request(o, Request::new(arm.clone(), data));
        Ok(Settings {
            model: r.model()?,
            solver: r.settings()?,
            cross_validate: o.cross_validate,
        })
    }

    fn new() -> *mut AacmmCalibrateOptions {
        let mut o = std::ptr::null_mut();
        // SAFETY: `o` is writable.
        let status = unsafe { aacmm_calibrate_options_new(&mut o) };
        assert_eq!(status, AacmmStatus::Ok);
        assert!(!o.is_null());
        o
    }

    fn last_error() -> String {
        let mut buf = [0 as c_char; 512];
        // SAFETY: `buf` has 512 writable bytes.
        unsafe { aacmm_last_error_message(buf.as_mut_ptr(), buf.len()) };
        // SAFETY: NUL-terminated by the call.
        let s = unsafe { std::ffi::CStr::from_ptr(buf.as_ptr()) };
        s.to_string_lossy().into_owned()
    }

    /// The options behind a live handle.
    fn get(o: *mut AacmmCalibrateOptions) -> AacmmCalibrateOptions {
        // SAFETY: a live handle made by `new`.
        unsafe { read(o) }.unwrap()
    }

    /// A refusal: `INVALID_ARGUMENT` and a message that starts with
    /// `expected` (the option as the C API names it, and the value).
    fn refused(status: AacmmStatus, expected: &str) {
        assert_eq!(status, AacmmStatus::InvalidArgument, "{expected}");
        let m = last_error();
        assert!(m.starts_with(expected), "{m}");
    }

    fn kinova() -> Arm {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        read_arm(&root.join("examples/mukca/kinova-1/arm.toml"))
            .unwrap()
            .0
    }

    /// Every setter refuses what the library would refuse, naming the
    /// option as its setter does, and keeps the earlier value; every
    /// setter refuses `NULL` options.
    #[test]
    fn each_setter_checks_its_value() {
        let o = new();
        // SAFETY: `o` is live and used by this thread only; the strings
        // are NUL-terminated literals.
        unsafe {
            refused(
                aacmm_calibrate_options_set_method(o, 7),
                "method = 7: one of AACMM_METHOD_LM (0)",
            );
            refused(
                aacmm_calibrate_options_set_fix(o, c"theta1,theta13".as_ptr()),
                "fix = theta1,theta13: unknown parameter `theta13`",
            );
            refused(
                aacmm_calibrate_options_set_fix(o, c"auto,theta1".as_ptr()),
                "fix = auto,theta1: `auto` stands alone",
            );
            // A string inside the builder, which the setter writes.
            refused(
                aacmm_calibrate_options_set_fix(o, o.cast()),
                "`fix` and `options` overlap",
            );
            let q = o.cast_const().cast::<f64>();
            let status = aacmm_calibrate_options_set_positions(
                o,
                6,
                q,
                18,
                q,
                9,
                std::ptr::null(),
                0,
                std::ptr::null(),
                0,
                std::ptr::null(),
                0,
            );
            assert_eq!(status, AacmmStatus::InvalidArgument);
            let bad_utf8 = [0xffu8, 0];
            refused(
                aacmm_calibrate_options_set_fix(o, bad_utf8.as_ptr().cast()),
                "fix is not valid UTF-8",
            );
            refused(
                aacmm_calibrate_options_set_cross_validate(o, 1),
                "cross_validate = 1: 0 (none) or 2 or more folds",
            );
            refused(
                aacmm_calibrate_options_set_encoder_noise_rad(o, -1.0),
                "encoder_noise_rad = -1: must be a finite number ≥ 0",
            );
            refused(
                aacmm_calibrate_options_set_probe_noise_mm(o, f64::NAN),
                "probe_noise_mm = NaN: must be a finite number ≥ 0",
            );
            refused(
                aacmm_calibrate_options_set_length_uncertainty_mm(o, -0.5),
                "length_uncertainty_mm = -0.5: must be a finite number ≥ 0",
            );
            refused(
                aacmm_calibrate_options_set_length_weight(o, f64::INFINITY),
                "length_weight = inf: must be a finite number > 0",
            );
            refused(
                aacmm_calibrate_options_set_position_noise_mm(o, -0.015, 0.0),
                "position_noise a_mm = -0.015: must be a finite number > 0",
            );
            refused(
                aacmm_calibrate_options_set_position_noise_mm(o, 0.015, f64::NAN),
                "position_noise b_mm_per_m = NaN: must be a finite number ≥ 0",
            );
            refused(
                aacmm_calibrate_options_set_position_noise_mm(o, 0.0, 0.006),
                "position_noise b_mm_per_m = 0.006: a distance-dependent position σ needs its \
                 constant part too",
            );
            refused(
                aacmm_calibrate_options_set_orientation_noise_rad(o, -0.01),
                "orientation_noise_rad = -0.01: must be a finite number > 0",
            );
            refused(
                aacmm_calibrate_options_set_robust(o, 9, 0.0),
                "robust = 9: one of AACMM_ROBUST_NONE (0)",
            );
            refused(
                aacmm_calibrate_options_set_robust(o, AACMM_ROBUST_HUBER, -1.0),
                "robust scale = -1: must be a finite number > 0",
            );
            refused(
                aacmm_calibrate_options_set_prior(o, c"length=0.5".as_ptr()),
                "prior = length=0.5: `length=0.5`: no unit",
            );
            refused(
                aacmm_calibrate_options_set_prior(o, c"theta13=1deg".as_ptr()),
                "prior = theta13=1deg: ",
            );
            refused(
                aacmm_calibrate_options_set_prior(o, c"theta5=0.05mm".as_ptr()),
                "prior = theta5=0.05mm: `theta5=0.05mm`: theta5 is an angle",
            );
            refused(
                aacmm_calibrate_options_set_compliance(o, c"0".as_ptr()),
                "compliance = 0: a joint is a number from 1",
            );
            refused(
                aacmm_calibrate_options_set_compliance(o, c"2,3,2".as_ptr()),
                "compliance = 2: joint listed twice",
            );
            refused(
                aacmm_calibrate_options_set_compliance(o, c"2,13".as_ptr()),
                "compliance = 13: joint 13: the toolkit computes chains of 1 to 12 joints",
            );
            refused(
                aacmm_calibrate_options_set_harmonics(o, c"2:".as_ptr()),
                "harmonics = 2:: an order is a whole number from 1 to 16",
            );
            refused(
                aacmm_calibrate_options_set_harmonics(o, c"2".as_ptr()),
                "harmonics = 2: expected JOINT:ORDERS",
            );
            refused(
                aacmm_calibrate_options_set_harmonics(o, c"13:1".as_ptr()),
                "harmonics = 13: joint 13: the toolkit computes chains of 1 to 12 joints",
            );
            refused(
                aacmm_calibrate_options_set_backlash(o, c"2,2".as_ptr()),
                "backlash = 2: joint listed twice",
            );
            // A hostile worker count is refused, not attempted (the bound
            // of Python's `threads` and the command line's `--threads`).
            refused(
                aacmm_calibrate_options_set_threads(o, 1025),
                "threads = 1025: at most 1024 worker threads",
            );
            refused(
                aacmm_calibrate_options_set_threads(o, 1 << 62),
                "threads = 4611686018427387904: at most 1024 worker threads",
            );
            refused(
                aacmm_calibrate_options_set_threads(o, usize::MAX),
                "threads = 18446744073709551615: at most 1024",
            );
        }
        // Nothing refused was kept: still the defaults.
        let d = AacmmCalibrateOptions::default();
        let kept = get(o);
        assert_eq!(format!("{kept:?}"), format!("{d:?}"));
        let null = std::ptr::null_mut();
        // SAFETY: NULL options are refused before any use.
        let statuses = unsafe {
            [
                aacmm_calibrate_options_set_method(null, AACMM_METHOD_LM),
                aacmm_calibrate_options_set_fix(null, std::ptr::null()),
                aacmm_calibrate_options_set_seed(null, 1),
                aacmm_calibrate_options_set_cross_validate(null, 0),
                aacmm_calibrate_options_set_encoder_noise_rad(null, 0.0),
                aacmm_calibrate_options_set_probe_noise_mm(null, 0.0),
                aacmm_calibrate_options_set_length_uncertainty_mm(null, 0.0),
                aacmm_calibrate_options_set_length_weight(null, 0.0),
                aacmm_calibrate_options_set_threads(null, 0),
                aacmm_calibrate_options_set_robust(null, AACMM_ROBUST_NONE, 0.0),
                aacmm_calibrate_options_set_prior(null, std::ptr::null()),
                aacmm_calibrate_options_set_accept_poor_fit(null, true),
                aacmm_calibrate_options_set_compliance(null, std::ptr::null()),
                aacmm_calibrate_options_set_harmonics(null, std::ptr::null()),
                aacmm_calibrate_options_set_thermal(null, true),
                aacmm_calibrate_options_set_drift(null, true),
                aacmm_calibrate_options_set_position_noise_mm(null, 0.0, 0.0),
                aacmm_calibrate_options_set_positions(
                    null,
                    6,
                    std::ptr::null(),
                    0,
                    std::ptr::null(),
                    0,
                    std::ptr::null(),
                    0,
                    std::ptr::null(),
                    0,
                    std::ptr::null(),
                    0,
                ),
                aacmm_calibrate_options_set_positions_file(null, std::ptr::null()),
                aacmm_calibrate_options_new(std::ptr::null_mut()),
            ]
        };
        assert!(statuses.iter().all(|&s| s == AacmmStatus::NullPointer));
        // SAFETY: live, not used after.
        unsafe { aacmm_calibrate_options_free(o) };
    }

    /// What is set arrives in the library's settings, in its units.
    #[test]
    fn set_values_reach_the_library() {
        let o = new();
        // SAFETY: `o` is live and used by this thread only; the strings
        // are NUL-terminated literals.
        unsafe {
            for status in [
                aacmm_calibrate_options_set_method(o, AACMM_METHOD_LM),
                aacmm_calibrate_options_set_fix(o, c"theta1, d1".as_ptr()),
                aacmm_calibrate_options_set_seed(o, 9),
                aacmm_calibrate_options_set_cross_validate(o, 3),
                aacmm_calibrate_options_set_encoder_noise_rad(o, 1e-4),
                aacmm_calibrate_options_set_probe_noise_mm(o, 0.01),
                aacmm_calibrate_options_set_length_uncertainty_mm(o, 0.002),
                aacmm_calibrate_options_set_length_weight(o, 5.0),
                aacmm_calibrate_options_set_threads(o, 2),
                aacmm_calibrate_options_set_robust(o, AACMM_ROBUST_CAUCHY, 0.0),
                aacmm_calibrate_options_set_accept_poor_fit(o, true),
                aacmm_calibrate_options_set_position_noise_mm(o, 0.015, 0.006),
                aacmm_calibrate_options_set_compliance(o, c"3, 2".as_ptr()),
                aacmm_calibrate_options_set_harmonics(o, c"2:1,5:1-2".as_ptr()),
                aacmm_calibrate_options_set_backlash(o, c"3,2".as_ptr()),
                aacmm_calibrate_options_set_thermal(o, true),
                aacmm_calibrate_options_set_drift(o, true),
            ] {
                assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
            }
        }
        let arm = Arm::without_limits("nominal", DhParams::paper_nominal());
        let s = settings(&get(o), &arm).unwrap();
        assert_eq!(s.solver.method, Method::Lm);
        assert_eq!(
            (s.solver.seed, s.solver.threads, s.cross_validate),
            (9, 2, 3)
        );
        assert_eq!(s.model.fix, FixSpec::Columns(vec![18, 6]));
        let n = s.model.noise;
        assert_eq!(n.encoder_rad, Some(1e-4));
        assert_eq!(n.probe_mm, Some(0.01));
        assert_eq!((n.length_default_mm, n.length_weight), (0.002, Some(5.0)));
        assert_eq!(
            (n.position_mm, n.position_mm_per_m),
            (Some(0.015), Some(0.006))
        );
        let r = s.model.robust.unwrap();
        assert_eq!(
            (r.loss, r.scale_k),
            (Loss::Cauchy, Loss::Cauchy.default_k())
        );
        assert!(s.model.accept_poor_fit);
        assert_eq!(s.model.prior, None);
        // 1-based joints in the text, 0-based in the model, sorted.
        assert_eq!(
            s.model.beyond,
            Beyond {
                compliance: vec![1, 2],
                harmonics: vec![(1, 1), (4, 1), (4, 2)],
                backlash: vec![1, 2],
                thermal: true,
                drift: true,
            }
        );
        // 0 = one per core; NULL fix = auto; robust off again.
        // SAFETY: as above.
        unsafe {
            aacmm_calibrate_options_set_threads(o, 0);
            aacmm_calibrate_options_set_fix(o, std::ptr::null());
            aacmm_calibrate_options_set_robust(o, AACMM_ROBUST_NONE, 0.0);
            aacmm_calibrate_options_set_compliance(o, std::ptr::null());
            aacmm_calibrate_options_set_harmonics(o, std::ptr::null());
            aacmm_calibrate_options_set_backlash(o, std::ptr::null());
            aacmm_calibrate_options_set_thermal(o, false);
            aacmm_calibrate_options_set_drift(o, false);
        }
        let s = settings(&get(o), &arm).unwrap();
        assert_eq!(s.solver.threads, aacmm_core::calibrate::available_threads());
        // The bound itself is a worker count.
        // SAFETY: as above.
        let status = unsafe { aacmm_calibrate_options_set_threads(o, MAX_THREADS) };
        assert_eq!(status, AacmmStatus::Ok);
        assert_eq!(settings(&get(o), &arm).unwrap().solver.threads, MAX_THREADS);
        // SAFETY: as above.
        unsafe { aacmm_calibrate_options_set_threads(o, 0) };
        assert_eq!(s.model.fix, FixSpec::Auto);
        assert_eq!(s.model.robust, None);
        assert!(s.model.beyond.is_empty(), "NULL and false: no model");
        // A position σ without its distance part: 0 = not stated, as `A`
        // alone on the command line; 0 for both: none.
        // SAFETY: as above.
        unsafe { aacmm_calibrate_options_set_position_noise_mm(o, 0.02, 0.0) };
        let n = settings(&get(o), &arm).unwrap().model.noise;
        assert_eq!((n.position_mm, n.position_mm_per_m), (Some(0.02), None));
        // SAFETY: as above.
        unsafe { aacmm_calibrate_options_set_position_noise_mm(o, 0.0, 0.0) };
        let n = settings(&get(o), &arm).unwrap().model.noise;
        assert_eq!((n.position_mm, n.position_mm_per_m), (None, None));
        // An orientation σ, rad; 0: not stated.
        // SAFETY: as above.
        unsafe { aacmm_calibrate_options_set_orientation_noise_rad(o, 2e-4) };
        let n = settings(&get(o), &arm).unwrap().model.noise;
        assert_eq!(n.orientation_rad, Some(2e-4));
        // SAFETY: as above.
        unsafe { aacmm_calibrate_options_set_orientation_noise_rad(o, 0.0) };
        let n = settings(&get(o), &arm).unwrap().model.noise;
        assert_eq!(n.orientation_rad, None);
        // A 7-joint name passes the setter but not a 6-joint arm.
        // SAFETY: as above.
        unsafe { aacmm_calibrate_options_set_fix(o, c"theta7".as_ptr()) };
        let e = settings(&get(o), &arm).err().unwrap();
        assert_eq!(e.status, AacmmStatus::InvalidArgument);
        assert!(
            e.message.starts_with("fix = theta7: unknown parameter"),
            "{}",
            e.message
        );
        // So does a compliance of joint 7, refused by the model's check
        // for the arm at hand.
        // SAFETY: as above.
        unsafe {
            aacmm_calibrate_options_set_fix(o, std::ptr::null());
            aacmm_calibrate_options_set_compliance(o, c"2,7".as_ptr());
        }
        let model = settings(&get(o), &arm).unwrap().model;
        let e = Error::from(model.check(6).unwrap_err());
        assert_eq!(e.status, AacmmStatus::InvalidArgument);
        assert_eq!(e.message, "compliance = 7: joint 7: the arm has 6 joints");
        // SAFETY: live, not used after.
        unsafe { aacmm_calibrate_options_free(o) };
    }

    /// The arm file's `[prior]` is the default; `none` drops it; a
    /// specification overrides it entry by entry, as `--prior` does.
    #[test]
    fn the_arm_files_prior_is_used_unless_overridden() {
        let arm = kinova();
        let file = arm
            .prior
            .clone()
            .expect("kinova-1's arm file has a [prior]");
        let o = new();
        let s = settings(&get(o), &arm).unwrap();
        assert_eq!(s.model.prior.as_ref(), Some(&file));
        // SAFETY: `o` is live and used by this thread only.
        unsafe { aacmm_calibrate_options_set_prior(o, c"none".as_ptr()) };
        assert_eq!(settings(&get(o), &arm).unwrap().model.prior, None);
        // SAFETY: as above.
        unsafe { aacmm_calibrate_options_set_prior(o, c"length=0.3mm,theta5=0.05deg".as_ptr()) };
        let given = Tolerances::parse("length=0.3mm,theta5=0.05deg", 6)
            .unwrap()
            .unwrap();
        let s = settings(&get(o), &arm).unwrap();
        assert_eq!(s.model.prior, Some(file.clone().overridden_by(&given)));
        let sigmas = s.model.prior.unwrap().sigmas(6);
        assert_eq!(sigmas[0], Some(0.3), "a1: the given length");
        assert_eq!(
            sigmas[26],
            Some(2.0),
            "Bz: the file's own probe entry stays"
        );
        // An arm without a file prior takes the specification alone.
        let bare = Arm::without_limits("nominal", DhParams::paper_nominal());
        let s = settings(&get(o), &bare).unwrap();
        assert_eq!(s.model.prior, Some(given));
        // SAFETY: live, not used after.
        unsafe { aacmm_calibrate_options_free(o) };
    }
}
