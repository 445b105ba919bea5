//! A robot on a linear track (one prismatic joint before six revolute
//! ones) through the C API: the joint types set on an arm made from its
//! parameters, positions equal to the Rust API's with the slide in mm.

// Calling the C ABI from Rust takes raw pointers, as C does.
#![allow(unsafe_code)]

mod common;
use common::last_error;

use std::ffi::CString;

use aacmm_capi::{
    AacmmArm, AacmmStatus, aacmm_arm_free, aacmm_arm_from_params, aacmm_arm_set_joint_types,
    aacmm_positions,
};
use aacmm_core::io::read_arm;
use aacmm_core::kernel::ArmKernel;

#[test]
fn a_track_arm_is_built_with_its_joint_types() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/track-6r.toml");
    let (track, _) = read_arm(std::path::Path::new(root)).unwrap();
    let params = track.params.to_vec();
    let mut arm: *mut AacmmArm = std::ptr::null_mut();
    // SAFETY: `params` is live for the call, `arm` writable.
    let status = unsafe { aacmm_arm_from_params(7, params.as_ptr(), params.len(), &mut arm) };
    assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
    let q: Vec<f64> = (0..5)
        .flat_map(|i| {
            let mut row = vec![300.0 * i as f64];
            row.extend((1..7).map(|j| 0.3 * (i * j) as f64 - 0.5));
            row
        })
        .collect();
    let positions = |arm: *mut AacmmArm| {
        let mut p = vec![0.0; 15];
        // SAFETY: `q` and `p` are live and of the lengths given.
        let status = unsafe { aacmm_positions(arm, q.as_ptr(), q.len(), p.as_mut_ptr(), p.len()) };
        assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
        p
    };
    let revolute = positions(arm);
    for bad in ["PRRX", "PRRRRR"] {
        let text = CString::new(bad).unwrap();
        // SAFETY: a live handle and a NUL-terminated string.
        let status = unsafe { aacmm_arm_set_joint_types(arm, text.as_ptr()) };
        assert_eq!(status, AacmmStatus::InvalidArgument, "{bad}");
        assert!(last_error().starts_with("types = "), "{}", last_error());
    }
    // Refused types leave the arm as it was.
    assert_eq!(positions(arm), revolute);
    let types = CString::new("PRRRRRR").unwrap();
    // SAFETY: a live handle and a NUL-terminated string.
    let status = unsafe { aacmm_arm_set_joint_types(arm, types.as_ptr()) };
    assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
    let sliding = positions(arm);
    let kernel = ArmKernel::new(&track.params).unwrap();
    let rows: Vec<&[f64]> = q.chunks(7).collect();
    let want: Vec<f64> = kernel.positions_of(&rows).unwrap().concat();
    assert_eq!(sliding, want);
    assert_ne!(sliding, revolute);
    // SAFETY: a live handle, not used afterwards.
    unsafe { aacmm_arm_free(arm) };
}

