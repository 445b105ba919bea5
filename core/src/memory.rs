//! Memory sized by the input, asked for before any work so that a hostile
//! or simply too large input is an error, not an abort of the host process.
//!
//! Rust's default response to a failed allocation is to abort the process:
//! a host program (Python, a C program) would simply die. Two means keep
//! that from happening, and they protect against different things:
//!
//! - **Fallible reservations** ([`try_vec`], `try_grow`): every buffer
//!   whose size follows from the input (a file's text, its rows, the data
//!   set's arrays, the C API's copies) is reserved with `try_reserve`, and
//!   the input limits (a line of at most 1 MiB, an arm or campaign file of
//!   at most 16 MiB, `bytes_for`'s overflow check) bound what one input
//!   can ask for. A size that overflows or exceeds `isize::MAX` is refused
//!   everywhere, deterministically.
//! - **Probes** ([`room_for`], `room_for_work`): work whose buffers are
//!   made deep inside the solver or the report asks, before it starts, for
//!   what it holds at its peak (measured and rounded up:
//!   `data_set_bytes_per_touch`, `WORK_BYTES_PER_TOUCH`) and gives it
//!   back at once. A probe is refused — and the work with it, with a
//!   message — exactly when the system refuses the address space:
//!   under an address-space limit (`ulimit -v`, `RLIMIT_AS`: exact enough
//!   to be deterministic, tested in the Python and C suites); under Linux's
//!   default heuristic overcommit (`vm.overcommit_memory = 0`), a request
//!   larger than the machine's memory and swap (on a 24 GiB machine
//!   without swap, 30 GiB is refused and 20 GiB granted); and under strict
//!   accounting (`= 2`), beyond the commit limit.
//!
//! Neither protects against a **cgroup memory limit** (a container's
//! `--memory`, systemd's `MemoryMax`, a Kubernetes limit): it limits the
//! memory a process touches, not the address space it reserves, so the
//! probe and the reservations succeed, and when the work's pages take the
//! group past its limit the kernel's OOM killer ends the process
//! (`SIGKILL`, no message). Nor against memory other processes take
//! between the check and the work. Under such a limit, size the input to
//! it: [`calibration_bytes`] says what a calibration holds at its peak.

/// What a calibration, an identification or an evaluation allocates per
/// touch (or reference position) beyond the data set it works on (the
/// Jacobian blocks, the leverage, the report's positions and figures):
/// measured at 10⁶ touches of a 6-joint arm, `/usr/bin/time` peak less the
/// data set's [`data_set_bytes_per_touch`] — 122 bytes (`calibrate`, the
/// global method), 77 (`--method lm`), 50 (`identify`), 18 (`evaluate`) —
/// and rounded up for a 7-joint arm's wider Jacobian rows.
pub(crate) const WORK_BYTES_PER_TOUCH: usize = 160;

/// The same per reference length, rounded up.
pub const WORK_BYTES_PER_LENGTH: usize = 128;

/// What an identification allocates per touch beyond its data set: 50
/// measured (as [`WORK_BYTES_PER_TOUCH`]), rounded up.
pub(crate) const IDENTIFY_BYTES_PER_TOUCH: usize = 96;

/// What an evaluation allocates per touch beyond its data set, the
/// positions the caller computes first (24 bytes) included: 18 measured
/// besides them, rounded up.
pub(crate) const EVALUATE_BYTES_PER_TOUCH: usize = 64;

/// What a data set holds per touch of `joints` joints with `conditions`
/// condition columns (temperature, time): the readings in touch order (8
/// bytes a joint), their sin and cos (16), the touch order while sorting
/// (8), the source lines and rows (8), 8 bytes per condition.
pub(crate) const fn data_set_bytes_per_touch(joints: usize, conditions: usize) -> usize {
    24 * joints + 16 + 8 * conditions
}

/// Memory that could not be had: what for, and how many bytes.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "out of memory: {what} needs {bytes} bytes, more than this process can allocate (raise its \
     memory limit or split the input)"
)]
pub struct OutOfMemory {
    /// What the memory was for (names the input that sized it).
    pub what: String,
    /// The bytes asked for (`usize::MAX` when the size itself overflowed).
    pub bytes: usize,
}

impl OutOfMemory {
    /// The error for `bytes` bytes for `what`.
    pub(crate) fn new(what: impl Into<String>, bytes: usize) -> OutOfMemory {
        OutOfMemory {
            what: what.into(),
            bytes,
        }
    }
}

/// `count × size`, or an [`OutOfMemory`] for `what` when it overflows or
/// exceeds what one allocation may be (`isize::MAX`).
pub(crate) fn bytes_for(what: &str, count: usize, size: usize) -> Result<usize, OutOfMemory> {
    count
        .checked_mul(size)
        .filter(|&b| b <= isize::MAX as usize)
        .ok_or_else(|| OutOfMemory::new(what, usize::MAX))
}

