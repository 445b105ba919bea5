//! The front door in one import: `use aacmm_core::prelude::*;`.
//!
//! What a program needs for the common jobs, wherever in the crate it
//! lives:
//!
//! - **reading** an arm and its touches: [`read_arm`], [`Arm`] (its
//!   geometry a [`DhParams`]), [`DataSet`] (`DataSet::read`), the units
//!   files state ([`AngleUnit`], [`LengthUnit`]) and the errors that name a
//!   file and line or a setting ([`InputError`], [`OptionError`]);
//! - **simulating** a campaign with a known true arm: [`simulate`],
//!   [`CampaignSettings`], [`ErrorModel`], [`Campaign`];
//! - **calibrating**: the session path every front end takes — a
//!   [`Request`] (settings as text and values) or a [`Problem`] (typed
//!   settings), run to a [`CalibrationReport`] — or the bare fit,
//!   [`calibrate`] / [`calibrate_with`], with [`ModelOptions`],
//!   [`SolverSettings`], [`Method`], [`FixSpec`], [`Noise`], [`Robust`],
//!   giving a [`Calibration`] (its parameters named by [`ParamId`]);
//! - **evaluating** an arm on measured positions: [`evaluate`];
//! - **extending** the least squares: a new measurement is a [`Term`]
//!   (evaluated [`At`] a point, adding rows to a [`Normal`], leaving and
//!   reading [`Shared`] centres, saying what it [`Sees`], refusing its
//!   inputs with a [`TermError`]), a new unknown a
//!   [`Block`] in the [`Layout`] ([`BlockId`]); a new solver is a [`Solver`]
//!   that minimises a [`Task`]'s [`Objective`] and returns an [`Outcome`]
//!   with its [`Stop`] reason, reporting progress to a [`Context`]
//!   (run it with [`calibrate_with`] on [`FitInputs`], or in a session
//!   with `session::run`).
//!
//! Everything else (the kernel, the metrics' parts, the report, the
//! identifiability analysis, URDF) is one module path away; nothing here is
//! reachable only through the prelude.
//!
//! ```
//! use aacmm_core::prelude::*;
//!
//! // A campaign with a known true arm: the paper's nominal arm with its
//! // Table 2 errors, 8 sockets touched 10 times, 3 reference lengths.
//! let nominal = Arm::without_limits("nominal", DhParams::paper_nominal());
//! let mut settings = CampaignSettings::new(1, ErrorModel::Paper, 8, 10);
//! settings.reference_lengths = 3;
//! let data: DataSet = simulate(&nominal, &settings)?.data_set()?;
//!
//! let problem = Problem::new(nominal, data, ModelOptions::default())?;
//! let report = problem.run(&SolverSettings::default().with_method(Method::Lm))?;
//! assert!(report.is_usable());
//! let fitted = &report.validation.fitted;
//! assert!(fitted.after.e_mean < fitted.before.e_mean);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub use crate::calibrate::{
    Calibration, CalibrationError, Context, FitInputs, FixSpec, Method, ModelOptions, Outcome,
    Robust, Solver, SolverSettings, Stop, Task, calibrate, calibrate_with,
};
pub use crate::dataset::DataSet;
pub use crate::domain::Arm;
pub use crate::error::{InputError, OptionError};
pub use crate::io::{AngleUnit, LengthUnit, read_arm};
pub use crate::metrics::evaluate;
pub use crate::objective::Objective;
pub use crate::params::{DhParams, ParamId};
pub use crate::residuals::Role;
pub use crate::residuals::{
    At, Block, BlockId, Layout, Noise, Normal, Sees, Shared, Term, TermError,
};
pub use crate::session::{CalibrationReport, Problem, Request};
pub use crate::simulate::{Campaign, CampaignSettings, ErrorModel, simulate};
