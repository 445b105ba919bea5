//! Errors on their way to Python: the library's typed errors become one
//! [`Error`] (a kind and the library's message, `Send` so that it can leave
//! a block run without the GIL), then a Python exception. [`guard`] catches
//! panics so that none unwinds into the interpreter.

use std::panic::{AssertUnwindSafe, catch_unwind};

use aacmm_core::calibrate::CalibrationError as CoreCalibrationError;
use aacmm_core::error::InputError as CoreInputError;
use aacmm_core::error::OptionError;
use aacmm_core::kernel::KernelError;
use aacmm_core::metrics::MetricsError;
use aacmm_core::setting::{Setting, Spelling};
use aacmm_core::simulate::SimError;
use pyo3::PyErr;
use pyo3::exceptions::{PyException, PyMemoryError, PyOSError, PyValueError};

pyo3::create_exception!(
    aacmm,
    AacmmError,
    PyException,
    "Base class of the errors aacmm raises (besides OSError for unreadable files and \
     ValueError/TypeError for malformed arguments)."
);
pyo3::create_exception!(
    aacmm,
    InputError,
    AacmmError,
    "Invalid input data: a file's content (the message names file, line and field) or \
     arrays (the message names the argument and index)."
);
pyo3::create_exception!(
    aacmm,
    CalibrationError,
    AacmmError,
    "The calibration (or identification, evaluation, simulation) cannot run on this input: \
     too few residuals, a fixed set that leaves a direction the data cannot see, a start arm \
     that gives non-finite positions, impossible settings."
);
pyo3::create_exception!(
    aacmm,
    UnsupportedError,
    AacmmError,
    "An arm with a joint count the toolkit has no kernel for (it has 6 and 7)."
);

/// What kind of exception an [`Error`] becomes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    /// `aacmm.InputError`.
    Input,
    /// `OSError`: a file that cannot be read or written.
    Io,
    /// `aacmm.CalibrationError`.
    Calibration,
    /// `aacmm.UnsupportedError`.
    Unsupported,
    /// `ValueError`: an argument out of range or of the wrong shape.
    Value,
    /// `aacmm.AacmmError`: a bug inside aacmm (a caught panic).
    Internal,
    /// `MemoryError`: an output or a copy sized by the input that cannot be
    /// allocated (refused before any work, as numpy refuses).
    Memory,
}

/// Refuses an output directory `dir` that is empty (the current directory
/// by accident) or that holds results of any aacmm command (the library's
/// rule, [`aacmm_core::report::earlier_results`]: a calibration's, a
/// campaign's, a report's) unless `force`, as the command line refuses
/// without `--force`.
pub(crate) fn check_out_dir(dir: &std::path::Path, force: bool) -> Result<()> {
    if dir.as_os_str().is_empty() {
        return Err(Error::new(
            Kind::Value,
            "dir: empty; give a directory (\".\" for the current one)",
        ));
    }
    let found = aacmm_core::report::earlier_results(dir);
    if !force && let Some(name) = found.first() {
        return Err(Error::new(
            Kind::Io,
            format!(
                "{}: holds an earlier result ({name}); write(..., force=True) writes over it",
                dir.display()
            ),
        ));
    }
    Ok(())
}

/// The product of `dims` (an array's element count), or a `MemoryError`
/// naming `what` when it overflows.
pub(crate) fn elements(dims: &[usize], what: &str) -> Result<usize> {
    dims.iter()
        .try_fold(1usize, |n, &d| n.checked_mul(d))
        .filter(|n| n.checked_mul(size_of::<f64>()).is_some())
        .ok_or_else(|| {
            Error::new(
                Kind::Memory,
                format!("{what}: an array of shape {dims:?} cannot be allocated"),
            )
        })
}

/// An empty buffer with room for `count` values, or a `MemoryError` naming
/// `what`: a hostile size is refused, not an abort of the process.
pub(crate) fn buffer<T>(count: usize, what: &str) -> Result<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(count).map_err(|e| {
        Error::new(
            Kind::Memory,
            format!("{what}: {count} values cannot be allocated ({e})"),
        )
    })?;
    Ok(v)
}

