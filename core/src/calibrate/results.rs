//! What a calibration returns: [`Calibration`] and the records it is made
//! of — each parameter's [`Estimate`] (and its [`EstimateRecord`] in user
//! units), the auxiliary columns, the counts behind the variance factor
//! ([`Dof`]), the solver's account ([`SolverSummary`], [`Phase`]), the
//! correlations and the [`Checks`]. What it says of its frames, tools and
//! mount is in `frames.rs`, the covariances predictions need in
//! `covariance.rs`.

use serde::{Deserialize, Serialize};

use super::{
    AnnealTrace, GlobalTrace, LmIteration, LmOptions, LmResult, Method, PriorReport, RobustFit,
    Stop, checks,
};
use crate::identify::{Correlation, Identification};
use crate::params::{DhParams, JointKind, ParamId};

/// Work and time of one phase of a solver. The time is not serialised, so
/// that the same seed gives the same `calibration.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct Phase {
    /// What ran: `anneal`, `lm`, `circle sweeps`, …
    pub name: String,
    /// Cost or energy evaluations (positions only).
    pub cost_evaluations: usize,
    /// Jacobian evaluations.
    pub jacobian_evaluations: usize,
    /// Wall time, s.
    #[serde(skip)]
    pub seconds: f64,
}

impl Phase {
    /// An empty phase.
    pub fn new(name: &str) -> Phase {
        Phase {
            name: name.to_string(),
            cost_evaluations: 0,
            jacobian_evaluations: 0,
            seconds: 0.0,
        }
    }

    /// Adds `other`'s evaluations and time.
    pub(crate) fn add(&mut self, other: &Phase) {
        self.cost_evaluations += other.cost_evaluations;
        self.jacobian_evaluations += other.jacobian_evaluations;
        self.seconds += other.seconds;
    }

    pub(crate) fn add_lm(&mut self, fit: &LmResult, seconds: f64) {
        self.cost_evaluations += fit.cost_evaluations;
        self.jacobian_evaluations += fit.jacobian_evaluations;
        self.seconds += seconds;
    }
}

/// One parameter's result, in internal units (mm, rad). Files show it in
/// user units (mm, deg) as an [`EstimateRecord`]; reading one back
/// converts degrees to radians (exact to the last bit or two).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(into = "EstimateRecord", try_from = "EstimateRecord")]
#[non_exhaustive]
pub struct Estimate {
    /// The parameter.
    pub id: ParamId,
    /// Start value, mm or rad.
    pub nominal: f64,
    /// Calibrated value, mm or rad (zero offsets wrapped to ±π).
    pub calibrated: f64,
    /// `calibrated − nominal` (for zero offsets wrapped to ±π).
    pub correction: f64,
    /// Standard uncertainty; `None` for a fixed parameter (or one the data
    /// do not determine).
    pub sigma: Option<f64>,
    /// Why it is fixed; `None` for a free parameter.
    pub fixed: Option<String>,
}

/// An [`Estimate`] as users see it: named, in mm or deg.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EstimateRecord {
    /// Name (`a1`, `alpha3`, `Bz`, …).
    pub name: String,
    /// `mm` or `deg`.
    pub unit: String,
    /// Start value.
    pub nominal: f64,
    /// Calibrated value.
    pub calibrated: f64,
    /// `calibrated − nominal`.
    pub correction: f64,
    /// Standard uncertainty (k = 1).
    pub sigma: Option<f64>,
    /// Why it is fixed.
    pub fixed: Option<String>,
}

