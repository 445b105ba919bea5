//! Errors in user input, located as precisely as the input allows: in a
//! file ([`InputError`]) or in a setting ([`OptionError`]).
//!
//! Every message names the file; where known, also the 1-based line and the
//! field (a TOML key or a CSV column). Readers never panic on bad input and
//! never drop data silently: they either return the data or one of these.

use crate::setting::Setting;

/// A problem with user input, located precisely.
///
/// [`Display`](std::fmt::Display) always starts with the file name, then the line
/// and the field where known:
///
/// ```
/// use aacmm_core::error::InputError;
/// let e = InputError::field("arm.toml", 7, "alpha", "expected a number, found a string");
/// assert_eq!(e.to_string(), "arm.toml:7: field `alpha`: expected a number, found a string");
/// let e = InputError::field("arm.toml", 0, "length_unit", "missing");
/// assert_eq!(e.to_string(), "arm.toml: field `length_unit`: missing");
/// assert_eq!(e.line(), None);
/// ```
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// A problem with one field (TOML key, CSV column). `line` is 1-based;
    /// 0 means the field concerns the whole file (e.g. a missing key), and the
    /// message then has no line number.
    #[error("{}", located(file, *line, Some(field), message))]
    Field {
        /// File name as given by the caller.
        file: String,
        /// 1-based line, or 0 for the whole file.
        line: usize,
        /// The key or column concerned.
        field: String,
        /// What is wrong, and what is expected.
        message: String,
    },
    /// A problem with one line as a whole (syntax, column count).
    #[error("{}", located(file, *line, None, message))]
    Line {
        /// File name as given by the caller.
        file: String,
        /// 1-based line.
        line: usize,
        /// What is wrong, and what is expected.
        message: String,
    },
    /// A problem with the file as a whole (e.g. no data).
    #[error("{file}: {message}")]
    File {
        /// File name as given by the caller.
        file: String,
        /// What is wrong, and what is expected.
        message: String,
    },
    /// The file could not be read or written. The OS error is part of the
    /// message, not a separate `source`, so error chains print it once.
    #[error("{file}: {error}")]
    Io {
        /// File name as given by the caller.
        file: String,
        /// The underlying error.
        error: std::io::Error,
    },
    /// The file (or what it asks for) needs more memory than the process
    /// can allocate: refused before the work, not an abort of the process.
    #[error("{file}: {error}")]
    Memory {
        /// File name as given by the caller.
        file: String,
        /// What the memory was for, and how much.
        error: crate::memory::OutOfMemory,
    },
}

/// `file:line: field `f`: message`, leaving out the unknown parts.
fn located(file: &str, line: usize, field: Option<&str>, message: &str) -> String {
    let mut s = String::from(file);
    if line > 0 {
        s.push_str(&format!(":{line}"));
    }
    s.push_str(": ");
    if let Some(field) = field {
        s.push_str(&format!("field `{field}`: "));
    }
    s.push_str(message);
    s
}

