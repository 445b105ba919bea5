//! Levenberg–Marquardt on the reduced normal equations
//! ([`crate::residuals`]): Marquardt's diagonal scaling (so mm and rad need
//! no hand-tuned units), Nielsen's damping update, MINPACK-style stopping
//! tests, and a trial step costing positions only.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::CalibrationError;
use crate::damping::Damping;
use crate::error::{OptionError, check_nonnegative};
use crate::objective::Objective;
use crate::params::DhParams;
use crate::residuals::Normal;
use crate::setting::Setting;

/// Why the solver stopped, as MINPACK's `info` or Ceres' termination type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// The next step's relative cost reduction, actual and predicted, is
    /// below `ftol` (the step is not taken).
    CostTolerance,
    /// The next scaled step is below `xtol` relative to the scaled
    /// parameters (not taken).
    StepTolerance,
    /// Every column is orthogonal to the residuals within `gtol`.
    GradientTolerance,
    /// The residuals vanished (exact data).
    ZeroResidual,
    /// The iteration budget ran out first.
    MaxIterations,
    /// No step lowered the cost even with huge damping, and the gradient
    /// test passes at a tolerance of 1e-6: a minimum to machine
    /// precision.
    MachinePrecision,
    /// No step lowered the cost even with huge damping, yet the gradient is
    /// not small: not a converged minimum (a numerical failure, or a cost
    /// that is not smooth there).
    NoProgress,
}

/// The gradient test (largest cosine between a column and the residuals)
/// that a stalled LM must pass to count as converged.
pub(crate) const MACHINE_PRECISION_GTOL: f64 = 1e-6;

impl Termination {
    /// Whether the result is a converged minimum.
    pub fn was_successful(self) -> bool {
        !matches!(self, Termination::MaxIterations | Termination::NoProgress)
    }

    /// A sentence for summaries.
    pub fn describe(self) -> &'static str {
        match self {
            Termination::CostTolerance => "relative cost reduction below ftol",
            Termination::StepTolerance => "relative step below xtol",
            Termination::GradientTolerance => "gradient below gtol",
            Termination::ZeroResidual => "residuals vanished",
            Termination::MaxIterations => "iteration limit reached",
            Termination::MachinePrecision => {
                "no step lowers the cost and the gradient is nil (minimum to machine precision)"
            }
            Termination::NoProgress => {
                "no step lowers the cost, yet the gradient is not small (not converged)"
            }
        }
    }
}

/// Tolerances and limits of Levenberg–Marquardt; a builder. The library's
/// LM works on the reduced normal equations ([`crate::residuals`]) with
/// Marquardt's diagonal scaling (so mm and rad need no hand-tuned units),
/// Nielsen's damping update, MINPACK-style stopping tests, and a trial step
/// costing positions only.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LmOptions {
    /// Iteration limit (accepted or rejected steps).
    pub max_iterations: usize,
    /// Relative cost reduction that counts as converged.
    pub ftol: f64,
    /// Relative scaled step that counts as converged.
    pub xtol: f64,
    /// Largest cosine between a column and the residuals at a minimum.
    pub gtol: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            max_iterations: 200,
            ftol: 1e-12,
            xtol: 1e-12,
            gtol: 1e-12,
        }
    }
}

setters!(LmOptions {
    max_iterations: usize, "Sets the iteration limit.";
    ftol: f64, "Sets `ftol`.";
    xtol: f64, "Sets `xtol`.";
    gtol: f64, "Sets `gtol`.";
});

impl LmOptions {
    /// Checks the settings; the error names the setting (`lm.ftol`, …).
    ///
    /// ```
    /// use aacmm_core::calibrate::LmOptions;
    /// assert!(LmOptions::default().check().is_ok());
    /// assert_eq!(LmOptions::default().max_iterations(0).check().unwrap_err().field(), "lm.max_iterations");
    /// ```
    pub fn check(&self) -> Result<(), OptionError> {
        if self.max_iterations == 0 {
            return Err(OptionError::new(Setting::LmIterations, 0, "at least 1"));
        }
        for (field, v) in [
            (Setting::LmFtol, self.ftol),
            (Setting::LmXtol, self.xtol),
            (Setting::LmGtol, self.gtol),
        ] {
            check_nonnegative(field, v, true)?;
        }
        Ok(())
    }
}

