//! Robust fitting: iteratively reweighted least squares (IRLS) after any
//! solver, so that a few bad touches (a mislabelled socket, a probe that
//! slipped) do not pull the arm.
//!
//! Every touch `i` gets a scalar weight `w_i ∈ (0, 1]` that multiplies its
//! weight matrix `A_i`. One IRLS pass: at the current arm, each touch's
//! standardised residual `u_i = sqrt(rᵢᵀ A_i rᵢ / (1 − h_i))` (the
//! leverage-corrected residual of [`crate::calibrate::checks`], in units of
//! the touch's own σ); the robust scale `σ̂` of those residuals (below); the
//! weights `w_i = ψ(z_i)/z_i` of the loss at `z_i = u_i/σ̂`; LM refits under
//! them. Passes repeat until no weight moves by more than
//! 0.001 (at most 30 refits). Deterministic: no
//! random draw, and the normal equations are the same bits on any thread
//! count.
//!
//! - **Scale** `σ̂`: `σ̂² = median(u_i²) / 2.366`, the median of the
//!   squared standardised residuals over the median of `χ²₃` (2.366) — the
//!   analogue, for a 3-D residual norm, of the MAD of a scalar one (which
//!   is `χ₁`-based). The leverage `h_i` is the full one (the point's centre
//!   and the free parameters, [`crate::objective::Objective::standardised`]
//!   with the last refit's normal matrix), so each `u_i²` is about `χ²₃`
//!   with no global dof factor. A few outliers do not move a median;
//!   `σ̂ ≈ 1` when the weights (the stated noise) are right.
//! - **Observations of any row count**: a term's observation of `k` rows
//!   (a distance is one, a pose six) has `u² ≈ χ²_k`. Its loss is on its
//!   own `k`-dimensional norm (`z = u/σ̂`); the scale's median takes each
//!   `u²` in a touch's units (times `m₃/m_k`, `m_k` the median of `χ²_k`),
//!   the median test uses the mean density of those laws, the sandwich's
//!   terms are `ψ²/k` and `((k − 1)w + ψ')/k`, and the outlier test holds
//!   each against the `χ²_k` quantile. The default constants are tuned for
//!   `k = 3`; all-touch campaigns give the same bits as before.
//! - **Losses**: Huber, `w = min(1, k/z)`; Cauchy, `w = 1/(1 + (z/k)²)`.
//!   The usual constants 1.345 and 2.385 give 95 % efficiency under
//!   Gaussian noise for a *scalar* residual; on a 3-D residual norm they
//!   give 92.6 % and 93.7 %, and the same 95 % needs `k` = 1.62 (Huber)
//!   and 2.65 (Cauchy): those are the defaults ([`Loss::default_k`]; a
//!   test checks the efficiency by quadrature).
//! - **Uncertainty**: a sandwich. The refits solve `Σ J̃_iᵀ A_i^½ ψ(z_i)
//!   e_i/z_i = 0`, `e_i = A_i^½ r_i/σ̂` the whitened residual, `z_i = |e_i|`
//!   (and `J̃_i` the touch's Jacobian with its point's centre profiled out).
//!   Its score's variance is `M = Σ J̃ᵀ A^½ E[ψ² ûûᵀ] A^½ J̃` (`û = e/z`)
//!   and its derivative `B = Σ J̃ᵀ A^½ E[w (I − ûûᵀ) + ψ' ûûᵀ] A^½ J̃`
//!   (`w = ψ/z`: a tangential move of `e` is weighed `w`, a radial one
//!   `ψ'`). Under noise that is Gaussian in the whitened coordinates the
//!   direction `û` is uniform and independent of `z`, so `E[ûûᵀ] = I/3`:
//!   `M = Σ (ψ_i²/3) J̃ᵀ A J̃` and `B = Σ b_i J̃ᵀ A J̃` with the curvature
//!   weight `b = (2w + ψ')/3` — the 3-D norm's version of Huber's
//!   `E[ψ²]/E[ψ']²` (`1/b` is not `1/w`: a Huber touch beyond `k` has
//!   `b = 2w/3`). The covariance is `σ̂² B⁻¹ M B⁻¹`; with the one-ratio
//!   approximation `M ≈ κ B`, `κ = Σ ψ_i²/3 / Σ b_i` (both sums over the
//!   touches at the end, outliers included: a Huber outlier adds `k²/3` to
//!   the score's variance, a Cauchy one almost nothing), it is
//!   `σ̂² κ (J̃ᵀ B J̃)⁻¹` — the normal matrix under the weights `b` (whose
//!   point centres are the ones `B`'s profiling needs). Gaussian noise
//!   alone gives `σ̂² N⁻¹ / efficiency` (1.05 at the default `k`). That is
//!   the asymptotic law; with few residual rows per unknown, Huber's
//!   small-sample factor `K² = (1 + (p/n) var(b)/E[b]²)²` multiplies it
//!   (`p/n` here the free parameters and point centres per residual row of
//!   the touches; `var(b)/E[b]² ≈ 0.1` under Gaussian noise, so `K²` is
//!   1.04 for 10 sockets × 10 touches, 1.08 for 6 × 6). The
//!   IRLS covariance `σ̂² (Jᵀ W J)⁻¹` used before had neither `κ` nor
//!   `K²`, and weighed by `w`: over 200 simulated campaigns of 6 sockets ×
//!   6 touches with 2 gross outliers each (`core/tests/honest.rs`) the
//!   RMS of its normalised errors `(p̂ − p)/σ` was 1.09 (Huber) and 0.95
//!   (Cauchy) — the two losses off in opposite directions, each near 1
//!   only through a dof factor on `σ̂²` (1.30 there) that the full
//!   leverage now replaces; the sandwich's are 1.04 and 1.03.
//! - **Fit quality**: the weighted cost has no `χ²` distribution, so the
//!   `χ²` test is replaced by a test of the robust scale against the stated
//!   noise: the sample median of `u²` is asymptotically normal about 2.366
//!   with standard deviation `1/(2 f₃(2.366) √n)` (`f₃` the `χ²₃` density),
//!   both tails, the same significance levels as the `χ²` test. It does not
//!   count the outliers against the fit: a robust fit of a campaign with a
//!   few bad touches is not called a poor fit.
//!
//! The global search compares its starts by plain least squares, but with
//! stated noise judges a start whose plain cost misses the noise floor by
//! its robust refit ([`super::global`]): a gross touch would otherwise keep
//! every start off the floor and lead the search to a wrong minimum that
//! the refits after it keep. With `sa` (annealing alone) the robust
//! refits are LM all the same (phase `lm, robust …`), and the stop says
//! so: annealing, then LM.

