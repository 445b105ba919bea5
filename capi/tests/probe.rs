//! Probe qualification through the C API (`aacmm_qualify_probe`): the
//! library's qualification figure for figure and its qualified arm, a loose
//! stylus refused in C's words with no arm to use, and bad options and an
//! unknown probe refused with a code and a message.

// Calling the C ABI from Rust takes raw pointers, as C does.
#![allow(unsafe_code)]

mod common;
use common::last_error;
#[path = "common/sphere_files.rs"]
mod sphere_files;
use sphere_files::arm;

use std::ffi::{CString, c_char};

use aacmm_capi::{
    AACMM_ANGLE_DEG, AacmmArm, AacmmProbeFigures, AacmmProbeOptions, AacmmProbeQualification,
    AacmmStatus, aacmm_arm_free, aacmm_arm_from_file, aacmm_arm_params, aacmm_param_count,
    aacmm_probe_options_free, aacmm_probe_options_new, aacmm_probe_options_set_limits,
    aacmm_probe_options_set_noise, aacmm_probe_options_set_tool, aacmm_probe_qualification_arm,
    aacmm_probe_qualification_figures, aacmm_probe_qualification_free,
    aacmm_probe_qualification_refusal, aacmm_probe_qualification_refusal_count,
    aacmm_probe_qualification_warning, aacmm_probe_qualification_warning_count,
    aacmm_qualify_probe,
};
use aacmm_core::io::AngleUnit;
use aacmm_core::residuals::Noise;
use aacmm_core::session::Spelling;
use aacmm_core::session::probe::{ProbeSettings, qualify_probe};
use aacmm_core::simulate::SphereSettings;

const ENCODER_RAD: f64 = 0.001 * std::f64::consts::PI / 180.0;
const PROBE_MM: f64 = 0.005;

/// The arm file and one sphere probed by that very arm with the seating
/// noise `probe_mm`, in a directory of their own.
fn files(name: &str, probe_mm: f64) -> (CString, CString, std::path::PathBuf) {
    let settings = SphereSettings {
        placements: 1,
        diameter_mm: 25.4,
        ball_diameter_mm: 6.0,
        encoder_rad: ENCODER_RAD,
        probe_mm,
        seed: 5,
    };
    sphere_files::files(&format!("probe-{name}"), &settings)
}

/// Options for the 25.4 mm sphere at the stated noise.
fn options() -> *mut AacmmProbeOptions {
    let mut o: *mut AacmmProbeOptions = std::ptr::null_mut();
    // SAFETY: valid out pointer; a live handle after.
    unsafe {
        assert_eq!(aacmm_probe_options_new(25.4, &mut o), AacmmStatus::Ok);
        assert_eq!(
            aacmm_probe_options_set_noise(o, ENCODER_RAD, PROBE_MM),
            AacmmStatus::Ok
        );
    }
    o
}

/// The qualification of `spheres` by the arm file `arm_path`.
fn qualify(
    arm_path: &CString,
    spheres: &CString,
    o: *const AacmmProbeOptions,
) -> (AacmmStatus, *mut AacmmProbeQualification) {
    let mut arm: *mut AacmmArm = std::ptr::null_mut();
    let mut q: *mut AacmmProbeQualification = std::ptr::null_mut();
    // SAFETY: NUL-terminated paths, valid out pointers, live handles.
    unsafe {
        assert_eq!(
            aacmm_arm_from_file(arm_path.as_ptr(), &mut arm),
            AacmmStatus::Ok
        );
        let status = aacmm_qualify_probe(arm, spheres.as_ptr(), AACMM_ANGLE_DEG, o, &mut q);
        aacmm_arm_free(arm);
        (status, q)
    }
}

fn figures(q: *const AacmmProbeQualification) -> AacmmProbeFigures {
    let mut f = std::mem::MaybeUninit::<AacmmProbeFigures>::uninit();
    // SAFETY: a live handle; `f` writable.
    unsafe {
        assert_eq!(
            aacmm_probe_qualification_figures(q, f.as_mut_ptr()),
            AacmmStatus::Ok
        );
        f.assume_init()
    }
}

