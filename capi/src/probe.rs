//! Qualifying one probe of an arm on a reference sphere, the arm's geometry
//! held (`aacmm probe`): options made by a builder, the result an opaque
//! handle with accessors — its figures, its refusals in C's words, and the
//! arm with the qualified probe.

use std::ffi::c_char;

use aacmm_core::domain::{Arm, DEFAULT_TOOL};
use aacmm_core::io::spheres::read_spheres;
use aacmm_core::io::{AngleUnit, source_name};
use aacmm_core::residuals::Noise;
use aacmm_core::session::Spelling;
use aacmm_core::session::probe::{
    DEFAULT_TOLERANCE_MM, ProbeQualification, ProbeSettings, qualify_probe,
};

use crate::arm::{AacmmArm, handle};
use crate::calibrate::{AACMM_ANGLE_DEG, AACMM_ANGLE_RAD, AacmmAngleUnit, count_out, text_out};
use crate::error::{AacmmStatus, Error, guard, guard_value};
use crate::options::stated;
use crate::ptr::{self, Args};

/// What a probe qualification is asked. Opaque; made by
/// `aacmm_probe_options_new`, changed by its setters, released by
/// `aacmm_probe_options_free`.
#[derive(Clone, Debug)]
pub struct AacmmProbeOptions {
    settings: ProbeSettings,
}

/// A probe qualification. Opaque; made by `aacmm_qualify_probe`, read by
/// its accessors, released by `aacmm_probe_qualification_free`.
#[derive(Debug)]
pub struct AacmmProbeQualification {
    q: ProbeQualification,
    qualified: Arm,
}

/// A qualification's figures, for `aacmm_probe_qualification_figures`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AacmmProbeFigures {
    /// Whether the qualified probe may be used (no refusal).
    pub usable: bool,
    /// Points fitted.
    pub points: usize,
    /// The qualified tip offset, mm (the last joint's frame).
    pub offset_mm: [f64; 3],
    /// Its σ per coordinate, mm.
    pub offset_sigma_mm: [f64; 3],
    /// How far the tip moved from the arm's stated offset, mm.
    pub moved_mm: f64,
    /// The effective ball diameter, mm.
    pub ball_diameter_mm: f64,
    /// Its σ, mm.
    pub ball_sigma_mm: f64,
}

/// New options for a sphere of certified diameter `sphere_diameter_mm` at
/// `*out` (release them with `aacmm_probe_options_free`): the arm's
/// `[probe]`, noise not stated (estimated), a tolerance of 0.05 mm on the
/// tip's move, no limit on the sphere's form.
///
/// Errors: `AACMM_STATUS_NULL_POINTER` (`out`),
/// `AACMM_STATUS_INVALID_ARGUMENT` for a diameter out of range (in metres?).
///
/// # Safety
///
/// `out` is `NULL` or points to writable memory for one pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_probe_options_new(
    sphere_diameter_mm: f64,
    out: *mut *mut AacmmProbeOptions,
) -> AacmmStatus {
    guard(|| {
        aacmm_core::residuals::spheres::check_sphere_diameter(sphere_diameter_mm)?;
        let options = AacmmProbeOptions {
            settings: ProbeSettings {
                tool: DEFAULT_TOOL.to_string(),
                sphere_diameter_mm,
                noise: Noise::default(),
                tolerance_mm: DEFAULT_TOLERANCE_MM,
                max_form_mm: None,
                spelling: Spelling::C,
            },
        };
        // SAFETY: by the contract.
        unsafe { ptr::hand_out(out, options, "out") }
    })
}

/// Releases options. `NULL` is allowed (nothing happens).
///
/// # Safety
///
/// `options` is `NULL` or a live options handle, not used afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_probe_options_free(options: *mut AacmmProbeOptions) {
    // SAFETY: by the contract.
    guard_value((), || unsafe { ptr::release(options) })
}

/// The probe qualified: `"probe"` (the arm's `[probe]`, the default) or a
/// `[[tool]]`'s name (`--tool`); the arm's own check names an unknown one.
///
/// Errors (for every setter): `AACMM_STATUS_NULL_POINTER`,
/// `AACMM_STATUS_INVALID_ARGUMENT` for a value out of range (the options
/// keep their earlier value).
///
/// # Safety
///
/// `options` is `NULL` or a live options handle no other thread uses
/// during the call; `tool` is `NULL` or a NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_probe_options_set_tool(
    options: *mut AacmmProbeOptions,
    tool: *const c_char,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        // SAFETY: by the contract.
        let name = unsafe { ptr::c_str(tool, "tool") }?;
        let name = name
            .to_str()
            .map_err(|_| Error::invalid("tool: not UTF-8"))?;
        o.settings.tool = name.to_string();
        Ok(())
    })
}

