//! The C API under hostile use (issue 29): an output that shares memory
//! with an input (or another output) is refused before anything is
//! written; absurd lengths are length errors, never overlaps or internal
//! errors; and work sized by the input does not abort the host when memory
//! runs out (a child process under an address-space limit survives with a
//! status).

// Calling the C ABI from Rust takes raw pointers, as C does.
#![allow(unsafe_code)]

mod common;
use common::last_error;

use std::ffi::{CString, c_char};
use std::process::Command;

use aacmm_capi::{
    AACMM_ANGLE_DEG, AacmmArm, AacmmCalibrateOptions, AacmmCalibration, AacmmReferenceLength,
    AacmmStatus, aacmm_arm_free, aacmm_arm_from_params, aacmm_arm_params, aacmm_calibrate,
    aacmm_calibrate_files, aacmm_calibrate_options_free, aacmm_calibrate_options_new,
    aacmm_calibrate_options_set_encoder_noise_rad, aacmm_calibrate_options_set_fix,
    aacmm_calibrate_options_set_length_weight, aacmm_calibrate_options_set_positions,
    aacmm_calibrate_options_set_prior, aacmm_calibrate_options_set_probe_noise_mm,
    aacmm_calibrate_options_set_seed, aacmm_calibration_arm, aacmm_calibration_fixed,
    aacmm_calibration_free, aacmm_calibration_params, aacmm_calibration_report,
    aacmm_calibration_sigmas, aacmm_calibration_verdict, aacmm_jacobians, aacmm_last_error_message,
    aacmm_positions,
};
use aacmm_core::params::DhParams;

/// A failure with `status` whose message contains `expected`.
fn refused(status: AacmmStatus, want: AacmmStatus, expected: &str) {
    let m = last_error();
    assert_eq!(status, want, "{expected}: {m}");
    assert!(m.contains(expected), "expected `{expected}`, got: {m}");
}

fn nominal() -> *mut AacmmArm {
    let params = DhParams::paper_nominal().to_vec();
    let mut arm = std::ptr::null_mut();
    // SAFETY: 27 doubles and a writable out.
    let status = unsafe { aacmm_arm_from_params(6, params.as_ptr(), 27, &mut arm) };
    assert_eq!(status, AacmmStatus::Ok);
    arm
}

/// The shipped paper campaign, calibrated from its files.
fn calibration() -> *mut AacmmCalibration {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let path = |p: &str| CString::new(format!("{root}/{p}")).unwrap();
    let arm = path("examples/paper-table-1.toml");
    let poses = path("examples/paper-campaign/poses.csv");
    let mut cal = std::ptr::null_mut();
    // SAFETY: NUL-terminated paths, default options, a writable out.
    let status = unsafe {
        aacmm_calibrate_files(
            arm.as_ptr(),
            poses.as_ptr(),
            std::ptr::null(),
            AACMM_ANGLE_DEG,
            std::ptr::null(),
            &mut cal,
        )
    };
    assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
    cal
}

/// `aacmm_arm_from_params(6, b, 27, (AacmmArm**)&b[0])` built an arm with
/// a1 = 0 (the slot was NULLed before `b` was read): now refused, `b`
/// untouched.
#[test]
fn an_arm_slot_inside_the_parameters_is_refused() {
    let mut b = DhParams::paper_nominal().to_vec();
    let before = b.clone();
    let slot = b.as_mut_ptr();
    // SAFETY: `slot` points to 27 doubles, room for a pointer; the call
    // must refuse it before writing.
    let status = unsafe { aacmm_arm_from_params(6, slot, 27, slot.cast::<*mut AacmmArm>()) };
    refused(
        status,
        AacmmStatus::InvalidArgument,
        "`params` and `out` overlap",
    );
    assert_eq!(b, before, "nothing written");
    // The slot just after the parameters is fine.
    let mut both = [0.0f64; 28];
    both[..27].copy_from_slice(&before);
    let base = both.as_mut_ptr();
    // SAFETY: 27 doubles, then room for one pointer (8-byte aligned).
    let status = unsafe { aacmm_arm_from_params(6, base, 27, base.add(27).cast()) };
    assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
    // SAFETY: the handle just written there.
    unsafe { aacmm_arm_free(*base.add(27).cast::<*mut AacmmArm>()) };
}

