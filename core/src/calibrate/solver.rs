//! The solvers behind one trait: each takes the same [`Task`] (the
//! objective at the start's weights, the start point, the free columns, the
//! model's and the solver's settings) and a [`Context`] (a progress
//! observer), and returns an [`Outcome`] with its own [`Stop`] reason. What
//! follows a solve — reweighing at the solution, covariance, dof — is the
//! library's own ([`super::calibrate_with`]), the same for every solver.
//!
//! The trait is open: a solver of another crate evaluates the task's
//! [`Objective`] (its cost, its normal equations over the free columns, its
//! local update `x ⊞ δ`) as the library's solvers do, and returns
//! [`Outcome::at`] its minimum with [`Stop::External`].

use serde::{Deserialize, Serialize};

use super::anneal::{self, AnnealStop, AnnealTrace};
use super::global::{self, GlobalStop, GlobalTrace};
use super::lm::{self, LmIteration, LmResult, Termination};
use super::{CalibrationError, Method, ModelOptions, Phase, SolverSettings};
use crate::dataset::DataSet;
use crate::objective::Objective;
use crate::params::DhParams;
use crate::random::{rng, streams};
use crate::residuals::Normal;

/// Told `(phase, fraction done)` as a solver runs.
pub(crate) type Observer<'a> = &'a mut dyn FnMut(&str, f64);

/// What a solver reports to while it runs, and what may stop it: an
/// observer told the phase running and the fraction of it done (for a
/// progress bar), and a [`Cancel`] token another thread (a GUI's stop
/// button, a Ctrl-C handler) may set. Threads and seed are settings
/// ([`super::SolverSettings`]), not part of it.
#[derive(Default)]
pub struct Context<'a> {
    /// Told `(phase, fraction done)`, if any.
    pub observer: Option<Observer<'a>>,
    /// Checked by every solver between its steps, if any.
    pub cancel: Option<Cancel>,
}

impl<'a> Context<'a> {
    /// A context with no observer and no cancellation.
    ///
    /// ```
    /// let ctx = aacmm_core::calibrate::Context::new();
    /// assert!(ctx.observer.is_none() && ctx.cancel.is_none());
    /// ```
    pub fn new() -> Context<'a> {
        Context::default()
    }

    /// This context, telling `observer` the progress.
    pub fn observed(mut self, observer: Observer<'a>) -> Context<'a> {
        self.observer = Some(observer);
        self
    }

    /// This context, stopped when `cancel` is set.
    pub fn cancelled_by(mut self, cancel: Cancel) -> Context<'a> {
        self.cancel = Some(cancel);
        self
    }

    /// Tells the observer that `fraction` of `phase` is done.
    pub(crate) fn observe(&mut self, phase: &str, fraction: f64) {
        if let Some(o) = self.observer.as_mut() {
            o(phase, fraction);
        }
    }

    /// [`CalibrationError::Cancelled`] once the token is set; else nothing.
    ///
    /// # Errors
    ///
    /// [`CalibrationError::Cancelled`].
    pub fn check(&self) -> Result<(), CalibrationError> {
        Cancel::check(self.cancel.as_ref())
    }

    /// The cancellation token, if one was given: what the calibrations a
    /// run makes of its own (the folds) check too.
    pub(crate) fn cancel_token(&self) -> Option<&Cancel> {
        self.cancel.as_ref()
    }
}

/// A cancellation token: cheap to clone, shared between the thread that
/// runs a calibration and any thread that may stop it. Every solver checks
/// it between its steps (an LM iteration, a global search's start, an
/// annealing temperature) and returns [`CalibrationError::Cancelled`]: a
/// cancelled calibration has no result to judge or use.
///
/// ```
/// use aacmm_core::calibrate::Cancel;
/// let token = Cancel::new();
/// let other = token.clone();
/// assert!(!token.is_cancelled());
/// other.cancel();
/// assert!(token.is_cancelled());
/// ```
#[derive(Clone, Debug, Default)]
pub struct Cancel(std::sync::Arc<std::sync::atomic::AtomicBool>);

impl Cancel {
    /// A token not yet set.
    pub fn new() -> Cancel {
        Cancel::default()
    }

    /// Sets the token: every calibration that checks it stops at its next
    /// check. Safe from any thread, and from a signal handler's thread.
    pub fn cancel(&self) {
        self.0.store(true, std::sync::atomic::Ordering::Relaxed);
    }