use serde::{Deserialize, Serialize};

use super::checks::{CHI_SQUARE_REFUSE, ChiSquareVerdict};
use super::lm::{LmOptions, LmResult, levenberg_marquardt};
use super::{CalibrationError, OptionError, Phase};
use crate::objective::Objective;
use crate::residuals::{Normal, ParameterLeverage};
use crate::setting::Setting;

/// IRLS stops when no touch's weight moved by more than this.
pub(crate) const WEIGHT_TOLERANCE: f64 = 1e-3;
/// Most robust refits.
pub(crate) const MAX_PASSES: usize = 30;
/// Touches below this weight are listed as downweighted in summaries: a
/// touch the noise explains falls below it with probability about 1e-4
/// (Cauchy, `z > √3·k`) or 4e-9 (Huber, `z > 4k`) at the default `k`.
pub const DOWNWEIGHTED: f64 = 0.25;
/// The smallest weight a touch gets (so that its matrix stays invertible
/// in sums; a Cauchy weight of a touch thousands of σ off would underflow).
pub(crate) const MIN_WEIGHT: f64 = 1e-9;
use crate::objective::{Observed, RowCounts};
use crate::stats::CHI2_3_MEDIAN;

/// The loss of a robust fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Loss {
    /// Huber: quadratic up to `k`, linear beyond (`w = min(1, k/z)`).
    Huber,
    /// Cauchy: `w = 1/(1 + (z/k)²)`; far outliers weigh almost nothing.
    Cauchy,
}

impl Loss {
    /// Both losses.
    pub const ALL: [Loss; 2] = [Loss::Huber, Loss::Cauchy];

