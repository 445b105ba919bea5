//! The C ABI of aacmm: the generated arm kernel and the calibrator as a C
//! library (`cdylib` and `staticlib`), declared by the cbindgen-generated
//! header `capi/include/aacmm.h`.
//!
//! Conventions, for every function:
//!
//! - lengths in mm, angles in rad; parameters in the toolkit's fixed order
//!   `a1..an, d1..dn, alpha1..alphan, theta1..thetan, Bx, By, Bz`;
//! - arrays are row-major and passed with their length in elements, which
//!   must match what the arm and the other arguments imply
//!   (`AACMM_STATUS_LENGTH` otherwise);
//! - every function that can fail returns an [`AacmmStatus`]; the message of
//!   the last failure on the calling thread is copied out by
//!   [`aacmm_last_error_message`]; `NULL` pointers, wrong lengths, misaligned
//!   or overlapping buffers give codes, never a crash;
//! - every output (a buffer, a length, a struct, a handle's slot) is
//!   checked against every input (arrays, strings, handles) and every other
//!   output before anything is written: one that shares memory with
//!   another argument gives `AACMM_STATUS_INVALID_ARGUMENT` and nothing is
//!   written, not even the `NULL` an output handle gets on other errors;
//!   the lengths are checked before, so that one past what memory can hold
//!   gives `AACMM_STATUS_LENGTH`;
//! - memory for work sized by the input is asked for before the work, and a
//!   refusal gives `AACMM_STATUS_OUT_OF_MEMORY`, never an abort of the host;
//! - every entry point catches panics: a bug inside gives
//!   `AACMM_STATUS_PANIC`, never an unwind into C or an abort of the host;
//! - handles (`AacmmArm`, `AacmmCalibration`) are opaque, immutable once
//!   made, usable from several threads at once, and released by their
//!   `…_free` function; the options of a calibration
//!   (`AacmmCalibrateOptions`) are an opaque builder too, changed only by
//!   its setters, so that options can be added without changing a layout
//!   a compiled caller relies on.
//!
//! Only `aacmm_`-prefixed symbols are exported.

// An FFI layer cannot avoid `unsafe`: it dereferences raw pointers from C
// and exports unmangled symbols. The workspace denies `unsafe_code`; this
// crate alone allows it, and every block states why it is sound in a
// `// SAFETY:` comment (clippy's `undocumented_unsafe_blocks`). The checks
// behind those comments live in `ptr`.
#![allow(unsafe_code)]

mod arm;
mod calibrate;
mod cancel;
mod error;
mod map;
mod options;
mod positions;
mod probe;
mod ptr;

use std::ffi::c_char;

