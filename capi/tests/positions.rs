//! Reference positions through the C API: a simulated tracker campaign
//! given as arrays calibrates on the positions alone (the library's report
//! byte for byte, the frames close to the truth), with touches too, and bad
//! arrays are refused with a code and a message naming the argument.

// Calling the C ABI from Rust takes raw pointers, as C does.
#![allow(unsafe_code)]

mod common;
use common::last_error;

use std::ffi::{CStr, CString, c_char};
use std::mem::MaybeUninit;

use aacmm_capi::{
    AACMM_ANGLE_DEG, AACMM_METHOD_LM, AacmmArm, AacmmCalibrateOptions, AacmmCalibration,
    AacmmFrame, AacmmStatus, AacmmTool, aacmm_arm_free, aacmm_arm_from_file, aacmm_arm_from_params,
    aacmm_calibrate, aacmm_calibrate_files, aacmm_calibrate_options_free,
    aacmm_calibrate_options_new, aacmm_calibrate_options_set_encoder_noise_rad,
    aacmm_calibrate_options_set_method, aacmm_calibrate_options_set_position_noise_mm,
    aacmm_calibrate_options_set_position_tools, aacmm_calibrate_options_set_positions,
    aacmm_calibrate_options_set_positions_file, aacmm_calibrate_options_set_probe_noise_mm,
    aacmm_calibration_frame, aacmm_calibration_frame_count, aacmm_calibration_free,
    aacmm_calibration_report, aacmm_calibration_summary, aacmm_calibration_tool,
    aacmm_calibration_tool_count,
};
use aacmm_capi::{
    AACMM_MAP_BASE, AACMM_MAP_FRAME, AACMM_MAP_TOOL, AacmmMapKind, AacmmUncertaintyMap,
    AacmmUncertaintyRegion, aacmm_calibration_uncertainty_map,
    aacmm_calibration_uncertainty_map_at, aacmm_calibration_uncertainty_map_count,
    aacmm_calibration_uncertainty_map_name, aacmm_calibration_uncertainty_map_region,
};
use aacmm_core::dataset::DataSet;
use aacmm_core::domain::{Arm, Positions};
use aacmm_core::identify::identify;
use aacmm_core::io::{AngleUnit, LengthUnit, write_arm};
use aacmm_core::params::DhParams;
use aacmm_core::plan::UncertaintyMap;
use aacmm_core::residuals::{Frame, Noise};
use aacmm_core::session::{CalibrationReport, Request, Sources};
use aacmm_core::simulate::{
    CampaignSettings, ErrorModel, PositionCampaign, PositionSettings, perturbed_tools,
    random_tools, seen_at_markers, simulate, simulate_positions, simulate_tracker,
};

/// A failure with `status` whose message starts with `expected`.
fn refused(status: AacmmStatus, want: AacmmStatus, expected: &str) {
    let m = last_error();
    assert_eq!(status, want, "{expected}: {m}");
    assert!(m.starts_with(expected), "expected `{expected}…`, got: {m}");
}

/// A tracker's noise: 15 µm + 6 µm/m.
fn tracker() -> Noise {
    Noise {
        position_mm: Some(0.015),
        position_mm_per_m: Some(0.006),
        ..Noise::default()
    }
}

fn nominal() -> Arm {
    // As `aacmm_arm_from_params` names it.
    Arm::without_limits("arm", DhParams::paper_nominal())
}

/// Options that free themselves.
struct Options(*mut AacmmCalibrateOptions);

impl Options {
    /// LM (fast from the nominal start) with the tracker's noise.
    fn lm() -> Options {
        let mut o = std::ptr::null_mut();
        // SAFETY: `o` is writable; then live options used by this thread.
        unsafe {
            assert_eq!(aacmm_calibrate_options_new(&mut o), AacmmStatus::Ok);
            assert_eq!(
                aacmm_calibrate_options_set_method(o, AACMM_METHOD_LM),
                AacmmStatus::Ok
            );
            assert_eq!(
                aacmm_calibrate_options_set_position_noise_mm(o, 0.015, 0.006),
                AacmmStatus::Ok
            );
        }
        Options(o)
    }
}

impl Drop for Options {
    fn drop(&mut self) {
        // SAFETY: a live handle, not used after.
        unsafe { aacmm_calibrate_options_free(self.0) };
    }
}

/// An arm handle that frees itself.
struct ArmHandle(*mut AacmmArm);

impl ArmHandle {
    fn of(arm: &Arm) -> ArmHandle {
        let p = arm.params.to_vec();
        let mut out = std::ptr::null_mut();
        // SAFETY: `p` holds `p.len()` doubles; `out` is writable.
        let status = unsafe {
            aacmm_arm_from_params(arm.params.joint_count(), p.as_ptr(), p.len(), &mut out)
        };
        assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
        ArmHandle(out)
    }
}

impl Drop for ArmHandle {
    fn drop(&mut self) {
        // SAFETY: a live handle, not used after.
        unsafe { aacmm_arm_free(self.0) };
    }
}

