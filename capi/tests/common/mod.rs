//! What the C API's test programs share.

use std::ffi::{CStr, c_char};

use aacmm_capi::aacmm_last_error_message;

/// The calling thread's last error message (`aacmm_last_error_message`).
pub fn last_error() -> String {
    let mut buf = [0 as c_char; 1024];
    // SAFETY: `buf` has 1024 writable bytes.
    unsafe { aacmm_last_error_message(buf.as_mut_ptr(), buf.len()) };
    // SAFETY: NUL-terminated by the call.
    unsafe { CStr::from_ptr(buf.as_ptr()) }
        .to_string_lossy()
        .into_owned()
}