    /// Whether the token is set.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// [`CalibrationError::Cancelled`] when `token` is given and set.
    pub(crate) fn check(token: Option<&Cancel>) -> Result<(), CalibrationError> {
        match token.is_some_and(Cancel::is_cancelled) {
            true => Err(CalibrationError::Cancelled),
            false => Ok(()),
        }
    }
}

/// What every solver works on. Made by [`super::calibrate_with`] after the
/// settings and the identifiability were checked.
pub struct Task<'a, 'o> {
    /// The start arm.
    pub start: &'a DhParams,
    /// The start point: every column (the geometry's, then the auxiliary
    /// blocks').
    pub x: &'a [f64],
    /// The touches and lengths (what the annealer's energy measures).
    pub data: &'a DataSet,
    /// The least squares, weighed at the start.
    pub objective: &'a Objective<'o>,
    /// The free columns.
    pub free: &'a [usize],
    /// The model's settings (noise, tolerances).
    pub model: &'a ModelOptions,
    /// The solvers' settings, threads and seed.
    pub settings: &'a SolverSettings,
    /// Degrees of freedom when the noise is stated (enables noise-floor
    /// tests), else `None`.
    pub stated_dof: Option<usize>,
    /// Degrees of freedom of the fit, stated noise or not (what the fit's
    /// own noise level, `cost / dof`, is measured in).
    pub dof: usize,
    /// The normal equations at the start over `free`.
    pub start_normal: Normal,
}

/// Why a solver stopped: its own reason, and the final LM's where one ran.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Stop {
    /// Levenberg–Marquardt from the start arm.
    Lm(Termination),
    /// The paper's annealing alone: no LM ran.
    Anneal(AnnealStop),
    /// Annealing, then LM from its best point.
    Hybrid {
        /// Why the annealing stopped.
        anneal: AnnealStop,
        /// Why the LM stopped.
        lm: Termination,
    },
    /// The global search, then its best start's LM.
    Global {
        /// Why the search stopped.
        search: GlobalStop,
        /// Why the best start's LM stopped.
        lm: Termination,
    },
    /// A solver of another crate ([`Method::External`]).
    External {
        /// Whether it reached a minimum it vouches for.
        converged: bool,
    },
}

impl Stop {
    /// Whether the result is a usable solution (Ceres'
    /// `IsSolutionUsable`): the final LM converged, and the method's own
    /// stop is not a spent budget.
    pub fn is_solution_usable(self) -> bool {
        match self {
            Stop::Lm(t) => t.was_successful(),
            Stop::Anneal(a) => a != AnnealStop::EvaluationBudget,
            Stop::Hybrid { anneal, lm } => {
                anneal != AnnealStop::EvaluationBudget && lm.was_successful()
            }
            Stop::Global { search, lm } => search.confirmed() && lm.was_successful(),
            Stop::External { converged } => converged,
        }
    }

    /// The final LM's termination, if one ran.
    pub fn lm(self) -> Option<Termination> {
        match self {
            Stop::Lm(t) | Stop::Hybrid { lm: t, .. } | Stop::Global { lm: t, .. } => Some(t),
            Stop::Anneal(_) | Stop::External { .. } => None,
        }
    }

    /// The same stop with the final LM's termination replaced (after a
    /// refit under the weights at the solution).
    pub(crate) fn with_lm(self, t: Termination) -> Stop {
        match self {
            Stop::Lm(_) => Stop::Lm(t),
            Stop::Hybrid { anneal, .. } => Stop::Hybrid { anneal, lm: t },
            Stop::Global { search, .. } => Stop::Global { search, lm: t },
            // A refit after an external solver is the library's LM.
            Stop::External { .. } => Stop::Lm(t),
            Stop::Anneal(a) => Stop::Anneal(a),
        }
    }

    /// A sentence for summaries: what stopped the method, and the final
    /// LM.
    ///
    /// ```
    /// use aacmm_core::calibrate::{GlobalStop, Stop, Termination};
    /// let s = Stop::Global { search: GlobalStop::StartBudget, lm: Termination::CostTolerance };
    /// assert_eq!(
    ///     s.describe(),
    ///     "start budget spent without confirmation; final LM: relative cost reduction below ftol"
    /// );
    /// ```
    pub fn describe(self) -> String {
        match self {
            Stop::Lm(t) => t.describe().to_string(),
            Stop::Anneal(a) => format!("annealing: {} (no LM)", a.describe()),
            Stop::Hybrid { anneal, lm } => {
                format!("annealing: {}; LM: {}", anneal.describe(), lm.describe())
            }
            Stop::Global { search, lm } => {
                format!("{}; final LM: {}", search.describe(), lm.describe())
            }
            Stop::External { converged: true } => "an external solver: converged".to_string(),
            Stop::External { converged: false } => "an external solver: not converged".to_string(),
        }
    }
}

