//! What follows every solver, once, in named stages: the sign convention;
//! the weights at the solution (and a refit when they moved); the unit σ
//! of terms without stated noise, settled against the prior; the robust
//! refits; the covariance; the diagnostics (estimates, correlations,
//! outliers, the predicted position uncertainty, the plausibility checks);
//! and the assembly of the [`Calibration`].

use nalgebra::DMatrix;

use super::anneal::AnnealTrace;
use super::checks::{ChiSquare, PositionUncertainty, gross_corrections};
use super::global::GlobalTrace;
use super::lm::{LmIteration, LmResult, levenberg_marquardt};
use super::robust::RobustFit;
use super::{
    Calibration, CalibrationError, Checks, CorrelationMatrix, Method, ModelOptions, Outcome, Phase,
    PriorReport, SolverSettings, SolverSummary, Stop,
};
use crate::dataset::DataSet;
use crate::identify::{Identification, strong_correlations};
use crate::objective::Objective;
use crate::params::{DhParams, ParamId};
use crate::residuals::Normal;

mod counts;
mod covariance;
mod diagnostics;
mod refits;

pub(crate) use counts::Counts;
use covariance::{
    Covariance, correlations, covariance, geometry_covariance, held_directions,
    position_uncertainty,
};
use diagnostics::{
    auxiliary, estimates, implausible_blocks, screen_outliers, standardised, touch_effects,
    touch_sigma_found,
};
use refits::{reweigh_at_solution, robust_refits, settle_unit_sigma, typical_sigma};

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

/// The calibration, from the fit and its covariance.
fn assemble(
    mut fit: Fit<'_>,
    setup: Setup<'_>,
    covariance: Covariance,
    initial_cost: f64,
) -> Result<Calibration, CalibrationError> {
    let Covariance {
        cov,
        sigma0,
        dof,
        normal_inverse,
    } = covariance;
    let stated = setup.stated;
    let prior = prior_report(&fit, &setup, &cov);
    let parameters = estimates(&mut fit, &setup, &cov);
    let auxiliary = auxiliary(&fit, &setup, &cov);
    let layout = fit.objective.layout();
    // The free columns' names (the report names nothing else).
    let names: Vec<String> = (setup.free.iter())
        .map(|&c| layout.parameter(c).map_or(String::new(), |p| p.name))
        .collect();
    let p = setup.free.len();
    let rho = correlations(&cov);
    let t2 = standardised(&fit, &setup, normal_inverse.as_ref())?;
    // Its full leverage evaluates the touches' Jacobians.
    fit.extra_jacobians += 1;
    let (outlier_threshold, outliers) = super::checks::outliers(&fit.objective, &t2);
    let (outliers, outlier_screen, screen_phase) = screen_outliers(&fit, &setup, outliers)?;
    let position_uncertainty = predicted_uncertainty(&fit, &setup, &cov, sigma0)?;
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

/// What the prior did, when the fit had one.
fn prior_report(fit: &Fit<'_>, setup: &Setup<'_>, cov: &DMatrix<f64>) -> Option<PriorReport> {
    match (&setup.model.prior, fit.objective.prior()) {
        (Some(t), Some(term)) => Some(PriorReport::new(
            t,
            term,
            &fit.x,
            &setup.free,
            cov,
            setup.start,
            setup.carried.clone(),
        )),
        _ => None,
    }
}

/// The predicted uncertainty of a probed position over the data's poses,
/// from the covariance of the columns that move a probe: the geometry's
/// and the corrections' (whose Jacobian columns follow the chain's, at the
/// fitted values).
fn predicted_uncertainty(
    fit: &Fit<'_>,
    setup: &Setup<'_>,
    cov: &DMatrix<f64>,
    sigma0: f64,
) -> Result<Option<PositionUncertainty>, CalibrationError> {
    let layout = fit.objective.layout();
    let (geometry_free, geometry_cov) = geometry_covariance(&setup.free, layout.arm_columns(), cov);
    let effects = touch_effects(fit, setup)?;
    position_uncertainty(
        &fit.params,
        setup.data,
        effects.as_ref(),
        &geometry_free,
        &geometry_cov,
        touch_sigma_found(fit.unit_sigma, setup.stated, sigma0),
    )
}
