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