pub use arm::{
    AacmmArm, aacmm_arm_free, aacmm_arm_from_file, aacmm_arm_from_file_accepting_rejected,
    aacmm_arm_from_params, aacmm_arm_joints, aacmm_arm_params, aacmm_arm_set_joint_types,
    aacmm_arm_warnings, aacmm_jacobians, aacmm_joint_jacobian, aacmm_param_count, aacmm_positions,
};
pub use calibrate::{
    AACMM_ANGLE_DEG, AACMM_ANGLE_RAD, AACMM_REASON_CHI_SQUARE, AACMM_REASON_DATA_DISAGREE_WITH_ARM,
    AACMM_REASON_IMPLAUSIBLE_BLOCKS, AACMM_REASON_NOT_NOMINAL_GEOMETRY, AACMM_REASON_OTHER,
    AACMM_REASON_OUTLIERS, AACMM_REASON_RADIANS_AS_DEGREES, AACMM_REASON_ROBUST_SCALE,
    AACMM_REASON_UNCONFIRMED, AACMM_REASON_UNDETERMINED, AACMM_REASON_WORSE_AT_POSITIONS,
    AACMM_REASON_WORSE_ON_DATA, AacmmAngleUnit, AacmmAuxiliary, AacmmCalibration,
    AacmmCalibrationSummary, AacmmFrame, AacmmReasonKind, AacmmReferenceLength, AacmmTermination,
    AacmmTool, aacmm_calibrate, aacmm_calibrate_files, aacmm_calibration_arm,
    aacmm_calibration_auxiliary, aacmm_calibration_auxiliary_count, aacmm_calibration_fixed,
    aacmm_calibration_frame, aacmm_calibration_frame_count, aacmm_calibration_free,
    aacmm_calibration_params, aacmm_calibration_reason, aacmm_calibration_reason_count,
    aacmm_calibration_report, aacmm_calibration_sigmas, aacmm_calibration_summary,
    aacmm_calibration_tool, aacmm_calibration_tool_count, aacmm_calibration_verdict,
    aacmm_calibration_verdict_notes,
};
pub use cancel::{
    AacmmCancel, aacmm_calibrate_options_set_cancel, aacmm_cancel_free, aacmm_cancel_new,
    aacmm_cancel_set,
};
pub use error::{AacmmStatus, aacmm_last_error_message};
pub use map::{
    AACMM_MAP_BASE, AACMM_MAP_FRAME, AACMM_MAP_TOOL, AacmmMapKind, AacmmUncertaintyMap,
    AacmmUncertaintyRegion, aacmm_calibration_uncertainty_map,
    aacmm_calibration_uncertainty_map_at, aacmm_calibration_uncertainty_map_count,
    aacmm_calibration_uncertainty_map_name, aacmm_calibration_uncertainty_map_region,
    aacmm_calibration_uncertainty_region, aacmm_calibration_uncertainty_region_count,
};
pub use options::{
    AACMM_METHOD_GLOBAL, AACMM_METHOD_HYBRID, AACMM_METHOD_LM, AACMM_METHOD_SA,
    AACMM_ROBUST_CAUCHY, AACMM_ROBUST_HUBER, AACMM_ROBUST_NONE, AacmmCalibrateOptions, AacmmMethod,
    AacmmRobust, aacmm_calibrate_options_free, aacmm_calibrate_options_new,
    aacmm_calibrate_options_set_accept_poor_fit, aacmm_calibrate_options_set_backlash,
    aacmm_calibrate_options_set_compliance, aacmm_calibrate_options_set_cross_validate,
    aacmm_calibrate_options_set_drift, aacmm_calibrate_options_set_encoder_noise_rad,
    aacmm_calibrate_options_set_fix, aacmm_calibrate_options_set_global_starts,
    aacmm_calibrate_options_set_harmonics, aacmm_calibrate_options_set_length_uncertainty_mm,
    aacmm_calibrate_options_set_length_weight, aacmm_calibrate_options_set_method,
    aacmm_calibrate_options_set_orientation_noise_rad,
    aacmm_calibrate_options_set_position_noise_mm,
    aacmm_calibrate_options_set_position_orientations, aacmm_calibrate_options_set_position_tools,
    aacmm_calibrate_options_set_positions, aacmm_calibrate_options_set_positions_file,
    aacmm_calibrate_options_set_prior, aacmm_calibrate_options_set_probe_noise_mm,
    aacmm_calibrate_options_set_robust, aacmm_calibrate_options_set_seed,
    aacmm_calibrate_options_set_sphere_diameter_mm, aacmm_calibrate_options_set_spheres_file,
    aacmm_calibrate_options_set_thermal, aacmm_calibrate_options_set_threads,
};
pub use probe::{
    AacmmProbeFigures, AacmmProbeOptions, AacmmProbeQualification, aacmm_probe_options_free,
    aacmm_probe_options_new, aacmm_probe_options_set_limits, aacmm_probe_options_set_noise,
    aacmm_probe_options_set_tool, aacmm_probe_qualification_arm, aacmm_probe_qualification_figures,
    aacmm_probe_qualification_free, aacmm_probe_qualification_refusal,
    aacmm_probe_qualification_refusal_count, aacmm_probe_qualification_warning,
    aacmm_probe_qualification_warning_count, aacmm_qualify_probe,
};

/// The library's version (`MAJOR.MINOR.PATCH`, the workspace's version), as
/// a static NUL-terminated string: do not free it.
#[unsafe(no_mangle)]
pub extern "C" fn aacmm_version() -> *const c_char {
    const VERSION: &str = concat!(env!("CARGO_PKG_VERSION"), "\0");
    VERSION.as_ptr().cast()
}
