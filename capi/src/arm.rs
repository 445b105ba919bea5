//! The arm handle and the kernel: positions, parameter Jacobians, the joint
//! Jacobian.

use std::ffi::c_char;

use aacmm_core::domain::Arm;
use aacmm_core::io::{Rejected, read_arm_with, source_name};
use aacmm_core::kernel::{ArmKernel, PreparedPoses};
use aacmm_core::params::{ChainShape, DhParams, ParamId, param_count};

use crate::error::{AacmmStatus, Error, guard, guard_value};
use crate::ptr::{self, Args};

/// An arm: its geometry prepared for the generated kernel of its joint
/// count. Opaque; made by `aacmm_arm_from_file`, `aacmm_arm_from_params`
/// or `aacmm_calibration_arm`, released by `aacmm_arm_free`.
///
/// A handle is never modified after it is made (but by
/// `aacmm_arm_set_joint_types`, called before it is shared): several
/// threads may use the same handle at once.
pub struct AacmmArm {
    pub(crate) arm: Arm,
    pub(crate) kernel: ArmKernel,
    /// Where the arm came from, for reports.
    pub(crate) source: String,
    pub(crate) warnings: Vec<String>,
}

impl AacmmArm {
    pub(crate) fn new(arm: Arm, source: String, warnings: Vec<String>) -> Result<AacmmArm, Error> {
        let kernel = ArmKernel::new(&arm.params).map_err(|e| Error::from(e).prefixed(&source))?;
        Ok(AacmmArm {
            arm,
            kernel,
            source,
            warnings,
        })
    }

    pub(crate) fn joints(&self) -> usize {
        self.kernel.joints()
    }
}

impl Error {
    fn prefixed(mut self, what: &str) -> Error {
        self.message = format!("{what}: {}", self.message);
        self
    }
}

/// The handle behind `arm`.
///
/// # Safety
///
/// `arm` is `NULL` or a live handle.
pub(crate) unsafe fn handle<'a>(arm: *const AacmmArm) -> Result<&'a AacmmArm, Error> {
    // SAFETY: forwarded contract.
    unsafe { ptr::object(arm, "arm") }
}

/// Readings `q` (row-major, one row per pose: rad, mm for a prismatic
/// joint) prepared for the kernel of a chain of `shape`.
pub(crate) fn prepare(shape: ChainShape, q: &[f64]) -> Result<PreparedPoses, Error> {
    Ok(match shape.joints() {
        6 => PreparedPoses::for_shape(shape, q.as_chunks::<6>().0)?,
        7 => PreparedPoses::for_shape(shape, q.as_chunks::<7>().0)?,
        joints => PreparedPoses::for_shape(shape, &q.chunks_exact(joints).collect::<Vec<_>>())?,
    })
}

/// The number of poses in `q_len` readings for an arm of `joints` joints.
pub(crate) fn pose_count(q_len: usize, joints: usize) -> Result<usize, Error> {
    if !q_len.is_multiple_of(joints) {
        return Err(Error::length(format!(
            "q_len = {q_len} is not a multiple of the arm's {joints} joints"
        )));
    }
    Ok(q_len / joints)
}

fn expect_len(name: &str, got: usize, expected: usize, what: &str) -> Result<(), Error> {
    if got == expected {
        Ok(())
    } else {
        Err(Error::length(format!(
            "{name} = {got}, expected {expected} ({what})"
        )))
    }
}

/// The number of geometric parameters of a `joints`-joint arm: `4·joints + 3`.
#[unsafe(no_mangle)]
pub extern "C" fn aacmm_param_count(joints: usize) -> usize {
    guard_value(0, || {
        joints
            .checked_mul(4)
            .and_then(|n| n.checked_add(3))
            .unwrap_or(0)
    })
}