/// `aacmm_calibrate(arm, q, …, (AacmmCalibration**)q)` calibrated as if
/// q[0] = 0: now refused, `q` untouched; so is an out slot inside the arm
/// handle or the lengths.
#[test]
fn a_calibration_slot_inside_an_input_is_refused() {
    let arm = nominal();
    let mut q: Vec<f64> = (0..6 * 9).map(|i| (i as f64 * 0.7).sin()).collect();
    let before = q.clone();
    let points: Vec<u32> = (0..9).map(|i| i / 3).collect();
    let slot = q.as_mut_ptr();
    // SAFETY: the arrays hold their stated lengths; the out slot (inside
    // `q`) must be refused before any write.
    let status = unsafe {
        aacmm_calibrate(
            arm,
            slot,
            q.len(),
            points.as_ptr(),
            9,
            std::ptr::null(),
            0,
            std::ptr::null(),
            slot.cast(),
        )
    };
    refused(
        status,
        AacmmStatus::InvalidArgument,
        "`q` and `out` overlap",
    );
    assert_eq!(q, before, "nothing written");
    let mut lengths = [AacmmReferenceLength {
        point_a: 0,
        point_b: 1,
        distance_mm: 100.0,
        uncertainty_mm: f64::NAN,
    }];
    let in_lengths = lengths.as_mut_ptr();
    // SAFETY: as above, the slot inside `lengths`.
    let status = unsafe {
        aacmm_calibrate(
            arm,
            q.as_ptr(),
            54,
            points.as_ptr(),
            9,
            in_lengths,
            1,
            std::ptr::null(),
            in_lengths.cast(),
        )
    };
    refused(
        status,
        AacmmStatus::InvalidArgument,
        "`lengths` and `out` overlap",
    );
    assert_eq!(lengths[0].point_b, 1);
    // SAFETY: as above, the slot inside the arm handle.
    let status = unsafe {
        aacmm_calibrate(
            arm,
            q.as_ptr(),
            54,
            points.as_ptr(),
            9,
            std::ptr::null(),
            0,
            std::ptr::null(),
            arm.cast(),
        )
    };
    refused(
        status,
        AacmmStatus::InvalidArgument,
        "`start` and `out` overlap",
    );
    // The handle still works: it was not written.
    let mut params = [0.0; 27];
    // SAFETY: a live handle, 27 writable doubles.
    let status = unsafe { aacmm_arm_params(arm, params.as_mut_ptr(), 27) };
    assert_eq!(status, AacmmStatus::Ok);
    assert_eq!(params.to_vec(), DhParams::paper_nominal().to_vec());
    // SAFETY: the handle, not used after.
    unsafe { aacmm_arm_free(arm) };
}

/// `aacmm_calibration_report(c, buf, n, (size_t*)(buf + 16))` returned a
/// garbage length: now refused with the buffer untouched; outputs inside
/// the handle, or overlapping each other, likewise.
#[test]
fn a_length_inside_the_buffer_is_refused() {
    let cal = calibration();
    let mut buf = [0x55u64; 8];
    let bytes = buf.as_mut_ptr().cast::<c_char>();
    // SAFETY: `buf` has 64 writable bytes; the call must refuse before
    // writing.
    let status =
        unsafe { aacmm_calibration_report(cal, bytes, 64, buf.as_mut_ptr().add(2).cast()) };
    refused(
        status,
        AacmmStatus::InvalidArgument,
        "`buf` and `len` overlap",
    );
    assert_eq!(buf, [0x55u64; 8], "nothing written");
    let mut len = 0usize;
    // SAFETY: a live handle, and outputs that must be refused: the usable
    // flag inside the buffer, the length inside the handle.
    unsafe {
        let status = aacmm_calibration_verdict(cal, bytes.cast(), bytes, 64, &mut len);
        refused(
            status,
            AacmmStatus::InvalidArgument,
            "`usable` and `buf` overlap",
        );
        let status = aacmm_calibration_report(cal, bytes, 64, cal.cast());
        refused(
            status,
            AacmmStatus::InvalidArgument,
            "`cal` and `len` overlap",
        );
        let status = aacmm_calibration_arm(cal, cal.cast());
        refused(
            status,
            AacmmStatus::InvalidArgument,
            "`cal` and `out` overlap",
        );
    }
    assert_eq!(buf, [0x55u64; 8], "nothing written");
    // The handle is intact: the report's length is what it was.
    // SAFETY: a live handle and a writable length.
    let status = unsafe { aacmm_calibration_report(cal, std::ptr::null_mut(), 0, &mut len) };
    assert_eq!(status, AacmmStatus::BufferTooSmall);
    assert!(len > 1000, "{len}");
    // SAFETY: the handle, not used after.
    unsafe { aacmm_calibration_free(cal) };
}

