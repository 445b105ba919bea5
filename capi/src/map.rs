//! A calibration's uncertainty map: the predicted position uncertainty over
//! a sampled workspace (the report's `uncertainty_map`), as plain structs.

use std::ffi::c_char;

use aacmm_core::plan::UncertaintyMap;

use crate::calibrate::{AacmmCalibration, count_out, result, text_out};
use crate::error::{AacmmStatus, Error, guard};
use crate::ptr::{self, Args};

/// Which of a calibration's uncertainty maps: `AACMM_MAP_BASE` (the arm's
/// base frame, at its probe: the report's `uncertainty_map`, at most one),
/// `AACMM_MAP_FRAME` (one per fitted instrument frame, with its
/// registration: `uncertainty_maps_in_frames`) or `AACMM_MAP_TOOL` (one per
/// tool point whose offset was fitted: `uncertainty_maps_at_tools`).
pub type AacmmMapKind = u32;

/// The base frame's map, at the probe.
pub const AACMM_MAP_BASE: AacmmMapKind = 0;

/// The maps as each fitted instrument frame sees the probe.
pub const AACMM_MAP_FRAME: AacmmMapKind = 1;

/// The maps at each fitted tool point.
pub const AACMM_MAP_TOOL: AacmmMapKind = 2;

/// A calibration's uncertainty map, for
/// `aacmm_calibration_uncertainty_map`: the radius that holds the
/// calibrated probe position's error with `coverage` (95 %) probability,
/// from the covariance of the fitted geometry, over `poses` poses drawn
/// within the arm's joint limits (or the ranges the campaign turned the
/// joints through); the report's `uncertainty_map`, whose `workspace` says
/// which, and whose `points` hold the poses of its figure.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AacmmUncertaintyMap {
    /// Probability each radius covers (0.95).
    pub coverage: f64,
    /// The radius of an isotropic 3-D error in units of its per-coordinate
    /// σ (2.80: a 3-D error needs more than the 2 σ of one coordinate).
    pub k_isotropic: f64,
    /// Poses sampled.
    pub poses: usize,
    /// RMS of the radius over the poses, mm.
    pub rms_mm: f64,
    /// Median of the radius, mm.
    pub median_mm: f64,
    /// Largest radius, mm.
    pub max_mm: f64,
    /// Bands of distance from the shoulder the poses are summarised in
    /// (`aacmm_calibration_uncertainty_region`).
    pub regions: usize,
}

/// One band of distance from the shoulder (the base axis at the first
/// joint's height) of an uncertainty map, for
/// `aacmm_calibration_uncertainty_region`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AacmmUncertaintyRegion {
    /// Distance of the probe from the shoulder, from (mm).
    pub reach_from_mm: f64,
    /// … to (mm).
    pub reach_to_mm: f64,
    /// Poses in the band.
    pub poses: usize,
    /// RMS of the 95 % radius, mm (0 for an empty band).
    pub rms_mm: f64,
    /// Largest radius, mm.
    pub max_mm: f64,
}

/// The maps of kind `kind` of `cal` (the base frame's: none or one).
fn maps_of(cal: &AacmmCalibration, kind: AacmmMapKind) -> Result<&[UncertaintyMap], Error> {
    let r = &cal.report;
    match kind {
        AACMM_MAP_BASE => Ok(r.uncertainty_map.as_slice()),
        AACMM_MAP_FRAME => Ok(&r.uncertainty_maps_in_frames),
        AACMM_MAP_TOOL => Ok(&r.uncertainty_maps_at_tools),
        _ => Err(Error::invalid(format!(
            "kind = {kind}: not AACMM_MAP_BASE (0), AACMM_MAP_FRAME (1) or AACMM_MAP_TOOL (2)"
        ))),
    }
}

/// Map `index` of kind `kind` of `cal`: `AACMM_STATUS_NOT_AVAILABLE` for
/// the base frame's when the calibration has none, an invalid argument for
/// an index beyond the others.
fn map_at(
    cal: &AacmmCalibration,
    kind: AacmmMapKind,
    index: usize,
) -> Result<&UncertaintyMap, Error> {
    let maps = maps_of(cal, kind)?;
    if kind == AACMM_MAP_BASE && maps.is_empty() && index == 0 {
        return Err(Error::new(
            AacmmStatus::NotAvailable,
            "the calibration has no uncertainty map: the covariance of its free geometry \
             is not finite",
        ));
    }
    maps.get(index).ok_or_else(|| {
        Error::invalid(format!(
            "index = {index}: the calibration has {} uncertainty map(s) of kind {kind}",
            maps.len()
        ))
    })
}

