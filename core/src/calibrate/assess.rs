//! What follows every solver, once: the sign convention, the weights at the
//! solution (and a refit when they moved), the touch σ, the covariance,
//! correlations and degrees of freedom.

use nalgebra::DMatrix;

use super::checks::{ChiSquare, gross_corrections};
use super::lm::{LmIteration, levenberg_marquardt};
use super::{
    Calibration, CalibrationError, Checks, CorrelationMatrix, Dof, Estimate, Method, ModelOptions,
    Outcome, Phase, SolverSettings, SolverSummary, Stop,
};
use crate::dataset::DataSet;
use crate::identify::{Identification, strong_correlations};
use crate::kernel::ArmKernel;
use crate::params::{DhParams, ParamId, ParamKind, wrap};
use crate::residuals::Weights;

/// Largest relative change of the weights at the solution, against those of
/// the fit, that needs no refit: the estimate moves by about this fraction
/// of its σ.
pub const REWEIGH_TOLERANCE: f64 = 0.05;

/// With a prior and no stated noise, at most this many refits while the
/// estimated touch σ settles.
const MAX_SIGMA_REFITS: usize = 6;

/// Residual rows and unknowns of a fit.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Counts {
    touch_rows: usize,
    length_rows: usize,
    centre_coordinates: usize,
    free: usize,
    pub(crate) prior_rows: usize,
}

impl Counts {
    pub(crate) fn new(data: &DataSet, free: usize) -> Counts {
        Counts {
            touch_rows: 3 * data.len(),
            length_rows: data.references().len(),
            centre_coordinates: 3 * data.points().len(),
            free,
            prior_rows: 0,
        }
    }

    /// These counts with `rows` pseudo-observations of a prior.
    pub(crate) fn with_prior_rows(self, rows: usize) -> Counts {
        Counts {
            prior_rows: rows,
            ..self
        }
    }

    /// Residual rows: touches, lengths and the prior's pseudo-observations.
    pub(crate) fn residuals(self) -> usize {
        self.touch_rows + self.length_rows + self.prior_rows
    }

    pub(crate) fn unknowns(self) -> usize {
        self.free + self.centre_coordinates
    }

    /// `m − p` (at least 1 once [`super::calibrate_with`] checked it).
    pub(crate) fn dof(self) -> usize {
        self.residuals().saturating_sub(self.unknowns()).max(1)
    }

    /// `(3n − 3k) / (3n − 3k − p)`: the share of the touch residuals the
    /// free parameters take, which the leverage on the centroids does not
    /// correct ([`super::robust`]).
    pub(crate) fn scale_dof_factor(self) -> f64 {
        let rows = self.touch_rows.saturating_sub(self.centre_coordinates);
        rows as f64 / self.touch_dof() as f64
    }

    /// The touches' own degrees of freedom, for a σ estimated from them.
    fn touch_dof(self) -> usize {
        self.touch_rows
            .saturating_sub(self.centre_coordinates + self.free)
            .max(1)
    }
}

/// What [`assess`] needs besides the solver's outcome.
pub(crate) struct Setup<'a> {
    pub start: &'a DhParams,
    pub data: &'a DataSet,
    pub model: &'a ModelOptions,
    pub settings: &'a SolverSettings,
    pub method: Method,
    pub free: Vec<usize>,
    pub identification: Option<Identification>,
    pub reasons: Vec<(ParamId, String)>,
    /// The weights the solver fitted under (at the start arm).
    pub weights: Weights,
    pub counts: Counts,
}