/// One iteration, for the report's progress figure.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LmIteration {
    /// 1-based.
    pub iteration: usize,
    /// Cost `Σ r²` after the iteration.
    pub cost: f64,
    /// Damping used.
    pub lambda: f64,
    /// Whether the step was taken.
    pub accepted: bool,
}

/// What a Levenberg–Marquardt fit returns.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct LmResult {
    /// The parameters at the end (fixed ones unchanged).
    pub(crate) params: DhParams,
    /// Every column at the end (the geometry's, then the auxiliary
    /// blocks').
    pub(crate) x: Vec<f64>,
    /// Why it stopped.
    pub(crate) termination: Termination,
    /// Iterations (steps tried).
    pub(crate) iterations: usize,
    /// Cost evaluations (positions only).
    pub(crate) cost_evaluations: usize,
    /// Jacobian evaluations (normal equations).
    pub(crate) jacobian_evaluations: usize,
    /// Cost at the start and per iteration.
    pub(crate) initial_cost: f64,
    /// Per iteration.
    pub(crate) history: Vec<LmIteration>,
    /// The normal equations at the result.
    pub(crate) normal: Normal,
}

/// Minimises `objective` over the columns `free` from the point `start`
/// (every column).
///
/// Never returns NaN: a trial step with a non-finite cost is rejected like
/// any step that does not lower the cost.
pub(crate) fn levenberg_marquardt(
    objective: &Objective<'_>,
    start: &[f64],
    free: &[usize],
    options: &LmOptions,
) -> Result<LmResult, CalibrationError> {
    levenberg_marquardt_until(objective, start, free, options, None)
}

/// [`levenberg_marquardt`], stopped with [`CalibrationError::Cancelled`]
/// once `cancel` is set.
pub(crate) fn levenberg_marquardt_until(
    objective: &Objective<'_>,
    start: &[f64],
    free: &[usize],
    options: &LmOptions,
    cancel: Option<&super::Cancel>,
) -> Result<LmResult, CalibrationError> {
    super::Cancel::check(cancel)?;
    let normal = objective.normal(start, free)?;
    let mut fit = levenberg_marquardt_cancellable(objective, start, normal, options, cancel)?;
    fit.jacobian_evaluations += 1;
    Ok(fit)
}

/// [`levenberg_marquardt`] from the normal equations already computed at
/// `start` (over the free columns `normal.free`), which it does not count;
/// stopped with [`CalibrationError::Cancelled`] before any iteration once
/// `cancel` is set.
pub(crate) fn levenberg_marquardt_cancellable(
    objective: &Objective<'_>,
    start: &[f64],
    normal: Normal,
    options: &LmOptions,
    cancel: Option<&super::Cancel>,
) -> Result<LmResult, CalibrationError> {
    if !normal.cost().is_finite() {
        return Err(CalibrationError::NonFiniteStart);
    }
    let mut descent = Descent::new(objective, start, normal, options);
    let mut termination = Termination::MaxIterations;
    for iteration in 1..=options.max_iterations {
        super::Cancel::check(cancel)?;
        if let Some(stop) = descent.iterate(iteration)? {
            termination = stop;
            break;
        }
    }
    descent.finish(termination)
}

/// One Levenberg–Marquardt descent: where it stands, its normal equations
/// there, the damping, and its account so far.
struct Descent<'a, 'o> {
    objective: &'a Objective<'o>,
    options: &'a LmOptions,
    free: Vec<usize>,
    /// Every column.
    x: Vec<f64>,
    /// The normal equations at `x`; N and g as matrices, made again only
    /// when a step is taken (a rejected step keeps them: near the minimum
    /// most steps are).
    normal: Normal,
    n: DMatrix<f64>,
    g: DVector<f64>,
    /// Buffers of the damped solve and of `N δ`, kept from one trial to the
    /// next (a fit makes a dozen trials; each made five allocations).
    damped: DMatrix<f64>,
    n_delta: DVector<f64>,
    /// Marquardt's diagonal scale: per column, the largest diagonal of N
    /// seen so far (so mm and rad need no hand-tuned units).
    scale: Vec<f64>,
    damping: Damping,
    /// Positions of the trial cost, reused.
    xyz: Vec<[f64; 3]>,
    initial_cost: f64,
    history: Vec<LmIteration>,
    cost_evaluations: usize,
    jacobian_evaluations: usize,
}

