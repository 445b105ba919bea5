//! Data without articulation through the C API: once a panic in the
//! identifiability analysis (status 99, with the panic message and a
//! backtrace on the host's stderr), now an input error naming the file.

// Calling the C ABI from Rust takes raw pointers, as C does.
#![allow(unsafe_code)]

use std::ffi::{CStr, CString, c_char};
use std::path::Path;

use aacmm_capi::{AACMM_ANGLE_DEG, AacmmStatus, aacmm_calibrate_files, aacmm_last_error_message};

/// The shipped campaign's first row of each socket, repeated ten times.
fn static_poses() -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join("examples/paper-campaign/poses.csv")).unwrap();
    let mut lines = text.lines();
    let mut out = format!("{}\n", lines.next().unwrap());
    let mut seen = Vec::new();
    for line in lines {
        let label = line.split(',').next().unwrap().to_string();
        if !seen.contains(&label) {
            seen.push(label);
            out.push_str(&format!("{line}\n").repeat(10));
        }
    }
    out
}

#[test]
fn static_data_is_an_input_error() {
    let dir = std::env::temp_dir().join(format!("aacmm-capi-static-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let poses = dir.join("static.csv");
    std::fs::write(&poses, static_poses()).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let arm = CString::new(root.join("examples/paper-table-1.toml").to_str().unwrap()).unwrap();
    let poses_c = CString::new(poses.to_str().unwrap()).unwrap();
    let mut out = std::ptr::null_mut();
    // SAFETY: NUL-terminated paths, a NULL lengths path (none), NULL
    // options (the defaults) and an output slot.
    let status = unsafe {
        aacmm_calibrate_files(
            arm.as_ptr(),
            poses_c.as_ptr(),
            std::ptr::null(),
            AACMM_ANGLE_DEG,
            std::ptr::null(),
            &mut out,
        )
    };
    let mut buf = [0 as c_char; 512];
    // SAFETY: `buf` has 512 writable bytes.
    unsafe { aacmm_last_error_message(buf.as_mut_ptr(), buf.len()) };
    // SAFETY: NUL-terminated by the call.
    let message = unsafe { CStr::from_ptr(buf.as_ptr()) }.to_string_lossy();
    assert_eq!(status, AacmmStatus::Input, "{message}");
    assert!(out.is_null());
    assert!(message.contains("static.csv: no articulation"), "{message}");
    let _ = std::fs::remove_dir_all(&dir);
}
