//! Levenberg–Marquardt on the reduced normal equations
//! ([`crate::residuals`]): Marquardt's diagonal scaling (so mm and rad need
//! no hand-tuned units), Nielsen's damping update, MINPACK-style stopping
//! tests, and a trial step costing positions only.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::CalibrationError;
use super::prior::{cost_at, normal_at};
use crate::dataset::DataSet;
use crate::error::{OptionError, check_nonnegative};
use crate::params::DhParams;
use crate::residuals::{Normal, Weights};

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
    /// test passes at [`MACHINE_PRECISION_GTOL`]: a minimum to machine
    /// precision.
    MachinePrecision,
    /// No step lowered the cost even with huge damping, yet the gradient is
    /// not small: not a converged minimum (a numerical failure, or a cost
    /// that is not smooth there).
    NoProgress,
}

/// The gradient test (largest cosine between a column and the residuals)
/// that a stalled LM must pass to count as converged.
pub const MACHINE_PRECISION_GTOL: f64 = 1e-6;

impl Termination {
    /// Whether the result is a converged minimum.
    ///
    /// ```
    /// use aacmm_core::calibrate::Termination;
    /// assert!(Termination::CostTolerance.was_successful());
    /// assert!(!Termination::MaxIterations.was_successful());
    /// assert!(!Termination::NoProgress.was_successful());
    /// assert!(Termination::MachinePrecision.was_successful());
    /// ```
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

/// Tolerances and limits of Levenberg–Marquardt; a builder.
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
    /// assert_eq!(LmOptions::default().max_iterations(0).check().unwrap_err().field, "lm.max_iterations");
    /// ```
    pub fn check(&self) -> Result<(), OptionError> {
        if self.max_iterations == 0 {
            return Err(OptionError::new("lm.max_iterations", 0, "at least 1"));
        }
        for (field, v) in [
            ("lm.ftol", self.ftol),
            ("lm.xtol", self.xtol),
            ("lm.gtol", self.gtol),
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
pub struct LmResult {
    /// The parameters at the end (fixed ones unchanged).
    pub params: DhParams,
    /// Why it stopped.
    pub termination: Termination,
    /// Iterations (steps tried).
    pub iterations: usize,
    /// Cost evaluations (positions only).
    pub cost_evaluations: usize,
    /// Jacobian evaluations (normal equations).
    pub jacobian_evaluations: usize,
    /// Cost at the start and per iteration.
    pub initial_cost: f64,
    /// Per iteration.
    pub history: Vec<LmIteration>,
    /// The normal equations at the result.
    pub(crate) normal: Normal,
}

impl LmResult {
    /// This fit followed by `refit` (which started where this one ended):
    /// one history, iterations numbered on, this fit's initial cost and
    /// both fits' evaluations.
    pub fn then(self, refit: LmResult) -> LmResult {
        let mut history = self.history;
        let n = history.len();
        history.extend(refit.history.iter().map(|h| LmIteration {
            iteration: h.iteration + n,
            ..*h
        }));
        LmResult {
            history,
            initial_cost: self.initial_cost,
            iterations: self.iterations + refit.iterations,
            cost_evaluations: self.cost_evaluations + refit.cost_evaluations,
            jacobian_evaluations: self.jacobian_evaluations + refit.jacobian_evaluations,
            ..refit
        }
    }
}

/// Minimises the weighted cost over the parameters `free` (indices in the
/// fixed order of [`crate::params`]) from `start`, the normal equations on
/// `threads` threads.
///
/// Never returns NaN: a trial step with a non-finite cost is rejected like
/// any step that does not lower the cost.
pub(crate) fn levenberg_marquardt(
    start: &DhParams,
    data: &DataSet,
    weights: &Weights,
    free: &[usize],
    options: &LmOptions,
    threads: usize,
) -> Result<LmResult, CalibrationError> {
    let normal = normal_at(start, data, weights, free, threads)?;
    let mut fit = levenberg_marquardt_from(start, normal, data, weights, options, threads)?;
    fit.jacobian_evaluations += 1;
    Ok(fit)
}

/// [`levenberg_marquardt`] from the normal equations already computed at
/// `start` (over the free columns `normal.free`), which it does not count.
pub(crate) fn levenberg_marquardt_from(
    start: &DhParams,
    normal: Normal,
    data: &DataSet,
    weights: &Weights,
    options: &LmOptions,
    threads: usize,
) -> Result<LmResult, CalibrationError> {
    let free = &normal.free.clone();
    let p = free.len();
    let mut x = start.to_vec();
    // The prior, if any, rides with the weights ([`super::prior`]).
    let params_of = |x: &[f64]| -> Result<DhParams, CalibrationError> {
        start.with_values(x).ok_or(CalibrationError::Shape)
    };
    let mut normal = normal;
    if !normal.cost().is_finite() {
        return Err(CalibrationError::NonFiniteStart);
    }
    let initial_cost = normal.cost();
    let mut xyz = vec![[0.0; 3]; data.len()];
    let mut history = Vec::new();
    let mut scale = vec![0.0f64; p];
    let mut lambda = 1e-3;
    let mut nu = 2.0;
    let (mut cost_evaluations, mut jacobian_evaluations) = (0, 0);
    let mut termination = Termination::MaxIterations;
    // N and g as matrices, made again only when a step is taken (a
    // rejected step keeps them: near the minimum most steps are).
    let matrices = |normal: &Normal| {
        (
            DMatrix::from_row_slice(p, p, &normal.jtj),
            DVector::from_column_slice(&normal.jtr),
        )
    };
    let (mut n, mut g) = matrices(&normal);
    for iteration in 1..=options.max_iterations {
        let f = normal.cost();
        if f <= f64::MIN_POSITIVE {
            termination = Termination::ZeroResidual;
            break;
        }
        for (s, c) in scale.iter_mut().zip(0..p) {
            *s = s.max(normal.jtj[c * p + c]).max(f64::MIN_POSITIVE);
        }
        let gmax = (0..p)
            .map(|c| g[c].abs() / (normal.jtj[c * p + c].max(f64::MIN_POSITIVE) * f).sqrt())
            .fold(0.0, f64::max);
        if gmax <= options.gtol {
            termination = Termination::GradientTolerance;
            break;
        }
        let mut a = n.clone();
        for c in 0..p {
            a[(c, c)] += lambda * scale[c];
        }
        let step = a.cholesky().map(|ch| -ch.solve(&g));
        let Some(delta) = step.filter(|d| d.iter().all(|v| v.is_finite())) else {
            lambda *= nu;
            nu *= 2.0;
            history.push(LmIteration {
                iteration,
                cost: f,
                lambda,
                accepted: false,
            });
            continue;
        };
        let mut trial = x.clone();
        for (c, &col) in free.iter().enumerate() {
            trial[col] += delta[c];
        }
        let f_new = cost_at(&params_of(&trial)?, data, weights, free, &mut xyz)?;
        cost_evaluations += 1;
        // |r + Jδ|² = f + 2δᵀg + δᵀNδ
        let predicted = -(2.0 * delta.dot(&g) + delta.dot(&(&n * &delta)));
        let actual = f - f_new;
        let rho = if predicted > 0.0 {
            actual / predicted
        } else {
            -1.0
        };
        let scaled =
            |v: &[f64]| -> f64 { (0..p).map(|c| scale[c] * v[c] * v[c]).sum::<f64>().sqrt() };
        let xs: Vec<f64> = free.iter().map(|&c| x[c]).collect();
        let small_step = scaled(delta.as_slice()) <= options.xtol * (scaled(&xs) + options.xtol);
        if rho > 0.0 && f_new.is_finite() {
            // A step too small to matter is not taken: the result stays
            // where its normal equations were computed (they give the
            // covariance), and the Jacobian pass at the step's end is saved.
            if actual <= options.ftol * f && predicted <= options.ftol * f {
                termination = Termination::CostTolerance;
                break;
            }
            if small_step {
                termination = Termination::StepTolerance;
                break;
            }
            x = trial;
            normal = normal_at(&params_of(&x)?, data, weights, free, threads)?;
            (n, g) = matrices(&normal);
            jacobian_evaluations += 1;
            lambda *= (1.0f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
            nu = 2.0;
            history.push(LmIteration {
                iteration,
                cost: normal.cost(),
                lambda,
                accepted: true,
            });
        } else {
            lambda *= nu;
            nu *= 2.0;
            history.push(LmIteration {
                iteration,
                cost: f,
                lambda,
                accepted: false,
            });
            if small_step || lambda > 1e16 {
                termination = if gmax <= MACHINE_PRECISION_GTOL {
                    Termination::MachinePrecision
                } else {
                    Termination::NoProgress
                };
                break;
            }
        }
    }
    Ok(LmResult {
        params: start.with_values(&x).ok_or(CalibrationError::Shape)?,
        termination,
        iterations: history.len(),
        cost_evaluations,
        jacobian_evaluations,
        initial_cost,
        history,
        normal,
    })
}
