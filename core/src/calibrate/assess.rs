//! What follows every solver, once, in named stages: the sign convention;
//! the weights at the solution (and a refit when they moved); the unit σ
//! of terms without stated noise, settled against the prior; the robust
//! refits; the covariance; the diagnostics (estimates, correlations,
//! outliers, the predicted position uncertainty, the plausibility checks);
//! and the assembly of the [`Calibration`].

use nalgebra::DMatrix;

use super::anneal::AnnealTrace;
use super::checks::{ChiSquare, Outlier, OutlierScreen, gross_corrections};
use super::global::GlobalTrace;
use super::lm::{LmIteration, LmResult, levenberg_marquardt};
use super::robust::RobustFit;
use super::{
    AuxiliaryEstimate, Calibration, CalibrationError, Checks, CorrelationMatrix, Dof, Estimate,
    Method, ModelOptions, Outcome, Phase, SolverSettings, SolverSummary, Stop, TermRows,
};
use crate::dataset::DataSet;
use crate::identify::{Identification, strong_correlations};
use crate::kernel::ArmKernel;
use crate::objective::Objective;
use crate::params::{DhParams, ParamId, ParamKind, wrap};
use crate::residuals::{Normal, Role};
use crate::stats::coverage::{COVERAGE, K_ISOTROPIC, eigenvalues, radius};

/// Largest relative change of the weights at the solution, against those of
/// the fit, that needs no refit: the estimate moves by about this fraction
/// of its σ.
pub(crate) const REWEIGH_TOLERANCE: f64 = 0.05;

/// With a prior and no stated noise, at most this many refits while the
/// estimated touch σ settles.
const MAX_SIGMA_REFITS: usize = 6;

/// One term's share of the residuals and unknowns.
#[derive(Clone, Debug)]
struct TermCount {
    name: String,
    role: Role,
    rows: usize,
    eliminated: usize,
    /// Its weights are in units of an estimated σ.
    unit: bool,
    /// It has observations a robust loss weighs.
    observed: bool,
}

/// Residual rows and unknowns of a fit, per term.
#[derive(Clone, Debug)]
pub(crate) struct Counts {
    terms: Vec<TermCount>,
    free: usize,
}

impl Counts {
    /// The counts of `objective`'s terms over the columns `free`.
    pub(crate) fn of(objective: &Objective<'_>, free: &[usize]) -> Counts {
        Counts {
            terms: objective
                .terms()
                .map(|t| TermCount {
                    name: t.name().to_string(),
                    role: t.role(),
                    rows: t.rows(free),
                    eliminated: t.eliminated(),
                    unit: t.unit_weighted(),
                    observed: t.observations() > 0,
                })
                .collect(),
            free: free.len(),
        }
    }

    /// Residual rows: every term's (the prior's pseudo-observations too).
    pub(crate) fn residuals(&self) -> usize {
        self.terms.iter().map(|t| t.rows).sum()
    }

    /// The free columns and every unknown eliminated inside the terms.
    pub(crate) fn unknowns(&self) -> usize {
        self.free + self.eliminated()
    }

    fn eliminated(&self) -> usize {
        self.terms.iter().map(|t| t.eliminated).sum()
    }

    /// `m − p` (at least 1 once [`super::calibrate_with`] checked it).
    pub(crate) fn dof(&self) -> usize {
        self.residuals().saturating_sub(self.unknowns()).max(1)
    }

    /// The rows of the terms of role `role`.
    fn rows_of(&self, role: Role) -> usize {
        self.terms
            .iter()
            .filter(|t| t.role == role)
            .map(|t| t.rows)
            .sum()
    }

    /// Rows and eliminated unknowns of the terms `which` accepts.
    fn sum(&self, which: impl Fn(&TermCount) -> bool) -> (usize, usize) {
        self.terms
            .iter()
            .filter(|t| which(t))
            .fold((0, 0), |(r, e), t| (r + t.rows, e + t.eliminated))
    }

    /// The unit-weighted terms' own degrees of freedom, for a σ estimated
    /// from their residuals.
    fn unit_dof(&self) -> usize {
        let (rows, eliminated) = self.sum(|t| t.unit);
        rows.saturating_sub(eliminated + self.free).max(1)
    }

    /// `(e_o + p) / m_o` over the observed terms (rows `m_o`, eliminated
    /// unknowns `e_o`): the unknowns per residual row, Huber's `p/n` of
    /// the robust covariance's small-sample factor ([`super::robust`]).
    fn unknowns_per_row(&self) -> f64 {
        let (rows, eliminated) = self.sum(|t| t.observed);
        ((eliminated + self.free) as f64 / rows.max(1) as f64).min(1.0)
    }

    /// Whether every term's weights are in units of the estimated σ: the
    /// normal equations can then be rescaled by it instead of reweighed.
    fn all_unit(&self) -> bool {
        self.terms.iter().all(|t| t.unit)
    }

    /// The counts as reported, with the variance factor `sigma0` and the
    /// touch σ `unit_sigma` (from the stated noise when `stated`).
    fn report(&self, sigma0: f64, unit_sigma: f64, stated: bool) -> Dof {
        Dof {
            touch_rows: self.rows_of(Role::Touches),
            length_rows: self.rows_of(Role::Lengths),
            free_parameters: self.free,
            centre_coordinates: self.eliminated(),
            degrees_of_freedom: self.dof(),
            sigma0,
            touch_sigma_mm: unit_sigma,
            touch_sigma_estimated: !stated,
            prior_rows: self.rows_of(Role::Prior),
            other_rows: self.other_rows(),
        }
    }

