//! From C pointers to Rust references, checked: `NULL`, misalignment, sizes
//! past `isize::MAX` and overlapping buffers become errors, never undefined
//! behaviour. What cannot be checked (that a buffer really holds the length
//! the caller states, that a handle is live) is the caller's contract,
//! stated in each function's `# Safety` section.

use std::ffi::{CStr, c_char};
use std::mem::MaybeUninit;
use std::path::PathBuf;

use crate::error::Error;

/// Checks that `len` elements of `T` at `ptr` could form a slice.
fn check<T>(ptr: *const T, len: usize, name: &str) -> Result<(), Error> {
    if len == 0 {
        return Ok(());
    }
    if ptr.is_null() {
        return Err(Error::null(name));
    }
    if !ptr.is_aligned() {
        return Err(Error::invalid(format!(
            "`{name}` is not aligned for its element type"
        )));
    }
    if len
        .checked_mul(size_of::<T>())
        .is_none_or(|bytes| bytes > isize::MAX as usize)
    {
        return Err(Error::length(format!(
            "`{name}`: length {len} is too large"
        )));
    }
    Ok(())
}

/// `len` elements at `ptr` as a slice; an empty slice when `len` is 0
/// (`ptr` may then be `NULL`).
///
/// # Safety
///
/// Unless `len` is 0, `ptr` is `NULL` or points to `len` initialised values
/// of `T` that nothing mutates during `'a`.
pub(crate) unsafe fn input<'a, T>(ptr: *const T, len: usize, name: &str) -> Result<&'a [T], Error> {
    check(ptr, len, name)?;
    if len == 0 {
        return Ok(&[]);
    }
    // SAFETY: `check` made sure `ptr` is non-null, aligned and `len` values
    // fit in `isize`; the caller guarantees they are initialised and not
    // mutated while the slice lives.
    Ok(unsafe { std::slice::from_raw_parts(ptr, len) })
}

/// `len` writable elements at `ptr` as a slice of [`MaybeUninit`]; an empty
/// slice when `len` is 0. The caller's memory may be uninitialised (C
/// output buffers often are), and a reference to an uninitialised `T` is
/// undefined behaviour even for `f64` or `bool`; a `MaybeUninit<T>` may hold
/// anything, so this slice is sound whatever the buffer holds. Fill it with
/// [`MaybeUninit::write`] or [`write_all`]; never read it.
///
/// # Safety
///
/// Unless `len` is 0, `ptr` is `NULL` or points to `len` writable values of
/// `T` that nothing else reads or writes during `'a`.
pub(crate) unsafe fn output<'a, T: Copy>(
    ptr: *mut T,
    len: usize,
    name: &str,
) -> Result<&'a mut [MaybeUninit<T>], Error> {
    check(ptr, len, name)?;
    if len == 0 {
        return Ok(&mut []);
    }
    // SAFETY: `check` made sure `ptr` is non-null, aligned and `len` values
    // fit in `isize`; `MaybeUninit<T>` has `T`'s layout and every content
    // (initialised or not) is valid for it; the caller guarantees the memory
    // is writable and not accessed elsewhere while the slice lives.
    Ok(unsafe { std::slice::from_raw_parts_mut(ptr.cast::<MaybeUninit<T>>(), len) })
}

/// Writes `src` into the first `src.len()` elements of `dst` (at most
/// `dst.len()`); what `write_copy_of_slice` does from Rust 1.93, above the
/// crate's MSRV.
pub(crate) fn write_all<T: Copy>(dst: &mut [MaybeUninit<T>], src: &[T]) {
    debug_assert!(src.len() <= dst.len());
    for (slot, &v) in dst.iter_mut().zip(src) {
        slot.write(v);
    }
}

/// The bytes `len` elements of `T` take, checked: a size past `isize::MAX`
/// (what no allocation can have) is `AACMM_STATUS_LENGTH`, naming `name`.
pub(crate) fn bytes<T>(name: &str, len: usize) -> Result<usize, Error> {
    len.checked_mul(size_of::<T>())
        .filter(|&bytes| bytes <= isize::MAX as usize)
        .ok_or_else(|| {
            Error::length(format!(
                "`{name}`: length {len} is too large ({} bytes each)",
                size_of::<T>()
            ))
        })
}

/// An empty vector with room for `len` elements, for a copy or a result
/// sized by the input: a size past what memory can hold is
/// `AACMM_STATUS_LENGTH`, a failed allocation `AACMM_STATUS_OUT_OF_MEMORY`
/// (Rust's default would abort the host), each naming `what`, the length
/// argument.
pub(crate) fn try_vec<T>(what: &str, len: usize) -> Result<Vec<T>, Error> {
    let bytes = len
        .checked_mul(size_of::<T>())
        .filter(|&bytes| bytes <= isize::MAX as usize)
        .ok_or_else(|| {
            Error::length(format!(
                "{what} = {len}: too large to hold in memory ({} bytes each)",
                size_of::<T>()
            ))
        })?;
    aacmm_core::memory::try_vec(what, len)
        .map_err(|_| Error::out_of_memory(format!("{what} = {len}: cannot allocate {bytes} bytes")))
}