/// A trial step and what it did to the cost.
struct Trial {
    /// Every parameter after the step.
    x: Vec<f64>,
    f_new: f64,
    /// The actual and the predicted cost reduction.
    actual: f64,
    predicted: f64,
    /// The gain ratio, actual over predicted (−1 when none is predicted).
    rho: f64,
    /// Whether the scaled step is below `xtol` relative to the scaled
    /// parameters.
    small_step: bool,
}

impl Trial {
    /// Whether the step lowered the cost (never so for a non-finite cost).
    fn lowers_cost(&self) -> bool {
        self.rho > 0.0 && self.f_new.is_finite()
    }

    /// Converged at `f` (the cost before the step) by `ftol` or `xtol`.
    /// Such a step is not taken: the result stays where its normal
    /// equations were computed (they give the covariance), and the Jacobian
    /// pass at the step's end is saved.
    fn converged(&self, f: f64, options: &LmOptions) -> Option<Termination> {
        if self.actual <= options.ftol * f && self.predicted <= options.ftol * f {
            Some(Termination::CostTolerance)
        } else if self.small_step {
            Some(Termination::StepTolerance)
        } else {
            None
        }
    }
}

impl<'a, 'o> Descent<'a, 'o> {
    fn new(
        objective: &'a Objective<'o>,
        start: &[f64],
        normal: Normal,
        options: &'a LmOptions,
    ) -> Descent<'a, 'o> {
        let free = normal.free.clone();
        let p = free.len();
        let (n, g) = matrices(&normal, p);
        Descent {
            objective,
            options,
            x: start.to_vec(),
            initial_cost: normal.cost(),
            normal,
            damped: n.clone(),
            n_delta: DVector::zeros(p),
            n,
            g,
            scale: vec![0.0f64; p],
            damping: Damping::nielsen(),
            xyz: Vec::new(),
            history: Vec::new(),
            cost_evaluations: 0,
            jacobian_evaluations: 0,
            free,
        }
    }

    /// One iteration — the gradient test, the damped solve, the trial
    /// step, then acceptance or rejection; why the descent stops, if it
    /// does.
    fn iterate(&mut self, iteration: usize) -> Result<Option<Termination>, CalibrationError> {
        let f = self.normal.cost();
        if f <= f64::MIN_POSITIVE {
            return Ok(Some(Termination::ZeroResidual));
        }
        self.widen_scale();
        let gmax = self.gradient_cosine(f);
        if gmax <= self.options.gtol {
            return Ok(Some(Termination::GradientTolerance));
        }
        // A damped system that cannot be solved is damped harder; giving
        // up is left to the steps that can be tried.
        let Some(delta) = self.damped_step() else {
            self.reject(iteration, f);
            return Ok(None);
        };
        let trial = self.trial(&delta, f)?;
        if trial.lowers_cost() {
            if let Some(stop) = trial.converged(f, self.options) {
                return Ok(Some(stop));
            }
            self.accept(iteration, trial)?;
            return Ok(None);
        }
        self.reject(iteration, f);
        Ok((trial.small_step || self.damping.exhausted()).then(|| stalled(gmax)))
    }

    fn widen_scale(&mut self) {
        let p = self.free.len();
        let jtj = &self.normal.jtj;
        for (s, c) in self.scale.iter_mut().zip(0..p) {
            *s = s.max(jtj[c * p + c]).max(f64::MIN_POSITIVE);
        }
    }

    /// The gradient test: the largest cosine between a column and the
    /// residuals (cost `f`).
    fn gradient_cosine(&self, f: f64) -> f64 {
        let p = self.free.len();
        (0..p)
            .map(|c| {
                self.g[c].abs() / (self.normal.jtj[c * p + c].max(f64::MIN_POSITIVE) * f).sqrt()
            })
            .fold(0.0, f64::max)
    }