    /// The rows of the terms that are neither touches, lengths nor the
    /// prior (by role), by name.
    fn other_rows(&self) -> Vec<TermRows> {
        self.terms
            .iter()
            .filter(|t| ![Role::Touches, Role::Lengths, Role::Prior].contains(&t.role))
            .map(|t| TermRows {
                term: t.name.clone(),
                rows: t.rows,
                eliminated: t.eliminated,
            })
            .collect()
    }
}

/// What [`assess`] needs besides the objective and the solver's outcome.
pub(crate) struct Setup<'a> {
    pub(crate) start: &'a DhParams,
    /// Every column at the start.
    pub(crate) x0: &'a [f64],
    pub(crate) data: &'a DataSet,
    pub(crate) model: &'a ModelOptions,
    pub(crate) settings: &'a SolverSettings,
    pub(crate) method: Method,
    pub(crate) free: Vec<usize>,
    pub(crate) identification: Option<Identification>,
    pub(crate) reasons: Vec<(ParamId, String)>,
    /// Auxiliary columns held at their start, with why (corrections the
    /// data cannot separate).
    pub(crate) held: Vec<(usize, String)>,
    pub(crate) counts: Counts,
    /// Whether every data term states its noise ([`Objective::stated`]).
    pub(crate) stated: bool,
    /// Tolerances carried onto free partners of redundant parameters.
    pub(crate) carried: Vec<super::prior::CarriedTolerance>,
    /// The weak directions held at nominal, if any.
    pub(crate) holds: Option<crate::residuals::HoldTerm>,
}

/// The fit as it passes from stage to stage.
struct Fit<'o> {
    /// The objective, as weighed now.
    objective: Objective<'o>,
    x: Vec<f64>,
    params: DhParams,
    normal: Normal,
    stop: Stop,
    iterations: usize,
    history: Vec<LmIteration>,
    phases: Vec<Phase>,
    anneal: Option<AnnealTrace>,
    global: Option<GlobalTrace>,
    /// Evaluations beyond the phases' own.
    extra_jacobians: usize,
    extra_costs: usize,
    /// The σ of a unit-weighted observation (a touch, mm).
    unit_sigma: f64,
    /// Whether the terms still carry unit weights (the normal equations were
    /// rescaled by the estimated σ, the weights not).
    unit_weights: bool,
    /// The robust fit and every observation's weight, when one ran.
    robust: Option<(RobustFit, Vec<f64>)>,
    /// A robust fit's normal equations under the curvature weights (the
    /// sandwich's `J̃ᵀ B J̃`, [`super::robust`]).
    curvature: Option<Normal>,
}

impl Fit<'_> {
    /// Takes the refit's point, normal equations and final LM's stop.
    fn take(&mut self, fit: LmResult) {
        self.stop = self.stop.with_lm(fit.termination);
        self.params = fit.params;
        self.x = fit.x;
        self.normal = fit.normal;
    }

    /// The unit-weighted terms' cost in the current normal equations.
    fn unit_cost(&self) -> f64 {
        (self.normal.costs.iter().zip(self.objective.terms()))
            .filter(|(_, t)| t.unit_weighted())
            .map(|(c, _)| *c)
            .sum()
    }

    /// An LM refit from the current point, as the phase `name`.
    fn refit(&mut self, setup: &Setup<'_>, name: &str) -> Result<LmResult, CalibrationError> {
        let timer = std::time::Instant::now();
        let refit = levenberg_marquardt(&self.objective, &self.x, &setup.free, &setup.settings.lm)?;
        let mut phase = Phase::new(name);
        phase.add_lm(&refit, timer.elapsed().as_secs_f64());
        self.phases.push(phase);
        Ok(refit)
    }

    /// Weighs the objective at the current point, the unit-weighted terms
    /// as `unit_sigma`.
    fn reweigh(&mut self) -> Result<(), CalibrationError> {
        self.objective.weigh(&self.x, self.unit_sigma)?;
        Ok(())
    }
}

/// Reweighs at the solution, refits when the weights moved, and computes
/// the covariance, correlations and dof: the same for every solver.
pub(crate) fn assess(
    setup: Setup<'_>,
    objective: Objective<'_>,
    outcome: Outcome,
) -> Result<Calibration, CalibrationError> {
    let mut fit = Fit {
        objective,
        x: outcome.x,
        params: outcome.params,
        normal: outcome.normal,
        stop: outcome.stop,
        iterations: outcome.iterations,
        history: outcome.history,
        phases: outcome.phases,
        anneal: outcome.anneal,
        global: outcome.global,
        extra_jacobians: 0,
        extra_costs: 0,
        unit_sigma: 1.0,
        unit_weights: false,
        robust: None,
        curvature: None,
    };
    normalise_signs(&mut fit, &setup)?;
    reweigh_at_solution(&mut fit, &setup)?;
    settle_unit_sigma(&mut fit, &setup)?;
    if setup.stated {
        fit.unit_sigma = typical_sigma(&fit.objective);
    }
    // Unit weights still (no stated noise, no other term): the normal
    // equations were rescaled by the estimated σ, the weights not.
    fit.unit_weights = !setup.stated && setup.counts.all_unit();
    robust_refits(&mut fit, &setup)?;
    let initial_cost = initial_cost(&mut fit, &setup)?;
    let covariance = covariance(&fit, &setup);
    assemble(fit, setup, covariance, initial_cost)
}

