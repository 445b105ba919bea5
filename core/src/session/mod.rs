//! The calibration session every front end runs: a [`Problem`] (arm, data,
//! settings, optional held-out data and cross-validation, where the inputs
//! came from) checked once when it is made; [`run`] calibrates, validates
//! and cross-validates it and returns one [`CalibrationReport`] — the schema
//! of `calibration.json`, the input of the HTML report, what the C API's
//! report function returns. The command line, the C API and the examples
//! are shells around this module.
//!
//! ```
//! use aacmm_core::{Arm, ModelOptions, Problem, SolverSettings, params::DhParams, simulate::*};
//! let nominal = Arm::without_limits("nominal", DhParams::paper_nominal());
//! let mut settings = CampaignSettings::new(1, ErrorModel::Paper, 8, 10);
//! settings.reference_lengths = 3;
//! let data = simulate(&nominal, &settings).unwrap().data_set().unwrap();
//! let problem = Problem::new(nominal, data, ModelOptions::default()).unwrap();
//! let report = problem.run(&SolverSettings::default()).unwrap();
//! assert!(report.is_usable());
//! assert!(report.validation.fitted.after.e_mean < report.validation.fitted.before.e_mean);
//! ```

mod calibration_report;
mod checks;
pub(crate) mod evaluation;
pub(crate) mod identification;
mod map;
mod nouns;
mod position_evaluation;
pub mod probe;
mod problem;
pub mod request;
mod run;
pub mod spheres;
pub mod tools;
mod verdict;

pub use evaluation::EvaluationReport;
pub use identification::IdentifyReport;
pub use position_evaluation::{FrameEvaluation, MountEvaluation, PositionEvaluation};
pub use request::{Request, user_noise};
pub use verdict::{Note, Reason, Setting, Spelling, StatedNoise, UnconfirmedSearch, Verdict};

pub use calibration_report::{CalibrationReport, CrossValidation, HeldOut, Units, Validation};
pub use checks::check_units;
pub use problem::{HeldOutData, Problem, Sources, room_to_calibrate};
pub use run::run;

// What the session's other modules use from these, by `super::`.
use crate::calibrate::Calibration;
use crate::calibrate::validate::BeforeAfter;
// What the observations are called: the verdict's words and the report's.
pub(crate) use nouns::{noun, outliers_noun};