/// Outputs of the kernel that overlap the arm handle, or each other.
#[test]
fn kernel_outputs_inside_the_handle_or_each_other_are_refused() {
    let arm = nominal();
    let q = [0.1f64; 6];
    let mut out = [0.0f64; 3 + 81];
    let p = out.as_mut_ptr();
    // SAFETY: a live handle; outputs that must be refused before writing.
    unsafe {
        let status = aacmm_arm_params(arm, arm.cast(), 27);
        refused(
            status,
            AacmmStatus::InvalidArgument,
            "`arm` and `params` overlap",
        );
        let status = aacmm_jacobians(arm, q.as_ptr(), 6, p, 3, p.add(2), 81);
        refused(
            status,
            AacmmStatus::InvalidArgument,
            "`p` and `jac` overlap",
        );
        let status = aacmm_jacobians(arm, q.as_ptr(), 6, p, 3, p.add(3), 81);
        assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
        aacmm_arm_free(arm);
    }
}

/// `q_len = SIZE_MAX − 3` said "`q` and `p` overlap" (the byte span
/// saturated); `lengths_len = SIZE_MAX / 64` was an internal error
/// ("capacity overflow"): both are length errors naming the argument.
#[test]
fn absurd_lengths_are_length_errors() {
    let arm = nominal();
    let q = [0.0f64; 6];
    let mut p = [0.0f64; 3];
    let q_len = usize::MAX - 3;
    assert_eq!(q_len % 6, 0);
    // SAFETY: refused before any pointer is used.
    let status = unsafe { aacmm_positions(arm, q.as_ptr(), q_len, p.as_mut_ptr(), q_len / 2) };
    refused(
        status,
        AacmmStatus::Length,
        "`q`: length 18446744073709551612",
    );
    let lengths = [AacmmReferenceLength {
        point_a: 0,
        point_b: 1,
        distance_mm: 1.0,
        uncertainty_mm: f64::NAN,
    }];
    let mut out = std::ptr::null_mut();
    // SAFETY: refused before `lengths` is read.
    let status = unsafe {
        aacmm_calibrate(
            arm,
            std::ptr::null(),
            0,
            std::ptr::null(),
            0,
            lengths.as_ptr(),
            usize::MAX / 64,
            std::ptr::null(),
            &mut out,
        )
    };
    refused(
        status,
        AacmmStatus::Length,
        "lengths_len = 288230376151711743",
    );
    assert!(out.is_null());
    // SAFETY: the handle, not used after.
    unsafe { aacmm_arm_free(arm) };
}

/// Set in the child process of [`memory_limits_give_a_status`].
const CHILD: &str = "AACMM_CAPI_HOSTILE_MEMORY_CHILD";

/// This process's virtual size, bytes (Linux).
fn virtual_size() -> usize {
    let status = std::fs::read_to_string("/proc/self/status").expect("/proc/self/status");
    let line = status
        .lines()
        .find(|l| l.starts_with("VmSize:"))
        .expect("VmSize");
    let kb: usize = line.split_whitespace().nth(1).unwrap().parse().unwrap();
    kb * 1024
}

/// Caps this process's address space at `headroom` bytes above what it
/// uses now (`prlimit`, util-linux); false when the tool is missing.
fn limit_address_space(headroom: usize) -> bool {
    let limit = virtual_size() + headroom;
    let out = Command::new("prlimit")
        .args(["--pid", &std::process::id().to_string()])
        .arg(format!("--as={limit}:{limit}"))
        .output();
    match out {
        Ok(out) => {
            assert!(out.status.success(), "prlimit: {out:?}");
            true
        }
        Err(_) => false,
    }
}