/// Checks, before any work, that `bytes` (what a computation sized by
/// `what` will allocate inside the library, where a failure would abort)
/// can be allocated now, and releases them: `AACMM_STATUS_OUT_OF_MEMORY`
/// when they cannot (what that sees, and the cgroup limit it does not:
/// [`aacmm_core::memory`]). A check, not a promise: memory may run out
/// later all the same.
pub(crate) fn room_for(what: &str, bytes: usize) -> Result<(), Error> {
    if bytes > isize::MAX as usize {
        return Err(Error::length(format!(
            "{what}: the work needs {bytes} bytes, more than memory can hold"
        )));
    }
    aacmm_core::memory::room_for(what, bytes).map_err(|_| {
        Error::out_of_memory(format!(
            "{what}: cannot allocate the {bytes} bytes the work needs"
        ))
    })
}

/// The memory one argument takes, for [`Args`].
#[derive(Clone, Copy, Debug, Default)]
struct Region<'n> {
    name: &'n str,
    start: usize,
    bytes: usize,
    written: bool,
}

/// The memory an entry point reads and writes, declared before anything is
/// written — the `NULL` put in an output handle's slot included — so that
/// an output which shares memory with an input, or with another output,
/// is refused (`AACMM_STATUS_INVALID_ARGUMENT`) rather than read after it
/// was written (a silently wrong result) or aliased by a Rust reference.
/// Each length is checked first (`AACMM_STATUS_LENGTH` for one past what
/// memory can hold), so that a span never saturates into a false overlap.
/// `NULL` and empty arguments take no memory here; `NULL` is refused later,
/// where the argument is used. Inputs may share memory with each other
/// (they are only read).
#[derive(Debug, Default)]
pub(crate) struct Args<'n> {
    regions: [Region<'n>; Args::MAX],
    len: usize,
}

impl<'n> Args<'n> {
    /// The most arguments an entry point has.
    const MAX: usize = 8;

    pub(crate) fn new() -> Args<'n> {
        Args::default()
    }

    fn add(mut self, name: &'n str, start: usize, bytes: usize, written: bool) -> Self {
        debug_assert!(self.len < Args::MAX, "more than {} arguments", Args::MAX);
        if let Some(slot) = self.regions.get_mut(self.len) {
            *slot = Region {
                name,
                start,
                bytes,
                written,
            };
            self.len += 1;
        }
        self
    }

    /// `len` elements of `T` read at `ptr`.
    pub(crate) fn input<T>(self, name: &'n str, ptr: *const T, len: usize) -> Result<Self, Error> {
        let bytes = bytes::<T>(name, len)?;
        Ok(self.add(name, ptr as usize, bytes, false))
    }

    /// `len` elements of `T` written at `ptr`.
    pub(crate) fn output<T>(self, name: &'n str, ptr: *mut T, len: usize) -> Result<Self, Error> {
        let bytes = bytes::<T>(name, len)?;
        Ok(self.add(name, ptr as usize, bytes, true))
    }

    /// One `T` read at `ptr` (a handle, an options builder).
    pub(crate) fn object<T>(self, name: &'n str, ptr: *const T) -> Self {
        self.add(name, ptr as usize, size_of::<T>(), false)
    }

    /// One `T` written at `ptr` (an out-parameter, a handle's slot).
    pub(crate) fn out<T>(self, name: &'n str, ptr: *mut T) -> Self {
        self.add(name, ptr as usize, size_of::<T>(), true)
    }

    /// A NUL-terminated string read at `ptr`, its NUL included.
    ///
    /// # Safety
    ///
    /// `ptr` is `NULL` or points to a NUL-terminated string.
    pub(crate) unsafe fn c_str(self, name: &'n str, ptr: *const c_char) -> Self {
        let bytes = match ptr.is_null() {
            true => 0,
            // SAFETY: non-null and NUL-terminated, by the contract.
            false => unsafe { CStr::from_ptr(ptr) }.count_bytes() + 1,
        };
        self.add(name, ptr as usize, bytes, false)
    }

    /// Refuses an output that shares a byte with any other argument, and
    /// an argument whose bytes run past the end of the address space.
    pub(crate) fn disjoint(self) -> Result<(), Error> {
        let regions = &self.regions[..self.len];
        let end = |r: &Region| r.start.checked_add(r.bytes);
        let used = |r: &&Region| r.start != 0 && r.bytes > 0;
        for r in regions.iter().filter(used) {
            if end(r).is_none() {
                return Err(Error::length(format!(
                    "`{}`: {} bytes from its address run past the end of memory",
                    r.name, r.bytes
                )));
            }
        }
        for (i, a) in regions.iter().enumerate().filter(|(_, r)| used(r)) {
            for b in regions[i + 1..].iter().filter(used) {
                let meet = a.start < b.start + b.bytes && b.start < a.start + a.bytes;
                if meet && (a.written || b.written) {
                    return Err(Error::invalid(format!(
                        "`{}` and `{}` overlap; pass separate buffers",
                        a.name, b.name
                    )));
                }
            }
        }
        Ok(())
    }
}

