//! Whether a calibration may be used, typed: each reason for a refusal
//! ([`Reason`]) and each note beside a verdict ([`Note`]) carries its data
//! (the χ² figures, the parameters and their corrections, the outliers'
//! `file:line`, the unconfirmed search's counts), and says itself in the
//! words of the front end that asks ([`Spelling`]): the command line's
//! flags, Python's keyword arguments or C's setters, each option named once
//! ([`Setting`]). A program matches on the variants; a person reads
//! [`Reason::describe`].
//!
//! `calibration.json`'s `/verdict` and `calibrated.toml`'s `[verdict]` keep
//! the command line's sentences ([`Verdict::words`]): read back, a reason is
//! the sentence it was written as ([`Reason::Recorded`]).

use serde::{Deserialize, Serialize};

use crate::calibrate::checks::{ChiSquare, GrossCorrection, Outlier};
use crate::domain::ArmVerdict;
use crate::residuals::Noise;
pub use crate::setting::{Setting, Spelling};

mod checks;
#[cfg(test)]
mod tests;
mod words;

pub(super) use checks::verdict_of;

/// Whether a calibration may be used: exit 0 of the command line. Written
/// into `calibration.json` and `calibrated.toml` in the command line's
/// words ([`Verdict::words`], the [`ArmVerdict`] a reader of those files
/// gets back).
#[derive(Clone, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct Verdict {
    /// Usable: no reason against it.
    pub usable: bool,
    /// Why not (empty when usable), the first cause first.
    pub reasons: Vec<Reason>,
    /// What a metrologist should know although the result is usable.
    pub notes: Vec<Note>,
}

impl Verdict {
    /// The verdict in `spelling`'s words: its reasons and notes as
    /// sentences.
    pub fn words(&self, spelling: Spelling) -> ArmVerdict {
        ArmVerdict {
            usable: self.usable,
            reasons: self.reasons.iter().map(|r| r.describe(spelling)).collect(),
            notes: self.notes.iter().map(|n| n.describe(spelling)).collect(),
        }
    }
}

impl Serialize for Verdict {
    /// The command line's words: `calibration.json`'s `/verdict`.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.words(Spelling::Cli).serialize(s)
    }
}

impl<'de> Deserialize<'de> for Verdict {
    /// A verdict read back from its sentences: each a [`Reason::Recorded`]
    /// or [`Note::Recorded`].
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Verdict, D::Error> {
        let words = ArmVerdict::deserialize(d)?;
        Ok(Verdict {
            usable: words.usable,
            reasons: (words.reasons.into_iter())
                .map(|text| Reason::Recorded { text })
                .collect(),
            notes: (words.notes.into_iter())
                .map(|text| Note::Recorded { text })
                .collect(),
        })
    }
}