/// A calibration result that frees itself.
struct Calibration(*mut AacmmCalibration);

impl Drop for Calibration {
    fn drop(&mut self) {
        // SAFETY: a live handle (or NULL), not used after.
        unsafe { aacmm_calibration_free(self.0) };
    }
}

impl Calibration {
    /// `aacmm_calibrate` on `start` with touches `q`/`points` (may be
    /// empty) and the options' positions.
    fn run(
        start: &ArmHandle,
        q: &[f64],
        points: &[u32],
        o: &Options,
    ) -> Result<Calibration, AacmmStatus> {
        let mut out = std::ptr::null_mut();
        // SAFETY: a live arm and options; the arrays as stated (no lengths);
        // a writable output slot.
        let status = unsafe {
            aacmm_calibrate(
                start.0,
                q.as_ptr(),
                q.len(),
                points.as_ptr(),
                points.len(),
                std::ptr::null(),
                0,
                o.0,
                &mut out,
            )
        };
        match status {
            AacmmStatus::Ok => Ok(Calibration(out)),
            s => {
                assert!(out.is_null());
                Err(s)
            }
        }
    }

    fn report(&self) -> String {
        let mut len = 0;
        // SAFETY: a live result; a NULL buffer of length 0 asks the length.
        let status = unsafe { aacmm_calibration_report(self.0, std::ptr::null_mut(), 0, &mut len) };
        assert_eq!(status, AacmmStatus::BufferTooSmall);
        let mut buf = vec![0u8; len + 1];
        // SAFETY: `buf` has `len + 1` writable bytes.
        let status = unsafe {
            aacmm_calibration_report(self.0, buf.as_mut_ptr().cast(), buf.len(), &mut len)
        };
        assert_eq!(status, AacmmStatus::Ok);
        String::from_utf8(buf[..len].to_vec()).unwrap()
    }

    fn successful(&self) -> bool {
        let mut s = MaybeUninit::uninit();
        // SAFETY: a live result; room for the struct, written on success.
        unsafe {
            assert_eq!(
                aacmm_calibration_summary(self.0, s.as_mut_ptr()),
                AacmmStatus::Ok
            );
            s.assume_init().successful
        }
    }

    /// Every frame: name and values.
    fn frames(&self) -> Vec<(String, AacmmFrame)> {
        let mut count = usize::MAX;
        // SAFETY: a live result; `count` is writable.
        let status = unsafe { aacmm_calibration_frame_count(self.0, &mut count) };
        assert_eq!(status, AacmmStatus::Ok);
        (0..count)
            .map(|i| {
                let mut frame = MaybeUninit::uninit();
                let mut buf = [0 as c_char; 64];
                let mut len = 0;
                // SAFETY: a live result; room for the struct; `buf` has 64
                // writable bytes; `len` is writable.
                let status = unsafe {
                    aacmm_calibration_frame(
                        self.0,
                        i,
                        frame.as_mut_ptr(),
                        buf.as_mut_ptr(),
                        buf.len(),
                        &mut len,
                    )
                };
                assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
                // SAFETY: NUL-terminated by the call.
                let name = unsafe { CStr::from_ptr(buf.as_ptr()) };
                assert_eq!(name.to_bytes().len(), len);
                // SAFETY: written on success.
                let frame = unsafe { frame.assume_init() };
                (name.to_str().unwrap().to_string(), frame)
            })
            .collect()
    }
}

/// Position arrays as C holds them.
#[derive(Clone)]
struct Arrays {
    joints: usize,
    q: Vec<f64>,
    xyz: Vec<f64>,
    frames: Vec<u32>,
    names: Vec<CString>,
    uncertainty: Vec<f64>,
}

impl Arrays {
    /// The rows of `p`, with a frame index per row.
    fn of(p: &Positions) -> Arrays {
        Arrays {
            joints: p.joints(),
            q: p.readings().to_vec(),
            xyz: (0..p.len()).flat_map(|i| p.position(i)).collect(),
            frames: (0..p.len()).map(|i| p.frame(i) as u32).collect(),
            names: (p.frames().iter())
                .map(|n| CString::new(n.as_str()).unwrap())
                .collect(),
            uncertainty: Vec::new(),
        }
    }

    /// `aacmm_calibrate_options_set_positions` of these arrays.
    fn set(&self, o: &Options) -> AacmmStatus {
        let names: Vec<*const c_char> = self.names.iter().map(|n| n.as_ptr()).collect();
        // SAFETY: live options; every array holds its stated length; the
        // names are NUL-terminated.
        unsafe {
            aacmm_calibrate_options_set_positions(
                o.0,
                self.joints,
                self.q.as_ptr(),
                self.q.len(),
                self.xyz.as_ptr(),
                self.xyz.len(),
                self.frames.as_ptr(),
                self.frames.len(),
                names.as_ptr(),
                names.len(),
                self.uncertainty.as_ptr(),
                self.uncertainty.len(),
            )
        }
    }