/// Puts the arm into the start's sign convention. Same positions, other
/// signs: the normal equations change sign pattern, so they are computed
/// again for the covariance.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
fn normalise_signs(fit: &mut Fit<'_>, setup: &Setup<'_>) -> Result<(), CalibrationError> {
    let changes = super::global::normalize_signs(&mut fit.params, setup.start, &setup.free);
    if !changes.is_empty() {
        let geometry = fit.params.to_vec();
        fit.x[..geometry.len()].copy_from_slice(&geometry);
        fit.normal = fit.objective.normal(&fit.x, &setup.free)?;
        fit.extra_jacobians += 1;
    }
    if let Some(g) = &mut fit.global {
        g.sign_changes = changes;
    }
    Ok(())
}

/// Weighs at the solution, not at the start: encoder noise moves the probe
/// along directions that depend on the arm, and the lengths' weights on the
/// centroids' directions — both far off when the zeros were. Without
/// stated noise the unit σ is first estimated from the unit-weighted
/// terms' residuals, so that the other terms weigh right against them;
/// when every term is unit-weighted the normal equations are rescaled
/// instead.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
fn reweigh_at_solution(fit: &mut Fit<'_>, setup: &Setup<'_>) -> Result<(), CalibrationError> {
    let stated = setup.stated;
    if !stated {
        // Unit weights: the residuals are mm. Estimate σ so that the other
        // terms weigh right against them.
        fit.unit_sigma = (fit.unit_cost() / setup.counts.unit_dof() as f64)
            .sqrt()
            .max(1e-9);
    }
    if !stated && setup.counts.all_unit() {
        let w2 = 1.0 / (fit.unit_sigma * fit.unit_sigma);
        fit.normal.jtj.iter_mut().for_each(|v| *v *= w2);
        let unit: Vec<bool> = fit.objective.terms().map(|t| t.unit_weighted()).collect();
        for (c, u) in fit.normal.costs.iter_mut().zip(unit) {
            if u {
                *c *= w2;
            }
        }
        for h in &mut fit.history {
            h.cost *= w2;
        }
        return Ok(());
    }
    let timer = std::time::Instant::now();
    // Weights that moved by under REWEIGH_TOLERANCE would move the estimate
    // by a like fraction of its σ and its σ not at all (shipped campaign,
    // lm: weights 3 % off moved no parameter by more than 3.4 % of its σ,
    // and σ by 1e-5 of itself): the fit's weights stand.
    let settled =
        stated && fit.objective.weight_change(&fit.x, fit.unit_sigma)? <= REWEIGH_TOLERANCE;
    if settled {
        // The fit's weights, normal equations and history stand.
        return Ok(());
    }
    fit.reweigh()?;
    if fit.stop.lm().is_none() {
        // No LM ran (annealing alone): none runs now either.
        fit.normal = fit.objective.normal(&fit.x, &setup.free)?;
        fit.extra_jacobians += 1;
        return Ok(());
    }
    let refit = levenberg_marquardt(&fit.objective, &fit.x, &setup.free, &setup.settings.lm)?;
    let mut phase = Phase::new("lm, weighed at the solution");
    phase.add_lm(&refit, timer.elapsed().as_secs_f64());
    fit.phases.push(phase);
    // With stated noise the weights keep their units: one history, the
    // descent then the polish. Otherwise the units changed.
    let n = if stated { fit.history.len() } else { 0 };
    if !stated {
        fit.history.clear();
        fit.iterations = 0;
    }
    fit.history
        .extend(refit.history.iter().map(|h| LmIteration {
            iteration: h.iteration + n,
            ..*h
        }));
    fit.iterations += refit.iterations;
    fit.take(refit);
    Ok(())
}

/// With a prior and no stated noise: the prior weighs against the touches,
/// so their σ must be right before the prior's pull is — estimate it again
/// from the refit until it settles (the first fit weighed touches as 1 mm).
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
fn settle_unit_sigma(fit: &mut Fit<'_>, setup: &Setup<'_>) -> Result<(), CalibrationError> {
    if !fit.objective.has_prior() || setup.stated {
        return Ok(());
    }
    for _ in 0..MAX_SIGMA_REFITS {
        let next = fit.unit_sigma * (fit.unit_cost() / setup.counts.unit_dof() as f64).sqrt();
        if !(next.is_finite() && next > 0.0)
            || (next / fit.unit_sigma - 1.0).abs() <= REWEIGH_TOLERANCE
        {
            break;
        }
        fit.unit_sigma = next.max(1e-9);
        fit.reweigh()?;
        let refit = fit.refit(setup, "lm, touch σ re-estimated (prior)")?;
        // The weights changed units again: the history is the refit's.
        fit.history = refit.history.clone();
        fit.iterations = refit.iterations;
        fit.take(refit);
    }
    Ok(())
}

/// The σ the stated noise gives a typical observation (the touches'), mm.
fn typical_sigma(objective: &Objective<'_>) -> f64 {
    objective
        .terms()
        .find_map(|t| t.typical_sigma())
        .unwrap_or(f64::NAN)
}