    /// The name used on the command line and in reports.
    ///
    /// ```
    /// use aacmm_core::calibrate::robust::Loss;
    /// assert_eq!(Loss::parse("cauchy"), Some(Loss::Cauchy));
    /// assert_eq!(Loss::Huber.name(), "huber");
    /// assert_eq!(Loss::parse("bogus"), None);
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Loss::Huber => "huber",
            Loss::Cauchy => "cauchy",
        }
    }

    /// The loss of a name.
    pub fn parse(s: &str) -> Option<Loss> {
        Loss::ALL.into_iter().find(|l| l.name() == s)
    }

    /// The default tuning constant: 95 % efficiency under Gaussian noise on
    /// the 3-D standardised residual norm (1.62 Huber, 2.65 Cauchy; see the
    /// module documentation).
    pub fn default_k(self) -> f64 {
        match self {
            Loss::Huber => 1.62,
            Loss::Cauchy => 2.65,
        }
    }

    /// The weight `ψ(z)/z` at the scaled residual norm `z ≥ 0`, tuning
    /// constant `k`, at least 1e-9.
    ///
    /// ```
    /// use aacmm_core::calibrate::robust::Loss;
    /// assert_eq!(Loss::Huber.weight(1.0, 1.62), 1.0);
    /// assert!((Loss::Huber.weight(3.24, 1.62) - 0.5).abs() < 1e-12);
    /// assert!((Loss::Cauchy.weight(2.65, 2.65) - 0.5).abs() < 1e-12);
    /// ```
    pub fn weight(self, z: f64, k: f64) -> f64 {
        let w = match self {
            Loss::Huber => {
                if z <= k {
                    1.0
                } else {
                    k / z
                }
            }
            Loss::Cauchy => 1.0 / (1.0 + (z / k) * (z / k)),
        };
        if w.is_nan() {
            MIN_WEIGHT
        } else {
            w.max(MIN_WEIGHT)
        }
    }
}

impl Loss {
    /// `ψ'(z)`, the slope of `ψ(z) = z·w(z)` (the radial weight).
    fn slope(self, z: f64, k: f64) -> f64 {
        match self {
            Loss::Huber => {
                if z <= k {
                    1.0
                } else {
                    0.0
                }
            }
            Loss::Cauchy => {
                let t2 = (z / k) * (z / k);
                (1.0 - t2) / ((1.0 + t2) * (1.0 + t2))
            }
        }
    }

    /// The sandwich's terms of an observation of `rows` rows at `z`:
    /// `ψ²/d` (its score's variance) and the curvature weight
    /// `b = ((d − 1)w + ψ')/d`, `d = rows` (module documentation: a touch's
    /// `d` is 3); 0 and the smallest weight for a `z` not a number.
    pub(crate) fn sandwich_terms(self, z: f64, k: f64, rows: usize) -> (f64, f64) {
        let d = rows.max(1) as f64;
        if !z.is_finite() {
            return (if z.is_nan() { 0.0 } else { k * k / d }, MIN_WEIGHT);
        }
        let w = self.weight(z, k);
        let psi = z * w;
        let b = ((d - 1.0) * w + self.slope(z, k)) / d;
        (psi * psi / d, b.max(MIN_WEIGHT))
    }
}

/// A robust fit's settings: the loss and its tuning constant `k` (in units
/// of the robust scale of the standardised 3-D residual norm).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Robust {
    /// The loss.
    pub loss: Loss,
    /// The tuning constant `k` (> 0).
    pub scale_k: f64,
}

impl Robust {
    /// `loss` with its default constant ([`Loss::default_k`]).
    pub fn new(loss: Loss) -> Robust {
        Robust {
            loss,
            scale_k: loss.default_k(),
        }
    }

    /// `Ok` when `scale_k` is finite and positive (refused as
    /// `robust.scale_k`).
    ///
    /// ```
    /// use aacmm_core::calibrate::robust::{Loss, Robust};
    /// let e = Robust { loss: Loss::Huber, scale_k: -1.0 }.check().unwrap_err();
    /// assert_eq!(e.field(), "robust.scale_k");
    /// ```
    pub fn check(&self) -> Result<(), OptionError> {
        crate::error::check_nonnegative(Setting::RobustScale, self.scale_k, false)
    }
}

/// One touch's weight in a robust fit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TouchWeight {
    /// Where it was read: `file:line`.
    pub at: String,
    /// Its point's label.
    pub point: String,
    /// Its weight in (0, 1]: 1 for a touch the noise explains.
    pub weight: f64,
}