/// Reweighs at the solution, refits when the weights moved, and computes
/// the covariance, correlations and dof: the same for every solver.
pub(crate) fn assess(setup: Setup, outcome: Outcome) -> Result<Calibration, CalibrationError> {
    let Setup {
        start,
        data,
        model,
        settings,
        method,
        free,
        identification,
        reasons,
        mut weights,
        counts,
    } = setup;
    let Outcome {
        mut params,
        mut stop,
        mut iterations,
        mut history,
        mut phases,
        anneal,
        mut global,
        mut normal,
    } = outcome;
    let (lm, threads) = (settings.lm, settings.threads);
    let stated = model.noise.stated();
    let normal_at = |params: &DhParams, weights: &Weights| -> Result<_, CalibrationError> {
        super::prior::normal_at(params, data, weights, &free, threads)
    };
    let has_prior = weights.prior.is_some();
    // The touches' and lengths' weights at another arm, in place: the old
    // ones are freed first (one set at a time: 48 MB at 10⁶ touches), the
    // prior rides along.
    let reweigh = |weights: &mut Weights,
                   params: &DhParams,
                   touch_sigma: f64|
     -> Result<(), CalibrationError> {
        let prior = weights.prior.take();
        *weights = Weights::default();
        *weights = Weights::new_threads(
            &ArmKernel::new(params)?,
            data,
            &model.noise,
            touch_sigma,
            threads,
        )?;
        weights.prior = prior;
        Ok(())
    };
    let mut extra_jacobians = 0;
    let mut extra_costs = 0;
    let sign_changes = super::global::normalize_signs(&mut params, start, &free);
    if !sign_changes.is_empty() {
        // Same positions, other signs: the normal equations change sign
        // pattern, so recompute them for the covariance.
        normal = normal_at(&params, &weights)?;
        extra_jacobians += 1;
    }
    if let Some(g) = &mut global {
        g.sign_changes = sign_changes;
    }
    let mut touch_sigma = 1.0;
    if !stated {
        // Unit weights: the touch residuals are mm. Estimate σ so that the
        // lengths weigh right against the touches.
        touch_sigma = (normal.touch_cost / counts.touch_dof() as f64)
            .sqrt()
            .max(1e-9);
    }
    if stated || counts.length_rows > 0 || has_prior {
        // Weigh at the solution, not at the start: encoder noise moves the
        // probe along directions that depend on the arm, and the lengths'
        // weights on the centroids' directions — both far off when the
        // zeros were.
        let timer = std::time::Instant::now();
        // Weights that moved by under REWEIGH_TOLERANCE would move the
        // estimate by a like fraction of its σ and its σ not at all (shipped
        // campaign, lm: weights 3 % off moved no parameter by more than
        // 3.4 % of its σ, and σ by 1e-5 of itself): the fit's weights stand.
        let settled = stated
            && weights.relative_change_to(
                &ArmKernel::new(&params)?,
                data,
                &model.noise,
                touch_sigma,
                threads,
            )? <= REWEIGH_TOLERANCE;
        if settled {
            // The fit's weights, normal equations and history stand.
        } else if stop.lm().is_none() {
            // No LM ran (annealing alone): none runs now either.
            reweigh(&mut weights, &params, touch_sigma)?;
            normal = normal_at(&params, &weights)?;
            extra_jacobians += 1;
        } else {
            reweigh(&mut weights, &params, touch_sigma)?;
            let refit = levenberg_marquardt(&params, data, &weights, &free, &lm, threads)?;
            let mut phase = Phase::new("lm, weighed at the solution");
            phase.add_lm(&refit, timer.elapsed().as_secs_f64());
            phases.push(phase);
            // With stated noise the weights keep their units: one history,
            // the descent then the polish. Otherwise the units changed.
            let n = if stated { history.len() } else { 0 };
            if !stated {
                history.clear();
                iterations = 0;
            }
            history.extend(refit.history.iter().map(|h| LmIteration {
                iteration: h.iteration + n,
                ..*h
            }));
            iterations += refit.iterations;
            stop = stop.with_lm(refit.termination);
            params = refit.params;
            normal = refit.normal;
        }
    } else {
        let w2 = 1.0 / (touch_sigma * touch_sigma);
        normal.jtj.iter_mut().for_each(|v| *v *= w2);
        normal.touch_cost *= w2;
        for h in &mut history {
            h.cost *= w2;
        }
    }
    if has_prior && !stated {
        // The prior weighs against the touches, so their σ must be right
        // before the prior's pull is: estimate it again from the refit
        // until it settles (the first fit weighed touches as 1 mm).
        for _ in 0..MAX_SIGMA_REFITS {
            let next = touch_sigma * (normal.touch_cost / counts.touch_dof() as f64).sqrt();
            if !(next.is_finite() && next > 0.0)
                || (next / touch_sigma - 1.0).abs() <= REWEIGH_TOLERANCE
            {
                break;
            }
            touch_sigma = next.max(1e-9);
            let timer = std::time::Instant::now();
            reweigh(&mut weights, &params, touch_sigma)?;
            let refit = levenberg_marquardt(&params, data, &weights, &free, &lm, threads)?;
            let mut phase = Phase::new("lm, touch σ re-estimated (prior)");
            phase.add_lm(&refit, timer.elapsed().as_secs_f64());
            phases.push(phase);
            // The weights changed units again: the history is the refit's.
            history = refit.history.clone();
            iterations = refit.iterations;
            stop = stop.with_lm(refit.termination);
            params = refit.params;
            normal = refit.normal;
        }
    }
    if stated {
        touch_sigma = weights.typical_touch_sigma();
    }
    // Unit weights still (no stated noise, no lengths, no prior): the normal
    // equations were rescaled by the estimated σ, the weights not.
    let mut unit_weights = !stated && counts.length_rows == 0 && !has_prior;
    let mut robust = None;
    if let Some(r) = model.robust {
        if unit_weights {
            reweigh(&mut weights, &params, touch_sigma)?;
            unit_weights = false;
        }
        let irls = |params: &DhParams, weights: &Weights| {
            super::robust::irls(
                r,
                params,
                data,
                weights,
                &free,
                &lm,
                threads,
                counts.scale_dof_factor(),
                stated,
            )
        };
        let mut out = irls(&params, &weights)?;
        if has_prior && !stated {
            // The touch σ was estimated with the outliers in; the prior
            // weighs against it, so refit at σ·σ̂ until σ̂ settles — else
            // the prior pulls (σ/σ_robust)² too hard.
            for _ in 0..MAX_SIGMA_REFITS {
                let s = out.fit.scale;
                if !(s.is_finite() && s > 0.0) || (s - 1.0).abs() <= REWEIGH_TOLERANCE {
                    break;
                }
                touch_sigma *= s;
                extra_jacobians += out.fit.passes + 1;
                phases.push(out.phase);
                reweigh(&mut weights, &out.params, touch_sigma)?;
                out = irls(&out.params, &weights)?;
            }
        }
        extra_jacobians += out.fit.passes + 1;
        phases.push(out.phase);
        history = out.last.history;
        iterations = out.last.iterations;
        // The refits are LM, after `sa` too: say so.
        stop = match stop {
            Stop::Anneal(anneal) => Stop::Hybrid {
                anneal,
                lm: out.last.termination,
            },
            other => other.with_lm(out.last.termination),
        };
        params = out.params;
        normal = out.last.normal;
        weights = out.weights;
        if !stated {
            // The estimated σ held the outliers; the robust scale does not.
            touch_sigma *= out.fit.scale;
        }
        robust = Some((out.fit, out.touch_weights));
    }
    // The start arm's cost under the final weights: "cost A -> B" compares
    // like with like whatever the method did in between.
    // Its position buffer is freed at once: at 10⁶ touches it is 24 MB
    // beside the later checks' own.
    let mut initial_cost = crate::residuals::cost(
        &ArmKernel::new(start)?,
        data,
        &weights,
        &mut vec![[0.0; 3]; data.len()],
    )?;
    extra_costs += 1;
    if unit_weights {
        initial_cost /= touch_sigma * touch_sigma;
    }
    let degrees_of_freedom = counts.dof();
    // Robust: the IRLS covariance σ̂²(JᵀWJ)⁻¹ with σ̂ the robust scale.
    let sigma0 = match &robust {
        Some((fit, _)) => fit.scale,
        None => (normal.cost() / degrees_of_freedom as f64).sqrt(),
    };
    let p = free.len();
    let n = DMatrix::from_row_slice(p, p, &normal.jtj);
    let invert = |m: DMatrix<f64>| match m.cholesky() {
        Some(ch) => super::inverse::cholesky_inverse(&ch),
        None => DMatrix::from_element(p, p, f64::INFINITY),
    };
    let cov = match &weights.prior {
        // The stated tolerances are absolute: σ̂ rescales the data's
        // information, not the prior's — (N_data/σ̂² + P)⁻¹. Scaling the
        // whole σ̂²·N⁻¹ made a parameter the prior holds (data share 5 %)
        // 30 % more certain than its tolerance under a robust scale of 0.68.
        Some(term) if sigma0.is_finite() && sigma0 > 0.0 => {
            let mut m = n / (sigma0 * sigma0);
            for (a, &c) in free.iter().enumerate() {
                if let Some(s) = term.sigma(c) {
                    m[(a, a)] += (1.0 - 1.0 / (sigma0 * sigma0)) / (s * s);
                }
            }
            invert(m)
        }
        _ => invert(n) * (sigma0 * sigma0),
    };
    let prior = match (&model.prior, &weights.prior) {
        (Some(t), Some(term)) => Some(super::PriorReport::new(
            t,
            term,
            &params.to_vec(),
            &free,
            &cov,
            start,
        )),
        _ => None,
    };
    let ids: Vec<ParamId> = start.param_ids().collect();
    for j in &mut params.joints {
        j.theta = wrap(j.theta);
        j.alpha = wrap(j.alpha);
    }
    let parameters = ids
        .iter()
        .enumerate()
        .map(|(c, &id)| {
            let (nominal, calibrated) = (start.get(id), params.get(id));
            let correction = if matches!(
                id.kind,
                ParamKind::Theta | ParamKind::Alpha | ParamKind::Beta
            ) {
                wrap(calibrated - nominal)
            } else {
                calibrated - nominal
            };
            let sigma = free
                .iter()
                .position(|&f| f == c)
                .map(|a| cov[(a, a)].max(0.0).sqrt());
            Estimate {
                id,
                nominal,
                calibrated,
                correction,
                sigma: sigma.filter(|s| s.is_finite()),
                fixed: reasons
                    .iter()
                    .find(|(r, _)| *r == id)
                    .map(|(_, why)| why.clone()),
            }
        })
        .collect();
    let rho = (0..p)
        .map(|a| {
            (0..p)
                .map(|b| {
                    let r = cov[(a, b)] / (cov[(a, a)] * cov[(b, b)]).sqrt();
                    if r.is_finite() { r } else { 0.0 }
                })
                .collect()
        })
        .collect();
    // Suspect touches: residuals in units of their own σ — the stated
    // noise, or (estimated) the fit's σ̂.
    let mut t2 =
        crate::residuals::standardised_residuals(&ArmKernel::new(&params)?, data, &weights)?;
    if let Some((_, w)) = &robust {
        // In units of the touch's own σ, not of its robust weight.
        t2.iter_mut().zip(w).for_each(|(t, w)| *t /= w);
    }
    if !stated {
        // σ from the touches themselves, robustly: the median of a χ²₃
        // variable is 2.366, and a few outliers do not move a median.
        let mut sorted = t2.clone();
        sorted.sort_by(f64::total_cmp);
        let median = sorted.get(sorted.len() / 2).copied().unwrap_or(1.0);
        let s2 = (median / 2.366).max(f64::MIN_POSITIVE);
        t2.iter_mut().for_each(|v| *v /= s2);
    }
    let (outlier_threshold, outliers) = super::checks::outliers(data, &t2);
    let position_uncertainty = position_uncertainty(&params, data, &free, &cov, touch_sigma)?;
    let names: Vec<String> = ids.iter().map(ParamId::to_string).collect();
    let cost_evaluations = extra_costs + phases.iter().map(|p| p.cost_evaluations).sum::<usize>();
    let jacobian_evaluations =
        extra_jacobians + phases.iter().map(|p| p.jacobian_evaluations).sum::<usize>();
    Ok(Calibration {
        parameters,
        correlations: strong_correlations(&cov, &free, &names),
        correlation_matrix: CorrelationMatrix {
            parameters: free.iter().map(|&c| ids[c]).collect(),
            rho,
        },
        dof: Dof {
            touch_rows: counts.touch_rows,
            length_rows: counts.length_rows,
            free_parameters: p,
            centre_coordinates: counts.centre_coordinates,
            degrees_of_freedom,
            sigma0,
            touch_sigma_mm: touch_sigma,
            touch_sigma_estimated: !stated,
            prior_rows: counts.prior_rows,
        },
        solver: SolverSummary {
            method,
            stop,
            successful: stop.is_solution_usable(),
            iterations,
            cost_evaluations,
            jacobian_evaluations,
            initial_cost,
            final_cost: normal.cost(),
            history,
            options: lm,
            phases,
            anneal,
            global,
        },
        identification,
        checks: Checks {
            gross_corrections: gross_corrections(&params, start, &free),
            // A robust fit's weighted cost has no χ² law: its scale is
            // tested instead (`robust`).
            chi_square: (stated && robust.is_none())
                .then(|| ChiSquare::new(normal.cost(), degrees_of_freedom)),
            outliers,
            outlier_threshold,
            position_uncertainty,
        },
        params,
        robust: robust.map(|(fit, _)| fit),
        prior,
    })
}

