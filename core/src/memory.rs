//! Memory sized by the input, asked for before any work so that a hostile
//! or simply too large input is an error, not an abort of the host process.
//!
//! Rust's default response to a failed allocation is to abort the process:
//! a host program (Python, a C program) in a container with a memory limit
//! would simply die. Every buffer whose size follows from the input is
//! therefore either reserved with `try_reserve` ([`try_vec`]) or, where it
//! is made deep inside the solver or the report, covered by a probe
//! ([`room_for`]) of what the whole computation holds at its peak,
//! measured and rounded up ([`CALIBRATION_BYTES_PER_TOUCH`]).
//!
//! A probe is a check, not a promise: memory another process takes between
//! the check and the work can still run out. Under an address-space limit
//! (`ulimit -v`, `RLIMIT_AS`, the usual container case) the check is
//! exact enough to be deterministic: tested in the Python and C suites.

/// What a calibration holds at its peak per touch (the data set's readings
/// and their sin/cos, the Jacobian blocks, the leverage, the report's
/// positions): 229 bytes measured at 10⁶ touches of a 6-joint arm
/// (`calibrate --method lm`, 228.7 MB peak), rounded up.
pub const CALIBRATION_BYTES_PER_TOUCH: usize = 256;

/// What a calibration holds per reference length, rounded up.
pub const CALIBRATION_BYTES_PER_LENGTH: usize = 128;

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
    pub fn new(what: impl Into<String>, bytes: usize) -> OutOfMemory {
        OutOfMemory {
            what: what.into(),
            bytes,
        }
    }
}

/// `count × size`, or an [`OutOfMemory`] for `what` when it overflows or
/// exceeds what one allocation may be (`isize::MAX`).
///
/// ```
/// use aacmm_core::memory::bytes_for;
/// assert_eq!(bytes_for("q", 10, 8), Ok(80));
/// assert!(bytes_for("q", usize::MAX / 4, 8).is_err());
/// ```
pub fn bytes_for(what: &str, count: usize, size: usize) -> Result<usize, OutOfMemory> {
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
pub fn try_grow<T>(v: &mut Vec<T>, what: &str, additional: usize) -> Result<(), OutOfMemory> {
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

/// What a calibration of `touches` touches and `lengths` reference lengths
/// holds at its peak ([`CALIBRATION_BYTES_PER_TOUCH`],
/// [`CALIBRATION_BYTES_PER_LENGTH`]), saturated at `usize::MAX`.
pub fn calibration_bytes(touches: usize, lengths: usize) -> usize {
    (touches.saturating_mul(CALIBRATION_BYTES_PER_TOUCH))
        .saturating_add(lengths.saturating_mul(CALIBRATION_BYTES_PER_LENGTH))
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
        assert_eq!(calibration_bytes(10, 2), 10 * 256 + 2 * 128);
        assert_eq!(calibration_bytes(usize::MAX, 1), usize::MAX);
    }
}