    /// What the C API makes of the arrays: rows `P1`, `P2`, … at lines 1,
    /// 2, ….
    fn rows(&self) -> Positions {
        let mut p = Positions::new(self.joints);
        for i in 0..self.q.len() / self.joints {
            let name = self.names[self.frames[i] as usize].to_str().unwrap();
            let x = [self.xyz[3 * i], self.xyz[3 * i + 1], self.xyz[3 * i + 2]];
            let u = self.uncertainty.get(i).copied().filter(|u| !u.is_nan());
            let q = &self.q[i * self.joints..(i + 1) * self.joints];
            p.push(&format!("P{}", i + 1), name, q, x, u, i + 1);
        }
        p
    }
}

/// The library's calibration of `nominal` on `data` with the options of
/// [`Options::lm`] (and `noise`), named as the C API names arrays.
fn library(data: DataSet, noise: Noise, lengths: bool) -> CalibrationReport {
    let sources = Sources {
        arm_file: "<parameters>".to_string(),
        data_file: "<arrays>".to_string(),
        lengths_file: lengths.then(|| "<arrays>".to_string()),
        warnings: Vec::new(),
    };
    let request = Request::new(nominal(), data)
        .sources(sources)
        .noise(noise)
        .method("lm");
    request.run().unwrap().1
}

/// A true arm with random errors in the parameters a tracker campaign
/// identifies (those `fix = auto` holds stay nominal, so that the frames
/// have a true value to compare with: a base rotation error would move
/// into them), and its campaign: `poses` per frame from `frames` stations.
fn tracker_campaign(seed: u64, poses: usize, frames: usize) -> PositionCampaign {
    let settings = PositionSettings {
        poses,
        frames,
        noise: tracker(),
        seed,
    };
    let nominal = nominal();
    let (mut truth, first) =
        simulate_tracker(&nominal, &ErrorModel::random(1.0, false), &settings).unwrap();
    let data = DataSet::from_positions(first.positions, "sim.csv").unwrap();
    let id = identify(&nominal.params, &data, &tracker(), 1).unwrap();
    for f in &id.fixed {
        *truth.params.get_mut(f.id) = nominal.params.get(f.id);
    }
    simulate_positions(&truth, &settings).unwrap()
}

/// `R` of a rotation vector (rad), row-major.
fn matrix(w: [f64; 3]) -> [f64; 9] {
    let x = [w[0], w[1], w[2], 0.0, 0.0, 0.0];
    let cols: Vec<[f64; 3]> = (0..3)
        .map(|k| {
            let mut e = [0.0; 3];
            e[k] = 1.0;
            Frame::apply(&x, e)
        })
        .collect();
    std::array::from_fn(|m| cols[m % 3][m / 3])
}

/// The angle of `A Bᵀ`, rad.
fn angle_between(a: &[f64; 9], b: &[f64; 9]) -> f64 {
    let trace: f64 = (0..3)
        .map(|i| (0..3).map(|k| a[3 * i + k] * b[3 * i + k]).sum::<f64>())
        .sum();
    ((trace - 1.0) / 2.0).clamp(-1.0, 1.0).acos()
}