    /// The step `δ` of `(N + λ·diag(scale)) δ = −g`, if it solves to finite
    /// numbers. The damped matrix is factored in the kept buffer, which the
    /// factor gives back: the same operations as on a fresh copy.
    fn damped_step(&mut self) -> Option<DVector<f64>> {
        // (A failed factorisation consumed the buffer: made again here.)
        let mut a = std::mem::replace(&mut self.damped, DMatrix::zeros(0, 0));
        if a.shape() == self.n.shape() {
            a.copy_from(&self.n);
        } else {
            a = self.n.clone();
        }
        for c in 0..self.free.len() {
            a[(c, c)] += self.damping.value() * self.scale[c];
        }
        let ch = crate::residuals::cholesky(a)?;
        let mut step = self.g.clone();
        crate::residuals::cholesky_solve(&ch, step.as_mut_slice());
        step.neg_mut();
        self.damped = ch.unpack_dirty();
        step.iter().all(|v| v.is_finite()).then_some(step)
    }

    /// The cost after the step `delta` from cost `f` (positions only), and
    /// how it compares with the prediction.
    fn trial(&mut self, delta: &DVector<f64>, f: f64) -> Result<Trial, CalibrationError> {
        let p = self.free.len();
        let x = self.objective.plus(&self.x, &self.free, delta.as_slice());
        let f_new = self.objective.cost(&x, &self.free, &mut self.xyz)?;
        self.cost_evaluations += 1;
        // |r + Jδ|² = f + 2δᵀg + δᵀNδ
        self.n.mul_to(delta, &mut self.n_delta);
        let predicted = -(2.0 * delta.dot(&self.g) + delta.dot(&self.n_delta));
        let actual = f - f_new;
        let rho = if predicted > 0.0 {
            actual / predicted
        } else {
            -1.0
        };
        let scaled = |v: &[f64]| -> f64 {
            (0..p)
                .map(|c| self.scale[c] * v[c] * v[c])
                .sum::<f64>()
                .sqrt()
        };
        let xs: Vec<f64> = self.free.iter().map(|&c| self.x[c]).collect();
        let xtol = self.options.xtol;
        let small_step = scaled(delta.as_slice()) <= xtol * (scaled(&xs) + xtol);
        Ok(Trial {
            x,
            f_new,
            actual,
            predicted,
            rho,
            small_step,
        })
    }

    /// Takes the step: the normal equations at its end, less damping.
    fn accept(&mut self, iteration: usize, trial: Trial) -> Result<(), CalibrationError> {
        self.x = trial.x;
        self.normal = self.objective.normal(&self.x, &self.free)?;
        (self.n, self.g) = matrices(&self.normal, self.free.len());
        self.jacobian_evaluations += 1;
        self.damping.accept(trial.rho);
        self.history.push(LmIteration {
            iteration,
            cost: self.normal.cost(),
            lambda: self.damping.value(),
            accepted: true,
        });
        Ok(())
    }

    /// Stays at cost `f`, more damped.
    fn reject(&mut self, iteration: usize, f: f64) {
        self.damping.reject();
        self.history.push(LmIteration {
            iteration,
            cost: f,
            lambda: self.damping.value(),
            accepted: false,
        });
    }

    fn finish(self, termination: Termination) -> Result<LmResult, CalibrationError> {
        Ok(LmResult {
            params: (self.objective.layout().arm(&self.x)).ok_or(CalibrationError::Shape)?,
            x: self.x,
            termination,
            iterations: self.history.len(),
            cost_evaluations: self.cost_evaluations,
            jacobian_evaluations: self.jacobian_evaluations,
            initial_cost: self.initial_cost,
            history: self.history,
            normal: self.normal,
        })
    }
}

/// N (`p × p`) and g of `normal` as matrices.
fn matrices(normal: &Normal, p: usize) -> (DMatrix<f64>, DVector<f64>) {
    (
        DMatrix::from_row_slice(p, p, &normal.jtj),
        DVector::from_column_slice(&normal.jtr),
    )
}

/// Why a descent stops when no step lowers the cost: converged to machine
/// precision if the gradient test (`gmax`) passes at
/// [`MACHINE_PRECISION_GTOL`], otherwise no progress.
fn stalled(gmax: f64) -> Termination {
    if gmax <= MACHINE_PRECISION_GTOL {
        Termination::MachinePrecision
    } else {
        Termination::NoProgress
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn calibrate_lm_termination_was_successful() {
        use crate::calibrate::Termination;
        assert!(Termination::CostTolerance.was_successful());
        assert!(!Termination::MaxIterations.was_successful());
        assert!(!Termination::NoProgress.was_successful());
        assert!(Termination::MachinePrecision.was_successful());
    }
}
