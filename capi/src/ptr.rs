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

/// Refuses buffers that share memory: an output that overlaps an input (or
/// another output) would alias a Rust reference.
pub(crate) fn disjoint(buffers: &[(&str, usize, usize)]) -> Result<(), Error> {
    for (i, &(a, start_a, bytes_a)) in buffers.iter().enumerate() {
        for &(b, start_b, bytes_b) in &buffers[i + 1..] {
            let overlap = bytes_a > 0
                && bytes_b > 0
                && start_a < start_b.saturating_add(bytes_b)
                && start_b < start_a.saturating_add(bytes_a);
            if overlap {
                return Err(Error::invalid(format!(
                    "`{a}` and `{b}` overlap; pass separate buffers"
                )));
            }
        }
    }
    Ok(())
}

/// `(name, address, bytes)` of `len` elements at `ptr`, for [`disjoint`].
pub(crate) fn span<T>(name: &str, ptr: *const T, len: usize) -> (&str, usize, usize) {
    (name, ptr as usize, len.saturating_mul(size_of::<T>()))
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

    #[test]
    fn overlaps_are_found() {
        assert!(disjoint(&[("a", 100, 16), ("b", 116, 8)]).is_ok());
        assert!(disjoint(&[("a", 100, 16), ("b", 108, 8)]).is_err());
        assert!(disjoint(&[("a", 100, 0), ("b", 100, 8)]).is_ok());
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