/// Reads an arm file (TOML, the schema `aacmm` reads: 1 to 12 `[[joint]]`
/// entries, the units the file declares) into a new handle at `*out`.
///
/// Warnings about suspicious but legal content (e.g. lengths that look like
/// metres) are kept with the handle: see `aacmm_arm_warnings`. The path
/// `-` reads standard input, as the command line does.
///
/// A file whose `[verdict]` says NOT usable (the `calibrated.toml` of a
/// refused calibration) is refused with `AACMM_STATUS_INPUT`, the message
/// naming the reasons: see `aacmm_arm_from_file_accepting_rejected` to read
/// it anyway.
///
/// Errors: `AACMM_STATUS_NULL_POINTER` (`path` or `out`), `AACMM_STATUS_IO`
/// (cannot read the file), `AACMM_STATUS_INPUT` (invalid content; the
/// message names line and field), `AACMM_STATUS_UNSUPPORTED`. On error
/// `*out` is set to `NULL`.
///
/// # Safety
///
/// `path` is `NULL` or a NUL-terminated string; `out` is `NULL` or points to
/// writable memory for one pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_arm_from_file(
    path: *const c_char,
    out: *mut *mut AacmmArm,
) -> AacmmStatus {
    // SAFETY: the same contract.
    unsafe { from_file(path, out, Rejected::Refuse) }
}

/// `aacmm_arm_from_file`, except that a file whose `[verdict]` says NOT
/// usable is read, with a warning naming the reasons
/// (`aacmm_arm_warnings`): for inspecting a refused calibration's arm,
/// never for measuring with it.
///
/// # Safety
///
/// As `aacmm_arm_from_file`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_arm_from_file_accepting_rejected(
    path: *const c_char,
    out: *mut *mut AacmmArm,
) -> AacmmStatus {
    // SAFETY: the same contract.
    unsafe { from_file(path, out, Rejected::Warn) }
}

/// Both readers of arm files.
///
/// # Safety
///
/// As `aacmm_arm_from_file`.
unsafe fn from_file(
    path: *const c_char,
    out: *mut *mut AacmmArm,
    rejected: Rejected,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: `path` is NULL or NUL-terminated, by the contract.
        unsafe { Args::new().c_str("path", path) }
            .out("out", out)
            .disjoint()?;
        // SAFETY: `out` is NULL or writable, by the contract.
        unsafe { ptr::write(out, std::ptr::null_mut(), "out") }?;
        // SAFETY: `path` is NULL or NUL-terminated, by the contract.
        let path = unsafe { ptr::path(path, "path") }?;
        let (arm, warnings) = read_arm_with(&path, rejected)?;
        let source = source_name(&path);
        let warnings = warnings.iter().map(ToString::to_string).collect();
        let handle = AacmmArm::new(arm, source, warnings)?;
        // SAFETY: checked writable above.
        unsafe { ptr::hand_out(out, handle, "out") }
    })
}

/// Makes an arm from its parameters into a new handle at `*out`.
///
/// `params` holds the `4·joints + 3` parameters in the toolkit's fixed
/// order, lengths in mm and angles in rad:
/// `a1..an, d1..dn, alpha1..alphan, theta1..thetan, Bx, By, Bz`
/// (`n = joints`): link lengths `a`, link offsets `d`, link twists
/// `alpha`, encoder zero offsets `theta` (the joint angle is `q + theta`),
/// and the probe centre `B` in the last link's frame. Each link is
/// `Rz(theta + q) · Tz(d) · Tx(a) · Rx(alpha)`.
///
/// Errors: `AACMM_STATUS_NULL_POINTER`, `AACMM_STATUS_UNSUPPORTED` (a joint
/// count without a kernel: the toolkit computes 1 to 12), `AACMM_STATUS_LENGTH`
/// (`params_len != 4·joints + 3`), `AACMM_STATUS_INVALID_ARGUMENT` (a
/// parameter that is not a finite number). On error `*out` is `NULL`.
///
/// # Safety
///
/// `params` is `NULL` or points to `params_len` doubles; `out` is `NULL` or
/// points to writable memory for one pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_arm_from_params(
    joints: usize,
    params: *const f64,
    params_len: usize,
    out: *mut *mut AacmmArm,
) -> AacmmStatus {
    guard(|| {
        (Args::new().input("params", params, params_len)?)
            .out("out", out)
            .disjoint()?;
        // SAFETY: `out` is NULL or writable, by the contract.
        unsafe { ptr::write(out, std::ptr::null_mut(), "out") }?;
        // SAFETY: `params` holds `params_len` doubles, by the contract.
        let values = unsafe { ptr::input(params, params_len, "params") }?;
        let expected = aacmm_param_count(joints);
        if !aacmm_core::params::supports_joints(joints) {
            return Err(Error::new(
                AacmmStatus::Unsupported,
                format!(
                    "joints = {joints}: the toolkit computes {}",
                    aacmm_core::params::supported_joints_text()
                ),
            ));
        }
        expect_len("params_len", params_len, expected, "4 · joints + 3")?;
        if let Some((id, v)) = ParamId::all(joints)
            .zip(values)
            .find(|(_, v)| !v.is_finite())
        {
            return Err(Error::invalid(format!(
                "params[{}] ({id}) = {v}: parameters must be finite numbers",
                id.column(joints)
            )));
        }
        let dh = DhParams::from_slice(values).ok_or_else(|| Error::length("params_len"))?;
        let arm = Arm::without_limits("arm", dh);
        let handle = AacmmArm::new(arm, "<parameters>".to_string(), Vec::new())?;
        // SAFETY: checked writable above.
        unsafe { ptr::hand_out(out, handle, "out") }
    })
}