/// σ of each encoder reading, rad, and of the probe's seating per axis, mm
/// (`--encoder-noise`, in degrees there, and `--probe-noise`); 0 = not
/// stated (the default: the σ is estimated and no χ² test is made).
/// Finite and ≥ 0.
///
/// # Safety
///
/// As `aacmm_probe_options_set_tool`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_probe_options_set_noise(
    options: *mut AacmmProbeOptions,
    encoder_rad: f64,
    probe_mm: f64,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        let noise = Noise {
            encoder_rad: stated(encoder_rad),
            probe_mm: stated(probe_mm),
            ..Noise::default()
        };
        noise.check()?;
        o.settings.noise = noise;
        Ok(())
    })
}

/// The largest move of the tip from the arm's stated offset not warned
/// of, mm (`--tolerance`, default 0.05), and the largest form of the
/// sphere as the probe sees it, mm (`--max-form`; 0 = no limit, the
/// default: the form is judged by the stated noise alone). Finite and ≥ 0.
///
/// # Safety
///
/// As `aacmm_probe_options_set_tool`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_probe_options_set_limits(
    options: *mut AacmmProbeOptions,
    tolerance_mm: f64,
    max_form_mm: f64,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        for (name, v) in [("tolerance_mm", tolerance_mm), ("max_form_mm", max_form_mm)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(format!(
                    "{name} = {v}: a finite length ≥ 0, mm"
                )));
            }
        }
        o.settings.tolerance_mm = tolerance_mm;
        o.settings.max_form_mm = (max_form_mm > 0.0).then_some(max_form_mm);
        Ok(())
    })
}

/// Qualifies a probe of `arm` on the points of the sphere-surface file
/// `spheres_path` (`sphere,q1,...,qn[,articulation][,tool]`, readings in
/// `spheres_unit`; other probes' rows left out) as `options` ask (`NULL`:
/// the defaults need a sphere diameter, so `NULL` is refused): the result
/// handle at `*out`, usable or not (`aacmm_probe_qualification_figures`
/// says which, `aacmm_probe_qualification_refusal` why not).
///
/// Errors: `AACMM_STATUS_NULL_POINTER`, `AACMM_STATUS_IO`,
/// `AACMM_STATUS_INPUT` (the file's content, named by file, line and
/// field), `AACMM_STATUS_INVALID_ARGUMENT` (a probe the arm does not know,
/// a unit out of range), `AACMM_STATUS_CALIBRATION` (the fit's own). On
/// error `*out` is `NULL`.
///
/// # Safety
///
/// `arm` is `NULL` or a live arm handle; `spheres_path` is `NULL` or a
/// NUL-terminated string; `options` is `NULL` or a live options handle no
/// setter changes during the call; `out` is `NULL` or points to writable
/// memory for one pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_qualify_probe(
    arm: *const AacmmArm,
    spheres_path: *const c_char,
    spheres_unit: AacmmAngleUnit,
    options: *const AacmmProbeOptions,
    out: *mut *mut AacmmProbeQualification,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: the path is NULL or NUL-terminated, by the contract.
        let args = unsafe { Args::new().c_str("spheres_path", spheres_path) };
        (args.object("arm", arm).object("options", options))
            .out("out", out)
            .disjoint()?;
        // SAFETY: by the contract.
        unsafe { ptr::write(out, std::ptr::null_mut(), "out") }?;
        // SAFETY: by the contract.
        let (a, o) = unsafe { (handle(arm)?, ptr::object(options, "options")?) };
        // SAFETY: by the contract.
        let path = unsafe { ptr::path(spheres_path, "spheres_path") }?;
        let unit = match spheres_unit {
            AACMM_ANGLE_DEG => AngleUnit::Deg,
            AACMM_ANGLE_RAD => AngleUnit::Rad,
            u => {
                return Err(Error::invalid(format!(
                    "spheres_unit = {u}: AACMM_ANGLE_DEG ({AACMM_ANGLE_DEG}) or \
                     AACMM_ANGLE_RAD ({AACMM_ANGLE_RAD})"
                )));
            }
        };
        let (rows, read) = read_spheres(&path, unit, &a.arm)?;
        let mut q = qualify_probe(&a.arm, rows, &source_name(&path), &o.settings)?;
        // The reader's warnings (readings that look like radians) first.
        let read = read.iter().map(|w| w.to_string());
        q.warnings = read.chain(std::mem::take(&mut q.warnings)).collect();
        let qualified = q.qualified_arm(&a.arm);
        let result = AacmmProbeQualification { q, qualified };
        // SAFETY: checked writable above.
        unsafe { ptr::hand_out(out, result, "out") }
    })
}

/// Releases a qualification. `NULL` is allowed (nothing happens).
///
/// # Safety
///
/// `q` is `NULL` or a live qualification handle, not used afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_probe_qualification_free(q: *mut AacmmProbeQualification) {
    // SAFETY: by the contract.
    guard_value((), || unsafe { ptr::release(q) })
}

