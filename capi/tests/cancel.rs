//! Stopping a calibration through the C API: a token set before (or
//! during) the run gives `AACMM_STATUS_CANCELLED` and no result; a token
//! given but never set changes no byte of the report; from another thread,
//! a running search stops.

// Calling the C ABI from Rust takes raw pointers, as C does.
#![allow(unsafe_code)]

mod common;
use common::last_error;

use std::ffi::CString;

use aacmm_capi::{
    AACMM_ANGLE_DEG, AacmmCalibration, AacmmCancel, AacmmStatus, aacmm_calibrate_files,
    aacmm_calibrate_options_free, aacmm_calibrate_options_new, aacmm_calibrate_options_set_cancel,
    aacmm_calibrate_options_set_encoder_noise_rad, aacmm_calibrate_options_set_probe_noise_mm,
    aacmm_calibration_free, aacmm_calibration_report, aacmm_cancel_free, aacmm_cancel_new,
    aacmm_cancel_set,
};

fn example(path: &str) -> CString {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../examples")
        .join(path);
    CString::new(p.to_str().unwrap()).unwrap()
}

/// The shipped campaign calibrated (global, the default) with `cancel`
/// (`NULL`: none): the status and, on success, the report.
///
/// # Safety
///
/// `cancel` is `NULL` or a live token.
unsafe fn calibrate(cancel: *const AacmmCancel) -> (AacmmStatus, Option<String>) {
    let (arm, poses, lengths) = (
        example("paper-table-1.toml"),
        example("paper-campaign/poses.csv"),
        example("paper-campaign/lengths.csv"),
    );
    let mut o = std::ptr::null_mut();
    let mut cal: *mut AacmmCalibration = std::ptr::null_mut();
    // SAFETY: writable slots, live handles and NUL-terminated paths.
    unsafe {
        assert_eq!(aacmm_calibrate_options_new(&mut o), AacmmStatus::Ok);
        aacmm_calibrate_options_set_encoder_noise_rad(o, 0.012f64.to_radians());
        aacmm_calibrate_options_set_probe_noise_mm(o, 0.024);
        assert_eq!(
            aacmm_calibrate_options_set_cancel(o, cancel),
            AacmmStatus::Ok
        );
        let status = aacmm_calibrate_files(
            arm.as_ptr(),
            poses.as_ptr(),
            lengths.as_ptr(),
            AACMM_ANGLE_DEG,
            o,
            &mut cal,
        );
        aacmm_calibrate_options_free(o);
        if status != AacmmStatus::Ok {
            assert!(cal.is_null());
            return (status, None);
        }
        let mut len = 0;
        aacmm_calibration_report(cal, std::ptr::null_mut(), 0, &mut len);
        let mut buf = vec![0u8; len + 1];
        aacmm_calibration_report(cal, buf.as_mut_ptr().cast(), buf.len(), &mut len);
        aacmm_calibration_free(cal);
        (
            status,
            Some(String::from_utf8(buf[..len].to_vec()).unwrap()),
        )
    }
}

#[test]
fn a_set_token_stops_the_calibration_and_an_unset_one_changes_nothing() {
    // SAFETY: the token is live until freed at the end.
    unsafe {
        let mut token = std::ptr::null_mut();
        assert_eq!(aacmm_cancel_new(&mut token), AacmmStatus::Ok);
        let (status, plain) = calibrate(std::ptr::null());
        assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
        let (status, given) = calibrate(token);
        assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
        assert_eq!(given, plain, "a token never set changes no byte");
        assert_eq!(aacmm_cancel_set(token), AacmmStatus::Ok);
        let (status, none) = calibrate(token);
        assert_eq!((status, none), (AacmmStatus::Cancelled, None));
        assert!(last_error().contains("cancelled"), "{}", last_error());
        aacmm_cancel_free(token);
        assert_eq!(aacmm_cancel_set(std::ptr::null()), AacmmStatus::NullPointer);
        aacmm_cancel_free(std::ptr::null_mut());
    }
}

/// A token set from another thread while calibrations run stops the one
/// running: some run ends `CANCELLED` before all would have finished.
#[test]
fn a_token_set_from_another_thread_stops_a_running_calibration() {
    struct Token(*mut AacmmCancel);
    // SAFETY: the token is an atomic flag behind a handle: setting it from
    // another thread is what it is for.
    unsafe impl Send for Token {}
    // SAFETY: as above.
    unsafe impl Sync for Token {}
    let mut raw = std::ptr::null_mut();
    // SAFETY: a writable slot.
    assert_eq!(unsafe { aacmm_cancel_new(&mut raw) }, AacmmStatus::Ok);
    let token = Token(raw);
    let statuses = std::thread::scope(|s| {
        let runner = s.spawn(|| {
            let t = &token;
            // SAFETY: the token lives until after the scope.
            (0..200)
                .map(|_| unsafe { calibrate(t.0) }.0)
                .find(|&st| st != AacmmStatus::Ok)
        });
        std::thread::sleep(std::time::Duration::from_millis(200));
        // SAFETY: live until freed below.
        assert_eq!(unsafe { aacmm_cancel_set(token.0) }, AacmmStatus::Ok);
        runner.join().unwrap()
    });
    assert_eq!(statuses, Some(AacmmStatus::Cancelled), "{}", last_error());
    // SAFETY: no one uses it any more.
    unsafe { aacmm_cancel_free(token.0) };
}