impl InputError {
    /// A [`InputError::Field`] error (`line` 0 = the whole file).
    pub fn field(
        file: impl Into<String>,
        line: usize,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> InputError {
        InputError::Field {
            file: file_shown(file.into()),
            line,
            field: shown(&field.into()),
            message: bounded(message.into()),
        }
    }

    /// A [`InputError::Line`] error.
    pub fn line_error(
        file: impl Into<String>,
        line: usize,
        message: impl Into<String>,
    ) -> InputError {
        InputError::Line {
            file: file_shown(file.into()),
            line,
            message: bounded(message.into()),
        }
    }

    /// A [`InputError::File`] error.
    pub fn file_error(file: impl Into<String>, message: impl Into<String>) -> InputError {
        InputError::File {
            file: file_shown(file.into()),
            message: bounded(message.into()),
        }
    }

    /// An [`InputError::Io`] error.
    pub(crate) fn io(file: impl Into<String>, source: std::io::Error) -> InputError {
        InputError::Io {
            file: file_shown(file.into()),
            error: source,
        }
    }

    /// An [`InputError::Memory`] error.
    pub(crate) fn memory(file: impl Into<String>, error: crate::memory::OutOfMemory) -> InputError {
        InputError::Memory {
            file: file_shown(file.into()),
            error,
        }
    }

    /// The file concerned.
    ///
    /// ```
    /// use aacmm_core::error::InputError;
    /// assert_eq!(InputError::file_error("p.csv", "no data rows").file(), "p.csv");
    /// ```
    pub fn file(&self) -> &str {
        match self {
            InputError::Field { file, .. }
            | InputError::Line { file, .. }
            | InputError::File { file, .. }
            | InputError::Io { file, .. }
            | InputError::Memory { file, .. } => file,
        }
    }

    /// The 1-based line concerned, if the error is about one line.
    ///
    /// ```
    /// use aacmm_core::error::InputError;
    /// assert_eq!(InputError::line_error("p.csv", 4, "bad").line(), Some(4));
    /// assert_eq!(InputError::file_error("p.csv", "bad").line(), None);
    /// ```
    pub fn line(&self) -> Option<usize> {
        match self {
            InputError::Field { line, .. } | InputError::Line { line, .. } if *line > 0 => {
                Some(*line)
            }
            _ => None,
        }
    }

    /// The field (TOML key or CSV column) concerned, if the error is about one.
    ///
    /// ```
    /// use aacmm_core::error::InputError;
    /// assert_eq!(InputError::field("p.csv", 4, "q2", "bad").field_name(), Some("q2"));
    /// ```
    pub fn field_name(&self) -> Option<&str> {
        match self {
            InputError::Field { field, .. } => Some(field),
            _ => None,
        }
    }

    /// The message without the location.
    pub fn message(&self) -> String {
        match self {
            InputError::Field { message, .. }
            | InputError::Line { message, .. }
            | InputError::File { message, .. } => message.clone(),
            InputError::Io { error, .. } => error.to_string(),
            InputError::Memory { error, .. } => error.to_string(),
        }
    }
}

/// A setting out of range: which one (a [`Setting`], named by its path
/// in the settings struct that holds it — `ModelOptions` or
/// `SolverSettings` of [`crate::calibrate`](mod@crate::calibrate) —, e.g.
/// `noise.probe_mm`, `anneal.cooling`, `global.max_starts`, `fix`,
/// `robust.scale_k`, `threads`, `cross_validate`) and why. A front end
/// names the setting in its own words from the setting's row
/// ([`Setting::argument`]).
///
/// ```
/// use aacmm_core::{calibrate::SolverSettings, error::OptionError, setting::Setting};
/// let mut o = SolverSettings::default();
/// o.anneal.cooling = 1.5;
/// let e: OptionError = o.check().unwrap_err();
/// assert_eq!(e.setting, Setting::AnnealCooling);
/// assert_eq!(e.field(), "anneal.cooling");
/// assert_eq!(e.to_string(), "anneal.cooling = 1.5: must lie strictly between 0 and 1");
/// ```
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{} = {value}: {reason}", .setting.path())]
#[non_exhaustive]
pub struct OptionError {
    /// The setting refused.
    pub setting: Setting,
    /// The value refused, as text (in the setting's own unit).
    pub value: String,
    /// Why it is refused.
    pub reason: String,
}

impl OptionError {
    /// A refusal of `value` for `setting`, because of `reason`.
    pub fn new(
        setting: Setting,
        value: impl std::fmt::Display,
        reason: impl Into<String>,
    ) -> OptionError {
        OptionError {
            setting,
            value: shown(&value.to_string()),
            reason: bounded(reason.into()),
        }
    }

    /// The setting's path in its settings struct (`noise.probe_mm`,
    /// `cross_validate`): how the library's own text names it.
    pub fn field(&self) -> &'static str {
        self.setting.path()
    }
}

/// `Ok` when `v` is finite and `> 0` (or `≥ 0` with `zero_ok`).
pub(crate) fn check_nonnegative(
    setting: Setting,
    v: f64,
    zero_ok: bool,
) -> Result<(), OptionError> {
    let ok = v.is_finite() && (v > 0.0 || (zero_ok && v == 0.0));
    if ok {
        Ok(())
    } else {
        let bound = if zero_ok { "≥ 0" } else { "> 0" };
        Err(OptionError::new(
            setting,
            short(v),
            format!("must be a finite number {bound}"),
        ))
    }
}