/// Sets the kind of each joint of `arm`: `types` is a NUL-terminated
/// string of one letter per joint from the base, `R` revolute, `P`
/// prismatic (`"PRRRRRR"`: a robot on a linear track). A prismatic joint's
/// reading is a length in mm (whatever angle unit a call states) that adds
/// to its `d`; its `theta`, `a`, `alpha` stay constant. An arm made by
/// `aacmm_arm_from_params` is all revolute until this is called; one read
/// from a file has the kinds its `type` keys state. Call it before the
/// handle is shared between threads.
///
/// Errors: `AACMM_STATUS_NULL_POINTER`, `AACMM_STATUS_INVALID_ARGUMENT` (a
/// letter other than `R`/`P`, or another count than the arm's joints, not
/// UTF-8); on error the arm is unchanged.
///
/// # Safety
///
/// `arm` is `NULL` or a live handle no other thread uses during the call;
/// `types` is `NULL` or a NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_arm_set_joint_types(
    arm: *mut AacmmArm,
    types: *const c_char,
) -> AacmmStatus {
    guard(|| {
        // SAFETY: by the contract.
        let text = unsafe { ptr::c_str(types, "types") }?;
        // SAFETY: by the contract.
        let handle = unsafe { ptr::object_mut(arm, "arm") }?;
        let text = text
            .to_str()
            .map_err(|_| Error::invalid("types: not UTF-8".to_string()))?;
        let shape: ChainShape = text
            .parse()
            .map_err(|e| Error::invalid(format!("types = {text:?}: {e}")))?;
        if shape.joints() != handle.joints() {
            return Err(Error::invalid(format!(
                "types = {text:?} names {} joints, the arm has {}",
                shape.joints(),
                handle.joints()
            )));
        }
        let mut params = handle.arm.params.clone();
        for (j, joint) in params.joints.iter_mut().enumerate() {
            joint.kind = shape.kind(j);
        }
        let kernel = ArmKernel::new(&params).map_err(Error::from)?;
        handle.arm.params = params;
        handle.kernel = kernel;
        Ok(())
    })
}

/// Releases an arm handle. `NULL` is allowed (nothing happens).
///
/// # Safety
///
/// `arm` is `NULL` or a live handle, which must not be used afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_arm_free(arm: *mut AacmmArm) {
    // SAFETY: by the contract.
    guard_value((), || unsafe { ptr::release(arm) })
}

/// The number of joints of the arm, into `*joints`.
///
/// # Safety
///
/// `arm` is `NULL` or a live handle; `joints` is `NULL` or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_arm_joints(arm: *const AacmmArm, joints: *mut usize) -> AacmmStatus {
    guard(|| {
        Args::new()
            .object("arm", arm)
            .out("joints", joints)
            .disjoint()?;
        // SAFETY: by the contract.
        let arm = unsafe { handle(arm) }?;
        // SAFETY: by the contract.
        unsafe { ptr::write(joints, arm.joints(), "joints") }
    })
}

