//! Prior knowledge of the arm: stated tolerances of the nominal geometry,
//! entering the least squares as whitened pseudo-observations (a maximum a
//! posteriori fit).
//!
//! A tolerance `σ_k` (1σ, what the manufacturer knows from machining and
//! assembly) on a FREE parameter adds the residual `r_k = (p_k − p0_k)/σ_k`,
//! `p0` the nominal (start) arm's value, angles wrapped to ±π:
//!
//! ```text
//! JᵀJ += diag(1/σ²)      Jᵀr += (p − p0)/σ²      cost += Σ r_k²
//! ```
//!
//! Each such row counts in the degrees of freedom (`m + prior rows − p`), so
//! χ² and σ̂ stay honest, and the covariance comes from the augmented normal
//! matrix. A direction the data barely see is then held near nominal by its
//! tolerance instead of absorbing noise; a well-determined one hardly moves
//! (its data information dwarfs `1/σ²`).
//!
//! Where the prior acts: every Levenberg–Marquardt fit (hence `lm`, the
//! final LM of `hybrid` and `global`, and `global`'s comparison of minima,
//! which are LM costs), the covariance and the degrees of freedom. The
//! annealer's energy ignores it (the annealer only finds a start; its LM
//! polish, and a `sa` result's covariance, include it).
//!
//! `fix = auto` is decided on the data alone: parameters the data can never
//! determine (base motion, the redundant last link, scale without a length)
//! stay fixed — a prior would only split a data-determined sum between them
//! by their tolerances; weak but identifiable directions were already free
//! and are now regularised by the prior.
//!
//! Tolerances are given per class, per kind or per parameter
//! ([`Tolerances`]); the most specific applies.

use serde::{Deserialize, Serialize};

use crate::params::{DhParams, ParamId};
use crate::residuals::{PriorTerm, Term};
use crate::tolerances::Tolerances;

/// One parameter's prior and what the data made of it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PriorEstimate {
    /// Parameter name (`a1`, `theta5`, `Bz`).
    pub name: String,
    /// `mm` or `deg`.
    pub unit: String,
    /// The stated tolerance (1σ).
    pub tolerance: f64,
    /// Posterior standard uncertainty, `unit`: the parameter's σ of the
    /// result, from the augmented normal matrix with the data's part scaled
    /// by σ̂² and the prior's not; 0 (and `data_share` 0) when that matrix
    /// is singular (never NaN).
    pub posterior_sigma: f64,
    /// The data's share of the information: `1 − posterior variance /
    /// prior variance` (1 = the data alone determine it, 0 = the prior
    /// alone).
    pub data_share: f64,
    /// `(calibrated − nominal) / tolerance`: how far the data moved it, in
    /// tolerances.
    pub(crate) shift: f64,
}

/// A stated tolerance of a parameter `fix = auto` holds as redundant,
/// carried onto a free partner: the data see only their sum, so the sum's
/// tolerance is the partner's own and the carried one in quadrature.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CarriedTolerance {
    /// The fixed, redundant parameter (`theta5`).
    pub from: String,
    /// The free partner that carries it (`a5`).
    pub to: String,
    /// The partner's unit (`mm`, `deg`).
    pub unit: String,
    /// The redundant parameter's tolerance as it moves the partner:
    /// `|k| σ_from`, `k` the relation's coefficient, in `unit`.
    pub carried: f64,
    /// The partner's tolerance after carrying, in `unit`.
    pub tolerance: f64,
}

impl CarriedTolerance {
    /// In words: `a5 carries theta5: ±0.9599 mm, now ±1.0824 mm`.
    pub fn describe(&self) -> String {
        format!(
            "{} carries {}: ±{:.4} {u}, now ±{:.4} {u}",
            self.to,
            self.from,
            self.carried,
            self.tolerance,
            u = self.unit
        )
    }
}