/// The predicted position uncertainty of `params` (k = 2) over the poses of
/// `data` (an even sample of at most [`super::checks::UNCERTAINTY_POSES`]),
/// from the free parameters' covariance `cov`.
fn position_uncertainty(
    params: &DhParams,
    data: &DataSet,
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
    if step == 1 {
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
        k: K,
        poses: n,
        rms_mm: (sum / n as f64).sqrt(),
        max_mm: max,
        touch_mm: K * 3f64.sqrt() * touch_sigma,
    }))
}

/// Coverage factor of the predicted position uncertainty.
const K: f64 = 2.0;

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
    /// `n` poses' uncertainties (k = [`K`]) into the sums.
    #[inline(always)]
    fn add(&mut self, l: usize, jac: &[[f64; 3]], n: Option<usize>) {
        let (jf, q) = (&mut self.jf, self.free.len());
        for (a, &ca) in self.free.iter().enumerate() {
            for k in 0..3 {
                jf[a][k][l] = jac[ca][k];
            }
        }
        let Some(n) = n else { return };
        let mut tr = [0.0; LANES];
        for a in 0..q {
            let (ja, row) = (&jf[a], &self.c[a * q..(a + 1) * q]);
            for (jb, &cab) in jf.iter().zip(row) {
                for l in 0..LANES {
                    let jj = ja[0][l] * jb[0][l] + ja[1][l] * jb[1][l] + ja[2][l] * jb[2][l];
                    tr[l] += cab * jj;
                }
            }
        }
        for &t in &tr[..n] {
            let u = K * t.max(0.0).sqrt();
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
            let mut tr = 0.0;
            for (a, &ca) in free.iter().enumerate() {
                for (b, &cb) in free.iter().enumerate() {
                    let jj: f64 = (0..3).map(|k| jac[ca][k] * jac[cb][k]).sum();
                    tr += cov[(a, b)] * jj;
                }
            }
            let u = 2.0 * f64::max(tr, 0.0).sqrt();
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
            let u = position_uncertainty(&params, &data, &free, &cov, 0.01)
                .unwrap()
                .unwrap();
            let (n, rms, max) = one_at_a_time(&params, &data, &free, &cov);
            assert_eq!(u.poses, n, "{touches} touches");
            assert_eq!(u.rms_mm.to_bits(), rms.to_bits(), "{touches} touches");
            assert_eq!(u.max_mm.to_bits(), max.to_bits(), "{touches} touches");
        }
    }
}