/// What a robust fit did, in `calibration.json` (only when one ran).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobustFit {
    /// The loss.
    pub loss: Loss,
    /// Its tuning constant `k`.
    pub scale_k: f64,
    /// The robust scale `σ̂` of the standardised residuals at the end (1
    /// when the weights, i.e. the stated noise, are right): the parameters'
    /// σ are scaled by it.
    pub scale: f64,
    /// The sandwich's factor `κ K²`, `κ = Σ ψ²/3 / Σ b` and `K²` Huber's
    /// small-sample factor (module documentation): the parameters'
    /// covariance is `σ̂² κ K² (J̃ᵀ B J̃)⁻¹`.
    #[serde(default = "one")]
    pub sandwich: f64,
    /// Refits (IRLS passes).
    pub passes: usize,
    /// Whether the weights settled (no change above 0.001) within 30
    /// passes.
    pub converged: bool,
    /// `P(median ≥ observed)` of the squared standardised residuals under
    /// the stated noise (`None` without stated noise).
    pub p_upper: Option<f64>,
    /// `P(median ≤ observed)` (`None` without stated noise).
    pub p_lower: Option<f64>,
    /// The verdict of that test (`None` without stated noise).
    pub verdict: Option<ChiSquareVerdict>,
    /// Every touch's weight, in the data set's order (grouped by point).
    pub weights: Vec<TouchWeight>,
}

impl RobustFit {
    /// The touches weighed below [`DOWNWEIGHTED`], lowest first.
    pub fn downweighted(&self) -> Vec<&TouchWeight> {
        let mut v: Vec<&TouchWeight> = self
            .weights
            .iter()
            .filter(|t| t.weight < DOWNWEIGHTED)
            .collect();
        v.sort_by(|a, b| a.weight.total_cmp(&b.weight));
        v
    }

    /// Whether the scale test is far outside the stated noise (either
    /// tail), as [`super::checks::ChiSquare::far_outside`].
    pub(crate) fn far_outside(&self) -> bool {
        self.p_upper.is_some_and(|p| p < CHI_SQUARE_REFUSE)
            || self.p_lower.is_some_and(|p| p < CHI_SQUARE_REFUSE)
    }

    /// The scale test in words (`None` without stated noise).
    pub(crate) fn describe_scale(&self) -> Option<String> {
        let (v, up, lo) = (self.verdict?, self.p_upper?, self.p_lower?);
        let head = format!(
            "robust {} fit, scale {:.3} of the stated noise (median test, P above {:.3}, below \
             {:.3})",
            self.loss.name(),
            self.scale,
            up,
            lo
        );
        // Below the note level but not the refusal level: said to be a
        // note in the same sentence (the verdict stays usable).
        let note = if self.far_outside() {
            String::new()
        } else {
            format!(
                " — a note, not a refusal (a tail below {} but above the refusal level {:e}: \
                 the fit is usable)",
                super::checks::CHI_SQUARE_ALPHA,
                CHI_SQUARE_REFUSE
            )
        };
        Some(match v {
            ChiSquareVerdict::Consistent => format!("{head}: consistent with the stated noise"),
            ChiSquareVerdict::ResidualsTooLarge => format!(
                "{head}: most residuals larger than the stated noise explains{note}: noise \
                 understated or a model error"
            ),
            ChiSquareVerdict::ResidualsTooSmall => format!(
                "{head}: residuals smaller than the stated noise explains{note}: the noise is \
                 overstated (the uncertainties printed are rescaled by the robust scale)"
            ),
        })
    }
}

fn one() -> f64 {
    1.0
}

/// The median of `v` (upper median for an even count); 0 when empty.
fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    let m = s.len() / 2;
    crate::stats::kth_smallest(&mut s, m).unwrap_or(0.0)
}

/// The robust fit's result, for [`super::assess`].
pub(crate) struct Irls<'a> {
    /// Every column at the end.
    pub(crate) x: Vec<f64>,
    /// The objective of the last refit (base weights × robust weights).
    pub(crate) objective: Objective<'a>,
    /// The robust weights per touch.
    pub(crate) touch_weights: Vec<f64>,
    /// The last refit.
    pub(crate) last: LmResult,
    /// All refits' work.
    pub(crate) phase: Phase,
    /// The report.
    pub(crate) fit: RobustFit,
    /// Rows per observation (what law each standardised residual has).
    rows: RowCounts,
    /// The normal equations under the curvature weights `b`: the
    /// sandwich's `J̃ᵀ B J̃`.
    pub(crate) curvature: Normal,
}

/// Squared standardised residuals in units of the base weights' σ (the
/// full leverage under the robust weights `w`, which is what the fit used:
/// `normal` is the fit's normal equations at them).
fn base_standardised(
    x: &[f64],
    base: &Objective<'_>,
    w: &[f64],
    normal: &Normal,
) -> Result<Observed, CalibrationError> {
    let leverage = ParameterLeverage::of(normal, 1.0);
    let mut t2 = (base.with_observation_weights(w)).standardised(x, leverage.as_ref())?;
    t2.values.iter_mut().zip(w).for_each(|(t, w)| *t /= w);
    Ok(t2)
}