/// One reason a calibration is refused, with its data. Said in a front
/// end's words by [`Reason::describe`].
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
#[non_exhaustive]
pub enum Reason {
    /// Every joint reading is within ±2π read as degrees: radians read as
    /// degrees, the cause of the reasons after it.
    RadiansAsDegrees {
        /// The poses file.
        poses_file: String,
    },
    /// The data and the arm disagree: the global search found no arm of
    /// the nominal's kind, or its best leaves residuals hundreds of times
    /// the stated noise.
    DataDisagreeWithArm {
        /// The minima the search found when none was of the nominal's
        /// kind.
        minima_of_other_kinds: Option<usize>,
        /// σ̂₀ of the best minimum when hundreds of times the noise.
        far_sigma0: Option<f64>,
        /// A touch's stated σ, mm.
        touch_sigma_mm: f64,
        /// The arm's joints.
        joints: usize,
    },
    /// A few outliers pull the fit: the likely cause.
    Outliers {
        /// How many.
        count: usize,
        /// The first five.
        named: Vec<Outlier>,
        /// What each is of: `touch`, `target`, `point on its sphere`,
        /// `orientation`, `observation`.
        what: String,
        /// A robust loss was in use (and is not recommended again).
        robust_in_use: bool,
    },
    /// The solver did not reach a confirmed minimum.
    Unconfirmed {
        /// How it stopped, in words.
        stop: String,
        /// A global search that spent its starts: how many it had and
        /// whether a prior was in use (the remedy).
        search: Option<UnconfirmedSearch>,
    },
    /// Parameters the data determine moved implausibly far: a mirror
    /// image, a collapse, a unit mistake.
    NotNominalGeometry {
        /// The moves.
        moves: Vec<GrossCorrection>,
    },
    /// Parameters the data barely determine moved implausibly far.
    Undetermined {
        /// The moves, each with its σ (in its unit).
        moves: Vec<(GrossCorrection, f64)>,
        /// A prior was in use.
        prior_in_use: bool,
    },
    /// An auxiliary block's values are physically impossible.
    ImplausibleBlocks {
        /// Each block's complaint.
        blocks: Vec<String>,
    },
    /// The χ² test refuses the fit.
    ChiSquare {
        /// The test.
        chi: ChiSquare,
        /// The noise stated, when the fit is otherwise sound (a
        /// misstated noise is then a possible cause: said with the Birge
        /// ratio).
        stated: Option<StatedNoise>,
    },
    /// The robust scale's test refuses the fit.
    RobustScale {
        /// The test, in words.
        description: String,
    },
    /// Worse than nominal at its own reference positions.
    WorseAtPositions {
        /// Mean 3-D error before, mm.
        before_mm: f64,
        /// After, mm.
        after_mm: f64,
    },
    /// Worse than nominal on its own data.
    WorseOnData {
        /// The headline figure's name.
        what: String,
        /// Before, mm.
        before_mm: f64,
        /// After, mm.
        after_mm: f64,
    },
    /// A reason read back from a file: its sentence.
    Recorded {
        /// The sentence.
        text: String,
    },
}

/// A global search that spent its starts without confirming a minimum.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct UnconfirmedSearch {
    /// The starts it had.
    pub starts: usize,
    /// A prior was in use.
    pub prior_in_use: bool,
}

/// The noise a fit stated, as it holds it (rad, mm).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct StatedNoise {
    /// The encoders', rad.
    pub encoder_rad: Option<f64>,
    /// The probe's, mm.
    pub probe_mm: Option<f64>,
    /// A reference position's, mm.
    pub position_mm: Option<f64>,
    /// Its growth with distance, mm per m.
    pub position_mm_per_m: Option<f64>,
    /// A reference orientation's, rad.
    pub(crate) orientation_rad: Option<f64>,
}

impl StatedNoise {
    fn of(noise: &Noise) -> StatedNoise {
        StatedNoise {
            encoder_rad: noise.encoder_rad,
            probe_mm: noise.probe_mm,
            position_mm: noise.position_mm,
            position_mm_per_m: noise.position_mm_per_m,
            orientation_rad: noise.orientation_rad,
        }
    }
}

/// A note beside a verdict, with its data. Said in a front end's words by
/// [`Note::describe`].
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
#[non_exhaustive]
pub enum Note {
    /// A χ² outside its range but not refused.
    ChiSquare {
        /// The test.
        chi: ChiSquare,
    },
    /// A robust scale outside its range but not refused, in words.
    RobustScale {
        /// The test, in words.
        description: String,
    },
    /// The robust weights had not settled.
    RobustUnsettled {
        /// The weights' tolerance.
        tolerance: f64,
        /// The refits.
        passes: usize,
    },
    /// The data determine the arm too weakly beside a touch's scatter.
    WeakData {
        /// RMS of the predicted radius, mm.
        rms_mm: f64,
        /// Its coverage.
        coverage: f64,
        /// A touch's own radius at that coverage, mm.
        touch_mm: f64,
    },
    /// No reference length: the scale is the nominal's.
    ScaleUndetermined {
        /// The parameter held for scale.
        parameter: String,
        /// Its nominal value, mm.
        nominal_mm: f64,
        /// The arm's reach, mm.
        reach_mm: f64,
    },
    /// Nearly parallel axes: a joint suits Hayati's model.
    Hayati {
        /// The recommendation, in words.
        text: String,
    },
    /// A reason for refusal, accepted on request.
    Accepted {
        /// The reason.
        reason: Box<Reason>,
    },
    /// A note read back from a file: its sentence.
    Recorded {
        /// The sentence.
        text: String,
    },
}
