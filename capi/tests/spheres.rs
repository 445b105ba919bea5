//! Points on reference spheres through the C API: a sphere-surface file
//! calibrates alone with a stated diameter and cross-validation — the
//! library's report byte for byte —, and a diameter in metres, or a file
//! with `aacmm_calibrate`, is refused with a code and a message.

// Calling the C ABI from Rust takes raw pointers, as C does.
#![allow(unsafe_code)]

mod common;
use common::last_error;
#[path = "common/sphere_files.rs"]
mod sphere_files;

use std::ffi::CString;

use aacmm_capi::{
    AACMM_ANGLE_DEG, AACMM_METHOD_LM, AacmmStatus, aacmm_calibrate_files,
    aacmm_calibrate_options_free, aacmm_calibrate_options_new,
    aacmm_calibrate_options_set_cross_validate, aacmm_calibrate_options_set_encoder_noise_rad,
    aacmm_calibrate_options_set_method, aacmm_calibrate_options_set_probe_noise_mm,
    aacmm_calibrate_options_set_sphere_diameter_mm, aacmm_calibrate_options_set_spheres_file,
    aacmm_calibration_free, aacmm_calibration_report,
};
use aacmm_core::io::AngleUnit;
use aacmm_core::session::Request;
use aacmm_core::simulate::SphereSettings;

/// An arm file with a probe ball and a simulated sphere file, in a
/// directory of their own.
fn files() -> (CString, CString, std::path::PathBuf) {
    let settings = SphereSettings {
        placements: 4,
        diameter_mm: 25.4,
        ball_diameter_mm: 6.0,
        encoder_rad: 0.005f64.to_radians(),
        probe_mm: 0.01,
        seed: 5,
    };
    sphere_files::files("spheres", &settings)
}

#[test]
fn a_sphere_file_calibrates_as_the_library_does() {
    let (arm, spheres, _dir) = files();
    let mut o = std::ptr::null_mut();
    let mut cal = std::ptr::null_mut();
    // SAFETY: writable slots, live options and NUL-terminated paths.
    let report = unsafe {
        assert_eq!(aacmm_calibrate_options_new(&mut o), AacmmStatus::Ok);
        aacmm_calibrate_options_set_method(o, AACMM_METHOD_LM);
        aacmm_calibrate_options_set_encoder_noise_rad(o, 0.005f64.to_radians());
        aacmm_calibrate_options_set_probe_noise_mm(o, 0.01);
        aacmm_calibrate_options_set_cross_validate(o, 3);
        assert_eq!(
            aacmm_calibrate_options_set_sphere_diameter_mm(o, 0.0254),
            AacmmStatus::InvalidArgument
        );
        let m = last_error();
        assert!(
            m.starts_with("sphere_diameter_mm:") && m.contains("metres"),
            "{m}"
        );
        assert_eq!(
            aacmm_calibrate_options_set_sphere_diameter_mm(o, 25.4),
            AacmmStatus::Ok
        );
        assert_eq!(
            aacmm_calibrate_options_set_spheres_file(o, spheres.as_ptr()),
            AacmmStatus::Ok
        );
        let status = aacmm_calibrate_files(
            arm.as_ptr(),
            std::ptr::null(),
            std::ptr::null(),
            AACMM_ANGLE_DEG,
            o,
            &mut cal,
        );
        assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
        let mut len = 0;
        aacmm_calibration_report(cal, std::ptr::null_mut(), 0, &mut len);
        let mut buf = vec![0u8; len + 1];
        let status = aacmm_calibration_report(cal, buf.as_mut_ptr().cast(), buf.len(), &mut len);
        assert_eq!(status, AacmmStatus::Ok);
        aacmm_calibration_free(cal);
        aacmm_calibrate_options_free(o);
        String::from_utf8(buf[..len].to_vec()).unwrap()
    };
    // The library's session on the same files: the same bytes.
    let path = |c: &CString| std::path::PathBuf::from(c.to_str().unwrap());
    let noise = aacmm_core::session::user_noise(Some(0.005), Some(0.01), 0.001, None);
    let (_, ours) = Request::read_spheres_only(path(&arm), path(&spheres), AngleUnit::Deg)
        .unwrap()
        .sphere_diameter(Some(25.4))
        .noise(noise)
        .method("lm")
        .cross_validate(Some(3))
        .run()
        .unwrap();
    assert_eq!(report, ours.to_json());
    let theirs: serde_json::Value = serde_json::from_str(&report).unwrap();
    let folds = &theirs["validation"]["cross_validation"]["folds"];
    assert_eq!(folds[2]["terms"][0]["term"], "spheres");
}