/// `σ̂²` of the standardised residuals: their median in a three-row
/// observation's units over the median of `χ²₃` (module documentation).
fn scale_of(u2: &Observed) -> f64 {
    (median(&u2.as_three_rows()) / CHI2_3_MEDIAN).max(f64::MIN_POSITIVE)
}

/// IRLS from `x` (the solver's minimum under `base`, whose normal
/// equations there are `normal`). `stated`: whether the base weights come
/// from a stated noise (then the scale is tested); `ratio`, the unknowns
/// per residual row (Huber's `p/n`, for the covariance's small-sample
/// factor).
pub(crate) fn irls<'a>(
    robust: Robust,
    x: &[f64],
    (base, normal): (&Objective<'a>, &Normal),
    free: &[usize],
    lm: &LmOptions,
    (stated, ratio): (bool, f64),
) -> Result<Irls<'a>, CalibrationError> {
    let timer = std::time::Instant::now();
    let n = base.observations();
    // Each observation's loss on its own k-dimensional norm.
    let weights_of = |u2: &Observed, s2: f64| -> Vec<f64> {
        (u2.values.iter())
            .map(|&q| robust.loss.weight((q.max(0.0) / s2).sqrt(), robust.scale_k))
            .collect()
    };
    let mut phase = Phase::new(&format!("lm, robust {}", robust.loss.name()));
    let mut w = vec![1.0; n];
    let mut x = x.to_vec();
    let mut last: Option<LmResult> = None;
    let mut passes = 0;
    let mut converged = false;
    loop {
        let at = last.as_ref().map_or(normal, |l| &l.normal);
        let u2 = base_standardised(&x, base, &w, at)?;
        let next = weights_of(&u2, scale_of(&u2));
        let change = next
            .iter()
            .zip(&w)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        if last.is_some() && change <= WEIGHT_TOLERANCE {
            converged = true;
            break;
        }
        if passes == MAX_PASSES {
            break;
        }
        w = next;
        let fit = levenberg_marquardt(&base.with_observation_weights(&w), &x, free, lm)?;
        phase.add_lm(&fit, 0.0);
        passes += 1;
        x.clone_from(&fit.x);
        last = Some(fit);
    }
    phase.seconds = timer.elapsed().as_secs_f64();
    let last = last.expect("at least one refit ran");
    // The scale at the end, under the weights the last refit used.
    let u2 = base_standardised(&x, base, &w, &last.normal)?;
    let median_u2 = median(&u2.as_three_rows());
    let scale = scale_of(&u2).sqrt();
    let (sandwich, curvature) = sandwich(robust, (&u2, scale, ratio), (&x, base, free))?;
    let (p_upper, p_lower, verdict) = if stated && n > 0 {
        // The sample median (in χ²₃'s units) against its asymptotic law.
        let z = (median_u2 - CHI2_3_MEDIAN) / median_sd(&u2.rows);
        let p_upper = crate::stats::normal_upper(z);
        let p_lower = crate::stats::normal_upper(-z);
        let verdict = ChiSquareVerdict::from_tails(p_upper, p_lower);
        (Some(p_upper), Some(p_lower), Some(verdict))
    } else {
        (None, None, None)
    };
    let weights = (0..n)
        .map(|i| {
            let origin = base.origin(i);
            TouchWeight {
                at: origin.at,
                point: origin.group,
                weight: w[i],
            }
        })
        .collect();
    Ok(Irls {
        x,
        objective: base.with_observation_weights(&w),
        touch_weights: w,
        last,
        phase,
        rows: u2.rows,
        fit: RobustFit {
            loss: robust.loss,
            scale_k: robust.scale_k,
            scale,
            sandwich,
            passes,
            converged,
            p_upper,
            p_lower,
            verdict,
            weights,
        },
        curvature,
    })
}

/// The standard deviation of the sample median of the standardised
/// residuals of observations of `rows` rows each, in a three-row
/// observation's units ([`Observed::as_three_rows`]; asymptotically normal
/// about [`CHI2_3_MEDIAN`]): `1/(2 f̄ √n)`, `f̄` the mean density there —
/// `f₃(m₃)` for touches, `f_k(m_k) m_k/m₃` for a `k`-row observation.
fn median_sd(rows: &RowCounts) -> f64 {
    let n = rows.len();
    let density = if rows.iter().all(|k| k == 3) {
        CHI2_3_MEDIAN.sqrt() * (-CHI2_3_MEDIAN / 2.0).exp() / (2.0 * std::f64::consts::PI).sqrt()
    } else {
        let at = |k: usize| {
            let m = crate::stats::chi_square_median(k);
            crate::stats::chi_square_density(m, k) * m / CHI2_3_MEDIAN
        };
        rows.iter().map(at).sum::<f64>() / n.max(1) as f64
    };
    1.0 / (2.0 * density * (n as f64).sqrt())
}

