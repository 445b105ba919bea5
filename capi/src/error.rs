//! Result codes, the thread-local last-error message, and [`guard`]: the
//! wrapper every entry point runs its body in, so that an error becomes a
//! code plus a message and a panic never unwinds into C.

use std::cell::{Cell, RefCell};
use std::ffi::c_char;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Once;

use aacmm_core::calibrate::CalibrationError;
use aacmm_core::error::InputError;
use aacmm_core::error::OptionError;
use aacmm_core::kernel::KernelError;
use aacmm_core::parallel::WORKER_THREAD_NAME;
use aacmm_core::setting::Spelling;

use crate::ptr::copy_str;

/// What a call returns: `AACMM_STATUS_OK` (0), or why it failed. On failure
/// `aacmm_last_error_message` describes the error, and output handles are
/// set to `NULL` — unless the arguments themselves were refused (an output
/// that overlaps another argument, a length past what memory can hold):
/// then nothing is written.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AacmmStatus {
    /// Success.
    Ok = 0,
    /// A required pointer argument is `NULL` (or a buffer pointer is `NULL`
    /// while its length is not 0).
    NullPointer = 1,
    /// A buffer length does not match what the arm and the other arguments
    /// imply (e.g. `p_len != 3 · q_len / joints`), or is larger than memory
    /// can hold (what it implies included).
    Length = 2,
    /// An argument's value is out of range: a non-finite parameter, an
    /// unknown method, an unknown parameter name, a negative noise, a
    /// misaligned buffer, an output that shares memory with an input or
    /// another output, a path that is not valid text.
    InvalidArgument = 3,
    /// The arm has a joint count the toolkit has no kernel for (it
    /// computes chains of 1 to 12 joints).
    Unsupported = 4,
    /// A file could not be read (missing, unreadable).
    Io = 5,
    /// A file or an input array has invalid content: the message names the
    /// file (or array), line and field.
    Input = 6,
    /// The calibration cannot run on this data: too few residuals, a fixed
    /// set that leaves a direction the data cannot see, a start arm that
    /// gives non-finite positions.
    Calibration = 7,
    /// A string did not fit the caller's buffer: a truncated, NUL-terminated
    /// copy was written and the full length reported.
    BufferTooSmall = 8,
    /// The result has no such thing: an uncertainty map of a calibration
    /// whose covariance is not finite, the arm of a refused probe
    /// qualification.
    NotAvailable = 9,
    /// Memory for a result or a temporary sized by the input could not be
    /// allocated (under an address-space limit, or more than the machine
    /// has: see the README's "Limits and memory"; a cgroup memory limit is not
    /// seen, and ends the process later): nothing was computed, the host
    /// process is unaffected, and the message says how much was asked for.
    OutOfMemory = 10,
    /// The calibration was stopped by its cancellation token
    /// (`aacmm_cancel_set`): no result.
    Cancelled = 11,
    /// An internal error (a bug in aacmm) was caught; the host process is
    /// unaffected and the message says what happened.
    Panic = 99,
}

/// An error on its way to C: a code and a message.
#[derive(Debug)]
pub(crate) struct Error {
    pub(crate) status: AacmmStatus,
    pub(crate) message: String,
}

impl Error {
    pub(crate) fn new(status: AacmmStatus, message: impl Into<String>) -> Error {
        Error {
            status,
            message: message.into(),
        }
    }

    pub(crate) fn null(name: &str) -> Error {
        Error::new(AacmmStatus::NullPointer, format!("`{name}` is NULL"))
    }

    pub(crate) fn length(message: impl Into<String>) -> Error {
        Error::new(AacmmStatus::Length, message)
    }

    pub(crate) fn invalid(message: impl Into<String>) -> Error {
        Error::new(AacmmStatus::InvalidArgument, message)
    }

    pub(crate) fn out_of_memory(message: impl Into<String>) -> Error {
        Error::new(AacmmStatus::OutOfMemory, message)
    }
}

impl From<InputError> for Error {
    fn from(e: InputError) -> Error {
        let status = match e {
            InputError::Io { .. } => AacmmStatus::Io,
            InputError::Memory { .. } => AacmmStatus::OutOfMemory,
            _ => AacmmStatus::Input,
        };
        Error::new(status, e.to_string())
    }
}

impl From<KernelError> for Error {
    fn from(e: KernelError) -> Error {
        let status = match e {
            KernelError::Unsupported(_) => AacmmStatus::Unsupported,
            KernelError::Noise { .. } => AacmmStatus::InvalidArgument,
            _ => AacmmStatus::Length,
        };
        Error::new(status, e.to_string())
    }
}