/// Positions alone, two tracker stations, from arrays: the library's
/// result byte for byte, usable, each frame within 5 σ of the truth (its
/// rotation matrix the rotation of its rotation vector); then bad arrays
/// are refused, naming the argument, and leave the earlier positions.
#[test]
fn a_tracker_campaign_from_arrays_recovers_its_frames() {
    let c = tracker_campaign(7, 120, 2);
    let arrays = Arrays::of(&c.positions);
    assert_eq!(
        arrays.names,
        [c"station1".to_owned(), c"station2".to_owned()]
    );
    let o = Options::lm();
    assert_eq!(arrays.set(&o), AacmmStatus::Ok, "{}", last_error());
    let start = ArmHandle::of(&nominal());
    let cal = Calibration::run(&start, &[], &[], &o).expect("calibrates");

    // The library on the same rows and options.
    let data = DataSet::from_positions(arrays.rows(), "<arrays>").unwrap();
    let expected = library(data, tracker(), false);
    assert_eq!(cal.report(), expected.to_json());
    assert!(cal.successful(), "{:?}", expected.verdict);

    let frames = cal.frames();
    let records = expected.calibration.frame_records();
    assert_eq!(frames.len(), 2);
    for (((name, f), record), (true_name, x)) in frames.iter().zip(&records).zip(&c.frames) {
        assert_eq!((name, name), (&record.name, true_name));
        // The library's values, bit for bit.
        assert_eq!(f.rotation_deg, record.rotation_deg);
        assert_eq!(f.translation_mm, record.translation_mm);
        assert_eq!(
            Some(f.small_rotation_sigma_deg),
            record.small_rotation_sigma_deg
        );
        assert_eq!(Some(f.translation_sigma_mm), record.translation_sigma_mm);
        assert_eq!(
            f.rotation_matrix,
            matrix(f.rotation_deg.map(f64::to_radians))
        );
        // Close to the truth.
        let truth = matrix([x[0], x[1], x[2]]);
        let angle = angle_between(&f.rotation_matrix, &truth).to_degrees();
        let sigma = (f.small_rotation_sigma_deg.iter()).fold(0.0f64, |m, &s| m.max(s));
        assert!(
            angle <= 5.0 * sigma && angle < 0.01,
            "{name}: rotation {angle}° from the truth, σ {sigma}°"
        );
        for k in 0..3 {
            let (t, s) = (f.translation_mm[k], f.translation_sigma_mm[k]);
            assert!(
                (t - x[3 + k]).abs() <= 5.0 * s && s < 0.5,
                "{name}: t[{k}] = {t} mm, truth {}, σ {s}",
                x[3 + k]
            );
        }
        // An orthonormal R.
        let id = angle_between(&f.rotation_matrix, &f.rotation_matrix);
        assert!(id.abs() < 1e-6, "{id}");
    }

    // The accessors' own errors.
    let mut frame = MaybeUninit::uninit();
    let mut buf = [0x7f as c_char; 4];
    let mut len = 0;
    // SAFETY: a live result; room for the struct; `buf` has 4 writable
    // bytes; `len` is writable.
    unsafe {
        let status = aacmm_calibration_frame(
            cal.0,
            1,
            frame.as_mut_ptr(),
            buf.as_mut_ptr(),
            buf.len(),
            &mut len,
        );
        assert_eq!(status, AacmmStatus::BufferTooSmall);
        assert_eq!(len, "station2".len());
        assert_eq!(CStr::from_ptr(buf.as_ptr()), c"sta");
        assert_eq!(frame.assume_init().rotation_deg, frames[1].1.rotation_deg);
        refused(
            aacmm_calibration_frame(cal.0, 2, frame.as_mut_ptr(), buf.as_mut_ptr(), 4, &mut len),
            AacmmStatus::InvalidArgument,
            "index = 2: the calibration has 2 frame(s)",
        );
        refused(
            aacmm_calibration_frame(
                std::ptr::null(),
                0,
                frame.as_mut_ptr(),
                buf.as_mut_ptr(),
                4,
                &mut len,
            ),
            AacmmStatus::NullPointer,
            "`cal` is NULL",
        );
        refused(
            aacmm_calibration_frame(
                cal.0,
                0,
                std::ptr::null_mut(),
                buf.as_mut_ptr(),
                4,
                &mut len,
            ),
            AacmmStatus::NullPointer,
            "`frame` is NULL",
        );
        refused(
            aacmm_calibration_frame_count(cal.0, std::ptr::null_mut()),
            AacmmStatus::NullPointer,
            "`count` is NULL",
        );
    }

    // The maps as each station sees the probe, and the base frame's.
    let in_frames = &expected.uncertainty_maps_in_frames;
    assert_eq!(in_frames.len(), 2);
    maps_match(cal.0, AACMM_MAP_FRAME, in_frames);
    maps_match(cal.0, AACMM_MAP_BASE, expected.uncertainty_map.as_slice());
    maps_match(cal.0, AACMM_MAP_TOOL, &[]);
    let mut base = MaybeUninit::uninit();
    // SAFETY: a live result; room for the struct.
    let status = unsafe { aacmm_calibration_uncertainty_map(cal.0, base.as_mut_ptr()) };
    assert_eq!(status, AacmmStatus::Ok);
    // SAFETY: written on success.
    let base = unsafe { base.assume_init() };
    assert_eq!(base, map_at(cal.0, AACMM_MAP_BASE, 0));

    // Bad arrays: each refused with its argument named, and the options
    // keep the good positions (the same calibration again at the end).
    let bad = |change: &dyn Fn(&mut Arrays), status: AacmmStatus, message: &str| {
        let mut a = arrays.clone();
        change(&mut a);
        refused(a.set(&o), status, message);
    };
    // A third frame seen once.
    bad(
        &|a| {
            a.names.push(c"solo".to_owned());
            a.frames[5] = 2;
        },
        AacmmStatus::Input,
        "frames[5]: frame `solo` has 1 distinct position(s); its registration",
    );
    bad(
        &|a| a.xyz[3 * 4 + 1] = f64::NAN,
        AacmmStatus::Input,
        "xyz[13] = NaN (y of row 4): positions must be finite numbers (mm)",
    );
    bad(
        &|a| a.q[6 * 3 + 2] = f64::INFINITY,
        AacmmStatus::Input,
        "q[20] = inf: readings must be finite numbers (row 3, joint 3)",
    );
    bad(
        &|a| {
            a.xyz.pop();
        },
        AacmmStatus::Length,
        "xyz_len = 719, expected 720 for the 240 rows of q",
    );
    bad(
        &|a| a.frames[7] = 2,
        AacmmStatus::Input,
        "frames[7] = 2: an index into frame_names, which holds 2",
    );
    bad(
        &|a| a.names.push(c"spare".to_owned()),
        AacmmStatus::Input,
        "frame_names[2] (`spare`): no row of frames names it",
    );
    bad(
        &|a| a.names[1] = c"station1".to_owned(),
        AacmmStatus::Input,
        "frame_names[1]: `station1` is frame_names[0] too",
    );
    // A hostile name is echoed bounded: escaped, cut to 80 characters.
    let hostile = CString::new(format!("s\r\n{}", "x".repeat(9_997))).unwrap();
    bad(
        &|a| a.names.push(hostile.clone()),
        AacmmStatus::Input,
        "frame_names[2] (`s\\r\\nxxx",
    );
    let m = last_error();
    assert!(m.len() < 600 && !m.contains(char::is_control), "{m:.700}");
    assert!(
        m.ends_with("(10000 characters)): no row of frames names it"),
        "{m}"
    );
    bad(
        &|a| {
            a.names[0] = hostile.clone();
            a.names[1] = hostile.clone();
        },
        AacmmStatus::Input,
        "frame_names[1]: `s\\r\\nxxx",
    );
    let m = last_error();
    assert!(m.len() < 600 && !m.contains(char::is_control), "{m:.700}");
    assert!(
        m.contains("(10000 characters) is frame_names[0] too"),
        "{m}"
    );
    bad(
        &|a| a.names[1] = CString::new(vec![0xff]).unwrap(),
        AacmmStatus::InvalidArgument,
        "frame_names[1] is not valid UTF-8",
    );
    bad(
        &|a| a.names[0] = c" ".to_owned(),
        AacmmStatus::Input,
        "frame_names[0]: empty frame name",
    );
    bad(
        &|a| {
            a.uncertainty = vec![f64::NAN; 240];
            a.uncertainty[9] = -0.01;
        },
        AacmmStatus::Input,
        "uncertainty[9] = -0.01: a standard uncertainty per coordinate (mm) is a finite number > 0",
    );
    bad(
        &|a| a.uncertainty = vec![0.01; 3],
        AacmmStatus::Length,
        "uncertainty_len = 3, expected 0 or 240",
    );
    bad(
        &|a| a.joints = 13,
        AacmmStatus::Unsupported,
        "joints = 13: the toolkit computes chains of 1 to 12 joints",
    );
    bad(
        &|a| {
            a.frames.clear();
            a.names.clear();
            // Every row on the x axis.
            for (k, v) in a.xyz.iter_mut().enumerate() {
                if k % 3 != 0 {
                    *v = 0.0;
                }
            }
        },
        AacmmStatus::Input,
        "xyz: the positions of frame `instrument` lie on one line",
    );
    // NULL arrays and names.
    let names: Vec<*const c_char> = vec![c"station1".as_ptr(), std::ptr::null()];
    // SAFETY: live options; NULL pointers are refused before any use; the
    // other arrays hold their stated lengths.
    unsafe {
        refused(
            aacmm_calibrate_options_set_positions(
                o.0,
                6,
                arrays.q.as_ptr(),
                arrays.q.len(),
                std::ptr::null(),
                arrays.xyz.len(),
                std::ptr::null(),
                0,
                std::ptr::null(),
                0,
                std::ptr::null(),
                0,
            ),
            AacmmStatus::NullPointer,
            "`xyz` is NULL",
        );
        refused(
            aacmm_calibrate_options_set_positions(
                o.0,
                6,
                arrays.q.as_ptr(),
                arrays.q.len(),
                arrays.xyz.as_ptr(),
                arrays.xyz.len(),
                arrays.frames.as_ptr(),
                arrays.frames.len(),
                names.as_ptr(),
                names.len(),
                std::ptr::null(),
                0,
            ),
            AacmmStatus::NullPointer,
            "`frame_names[1]` is NULL",
        );
    }
    // A 7-joint set of positions for this 6-joint arm.
    let o7 = Options::lm();
    let seven = Arrays {
        joints: 7,
        q: (arrays.q.chunks(6))
            .flat_map(|r| [r, &[0.0][..]].concat())
            .collect(),
        ..arrays.clone()
    };
    assert_eq!(seven.set(&o7), AacmmStatus::Ok, "{}", last_error());
    refused(
        Calibration::run(&start, &[], &[], &o7).err().unwrap(),
        AacmmStatus::Length,
        "the options' positions (aacmm_calibrate_options_set_positions) have 7 joints per row; \
         the start arm has 6",
    );
    // The good positions stayed.
    let again = Calibration::run(&start, &[], &[], &o).expect("calibrates");
    assert_eq!(again.report(), cal.report());
}