/// What a solver returns.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The arm found (fixed parameters unchanged).
    pub params: DhParams,
    /// Every column found (the geometry's, then the auxiliary blocks').
    pub x: Vec<f64>,
    /// Why it stopped.
    pub stop: Stop,
    /// Iterations of the final LM (0 without one).
    pub iterations: usize,
    /// Cost per iteration of the final LM.
    pub history: Vec<LmIteration>,
    /// Work per phase, in order.
    pub phases: Vec<Phase>,
    /// The annealing's account (`sa`, `hybrid`).
    pub anneal: Option<AnnealTrace>,
    /// The global search's account.
    pub global: Option<GlobalTrace>,
    /// The normal equations at `params` under the task's weights.
    pub(crate) normal: Normal,
}

impl Outcome {
    /// The outcome of a solver that stopped at `x` (every column) for the
    /// reason `stop`: its normal equations there are computed here, for the
    /// covariance.
    ///
    /// # Errors
    ///
    /// The objective's, at `x`.
    pub fn at(task: &Task<'_, '_>, x: Vec<f64>, stop: Stop) -> Result<Outcome, CalibrationError> {
        let normal = task.objective.normal(&x, task.free)?;
        Ok(Outcome {
            params: (task.objective.layout().arm(&x)).ok_or(CalibrationError::Shape)?,
            x,
            stop,
            iterations: 0,
            history: Vec::new(),
            phases: vec![Phase {
                jacobian_evaluations: 1,
                ..Phase::new("external")
            }],
            anneal: None,
            global: None,
            normal,
        })
    }

    fn from_lm(fit: LmResult, stop: Stop, phases: Vec<Phase>) -> Outcome {
        Outcome {
            params: fit.params,
            x: fit.x,
            stop,
            iterations: fit.iterations,
            history: fit.history,
            phases,
            anneal: None,
            global: None,
            normal: fit.normal,
        }
    }
}

/// A calibration method.
pub trait Solver {
    /// The method, for reports.
    fn method(&self) -> Method;

    /// Minimises the task's cost over its free columns.
    ///
    /// # Errors
    ///
    /// The objective's; a refused setting.
    fn solve(&self, task: Task<'_, '_>, ctx: &mut Context<'_>)
    -> Result<Outcome, CalibrationError>;
}

/// Levenberg–Marquardt from the start arm.
#[derive(Clone, Copy, Debug, Default)]
pub struct Lm;

/// The paper's simulated annealing: alone, or (`hybrid`) until its
/// switching rule fires, then LM.
#[derive(Clone, Copy, Debug, Default)]
pub struct Anneal {
    /// Switch to LM by the paper's rule.
    pub(crate) hybrid: bool,
}

/// Converges from encoder zeros unknown in ±180° ([`super::global`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Global;

impl Method {
    /// The solver of this method.
    ///
    /// ```
    /// use aacmm_core::calibrate::Method;
    /// assert_eq!(Method::Hybrid.solver().method(), Method::Hybrid);
    /// ```
    pub fn solver(self) -> Box<dyn Solver> {
        match self {
            Method::Lm => Box::new(Lm),
            Method::Sa => Box::new(Anneal { hybrid: false }),
            Method::Hybrid => Box::new(Anneal { hybrid: true }),
            Method::Global => Box::new(Global),
            // Refused as the method to run (`SolverSettings::check`); a
            // session passed an external solver never asks for it.
            Method::External => Box::new(Lm),
        }
    }
}

impl Solver for Lm {
    fn method(&self) -> Method {
        Method::Lm
    }

    fn solve(
        &self,
        task: Task<'_, '_>,
        ctx: &mut Context<'_>,
    ) -> Result<Outcome, CalibrationError> {
        let timer = std::time::Instant::now();
        let fit = lm::levenberg_marquardt_cancellable(
            task.objective,
            task.x,
            task.start_normal,
            &task.settings.lm,
            ctx.cancel.as_ref(),
        )?;
        let mut phase = Phase::new("lm");
        phase.add_lm(&fit, timer.elapsed().as_secs_f64());
        let stop = Stop::Lm(fit.termination);
        Ok(Outcome::from_lm(fit, stop, vec![phase]))
    }
}

impl Solver for Anneal {
    fn method(&self) -> Method {
        if self.hybrid {
            Method::Hybrid
        } else {
            Method::Sa
        }
    }

