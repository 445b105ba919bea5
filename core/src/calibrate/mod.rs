//! Calibration: the parameters that make the touches agree.
//!
//! [`calibrate`] fits the free parameters by Levenberg–Marquardt ([`LmOptions`]) on
//! the weighted residuals of [`crate::residuals`], then reports what a
//! metrologist signs off on:
//!
//! - **uncertainty**: `σ̂² = Σr² / (m − p)` with `m` residual rows
//!   (`3·touches + lengths`) and `p` every unknown fitted (the free
//!   parameters and `3` centre coordinates per point, eliminated but fitted
//!   all the same); covariance `σ̂² (JᵀJ)⁻¹` of the free parameters, σ in mm
//!   or deg, correlations `|ρ| > 0.9`; fixed parameters with the reason;
//! - **weights**: `1/σ` from the stated noise; without it, a first fit with
//!   unit weights estimates the touch σ from its touch residuals
//!   (`Σr²_touch / (3·touches − 3·points − free)`), and a second fit uses it,
//!   so that reference lengths are weighed against touches correctly.
//!
//! Solvers ([`Method`]): `lm` from the start arm; `sa`, the paper's
//! annealing ([`anneal`]) on its own; `hybrid`, the paper's annealing with
//! its switching rule, then LM; `global` ([`global`]), which converges from
//! encoder zeros unknown anywhere in ±180°.
//!
//! Validation on held-out data lives in [`validate`].
//!
//! This file holds the methods and the driver ([`calibrate_with`]: the
//! checks of the settings against the data, the fixed set, the solver, the
//! assessment). Beside it: the errors (`error.rs`); the fixed set's stage
//! (`fixed.rs`); the result types (`results.rs`) and what a result says of
//! its frames, tools and mount (`frames.rs`) and of the covariances a
//! prediction needs (`covariance.rs`); the assessment after the solver
//! (`assess`).

/// Builder setters: `setters!(Type { field: type, "doc"; … })`, each
/// `fn field(self, v) -> Self`.
macro_rules! setters {
    ($t:ty { $($field:ident: $ty:ty, $doc:literal;)* }) => {
        impl $t {
            $(
                #[doc = $doc]
                pub fn $field(mut self, v: $ty) -> Self {
                    self.$field = v;
                    self
                }
            )*
        }
    };
}

pub mod anneal;
pub(crate) mod assess;
pub mod checks;
mod covariance;
pub mod energy;
mod error;
mod fixed;
mod frames;
pub mod global;
pub(crate) mod lm;
pub mod options;
pub mod prior;
mod results;
pub mod robust;
pub mod solver;
pub mod validate;

use serde::{Deserialize, Serialize};

use crate::error::OptionError;
use crate::setting::Setting;
pub use anneal::{AnnealOptions, AnnealStep, AnnealStop, AnnealTrace, SwitchRule};
pub(crate) use error::ANGLE_UNITS_REMEDY;
pub use error::CalibrationError;
pub(crate) use fixed::correction_columns;
pub use global::{GlobalOptions, GlobalStop, GlobalTrace};
pub(crate) use lm::LmResult;
pub use lm::{LmIteration, LmOptions, Termination};
pub use options::{
    FixSpec, MAX_THREADS, ModelOptions, SolverSettings, available_threads, check_threads,
};
pub use prior::{PriorConditioning, PriorReport};
pub use results::{
    AuxiliaryEstimate, Calibration, Checks, CorrelationMatrix, Dof, Estimate, EstimateRecord,
    Phase, SolverSummary, TermRows,
};
pub use robust::{Loss, Robust, RobustFit};
pub use solver::{Anneal, Cancel, Context, Global, Lm, Outcome, Solver, Stop, Task};

use crate::dataset::DataSet;
use crate::objective::Objective;
use crate::params::DhParams;
use crate::residuals::{Layout, Role, Term};
use fixed::settle_fixed_set;

/// The solvers of [`calibrate`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Levenberg–Marquardt from the start arm.
    Lm,
    /// The paper's simulated annealing alone (method.md §5).
    Sa,
    /// The paper's hybrid: annealing until its switching rule, then LM (§6).
    Hybrid,
    /// Converges from encoder zeros unknown in ±180° ([`global`]).
    #[default]
    Global,
    /// A solver of another crate, passed to the session as a [`Solver`]
    /// (the library has none by this name: [`SolverSettings::check`]
    /// refuses it as the method to run).
    External,
}

impl Method {
    /// Every method, in the order of the comparison table.
    pub const ALL: [Method; 4] = [Method::Lm, Method::Sa, Method::Hybrid, Method::Global];

    /// The name used on the command line and in reports.
    ///
    /// ```
    /// use aacmm_core::calibrate::Method;
    /// assert_eq!(Method::Hybrid.name(), "hybrid");
    /// assert_eq!(Method::parse("global"), Some(Method::Global));
    /// assert_eq!(Method::parse("ceres"), None);
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Method::Lm => "lm",
            Method::Sa => "sa",
            Method::Hybrid => "hybrid",
            Method::Global => "global",
            Method::External => "external",
        }
    }

    /// The method of a name (one of [`Method::ALL`]).
    pub fn parse(s: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == s)
    }
}

