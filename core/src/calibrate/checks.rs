//! What a metrologist checks before signing off, beyond convergence: that
//! the calibrated arm is still the nominal arm's kind of geometry (not its
//! mirror image, not folded to a point, not scaled by a unit mistake), and
//! that the residuals agree with the stated noise (a χ² test, both tails).
//!
//! The cost (touch scatter about centroids, distances between centroids) is
//! the same for an arm and for its mirror image, and an arm folded to a
//! point scatters nothing: neither can be told from the right arm by the fit
//! alone. What tells them apart is the nominal geometry: after the sign
//! convention is restored (`super::global::normalize_signs`), a proper
//! calibration moves lengths by millimetres and twists by fractions of a
//! degree; a mirror twin flips the signs of link lengths or turns twists by
//! about 180°, and a collapse takes links to zero.

use serde::{Deserialize, Serialize};

use crate::params::{DhParams, JointModel, ParamId, ParamKind, wrap};

/// A length may move from nominal by this fraction of its nominal value…
pub(crate) const LENGTH_TOLERANCE: f64 = 0.25;
/// …or by this fraction of the arm's reach, whichever is larger.
pub(crate) const REACH_TOLERANCE: f64 = 0.02;
/// A twist may move from nominal by this much, degrees.
pub(crate) const TWIST_TOLERANCE_DEG: f64 = 15.0;

/// A free parameter (or a combination of the last link's) that moved
/// implausibly far from nominal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct GrossCorrection {
    /// The parameter's name, or the last link's combination
    /// (`probe radius about axis 6`, `probe height along axis 6`).
    pub name: String,
    /// `mm` or `deg`.
    pub unit: String,
    /// Nominal value, in `unit`.
    pub nominal: f64,
    /// Calibrated value, in `unit`.
    pub calibrated: f64,
    /// The largest move accepted, in `unit`.
    pub tolerance: f64,
}

impl GrossCorrection {
    /// In words.
    pub fn describe(&self) -> String {
        format!(
            "{} {:.4} → {:.4} {} (more than ±{:.4})",
            self.name, self.nominal, self.calibrated, self.unit, self.tolerance
        )
    }
}

/// The probe centre relative to the last joint's axis, in the last joint's
/// base frame: its distance from the axis and its height along it — what
/// the last zero offset cannot change. (`A_n = Rz(θ+q)·Tz(d)·Tx(a)·Rx(α)`
/// puts the probe at `Rz(θ+q)·(a + Bx, By cos α − Bz sin α, d + By sin α +
/// Bz cos α)`; a Hayati last joint, `Rz(θ+q)·Tx(a)·Rx(α)·Ry(β)`, has no `d`
/// and turns the probe by `Ry(β)` first.)
fn last_link(p: &DhParams) -> (f64, f64) {
    let j = p.joints[p.joint_count() - 1];
    let [bx, by, bz] = p.probe;
    let (bx, bz, d) = match j.model {
        JointModel::Dh => (bx, bz, j.d),
        JointModel::Hayati => {
            let (sb, cb) = j.beta.sin_cos();
            (bx * cb + bz * sb, -bx * sb + bz * cb, 0.0)
        }
    };
    let (s, c) = j.alpha.sin_cos();
    let (x, y, z) = (j.a + bx, by * c - bz * s, d + by * s + bz * c);
    (x.hypot(y), z)
}