/// Touches and positions from arrays (some with a stated uncertainty) in
/// one fit: the library's report byte for byte; every array length 0
/// removes the positions again.
#[test]
fn touches_and_positions_from_arrays_are_fitted_together() {
    let nominal = nominal();
    let mut settings = CampaignSettings::new(3, ErrorModel::Paper, 6, 8);
    settings.encoder_noise_deg = 0.005;
    settings.probe_noise_mm = 0.01;
    settings.reference_lengths = 0;
    let touches = simulate(&nominal, &settings).unwrap();
    let tracker_settings = PositionSettings {
        poses: 40,
        frames: 1,
        noise: tracker(),
        seed: 11,
    };
    let seen = simulate_positions(&touches.true_arm, &tracker_settings).unwrap();
    let mut arrays = Arrays::of(&seen.positions);
    // Some rows state their uncertainty; NAN: the options' noise applies.
    arrays.uncertainty = (0..arrays.frames.len())
        .map(|i| if i % 3 == 0 { 0.02 } else { f64::NAN })
        .collect();
    let q = touches.poses.readings().to_vec();
    let points: Vec<u32> = (0..touches.poses.len())
        .map(|i| touches.poses.point(i) as u32)
        .collect();

    let o = Options::lm();
    // SAFETY: live options.
    unsafe {
        aacmm_calibrate_options_set_encoder_noise_rad(o.0, 0.005f64.to_radians());
        aacmm_calibrate_options_set_probe_noise_mm(o.0, 0.01);
    }
    assert_eq!(arrays.set(&o), AacmmStatus::Ok, "{}", last_error());
    let start = ArmHandle::of(&nominal);
    let both = Calibration::run(&start, &q, &points, &o).expect("calibrates");

    let noise = Noise {
        encoder_rad: Some(0.005f64.to_radians()),
        probe_mm: Some(0.01),
        ..tracker()
    };
    let data = DataSet::from_arrays(6, &q, &points, &[])
        .unwrap()
        .with_positions(arrays.rows(), "<arrays>")
        .unwrap();
    let expected = library(data.clone(), noise, false);
    assert_eq!(both.report(), expected.to_json());
    let frames = both.frames();
    assert_eq!(frames.len(), 1);
    assert_eq!(frames[0].0, "instrument");

    // No positions again: the touches alone, no frame.
    let none = Arrays {
        joints: 6,
        q: Vec::new(),
        xyz: Vec::new(),
        frames: Vec::new(),
        names: Vec::new(),
        uncertainty: Vec::new(),
    };
    assert_eq!(none.set(&o), AacmmStatus::Ok);
    let alone = Calibration::run(&start, &q, &points, &o).expect("calibrates");
    let expected = library(data.with_position_data(None), noise, false);
    assert_eq!(alone.report(), expected.to_json());
    assert!(alone.frames().is_empty());
}