/// Under an address space 64 MiB above its inputs: 10⁶ positions (whose
/// sin/cos alone took 96 MB before, an abort) succeed; a calibration of
/// 10⁶ touches (hundreds of MB inside the library) is refused with
/// `AACMM_STATUS_OUT_OF_MEMORY`, from arrays and from a 14 MB file; a
/// 256 MiB file of one line is refused for its line. In the child process
/// only.
#[test]
fn memory_limit_child() {
    if std::env::var_os(CHILD).is_none() {
        return;
    }
    let n = 1_000_000;
    let q: Vec<f64> = (0..6 * n).map(|i| (i as f64 * 0.37).sin()).collect();
    let mut p = vec![0.0f64; 3 * n];
    let points: Vec<u32> = (0..n as u32).map(|i| i / 4).collect();
    let arm = nominal();
    let files = hostile_files(n);
    if !limit_address_space(64 << 20) {
        println!("child skipped: no prlimit");
        return;
    }
    // The limit bites: what preparing every pose at once took (the sin
    // and cos of 6·10⁶ readings) cannot be allocated.
    let mut probe: Vec<u8> = Vec::new();
    println!(
        "limit bites {}",
        probe.try_reserve_exact(96_000_000).is_err()
    );
    // SAFETY: a live handle, buffers of the stated lengths.
    let status = unsafe { aacmm_positions(arm, q.as_ptr(), 6 * n, p.as_mut_ptr(), 3 * n) };
    println!("positions {status:?} {}", p[3 * n - 1] != 0.0);
    let mut out = std::ptr::null_mut();
    // SAFETY: as above, and a writable out.
    let status = unsafe {
        aacmm_calibrate(
            arm,
            q.as_ptr(),
            6 * n,
            points.as_ptr(),
            n,
            std::ptr::null(),
            0,
            std::ptr::null(),
            &mut out,
        )
    };
    println!("calibrate {status:?} {}", last_error());
    for (name, poses) in [("big", &files.big), ("endless", &files.endless)] {
        let mut out = std::ptr::null_mut();
        // SAFETY: NUL-terminated paths, default options, a writable out.
        let status = unsafe {
            aacmm_calibrate_files(
                files.arm.as_ptr(),
                poses.as_ptr(),
                std::ptr::null(),
                AACMM_ANGLE_DEG,
                std::ptr::null(),
                &mut out,
            )
        };
        println!("files {name} {status:?} {}", last_error());
    }
    _ = std::fs::remove_dir_all(&files.dir);
    println!("child done");
}

/// The arm file and two poses files for [`memory_limit_child`], as C
/// paths: `big`, `n` valid touches (14 bytes a row: the readings take 4×
/// the file), and `endless`, a 256 MiB file of one line after its header
/// (sparse: no disk is used).
struct HostileFiles {
    dir: std::path::PathBuf,
    arm: CString,
    big: CString,
    endless: CString,
}