/// The robust refits (IRLS), when asked for: from the fit's minimum, every
/// observation weighed by the loss; without stated noise and with a prior,
/// again at σ·σ̂ until the robust scale settles.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
fn robust_refits(fit: &mut Fit<'_>, setup: &Setup<'_>) -> Result<(), CalibrationError> {
    let Some(r) = setup.model.robust else {
        return Ok(());
    };
    let stated = setup.stated;
    if fit.unit_weights {
        fit.reweigh()?;
        fit.unit_weights = false;
    }
    let lm = &setup.settings.lm;
    let base = (&fit.objective, &fit.normal);
    let ratio = setup.counts.unknowns_per_row();
    let mut out = super::robust::irls(r, &fit.x, base, &setup.free, lm, (stated, ratio))?;
    if fit.objective.has_prior() && !stated {
        // The touch σ was estimated with the outliers in; the prior weighs
        // against it, so refit at σ·σ̂ until σ̂ settles — else the prior
        // pulls (σ/σ_robust)² too hard.
        for _ in 0..MAX_SIGMA_REFITS {
            let s = out.fit.scale;
            if !(s.is_finite() && s > 0.0) || (s - 1.0).abs() <= REWEIGH_TOLERANCE {
                break;
            }
            fit.unit_sigma *= s;
            // Its standardised residuals and sandwich (below), and the base
            // weights' normal equations for the next.
            fit.extra_jacobians += out.fit.passes + 4;
            fit.phases.push(out.phase);
            fit.objective.weigh(&out.x, fit.unit_sigma)?;
            // The base weights' normal equations at the robust point.
            let normal = fit.objective.normal(&out.x, &setup.free)?;
            let base = (&fit.objective, &normal);
            out = super::robust::irls(r, &out.x, base, &setup.free, lm, (stated, ratio))?;
        }
    }
    // The standardised residuals (with the full leverage's Jacobians)
    // before each refit, after the last twice, and the sandwich's normal
    // equations.
    fit.extra_jacobians += out.fit.passes + 3;
    fit.phases.push(out.phase);
    fit.history = out.last.history;
    fit.iterations = out.last.iterations;
    // The refits are LM, after `sa` too: say so.
    fit.stop = match fit.stop {
        Stop::Anneal(anneal) => Stop::Hybrid {
            anneal,
            lm: out.last.termination,
        },
        other => other.with_lm(out.last.termination),
    };
    fit.params = out.last.params;
    fit.x = out.x;
    fit.normal = out.last.normal;
    fit.objective = out.objective;
    if !stated {
        // The estimated σ held the outliers; the robust scale does not.
        fit.unit_sigma *= out.fit.scale;
    }
    fit.robust = Some((out.fit, out.touch_weights));
    fit.curvature = Some(out.curvature);
    Ok(())
}

/// The start arm's data cost under the final weights: "cost A -> B"
/// compares like with like whatever the method did in between. Its
/// position buffer is freed at once: at 10⁶ touches it is 24 MB beside the
/// later checks' own.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
fn initial_cost(fit: &mut Fit<'_>, setup: &Setup<'_>) -> Result<f64, CalibrationError> {
    let mut cost = fit.objective.data_cost(setup.x0, &mut Vec::new())?;
    fit.extra_costs += 1;
    if fit.unit_weights {
        cost /= fit.unit_sigma * fit.unit_sigma;
    }
    Ok(cost)
}

/// The free columns' covariance and the variance factor σ̂.
struct Covariance {
    cov: DMatrix<f64>,
    sigma0: f64,
    dof: usize,
}

/// `σ̂² N⁻¹`, or with a prior `(N_data/σ̂² + P)⁻¹`; robust: the sandwich
/// `σ̂² κ K² (J̃ᵀ B J̃)⁻¹` ([`super::robust`]), σ̂ the robust scale — in the
/// same forms, with `J̃ᵀ B J̃` for `N` and `σ̂² κ K²` for `σ̂²`.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
fn covariance(fit: &Fit<'_>, setup: &Setup<'_>) -> Covariance {
    let dof = setup.counts.dof();
    let (sigma0, variance, normal) = match (&fit.robust, &fit.curvature) {
        (Some((robust, _)), Some(curvature)) => (
            robust.scale,
            robust.scale * robust.scale * robust.sandwich,
            curvature,
        ),
        _ => {
            let s = (fit.normal.cost() / dof as f64).sqrt();
            (s, s * s, &fit.normal)
        }
    };
    let p = setup.free.len();
    let n = DMatrix::from_row_slice(p, p, &normal.jtj);
    let invert = |m: DMatrix<f64>| match m.cholesky() {
        Some(ch) => super::inverse::cholesky_inverse(&ch),
        None => DMatrix::from_element(p, p, f64::INFINITY),
    };
    let cov = match fit.objective.prior() {
        // The stated tolerances are absolute: σ̂ rescales the data's
        // information, not the prior's — (N_data/σ̂² + P)⁻¹. Scaling the
        // whole σ̂²·N⁻¹ made a parameter the prior holds (data share 5 %)
        // 30 % more certain than its tolerance under a robust scale of 0.68.
        Some(term) if variance.is_finite() && variance > 0.0 => {
            let mut m = n / variance;
            for (a, &c) in setup.free.iter().enumerate() {
                if let Some(s) = term.sigma(c) {
                    m[(a, a)] += (1.0 - 1.0 / variance) / (s * s);
                }
            }
            invert(m)
        }
        _ => invert(n) * variance,
    };
    Covariance { cov, sigma0, dof }
}