/// The arm's `4·joints + 3` parameters in the documented order (mm, rad;
/// see `aacmm_arm_from_params`) into `params`; `params_len` must be
/// `4·joints + 3`.
///
/// # Safety
///
/// `arm` is `NULL` or a live handle; `params` is `NULL` or points to
/// `params_len` writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_arm_params(
    arm: *const AacmmArm,
    params: *mut f64,
    params_len: usize,
) -> AacmmStatus {
    guard(|| {
        (Args::new().object("arm", arm))
            .output("params", params, params_len)?
            .disjoint()?;
        // SAFETY: by the contract.
        let arm = unsafe { handle(arm) }?;
        let values = arm.arm.params.to_vec();
        expect_len("params_len", params_len, values.len(), "4 · joints + 3")?;
        // SAFETY: by the contract.
        let out = unsafe { ptr::output(params, params_len, "params") }?;
        ptr::write_all(out, &values);
        Ok(())
    })
}

/// The warnings read with the arm file (one per line; empty when there are
/// none), copied into `buf` like `aacmm_last_error_message`; `*len` gets
/// the full length in bytes without the NUL. Returns
/// `AACMM_STATUS_BUFFER_TOO_SMALL` when the copy was truncated (`buf` may be
/// `NULL` with `buf_len` 0 to ask for the length).
///
/// # Safety
///
/// `arm` is `NULL` or a live handle; `buf` is `NULL` or points to `buf_len`
/// writable bytes; `len` is `NULL` or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_arm_warnings(
    arm: *const AacmmArm,
    buf: *mut c_char,
    buf_len: usize,
    len: *mut usize,
) -> AacmmStatus {
    guard(|| {
        string_args(Args::new().object("arm", arm), buf, buf_len, len)?;
        // SAFETY: by the contract.
        let arm = unsafe { handle(arm) }?;
        // SAFETY: by the contract.
        unsafe { string_out(&arm.warnings.join("\n"), buf, buf_len, len) }
    })
}

/// Checks the arguments of a string accessor: `args` (its inputs and other
/// outputs) with `buf` and `len`, which must share memory with none of them.
pub(crate) fn string_args(
    args: Args,
    buf: *mut c_char,
    buf_len: usize,
    len: *mut usize,
) -> Result<(), Error> {
    (args.output("buf", buf, buf_len)?)
        .out("len", len)
        .disjoint()
}

/// Copies `s` out for a string accessor: `*len` = its length, the status
/// says whether it fitted.
///
/// # Safety
///
/// `buf` is `NULL` or points to `buf_len` writable bytes; `len` is `NULL`
/// or writable.
pub(crate) unsafe fn string_out(
    s: &str,
    buf: *mut c_char,
    buf_len: usize,
    len: *mut usize,
) -> Result<(), Error> {
    // SAFETY: by the contract.
    unsafe { ptr::write(len, s.len(), "len") }?;
    if buf.is_null() && buf_len > 0 {
        return Err(Error::null("buf"));
    }
    // SAFETY: `buf` has `buf_len` writable bytes (or `buf_len` is 0).
    if unsafe { ptr::copy_str(s, buf, buf_len) } {
        Ok(())
    } else {
        Err(Error::new(
            AacmmStatus::BufferTooSmall,
            format!(
                "the string has {} bytes and a NUL; the buffer holds {buf_len}",
                s.len()
            ),
        ))
    }
}

/// Poses prepared at once (their sin and cos, 96 kB for 6 joints) by the
/// batch functions: memory that does not grow with the batch, so a large
/// one cannot exhaust it (a failed allocation aborts the host), and the
/// prepared poses stay in cache.
const BATCH: usize = 4096;