/// The free parameters of `calibrated` (columns `free`) that moved from
/// `nominal` by more than a plausible manufacturing or assembly error:
/// lengths by more than 25 % of their value or 2 % of the reach, twists by
/// more than 15°. Zero offsets are not checked (an assembled
/// arm's may be anywhere), and neither are the last link's parameters one
/// by one: with the last zero offset unknown, the probe may turn about the
/// last axis, so its distance from that axis and its height along it are
/// checked instead. Empty for a plausible arm.
///
/// ```
/// use aacmm_core::calibrate::checks::gross_corrections;
/// use aacmm_core::params::DhParams;
/// let nominal = DhParams::paper_nominal();
/// let all: Vec<usize> = (0..27).collect();
/// let mut near = nominal.clone();
/// near.joints[2].d += 0.8;
/// assert!(gross_corrections(&near, &nominal, &all).is_empty());
/// let mut mirrored = nominal.clone();
/// mirrored.joints[2].d = -mirrored.joints[2].d; // 250 → −250 mm
/// let gross = gross_corrections(&mirrored, &nominal, &all);
/// assert_eq!(gross[0].name, "d3");
/// let mut collapsed = nominal.clone();
/// collapsed.probe[2] = 0.0; // the probe folded onto the last link
/// let names: Vec<String> = gross_corrections(&collapsed, &nominal, &all).into_iter().map(|g| g.name).collect();
/// assert_eq!(names, ["probe radius about axis 6"]);
/// ```
pub fn gross_corrections(
    calibrated: &DhParams,
    nominal: &DhParams,
    free: &[usize],
) -> Vec<GrossCorrection> {
    let n = nominal.joint_count();
    let reach = nominal.reach();
    let length_tolerance = |v0: f64| (LENGTH_TOLERANCE * v0.abs()).max(REACH_TOLERANCE * reach);
    let last = n - 1;
    let in_last_link = |id: ParamId| {
        id.kind == ParamKind::Probe
            || (id.index == last
                && matches!(
                    id.kind,
                    ParamKind::A | ParamKind::D | ParamKind::Alpha | ParamKind::Beta
                ))
    };
    let mut gross: Vec<GrossCorrection> = free
        .iter()
        .filter_map(|&c| nominal.param_id(c))
        .filter(|&id| id.kind != ParamKind::Theta && !in_last_link(id))
        .filter_map(|id| {
            let (v0, v) = (nominal.get(id), calibrated.get(id));
            let (moved, tolerance) = match id.kind {
                // A Hayati β is a twist about the link's y axis.
                ParamKind::Alpha | ParamKind::Beta => {
                    (wrap(v - v0).abs(), TWIST_TOLERANCE_DEG.to_radians())
                }
                _ => ((v - v0).abs(), length_tolerance(v0)),
            };
            (moved.is_nan() || moved > tolerance).then(|| GrossCorrection {
                name: id.to_string(),
                unit: id.unit().to_string(),
                nominal: id.to_user(v0),
                calibrated: id.to_user(v),
                tolerance: id.to_user(tolerance),
            })
        })
        .collect();
    let ((r0, h0), (r, h)) = (last_link(nominal), last_link(calibrated));
    for (what, v0, v) in [("radius about", r0, r), ("height along", h0, h)] {
        let tolerance = length_tolerance(v0);
        let moved = (v - v0).abs();
        if moved.is_nan() || moved > tolerance {
            gross.push(GrossCorrection {
                name: format!("probe {what} axis {n}"),
                unit: "mm".to_string(),
                nominal: v0,
                calibrated: v,
                tolerance,
            });
        }
    }
    gross
}

/// The χ² test of the fit under stated noise: is `Σr²` what `dof` degrees
/// of freedom of residuals at the stated noise give?
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct ChiSquare {
    /// `Σr²` (weighted cost).
    pub statistic: f64,
    /// Degrees of freedom.
    pub dof: usize,
    /// `P(χ²_dof ≥ statistic)`: small when the residuals are larger than
    /// the noise explains.
    pub p_upper: f64,
    /// `P(χ²_dof ≤ statistic)`: small when they are smaller (noise
    /// overstated).
    pub p_lower: f64,
    /// What the test says.
    pub verdict: ChiSquareVerdict,
}

/// The verdict of [`ChiSquare`], at a significance of 0.001 in each tail.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ChiSquareVerdict {
    /// The residuals agree with the stated noise.
    Consistent,
    /// Larger than the stated noise explains: noise understated, a model
    /// error, outliers, or a wrong minimum.
    ResidualsTooLarge,
    /// Smaller than the stated noise explains: the noise is overstated, so
    /// the uncertainties are too large and the fit cannot be judged.
    ResidualsTooSmall,
}

impl ChiSquareVerdict {
    /// The verdict of a two-tailed test from its tail probabilities, each
    /// tail at [`CHI_SQUARE_ALPHA`].
    pub(crate) fn from_tails(p_upper: f64, p_lower: f64) -> ChiSquareVerdict {
        if p_upper < CHI_SQUARE_ALPHA {
            ChiSquareVerdict::ResidualsTooLarge
        } else if p_lower < CHI_SQUARE_ALPHA {
            ChiSquareVerdict::ResidualsTooSmall
        } else {
            ChiSquareVerdict::Consistent
        }
    }
}