/// Carries the tolerance of every parameter the identification fixed as
/// redundant onto the free partners of its relation (`∂p/∂from = Σ k
/// ∂p/∂to`: moving `from` by δ moves the probe as moving each `to` by
/// `k δ`), in quadrature; a partner without a tolerance of its own stays
/// without one. Replaces the objective's prior; what was carried, in the
/// order of the relations.
pub(crate) fn carry_redundant(
    objective: &mut crate::objective::Objective<'_>,
    identification: &crate::identify::Identification,
    arm: &DhParams,
) -> Vec<CarriedTolerance> {
    let Some(mut prior) = objective.prior().cloned() else {
        return Vec::new();
    };
    let column = |name: &str| arm.param_ids().position(|id| id.to_string() == name);
    let mut carried = Vec::new();
    for relation in &identification.null_relations {
        let Some(((from, _), partners)) = relation.terms.split_first() else {
            continue;
        };
        let Some(sigma) = column(from).and_then(|c| prior.sigma(c)) else {
            continue;
        };
        for (to, k) in partners {
            let Some(c) = column(to) else { continue };
            let extra = k.abs() * sigma;
            if let Some(now) = prior.carry(c, extra) {
                let Some(id) = arm.param_id(c) else { continue };
                carried.push(CarriedTolerance {
                    from: from.clone(),
                    to: to.clone(),
                    unit: id.unit().to_string(),
                    carried: id.to_user(extra),
                    tolerance: id.to_user(now),
                });
            }
        }
    }
    if !carried.is_empty() {
        objective.set_prior(prior);
    }
    carried
}

/// The prior of a calibration, as reported.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PriorReport {
    /// The tolerances as given, in words.
    pub tolerances: String,
    /// Pseudo-observation rows (free parameters with a tolerance).
    pub rows: usize,
    /// `Σ r_k²` of the prior at the result.
    pub cost: f64,
    /// Per free parameter with a tolerance, in the fixed order.
    pub parameters: Vec<PriorEstimate>,
    /// Tolerances of redundant fixed parameters carried onto their free
    /// partners (absent when none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub carried: Vec<CarriedTolerance>,
}

impl PriorReport {
    /// The report of `prior` at the result `x`, from the covariance of the
    /// free parameters (`inverse`, free columns `free`).
    pub(crate) fn new(
        tolerances: &Tolerances,
        prior: &PriorTerm,
        x: &[f64],
        free: &[usize],
        inverse: &nalgebra::DMatrix<f64>,
        arm: &DhParams,
        carried: Vec<CarriedTolerance>,
    ) -> PriorReport {
        let parameters = free
            .iter()
            .enumerate()
            .filter_map(|(a, &c)| {
                let s = prior.sigma(c)?;
                let id = arm.param_id(c)?;
                let var = inverse[(a, a)];
                let finite = var.is_finite() && var >= 0.0;
                Some(PriorEstimate {
                    name: id.to_string(),
                    unit: id.unit().to_string(),
                    tolerance: id.to_user(s),
                    posterior_sigma: if finite { id.to_user(var.sqrt()) } else { 0.0 },
                    data_share: if finite {
                        (1.0 - var / (s * s)).clamp(0.0, 1.0)
                    } else {
                        0.0
                    },
                    shift: prior.residual(c, x).unwrap_or(0.0),
                })
            })
            .collect();
        PriorReport {
            tolerances: tolerances.describe(arm.joint_count()),
            rows: prior.rows(free),
            cost: prior.cost(free, x),
            parameters,
            carried,
        }
    }

    /// A note when the data contradict the tolerances: the prior's cost
    /// above `rows + 3·sqrt(2·rows)` (its χ² expectation plus three
    /// standard deviations), naming the parameter moved farthest.
    pub(crate) fn conflict(&self) -> Option<String> {
        let rows = self.rows as f64;
        if self.rows == 0 || self.cost <= rows + 3.0 * (2.0 * rows).sqrt() {
            return None;
        }
        let worst = self
            .parameters
            .iter()
            .max_by(|a, b| a.shift.abs().total_cmp(&b.shift.abs()))?;
        Some(format!(
            " — more than the tolerances allow: the data move {} by {:+.1} tolerances (tolerances \
             too tight for this arm, or a nominal that is off)",
            worst.name, worst.shift
        ))
    }

    /// The entry of a parameter, by name.
    pub fn of(&self, name: &str) -> Option<&PriorEstimate> {
        self.parameters.iter().find(|p| p.name == name)
    }
}

