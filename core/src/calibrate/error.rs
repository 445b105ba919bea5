//! Why a calibration could not run: [`CalibrationError`], and the remedy
//! of readings in radians read as degrees in each front end's words.

use crate::error::OptionError;
use crate::kernel::KernelError;
use crate::metrics::MetricsError;
use crate::residuals::TermError;

/// What to do about readings in radians read as degrees, in each front
/// end's words (the library serves all three).
pub(crate) const ANGLE_UNITS_REMEDY: &str = "read the poses as radians (command line \
     `--angle-unit rad`, Python `angle_unit=\"rad\"`, C `AACMM_ANGLE_RAD`)";

/// The remedy of [`CalibrationError::AngleUnits`], in each front end's
/// words (the library serves all three), and whether reading the angles as
/// radians makes the lengths agree with the nominal arm.
fn angle_units_remedy(ratio_as_rad: f64, lengths_agree: bool) -> String {
    let remedy = ANGLE_UNITS_REMEDY;
    if lengths_agree {
        format!(
            "{remedy}: read so, the lengths are {ratio_as_rad:.4} times the nominal arm's \
             distances (the lengths file is not the cause)"
        )
    } else {
        format!(
            "{remedy}; read so, the lengths are still {ratio_as_rad:.3e} times the nominal arm's \
             distances: check the lengths file's unit (mm) too"
        )
    }
}

/// Why a calibration could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CalibrationError {
    /// The calibration was cancelled (its [`Cancel`](super::Cancel) token was set) before
    /// it finished: there is no result.
    #[error("cancelled before the calibration finished: no result")]
    Cancelled,
    /// A setting out of range.
    #[error(transparent)]
    Option(#[from] OptionError),
    /// The kernel refused the arm or the data.
    #[error(transparent)]
    Kernel(#[from] KernelError),
    /// A residual term refused its own inputs.
    #[error("{term}: {message}")]
    Term {
        /// The term's name.
        term: String,
        /// What is wrong.
        message: String,
    },
    /// The metrics refused positions (validation).
    #[error(transparent)]
    Metrics(#[from] MetricsError),
    /// The data were read for another joint count than the arm's.
    #[error("the arm has {arm} joints, the data {data}")]
    Joints {
        /// The arm's joints.
        arm: usize,
        /// The data's joints.
        data: usize,
    },
    /// The reference lengths are in another unit than the arm.
    #[error(
        "{file}: the reference lengths are {ratio:.3e} times the nominal arm's distances between \
         the same points (median): lengths and arm in different units? (the arm file's lengths \
         are mm inside the toolkit; the lengths file must be in mm)"
    )]
    LengthUnits {
        /// The lengths file.
        file: String,
        /// Median of stated length / nominal distance.
        ratio: f64,
    },
    /// The reference lengths disagree with the nominal arm because the
    /// arm's own file is in another unit than it declares: its reach is
    /// no arm's (under 10 mm or over 10 m), so the arm, not the lengths
    /// file, is the cause.
    #[error(
        "{}: the arm file's lengths, in the unit its `length_unit` declares, make the arm {} \
         long (its reach), and the reference lengths are {ratio:.3e} times its distances \
         between the same points (median): the arm file's numbers are in another unit than it \
         declares (millimetres declared as metres make an arm 1000 times too long) — set \
         `length_unit` to the unit its numbers are in; the lengths file (mm) is not the cause",
        if file.is_empty() { "the arm" } else { file },
        crate::error::length_words(*reach_mm)
    )]
    ArmUnits {
        /// The arm file (empty when the caller did not name it).
        file: String,
        /// The arm's reach as its file declares it, mm.
        reach_mm: f64,
        /// Median of stated length / nominal distance.
        ratio: f64,
    },
    /// The reference lengths disagree with the nominal arm because the
    /// joint readings look like radians read as degrees (every one within
    /// ±2π "degrees"): the angle unit is the cause, not the lengths file.
    #[error(
        "{file}: every joint reading, read as degrees, is within ±6.28° — these angles look like \
         radians read as degrees, so the reference lengths come out {ratio:.3e} times the nominal \
         arm's distances; {}",
        angle_units_remedy(*ratio_as_rad, *lengths_agree)
    )]
    AngleUnits {
        /// The poses file.
        file: String,
        /// Median of stated length / nominal distance, as read.
        ratio: f64,
        /// The same with the readings taken as radians.
        ratio_as_rad: f64,
        /// Whether `ratio_as_rad` is within the bound the lengths are
        /// checked against.
        lengths_agree: bool,
    },
    /// Reference positions the nominal arm cannot be registered to: another
    /// unit, swapped axes, another arm.
    #[error("{file}:{line}: field `{field}`: {message}")]
    Positions {
        /// The positions file.
        file: String,
        /// The first line of the frame concerned.
        line: usize,
        /// The field concerned.
        field: String,
        /// What is wrong, and what to do.
        message: String,
    },
    /// The calibration needs more memory than the process can allocate,
    /// found before any work (see [`crate::memory`]).
    #[error(transparent)]
    Memory(#[from] crate::memory::OutOfMemory),
    /// A parameter vector of the wrong length (a bug, not user input).
    #[error("internal: parameter vector of the wrong length")]
    Shape,
    /// The start arm gives non-finite positions.
    #[error("the start arm gives positions that are not finite numbers")]
    NonFiniteStart,
    /// More unknowns than residuals.
    #[error(
        "{residuals} residuals for {unknowns} unknowns ({free} free parameters + 3 per point): \
         touch more points or fix more parameters"
    )]
    TooFewResiduals {
        /// Residual rows.
        residuals: usize,
        /// Unknowns.
        unknowns: usize,
        /// Free parameters.
        free: usize,
    },
    /// The fixed set leaves a direction the data cannot see.
    #[error(
        "the free parameters include directions the data cannot see: {}; fix more \
         parameters (the automatic fixed set chooses them)",
        directions.join("; ")
    )]
    Unidentifiable {
        /// The open directions, in words.
        directions: Vec<String>,
    },
}

impl CalibrationError {
    /// Whether the message starts with the input at fault (the lengths
    /// file, the poses file, the arm file of a unit mistake): a front end
    /// that names the arm file before other errors adds nothing to it.
    pub fn names_its_input(&self) -> bool {
        matches!(
            self,
            CalibrationError::LengthUnits { .. }
                | CalibrationError::AngleUnits { .. }
                | CalibrationError::ArmUnits { .. }
        )
    }
}

impl From<TermError> for CalibrationError {
    fn from(e: TermError) -> Self {
        match e {
            TermError::Kernel(k) => CalibrationError::Kernel(k),
            TermError::Invalid { term, message } => CalibrationError::Term { term, message },
            TermError::Layout(e) => CalibrationError::Term {
                term: "layout".to_string(),
                message: e.to_string(),
            },
        }
    }
}