/// A positions file goes with `aacmm_calibrate_files`, arrays with
/// `aacmm_calibrate`; a NULL poses path needs a positions file.
#[test]
fn files_and_arrays_are_not_mixed() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let arm = CString::new(root.join("examples/paper-table-1.toml").to_str().unwrap()).unwrap();
    let settings = PositionSettings {
        poses: 10,
        frames: 1,
        noise: tracker(),
        seed: 1,
    };
    let (_, c) = simulate_tracker(&nominal(), &ErrorModel::Paper, &settings).unwrap();
    let arrays = Arrays::of(&c.positions);
    let o = Options::lm();
    assert_eq!(arrays.set(&o), AacmmStatus::Ok, "{}", last_error());
    let mut out = std::ptr::null_mut();
    // SAFETY: NUL-terminated paths or NULL, live options, a writable slot.
    unsafe {
        refused(
            aacmm_calibrate_files(
                arm.as_ptr(),
                std::ptr::null(),
                std::ptr::null(),
                AACMM_ANGLE_DEG,
                o.0,
                &mut out,
            ),
            AacmmStatus::InvalidArgument,
            "positions set as arrays (aacmm_calibrate_options_set_positions) go with \
             aacmm_calibrate",
        );
        refused(
            aacmm_calibrate_files(
                arm.as_ptr(),
                std::ptr::null(),
                std::ptr::null(),
                AACMM_ANGLE_DEG,
                std::ptr::null(),
                &mut out,
            ),
            AacmmStatus::NullPointer,
            "`poses_path` is NULL: give a poses file, a positions file",
        );
        let file = c"examples/ur5-tracker/positions-random.csv";
        assert_eq!(
            aacmm_calibrate_options_set_positions_file(o.0, file.as_ptr()),
            AacmmStatus::Ok
        );
    }
    let start = ArmHandle::of(&nominal());
    refused(
        Calibration::run(&start, &[], &[], &o).err().unwrap(),
        AacmmStatus::InvalidArgument,
        "a positions file (aacmm_calibrate_options_set_positions_file) goes with \
         aacmm_calibrate_files",
    );
    assert!(out.is_null());
}

/// The arrays of `rows`' tools as C gives them: per row 0 (the probe) or
/// `k` for `names[k - 1]`, and the names.
fn tool_arrays(rows: &Positions) -> (Vec<u32>, Vec<CString>) {
    let of = (0..rows.len()).map(|i| rows.tool(i) as u32).collect();
    let names = (rows.tools()[1..].iter())
        .map(|n| CString::new(n.as_str()).unwrap())
        .collect();
    (of, names)
}

/// `aacmm_calibrate_options_set_position_tools` of `of` and `names`.
fn set_tools(o: &Options, of: &[u32], names: &[CString]) -> AacmmStatus {
    let names: Vec<*const c_char> = names.iter().map(|n| n.as_ptr()).collect();
    // SAFETY: live options; the arrays hold their stated lengths; the names
    // are NUL-terminated.
    unsafe {
        aacmm_calibrate_options_set_position_tools(
            o.0,
            of.as_ptr(),
            of.len(),
            names.as_ptr(),
            names.len(),
        )
    }
}