/// An error with the library's message.
#[derive(Debug)]
pub(crate) struct Error {
    pub(crate) kind: Kind,
    pub(crate) message: String,
}

/// The result of the bindings' Rust side.
pub(crate) type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub(crate) fn new(kind: Kind, message: impl Into<String>) -> Error {
        Error {
            kind,
            message: message.into(),
        }
    }

    /// A bad argument (`ValueError`).
    pub(crate) fn value(message: impl Into<String>) -> Error {
        Error::new(Kind::Value, message)
    }

    /// The same error with `what: ` before its message.
    pub(crate) fn prefixed(mut self, what: &str) -> Error {
        self.message = format!("{what}: {}", self.message);
        self
    }
}

impl From<Error> for PyErr {
    fn from(e: Error) -> PyErr {
        match e.kind {
            Kind::Input => InputError::new_err(e.message),
            Kind::Io => PyOSError::new_err(e.message),
            Kind::Calibration => CalibrationError::new_err(e.message),
            Kind::Unsupported => UnsupportedError::new_err(e.message),
            Kind::Value => PyValueError::new_err(e.message),
            Kind::Internal => AacmmError::new_err(e.message),
            Kind::Memory => PyMemoryError::new_err(e.message),
        }
    }
}

impl From<CoreInputError> for Error {
    fn from(e: CoreInputError) -> Error {
        let kind = match e {
            CoreInputError::Io { .. } => Kind::Io,
            CoreInputError::Memory { .. } => Kind::Memory,
            _ => Kind::Input,
        };
        Error::new(kind, e.to_string())
    }
}

impl From<KernelError> for Error {
    fn from(e: KernelError) -> Error {
        let kind = match e {
            KernelError::Unsupported(_) => Kind::Unsupported,
            _ => Kind::Value,
        };
        Error::new(kind, e.to_string())
    }
}

impl From<aacmm_core::residuals::TermError> for Error {
    fn from(e: aacmm_core::residuals::TermError) -> Error {
        match e {
            aacmm_core::residuals::TermError::Kernel(k) => k.into(),
            other => Error::new(Kind::Value, other.to_string()),
        }
    }
}

/// A refused setting as a `ValueError` naming the Python argument. The
/// encoder σ is refused in the library's radians, so its message gives the
/// reason only (the caller knows the degrees it passed), as the command line
/// does. Settings the bindings do not expose keep the library's path.
impl From<OptionError> for Error {
    fn from(e: OptionError) -> Error {
        let message = match e.setting.argument(Spelling::Python) {
            Some(arg) if e.setting == Setting::EncoderNoise => format!("{arg}: {}", e.reason),
            Some(arg) => format!("{arg} = {}: {}", e.value, e.reason),
            None => e.to_string(),
        };
        Error::value(message)
    }
}

impl From<CoreCalibrationError> for Error {
    fn from(e: CoreCalibrationError) -> Error {
        let kind = match &e {
            CoreCalibrationError::Option(o) => return o.clone().into(),
            CoreCalibrationError::Kernel(KernelError::Unsupported(_)) => Kind::Unsupported,
            // Noise whose weights overflow or vanish: a bad argument, as in
            // `identify` (one rule per setting).
            CoreCalibrationError::Kernel(KernelError::Noise { .. }) => Kind::Value,
            CoreCalibrationError::Joints { .. } => Kind::Value,
            CoreCalibrationError::Memory(_) => Kind::Memory,
            _ => Kind::Calibration,
        };
        Error::new(kind, e.to_string())
    }
}

impl From<aacmm_core::report::ReportError> for Error {
    fn from(e: aacmm_core::report::ReportError) -> Error {
        Error::new(Kind::Calibration, e.to_string())
    }
}

impl From<aacmm_core::memory::OutOfMemory> for Error {
    fn from(e: aacmm_core::memory::OutOfMemory) -> Error {
        Error::new(Kind::Memory, e.to_string())
    }
}