/// Significance of the χ² test in each tail.
pub(crate) const CHI_SQUARE_ALPHA: f64 = 0.001;

/// Far outside: a fit this improbable is not usable without
/// `accept_poor_fit` (both tails).
pub(crate) const CHI_SQUARE_REFUSE: f64 = 1e-9;

impl ChiSquare {
    /// The test of `statistic` on `dof` degrees of freedom.
    ///
    /// ```
    /// use aacmm_core::calibrate::checks::{ChiSquare, ChiSquareVerdict};
    /// assert_eq!(ChiSquare::new(1000.0, 1000).verdict, ChiSquareVerdict::Consistent);
    /// assert_eq!(ChiSquare::new(9000.0, 1000).verdict, ChiSquareVerdict::ResidualsTooLarge);
    /// assert_eq!(ChiSquare::new(111.0, 1000).verdict, ChiSquareVerdict::ResidualsTooSmall);
    /// let t = ChiSquare::new(1000.0, 1000);
    /// assert!((t.p_upper - 0.5).abs() < 0.02 && (t.p_lower - 0.5).abs() < 0.02);
    /// ```
    pub fn new(statistic: f64, dof: usize) -> ChiSquare {
        // Each tail exact (the regularised incomplete gamma function), so
        // that both can be compared with 1e-9.
        // A statistic that is not a number cannot agree with any noise.
        let (p_upper, p_lower) = if statistic.is_nan() {
            (0.0, 1.0)
        } else {
            (
                crate::stats::chi_square_upper(statistic, dof),
                crate::stats::chi_square_lower(statistic, dof),
            )
        };
        let verdict = ChiSquareVerdict::from_tails(p_upper, p_lower);
        ChiSquare {
            statistic,
            dof,
            p_upper,
            p_lower,
            verdict,
        }
    }

    /// Whether the fit is far outside the stated noise, in either tail.
    pub fn far_outside(&self) -> bool {
        self.p_upper < CHI_SQUARE_REFUSE || self.p_lower < CHI_SQUARE_REFUSE
    }

    /// In words. A tail below 0.001 but not below 10⁻⁹ (the refusal
    /// level, [`ChiSquare::far_outside`]) is a note, and its sentence says so — with
    /// what it suggests — so that it cannot read as a refusal beside
    /// "Verdict: usable".
    pub fn describe(&self) -> String {
        let s0 = (self.statistic / self.dof.max(1) as f64).sqrt();
        let head = format!(
            "χ² = {:.1} on {} dof (sigma0 {s0:.3})",
            self.statistic, self.dof
        );
        let note = |p: f64| {
            format!(
                "(P = {p:.1e}: below {CHI_SQUARE_ALPHA} but above the refusal level \
                 {CHI_SQUARE_REFUSE:e}, so a note, not a refusal: the fit is usable)"
            )
        };
        match self.verdict {
            ChiSquareVerdict::Consistent => format!(
                "{head}: consistent with the stated noise (P above {:.3}, below {:.3})",
                self.p_upper, self.p_lower
            ),
            ChiSquareVerdict::ResidualsTooLarge if self.far_outside() => format!(
                "{head}: residuals larger than the stated noise explains (P = {:.1e}): noise \
                 understated, outliers, a model error or a wrong minimum",
                self.p_upper
            ),
            ChiSquareVerdict::ResidualsTooLarge => format!(
                "{head}: residuals larger than the stated noise explains {}; it suggests a noise \
                 {s0:.2} times the stated, a few poor touches (see Outliers) or a small model \
                 error (tolerances too tight, an effect beyond geometry)",
                note(self.p_upper)
            ),
            ChiSquareVerdict::ResidualsTooSmall if self.far_outside() => format!(
                "{head}: residuals smaller than the stated noise explains (P = {:.1e}): the noise \
                 is overstated (the uncertainties printed are rescaled by sigma0², so they are the \
                 fit's own), or the fit follows the noise",
                self.p_lower
            ),
            ChiSquareVerdict::ResidualsTooSmall => format!(
                "{head}: residuals smaller than the stated noise explains {}; it suggests a noise \
                 {s0:.2} times the stated (the uncertainties printed are rescaled by sigma0², so \
                 they are the fit's own)",
                note(self.p_lower)
            ),
        }
    }
}