/// Positions seen at two markers (an arm file's `[[tool]]`s) through C:
/// set by index, the library's report byte for byte, and each marker's
/// offset and σ read back with `aacmm_calibration_tool` as the library's
/// calibration has them; bad indices and names refused by array and index.
#[test]
fn tools_of_positions_are_set_by_index_and_read_back() {
    let dir = std::env::temp_dir().join(format!("aacmm-capi-tools-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let arm_path = dir.join("arm.toml");
    let start = Arm {
        tools: random_tools(2, 17),
        ..nominal()
    };
    write_arm(&arm_path, &start, LengthUnit::Mm, AngleUnit::Deg).unwrap();
    let mut truth = start.clone();
    truth.tools = perturbed_tools(&start.tools, 0.5, 23);
    let campaign = tracker_campaign(31, 60, 1);
    let rows = seen_at_markers(&truth, &campaign, &tracker(), 1.0, 5).unwrap();
    let arrays = Arrays::of(&rows);
    let (of, names) = tool_arrays(&rows);
    assert_eq!(names.len(), 2);

    let path = CString::new(arm_path.to_str().unwrap()).unwrap();
    let mut handle = std::ptr::null_mut();
    // SAFETY: a NUL-terminated path; a writable slot.
    let status = unsafe { aacmm_arm_from_file(path.as_ptr(), &mut handle) };
    assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
    let arm = ArmHandle(handle);
    let o = Options::lm();
    // Tools before positions: refused.
    refused(
        set_tools(&o, &of, &names),
        AacmmStatus::InvalidArgument,
        "no positions set as arrays",
    );
    assert_eq!(arrays.set(&o), AacmmStatus::Ok, "{}", last_error());
    let mut bad = of.clone();
    bad[3] = 3;
    refused(
        set_tools(&o, &bad, &names),
        AacmmStatus::Input,
        "tools[3] = 3: tool_names holds 2",
    );
    refused(
        set_tools(&o, &of[1..], &names),
        AacmmStatus::Length,
        "tools_len = ",
    );
    let unused = [
        names[0].clone(),
        names[1].clone(),
        CString::new("m9").unwrap(),
    ];
    refused(
        set_tools(&o, &of, &unused),
        AacmmStatus::Input,
        "tool_names[2]: `m9` is no row's",
    );
    let twice = [names[0].clone(), names[0].clone()];
    refused(
        set_tools(&o, &of, &twice),
        AacmmStatus::Input,
        "tool_names[1]: ",
    );
    assert_eq!(
        set_tools(&o, &of, &names),
        AacmmStatus::Ok,
        "{}",
        last_error()
    );
    let cal = Calibration::run(&arm, &[], &[], &o).unwrap();
    assert!(cal.successful());

    // The library on the same rows, named as C names them.
    let mut named = arrays.rows();
    for (i, &k) in of.iter().enumerate() {
        let name = if k == 0 {
            ""
        } else {
            &rows.tools()[k as usize]
        };
        named.set_tool_of(i, name);
    }
    let data = DataSet::from_positions(named, "<arrays>").unwrap();
    let sources = Sources {
        arm_file: arm_path.to_str().unwrap().to_string(),
        data_file: "<arrays>".to_string(),
        lengths_file: None,
        warnings: Vec::new(),
    };
    let read = aacmm_core::io::read_arm(&arm_path).unwrap().0;
    let request = Request::new(read, data)
        .sources(sources)
        .noise(tracker())
        .method("lm");
    let library = request.run().unwrap().1;
    assert_eq!(cal.report(), library.to_json());

    let mut count = 0;
    // SAFETY: a live result; `count` is writable.
    let status = unsafe { aacmm_calibration_tool_count(cal.0, &mut count) };
    assert_eq!(status, AacmmStatus::Ok);
    let expected = library.calibration.tool_estimates();
    assert_eq!(count, expected.len());
    for (i, (name, offset, sigma)) in expected.iter().enumerate() {
        let mut tool = MaybeUninit::<AacmmTool>::uninit();
        let mut buf = [0 as c_char; 32];
        let mut len = 0;
        // SAFETY: a live result; room for the struct and 32 bytes.
        let status = unsafe {
            aacmm_calibration_tool(cal.0, i, tool.as_mut_ptr(), buf.as_mut_ptr(), 32, &mut len)
        };
        assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
        // SAFETY: written on success; NUL-terminated by the call.
        let (tool, got) = unsafe { (tool.assume_init(), CStr::from_ptr(buf.as_ptr())) };
        assert_eq!(got.to_str().unwrap(), name);
        assert_eq!(tool.offset_mm, *offset);
        assert_eq!(Some(tool.sigma_mm), *sigma);
        // Recovered: within 4σ of the true marker.
        let t = truth.tools.iter().find(|t| &t.name == name).unwrap();
        for k in 0..3 {
            let z = (tool.offset_mm[k] - t.offset[k]) / tool.sigma_mm[k];
            assert!(z.abs() < 4.0, "{name}[{k}]: {z}");
        }
    }
    let at_tools = &library.uncertainty_maps_at_tools;
    assert_eq!(at_tools.len(), expected.len());
    maps_match(cal.0, AACMM_MAP_TOOL, at_tools);
    let mut tool = MaybeUninit::<AacmmTool>::uninit();
    // SAFETY: a live result; room for the struct; no name asked.
    let status = unsafe {
        aacmm_calibration_tool(
            cal.0,
            count,
            tool.as_mut_ptr(),
            std::ptr::null_mut(),
            0,
            &mut 0,
        )
    };
    refused(
        status,
        AacmmStatus::InvalidArgument,
        "index = 2: the calibration has 2 tool(s)",
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Map `index` of kind `kind` through the C API (it must exist).
fn map_at(cal: *const AacmmCalibration, kind: AacmmMapKind, index: usize) -> AacmmUncertaintyMap {
    let mut out = MaybeUninit::uninit();
    // SAFETY: a live result; room for the struct.
    let status =
        unsafe { aacmm_calibration_uncertainty_map_at(cal, kind, index, out.as_mut_ptr()) };
    assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
    // SAFETY: written on success.
    unsafe { out.assume_init() }
}

/// The C API's maps of kind `kind` are the library's `maps`, figure for
/// figure and band for band, named by their frame or tool; one index beyond
/// them and an unknown kind are refused.
fn maps_match(cal: *const AacmmCalibration, kind: AacmmMapKind, maps: &[UncertaintyMap]) {
    let mut count = 99;
    // SAFETY: a live result; `count` is writable.
    let status = unsafe { aacmm_calibration_uncertainty_map_count(cal, kind, &mut count) };
    assert_eq!((status, count), (AacmmStatus::Ok, maps.len()));
    for (i, m) in maps.iter().enumerate() {
        let got = map_at(cal, kind, i);
        assert_eq!(
            (got.coverage, got.k_isotropic, got.poses, got.regions),
            (m.coverage, m.k_isotropic, m.poses, m.regions.len())
        );
        assert_eq!(
            (got.rms_mm, got.median_mm, got.max_mm),
            (m.rms_mm, m.median_mm, m.max_mm)
        );
        let mut buf = [0x7f as c_char; 64];
        let mut len = 0;
        // SAFETY: a live result; 64 writable bytes; `len` is writable.
        let status = unsafe {
            aacmm_calibration_uncertainty_map_name(cal, kind, i, buf.as_mut_ptr(), 64, &mut len)
        };
        assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
        // SAFETY: NUL-terminated by the call.
        let name = unsafe { CStr::from_ptr(buf.as_ptr()) }.to_str().unwrap();
        let want = m.frame.as_deref().or(m.tool.as_deref()).unwrap_or("");
        assert_eq!((name, len), (want, want.len()));
        assert_eq!(want.is_empty(), kind == AACMM_MAP_BASE);
        for (b, r) in m.regions.iter().enumerate() {
            let mut out = MaybeUninit::<AacmmUncertaintyRegion>::uninit();
            // SAFETY: a live result; room for the struct.
            let status = unsafe {
                aacmm_calibration_uncertainty_map_region(cal, kind, i, b, out.as_mut_ptr())
            };
            assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
            // SAFETY: written on success.
            let got = unsafe { out.assume_init() };
            assert_eq!(
                (
                    got.reach_from_mm,
                    got.reach_to_mm,
                    got.poses,
                    got.rms_mm,
                    got.max_mm
                ),
                (r.reach_from_mm, r.reach_to_mm, r.poses, r.rms_mm, r.max_mm)
            );
        }
        let mut out = MaybeUninit::<AacmmUncertaintyRegion>::uninit();
        // SAFETY: a live result; room for the struct.
        let status = unsafe {
            aacmm_calibration_uncertainty_map_region(
                cal,
                kind,
                i,
                m.regions.len(),
                out.as_mut_ptr(),
            )
        };
        refused(
            status,
            AacmmStatus::InvalidArgument,
            &format!("index = {}: the uncertainty map has", m.regions.len()),
        );
    }
    let mut out = MaybeUninit::uninit();
    // SAFETY: a live result; room for the struct.
    let status =
        unsafe { aacmm_calibration_uncertainty_map_at(cal, kind, maps.len(), out.as_mut_ptr()) };
    if kind != AACMM_MAP_BASE || !maps.is_empty() {
        refused(
            status,
            AacmmStatus::InvalidArgument,
            &format!(
                "index = {}: the calibration has {} uncertainty map(s)",
                maps.len(),
                maps.len()
            ),
        );
    }
    // SAFETY: a live result; `count` is writable.
    let status = unsafe { aacmm_calibration_uncertainty_map_count(cal, 7, &mut count) };
    refused(
        status,
        AacmmStatus::InvalidArgument,
        "kind = 7: not AACMM_MAP_BASE",
    );
}