impl Estimate {
    /// The estimate in user units.
    ///
    /// ```
    /// use aacmm_core::calibrate::{Estimate, EstimateRecord};
    /// // Only the library makes an `Estimate` (`#[non_exhaustive]`); one
    /// // read back from a record (as from `calibration.json`) is in rad:
    /// let e = Estimate::try_from(EstimateRecord {
    ///     name: "theta2".into(), unit: "deg".into(),
    ///     nominal: 0.0, calibrated: 90.0, correction: 90.0, sigma: None, fixed: None,
    /// })?;
    /// assert!((e.calibrated - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    /// let r = e.user();
    /// assert_eq!((r.name.as_str(), r.unit.as_str()), ("theta2", "deg"));
    /// assert!((r.calibrated - 90.0).abs() < 1e-12);
    /// # Ok::<(), String>(())
    /// ```
    pub fn user(&self) -> EstimateRecord {
        let u = |v: f64| self.id.to_user(v);
        EstimateRecord {
            name: self.id.to_string(),
            unit: self.id.unit().to_string(),
            nominal: u(self.nominal),
            calibrated: u(self.calibrated),
            correction: u(self.correction),
            sigma: self.sigma.map(u),
            fixed: self.fixed.clone(),
        }
    }
}

impl From<Estimate> for EstimateRecord {
    fn from(e: Estimate) -> Self {
        e.user()
    }
}

impl TryFrom<EstimateRecord> for Estimate {
    type Error = String;

    fn try_from(r: EstimateRecord) -> Result<Self, String> {
        let id: ParamId = r.name.parse()?;
        if r.unit != id.unit() {
            return Err(format!(
                "{}: unit {}, expected `{}`",
                r.name,
                crate::error::quoted(&r.unit),
                id.unit()
            ));
        }
        let f = |v: f64| id.from_user(v);
        Ok(Estimate {
            id,
            nominal: f(r.nominal),
            calibrated: f(r.calibrated),
            correction: f(r.correction),
            sigma: r.sigma.map(f),
            fixed: r.fixed,
        })
    }
}

/// An auxiliary block's column as estimated, in the unit users see.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct AuxiliaryEstimate {
    /// Its name (`tracker.tx`).
    pub name: String,
    /// Its unit (`mm`, `deg`, or the block's own).
    pub unit: String,
    /// The start value.
    pub start: f64,
    /// The calibrated value.
    pub calibrated: f64,
    /// Standard uncertainty (k = 1); `None` when the data do not determine
    /// it. Of the value itself unless [`AuxiliaryEstimate::sigma_of`] says
    /// otherwise.
    pub sigma: Option<f64>,
    /// What `sigma` is the uncertainty of when not of the value: a frame's
    /// rotation columns hold its rotation vector, their σ is of a small
    /// rotation about the frame's named axis (`a small rotation about
    /// tracker's x axis`), the step the fit takes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma_of: Option<String>,
    /// Why it was held at its start value, when it was (a correction
    /// beyond geometry these data cannot separate).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixed: Option<String>,
}

/// A residual term's rows, beyond the touches, lengths and prior.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TermRows {
    /// The term's name.
    pub term: String,
    /// Its residual rows.
    pub rows: usize,
    /// Unknowns it eliminates.
    pub eliminated: usize,
}

/// Residual and unknown counts, and the a-posteriori variance factor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct Dof {
    /// Touch residual rows (3 per touch).
    pub touch_rows: usize,
    /// Length residual rows.
    pub length_rows: usize,
    /// Free parameters.
    pub free_parameters: usize,
    /// Eliminated unknowns: the point centres' coordinates (3 per point).
    pub centre_coordinates: usize,
    /// `m − p`.
    pub degrees_of_freedom: usize,
    /// `σ̂ = sqrt(Σr² / (m − p))`; 1 when the weights are right.
    pub sigma0: f64,
    /// The touch σ behind the weights, mm: with stated noise the median over
    /// touches of `sqrt(trace Σ_i / 3)`; otherwise estimated from the fit.
    pub touch_sigma_mm: f64,
    /// Whether the touch σ was estimated from the fit.
    pub touch_sigma_estimated: bool,
    /// Pseudo-observation rows of a prior (free parameters with a stated
    /// tolerance), counted in `degrees_of_freedom`; absent without one.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub prior_rows: usize,
    /// The rows of every other residual term, counted in
    /// `degrees_of_freedom`; absent without one.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub other_rows: Vec<TermRows>,
}