/// The qualification's figures into `*out`.
///
/// # Safety
///
/// `q` is `NULL` or a live qualification handle; `out` is `NULL` or
/// writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_probe_qualification_figures(
    q: *const AacmmProbeQualification,
    out: *mut AacmmProbeFigures,
) -> AacmmStatus {
    guard(|| {
        Args::new().object("q", q).out("out", out).disjoint()?;
        // SAFETY: by the contract.
        let q = &unsafe { ptr::object(q, "q") }?.q;
        let figures = AacmmProbeFigures {
            usable: q.usable(),
            points: q.points,
            offset_mm: q.offset,
            offset_sigma_mm: q.offset_sigma,
            moved_mm: q.moved_mm,
            ball_diameter_mm: q.ball_diameter_mm,
            ball_sigma_mm: q.ball_sigma_mm,
        };
        // SAFETY: by the contract.
        unsafe { ptr::write(out, figures, "out") }
    })
}

/// The number of reasons the qualification is refused (0 when usable)
/// into `*count`.
///
/// # Safety
///
/// `q` is `NULL` or a live qualification handle; `count` is `NULL` or
/// writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_probe_qualification_refusal_count(
    q: *const AacmmProbeQualification,
    count: *mut usize,
) -> AacmmStatus {
    // SAFETY: by the contract.
    unsafe { count_out((q, "q"), count, |q| Ok(q.q.refusals.len())) }
}

/// Refusal `index` (from 0) in C's words (a remedy names the C setter),
/// copied into `buf` like `aacmm_last_error_message`; `*len` gets its full
/// length in bytes without the NUL. `AACMM_STATUS_INVALID_ARGUMENT` for an
/// index at or beyond `aacmm_probe_qualification_refusal_count`.
///
/// # Safety
///
/// `q` is `NULL` or a live qualification handle; `buf` is `NULL` or points
/// to `buf_len` writable bytes; `len` is `NULL` or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_probe_qualification_refusal(
    q: *const AacmmProbeQualification,
    index: usize,
    buf: *mut c_char,
    buf_len: usize,
    len: *mut usize,
) -> AacmmStatus {
    // SAFETY: by the contract.
    unsafe { message_out(q, |q| &q.refusals, "refusal", index, (buf, buf_len, len)) }
}

/// The number of warnings of the qualification into `*count`: the sphere
/// file's (readings that look like radians), and a tip moved beyond the
/// tolerance (a bent or changed stylus; the qualified offset is still
/// given).
///
/// # Safety
///
/// As `aacmm_probe_qualification_refusal_count`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_probe_qualification_warning_count(
    q: *const AacmmProbeQualification,
    count: *mut usize,
) -> AacmmStatus {
    // SAFETY: by the contract.
    unsafe { count_out((q, "q"), count, |q| Ok(q.q.warnings.len())) }
}

/// Warning `index` (from 0), copied as `aacmm_probe_qualification_refusal`
/// copies a refusal.
///
/// # Safety
///
/// As `aacmm_probe_qualification_refusal`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_probe_qualification_warning(
    q: *const AacmmProbeQualification,
    index: usize,
    buf: *mut c_char,
    buf_len: usize,
    len: *mut usize,
) -> AacmmStatus {
    // SAFETY: by the contract.
    unsafe { message_out(q, |q| &q.warnings, "warning", index, (buf, buf_len, len)) }
}

/// Message `index` of the list `of` picks (`what` in the error) copied out.
///
/// # Safety
///
/// As `aacmm_probe_qualification_refusal`.
unsafe fn message_out(
    q: *const AacmmProbeQualification,
    of: impl Fn(&ProbeQualification) -> &Vec<String>,
    what: &str,
    index: usize,
    buf: (*mut c_char, usize, *mut usize),
) -> AacmmStatus {
    // SAFETY: by the contract.
    unsafe {
        text_out((q, "q"), buf, |q| {
            let list = of(&q.q);
            let text = list.get(index).ok_or_else(|| {
                Error::invalid(format!(
                    "index = {index}: the qualification has {} {what}(s)",
                    list.len()
                ))
            })?;
            Ok(text.replace('\n', " ").into())
        })
    }
}

/// The arm with the qualified probe (its offset and ball diameter) as a new
/// arm handle at `*out` (release it with `aacmm_arm_free`). Returns
/// `AACMM_STATUS_NOT_AVAILABLE` (and `*out` `NULL`) for a refused
/// qualification: a refused probe is not to be used.
///
/// # Safety
///
/// `q` is `NULL` or a live qualification handle; `out` is `NULL` or points
/// to writable memory for one pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_probe_qualification_arm(
    q: *const AacmmProbeQualification,
    out: *mut *mut AacmmArm,
) -> AacmmStatus {
    guard(|| {
        Args::new().object("q", q).out("out", out).disjoint()?;
        // SAFETY: by the contract.
        unsafe { ptr::write(out, std::ptr::null_mut(), "out") }?;
        // SAFETY: by the contract.
        let q = unsafe { ptr::object(q, "q") }?;
        if !q.q.usable() {
            return Err(Error::new(
                AacmmStatus::NotAvailable,
                "the probe is not qualified: see aacmm_probe_qualification_refusal",
            ));
        }
        let arm = AacmmArm::new(q.qualified.clone(), "<qualified>".into(), Vec::new())?;
        // SAFETY: checked writable above.
        unsafe { ptr::hand_out(out, arm, "out") }
    })
}