/// A map's figures as C's struct.
fn summary(m: &UncertaintyMap) -> AacmmUncertaintyMap {
    AacmmUncertaintyMap {
        coverage: m.coverage,
        k_isotropic: m.k_isotropic,
        poses: m.poses,
        rms_mm: m.rms_mm,
        median_mm: m.median_mm,
        max_mm: m.max_mm,
        regions: m.regions.len(),
    }
}

/// Band `index` of map `m` as C's struct, or an invalid argument.
fn region(m: &UncertaintyMap, index: usize) -> Result<AacmmUncertaintyRegion, Error> {
    let Some(r) = m.regions.get(index) else {
        return Err(Error::invalid(format!(
            "index = {index}: the uncertainty map has {} region(s)",
            m.regions.len()
        )));
    };
    Ok(AacmmUncertaintyRegion {
        reach_from_mm: r.reach_from_mm,
        reach_to_mm: r.reach_to_mm,
        poses: r.poses,
        rms_mm: r.rms_mm,
        max_mm: r.max_mm,
    })
}

/// The calibration's uncertainty map into `*out`. Returns
/// `AACMM_STATUS_NOT_AVAILABLE` (and leaves `*out` as it was) when the
/// calibration has none: its covariance is not finite.
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `out` is `NULL` or points to
/// writable memory for the struct.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_uncertainty_map(
    cal: *const AacmmCalibration,
    out: *mut AacmmUncertaintyMap,
) -> AacmmStatus {
    // SAFETY: by the contract.
    unsafe { aacmm_calibration_uncertainty_map_at(cal, AACMM_MAP_BASE, 0, out) }
}

/// The number of bands of the calibration's uncertainty map into `*count`
/// (0 when it has no map).
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `count` is `NULL` or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_uncertainty_region_count(
    cal: *const AacmmCalibration,
    count: *mut usize,
) -> AacmmStatus {
    // SAFETY: by the contract.
    unsafe {
        count_out((cal, "cal"), count, |c| {
            Ok((c.report.uncertainty_map.as_ref()).map_or(0, |m| m.regions.len()))
        })
    }
}

/// Band `index` of the calibration's uncertainty map (`0 ≤ index <
/// aacmm_calibration_uncertainty_region_count`, nearest the shoulder first)
/// into `*out`. Returns `AACMM_STATUS_NOT_AVAILABLE` when the calibration
/// has no map, `AACMM_STATUS_INVALID_ARGUMENT` for an index out of range
/// (`*out` is then left as it was).
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `out` is `NULL` or points to
/// writable memory for the struct.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_uncertainty_region(
    cal: *const AacmmCalibration,
    index: usize,
    out: *mut AacmmUncertaintyRegion,
) -> AacmmStatus {
    // SAFETY: by the contract.
    unsafe { aacmm_calibration_uncertainty_map_region(cal, AACMM_MAP_BASE, 0, index, out) }
}

/// The number of uncertainty maps of kind `kind` (`AACMM_MAP_BASE`,
/// `AACMM_MAP_FRAME`, `AACMM_MAP_TOOL`) into `*count`: 0 or 1 for the base
/// frame's, one per fitted instrument frame, one per fitted tool point.
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `count` is `NULL` or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_uncertainty_map_count(
    cal: *const AacmmCalibration,
    kind: AacmmMapKind,
    count: *mut usize,
) -> AacmmStatus {
    // SAFETY: by the contract.
    unsafe { count_out((cal, "cal"), count, |c| Ok(maps_of(c, kind)?.len())) }
}

/// Uncertainty map `index` of kind `kind` (`0 ≤ index <
/// aacmm_calibration_uncertainty_map_count`, in the report's order) into
/// `*out`; for the base frame's, as `aacmm_calibration_uncertainty_map`.
/// A frame's radii include its registration's uncertainty, a tool's its
/// offset's. `AACMM_STATUS_INVALID_ARGUMENT` for an unknown kind or an
/// index out of range (`*out` is then left as it was).
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `out` is `NULL` or points to
/// writable memory for the struct.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_uncertainty_map_at(
    cal: *const AacmmCalibration,
    kind: AacmmMapKind,
    index: usize,
    out: *mut AacmmUncertaintyMap,
) -> AacmmStatus {
    guard(|| {
        Args::new().object("cal", cal).out("out", out).disjoint()?;
        // SAFETY: by the contract.
        let m = map_at(unsafe { result(cal) }?, kind, index)?;
        // SAFETY: by the contract.
        unsafe { ptr::write(out, summary(m), "out") }
    })
}