/// A touch (or other observation) whose residual the noise model does not
/// explain.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct Outlier {
    /// Where it was read: `file:line`.
    pub at: String,
    /// Its point's label.
    pub point: String,
    /// Its standardised residual (`sqrt` of the leverage-corrected
    /// `rᵀ A r`, in units of its own σ).
    pub standardised: f64,
    /// What it is when neither a touch nor a reference position (the rows
    /// of a `file:line` that are): `orientation` for the tool orientation
    /// of a position's row, `sphere point` for a point probed on a
    /// sphere, a term's name for any other evidence; absent for touches
    /// and positions.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kind: Option<String>,
}

impl Outlier {
    /// What it is, in words: a `touch` or `position` (by `noun`, the data's
    /// own word), or its kind.
    pub(crate) fn noun<'a>(&'a self, noun: &'a str) -> &'a str {
        self.kind.as_deref().unwrap_or(noun)
    }
}

/// How a plain fit's outlier list was screened: after a gross error (a
/// touch labelled with the wrong point) the plain fit is pulled, and the
/// touches beyond the threshold are many — often all of them. A robust
/// refit from the plain minimum ([`super::robust`], Cauchy, used for
/// nothing else) weighs the culprits down and not the touches they pulled:
/// the list keeps to the named touches it weighs below
/// [`super::robust::DOWNWEIGHTED`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct OutlierScreen {
    /// The robust refit's loss.
    pub(crate) loss: super::robust::Loss,
    /// Touches beyond the threshold in the plain fit, before the screen.
    pub flagged: usize,
    /// The robust refit's scale `σ̂` (in the units of the plain fit's
    /// `sigma0`): far below `sigma0` when the touches it weighs down are
    /// what made the plain fit's residuals large; about `sigma0` when
    /// every residual is large (a wrong minimum, a wrong model).
    pub scale: f64,
}

impl OutlierScreen {
    /// Whether the touches the screen weighs down explain the plain fit's
    /// misfit: without them the residuals' scale is less than half the
    /// plain fit's `sigma0`.
    pub(crate) fn explains(&self, sigma0: f64) -> bool {
        self.scale.is_finite() && self.scale < sigma0 / 2.0
    }
}

/// The family-wise false-alarm rate of the outlier test: an observation
/// of `k` rows is named when its standardised squared residual exceeds the
/// `χ²_k` quantile at `1 − OUTLIER_ALPHA / observations` (Bonferroni), so a
/// campaign without outliers names one with this probability.
pub(crate) const OUTLIER_ALPHA: f64 = 0.01;

/// The observations whose standardised squared residual (`scaled`: already
/// divided by `σ0²` when the noise was estimated) exceeds the Bonferroni
/// threshold of its row count, largest first; and the threshold, in σ, of
/// the first observation's row count (the touches', when there are any).
pub(crate) fn outliers(
    objective: &crate::objective::Objective<'_>,
    scaled: &crate::objective::Observed,
) -> (f64, Vec<Outlier>) {
    let alpha = OUTLIER_ALPHA / scaled.values.len().max(1) as f64;
    // One quantile per row count present.
    let mut thresholds: Vec<(usize, f64)> = Vec::new();
    let mut threshold = |k: usize| match thresholds.iter().find(|(r, _)| *r == k) {
        Some(&(_, t)) => t,
        None => {
            let t = crate::stats::chi_square_upper_quantile(alpha, k);
            thresholds.push((k, t));
            t
        }
    };
    let first = threshold(scaled.rows.first().unwrap_or(3));
    let mut found: Vec<Outlier> = Vec::new();
    for (i, (&s, k)) in scaled.values.iter().zip(scaled.rows.iter()).enumerate() {
        if s > threshold(k) {
            let origin = objective.origin(i);
            let kind = match objective.term_of(i) {
                Some(t) if t.role() == crate::residuals::Role::Orientations => {
                    Some("orientation".to_string())
                }
                Some(t) if t.role() == crate::residuals::Role::Spheres => {
                    Some("sphere point".to_string())
                }
                Some(t) if t.role() == crate::residuals::Role::Other => Some(t.name().to_string()),
                _ => None,
            };
            found.push(Outlier {
                at: origin.at,
                point: origin.group,
                standardised: s.sqrt(),
                kind,
            });
        }
    }
    found.sort_by(|a, b| b.standardised.total_cmp(&a.standardised));
    (first.sqrt(), found)
}