/// Every geometry parameter's estimate (zero offsets and twists wrapped),
/// its σ from `cov` when free, and why it is fixed otherwise.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
fn estimates(fit: &mut Fit<'_>, setup: &Setup<'_>, cov: &DMatrix<f64>) -> Vec<Estimate> {
    let start = setup.start;
    for j in &mut fit.params.joints {
        j.theta = wrap(j.theta);
        j.alpha = wrap(j.alpha);
    }
    // The point follows: what is evaluated at it from here on is the
    // reported arm's.
    let geometry = fit.params.to_vec();
    fit.x[..geometry.len()].copy_from_slice(&geometry);
    start
        .param_ids()
        .enumerate()
        .map(|(c, id)| {
            let (nominal, calibrated) = (start.get(id), fit.params.get(id));
            let correction = if matches!(
                id.kind,
                ParamKind::Theta | ParamKind::Alpha | ParamKind::Beta
            ) {
                wrap(calibrated - nominal)
            } else {
                calibrated - nominal
            };
            let sigma = setup
                .free
                .iter()
                .position(|&f| f == c)
                .map(|a| cov[(a, a)].max(0.0).sqrt());
            Estimate {
                id,
                nominal,
                calibrated,
                correction,
                sigma: sigma.filter(|s| s.is_finite()),
                fixed: setup
                    .reasons
                    .iter()
                    .find(|(r, _)| *r == id)
                    .map(|(_, why)| why.clone()),
            }
        })
        .collect()
}

/// The auxiliary blocks' estimates (all their columns are free).
fn auxiliary(fit: &Fit<'_>, setup: &Setup<'_>, cov: &DMatrix<f64>) -> Vec<AuxiliaryEstimate> {
    let layout = fit.objective.layout();
    (layout.geometry_columns()..layout.len())
        .filter_map(|c| {
            let parameter = layout.parameter(c)?;
            let sigma = setup
                .free
                .iter()
                .position(|&f| f == c)
                .map(|a| cov[(a, a)].max(0.0).sqrt())
                .filter(|s| s.is_finite());
            let u = |v: f64| parameter.unit.to_user(v);
            let fixed = (setup.held.iter())
                .find(|(h, _)| *h == c)
                .map(|(_, why)| why.clone());
            Some(AuxiliaryEstimate {
                name: parameter.name.clone(),
                unit: parameter.unit.name().to_string(),
                start: u(setup.x0[c]),
                calibrated: u(fit.x[c]),
                sigma: sigma.map(u),
                sigma_of: layout.sigma_of(c),
                fixed,
            })
        })
        .collect()
}

/// The blocks whose values no real instrument could have, in words.
fn implausible_blocks(fit: &Fit<'_>, setup: &Setup<'_>) -> Vec<String> {
    let layout = fit.objective.layout();
    let mut first = layout.geometry_columns();
    layout
        .blocks()
        .filter_map(|b| {
            let cols = first..first + b.len();
            first = cols.end;
            b.implausible(&setup.x0[cols.clone()], &fit.x[cols])
        })
        .collect()
}

/// Every observation's standardised squared residual in units of its own
/// σ — the stated noise, or (estimated) the fit's, robustly: the median of
/// a χ²₃ variable is 2.366 (other row counts taken in its units), and a
/// few outliers do not move a median.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
fn standardised(
    fit: &Fit<'_>,
    setup: &Setup<'_>,
) -> Result<crate::objective::Observed, CalibrationError> {
    // The full leverage: the normal matrix of the weights the objective has
    // now (rescaled by 1/σ² without them when the weights are still unit).
    let scale = if fit.unit_weights {
        1.0 / (fit.unit_sigma * fit.unit_sigma)
    } else {
        1.0
    };
    let leverage = crate::residuals::ParameterLeverage::of(&fit.normal, scale);
    let mut t2 = fit.objective.standardised(&fit.x, leverage.as_ref())?;
    if let Some((_, w)) = &fit.robust {
        // In units of the observation's own σ, not of its robust weight.
        t2.values.iter_mut().zip(w).for_each(|(t, w)| *t /= w);
    }
    if !setup.stated {
        let mut sorted = t2.as_three_rows();
        let m = sorted.len() / 2;
        let median = crate::stats::kth_smallest(&mut sorted, m).unwrap_or(1.0);
        let s2 = (median / 2.366).max(f64::MIN_POSITIVE);
        t2.values.iter_mut().for_each(|v| *v /= s2);
    }
    Ok(t2)
}

/// The touches as the fitted arm's chain sees them with its corrections
/// beyond geometry, and those corrections' Jacobian factors; `None`
/// without corrections or touches.
fn touch_effects(
    fit: &Fit<'_>,
    setup: &Setup<'_>,
) -> Result<Option<crate::corrections::Effects>, CalibrationError> {
    let layout = fit.objective.layout();
    let (Some((block, cols)), false) = (layout.corrections(), setup.data.is_empty()) else {
        return Ok(None);
    };
    let physics = block.physics_at(&fit.x[cols]);
    if block.fit.is_empty() && !physics.corrects() {
        return Ok(None);
    }
    let data = setup.data;
    crate::corrections::Effects::new(
        &fit.params,
        &physics,
        &block.fit,
        data.poses(),
        data.conditions(),
    )
    .map(Some)
    .map_err(|message| CalibrationError::Term {
        term: "beyond".into(),
        message,
    })
}

/// The free columns below `arm` — the geometry's and the corrections'
/// beyond it — and their covariance: what moves a probe position.
fn geometry_covariance(
    free: &[usize],
    geometry: usize,
    cov: &DMatrix<f64>,
) -> (Vec<usize>, DMatrix<f64>) {
    let at: Vec<usize> = (0..free.len()).filter(|&a| free[a] < geometry).collect();
    let cols = at.iter().map(|&a| free[a]).collect();
    let sub = DMatrix::from_fn(at.len(), at.len(), |a, b| cov[(at[a], at[b])]);
    (cols, sub)
}