/// A reference to the value behind a handle or struct pointer.
///
/// # Safety
///
/// `ptr` is `NULL` or points to a live `T` that nothing mutates during `'a`.
pub(crate) unsafe fn object<'a, T>(ptr: *const T, name: &str) -> Result<&'a T, Error> {
    check(ptr, 1, name)?;
    // SAFETY: non-null and aligned (`check`); live and unaliased by the
    // caller's contract.
    Ok(unsafe { &*ptr })
}

/// A mutable reference to the value behind a handle (a builder's setter).
///
/// # Safety
///
/// `ptr` is `NULL` or points to a live `T` that nothing else reads or
/// writes during `'a`.
pub(crate) unsafe fn object_mut<'a, T>(ptr: *mut T, name: &str) -> Result<&'a mut T, Error> {
    check(ptr, 1, name)?;
    // SAFETY: non-null and aligned (`check`); live and not used elsewhere
    // by the caller's contract.
    Ok(unsafe { &mut *ptr })
}

/// Writes `value` to an out-parameter.
///
/// # Safety
///
/// `ptr` is `NULL` or points to memory writable as a `T`.
pub(crate) unsafe fn write<T>(ptr: *mut T, value: T, name: &str) -> Result<(), Error> {
    check(ptr, 1, name)?;
    // SAFETY: non-null and aligned (`check`); writable by the caller's
    // contract. `write` does not read or drop the old contents.
    unsafe { ptr.write(value) };
    Ok(())
}

/// `value` boxed and handed to the caller at `*out`, a handle its
/// `aacmm_…_free` releases ([`release`]); dropped again when `out` cannot
/// take it, so a failed call leaks nothing.
///
/// # Safety
///
/// `out` is `NULL` or points to memory writable as a pointer.
pub(crate) unsafe fn hand_out<T>(out: *mut *mut T, value: T, name: &str) -> Result<(), Error> {
    let handle = Box::into_raw(Box::new(value));
    // SAFETY: by the contract.
    let written = unsafe { write(out, handle, name) };
    if written.is_err() {
        // SAFETY: made just above and never handed out.
        drop(unsafe { Box::from_raw(handle) });
    }
    written
}

/// Releases a handle [`hand_out`] made; `NULL` does nothing.
///
/// # Safety
///
/// `handle` is `NULL` or a live handle of type `T`, which the caller gives
/// up.
pub(crate) unsafe fn release<T>(handle: *mut T) {
    if !handle.is_null() {
        // SAFETY: a live handle made by `Box::into_raw`, given up by the
        // caller.
        drop(unsafe { Box::from_raw(handle) });
    }
}

/// A C string argument.
///
/// # Safety
///
/// `ptr` is `NULL` or points to a NUL-terminated string that lives and is
/// not mutated during `'a`.
pub(crate) unsafe fn c_str<'a>(ptr: *const c_char, name: &str) -> Result<&'a CStr, Error> {
    if ptr.is_null() {
        return Err(Error::null(name));
    }
    // SAFETY: non-null; NUL-terminated and live by the caller's contract.
    Ok(unsafe { CStr::from_ptr(ptr) })
}

/// A path argument: bytes as they are on Unix, UTF-8 elsewhere.
///
/// # Safety
///
/// As [`c_str`].
pub(crate) unsafe fn path(ptr: *const c_char, name: &str) -> Result<PathBuf, Error> {
    // SAFETY: forwarded contract.
    let s = unsafe { c_str(ptr, name) }?;
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        Ok(PathBuf::from(std::ffi::OsStr::from_bytes(s.to_bytes())))
    }
    #[cfg(not(unix))]
    {
        s.to_str()
            .map(PathBuf::from)
            .map_err(|_| Error::invalid(format!("`{name}` is not valid UTF-8")))
    }
}