impl From<CalibrationError> for Error {
    fn from(e: CalibrationError) -> Error {
        let status = match &e {
            CalibrationError::Kernel(KernelError::Unsupported(_)) => AacmmStatus::Unsupported,
            CalibrationError::Kernel(KernelError::Noise { .. }) => AacmmStatus::InvalidArgument,
            CalibrationError::Kernel(_) => AacmmStatus::Length,
            CalibrationError::Option(o) => return Error::from(o.clone()),
            CalibrationError::Memory(_) => AacmmStatus::OutOfMemory,
            CalibrationError::Cancelled => AacmmStatus::Cancelled,
            _ => AacmmStatus::Calibration,
        };
        Error::new(status, e.to_string())
    }
}

impl From<OptionError> for Error {
    /// `AACMM_STATUS_INVALID_ARGUMENT`, naming the option as its setter
    /// does (`probe_noise_mm = -1: …`); settings the C API does not expose
    /// keep their library path.
    fn from(o: OptionError) -> Error {
        let option = (o.setting.argument(Spelling::C)).unwrap_or(o.field());
        Error::invalid(format!("{option} = {}: {}", o.value, o.reason))
    }
}

thread_local! {
    static LAST_ERROR: RefCell<String> = const { RefCell::new(String::new()) };
    /// How many guarded calls this thread is inside (a guarded body may
    /// call another entry point).
    static GUARDED: Cell<usize> = const { Cell::new(0) };
    /// Where the last quiet panic on this thread happened, for its message.
    static PANIC_AT: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Installs, once per process, a panic hook that stays silent for panics
/// inside a guarded call or on the library's worker threads: the host's
/// stderr is the host's, and the call's status and message already say
/// what happened. Other panics (the host's own, if it is Rust) go to the
/// hook that was installed before.
fn install_quiet_hook() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let guarded = GUARDED.try_with(Cell::get).unwrap_or(0) > 0;
            let worker = std::thread::current().name() == Some(WORKER_THREAD_NAME);
            if guarded || worker {
                if let Some(at) = info.location() {
                    let _ = PANIC_AT.try_with(|slot| *slot.borrow_mut() = Some(at.to_string()));
                }
            } else {
                previous(info);
            }
        }));
    });
}

/// Runs `body` counted as a guarded call on this thread (see
/// [`install_quiet_hook`]), catching a panic.
fn quietly<T>(body: impl FnOnce() -> T) -> std::thread::Result<T> {
    install_quiet_hook();
    let _ = GUARDED.try_with(|g| g.set(g.get() + 1));
    let result = catch_unwind(AssertUnwindSafe(body));
    let _ = GUARDED.try_with(|g| g.set(g.get().saturating_sub(1)));
    result
}

fn set_last_error(message: String) {
    // `try_with`: during thread teardown the slot may be gone; the code
    // still reaches the caller.
    let _ = LAST_ERROR.try_with(|slot| *slot.borrow_mut() = message);
}

/// Runs an entry point's body: `Ok` → `AACMM_STATUS_OK`; an error → its code,
/// with its message stored as the thread's last error; a panic → caught,
/// `AACMM_STATUS_PANIC`, and nothing printed (the message, with where it
/// happened, is the thread's last error).
pub(crate) fn guard(body: impl FnOnce() -> Result<(), Error>) -> AacmmStatus {
    match quietly(body) {
        Ok(Ok(())) => AacmmStatus::Ok,
        Ok(Err(e)) => {
            set_last_error(e.message);
            e.status
        }
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic without a message".to_string());
            let at = PANIC_AT
                .try_with(|slot| slot.borrow_mut().take())
                .ok()
                .flatten()
                .map(|at| format!(" (at {at})"))
                .unwrap_or_default();
            set_last_error(format!(
                "internal error in aacmm (please report it): {what}{at}"
            ));
            AacmmStatus::Panic
        }
    }
}

/// Runs a body that returns a value rather than a code (version, frees,
/// sizes); a panic gives `fallback`.
pub(crate) fn guard_value<T>(fallback: T, body: impl FnOnce() -> T) -> T {
    quietly(body).unwrap_or(fallback)
}