impl Dof {
    /// The residual rows of the other term named `term` (`positions`,
    /// `orientations`, `spheres`, a caller's), 0 when there is none.
    pub(crate) fn rows_of(&self, term: &str) -> usize {
        (self.other_rows.iter())
            .filter(|r| r.term == term)
            .map(|r| r.rows)
            .sum()
    }
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// The solver's account of itself.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct SolverSummary {
    /// The method that ran.
    pub method: Method,
    /// Why it stopped: the method's own reason and the final LM's.
    pub stop: Stop,
    /// Whether the result is a usable solution
    /// ([`Stop::is_solution_usable`]; read it through
    /// [`SolverSummary::is_solution_usable`]).
    pub(crate) successful: bool,
    /// Iterations of the final fit.
    pub iterations: usize,
    /// Cost evaluations (positions only), all fits.
    pub cost_evaluations: usize,
    /// Jacobian evaluations, all fits.
    pub jacobian_evaluations: usize,
    /// Cost `Σr²` of the start arm, weighed as the final fit.
    pub initial_cost: f64,
    /// Cost at the end.
    pub final_cost: f64,
    /// Cost per iteration of the final fit.
    pub history: Vec<LmIteration>,
    /// The tolerances.
    pub(crate) options: LmOptions,
    /// Work per phase, in order.
    pub phases: Vec<Phase>,
    /// The annealing (`sa`, `hybrid`).
    pub anneal: Option<AnnealTrace>,
    /// The global search (`global`).
    pub global: Option<GlobalTrace>,
}

impl SolverSummary {
    /// Whether the result is usable (Ceres' `IsSolutionUsable`).
    pub fn is_solution_usable(&self) -> bool {
        self.successful
    }
}

/// The correlation matrix of the free parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct CorrelationMatrix {
    /// The free parameters' names, in column order.
    pub parameters: Vec<String>,
    /// `ρ_ij`, row by row.
    pub rho: Vec<Vec<f64>>,
}

/// The checks a metrologist makes before signing off ([`checks`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct Checks {
    /// Free parameters moved implausibly far from nominal: a mirror image
    /// of the arm, a collapsed arm, or a unit mistake. Empty when the arm is
    /// plausible.
    pub gross_corrections: Vec<checks::GrossCorrection>,
    /// Auxiliary blocks whose values no real instrument could have (each
    /// block's own limits), in words; absent when there is none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub implausible_blocks: Vec<String>,
    /// The χ² test of the residuals against the stated noise (`None`
    /// without stated noise: the touch σ was estimated from the fit).
    pub chi_square: Option<checks::ChiSquare>,
    /// Touches the noise model does not explain (standardised residual
    /// beyond `outlier_threshold`), largest first.
    pub outliers: Vec<checks::Outlier>,
    /// The threshold of the outlier test, in σ of a touch.
    pub outlier_threshold: f64,
    /// When a plain fit named more than one touch, the robust refit that
    /// screened the list (`outliers` then keeps to the touches it weighs
    /// down); `None` otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outlier_screen: Option<checks::OutlierScreen>,
    /// How well the data determine the arm (`None` when the covariance is
    /// not finite).
    pub position_uncertainty: Option<checks::PositionUncertainty>,
}