/// A length in words: metres from 10 m on (an arm's reach in a unit
/// mistake reads better so), else millimetres.
pub(crate) fn length_words(mm: f64) -> String {
    if mm.abs() >= 10_000.0 {
        format!("{:.1} m", mm / 1000.0)
    } else {
        format!("{mm:.1} mm")
    }
}

/// A number for a message: plain when of ordinary size, else in `e`
/// notation (`1e300`, not three hundred digits).
pub fn short(v: f64) -> String {
    if v == 0.0 || (1e-4..1e15).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Most characters of a user's text (a label, a token, a field, a value)
/// that a message echoes; longer text is cut, its length said.
pub(crate) const MAX_SHOWN: usize = 80;

/// Most characters of a whole message: a safety net for user text echoed
/// without [`shown`] (a message of the library's own words is far shorter).
pub(crate) const MAX_MESSAGE: usize = 4000;

/// User text as a message shows it: control characters escaped (`\r`,
/// `\n`, `\0`, `\u{1b}`), cut after `MAX_SHOWN` characters with its full
/// length said, so that a hostile input cannot make a huge or garbled
/// message.
///
/// ```
/// use aacmm_core::error::shown;
/// assert_eq!(shown("S1"), "S1");
/// assert_eq!(shown("q6\rS1\n\0"), "q6\\rS1\\n\\0");
/// let long = "x".repeat(50_000_000);
/// assert_eq!(shown(&long), format!("{}… (50000000 characters)", "x".repeat(80)));
/// ```
pub fn shown(s: &str) -> String {
    match cut(s, MAX_SHOWN) {
        (text, Some(n)) => format!("{text}… ({n} characters)"),
        (text, None) => text,
    }
}

/// [`shown`] between backticks, as messages quote a user's token: the
/// length of a cut one after the closing backtick.
///
/// ```
/// use aacmm_core::error::quoted;
/// assert_eq!(quoted("S99"), "`S99`");
/// assert_eq!(quoted("a\tb"), "`a\\tb`");
/// assert_eq!(quoted(&"é".repeat(100)), format!("`{}…` (100 characters)", "é".repeat(80)));
/// ```
pub fn quoted(s: &str) -> String {
    match cut(s, MAX_SHOWN) {
        (text, Some(n)) => format!("`{text}…` ({n} characters)"),
        (text, None) => format!("`{text}`"),
    }
}

/// The first `max` characters of `s` with control characters escaped, and
/// the count of all of them when `s` is longer.
fn cut(s: &str, max: usize) -> (String, Option<usize>) {
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i == max {
            return (out, Some(s.chars().count()));
        }
        match c {
            '\0' => out.push_str("\\0"),
            c if c.is_control() => out.extend(c.escape_default()),
            c => out.push(c),
        }
    }
    (out, None)
}

/// A file's name as messages show it: as [`shown`], with room for the
/// longest path a system accepts.
fn file_shown(file: String) -> String {
    if file.len() <= MAX_MESSAGE && !file.contains(char::is_control) {
        return file;
    }
    match cut(&file, MAX_MESSAGE) {
        (text, Some(n)) => format!("{text}… ({n} characters)"),
        (text, None) => text,
    }
}

/// A whole message, cut after [`MAX_MESSAGE`] characters (its length said):
/// the bound on what any message of the library can hold.
pub(crate) fn bounded(message: String) -> String {
    match message.char_indices().nth(MAX_MESSAGE) {
        Some((at, _)) => format!(
            "{}… ({} characters)",
            &message[..at],
            message.chars().count()
        ),
        None => message,
    }
}

/// Largest seed, in calibration and simulation alike: seeds are written to
/// TOML files (`campaign.toml`), whose integers stop at `i64::MAX`.
pub(crate) const MAX_SEED: u64 = i64::MAX as u64;

/// Why `seed` (above [`MAX_SEED`]) is refused.
pub(crate) fn seed_bound(seed: u64) -> String {
    format!("at most {MAX_SEED} (seeds are written as TOML integers), got {seed}")
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn error_max_seed() {
        use crate::{calibrate::SolverSettings, error::MAX_SEED};
        let s = SolverSettings {
            seed: MAX_SEED + 1,
            ..Default::default()
        };
        assert_eq!(s.check().unwrap_err().field(), "seed");
        assert!(
            SolverSettings {
                seed: MAX_SEED,
                ..Default::default()
            }
            .check()
            .is_ok()
        );
    }
}