/// The calibration, from the fit and its covariance.
fn assemble(
    mut fit: Fit<'_>,
    setup: Setup<'_>,
    covariance: Covariance,
    initial_cost: f64,
) -> Result<Calibration, CalibrationError> {
    let Covariance { cov, sigma0, dof } = covariance;
    let stated = setup.stated;
    let prior = match (&setup.model.prior, fit.objective.prior()) {
        (Some(t), Some(term)) => Some(super::PriorReport::new(
            t,
            term,
            &fit.x,
            &setup.free,
            &cov,
            setup.start,
            setup.carried.clone(),
        )),
        _ => None,
    };
    let parameters = estimates(&mut fit, &setup, &cov);
    let auxiliary = auxiliary(&fit, &setup, &cov);
    let layout = fit.objective.layout();
    // The free columns' names (the report names nothing else).
    let names: Vec<String> = (setup.free.iter())
        .map(|&c| layout.parameter(c).map_or(String::new(), |p| p.name))
        .collect();
    let p = setup.free.len();
    let rho = correlations(&cov);
    let t2 = standardised(&fit, &setup)?;
    // Its full leverage evaluates the touches' Jacobians.
    fit.extra_jacobians += 1;
    let (outlier_threshold, outliers) = super::checks::outliers(&fit.objective, &t2);
    let (outliers, outlier_screen, screen_phase) = screen_outliers(&fit, &setup, outliers)?;
    // The columns that move a probe: the geometry's and the corrections'
    // (whose Jacobian columns follow the chain's, at the fitted values).
    let (geometry_free, geometry_cov) =
        geometry_covariance(&setup.free, layout.arm_columns(), &cov);
    let effects = touch_effects(&fit, &setup)?;
    let position_uncertainty = position_uncertainty(
        &fit.params,
        setup.data,
        effects.as_ref(),
        &geometry_free,
        &geometry_cov,
        touch_sigma_found(fit.unit_sigma, stated, sigma0),
    )?;
    let implausible = implausible_blocks(&fit, &setup);
    let physics = (layout.corrections()).map(|(block, cols)| block.physics_at(&fit.x[cols]));
    fit.phases.extend(screen_phase);
    let phases = &fit.phases;
    let cost_evaluations =
        fit.extra_costs + phases.iter().map(|p| p.cost_evaluations).sum::<usize>();
    let jacobian_evaluations =
        fit.extra_jacobians + phases.iter().map(|p| p.jacobian_evaluations).sum::<usize>();
    Ok(Calibration {
        physics,
        joint_types: fit.params.joints.iter().map(|j| j.kind).collect(),
        parameters,
        auxiliary,
        correlations: strong_correlations(&cov, p, |a| names[a].clone()),
        correlation_matrix: CorrelationMatrix {
            parameters: names,
            rho,
        },
        dof: setup.counts.report(sigma0, fit.unit_sigma, stated),
        solver: SolverSummary {
            method: setup.method,
            stop: fit.stop,
            successful: fit.stop.is_solution_usable(),
            iterations: fit.iterations,
            cost_evaluations,
            jacobian_evaluations,
            initial_cost,
            final_cost: fit.normal.cost(),
            history: fit.history,
            options: setup.settings.lm,
            phases: fit.phases,
            anneal: fit.anneal,
            global: fit.global,
        },
        identification: setup.identification,
        checks: Checks {
            gross_corrections: gross_corrections(&fit.params, setup.start, &setup.free),
            implausible_blocks: implausible,
            // A robust fit's weighted cost has no χ² law: its scale is
            // tested instead (`robust`).
            chi_square: (stated && fit.robust.is_none())
                .then(|| ChiSquare::new(fit.normal.cost(), dof)),
            outliers,
            outlier_threshold,
            outlier_screen,
            position_uncertainty,
        },
        held: held_directions(setup.holds.as_ref(), &fit.normal, sigma0),
        params: fit.params,
        robust: fit.robust.map(|(robust, _)| robust),
        prior,
    })
}

/// The correlation matrix of `cov` (0 where it is not a number).
fn correlations(cov: &DMatrix<f64>) -> Vec<Vec<f64>> {
    let p = cov.nrows();
    (0..p)
        .map(|a| {
            (0..p)
                .map(|b| {
                    let r = cov[(a, b)] / (cov[(a, a)] * cov[(b, b)]).sqrt();
                    if r.is_finite() { r } else { 0.0 }
                })
                .collect()
        })
        .collect()
}

/// The outliers as listed, the screen that kept them (if one ran) and its
/// work.
type Screened = (Vec<Outlier>, Option<OutlierScreen>, Option<Phase>);

/// A plain fit's outliers screened by a robust (Cauchy) refit from its
/// minimum when it names more than one touch
/// ([`super::checks::OutlierScreen`]): the named touches the refit weighs
/// below [`super::robust::DOWNWEIGHTED`], in the same order. The refit
/// changes nothing else; its work is a phase of its own. A robust fit's
/// list, or one of at most one touch, stands.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
fn screen_outliers(
    fit: &Fit<'_>,
    setup: &Setup<'_>,
    outliers: Vec<Outlier>,
) -> Result<Screened, CalibrationError> {
    if fit.robust.is_some() || outliers.len() <= 1 {
        return Ok((outliers, None, None));
    }
    let loss = super::robust::Loss::Cauchy;
    // Weights and normal equations in the same units (unit weights were
    // rescaled in the normal equations only).
    let mut base = fit.objective.clone();
    if fit.unit_weights {
        base.weigh(&fit.x, fit.unit_sigma)?;
    }
    let robust = super::robust::Robust::new(loss);
    let lm = &setup.settings.lm;
    let ratio = setup.counts.unknowns_per_row();
    let base = (&base, &fit.normal);
    let out = super::robust::irls(robust, &fit.x, base, &setup.free, lm, (false, ratio))?;
    let mut phase = out.phase;
    phase.name = format!("{} (outlier screen, not the fit)", phase.name);
    // As in `robust_refits`: the standardised residuals and the sandwich.
    phase.jacobian_evaluations += out.fit.passes + 3;
    let down: std::collections::HashSet<&str> = (out.fit.downweighted().into_iter())
        .map(|t| t.at.as_str())
        .collect();
    let flagged = outliers.len();
    let kept = (outliers.into_iter())
        .filter(|o| down.contains(o.at.as_str()))
        .collect();
    let screen = OutlierScreen {
        loss,
        flagged,
        scale: out.fit.scale,
    };
    Ok((kept, Some(screen), Some(phase)))
}