#[test]
fn a_probe_qualifies_as_the_library_qualifies_it() {
    let (arm_path, spheres, dir) = files("good", PROBE_MM);
    let o = options();
    let (status, q) = qualify(&arm_path, &spheres, o);
    assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
    let f = figures(q);
    let rows = aacmm_core::io::spheres::read_spheres(
        std::path::Path::new(spheres.to_str().unwrap()),
        AngleUnit::Deg,
        &arm(),
    )
    .unwrap()
    .0;
    let settings = ProbeSettings {
        tool: "probe".into(),
        sphere_diameter_mm: 25.4,
        noise: Noise {
            encoder_rad: Some(ENCODER_RAD),
            probe_mm: Some(PROBE_MM),
            ..Noise::default()
        },
        tolerance_mm: 0.05,
        max_form_mm: None,
        spelling: Spelling::C,
    };
    let file = aacmm_core::io::source_name(std::path::Path::new(spheres.to_str().unwrap()));
    let want = qualify_probe(&arm(), rows, &file, &settings).unwrap();
    assert!(f.usable && want.usable());
    assert_eq!(f.offset_mm, want.offset);
    assert_eq!(f.offset_sigma_mm, want.offset_sigma);
    assert_eq!(f.ball_diameter_mm, want.ball_diameter_mm);
    assert_eq!(f.points, 25);
    // The qualified arm: the library's, its probe moved.
    let mut qualified: *mut AacmmArm = std::ptr::null_mut();
    let n = aacmm_param_count(6);
    let mut params = vec![0.0; n];
    // SAFETY: live handles, valid out pointers, `params` has n slots.
    unsafe {
        assert_eq!(
            aacmm_probe_qualification_arm(q, &mut qualified),
            AacmmStatus::Ok
        );
        assert_eq!(
            aacmm_arm_params(qualified, params.as_mut_ptr(), n),
            AacmmStatus::Ok
        );
        aacmm_arm_free(qualified);
        aacmm_probe_qualification_free(q);
        aacmm_probe_options_free(o);
    }
    let want_arm = want.qualified_arm(&arm());
    assert_eq!(&params[n - 3..], &want_arm.params.probe[..]);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn a_loose_stylus_is_refused_in_cs_words_and_gives_no_arm() {
    let (arm_path, spheres, dir) = files("loose", 10.0 * PROBE_MM);
    let o = options();
    let (status, q) = qualify(&arm_path, &spheres, o);
    assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
    assert!(!figures(q).usable);
    let mut count = 0usize;
    let mut buf = [0 as c_char; 2048];
    let mut len = 0usize;
    let mut arm: *mut AacmmArm = std::ptr::null_mut();
    // SAFETY: live handles, valid out pointers, `buf` writable.
    unsafe {
        assert_eq!(
            aacmm_probe_qualification_refusal_count(q, &mut count),
            AacmmStatus::Ok
        );
        assert!(count >= 1);
        let s = aacmm_probe_qualification_refusal(q, 0, buf.as_mut_ptr(), buf.len(), &mut len);
        assert_eq!(s, AacmmStatus::Ok);
        let text = std::ffi::CStr::from_ptr(buf.as_ptr())
            .to_string_lossy()
            .into_owned();
        assert!(!text.contains("--"), "{text}");
        let s = aacmm_probe_qualification_refusal(q, count, buf.as_mut_ptr(), buf.len(), &mut len);
        assert_eq!(s, AacmmStatus::InvalidArgument);
        assert_eq!(
            aacmm_probe_qualification_arm(q, &mut arm),
            AacmmStatus::NotAvailable
        );
        assert!(arm.is_null());
        aacmm_probe_qualification_free(q);
        aacmm_probe_options_free(o);
    }
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn bad_options_and_an_unknown_probe_are_refused_by_name() {
    let mut o: *mut AacmmProbeOptions = std::ptr::null_mut();
    // SAFETY: valid out pointer.
    let s = unsafe { aacmm_probe_options_new(0.0254, &mut o) };
    assert_eq!(s, AacmmStatus::InvalidArgument);
    assert!(last_error().contains("metres"), "{}", last_error());
    let o = options();
    // SAFETY: a live handle.
    unsafe {
        assert_eq!(
            aacmm_probe_options_set_noise(o, -1.0, 0.0),
            AacmmStatus::InvalidArgument
        );
        assert_eq!(
            aacmm_probe_options_set_limits(o, f64::NAN, 0.0),
            AacmmStatus::InvalidArgument
        );
        assert!(last_error().contains("tolerance_mm"), "{}", last_error());
        let short = CString::new("short").unwrap();
        assert_eq!(
            aacmm_probe_options_set_tool(o, short.as_ptr()),
            AacmmStatus::Ok
        );
    }
    let (arm_path, spheres, dir) = files("unknown", PROBE_MM);
    let (status, q) = qualify(&arm_path, &spheres, o);
    assert_eq!(status, AacmmStatus::InvalidArgument);
    assert!(q.is_null());
    assert!(last_error().contains("short"), "{}", last_error());
    // SAFETY: a live handle.
    unsafe { aacmm_probe_options_free(o) };
    std::fs::remove_dir_all(dir).ok();
}

/// An arm file whose probe is 0.2 mm off the one that probed: qualified,
/// with the tip's move beyond the 0.05 mm tolerance a warning.
#[test]
fn a_moved_tip_is_qualified_with_a_warning() {
    let (_, spheres, dir) = files("moved", PROBE_MM);
    let mut moved = arm();
    moved.params.probe[2] += 0.2;
    let path = dir.join("moved.toml");
    let text = aacmm_core::io::arm_to_toml(&moved, aacmm_core::io::LengthUnit::Mm, AngleUnit::Deg);
    std::fs::write(&path, text).unwrap();
    let arm_path = CString::new(path.to_str().unwrap()).unwrap();
    let o = options();
    let (status, q) = qualify(&arm_path, &spheres, o);
    assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
    let f = figures(q);
    assert!(f.usable && (f.moved_mm - 0.2).abs() < 0.02, "{f:?}");
    let (mut count, mut len) = (0usize, 0usize);
    let mut buf = [0 as c_char; 1024];
    // SAFETY: live handles, valid out pointers, `buf` writable.
    unsafe {
        assert_eq!(
            aacmm_probe_qualification_warning_count(q, &mut count),
            AacmmStatus::Ok
        );
        assert_eq!(count, 1);
        let s = aacmm_probe_qualification_warning(q, 0, buf.as_mut_ptr(), buf.len(), &mut len);
        assert_eq!(s, AacmmStatus::Ok);
        let text = std::ffi::CStr::from_ptr(buf.as_ptr())
            .to_string_lossy()
            .into_owned();
        assert!(text.contains("the tip moved"), "{text}");
        aacmm_probe_qualification_free(q);
        aacmm_probe_options_free(o);
    }
    std::fs::remove_dir_all(dir).ok();
}
