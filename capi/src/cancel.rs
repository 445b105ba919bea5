//! Stopping a calibration from another thread: a cancellation token the
//! caller makes, hands to the options, and sets when the user gives up (a
//! GUI's Cancel button, a deadline). The solvers check it before each LM
//! iteration, at each start of a global search and every 64 cells of its
//! grid, at each annealing temperature and before each cross-validation
//! fold: a calibration stops within milliseconds and returns
//! `AACMM_STATUS_CANCELLED`, with no result.

use aacmm_core::calibrate::Cancel;

use crate::error::{AacmmStatus, guard, guard_value};
use crate::options::AacmmCalibrateOptions;
use crate::ptr;

/// A cancellation token. Opaque; made by `aacmm_cancel_new`, set by
/// `aacmm_cancel_set` (from any thread, at any time), released by
/// `aacmm_cancel_free`. Once set it stays set: make a new one for the next
/// calibration.
#[derive(Debug, Default)]
pub struct AacmmCancel {
    token: Cancel,
}

/// A new token, not set, at `*out` (release it with `aacmm_cancel_free`).
///
/// Errors: `AACMM_STATUS_NULL_POINTER` (`out`).
///
/// # Safety
///
/// `out` is `NULL` or points to writable memory for one pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_cancel_new(out: *mut *mut AacmmCancel) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        unsafe { ptr::hand_out(out, AacmmCancel::default(), "out") }
    })
}

/// Sets the token: every calibration given it stops at its next check and
/// returns `AACMM_STATUS_CANCELLED`. Safe from any thread, also while a
/// calibration runs with it.
///
/// Errors: `AACMM_STATUS_NULL_POINTER` (`cancel`).
///
/// # Safety
///
/// `cancel` is `NULL` or a live token.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_cancel_set(cancel: *const AacmmCancel) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let c = unsafe { ptr::object(cancel, "cancel") }?;
        c.token.cancel();
        Ok(())
    })
}

/// Releases a token. `NULL` is allowed (nothing happens). Options it was
/// given to keep their own reference: a calibration running with them can
/// still be stopped through another handle of it — not through this one,
/// which must not be used afterwards.
///
/// # Safety
///
/// `cancel` is `NULL` or a live token, which must not be used afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_cancel_free(cancel: *mut AacmmCancel) {
    // SAFETY: by the contract.
    guard_value((), || unsafe { ptr::release(cancel) })
}

/// Calibrations with these options stop when `cancel` is set (`NULL`: none
/// can be stopped, the default). The options hold their own reference to
/// the token.
///
/// Errors: `AACMM_STATUS_NULL_POINTER` (`options`).
///
/// # Safety
///
/// As `aacmm_calibrate_options_set_method`; `cancel` is `NULL` or a live
/// token.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibrate_options_set_cancel(
    options: *mut AacmmCalibrateOptions,
    cancel: *const AacmmCancel,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let o = unsafe { ptr::object_mut(options, "options") }?;
        let token = match cancel.is_null() {
            true => None,
            // SAFETY: by the contract.
            false => Some(unsafe { ptr::object(cancel, "cancel") }?.token.clone()),
        };
        o.set_cancel(token);
        Ok(())
    })
}