impl From<MetricsError> for Error {
    fn from(e: MetricsError) -> Error {
        let kind = match e {
            MetricsError::Memory(_) => Kind::Memory,
            _ => Kind::Calibration,
        };
        Error::new(kind, e.to_string())
    }
}

/// The Python argument of each simulation setting ([`SimError::Setting`]'s
/// key in `campaign.toml`) `simulate` exposes; the others keep their key.
const SIM_ARGUMENTS: [(&str, &str); 2] = [
    ("poses_per_socket", "poses"),
    ("sockets.points", "sockets_file"),
];

/// A refused simulation setting is a `ValueError` naming the Python
/// argument, as a refused calibration setting is; a campaign the arm cannot
/// perform is an `aacmm.CalibrationError`.
impl From<SimError> for Error {
    fn from(e: SimError) -> Error {
        match e {
            SimError::Input(e) => e.into(),
            SimError::Setting { name, message } => {
                let arg = SIM_ARGUMENTS
                    .iter()
                    .find(|(key, _)| *key == name)
                    .map_or(name.as_str(), |(_, arg)| arg);
                Error::value(format!("{arg}: {message}"))
            }
            SimError::Kernel(k) => k.into(),
            e => Error::new(Kind::Calibration, e.to_string()),
        }
    }
}

/// Runs `body`, turning a panic into an [`Kind::Internal`] error: no panic
/// unwinds into Python (where PyO3 would raise `PanicException`, which is
/// not an `Exception`).
pub(crate) fn guard<T>(body: impl FnOnce() -> Result<T>) -> Result<T> {
    catch_unwind(AssertUnwindSafe(body)).unwrap_or_else(|payload| {
        let what = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "a panic without a message".to_string());
        Err(Error::new(
            Kind::Internal,
            format!("internal error in aacmm (please report it): {what}"),
        ))
    })
}

/// How often a long calibration looks for Ctrl-C (Python's signal
/// handlers run only on the main thread, between its bytecodes: this
/// thread runs them while the work runs on another).
const SIGNAL_POLL: std::time::Duration = std::time::Duration::from_millis(20);

/// [`detached`] for a calibration that Ctrl-C may stop: `body` runs on a
/// thread of its own with `cancel` (the token its solvers check) while this
/// one, the caller's, wakes every [`SIGNAL_POLL`] to run Python's signal
/// handlers. A `KeyboardInterrupt` (or any exception a handler raises)
/// sets the token, waits for the work to stop at its next check, and is
/// raised as it is — no half-finished result.
pub(crate) fn interruptible<T: Send>(
    py: pyo3::Python<'_>,
    cancel: &aacmm_core::calibrate::Cancel,
    body: impl FnOnce() -> Result<T> + Send,
) -> pyo3::PyResult<T> {
    let mut raised: Option<PyErr> = None;
    let result = py.detach(|| {
        std::thread::scope(|s| {
            let (done, finished) = std::sync::mpsc::channel::<()>();
            let work = s.spawn(move || {
                let r = guard(body);
                let _ = done.send(());
                r
            });
            while raised.is_none() {
                match finished.recv_timeout(SIGNAL_POLL) {
                    Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                        if let Err(e) = pyo3::Python::attach(|py| py.check_signals()) {
                            cancel.cancel();
                            raised = Some(e);
                        }
                    }
                    _ => break,
                }
            }
            work.join().unwrap_or_else(|_| {
                Err(Error::new(
                    Kind::Internal,
                    "internal error in aacmm: a worker died",
                ))
            })
        })
    });
    match raised {
        Some(e) => Err(e),
        None => result.map_err(PyErr::from),
    }
}

/// Runs `body` without the GIL (other Python threads run meanwhile), with
/// panics caught.
pub(crate) fn detached<T: Send>(
    py: pyo3::Python<'_>,
    body: impl FnOnce() -> Result<T> + Send,
) -> pyo3::PyResult<T> {
    py.detach(|| guard(body)).map_err(PyErr::from)
}