/// What a prior does to the conditioning (`identify` with tolerances): the
/// rank and condition number of the scaled normal matrix (angles as arcs at
/// the reach, as [`crate::identify`] scales them) with and without the
/// prior's `diag(1/σ²)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PriorConditioning {
    /// The tolerances, in words.
    pub(crate) tolerances: String,
    /// Parameters with a tolerance.
    pub parameters_with_tolerance: usize,
    /// Parameters in all.
    pub parameters: usize,
    /// Identifiable combinations from the data alone (after the structural
    /// rules: [`crate::identify::Identification::rank`]).
    pub rank_without: usize,
    /// Determined combinations with the prior, all parameters (singular
    /// values above `1e-7 × s_max`, the identification's threshold).
    pub rank_with: usize,
    /// Condition number (`s_max / s_min`) over the free parameters of
    /// `fix = auto`, data alone.
    pub condition_without: f64,
    /// The same with the prior.
    pub condition_with: f64,
}

/// The rank and conditioning of `data` at `params` with and without the
/// prior `tolerances`, touches weighed from `noise` (without stated noise,
/// as a 0.01 mm touch, like [`crate::identify::identify`]: the prior's
/// weight relative to the data depends on that σ). `identification` is the
/// data's own analysis (its rank and recommended free set).
///
/// # Errors
///
/// The kernel's, for an arm it cannot evaluate or noise that overflows.
pub fn conditioning(
    params: &DhParams,
    data: &crate::dataset::DataSet,
    noise: &crate::residuals::Noise,
    tolerances: &Tolerances,
    identification: &crate::identify::Identification,
    threads: usize,
) -> Result<PriorConditioning, crate::residuals::TermError> {
    let evidence = crate::identify::Evidence { data, added: None };
    conditioning_with(params, evidence, noise, tolerances, identification, threads)
}

/// [`conditioning`] of the data and the terms `evidence` adds (points on
/// spheres, their own blocks eliminated).
///
/// # Errors
///
/// As [`conditioning`]; the terms' refusals.
pub(crate) fn conditioning_with(
    params: &DhParams,
    evidence: crate::identify::Evidence<'_>,
    noise: &crate::residuals::Noise,
    tolerances: &Tolerances,
    identification: &crate::identify::Identification,
    threads: usize,
) -> Result<PriorConditioning, crate::residuals::TermError> {
    use nalgebra::DMatrix;
    let n = params.joint_count();
    let (full, _) =
        crate::identify::data_normal(params, evidence.data, noise, evidence.added, threads)?;
    let np = full.free.len();
    let reach = params.reach();
    let ids: Vec<ParamId> = params.param_ids().collect();
    let d: Vec<f64> = ids
        .iter()
        .map(|i| if i.kind.is_length() { 1.0 } else { 1.0 / reach })
        .collect();
    let sigma = tolerances.sigmas_for(params);
    let scaled = |cols: &[usize], with: bool| {
        DMatrix::from_fn(cols.len(), cols.len(), |a, b| {
            let (ca, cb) = (cols[a], cols[b]);
            let mut v = full.jtj[ca * np + cb];
            if with && ca == cb {
                v += sigma[ca].map_or(0.0, |s| 1.0 / (s * s));
            }
            v * d[ca] * d[cb]
        })
    };
    let singular = |m: DMatrix<f64>| -> Vec<f64> {
        if !m.iter().all(|v| v.is_finite()) {
            return vec![0.0; m.nrows()];
        }
        let mut s: Vec<f64> = m
            .symmetric_eigenvalues()
            .iter()
            .map(|e| e.max(0.0).sqrt())
            .collect();
        s.sort_by(|a, b| b.total_cmp(a));
        s
    };
    let condition = |s: &[f64]| {
        let (max, min) = (
            s.first().copied().unwrap_or(0.0),
            s.last().copied().unwrap_or(0.0),
        );
        if min > 0.0 { max / min } else { f64::INFINITY }
    };
    let all: Vec<usize> = (0..np).collect();
    let with_all = singular(scaled(&all, true));
    let smax = with_all.first().copied().unwrap_or(0.0);
    let rank_with = with_all
        .iter()
        .filter(|&&s| s > crate::identify::RANK_TOLERANCE * smax)
        .count();
    let free = identification.free_columns();
    Ok(PriorConditioning {
        tolerances: tolerances.describe(n),
        parameters_with_tolerance: sigma.iter().filter(|s| s.is_some()).count(),
        parameters: np,
        rank_without: identification.rank,
        rank_with,
        condition_without: condition(&singular(scaled(&free, false))),
        condition_with: condition(&singular(scaled(&free, true))),
    })
}