/// A tracker campaign of the robot on a track, its carriage's readings in
/// mm: given as arrays (rad for the revolute joints, mm for the slide), as
/// a positions file in degrees (`AACMM_ANGLE_DEG`: the slide's column stays
/// mm) and to the Rust API's reader of that file, the same calibration —
/// one that fits the positions to the tracker's noise. A slide read as
/// degrees (×π/180) would put the carriage metres off.
#[test]
fn a_slides_readings_stay_mm_in_arrays_and_in_degree_files() {
    use aacmm_capi::{
        AACMM_ANGLE_DEG, AACMM_METHOD_LM, AacmmCalibrateOptions, AacmmCalibration,
        aacmm_arm_from_file, aacmm_calibrate, aacmm_calibrate_files, aacmm_calibrate_options_free,
        aacmm_calibrate_options_new, aacmm_calibrate_options_set_method,
        aacmm_calibrate_options_set_position_noise_mm, aacmm_calibrate_options_set_positions,
        aacmm_calibrate_options_set_positions_file, aacmm_calibration_free,
        aacmm_calibration_params, aacmm_calibration_report,
    };
    use aacmm_core::io::AngleUnit;
    use aacmm_core::io::positions::write_positions;
    use aacmm_core::residuals::Noise;
    use aacmm_core::session::{CalibrationReport, Request};
    use aacmm_core::simulate::{ErrorModel, PositionSettings, simulate_tracker};

    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/track-6r.toml");
    let arm_path = CString::new(root).unwrap();
    let (track, _) = read_arm(std::path::Path::new(root)).unwrap();
    let noise = Noise {
        position_mm: Some(0.015),
        position_mm_per_m: Some(0.006),
        ..Noise::default()
    };
    let settings = PositionSettings {
        poses: 150,
        frames: 1,
        noise,
        seed: 21,
    };
    let (_, campaign) =
        simulate_tracker(&track, &ErrorModel::random(0.5, false), &settings).unwrap();
    let rows = campaign.positions;
    let slide: Vec<f64> = (0..rows.len()).map(|i| rows.reading(i)[0]).collect();
    assert!(
        slide.iter().any(|&x| x > 100.0),
        "the carriage moves: {slide:?}"
    );
    let dir = std::env::temp_dir().join(format!("aacmm-capi-track-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("positions.csv");
    let mut text = Vec::new();
    write_positions(&mut text, &rows, AngleUnit::Deg).unwrap();
    let text = String::from_utf8(text).unwrap();
    // The carriage's column as it is (mm), the others in degrees.
    let first: Vec<&str> = text.lines().nth(1).unwrap().split(',').collect();
    assert_eq!(first[1].parse::<f64>().unwrap(), slide[0]);
    let q2: f64 = first[2].parse().unwrap();
    assert!((q2.to_radians() - rows.reading(0)[1]).abs() < 1e-12);
    std::fs::write(&file, &text).unwrap();
    let file_c = CString::new(file.to_str().unwrap()).unwrap();

    let mut o: *mut AacmmCalibrateOptions = std::ptr::null_mut();
    let mut arm: *mut AacmmArm = std::ptr::null_mut();
    // SAFETY: writable slots, live handles, arrays of the stated lengths and
    // NUL-terminated strings throughout; each handle freed once at the end.
    let (arrays, files) = unsafe {
        assert_eq!(aacmm_calibrate_options_new(&mut o), AacmmStatus::Ok);
        assert_eq!(
            aacmm_calibrate_options_set_method(o, AACMM_METHOD_LM),
            AacmmStatus::Ok
        );
        let status = aacmm_calibrate_options_set_position_noise_mm(o, 0.015, 0.006);
        assert_eq!(status, AacmmStatus::Ok);
        assert_eq!(
            aacmm_arm_from_file(arm_path.as_ptr(), &mut arm),
            AacmmStatus::Ok
        );
        let q = rows.readings();
        let xyz: Vec<f64> = (0..rows.len()).flat_map(|i| rows.position(i)).collect();
        let status = aacmm_calibrate_options_set_positions(
            o,
            7,
            q.as_ptr(),
            q.len(),
            xyz.as_ptr(),
            xyz.len(),
            std::ptr::null(),
            0,
            std::ptr::null(),
            0,
            std::ptr::null(),
            0,
        );
        assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
        let mut by_arrays: *mut AacmmCalibration = std::ptr::null_mut();
        let (no_q, no_points, no_lengths) = (std::ptr::null(), std::ptr::null(), std::ptr::null());
        let status = aacmm_calibrate(arm, no_q, 0, no_points, 0, no_lengths, 0, o, &mut by_arrays);
        assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
        let status = aacmm_calibrate_options_set_positions_file(o, file_c.as_ptr());
        assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
        let mut by_file: *mut AacmmCalibration = std::ptr::null_mut();
        let status = aacmm_calibrate_files(
            arm_path.as_ptr(),
            std::ptr::null(),
            std::ptr::null(),
            AACMM_ANGLE_DEG,
            o,
            &mut by_file,
        );
        assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
        let read = |cal: *mut AacmmCalibration| {
            let mut params = vec![0.0; 31];
            let status = aacmm_calibration_params(cal, params.as_mut_ptr(), params.len());
            assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
            let mut len = 0;
            let status = aacmm_calibration_report(cal, std::ptr::null_mut(), 0, &mut len);
            assert_eq!(status, AacmmStatus::BufferTooSmall);
            let mut buf = vec![0u8; len + 1];
            let status =
                aacmm_calibration_report(cal, buf.as_mut_ptr().cast(), buf.len(), &mut len);
            assert_eq!(status, AacmmStatus::Ok);
            aacmm_calibration_free(cal);
            let json = String::from_utf8(buf[..len].to_vec()).unwrap();
            (params, CalibrationReport::from_json(&json).unwrap())
        };
        let out = (read(by_arrays), read(by_file));
        aacmm_arm_free(arm);
        aacmm_calibrate_options_free(o);
        out
    };
    let library = Request::read_positions_only(root, &file, AngleUnit::Deg)
        .unwrap()
        .noise(noise)
        .method("lm")
        .run()
        .unwrap()
        .1;
    std::fs::remove_dir_all(&dir).ok();
    let want = library.calibration.params.to_vec();
    for (name, (params, report)) in [("arrays", &arrays), ("file", &files)] {
        for (c, (a, b)) in params.iter().zip(&want).enumerate() {
            assert!(
                (a - b).abs() <= 1e-9 * b.abs().max(1.0),
                "{name}: column {c}: {a} vs {b}"
            );
        }
        assert!(report.verdict.usable, "{name}: {:?}", report.verdict);
        let after = report
            .validation
            .fitted
            .after
            .positions
            .as_ref()
            .unwrap()
            .mean;
        assert!(after < 0.05, "{name}: fitted positions off by {after} mm");
    }
}