/// The name of uncertainty map `index` of kind `kind` — its instrument
/// frame's or its tool's; empty for the base frame's — copied into `buf`
/// like `aacmm_last_error_message`; `*len` gets its full length in bytes
/// without the NUL.
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `buf` is `NULL` or points to
/// `buf_len` writable bytes; `len` is `NULL` or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_uncertainty_map_name(
    cal: *const AacmmCalibration,
    kind: AacmmMapKind,
    index: usize,
    buf: *mut c_char,
    buf_len: usize,
    len: *mut usize,
) -> AacmmStatus {
    // SAFETY: by the contract.
    unsafe {
        text_out((cal, "cal"), (buf, buf_len, len), |c| {
            let m = map_at(c, kind, index)?;
            Ok(m.frame
                .as_deref()
                .or(m.tool.as_deref())
                .unwrap_or("")
                .into())
        })
    }
}

/// Band `band` of uncertainty map `index` of kind `kind` (nearest the
/// shoulder first; `AacmmUncertaintyMap::regions` of them) into `*out`.
/// `AACMM_STATUS_INVALID_ARGUMENT` for an unknown kind or an index out of
/// range (`*out` is then left as it was).
///
/// # Safety
///
/// `cal` is `NULL` or a live result handle; `out` is `NULL` or points to
/// writable memory for the struct.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_calibration_uncertainty_map_region(
    cal: *const AacmmCalibration,
    kind: AacmmMapKind,
    index: usize,
    band: usize,
    out: *mut AacmmUncertaintyRegion,
) -> AacmmStatus {
    guard(|| {
        Args::new().object("cal", cal).out("out", out).disjoint()?;
        // SAFETY: by the contract.
        let m = map_at(unsafe { result(cal) }?, kind, index)?;
        let value = region(m, band)?;
        // SAFETY: by the contract.
        unsafe { ptr::write(out, value, "out") }
    })
}

#[cfg(test)]
mod tests {
    use std::ffi::CString;

    use super::*;
    use crate::calibrate::{AACMM_ANGLE_DEG, aacmm_calibrate_files, aacmm_calibration_free};

    /// No calibration of a sound campaign lacks a map (its covariance is
    /// finite), so the test takes the shipped one's and drops the map.
    #[test]
    fn a_calibration_without_a_map_says_so() {
        let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
        let path = |p: &str| CString::new(format!("{root}/{p}")).unwrap();
        let (arm, poses) = (
            path("examples/paper-table-1.toml"),
            path("examples/paper-campaign/poses.csv"),
        );
        let mut handle: *mut AacmmCalibration = std::ptr::null_mut();
        // SAFETY: NUL-terminated paths, no options, a writable out.
        let status = unsafe {
            aacmm_calibrate_files(
                arm.as_ptr(),
                poses.as_ptr(),
                std::ptr::null(),
                AACMM_ANGLE_DEG,
                std::ptr::null(),
                &mut handle,
            )
        };
        assert_eq!(status, AacmmStatus::Ok);
        // SAFETY: the handle just made, used by this thread alone.
        let cal = unsafe { &mut *handle };
        assert!(cal.report.uncertainty_map.is_some());
        cal.report.uncertainty_map = None;
        let mut map = AacmmUncertaintyMap {
            coverage: -1.0,
            k_isotropic: -1.0,
            poses: 7,
            rms_mm: -1.0,
            median_mm: -1.0,
            max_mm: -1.0,
            regions: 7,
        };
        let before = map;
        // SAFETY: a live handle and a writable struct.
        let status = unsafe { aacmm_calibration_uncertainty_map(&*cal, &mut map) };
        assert_eq!(status, AacmmStatus::NotAvailable);
        assert_eq!(map, before, "left as it was");
        let mut count = 9;
        // SAFETY: a live handle and a writable count.
        let status = unsafe { aacmm_calibration_uncertainty_region_count(&*cal, &mut count) };
        assert_eq!((status, count), (AacmmStatus::Ok, 0));
        let mut region = AacmmUncertaintyRegion {
            reach_from_mm: 0.0,
            reach_to_mm: 0.0,
            poses: 0,
            rms_mm: 0.0,
            max_mm: 0.0,
        };
        // SAFETY: a live handle and a writable struct.
        let status = unsafe { aacmm_calibration_uncertainty_region(&*cal, 0, &mut region) };
        assert_eq!(status, AacmmStatus::NotAvailable);
        // SAFETY: the handle, not used afterwards.
        unsafe { aacmm_calibration_free(handle) };
    }
}