impl Irls<'_> {
    /// Whether the robust scale is within `k` standard deviations of the
    /// stated noise's (the median test's `z`): the robust counterpart of
    /// the global method's noise floor for χ² (`k` of its standard
    /// deviations).
    pub(crate) fn within_floor(&self, k: f64) -> bool {
        let n = self.rows.len();
        let scale = self.fit.scale;
        let z = (scale * scale * CHI2_3_MEDIAN - CHI2_3_MEDIAN) / median_sd(&self.rows);
        n > 0 && z.abs() <= k
    }
}

/// The sandwich's factor `κ K²` and the normal equations under the
/// curvature weights, from the squared standardised residuals `u2` at the
/// end, the robust scale and the unknowns per row (module documentation).
fn sandwich(
    robust: Robust,
    (u2, scale, ratio): (&Observed, f64, f64),
    (x, base, free): (&[f64], &Objective<'_>, &[usize]),
) -> Result<(f64, Normal), CalibrationError> {
    let (mut score, mut curve, mut curve2) = (0.0, 0.0, 0.0);
    let b: Vec<f64> = (u2.values.iter().zip(u2.rows.iter()))
        .map(|(&q, rows)| {
            let z = q.max(0.0).sqrt() / scale;
            let (psi2, b) = robust.loss.sandwich_terms(z, robust.scale_k, rows);
            score += psi2;
            curve += b;
            curve2 += b * b;
            b
        })
        .collect();
    let n = b.len().max(1) as f64;
    let kappa = if curve > 0.0 { score / curve } else { 1.0 };
    // Huber's small-sample factor K = 1 + (p/n) var(b)/E[b]².
    let (mean, mean2) = (curve / n, curve2 / n);
    let spread = if mean > 0.0 {
        ((mean2 - mean * mean) / (mean * mean)).max(0.0)
    } else {
        0.0
    };
    let k = 1.0 + ratio * spread;
    let normal = base.with_observation_weights(&b).normal(x, free)?;
    Ok((kappa * k * k, normal))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Efficiency of the radial M-estimator of a 3-D location with weight
    /// `w` under Gaussian noise, by quadrature over the χ₃ density.
    fn efficiency(loss: Loss, k: f64) -> f64 {
        let p = 3.0;
        let f = |r: f64| (2.0 / std::f64::consts::PI).sqrt() * r * r * (-r * r / 2.0).exp();
        let psi = |r: f64| r * loss.weight(r, k);
        let h = 1e-4;
        let dpsi = |r: f64| (psi(r + h) - psi((r - h).max(0.0))) / (r + h - (r - h).max(0.0));
        let (mut b, mut a) = (0.0, 0.0);
        let steps = 200_000;
        let dr = 12.0 / steps as f64;
        for s in 0..steps {
            let r = (s as f64 + 0.5) * dr;
            b += psi(r).powi(2) / p * f(r) * dr;
            a += ((1.0 - 1.0 / p) * psi(r) / r + dpsi(r) / p) * f(r) * dr;
        }
        a * a / b
    }

    #[test]
    fn default_constants_give_95_percent_efficiency_in_3d() {
        for loss in Loss::ALL {
            let e = efficiency(loss, loss.default_k());
            assert!((e - 0.95).abs() < 0.002, "{loss:?}: {e}");
        }
        // The 1-D constants fall short of it on a 3-D norm.
        assert!(efficiency(Loss::Huber, 1.345) < 0.93);
        assert!(efficiency(Loss::Cauchy, 2.385) < 0.94);
    }

    #[test]
    fn weights_lie_in_0_1_and_fall_with_the_residual() {
        for loss in Loss::ALL {
            let k = loss.default_k();
            let mut prev = 1.0;
            for z in [
                0.0,
                0.5,
                1.0,
                2.0,
                5.0,
                50.0,
                1e300,
                f64::INFINITY,
                f64::NAN,
            ] {
                let w = loss.weight(z, k);
                assert!((MIN_WEIGHT..=1.0).contains(&w), "{loss:?} {z}: {w}");
                if !z.is_nan() {
                    assert!(w <= prev);
                    prev = w;
                }
            }
        }
    }
}
