//! The refits after a solver: at the solution's weights, while the
//! estimated unit σ settles against a prior, and the robust ones.

use crate::calibrate::lm::{LmIteration, levenberg_marquardt};
use crate::calibrate::{CalibrationError, Phase, Stop};
use crate::objective::Objective;

use super::{Fit, Setup};

/// Largest relative change of the weights at the solution, against those of
/// the fit, that needs no refit: the estimate moves by about this fraction
/// of its σ.
pub(crate) const REWEIGH_TOLERANCE: f64 = 0.05;

/// With a prior and no stated noise, at most this many refits while the
/// estimated touch σ settles.
const MAX_SIGMA_REFITS: usize = 6;

/// Weighs at the solution, not at the start: encoder noise moves the probe
/// along directions that depend on the arm, and the lengths' weights on the
/// centroids' directions — both far off when the zeros were. Without
/// stated noise the unit σ is first estimated from the unit-weighted
/// terms' residuals, so that the other terms weigh right against them;
/// when every term is unit-weighted the normal equations are rescaled
/// instead.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
pub(super) fn reweigh_at_solution(
    fit: &mut Fit<'_>,
    setup: &Setup<'_>,
) -> Result<(), CalibrationError> {
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
pub(super) fn settle_unit_sigma(
    fit: &mut Fit<'_>,
    setup: &Setup<'_>,
) -> Result<(), CalibrationError> {
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
pub(super) fn typical_sigma(objective: &Objective<'_>) -> f64 {
    objective
        .terms()
        .find_map(|t| t.typical_sigma())
        .unwrap_or(f64::NAN)
}

/// The robust refits (IRLS), when asked for: from the fit's minimum, every
/// observation weighed by the loss; without stated noise and with a prior,
/// again at σ·σ̂ until the robust scale settles.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
pub(super) fn robust_refits(fit: &mut Fit<'_>, setup: &Setup<'_>) -> Result<(), CalibrationError> {
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
    let mut out =
        crate::calibrate::robust::irls(r, &fit.x, base, &setup.free, lm, (stated, ratio))?;
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
            out =
                crate::calibrate::robust::irls(r, &out.x, base, &setup.free, lm, (stated, ratio))?;
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