/// What [`calibrate`](super::calibrate) returns: read it through its fields and accessors
/// ([`Calibration::estimate`]); only the library builds one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct Calibration {
    /// The calibrated geometry (mm, rad; zero offsets wrapped to ±π):
    /// `parameters`' calibrated values (rebuilt from them when read back).
    #[serde(skip)]
    pub params: DhParams,
    /// Per parameter, in the fixed order.
    pub parameters: Vec<Estimate>,
    /// Per joint, base first, its type (`revolute`, `prismatic`: whether a
    /// reading turns θ, deg, or slides d, mm). Written when the chain has
    /// a slide; absent, every joint turns (an arm file's default), so that
    /// a revolute arm's JSON is what it always was and the chain read back
    /// ([`Calibration::restore_params`]) is the one fitted.
    #[serde(default, skip_serializing_if = "all_revolute")]
    pub joint_types: Vec<JointKind>,
    /// Per column of the auxiliary blocks (a frame, a scalar), in the
    /// layout's order; absent when there is none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub auxiliary: Vec<AuxiliaryEstimate>,
    /// Free-parameter pairs with `|ρ| > 0.9`.
    pub correlations: Vec<Correlation>,
    /// Every correlation of the free parameters.
    pub correlation_matrix: CorrelationMatrix,
    /// Counts and the variance factor.
    pub dof: Dof,
    /// The solver.
    pub solver: SolverSummary,
    /// The identifiability analysis behind the automatic fixed set.
    pub identification: Option<Identification>,
    /// Plausibility of the arm and of the fit.
    pub checks: Checks,
    /// The robust fit and every touch's weight (only when one ran:
    /// [`ModelOptions::robust`](super::ModelOptions::robust)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robust: Option<RobustFit>,
    /// The prior and the data's share of the information per parameter
    /// (only when tolerances were stated).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prior: Option<PriorReport>,
    /// Weak directions of the free geometry that no tolerance covers, held
    /// at nominal (docs/calibration.md, "Weak directions held at nominal"); absent when none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub held: Vec<crate::residuals::HeldDirection>,
    /// The arm's physics at the fit — masses, and every correction beyond
    /// geometry, fitted or stated ([`crate::corrections`]) — when the arm
    /// states a correction or the fit estimated one (masses alone correct
    /// nothing: then `None`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub physics: Option<crate::corrections::Physics>,
}

impl Calibration {
    /// Parameter `id`'s estimate: `None` when the arm has no such parameter
    /// (a joint beyond its count, the `d` of a Hayati joint).
    pub fn estimate(&self, id: ParamId) -> Option<&Estimate> {
        self.parameters.iter().find(|e| e.id == id)
    }

    /// The calibrated point of `layout` (the layout it was fitted on): the
    /// geometry's columns, then each auxiliary column's calibrated value
    /// back in internal units (a column not reported keeps its start):
    /// what a term is evaluated at after the fit.
    pub(crate) fn point_in(&self, layout: &crate::residuals::Layout) -> Vec<f64> {
        let mut x = layout.start();
        let g = layout.geometry_columns();
        x[..g].copy_from_slice(&self.params.to_vec()[..g]);
        for (k, e) in self.auxiliary.iter().enumerate() {
            let col = g + k;
            if let Some(p) = layout.parameter(col).filter(|p| p.name == e.name) {
                x[col] = if p.unit.is_angle() {
                    e.calibrated.to_radians()
                } else {
                    e.calibrated
                };
            }
        }
        x
    }

    /// The calibrated parameters as a vector in the fixed order (mm, rad):
    /// what [`DhParams::from_slice`] takes.
    pub fn calibrated_vector(&self) -> Vec<f64> {
        self.parameters.iter().map(|p| p.calibrated).collect()
    }

    /// Restores [`Calibration::params`] from the estimates, after reading a
    /// calibration back from JSON: each value to the parameter it names (a
    /// joint with an `hbeta…` is a Hayati joint).
    pub fn restore_params(&mut self) {
        if let Some(mut p) =
            DhParams::from_named(self.parameters.iter().map(|e| (e.id, e.calibrated)))
        {
            for (joint, &kind) in p.joints.iter_mut().zip(&self.joint_types) {
                *joint = joint.with_kind(kind);
            }
            self.params = p;
        }
    }
}

/// Whether every joint of `kinds` turns (nothing to write).
fn all_revolute(kinds: &[JointKind]) -> bool {
    kinds.iter().all(|&k| k == JointKind::Revolute)
}