/// Probe positions of `n = q_len / joints` poses.
///
/// `q` holds the encoder readings, rad (a prismatic joint's, mm:
/// `aacmm_arm_set_joint_types`), row-major `n × joints`
/// (`q[i·joints + j]` is joint `j` of pose `i`); `p` receives the probe
/// positions, mm, row-major `n × 3` (`p[3·i + k]`, `k` = x, y, z), in pose
/// order. The results are bit-identical to the Rust API's
/// (`ArmKernel::positions`) on the same inputs. Non-finite readings give
/// non-finite positions; they are not checked.
///
/// Errors: `AACMM_STATUS_NULL_POINTER` (`arm`, or a buffer whose length is
/// not 0), `AACMM_STATUS_LENGTH` (`q_len` not a multiple of the joint count,
/// `p_len != 3 · n`, or `q_len` past what memory can hold),
/// `AACMM_STATUS_INVALID_ARGUMENT` (`p` overlaps `q` or the handle). Memory
/// does not grow with `n`: poses are prepared a few thousand at a time.
///
/// # Safety
///
/// `arm` is `NULL` or a live handle; `q` points to `q_len` doubles and `p` to
/// `p_len` writable doubles (either may be `NULL` when its length is 0).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_positions(
    arm: *const AacmmArm,
    q: *const f64,
    q_len: usize,
    p: *mut f64,
    p_len: usize,
) -> AacmmStatus {
    guard(|| {
        (Args::new().object("arm", arm))
            .input("q", q, q_len)?
            .output("p", p, p_len)?
            .disjoint()?;
        // SAFETY: by the contract.
        let arm = unsafe { handle(arm) }?;
        let joints = arm.joints();
        let n = pose_count(q_len, joints)?;
        expect_len("p_len", p_len, 3 * n, "3 per pose")?;
        // SAFETY: by the contract; `p` does not overlap `q` (checked).
        let (q, p) = unsafe { (ptr::input(q, q_len, "q")?, ptr::output(p, p_len, "p")?) };
        // The kernel writes through `&mut [[f64; 3]]`, which must not refer
        // to the caller's possibly uninitialised memory: each chunk goes to
        // the stack first and is copied out (one write of `p`, no zeroing
        // pass). Poses are prepared a batch at a time (see `BATCH`). Chunks
        // and batches start at multiples of 4 poses, so the SIMD batches are
        // the same as in one call.
        const CHUNK: usize = 256;
        let mut chunk = [[0.0; 3]; CHUNK];
        for (q, p) in q.chunks(BATCH * joints).zip(p.chunks_mut(3 * BATCH)) {
            let poses = prepare(arm.kernel.shape(), q)?;
            for (start, dst) in (0..).step_by(CHUNK).zip(p.chunks_mut(3 * CHUNK)) {
                let m = dst.len() / 3;
                arm.kernel
                    .positions(&poses, start..start + m, &mut chunk[..m])?;
                ptr::write_all(dst, chunk[..m].as_flattened());
            }
        }
        Ok(())
    })
}

/// Probe positions and parameter Jacobians of `n = q_len / joints` poses.
///
/// `q` and `p` as in `aacmm_positions` (the positions are those of the
/// Jacobian kernel, which may differ from `aacmm_positions` in the last
/// bit). `jac` receives, per pose, the
/// `3 × P` Jacobian `∂p/∂parameter` (`P = 4·joints + 3`, the parameters in
/// the order of `aacmm_arm_from_params`; mm/mm for lengths, mm/rad for
/// angles), row-major: `jac[(3·i + k)·P + c] = ∂p_k/∂param_c` of pose `i`,
/// so `jac_len = 3 · P · n`. Positions and Jacobians are bit-identical to
/// the Rust API's (`ArmKernel::jacobians`).
///
/// Errors: as `aacmm_positions`, and `AACMM_STATUS_LENGTH` for
/// `jac_len != 3 · P · n`.
///
/// # Safety
///
/// `arm` is `NULL` or a live handle; `q` points to `q_len` doubles, `p` to
/// `p_len` and `jac` to `jac_len` writable doubles (each may be `NULL`
/// when its length is 0).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_jacobians(
    arm: *const AacmmArm,
    q: *const f64,
    q_len: usize,
    p: *mut f64,
    p_len: usize,
    jac: *mut f64,
    jac_len: usize,
) -> AacmmStatus {
    guard(|| {
        (Args::new().object("arm", arm))
            .input("q", q, q_len)?
            .output("p", p, p_len)?
            .output("jac", jac, jac_len)?
            .disjoint()?;
        // SAFETY: by the contract.
        let arm = unsafe { handle(arm) }?;
        let joints = arm.joints();
        let params = param_count(joints);
        let n = pose_count(q_len, joints)?;
        expect_len("p_len", p_len, 3 * n, "3 per pose")?;
        let per_pose = 3 * params;
        let expected = per_pose
            .checked_mul(n)
            .ok_or_else(|| Error::length(format!("q_len = {q_len}: too many poses")))?;
        expect_len(
            "jac_len",
            jac_len,
            expected,
            "3 · (4 · joints + 3) per pose",
        )?;
        // SAFETY: by the contract; the buffers do not overlap (checked).
        let (q, p, jac) = unsafe {
            (
                ptr::input(q, q_len, "q")?,
                ptr::output(p, p_len, "p")?,
                ptr::output(jac, jac_len, "jac")?,
            )
        };
        // A batch of poses prepared at a time (see `BATCH`).
        let batches = (q.chunks(BATCH * joints))
            .zip(p.chunks_mut(3 * BATCH))
            .zip(jac.chunks_mut(per_pose * BATCH));
        for ((q, p), jac) in batches {
            let poses = prepare(arm.kernel.shape(), q)?;
            let m = poses.len();
            arm.kernel.for_each_jacobian(&poses, 0..m, |i, pos, cols| {
                ptr::write_all(&mut p[3 * i..3 * i + 3], pos);
                let block = &mut jac[per_pose * i..per_pose * (i + 1)];
                for (c, col) in cols.iter().enumerate() {
                    for (k, &v) in col.iter().enumerate() {
                        block[k * params + c].write(v);
                    }
                }
            })?;
        }
        Ok(())
    })
}