/// Copies the message of the last failed call on this thread into `buf`.
///
/// Writes at most `buf_len - 1` bytes of UTF-8 (cut at a character
/// boundary) and a terminating NUL; writes nothing when `buf` is `NULL` or
/// `buf_len` is 0. Returns the full length of the message in bytes, without
/// the NUL (0 when no call on this thread has failed), like `snprintf`: a
/// return value `>= buf_len` means the copy was truncated.
///
/// The message describes the most recent call that returned an error;
/// successful calls leave it unchanged. Each thread has its own.
///
/// # Safety
///
/// `buf` is `NULL` or points to at least `buf_len` writable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aacmm_last_error_message(buf: *mut c_char, buf_len: usize) -> usize {
    guard_value(0, || {
        LAST_ERROR
            .try_with(|slot| {
                let message = slot.borrow();
                if !buf.is_null() {
                    // SAFETY: `buf` is not NULL and the caller guarantees
                    // `buf_len` writable bytes there.
                    unsafe { copy_str(&message, buf, buf_len) };
                }
                message.len()
            })
            .unwrap_or(0)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_a_code_and_a_message() {
        let status = guard(|| panic!("boom {}", 7));
        assert_eq!(status, AacmmStatus::Panic);
        let mut buf = [0 as c_char; 128];
        // SAFETY: `buf` has 128 writable bytes.
        let n = unsafe { aacmm_last_error_message(buf.as_mut_ptr(), buf.len()) };
        // SAFETY: `copy_str` NUL-terminated it.
        let text = unsafe { std::ffi::CStr::from_ptr(buf.as_ptr()) };
        assert_eq!(text.to_bytes().len(), n);
        assert!(
            text.to_str()
                .unwrap()
                .contains(": boom 7 (at capi/src/error.rs:"),
            "{text:?}"
        );
        assert_eq!(guard_value(5, || -> i32 { panic!("x") }), 5);
    }

    /// Set in the child process of [`panics_print_nothing`].
    const CHILD: &str = "AACMM_CAPI_QUIET_PANIC_CHILD";

    /// Panics inside guarded calls, on the calling thread and on a library
    /// worker thread; in the child process only (it checks nothing itself).
    #[test]
    fn quiet_panic_child() {
        if std::env::var_os(CHILD).is_none() {
            return;
        }
        assert_eq!(guard(|| panic!("boom on the caller")), AacmmStatus::Panic);
        let status = guard(|| {
            std::thread::scope(|s| {
                std::thread::Builder::new()
                    .name(WORKER_THREAD_NAME.into())
                    .spawn_scoped(s, || panic!("boom on a worker"))
                    .map(|_| ())
                    .map_err(|e| Error::invalid(e.to_string()))
            })
        });
        assert_eq!(status, AacmmStatus::Panic);
        assert_eq!(guard_value(3, || -> i32 { panic!("boom in a value") }), 3);
        println!("child done");
    }

    /// A panic caught by the guard prints nothing on the host's stderr (no
    /// message, no backtrace), even with `RUST_BACKTRACE=1`: run in a child
    /// process, whose stderr is the test's to read.
    #[test]
    fn panics_print_nothing() {
        if std::env::var_os(CHILD).is_some() {
            return;
        }
        let exe = std::env::current_exe().expect("the test binary");
        let out = std::process::Command::new(exe)
            .args(["--exact", "error::tests::quiet_panic_child", "--nocapture"])
            .env(CHILD, "1")
            .env("RUST_BACKTRACE", "1")
            .output()
            .expect("the test binary runs");
        let stdout = String::from_utf8_lossy(&out.stdout);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{stdout}\n{stderr}");
        assert!(stdout.contains("child done"), "{stdout}");
        assert!(!stderr.contains("boom"), "{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }

    #[test]
    fn the_message_names_where_the_panic_happened() {
        assert_eq!(guard(|| panic!("located")), AacmmStatus::Panic);
        let mut buf = [0 as c_char; 256];
        // SAFETY: `buf` has 256 writable bytes.
        unsafe { aacmm_last_error_message(buf.as_mut_ptr(), buf.len()) };
        // SAFETY: `copy_str` NUL-terminated it.
        let text = unsafe { std::ffi::CStr::from_ptr(buf.as_ptr()) };
        let text = text.to_str().unwrap();
        assert!(text.contains("located (at capi/src/error.rs:"), "{text}");
    }

    #[test]
    fn the_message_is_per_thread_and_kept_across_successes() {
        assert_eq!(
            guard(|| Err(Error::invalid("first"))),
            AacmmStatus::InvalidArgument
        );
        assert_eq!(guard(|| Ok(())), AacmmStatus::Ok);
        // SAFETY: a NULL buffer of length 0 only asks for the length.
        let len = unsafe { aacmm_last_error_message(std::ptr::null_mut(), 0) };
        assert_eq!(len, 5);
        let other = std::thread::spawn(|| {
            // SAFETY: as above.
            unsafe { aacmm_last_error_message(std::ptr::null_mut(), 0) }
        });
        assert_eq!(other.join().unwrap(), 0);
    }
}