/// A touch's σ as the fit found it: with stated noise, the stated σ times
/// σ̂ (the covariance carries σ̂² too, so a misstated noise makes the data
/// look neither too weak nor too strong against a touch's scatter).
fn touch_sigma_found(unit_sigma: f64, stated: bool, sigma0: f64) -> f64 {
    if stated && sigma0.is_finite() && sigma0 > 0.0 {
        unit_sigma * sigma0
    } else {
        unit_sigma
    }
}

/// The held directions as reported, each with the σ the data alone give it
/// at the fit: `σ̂ / sqrt(wᵀ N w − K)`, `w` its scaled unit vector in the
/// columns' units, `N` the normal matrix at the solution (which carries the
/// hold's own `K` along `w`, and no tolerance: held columns have none).
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
fn held_directions(
    holds: Option<&crate::residuals::HoldTerm>,
    normal: &Normal,
    sigma0: f64,
) -> Vec<crate::residuals::HeldDirection> {
    let Some(term) = holds else {
        return Vec::new();
    };
    let p = normal.free.len();
    term.holds()
        .iter()
        .map(|h| {
            let w: Vec<(usize, f64)> = (0..h.cols.len())
                .filter_map(|i| {
                    let a = normal.free.iter().position(|&f| f == h.cols[i])?;
                    Some((a, h.v[i] * h.d[i]))
                })
                .collect();
            let nww: f64 = (w.iter())
                .flat_map(|&(a, wa)| w.iter().map(move |&(b, wb)| (a, b, wa * wb)))
                .map(|(a, b, ww)| normal.jtj[a * p + b] * ww)
                .sum();
            let info = nww - term.stiffness();
            crate::residuals::HeldDirection {
                relation: h.text.clone(),
                terms: h.terms.clone(),
                ratio: h.ratio,
                sigma_mm: (info > 0.0)
                    .then(|| sigma0 / info.sqrt())
                    .filter(|s| s.is_finite()),
            }
        })
        .collect()
}

/// The predicted position uncertainty of `params` (the 95 % radius of each
/// pose's 3-D error) over the poses of `data` (an even sample of at most [`super::checks::UNCERTAINTY_POSES`]),
/// from the free parameters' covariance `cov`.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
fn position_uncertainty(
    params: &DhParams,
    data: &DataSet,
    effects: Option<&crate::corrections::Effects>,
    free: &[usize],
    cov: &DMatrix<f64>,
    touch_sigma: f64,
) -> Result<Option<super::checks::PositionUncertainty>, CalibrationError> {
    if data.is_empty() || cov.iter().any(|v| !v.is_finite()) {
        return Ok(None);
    }
    let kernel = ArmKernel::new(params)?;
    let step = data.len().div_ceil(super::checks::UNCERTAINTY_POSES).max(1);
    let q = free.len();
    let c: Vec<f64> = (0..q * q).map(|i| cov[(i / q, i % q)]).collect();
    let poses: Vec<usize> = (0..data.len()).step_by(step).collect();
    let mut sums = UncertaintySums {
        free,
        c,
        jf: vec![[[0.0; LANES]; 3]; q],
        sum: 0.0,
        max: 0.0,
    };
    // The Jacobians from the poses' stored sin/cos through the lanes kernel
    // (the same bits as `position_jacobian` of the readings, without their
    // trigonometry): every pose in one call when every pose is sampled.
    // The sums are inlined into the kernel's loop, so they are compiled with
    // its target features (AVX2 where the CPU has it; no FMA, so the same
    // bits as without).
    let last = |l: usize, i: usize| (l + 1 == LANES || i + step >= data.len()).then_some(l + 1);
    if let Some(e) = effects {
        // With corrections beyond geometry: the poses as the chain saw
        // them, each Jacobian extended by the corrections' columns.
        let mut ext = Vec::new();
        if step == 1 {
            kernel.for_each_jacobian(&e.poses, 0..data.len(), |i, pos, jac| {
                e.extend(i, pos, jac, &mut ext);
                sums.add(i % LANES, &ext, last(i % LANES, i));
            })?;
        } else {
            for (k, &i) in poses.iter().enumerate() {
                let l = k % LANES;
                kernel.for_each_jacobian(&e.poses, i..i + 1, |i, pos, jac| {
                    e.extend(i, pos, jac, &mut ext);
                    sums.add(l, &ext, last(l, i));
                })?;
            }
        }
    } else if step == 1 {
        kernel.for_each_jacobian(
            data.poses(),
            0..data.len(),
            #[inline(always)]
            |i, _, jac| sums.add(i % LANES, jac, last(i % LANES, i)),
        )?;
    } else {
        for (k, &i) in poses.iter().enumerate() {
            let l = k % LANES;
            kernel.for_each_jacobian(
                data.poses(),
                i..i + 1,
                #[inline(always)]
                |_, _, jac| sums.add(l, jac, last(l, i)),
            )?;
        }
    }
    let (sum, max) = (sums.sum, sums.max);
    let n = poses.len();
    Ok(Some(super::checks::PositionUncertainty {
        coverage: COVERAGE,
        poses: n,
        rms_mm: (sum / n as f64).sqrt(),
        max_mm: max,
        touch_mm: K_ISOTROPIC * touch_sigma,
    }))
}

