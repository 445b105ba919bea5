//! The diagnostics of a fit: the estimates with their σ, the auxiliary
//! blocks', the implausible blocks, the standardised residuals and the
//! outliers they show.

use nalgebra::DMatrix;

use crate::calibrate::checks::{Outlier, OutlierScreen};
use crate::calibrate::{AuxiliaryEstimate, CalibrationError, Estimate, Phase};
use crate::params::{ParamKind, wrap};

use super::{Fit, Setup};

/// Every geometry parameter's estimate (zero offsets and twists wrapped),
/// its σ from `cov` when free, and why it is fixed otherwise.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
pub(super) fn estimates(fit: &mut Fit<'_>, setup: &Setup<'_>, cov: &DMatrix<f64>) -> Vec<Estimate> {
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
pub(super) fn auxiliary(
    fit: &Fit<'_>,
    setup: &Setup<'_>,
    cov: &DMatrix<f64>,
) -> Vec<AuxiliaryEstimate> {
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
pub(super) fn implausible_blocks(fit: &Fit<'_>, setup: &Setup<'_>) -> Vec<String> {
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
/// few outliers do not move a median. `normal_inverse`: the covariance's
/// `N⁻¹` of the fit's normal equations, when it made one.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
pub(super) fn standardised(
    fit: &Fit<'_>,
    setup: &Setup<'_>,
    normal_inverse: Option<&DMatrix<f64>>,
) -> Result<crate::objective::Observed, CalibrationError> {
    use crate::residuals::ParameterLeverage;
    // The full leverage: the normal matrix of the weights the objective has
    // now (rescaled by 1/σ² without them when the weights are still unit).
    let scale = if fit.unit_weights {
        1.0 / (fit.unit_sigma * fit.unit_sigma)
    } else {
        1.0
    };
    // Unscaled, it is the covariance's matrix: the same Cholesky of the
    // same entries (a division by 1 is exact), so the same bits, once.
    let leverage = match normal_inverse {
        Some(inverse) if scale == 1.0 => ParameterLeverage::from_inverse(&fit.normal, inverse),
        _ => ParameterLeverage::of(&fit.normal, scale),
    };
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
pub(super) fn touch_effects(
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

/// The outliers as listed, the screen that kept them (if one ran) and its
/// work.
type Screened = (Vec<Outlier>, Option<OutlierScreen>, Option<Phase>);

/// A plain fit's outliers screened by a robust (Cauchy) refit from its
/// minimum when it names more than one touch
/// ([`crate::calibrate::checks::OutlierScreen`]): the named touches the refit weighs
/// below [`crate::calibrate::robust::DOWNWEIGHTED`], in the same order. The refit
/// changes nothing else; its work is a phase of its own. A robust fit's
/// list, or one of at most one touch, stands.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
pub(super) fn screen_outliers(
    fit: &Fit<'_>,
    setup: &Setup<'_>,
    outliers: Vec<Outlier>,
) -> Result<Screened, CalibrationError> {
    if fit.robust.is_some() || outliers.len() <= 1 {
        return Ok((outliers, None, None));
    }
    let loss = crate::calibrate::robust::Loss::Cauchy;
    // Weights and normal equations in the same units (unit weights were
    // rescaled in the normal equations only).
    let mut base = fit.objective.clone();
    if fit.unit_weights {
        base.weigh(&fit.x, fit.unit_sigma)?;
    }
    let robust = crate::calibrate::robust::Robust::new(loss);
    let lm = &setup.settings.lm;
    let ratio = setup.counts.unknowns_per_row();
    let base = (&base, &fit.normal);
    let out =
        crate::calibrate::robust::irls(robust, &fit.x, base, &setup.free, lm, (false, ratio))?;
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
pub(super) fn touch_sigma_found(unit_sigma: f64, stated: bool, sigma0: f64) -> f64 {
    if stated && sigma0.is_finite() && sigma0 > 0.0 {
        unit_sigma * sigma0
    } else {
        unit_sigma
    }
}