fn hostile_files(n: usize) -> HostileFiles {
    let dir = std::env::temp_dir().join(format!("aacmm-capi-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let big = dir.join("big.csv");
    let mut text = String::from("point,q1,q2,q3,q4,q5,q6\n");
    text.push_str(&"A,1,2,3,4,5,6\nA,2,3,4,5,6,7\n".repeat(n / 2));
    std::fs::write(&big, text).unwrap();
    let endless = dir.join("endless.csv");
    std::fs::write(&endless, "point,q1,q2,q3,q4,q5,q6\nA,1").unwrap();
    (std::fs::OpenOptions::new()
        .write(true)
        .open(&endless)
        .unwrap())
    .set_len(256 << 20)
    .unwrap();
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let c = |p: &std::path::Path| CString::new(p.to_str().unwrap()).unwrap();
    HostileFiles {
        dir: dir.clone(),
        arm: CString::new(format!("{root}/examples/paper-table-1.toml")).unwrap(),
        big: c(&big),
        endless: c(&endless),
    }
}

#[test]
fn memory_limits_give_a_status() {
    if std::env::var_os(CHILD).is_some() {
        return;
    }
    let exe = std::env::current_exe().expect("the test binary");
    let out = Command::new(exe)
        .args([
            "--exact",
            "memory_limit_child",
            "--nocapture",
            "--test-threads=1",
        ])
        .env(CHILD, "1")
        .env("MALLOC_ARENA_MAX", "1")
        .output()
        .expect("the test binary runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "the child died: {out:?}\n{stdout}\n{stderr}"
    );
    if stdout.contains("child skipped") {
        eprintln!("skipped: prlimit (util-linux) is not installed");
        return;
    }
    assert!(stdout.contains("child done"), "{stdout}\n{stderr}");
    assert!(stdout.contains("limit bites true"), "{stdout}");
    assert!(stdout.contains("positions Ok true"), "{stdout}");
    assert!(
        stdout.contains("calibrate OutOfMemory aacmm_calibrate: cannot allocate"),
        "{stdout}"
    );
    // A file whose readings need more than the limit: the reader's
    // reservation fails, a status; a file of one endless line: refused
    // for it after 1 MiB, though it is four times the limit.
    assert!(
        stdout.contains("files big OutOfMemory ") && stdout.contains("big.csv: out of memory"),
        "{stdout}"
    );
    assert!(
        stdout.contains("files endless Input ")
            && stdout.contains("endless.csv:2: line longer than 1 MiB"),
        "{stdout}"
    );
}

/// The full length of the last error message, bytes (the copy's return
/// value with no buffer).
fn last_error_len() -> usize {
    // SAFETY: no buffer: only the length is returned.
    unsafe { aacmm_last_error_message(std::ptr::null_mut(), 0) }
}

fn options() -> *mut AacmmCalibrateOptions {
    let mut o = std::ptr::null_mut();
    // SAFETY: a writable out.
    let status = unsafe { aacmm_calibrate_options_new(&mut o) };
    assert_eq!(status, AacmmStatus::Ok);
    o
}

/// The accessors that copy one value per parameter named their length
/// `len` (issue 29, item 7): each names its own argument, as
/// `aacmm_arm_params` does, and writes nothing into a short array.
#[test]
fn parameter_accessors_name_their_own_length() {
    let arm = nominal();
    let cal = calibration();
    let mut d = [0.5f64; 26];
    let mut b = [true; 26];
    // SAFETY: live handles; 26 writable values, one short of 27.
    unsafe {
        let status = aacmm_arm_params(arm, d.as_mut_ptr(), 26);
        refused(status, AacmmStatus::Length, "params_len = 26");
        let status = aacmm_calibration_params(cal, d.as_mut_ptr(), 26);
        refused(status, AacmmStatus::Length, "params_len = 26, expected 27");
        let status = aacmm_calibration_sigmas(cal, d.as_mut_ptr(), 26);
        refused(status, AacmmStatus::Length, "sigma_len = 26, expected 27");
        let status = aacmm_calibration_fixed(cal, b.as_mut_ptr(), 26);
        refused(status, AacmmStatus::Length, "fixed_len = 26, expected 27");
        // An output inside the handle is named by its own name too.
        let status = aacmm_calibration_sigmas(cal, cal.cast(), 27);
        refused(
            status,
            AacmmStatus::InvalidArgument,
            "`cal` and `sigma` overlap",
        );
    }
    assert_eq!((d, b), ([0.5; 26], [true; 26]), "nothing written");
    // SAFETY: the handles, not used after.
    unsafe {
        aacmm_calibration_free(cal);
        aacmm_arm_free(arm);
    }
}

/// A 50 MB text handed to the C API (issue 29, item 3: the message was
/// 50 MB): a refusal echoes at most 80 characters of it and says its
/// length — an option string, a label in a poses file (a line of 50 MB
/// is refused for its length; one of 900 kB is read and its label cut).
#[test]
fn fifty_megabyte_texts_give_short_messages() {
    let huge = CString::new("L".repeat(50_000_000)).unwrap();
    let o = options();
    // SAFETY: live options and a NUL-terminated string.
    unsafe {
        let status = aacmm_calibrate_options_set_fix(o, huge.as_ptr());
        refused(
            status,
            AacmmStatus::InvalidArgument,
            "… (50000000 characters): unknown parameter `LLL",
        );
        assert!(last_error_len() < 600, "{}", last_error_len());
        let status = aacmm_calibrate_options_set_prior(o, huge.as_ptr());
        refused(
            status,
            AacmmStatus::InvalidArgument,
            "(50000000 characters)",
        );
        assert!(last_error_len() < 600, "{}", last_error_len());
        aacmm_calibrate_options_free(o);
    }
    let dir = std::env::temp_dir().join(format!("aacmm-capi-labels-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let arm = CString::new(format!("{root}/examples/paper-table-1.toml")).unwrap();
    for (name, label, expected) in [
        (
            "fifty.csv",
            50_000_000,
            "fifty.csv:2: line longer than 1 MiB",
        ),
        ("nine.csv", 900_000, "(900000 characters) has 2 touches"),
    ] {
        let path = dir.join(name);
        // Two touches that articulate (q6 turns 34°): too few is the fault.
        let l = "L".repeat(label);
        let text = format!("point,q1,q2,q3,q4,q5,q6\n{l},1,2,3,4,5,6\n{l},1,2,3,4,5,40\n");
        std::fs::write(&path, text).unwrap();
        let poses = CString::new(path.to_str().unwrap()).unwrap();
        let mut out = std::ptr::null_mut();
        // SAFETY: NUL-terminated paths, default options, a writable out.
        let status = unsafe {
            aacmm_calibrate_files(
                arm.as_ptr(),
                poses.as_ptr(),
                std::ptr::null(),
                AACMM_ANGLE_DEG,
                std::ptr::null(),
                &mut out,
            )
        };
        refused(status, AacmmStatus::Input, expected);
        assert!(last_error_len() < 600, "{name}: {}", last_error_len());
        assert!(out.is_null());
    }
    _ = std::fs::remove_dir_all(&dir);
}

/// A value of 1e308 was printed as a 309-digit integer (issue 29, item
/// 7): refusals show it as `1e308`; and the same setting has the same
/// bound as in Python and the command line (encoder σ at most 180°, seed
/// at most 2⁶³ − 1, checked when calibrating).
#[test]
fn huge_values_are_shown_short_and_bounded_as_elsewhere() {
    let o = options();
    let arm = nominal();
    // SAFETY: live options; the setters refuse and keep the options.
    unsafe {
        let status = aacmm_calibrate_options_set_probe_noise_mm(o, -1e308);
        refused(
            status,
            AacmmStatus::InvalidArgument,
            "probe_noise_mm = -1e308: must be a finite number ≥ 0",
        );
        let status = aacmm_calibrate_options_set_length_weight(o, -1e308);
        refused(
            status,
            AacmmStatus::InvalidArgument,
            "length_weight = -1e308: must be a finite number > 0",
        );
        let status = aacmm_calibrate_options_set_prior(o, c"length=-1e308mm".as_ptr());
        refused(status, AacmmStatus::InvalidArgument, "(got -1e308 mm)");
        let status = aacmm_calibrate_options_set_prior(o, c"length=1e308mm".as_ptr());
        refused(
            status,
            AacmmStatus::InvalidArgument,
            "tolerance of length = 1e308 mm: above 1e12",
        );
        let q = [0.0f64, 0.1, 0.2, 0.3, 0.4, 0.5].repeat(3);
        let xyz = [0.0, 0.0, 0.0, 100.0, 0.0, 0.0, 0.0, 100.0, 0.0];
        let u = [-1e308, 0.01, 0.01];
        let status = aacmm_calibrate_options_set_positions(
            o,
            6,
            q.as_ptr(),
            q.len(),
            xyz.as_ptr(),
            9,
            std::ptr::null(),
            0,
            std::ptr::null(),
            0,
            u.as_ptr(),
            3,
        );
        refused(status, AacmmStatus::Input, "uncertainty[0] = -1e308: ");
        let status = aacmm_calibrate_options_set_encoder_noise_rad(o, 1e308);
        refused(status, AacmmStatus::InvalidArgument, "is more than 180°");
        assert!(!last_error().contains("0000000000"), "{}", last_error());
        let points: Vec<u32> = (0..9).map(|i| i / 3).collect();
        let q: Vec<f64> = (0..54).map(|i| (i as f64 * 0.7).sin()).collect();
        let mut out = std::ptr::null_mut();
        for (distance_mm, uncertainty_mm, expected) in [
            (
                -1e308,
                f64::NAN,
                "distance_mm = -1e308: must be a positive number",
            ),
            (
                100.0,
                -1e308,
                "uncertainty_mm = -1e308: must be a finite number ≥ 0",
            ),
        ] {
            let lengths = [AacmmReferenceLength {
                point_a: 0,
                point_b: 1,
                distance_mm,
                uncertainty_mm,
            }];
            let status = aacmm_calibrate(
                arm,
                q.as_ptr(),
                54,
                points.as_ptr(),
                9,
                lengths.as_ptr(),
                1,
                std::ptr::null(),
                &mut out,
            );
            refused(status, AacmmStatus::Input, expected);
        }
        // The seed bound of Python's calibrate and simulate.
        assert_eq!(
            aacmm_calibrate_options_set_seed(o, u64::MAX),
            AacmmStatus::Ok
        );
        let status = aacmm_calibrate(
            arm,
            q.as_ptr(),
            54,
            points.as_ptr(),
            9,
            std::ptr::null(),
            0,
            o,
            &mut out,
        );
        refused(
            status,
            AacmmStatus::InvalidArgument,
            "seed = 18446744073709551615: at most 9223372036854775807",
        );
        assert!(out.is_null());
        aacmm_calibrate_options_free(o);
        aacmm_arm_free(arm);
    }
}