/// Poses whose uncertainties [`position_uncertainty`] sums side by side:
/// independent chains, so they run together (each in its own order: the
/// same bits as one at a time).
const LANES: usize = 8;

/// [`position_uncertainty`]'s running sums: the covariance row-major, the
/// free columns of [`LANES`] poses' position Jacobians side by side.
struct UncertaintySums<'a> {
    free: &'a [usize],
    c: Vec<f64>,
    jf: Vec<[[f64; LANES]; 3]>,
    sum: f64,
    max: f64,
}

impl UncertaintySums<'_> {
    /// Pose `l` of the group from its Jacobian; with the group's last, its
    /// `n` poses' 95 % radii ([`radius`]) into the sums.
    #[inline(always)]
    fn add(&mut self, l: usize, jac: &[[f64; 3]], n: Option<usize>) {
        let (jf, q) = (&mut self.jf, self.free.len());
        for (a, &ca) in self.free.iter().enumerate() {
            for k in 0..3 {
                jf[a][k][l] = jac[ca][k];
            }
        }
        let Some(n) = n else { return };
        // The position's covariance J C Jᵀ, its six distinct entries (xx,
        // yy, zz, xy, xz, yz) per lane: its eigenvalues, not only its trace,
        // give the radius that covers 95 % of a 3-D error.
        const PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];
        let mut m = [[0.0; LANES]; 6];
        for a in 0..q {
            let (ja, row) = (&jf[a], &self.c[a * q..(a + 1) * q]);
            for (jb, &cab) in jf.iter().zip(row) {
                for (e, &(r, s)) in PAIRS.iter().enumerate() {
                    for l in 0..LANES {
                        m[e][l] += cab * ja[r][l] * jb[s][l];
                    }
                }
            }
        }
        for l in 0..n {
            let [xx, yy, zz, xy, xz, yz] = m.map(|e| e[l]);
            let u = radius(eigenvalues([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]));
            self.sum += u * u;
            self.max = self.max.max(u);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`position_uncertainty`] one pose at a time, as before the poses went
    /// four at a time: the reference the lanes must match bit for bit.
    fn one_at_a_time(
        params: &DhParams,
        data: &DataSet,
        free: &[usize],
        cov: &DMatrix<f64>,
    ) -> (usize, f64, f64) {
        let kernel = ArmKernel::new(params).unwrap();
        let step = data
            .len()
            .div_ceil(super::super::checks::UNCERTAINTY_POSES)
            .max(1);
        let mut jac = vec![[0.0; 3]; params.param_count()];
        let (mut sum, mut max, mut n) = (0.0, 0.0f64, 0usize);
        for i in (0..data.len()).step_by(step) {
            kernel.position_jacobian(data.reading(i), &mut jac).unwrap();
            let mut m = [[0.0; 3]; 3];
            for (a, &ca) in free.iter().enumerate() {
                for (b, &cb) in free.iter().enumerate() {
                    for (r, mr) in m.iter_mut().enumerate() {
                        for (s, v) in mr.iter_mut().enumerate() {
                            *v += cov[(a, b)] * jac[ca][r] * jac[cb][s];
                        }
                    }
                }
            }
            // Symmetric as the lanes' (which sum the upper triangle only).
            (m[1][0], m[2][0], m[2][1]) = (m[0][1], m[0][2], m[1][2]);
            let u = radius(eigenvalues(m));
            sum += u * u;
            max = max.max(u);
            n += 1;
        }
        (n, (sum / n as f64).sqrt(), max)
    }

    /// Pose counts that leave 1, 2, 3 and 4 poses in the last group, and one
    /// sampled (more than UNCERTAINTY_POSES touches): the same bits.
    #[test]
    fn position_uncertainty_in_lanes_is_the_same_bits() {
        let params = DhParams::paper_nominal();
        let free: Vec<usize> = (2..params.param_count() - 2).collect();
        let q = free.len();
        // A symmetric positive-definite covariance with correlations.
        let cov = DMatrix::from_fn(q, q, |a, b| {
            let d = a.abs_diff(b) as f64;
            if a == b {
                1e-4 * (1.0 + a as f64)
            } else {
                1e-5 / (1.0 + d)
            }
        });
        for touches in [3usize, 5, 6, 7, 9, 4003] {
            // At least 3 touches a point.
            let points = (touches / 3).min(3);
            let labels: Vec<String> = (0..touches).map(|i| format!("p{}", i % points)).collect();
            let readings: Vec<Vec<f64>> = (0..touches)
                .map(|i| {
                    (0..6)
                        .map(|j| ((i * 7 + j * 13) % 31) as f64 * 0.2 - 3.0)
                        .collect()
                })
                .collect();
            let data = DataSet::from_touches(&labels, &readings, &[]).unwrap();
            let u = position_uncertainty(&params, &data, None, &free, &cov, 0.01)
                .unwrap()
                .unwrap();
            let (n, rms, max) = one_at_a_time(&params, &data, &free, &cov);
            assert_eq!(u.poses, n, "{touches} touches");
            assert_eq!(u.rms_mm.to_bits(), rms.to_bits(), "{touches} touches");
            assert_eq!(u.max_mm.to_bits(), max.to_bits(), "{touches} touches");
        }
    }
}