/// How well the data determine the calibrated arm where it was used: the
/// predicted uncertainty of a probe position over the campaign's poses, as
/// the radius `U` that holds the position's 3-D error with 95 % probability
/// ([`crate::stats::coverage::radius`] of the eigenvalues of `J C Jᵀ`, `C`
/// the free parameters' covariance, `J` the position's parameter
/// Jacobian) — the uncertainty map's radius. The `2·sqrt(tr(J C Jᵀ))`
/// reported before was labelled `k = 2` but had no stated coverage: it is
/// `3.46 σ` (99.3 %) for an isotropic error and `2 σ` (95.4 %) for one
/// along a single direction, where the 95 % radii are `2.80 σ` and
/// `1.96 σ`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct PositionUncertainty {
    /// Probability each radius covers (0.95).
    pub coverage: f64,
    /// Poses evaluated (every touch, or an even sample of them).
    pub poses: usize,
    /// RMS of `U` over the poses, mm.
    pub rms_mm: f64,
    /// Largest `U`, mm.
    pub max_mm: f64,
    /// A single touch's own scatter at the same coverage: the 95 % radius
    /// of an isotropic 3-D error of the touch's σ per coordinate,
    /// `2.7955·σ_touch`, mm: what the arm's uncertainty is compared with.
    pub touch_mm: f64,
}

impl PositionUncertainty {
    /// Whether the arm's own uncertainty would add more than 5 % to a
    /// single measurement's scatter (`sqrt(1 + (U/T)²) > 1.05`, i.e. `U`
    /// above a third of a touch's `T`, both 95 % radii): the data, not the
    /// noise, limit the arm.
    pub(crate) fn weak(&self) -> bool {
        self.rms_mm > WEAK_FRACTION * self.touch_mm
    }

    /// In words.
    pub fn describe(&self) -> String {
        format!(
            "predicted position uncertainty of the calibrated arm over the campaign's poses \
             ({:.0} % radius in 3-D): RMS {:.4} mm, max {:.4} mm (one touch scatters ±{:.4} \
             mm)",
            100.0 * self.coverage,
            self.rms_mm,
            self.max_mm,
            self.touch_mm
        )
    }
}

/// [`PositionUncertainty::weak`]: the arm's uncertainty against a touch's
/// scatter, `sqrt(1.05² − 1)`.
pub(crate) const WEAK_FRACTION: f64 = 0.32;

/// Most poses [`PositionUncertainty`] evaluates (an even sample beyond).
pub(crate) const UNCERTAINTY_POSES: usize = 2000;

#[cfg(test)]
mod tests {
    use super::*;

    /// A Hayati last joint: its β turns the probe about the link's y axis,
    /// which the zero offset cannot undo — a 60° β that brings the probe
    /// 34 mm nearer axis 6 is gross, as halving Bz is; the nominal in Hayati
    /// form (β = 0) is not.
    #[test]
    fn a_hayati_last_joints_beta_moves_the_last_link() {
        let mut nominal = DhParams::paper_nominal();
        nominal.joints[5].model = JointModel::Hayati;
        nominal.joints[5].d = 0.0;
        let all: Vec<usize> = (0..27).collect();
        assert!(gross_corrections(&nominal, &nominal, &all).is_empty());
        let mut turned = nominal.clone();
        turned.joints[5].beta = 60f64.to_radians();
        // α6 = 90°: the probe (Bz = 100) lies 100 mm off axis 6, a6 = −35
        // beside it; Ry(60°) swings it to (86.6, 0, 50) in the last frame.
        let (r0, _) = last_link(&nominal);
        let (r, _) = last_link(&turned);
        assert!((r0 - 35f64.hypot(100.0)).abs() < 1e-9, "{r0}");
        let x = -35.0 + 100.0 * 60f64.to_radians().sin();
        assert!((r - x.hypot(50.0)).abs() < 1e-9, "{r}");
        let names: Vec<String> = gross_corrections(&turned, &nominal, &all)
            .into_iter()
            .map(|g| g.name)
            .collect();
        assert!(!names.is_empty(), "β6 = 60° passed as plausible");
        let mut lowered = nominal.clone();
        lowered.probe[2] = 50.0;
        assert!(!gross_corrections(&lowered, &nominal, &all).is_empty());
    }
}