/// Copies `s` into `buf` as a NUL-terminated string of at most
/// `buf_len - 1` bytes, cut at a character boundary; nothing when
/// `buf_len` is 0 or `buf` is `NULL`. Returns whether all of `s` and its
/// NUL fitted.
///
/// # Safety
///
/// `buf` points to at least `buf_len` writable bytes (it may be `NULL` only
/// when `buf_len` is 0).
pub(crate) unsafe fn copy_str(s: &str, buf: *mut c_char, buf_len: usize) -> bool {
    if buf_len == 0 || buf.is_null() {
        return false;
    }
    let mut n = s.len().min(buf_len - 1);
    while !s.is_char_boundary(n) {
        n -= 1;
    }
    // SAFETY: `buf` has `buf_len > n` writable bytes; `s` and `buf` do not
    // overlap (`s` is Rust-owned).
    unsafe {
        std::ptr::copy_nonoverlapping(s.as_ptr().cast::<c_char>(), buf, n);
        buf.add(n).write(0);
    }
    n == s.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn copies_cut_at_a_character_boundary() {
        let mut buf = [1 as c_char; 4];
        // SAFETY: `buf` has 4 writable bytes.
        assert!(!unsafe { copy_str("aσb", buf.as_mut_ptr(), 3) });
        assert_eq!(buf[..2], [b'a' as c_char, 0]);
        // SAFETY: as above.
        assert!(unsafe { copy_str("aσ", buf.as_mut_ptr(), 4) });
        assert_eq!(buf[3], 0);
    }

    #[test]
    fn outputs_are_written_without_reading() {
        // Uninitialised `bool`s: only `MaybeUninit` may refer to them.
        let mut buf = [MaybeUninit::<bool>::uninit(); 3];
        // SAFETY: `buf` holds 3 writable `bool`s, used only through `out`.
        let out = unsafe { output(buf.as_mut_ptr().cast::<bool>(), 3, "flags") }.unwrap();
        for (i, slot) in out.iter_mut().enumerate() {
            slot.write(i == 1);
        }
        // SAFETY: every element was written above.
        let flags = unsafe { buf.map(|b| b.assume_init()) };
        assert_eq!(flags, [false, true, false]);
        // SAFETY: refused before any use.
        assert!(unsafe { output::<f64>(std::ptr::null_mut(), 1, "p") }.is_err());
    }

    fn at<T>(address: usize) -> *mut T {
        std::ptr::without_provenance_mut(address)
    }

    #[test]
    fn overlaps_are_found() {
        let check = |a: usize, a_len: usize, b: usize, b_len: usize| {
            Args::new()
                .input("a", at::<u64>(a), a_len)?
                .output("b", at::<u64>(b), b_len)?
                .disjoint()
        };
        assert!(check(128, 2, 144, 1).is_ok());
        let err = check(128, 2, 136, 1).unwrap_err();
        assert_eq!(err.status, crate::error::AacmmStatus::InvalidArgument);
        assert_eq!(err.message, "`a` and `b` overlap; pass separate buffers");
        assert!(check(128, 0, 128, 1).is_ok(), "empty");
        assert!(check(0, 4, 0, 4).is_ok(), "NULL: refused where used");
        // Two inputs may share memory; an output may not share an
        // output's.
        let inputs = Args::new().input("a", at::<u64>(128), 2).unwrap();
        assert!(
            inputs
                .input("b", at::<u64>(128), 2)
                .unwrap()
                .disjoint()
                .is_ok()
        );
        let outputs = Args::new().out("a", at::<u64>(128));
        assert!(outputs.out("b", at::<u32>(132)).disjoint().is_err());
    }

    /// A length past what memory holds is a length error, before (and
    /// never mistaken for) an overlap.
    #[test]
    fn sizes_are_checked_before_overlap() {
        let err = Args::new()
            .input("q", at::<f64>(64), usize::MAX - 3)
            .unwrap_err();
        assert_eq!(err.status, crate::error::AacmmStatus::Length);
        assert!(err.message.starts_with("`q`: length"), "{}", err.message);
        let near_the_end = usize::MAX - 15;
        let err = Args::new()
            .input("q", at::<u8>(near_the_end), 64)
            .and_then(|a| a.output("p", at::<u8>(64), 8))
            .and_then(Args::disjoint)
            .unwrap_err();
        assert_eq!(err.status, crate::error::AacmmStatus::Length);
    }

    #[test]
    fn null_and_misaligned_pointers_are_refused() {
        // SAFETY: the pointers are checked before any use.
        unsafe {
            assert!(input::<f64>(std::ptr::null(), 0, "q").unwrap().is_empty());
            assert!(input::<f64>(std::ptr::null(), 1, "q").is_err());
            let v = [0.0f64; 2];
            let odd = v.as_ptr().cast::<u8>().add(1).cast::<f64>();
            assert!(input::<f64>(odd, 1, "q").is_err());
            assert!(input::<f64>(v.as_ptr(), usize::MAX / 4, "q").is_err());
        }
    }
}