/// Probe position and joint Jacobian `∂p/∂q` of one pose: what inverse
/// kinematics and encoder-noise propagation need.
///
/// `q` holds the pose's `joints` readings (rad; `q_len = joints`); `p`
/// receives the position (mm; `p_len = 3`); `jac` the `3 × joints` Jacobian,
/// mm/rad, row-major: `jac[k·joints + j] = ∂p_k/∂q_j` (`jac_len = 3 · joints`).
///
/// Errors: as `aacmm_positions`.
///
/// # Safety
///
/// As `aacmm_jacobians`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_joint_jacobian(
    arm: *const AacmmArm,
    q: *const f64,
    q_len: usize,
    p: *mut f64,
    p_len: usize,
    jac: *mut f64,
    jac_len: usize,
) -> AacmmStatus {
    guard(|| {
        (Args::new().object("arm", arm))
            .input("q", q, q_len)?
            .output("p", p, p_len)?
            .output("jac", jac, jac_len)?
            .disjoint()?;
        // SAFETY: by the contract.
        let arm = unsafe { handle(arm) }?;
        let joints = arm.joints();
        expect_len("q_len", q_len, joints, "one reading per joint")?;
        expect_len("p_len", p_len, 3, "x, y, z")?;
        expect_len("jac_len", jac_len, 3 * joints, "3 · joints")?;
        // SAFETY: by the contract; the buffers do not overlap (checked).
        let (q, p, jac) = unsafe {
            (
                ptr::input(q, q_len, "q")?,
                ptr::output(p, p_len, "p")?,
                ptr::output(jac, jac_len, "jac")?,
            )
        };
        let mut cols = vec![[0.0; 3]; joints];
        ptr::write_all(p, &arm.kernel.joint_jacobian(q, &mut cols)?);
        for (j, col) in cols.iter().enumerate() {
            for (k, &v) in col.iter().enumerate() {
                jac[k * joints + j].write(v);
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn nominal() -> *mut AacmmArm {
        let params = DhParams::paper_nominal().to_vec();
        let mut arm = std::ptr::null_mut();
        // SAFETY: `params` holds 27 doubles; `arm` is writable.
        let status = unsafe { aacmm_arm_from_params(6, params.as_ptr(), 27, &mut arm) };
        assert_eq!(status, AacmmStatus::Ok);
        arm
    }

    #[test]
    fn empty_batches_are_fine_and_huge_ones_are_refused() {
        let arm = nominal();
        let null = std::ptr::null_mut();
        // SAFETY: zero-length buffers may be NULL; the huge lengths are
        // refused before any pointer is used.
        unsafe {
            assert_eq!(aacmm_positions(arm, null, 0, null, 0), AacmmStatus::Ok);
            assert_eq!(
                aacmm_jacobians(arm, null, 0, null, 0, null, 0),
                AacmmStatus::Ok
            );
            let huge = usize::MAX / 6 * 6;
            let q = [0.0f64; 6];
            let mut p = [0.0f64; 3];
            let status = aacmm_jacobians(
                arm,
                q.as_ptr(),
                huge,
                p.as_mut_ptr(),
                huge / 2,
                p.as_mut_ptr(),
                3,
            );
            assert_eq!(status, AacmmStatus::Length);
            assert_eq!(
                aacmm_positions(arm, q.as_ptr(), huge, p.as_mut_ptr(), 3),
                AacmmStatus::Length
            );
            aacmm_arm_free(arm);
        }
    }

    /// Positions go out through stack chunks of 256 poses, prepared in
    /// batches of `BATCH`: two full batches and 601 poses (two full chunks
    /// and a tail that is not a multiple of the 4 lanes) into an
    /// uninitialised buffer give the Rust API's bits, in order.
    #[test]
    fn chunked_positions_fill_an_uninitialised_buffer() {
        let arm = nominal();
        let n = 2 * BATCH + 601;
        let q: Vec<f64> = (0..6 * n).map(|i| (i as f64 * 0.37).sin() * 3.0).collect();
        let mut p: Vec<f64> = Vec::with_capacity(3 * n);
        // SAFETY: live handle; `q` holds `6n` doubles; `p` has room for
        // `3n` (uninitialised) doubles, all written on success.
        unsafe {
            let status = aacmm_positions(arm, q.as_ptr(), 6 * n, p.as_mut_ptr(), 3 * n);
            assert_eq!(status, AacmmStatus::Ok);
            p.set_len(3 * n);
        }
        let rows: Vec<&[f64]> = q.chunks(6).collect();
        // SAFETY: live handle, freed below and not used after.
        let expected = unsafe { handle(arm) }
            .unwrap()
            .kernel
            .positions_of(&rows)
            .unwrap();
        assert_eq!(p, expected.as_flattened());
        // SAFETY: live handle, not used after.
        unsafe { aacmm_arm_free(arm) };
    }

    /// Jacobians of poses prepared in batches of `BATCH` are those of one
    /// preparation of them all, bit for bit.
    #[test]
    fn batched_jacobians_are_those_of_one_batch() {
        let arm = nominal();
        let n = BATCH + 5;
        let q: Vec<f64> = (0..6 * n).map(|i| (i as f64 * 0.29).cos() * 2.0).collect();
        let (mut p, mut jac) = (vec![0.0; 3 * n], vec![0.0; 81 * n]);
        // SAFETY: live handle; buffers of the stated lengths.
        let status = unsafe {
            aacmm_jacobians(
                arm,
                q.as_ptr(),
                6 * n,
                p.as_mut_ptr(),
                3 * n,
                jac.as_mut_ptr(),
                81 * n,
            )
        };
        assert_eq!(status, AacmmStatus::Ok);
        // SAFETY: live handle, freed below and not used after.
        let kernel = &unsafe { handle(arm) }.unwrap().kernel;
        let poses = prepare(ChainShape::revolute(6).unwrap(), &q).unwrap();
        let mut seen = 0;
        kernel
            .for_each_jacobian(&poses, 0..n, |i, pos, cols| {
                assert_eq!(p[3 * i..3 * i + 3], pos[..], "pose {i}");
                for (c, col) in cols.iter().enumerate() {
                    for (k, &v) in col.iter().enumerate() {
                        assert_eq!(jac[81 * i + 27 * k + c].to_bits(), v.to_bits());
                    }
                }
                seen += 1;
            })
            .unwrap();
        assert_eq!(seen, n);
        // SAFETY: live handle, not used after.
        unsafe { aacmm_arm_free(arm) };
    }

    #[test]
    fn params_round_trip_and_are_checked() {
        let arm = nominal();
        let mut back = [0.0; 27];
        let mut joints = 0;
        // SAFETY: live handle, writable buffers of the stated lengths.
        unsafe {
            assert_eq!(
                aacmm_arm_params(arm, back.as_mut_ptr(), 27),
                AacmmStatus::Ok
            );
            assert_eq!(aacmm_arm_joints(arm, &mut joints), AacmmStatus::Ok);
            assert_eq!(
                aacmm_arm_params(arm, back.as_mut_ptr(), 26),
                AacmmStatus::Length
            );
            aacmm_arm_free(arm);
        }
        assert_eq!(back.to_vec(), DhParams::paper_nominal().to_vec());
        assert_eq!(joints, 6);
        let mut bad = DhParams::paper_nominal().to_vec();
        bad[3] = f64::INFINITY;
        let mut out = std::ptr::null_mut();
        // SAFETY: as above.
        let status = unsafe { aacmm_arm_from_params(6, bad.as_ptr(), 27, &mut out) };
        assert_eq!(status, AacmmStatus::InvalidArgument);
        assert!(out.is_null());
    }
}