    fn solve(
        &self,
        task: Task<'_, '_>,
        ctx: &mut Context<'_>,
    ) -> Result<Outcome, CalibrationError> {
        // The paper's energy sees every touch through the arm's probe.
        if task.data.touch_tools().is_some() {
            return Err(crate::error::OptionError::new(
                crate::setting::Setting::Method,
                self.method().name(),
                "the annealing energy sees every touch through the arm's probe: touches by \
                 several tools (a `tool` column) are fitted by lm or global",
            )
            .into());
        }
        let timer = std::time::Instant::now();
        let mut rng = rng(task.settings.seed, streams::SOLVER);
        // The paper's energy is the touches' and lengths': it moves the
        // geometry only.
        let geometry = task.objective.layout().geometry_columns();
        let free: Vec<usize> = task
            .free
            .iter()
            .copied()
            .filter(|&c| c < geometry)
            .collect();
        let (best, trace) = anneal::anneal_observed(
            task.start,
            task.data,
            &free,
            &task.settings.anneal,
            self.hybrid.then_some(&task.settings.switch),
            &mut rng,
            &mut |f| {
                ctx.observe("anneal", f);
                ctx.check()
            },
        )?;
        let mut phases = vec![Phase {
            cost_evaluations: trace.evaluations,
            seconds: timer.elapsed().as_secs_f64(),
            ..Phase::new("anneal")
        }];
        let mut outcome = if self.hybrid {
            let timer = std::time::Instant::now();
            let fit = lm::levenberg_marquardt_until(
                task.objective,
                &point(&task, &best),
                task.free,
                &task.settings.lm,
                ctx.cancel.as_ref(),
            )?;
            let mut phase = Phase::new("lm");
            phase.add_lm(&fit, timer.elapsed().as_secs_f64());
            phases.push(phase);
            let stop = Stop::Hybrid {
                anneal: trace.stop,
                lm: fit.termination,
            };
            Outcome::from_lm(fit, stop, phases)
        } else {
            // No LM: the normal equations at the best point give the
            // covariance.
            let x = point(&task, &best);
            let normal = task.objective.normal(&x, task.free)?;
            phases[0].jacobian_evaluations = 1;
            Outcome {
                params: best,
                x,
                stop: Stop::Anneal(trace.stop),
                iterations: 0,
                history: Vec::new(),
                phases,
                anneal: None,
                global: None,
                normal,
            }
        };
        outcome.anneal = Some(trace);
        Ok(outcome)
    }
}

impl Solver for Global {
    fn method(&self) -> Method {
        Method::Global
    }

    fn solve(
        &self,
        task: Task<'_, '_>,
        ctx: &mut Context<'_>,
    ) -> Result<Outcome, CalibrationError> {
        let mut rng = rng(task.settings.seed, streams::SOLVER);
        let problem = global::GlobalProblem {
            objective: task.objective,
            free: task.free,
            lm: &task.settings.lm,
            stated_dof: task.stated_dof,
            dof: task.dof,
            start_normal: Some(task.start_normal),
            robust: task.model.robust,
            cancel: ctx.cancel.clone(),
        };
        let (fit, trace, phases) = global::global(
            task.start,
            &problem,
            &task.settings.global,
            &mut rng,
            &mut |f| ctx.observe("global", f),
        )?;
        let stop = Stop::Global {
            search: trace.stop,
            lm: fit.termination,
        };
        let mut outcome = Outcome::from_lm(fit, stop, phases);
        outcome.global = Some(trace);
        Ok(outcome)
    }
}

/// The task's start with the geometry `arm` (the auxiliary blocks where
/// the task starts them).
fn point(task: &Task<'_, '_>, arm: &DhParams) -> Vec<f64> {
    let mut x = arm.to_vec();
    x.extend(&task.x[task.objective.layout().geometry_columns()..]);
    x
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn calibrate_solver_stop_is_solution_usable() {
        use crate::calibrate::{GlobalStop, Stop, Termination};
        assert!(Stop::Lm(Termination::CostTolerance).is_solution_usable());
        assert!(!Stop::Lm(Termination::NoProgress).is_solution_usable());
        let unconfirmed = Stop::Global {
            search: GlobalStop::StartBudget,
            lm: Termination::CostTolerance,
        };
        assert!(!unconfirmed.is_solution_usable());
    }
}