/// An empty vector with room for `len` elements, or an [`OutOfMemory`]
/// naming `what`.
///
/// ```
/// use aacmm_core::memory::try_vec;
/// let v: Vec<f64> = try_vec("readings", 100).unwrap();
/// assert!(v.capacity() >= 100);
/// assert!(try_vec::<f64>("readings", usize::MAX / 4).is_err());
/// ```
pub fn try_vec<T>(what: &str, len: usize) -> Result<Vec<T>, OutOfMemory> {
    let mut v = Vec::new();
    try_grow(&mut v, what, len)?;
    Ok(v)
}

/// Room for `additional` more elements in `v` (amortised growth, as
/// `push`), or an [`OutOfMemory`] naming `what`.
pub(crate) fn try_grow<T>(
    v: &mut Vec<T>,
    what: &str,
    additional: usize,
) -> Result<(), OutOfMemory> {
    v.try_reserve(additional).map_err(|_| {
        let bytes = (v.len().saturating_add(additional)).saturating_mul(size_of::<T>());
        OutOfMemory::new(what, bytes)
    })
}

/// Checks, before any work, that `bytes` can be allocated now (and gives
/// them back): an [`OutOfMemory`] naming `what` when they cannot. See the
/// module docs for what the check promises.
///
/// ```
/// use aacmm_core::memory::room_for;
/// assert!(room_for("a calibration", 1 << 20).is_ok());
/// assert!(room_for("a calibration", usize::MAX).is_err());
/// ```
pub fn room_for(what: &str, bytes: usize) -> Result<(), OutOfMemory> {
    let mut probe: Vec<u8> = Vec::new();
    if bytes > isize::MAX as usize || probe.try_reserve_exact(bytes).is_err() {
        return Err(OutOfMemory::new(what, bytes));
    }
    Ok(())
}

/// What the work on a data set of `touches` touches (or positions) and
/// `lengths` reference lengths allocates beyond the data set: `per_touch`
/// bytes a touch (e.g. [`WORK_BYTES_PER_TOUCH`]) and
/// [`WORK_BYTES_PER_LENGTH`] a length, saturated at `usize::MAX`.
pub(crate) fn work_bytes(touches: usize, lengths: usize, per_touch: usize) -> usize {
    (touches.saturating_mul(per_touch))
        .saturating_add(lengths.saturating_mul(WORK_BYTES_PER_LENGTH))
}

/// [`room_for`] the work `what` on `touches` touches (or positions) and
/// `lengths` reference lengths, `per_touch` bytes a touch (e.g.
/// [`WORK_BYTES_PER_TOUCH`]) and [`WORK_BYTES_PER_LENGTH`] a length, and
/// `extra` bytes besides; the message counts them.
pub(crate) fn room_for_work(
    what: &str,
    touches: usize,
    lengths: usize,
    per_touch: usize,
    extra: usize,
) -> Result<(), OutOfMemory> {
    let what = format!("{what} {touches} observations and {lengths} lengths");
    room_for(
        &what,
        work_bytes(touches, lengths, per_touch).saturating_add(extra),
    )
}

/// What a calibration of `touches` touches of a `joints`-joint arm and
/// `lengths` reference lengths holds at its peak, its data set included: for
/// a caller that checks before it builds the data set (the C API's arrays).
pub fn calibration_bytes(touches: usize, lengths: usize, joints: usize) -> usize {
    let data = touches.saturating_mul(data_set_bytes_per_touch(joints, 0));
    data.saturating_add(work_bytes(touches, lengths, WORK_BYTES_PER_TOUCH))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn growth_failure_names_the_input() {
        let mut v: Vec<u64> = vec![1, 2];
        let e = try_grow(&mut v, "poses.csv rows", usize::MAX / 2).unwrap_err();
        assert_eq!(e.what, "poses.csv rows");
        assert!(
            e.to_string()
                .starts_with("out of memory: poses.csv rows needs")
        );
        assert_eq!(v, [1, 2]);
        try_grow(&mut v, "rows", 10).unwrap();
        assert!(v.capacity() >= 12);
    }

    #[test]
    fn calibration_bytes_saturates() {
        assert_eq!(work_bytes(10, 2, WORK_BYTES_PER_TOUCH), 10 * 160 + 2 * 128);
        assert_eq!(calibration_bytes(10, 2, 6), 10 * 320 + 2 * 128);
        assert_eq!(calibration_bytes(usize::MAX, 1, 6), usize::MAX);
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn memory_data_set_bytes_per_touch() {
        use crate::memory::data_set_bytes_per_touch;
        assert_eq!(data_set_bytes_per_touch(6, 0), 160);
    }

    #[test]
    fn memory_bytes_for() {
        use crate::memory::bytes_for;
        assert_eq!(bytes_for("q", 10, 8), Ok(80));
        assert!(bytes_for("q", usize::MAX / 4, 8).is_err());
    }

    #[test]
    fn memory_room_for_work() {
        use crate::memory::{WORK_BYTES_PER_TOUCH, room_for_work};
        assert!(room_for_work("identifying from", 100, 2, WORK_BYTES_PER_TOUCH, 0).is_ok());
        let e = room_for_work("identifying from", usize::MAX / 2, 0, 96, 0).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("out of memory: identifying from 9223372036854775807 observations")
        );
    }
}