/// Calibrates `start` (the nominal arm) on `data`: the model `model`, solved
/// as `settings` say (method, threads, seed). The geometry alone states no
/// masses: with [`ModelOptions::beyond`] a compliance is refused (a
/// [`crate::session::Problem`] of an arm file with masses fits one).
///
/// ```
/// use aacmm_core::{calibrate::*, domain::Arm, params::DhParams, simulate::*};
/// let nominal = Arm::without_limits("nominal", DhParams::paper_nominal());
/// let mut settings = CampaignSettings::new(1, ErrorModel::Paper, 8, 10);
/// settings.reference_lengths = 3;
/// let campaign = simulate(&nominal, &settings).unwrap();
/// let data = campaign.data_set().unwrap();
/// let model = ModelOptions::default();
/// let c = calibrate(&nominal.params, &data, &model, &SolverSettings::default()).unwrap();
/// assert!(c.solver.is_solution_usable());
/// assert_eq!(c.parameters.iter().filter(|p| p.fixed.is_none()).count(), 21);
/// ```
pub fn calibrate(
    start: &DhParams,
    data: &DataSet,
    model: &ModelOptions,
    settings: &SolverSettings,
) -> Result<Calibration, CalibrationError> {
    let solver = settings.method.solver();
    // A bare geometry states no masses: the models beyond it that need none
    // (harmonics, expansion, drift) are fitted, a compliance refused.
    let physics = crate::corrections::Physics::default();
    model
        .beyond
        .check_inputs(&physics, &data.condition_sets())?;
    let layout = crate::residuals::positions::layout_with(start, data, &physics, &model.beyond)?;
    let inputs = FitInputs {
        layout: &layout,
        data,
        model,
        terms: &[],
    };
    calibrate_with(inputs, settings, &*solver, &mut Context::new())
}

/// A calibration to run: the data and the model, on the columns of
/// `layout` — the start arm's geometry, then any auxiliary parameter block
/// a caller adds — with the residual terms a caller adds to the data's own
/// (touches, reference lengths, the prior).
#[derive(Clone, Copy)]
pub struct FitInputs<'p> {
    /// The columns: the start arm's geometry first.
    pub layout: &'p Layout,
    /// The touches and reference lengths.
    pub data: &'p DataSet,
    /// The model's settings.
    pub model: &'p ModelOptions,
    /// Residual terms beyond the data's.
    pub terms: &'p [Box<dyn Term>],
}

/// [`calibrate`] with a given solver and context (a progress observer), on
/// `inputs` (which may add parameter blocks and residual terms). Checks
/// every setting first ([`ModelOptions::check_for`],
/// [`SolverSettings::check`]).
pub fn calibrate_with(
    inputs: FitInputs<'_>,
    settings: &SolverSettings,
    solver: &dyn Solver,
    ctx: &mut Context,
) -> Result<Calibration, CalibrationError> {
    let FitInputs {
        layout,
        data,
        model,
        terms,
    } = inputs;
    let start = layout.geometry();
    model.check_for(start)?;
    settings.check()?;
    check_method_for(solver.method(), data)?;
    let extra = terms.iter().map(|t| dyn_clone::clone_box(&**t)).collect();
    let mut objective = Objective::of_data(
        layout.clone(),
        data,
        &model.noise,
        extra,
        model.prior.as_ref(),
        1.0,
        settings.threads,
    )?;
    check_terms_for(solver.method(), &objective)?;
    let x0 = objective.start();
    let fixed = settle_fixed_set(&mut objective, layout, &x0, model, data)?;
    let task = Task {
        start,
        x: &x0,
        data,
        objective: &objective,
        free: &fixed.free,
        model,
        settings,
        stated_dof: fixed.stated.then_some(fixed.counts.dof()),
        dof: fixed.counts.dof(),
        start_normal: fixed.start_normal,
    };
    let mut outcome = solver.solve(task, ctx)?;
    // A solver of another crate may not check the token: what follows
    // (refits, covariance, leverage) is not started once it is set.
    ctx.check()?;
    outcome.phases.insert(0, fixed.phase);
    let setup = assess::Setup {
        start,
        x0: &x0,
        data,
        model,
        settings,
        method: solver.method(),
        free: fixed.free,
        identification: fixed.identification,
        reasons: fixed.reasons,
        held: fixed.held,
        counts: fixed.counts,
        stated: fixed.stated,
        carried: fixed.carried,
        holds: fixed.holds,
    };
    assess::assess(setup, objective, outcome)
}

/// Refuses a method that cannot use the data: the paper's annealing
/// minimises the touches' energy (its OA), so `sa` alone would ignore
/// reference positions, and neither `sa` nor `hybrid` has anything to
/// anneal without touches. Any other evidence `sa` would not weigh is
/// refused by [`check_terms_for`], by its term's name.
fn check_method_for(method: Method, data: &DataSet) -> Result<(), OptionError> {
    let why = match method {
        Method::Sa if data.positions().is_some() => {
            "anneals the paper's touch energy alone, which reference positions are no part of"
        }
        Method::Hybrid if data.is_empty() => {
            "anneals the paper's touch energy, and these data have no touches"
        }
        _ => return Ok(()),
    };
    Err(OptionError::new(
        Setting::Method,
        method.name(),
        format!("{why}: use lm or global (the default)"),
    ))
}

/// Refuses `sa` with evidence its energy does not measure: the annealer
/// minimises the touches' and lengths' energy, so any other term — a tool
/// orientation, a term written outside the library — would be ignored
/// while the result claims to fit it. Prior knowledge is not evidence: the
/// fit after the annealing carries it.
fn check_terms_for(method: Method, objective: &Objective<'_>) -> Result<(), OptionError> {
    if method != Method::Sa {
        return Ok(());
    }
    let ignored = objective.terms().find(|t| {
        let role = t.role();
        !role.is_prior() && !matches!(role, Role::Touches | Role::Lengths)
    });
    match ignored {
        None => Ok(()),
        Some(t) => Err(OptionError::new(
            Setting::Method,
            method.name(),
            format!(
                "anneals the paper's touch energy alone, which the term `{}` is no part of: \
                 use lm or global (the default)",
                t.name()
            ),
        )),
    }
}
