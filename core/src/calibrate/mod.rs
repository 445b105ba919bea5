//! Calibration: the parameters that make the touches agree.
//!
//! [`calibrate`] fits the free parameters by Levenberg–Marquardt ([`LmOptions`]) on
//! the weighted residuals of [`crate::residuals`], then reports what a
//! metrologist signs off on:
//!
//! - **uncertainty**: `σ̂² = Σr² / (m − p)` with `m` residual rows
//!   (`3·touches + lengths`) and `p` every unknown fitted (the free
//!   parameters and `3` centre coordinates per point, eliminated but fitted
//!   all the same); covariance `σ̂² (JᵀJ)⁻¹` of the free parameters, σ in mm
//!   or deg, correlations `|ρ| > 0.9`; fixed parameters with the reason;
//! - **weights**: `1/σ` from the stated noise; without it, a first fit with
//!   unit weights estimates the touch σ from its touch residuals
//!   (`Σr²_touch / (3·touches − 3·points − free)`), and a second fit uses it,
//!   so that reference lengths are weighed against touches correctly.
//!
//! Solvers ([`Method`]): `lm` from the start arm; `sa`, the paper's
//! annealing ([`anneal`]) on its own; `hybrid`, the paper's annealing with
//! its switching rule, then LM; `global` ([`global`]), which converges from
//! encoder zeros unknown anywhere in ±180°.
//!
//! Validation on held-out data lives in [`validate`].

/// Builder setters: `setters!(Type { field: type, "doc"; … })`, each
/// `fn field(self, v) -> Self`.
macro_rules! setters {
    ($t:ty { $($field:ident: $ty:ty, $doc:literal;)* }) => {
        impl $t {
            $(
                #[doc = $doc]
                pub fn $field(mut self, v: $ty) -> Self {
                    self.$field = v;
                    self
                }
            )*
        }
    };
}

pub mod anneal;
pub(crate) mod assess;
pub mod checks;
pub mod energy;
pub mod global;
mod inverse;
pub(crate) mod lm;
pub mod options;
pub mod prior;
pub mod robust;
pub mod solver;
pub mod validate;

use serde::{Deserialize, Serialize};

use crate::error::OptionError;
use crate::setting::Setting;
pub use anneal::{AnnealOptions, AnnealStep, AnnealStop, AnnealTrace, SwitchRule};
pub use global::{GlobalOptions, GlobalStop, GlobalTrace};
pub use lm::LmIteration;
pub(crate) use lm::LmResult;
pub use lm::{LmOptions, Termination};
pub use options::{
    DEFAULT_LENGTH_SIGMA_MM, FixSpec, MAX_THREADS, ModelOptions, SolverSettings, available_threads,
    check_threads,
};
pub use prior::{PriorConditioning, PriorReport};
pub use robust::{Loss, Robust, RobustFit};
pub use solver::{Anneal, Cancel, Context, Global, Lm, Outcome, Solver, Stop, Task};

use crate::dataset::DataSet;
use crate::identify::{Correlation, Identification, identify_from, open_directions_from};
use crate::kernel::KernelError;
use crate::metrics::MetricsError;
use crate::objective::Objective;
use crate::params::{DhParams, JointKind, ParamId, ParamKind};
use crate::residuals::{Elimination, Layout, Normal, Role, Term, TermError};

/// What to do about readings in radians read as degrees, in each front
/// end's words (the library serves all three).
pub(crate) const ANGLE_UNITS_REMEDY: &str = "read the poses as radians (command line \
     `--angle-unit rad`, Python `angle_unit=\"rad\"`, C `AACMM_ANGLE_RAD`)";

/// The remedy of [`CalibrationError::AngleUnits`], in each front end's
/// words (the library serves all three), and whether reading the angles as
/// radians makes the lengths agree with the nominal arm.
fn angle_units_remedy(ratio_as_rad: f64, lengths_agree: bool) -> String {
    let remedy = ANGLE_UNITS_REMEDY;
    if lengths_agree {
        format!(
            "{remedy}: read so, the lengths are {ratio_as_rad:.4} times the nominal arm's \
             distances (the lengths file is not the cause)"
        )
    } else {
        format!(
            "{remedy}; read so, the lengths are still {ratio_as_rad:.3e} times the nominal arm's \
             distances: check the lengths file's unit (mm) too"
        )
    }
}

/// Why a calibration could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CalibrationError {
    /// The calibration was cancelled (its [`Cancel`] token was set) before
    /// it finished: there is no result.
    #[error("cancelled before the calibration finished: no result")]
    Cancelled,
    /// A setting out of range.
    #[error(transparent)]
    Option(#[from] OptionError),
    /// The kernel refused the arm or the data.
    #[error(transparent)]
    Kernel(#[from] KernelError),
    /// A residual term refused its own inputs.
    #[error("{term}: {message}")]
    Term {
        /// The term's name.
        term: String,
        /// What is wrong.
        message: String,
    },
    /// The metrics refused positions (validation).
    #[error(transparent)]
    Metrics(#[from] MetricsError),
    /// The data were read for another joint count than the arm's.
    #[error("the arm has {arm} joints, the data {data}")]
    Joints {
        /// The arm's joints.
        arm: usize,
        /// The data's joints.
        data: usize,
    },
    /// The reference lengths are in another unit than the arm.
    #[error(
        "{file}: the reference lengths are {ratio:.3e} times the nominal arm's distances between \
         the same points (median): lengths and arm in different units? (the arm file's lengths \
         are mm inside the toolkit; the lengths file must be in mm)"
    )]
    LengthUnits {
        /// The lengths file.
        file: String,
        /// Median of stated length / nominal distance.
        ratio: f64,
    },
    /// The reference lengths disagree with the nominal arm because the
    /// arm's own file is in another unit than it declares: its reach is
    /// no arm's (under 10 mm or over 10 m), so the arm, not the lengths
    /// file, is the cause.
    #[error(
        "{}: the arm file's lengths, in the unit its `length_unit` declares, make the arm {} \
         long (its reach), and the reference lengths are {ratio:.3e} times its distances \
         between the same points (median): the arm file's numbers are in another unit than it \
         declares (millimetres declared as metres make an arm 1000 times too long) — set \
         `length_unit` to the unit its numbers are in; the lengths file (mm) is not the cause",
        if file.is_empty() { "the arm" } else { file },
        crate::error::length_words(*reach_mm)
    )]
    ArmUnits {
        /// The arm file (empty when the caller did not name it).
        file: String,
        /// The arm's reach as its file declares it, mm.
        reach_mm: f64,
        /// Median of stated length / nominal distance.
        ratio: f64,
    },
    /// The reference lengths disagree with the nominal arm because the
    /// joint readings look like radians read as degrees (every one within
    /// ±2π "degrees"): the angle unit is the cause, not the lengths file.
    #[error(
        "{file}: every joint reading, read as degrees, is within ±6.28° — these angles look like \
         radians read as degrees, so the reference lengths come out {ratio:.3e} times the nominal \
         arm's distances; {}",
        angle_units_remedy(*ratio_as_rad, *lengths_agree)
    )]
    AngleUnits {
        /// The poses file.
        file: String,
        /// Median of stated length / nominal distance, as read.
        ratio: f64,
        /// The same with the readings taken as radians.
        ratio_as_rad: f64,
        /// Whether `ratio_as_rad` is within the bound the lengths are
        /// checked against.
        lengths_agree: bool,
    },
    /// Reference positions the nominal arm cannot be registered to: another
    /// unit, swapped axes, another arm.
    #[error("{file}:{line}: field `{field}`: {message}")]
    Positions {
        /// The positions file.
        file: String,
        /// The first line of the frame concerned.
        line: usize,
        /// The field concerned.
        field: String,
        /// What is wrong, and what to do.
        message: String,
    },
    /// The calibration needs more memory than the process can allocate,
    /// found before any work (see [`crate::memory`]).
    #[error(transparent)]
    Memory(#[from] crate::memory::OutOfMemory),
    /// A parameter vector of the wrong length (a bug, not user input).
    #[error("internal: parameter vector of the wrong length")]
    Shape,
    /// The start arm gives non-finite positions.
    #[error("the start arm gives positions that are not finite numbers")]
    NonFiniteStart,
    /// More unknowns than residuals.
    #[error(
        "{residuals} residuals for {unknowns} unknowns ({free} free parameters + 3 per point): \
         touch more points or fix more parameters"
    )]
    TooFewResiduals {
        /// Residual rows.
        residuals: usize,
        /// Unknowns.
        unknowns: usize,
        /// Free parameters.
        free: usize,
    },
    /// The fixed set leaves a direction the data cannot see.
    #[error(
        "the free parameters include directions the data cannot see: {}; fix more \
         parameters (the automatic fixed set chooses them)",
        directions.join("; ")
    )]
    Unidentifiable {
        /// The open directions, in words.
        directions: Vec<String>,
    },
}

impl CalibrationError {
    /// Whether the message starts with the input at fault (the lengths
    /// file, the poses file, the arm file of a unit mistake): a front end
    /// that names the arm file before other errors adds nothing to it.
    pub fn names_its_input(&self) -> bool {
        matches!(
            self,
            CalibrationError::LengthUnits { .. }
                | CalibrationError::AngleUnits { .. }
                | CalibrationError::ArmUnits { .. }
        )
    }
}

impl From<TermError> for CalibrationError {
    fn from(e: TermError) -> Self {
        match e {
            TermError::Kernel(k) => CalibrationError::Kernel(k),
            TermError::Invalid { term, message } => CalibrationError::Term { term, message },
            TermError::Layout(e) => CalibrationError::Term {
                term: "layout".to_string(),
                message: e.to_string(),
            },
        }
    }
}

/// The solvers of [`calibrate`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Levenberg–Marquardt from the start arm.
    Lm,
    /// The paper's simulated annealing alone (method.md §5).
    Sa,
    /// The paper's hybrid: annealing until its switching rule, then LM (§6).
    Hybrid,
    /// Converges from encoder zeros unknown in ±180° ([`global`]).
    #[default]
    Global,
    /// A solver of another crate, passed to the session as a [`Solver`]
    /// (the library has none by this name: [`SolverSettings::check`]
    /// refuses it as the method to run).
    External,
}

impl Method {
    /// Every method, in the order of the comparison table.
    pub const ALL: [Method; 4] = [Method::Lm, Method::Sa, Method::Hybrid, Method::Global];

    /// The name used on the command line and in reports.
    ///
    /// ```
    /// use aacmm_core::calibrate::Method;
    /// assert_eq!(Method::Hybrid.name(), "hybrid");
    /// assert_eq!(Method::parse("global"), Some(Method::Global));
    /// assert_eq!(Method::parse("ceres"), None);
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Method::Lm => "lm",
            Method::Sa => "sa",
            Method::Hybrid => "hybrid",
            Method::Global => "global",
            Method::External => "external",
        }
    }

    /// The method of a name (one of [`Method::ALL`]).
    pub fn parse(s: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == s)
    }
}

/// Work and time of one phase of a solver. The time is not serialised, so
/// that the same seed gives the same `calibration.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct Phase {
    /// What ran: `anneal`, `lm`, `circle sweeps`, …
    pub name: String,
    /// Cost or energy evaluations (positions only).
    pub(crate) cost_evaluations: usize,
    /// Jacobian evaluations.
    pub(crate) jacobian_evaluations: usize,
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
    pub(crate) eliminated: usize,
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
    pub fn rows_of(&self, term: &str) -> usize {
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
    /// (`Stop::is_solution_usable`).
    pub successful: bool,
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
    pub(crate) outlier_threshold: f64,
    /// When a plain fit named more than one touch, the robust refit that
    /// screened the list (`outliers` then keeps to the touches it weighs
    /// down); `None` otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outlier_screen: Option<checks::OutlierScreen>,
    /// How well the data determine the arm (`None` when the covariance is
    /// not finite).
    pub position_uncertainty: Option<checks::PositionUncertainty>,
}

/// What [`calibrate`] returns: read it through its fields and accessors
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
    pub(crate) joint_types: Vec<JointKind>,
    /// Per column of the auxiliary blocks (a frame, a scalar), in the
    /// layout's order; absent when there is none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub auxiliary: Vec<AuxiliaryEstimate>,
    /// Free-parameter pairs with `|ρ| > 0.9`.
    pub(crate) correlations: Vec<Correlation>,
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
    /// [`ModelOptions::robust`]).
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

    /// The free geometry's columns (of the `4n + 3`) and their covariance
    /// (mm, rad): the parameters' σ with the correlation matrix. `None`
    /// without a free parameter, or with one whose σ is not finite.
    pub fn geometry_covariance(&self) -> Option<(Vec<usize>, nalgebra::DMatrix<f64>)> {
        let (free, columns) = self.free_geometry()?;
        Some((free, self.covariance_of(&columns)?))
    }

    /// The free geometry's columns, the registration of the fitted frame
    /// `name` (`[rx, ry, rz, tx, ty, tz]`, rad, mm) and the joint
    /// covariance of the two (mm, rad; `(q + 6)²`, the frame's six columns
    /// last, its rotation's of a small rotation about the frame's axes):
    /// what a prediction in that instrument's frame
    /// ([`crate::plan::position_covariances`]) needs, the frame's
    /// registration error and its correlation with the arm's counted in.
    /// `None` without such a frame, or as [`Calibration::geometry_covariance`].
    pub fn frame_covariance(
        &self,
        name: &str,
    ) -> Option<(Vec<usize>, [f64; 6], nalgebra::DMatrix<f64>)> {
        let (free, mut columns) = self.free_geometry()?;
        let (_, cols) = (self.frame_columns().into_iter()).find(|(n, _)| *n == name)?;
        for (k, c) in cols.iter().enumerate() {
            let sigma = if k < 3 {
                c.sigma.map(f64::to_radians)
            } else {
                c.sigma
            };
            columns.push((c.name.clone(), sigma));
        }
        let x = self.frames().into_iter().find(|(n, _)| n == name)?.1;
        Some((free, x, self.covariance_of(&columns)?))
    }

    /// What a prediction at the tool point `name` (a `[[tool]]` whose
    /// offset was fitted, block `tool.NAME`) needs: the free geometry's
    /// columns but the probe's (the tool replaces the probe), then the
    /// probe's three — the kernel's derivative over the probe's offset,
    /// which at the tool's offset is the derivative over the tool's —; the
    /// tool's fitted offset (mm, the last joint's frame); and the joint
    /// covariance of those geometry columns and the tool's `x, y, z` (mm
    /// and rad), their correlation counted in. `None` when the tool's
    /// offset was not fitted or a σ is not finite, or without free
    /// geometry.
    pub fn tool_covariance(
        &self,
        name: &str,
    ) -> Option<(Vec<usize>, [f64; 3], nalgebra::DMatrix<f64>)> {
        let n = self.params.joint_count();
        let (free, named) = self.free_geometry()?;
        // The probe's columns: the tool's offset takes their place.
        let probe: [usize; 3] = std::array::from_fn(|k| {
            let id = ParamId {
                kind: ParamKind::Probe,
                index: k,
            };
            id.column(n)
        });
        let (mut columns, mut sigmas): (Vec<usize>, NamedSigmas) = (free.iter().zip(named))
            .filter(|(c, _)| !probe.contains(c))
            .map(|(c, s)| (*c, s))
            .unzip();
        let prefix = crate::io::tools::TOOL_BLOCK_PREFIX;
        let mut x = [0.0; 3];
        for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
            let full = format!("{prefix}{name}.{axis}");
            let c = self.auxiliary.iter().find(|c| c.name == full)?;
            x[k] = c.calibrated;
            sigmas.push((full, Some(c.sigma?)));
            columns.push(probe[k]);
        }
        Some((columns, x, self.covariance_of(&sigmas)?))
    }

    /// The free geometry parameters' columns (of the `4n + 3`), and each
    /// one's name and σ. `None` without one.
    fn free_geometry(&self) -> Option<(Vec<usize>, NamedSigmas)> {
        let n = self.params.joint_count();
        let free: Vec<&Estimate> = (self.parameters.iter())
            .filter(|e| e.fixed.is_none())
            .collect();
        if free.is_empty() {
            return None;
        }
        let columns = free.iter().map(|e| (e.id.to_string(), e.sigma)).collect();
        Some((free.iter().map(|e| e.id.column(n)).collect(), columns))
    }

    /// The covariance of the named free columns: their σ with the
    /// correlation matrix. `None` when one is not in the matrix or its σ is
    /// not finite.
    fn covariance_of(&self, columns: &[(String, Option<f64>)]) -> Option<nalgebra::DMatrix<f64>> {
        let names = &self.correlation_matrix.parameters;
        let at: Vec<usize> = (columns.iter())
            .map(|(name, _)| names.iter().position(|m| m == name))
            .collect::<Option<_>>()?;
        let sigma: Vec<f64> = columns.iter().map(|c| c.1).collect::<Option<_>>()?;
        if sigma.iter().any(|s| !s.is_finite()) {
            return None;
        }
        let rho = &self.correlation_matrix.rho;
        let q = columns.len();
        Some(nalgebra::DMatrix::from_fn(q, q, |a, b| {
            let r = if a == b { 1.0 } else { rho[at[a]][at[b]] };
            sigma[a] * sigma[b] * r
        }))
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

    /// Each fitted frame's registration `[rx, ry, rz, tx, ty, tz]` (rad, mm)
    /// by name: the auxiliary columns `NAME.rx … NAME.tz` of the frames of
    /// reference positions.
    pub fn frames(&self) -> Vec<validate::FrameValues> {
        self.frame_columns()
            .into_iter()
            .map(|(name, cols)| {
                let x = std::array::from_fn(|k| {
                    let v = cols[k].calibrated;
                    if k < 3 { v.to_radians() } else { v }
                });
                (name.to_string(), x)
            })
            .collect()
    }

    /// [`Calibration::frames`], then the fitted tool mount of orientations
    /// when there is one, under its block's name
    /// ([`validate::FrameValues`]): what the figures of orientations need.
    pub fn frames_with_mount(&self) -> Vec<validate::FrameValues> {
        let mut frames = self.frames();
        if let Some(m) = self.mount() {
            let r = m.map(f64::to_radians);
            frames.push((
                crate::residuals::MOUNT_BLOCK.to_string(),
                [r[0], r[1], r[2], 0.0, 0.0, 0.0],
            ));
        }
        for (name, x) in self.tool_offsets() {
            frames.push((
                crate::io::tools::block_name(&name),
                [x[0], x[1], x[2], 0.0, 0.0, 0.0],
            ));
        }
        frames
    }

    /// Each fitted tool point's offset (`[[tool]]`, [`crate::io::tools`]):
    /// its name and `[x, y, z]` (mm, the last joint's frame), with their
    /// σ when determined, in the order of the columns.
    pub fn tool_estimates(&self) -> Vec<(String, [f64; 3], Option<[f64; 3]>)> {
        let aux = &self.auxiliary;
        let prefix = crate::io::tools::TOOL_BLOCK_PREFIX;
        (0..aux.len())
            .filter_map(|i| {
                let name = aux[i].name.strip_prefix(prefix)?.strip_suffix(".x")?;
                let cols = aux.get(i..i + 3)?;
                let named = (cols.iter().zip(["x", "y", "z"]))
                    .all(|(c, axis)| c.name == format!("{prefix}{name}.{axis}"));
                let sigma = [cols[0].sigma, cols[1].sigma, cols[2].sigma];
                let sigma = match sigma {
                    [Some(a), Some(b), Some(c)] => Some([a, b, c]),
                    _ => None,
                };
                let x = std::array::from_fn(|k| cols[k].calibrated);
                named.then(|| (name.to_string(), x, sigma))
            })
            .collect()
    }

    /// [`Calibration::tool_estimates`] without the σ.
    pub fn tool_offsets(&self) -> Vec<(String, [f64; 3])> {
        (self.tool_estimates().into_iter())
            .map(|(n, x, _)| (n, x))
            .collect()
    }

    /// The fitted tool mount of orientations ([`crate::residuals::Mount`]),
    /// its rotation vector in degrees; `None` when none was fitted.
    pub fn mount(&self) -> Option<[f64; 3]> {
        let cols = self.mount_columns()?;
        Some(std::array::from_fn(|k| cols[k].calibrated))
    }

    /// The fitted tool mount as a calibrated arm file carries it
    /// ([`crate::io::frames::MountRecord`]); `None` when none was fitted.
    pub fn mount_record(&self) -> Option<crate::io::frames::MountRecord> {
        let cols = self.mount_columns()?;
        let sigma = [cols[0].sigma, cols[1].sigma, cols[2].sigma];
        Some(crate::io::frames::MountRecord {
            rotation_deg: std::array::from_fn(|k| cols[k].calibrated),
            small_rotation_sigma_deg: sigma[0]
                .zip(sigma[1])
                .zip(sigma[2])
                .map(|((a, b), c)| [a, b, c]),
        })
    }

    /// The mount's three columns `mount.rx … mount.rz`, if fitted.
    fn mount_columns(&self) -> Option<&[AuxiliaryEstimate]> {
        let name = |k: &str| format!("{}.{k}", crate::residuals::MOUNT_BLOCK);
        let i = (self.auxiliary.iter()).position(|c| c.name == name("rx"))?;
        let cols = self.auxiliary.get(i..i + 3)?;
        (cols[1].name == name("ry") && cols[2].name == name("rz")).then_some(cols)
    }

    /// Each fitted frame as a calibrated arm file carries it
    /// ([`crate::io::frames`]): values and σ in deg and mm.
    pub fn frame_records(&self) -> Vec<crate::io::frames::FrameRecord> {
        self.frame_columns()
            .into_iter()
            .map(|(name, cols)| {
                let three = |from: usize| std::array::from_fn(|k| cols[from + k].calibrated);
                let sigmas = |from: usize| -> Option<[f64; 3]> {
                    Some([
                        cols[from].sigma?,
                        cols[from + 1].sigma?,
                        cols[from + 2].sigma?,
                    ])
                };
                crate::io::frames::FrameRecord {
                    name: name.to_string(),
                    rotation_deg: three(0),
                    translation_mm: three(3),
                    small_rotation_sigma_deg: sigmas(0),
                    translation_sigma_mm: sigmas(3),
                }
            })
            .collect()
    }

    /// The frames among the auxiliary columns: each name and its six
    /// columns `NAME.rx … NAME.tz` (user units: deg, mm).
    fn frame_columns(&self) -> Vec<(&str, &[AuxiliaryEstimate])> {
        const AXES: [&str; 6] = ["rx", "ry", "rz", "tx", "ty", "tz"];
        let aux = &self.auxiliary;
        (0..aux.len())
            .filter_map(|i| {
                let name = aux[i].name.strip_suffix(".rx")?;
                let cols = aux.get(i..i + 6)?;
                let named = (cols.iter().zip(AXES))
                    .all(|(c, axis)| c.name.strip_prefix(name) == Some(&format!(".{axis}")));
                named.then_some((name, cols))
            })
            .collect()
    }

    /// Restores [`Calibration::params`] from the estimates, after reading a
    /// calibration back from JSON: each value to the parameter it names (a
    /// joint with an `hbeta…` is a Hayati joint).
    pub(crate) fn restore_params(&mut self) {
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

/// Columns by name, each with its σ (`None`: not determined).
type NamedSigmas = Vec<(String, Option<f64>)>;

/// Whether every joint of `kinds` turns (nothing to write).
fn all_revolute(kinds: &[JointKind]) -> bool {
    kinds.iter().all(|&k| k == JointKind::Revolute)
}

/// Calibrates `start` (the nominal arm) on `data`: the model `model`, solved
/// as `settings` say (method, threads, seed). The geometry alone states no
/// masses: with [`ModelOptions::beyond`] a compliance is refused (a
/// [`crate::session::Problem`] of an arm file with masses fits one).
///
/// ```
/// use aacmm_core::{calibrate::*, io::Arm, params::DhParams, simulate::*};
/// let nominal = Arm::without_limits("nominal", DhParams::paper_nominal());
/// let mut settings = CampaignSettings::new(1, ErrorModel::Paper, 8, 10);
/// settings.reference_lengths = 3;
/// let campaign = simulate(&nominal, &settings).unwrap();
/// let data = campaign.data_set().unwrap();
/// let model = ModelOptions::default();
/// let c = calibrate(&nominal.params, &data, &model, &SolverSettings::default()).unwrap();
/// assert!(c.solver.successful);
/// assert_eq!(c.parameters.iter().filter(|p| p.fixed.is_none()).count(), 21);
/// ```
pub fn calibrate(
    start: &DhParams,
    data: &DataSet,
    model: &ModelOptions,
    settings: &SolverSettings,
) -> Result<Calibration, CalibrationError> {
    let solver = settings.method.solver();
    // A bare geometry states no masses: the models beyond it that need none
    // (harmonics, expansion, drift) are fitted, a compliance refused.
    let physics = crate::corrections::Physics::default();
    model
        .beyond
        .check_inputs(&physics, &data.condition_sets())?;
    let layout = crate::residuals::positions::layout_with(start, data, &physics, &model.beyond)?;
    let inputs = FitInputs {
        layout: &layout,
        data,
        model,
        terms: &[],
    };
    calibrate_with(inputs, settings, &*solver, &mut Context::new())
}

/// A calibration to run: the data and the model, on the columns of
/// `layout` — the start arm's geometry, then any auxiliary parameter block
/// a caller adds — with the residual terms a caller adds to the data's own
/// (touches, reference lengths, the prior).
#[derive(Clone, Copy)]
pub struct FitInputs<'p> {
    /// The columns: the start arm's geometry first.
    pub layout: &'p Layout,
    /// The touches and reference lengths.
    pub data: &'p DataSet,
    /// The model's settings.
    pub model: &'p ModelOptions,
    /// Residual terms beyond the data's.
    pub terms: &'p [Box<dyn Term>],
}

/// [`calibrate`] with a given solver and context (a progress observer), on
/// `inputs` (which may add parameter blocks and residual terms). Checks
/// every setting first (`ModelOptions::check_for`,
/// [`SolverSettings::check`]).
pub fn calibrate_with(
    inputs: FitInputs<'_>,
    settings: &SolverSettings,
    solver: &dyn Solver,
    ctx: &mut Context,
) -> Result<Calibration, CalibrationError> {
    let FitInputs {
        layout,
        data,
        model,
        terms,
    } = inputs;
    let start = layout.geometry();
    model.check_for(start)?;
    settings.check()?;
    check_method_for(solver.method(), data)?;
    let extra = terms.iter().map(|t| dyn_clone::clone_box(&**t)).collect();
    let mut objective = Objective::of_data(
        layout.clone(),
        data,
        &model.noise,
        extra,
        model.prior.as_ref(),
        1.0,
        settings.threads,
    )?;
    check_terms_for(solver.method(), &objective)?;
    let x0 = objective.start();
    // One pass over the data at the start serves the identifiability
    // analysis and, restricted to the free columns, the first step.
    let timer = std::time::Instant::now();
    let all: Vec<usize> = (0..layout.len()).collect();
    let full = objective.normal_of(&x0, &all, |t| !t.is_prior())?;
    let FixedSet {
        free,
        identification,
        reasons,
        holds,
    } = fixed_set(start, &objective, model, &full, data)?;
    let (mut free, mut held) = correction_columns(&full, layout, free)?;
    hold_blocks(layout, &mut free, &mut held);
    let (carried, holds) =
        complete_prior(&mut objective, identification.as_ref(), holds, start, &x0);
    if free.is_empty() {
        return Err(OptionError::new(
            Setting::Fix,
            model.fix.describe_for(start),
            "every parameter is fixed: nothing is left to calibrate",
        )
        .into());
    }
    // The fixed set is the data's own (see [`prior`]); the prior joins
    // every fit from here on.
    let counts = assess::Counts::of(&objective, &free);
    // Whether every data term states its noise (else σ is estimated).
    let stated = objective.stated();
    if counts.residuals() <= counts.unknowns() {
        return Err(CalibrationError::TooFewResiduals {
            residuals: counts.residuals(),
            unknowns: counts.unknowns(),
            free: free.len(),
        });
    }
    let identify_phase = Phase {
        jacobian_evaluations: 1,
        seconds: timer.elapsed().as_secs_f64(),
        ..Phase::new("identify")
    };
    let mut start_normal = full.restrict(&free).ok_or(CalibrationError::Shape)?;
    objective.add_terms(&mut start_normal, &x0, |t| t.is_prior())?;
    let task = Task {
        start,
        x: &x0,
        data,
        objective: &objective,
        free: &free,
        model,
        settings,
        stated_dof: stated.then_some(counts.dof()),
        dof: counts.dof(),
        start_normal,
    };
    let mut outcome = solver.solve(task, ctx)?;
    // A solver of another crate may not check the token: what follows
    // (refits, covariance, leverage) is not started once it is set.
    ctx.check()?;
    outcome.phases.insert(0, identify_phase);
    let setup = assess::Setup {
        start,
        x0: &x0,
        data,
        model,
        settings,
        method: solver.method(),
        free,
        identification,
        reasons,
        held,
        counts,
        stated,
        carried,
        holds,
    };
    assess::assess(setup, objective, outcome)
}

/// Refuses a method that cannot use the data: the paper's annealing
/// minimises the touches' energy (its OA), so `sa` alone would ignore
/// reference positions, and neither `sa` nor `hybrid` has anything to
/// anneal without touches. Any other evidence `sa` would not weigh is
/// refused by [`check_terms_for`], by its term's name.
fn check_method_for(method: Method, data: &DataSet) -> Result<(), OptionError> {
    let why = match method {
        Method::Sa if data.positions().is_some() => {
            "anneals the paper's touch energy alone, which reference positions are no part of"
        }
        Method::Hybrid if data.is_empty() => {
            "anneals the paper's touch energy, and these data have no touches"
        }
        _ => return Ok(()),
    };
    Err(OptionError::new(
        Setting::Method,
        method.name(),
        format!("{why}: use lm or global (the default)"),
    ))
}

/// Refuses `sa` with evidence its energy does not measure: the annealer
/// minimises the touches' and lengths' energy, so any other term — a tool
/// orientation, a term written outside the library — would be ignored
/// while the result claims to fit it. Prior knowledge is not evidence: the
/// fit after the annealing carries it.
fn check_terms_for(method: Method, objective: &Objective<'_>) -> Result<(), OptionError> {
    if method != Method::Sa {
        return Ok(());
    }
    let ignored = objective.terms().find(|t| {
        let role = t.role();
        !role.is_prior() && !matches!(role, Role::Touches | Role::Lengths)
    });
    match ignored {
        None => Ok(()),
        Some(t) => Err(OptionError::new(
            Setting::Method,
            method.name(),
            format!(
                "anneals the paper's touch energy alone, which the term `{}` is no part of: \
                 use lm or global (the default)",
                t.name()
            ),
        )),
    }
}

/// The free columns, the identifiability analysis behind them (`fix =
/// auto`), why each fixed parameter is fixed and the weak directions to
/// hold; a user's fixed set that leaves a direction the data (and the
/// tolerances) cannot see is refused.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
fn fixed_set(
    start: &DhParams,
    objective: &Objective<'_>,
    model: &ModelOptions,
    full: &Normal,
    data: &DataSet,
) -> Result<FixedSet, CalibrationError> {
    let layout = objective.layout();
    let geometry = layout.geometry_columns();
    // Every auxiliary column is free: the geometry is analysed with them
    // fitted too (their elimination, as the centres' is).
    let aux: Vec<usize> = (geometry..layout.len()).collect();
    let full = full.geometry_only(layout).map_err(|e| match e {
        Elimination::Shape => CalibrationError::Shape,
        Elimination::Undetermined(_) => CalibrationError::Unidentifiable {
            directions: vec![e.to_string()],
        },
    })?;
    let sees = objective.sees();
    let mut holds = Vec::new();
    let (mut free, identification, reasons) = match &model.fix {
        FixSpec::Auto => {
            let id = identify_from(start, sees, full.clone(), data);
            let free = id.free_columns();
            let reasons: Vec<(ParamId, String)> =
                id.fixed.iter().map(|f| (f.id, f.reason.clone())).collect();
            holds = weak_untoleranced(start, full, &free, model, &id);
            (free, Some(id), reasons)
        }
        FixSpec::Columns(fixed) => {
            let free: Vec<usize> = (0..start.param_count())
                .filter(|c| !fixed.contains(c))
                .collect();
            let unknown = untoleranced(start, model, &free);
            let directions = open_directions_from(start, sees, full, &unknown);
            if !directions.is_empty() {
                return Err(CalibrationError::Unidentifiable { directions });
            }
            let reasons = fixed
                .iter()
                .filter_map(|&c| start.param_id(c))
                .map(|id| (id, "fixed by the user".to_string()))
                .collect();
            (free, None, reasons)
        }
    };
    free.extend(aux);
    Ok(FixedSet {
        free,
        identification,
        reasons,
        holds,
    })
}

/// Takes the columns of the blocks the layout holds ([`Layout::hold`]) out
/// of `free`, each with why in `held`.
///
/// [`Layout::hold`]: crate::residuals::Layout::hold
fn hold_blocks(
    layout: &crate::residuals::Layout,
    free: &mut Vec<usize>,
    held: &mut Vec<(usize, String)>,
) {
    for c in layout.held_columns() {
        if let Some(at) = free.iter().position(|&f| f == c) {
            free.remove(at);
            held.push((
                c,
                "held at its start: the problem holds its block".to_string(),
            ));
        }
    }
}

/// What the automatic fixed set adds to the prior: the tolerances of the
/// redundant fixed parameters carried onto their free partners, and the
/// weak directions `holds` held at `x0` (as a term of the objective).
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
fn complete_prior(
    objective: &mut Objective<'_>,
    identification: Option<&Identification>,
    holds: Vec<crate::residuals::Hold>,
    start: &DhParams,
    x0: &[f64],
) -> (
    Vec<prior::CarriedTolerance>,
    Option<crate::residuals::HoldTerm>,
) {
    let Some(id) = identification else {
        return (Vec::new(), None);
    };
    let carried = prior::carry_redundant(objective, id, start);
    let s_max = id.analysed_singular_values.first().copied().unwrap_or(0.0);
    let holds = (!holds.is_empty()).then(|| crate::residuals::HoldTerm::new(holds, x0, s_max));
    if let Some(h) = &holds {
        objective.push_term(Box::new(h.clone()));
    }
    (carried, holds)
}

/// The free columns, the identifiability analysis behind them (`fix =
/// auto`), why each fixed parameter is fixed, and the weak directions held
/// at nominal.
struct FixedSet {
    free: Vec<usize>,
    identification: Option<Identification>,
    reasons: Vec<(ParamId, String)>,
    holds: Vec<crate::residuals::Hold>,
}

/// The weak directions among the free parameters that no tolerance covers
/// (a parameter with a tolerance is determined by it, as in the user's
/// fixed set): with them free, noise and model error would move the arm
/// along them by tens of millimetres, so they are held at nominal
/// ([`crate::residuals::HoldTerm`]).
fn weak_untoleranced(
    start: &DhParams,
    full: Normal,
    free: &[usize],
    model: &ModelOptions,
    id: &Identification,
) -> Vec<crate::residuals::Hold> {
    let s_max = id.analysed_singular_values.first().copied().unwrap_or(0.0);
    crate::identify::weak_holds(start, full, &untoleranced(start, model, free), s_max)
}

/// The columns of `free` without a stated tolerance. A tolerance
/// determines its parameter as a fixed value would (the prior sees every
/// direction that moves it): only directions among these are open.
fn untoleranced(start: &DhParams, model: &ModelOptions, free: &[usize]) -> Vec<usize> {
    let sigmas = model.prior.as_ref().map(|t| t.sigmas_for(start));
    free.iter()
        .copied()
        .filter(|&c| sigmas.as_ref().is_none_or(|s| s[c].is_none()))
        .collect()
}

/// A correction column whose information, once the free geometry, the
/// frames and the corrections accepted before it are fitted, is below this
/// share of its own is held at its stated value: its effect is (to one part
/// in 10⁶ of its variance) what the others already do, and fitting it
/// would only trade it against them.
pub(crate) const CORRECTION_SEPARATION: f64 = 1e-6;

/// The free columns with the correction columns beyond geometry judged one
/// at a time, in the block's order, against the `free` geometry, the frames
/// and the corrections kept before: kept when the data separate it
/// ([`CORRECTION_SEPARATION`]), else held with why (by column).
#[allow(clippy::type_complexity)] // the free columns and the held ones
pub(crate) fn correction_columns(
    full: &Normal,
    layout: &Layout,
    free: Vec<usize>,
) -> Result<(Vec<usize>, Vec<(usize, String)>), CalibrationError> {
    let Some((_, corrections)) = layout.corrections() else {
        return Ok((free, Vec::new()));
    };
    let mut base: Vec<usize> = free
        .iter()
        .copied()
        .filter(|c| !corrections.contains(c))
        .collect();
    let mut held = Vec::new();
    let name = |c: usize| layout.parameter(c).map_or(String::new(), |p| p.name);
    for c in corrections.clone() {
        let cols: Vec<usize> = base.iter().copied().chain([c]).collect();
        let n = full.restrict(&cols).ok_or(CalibrationError::Shape)?;
        let k = cols.len();
        let m = nalgebra::DMatrix::from_row_slice(k, k, &n.jtj);
        let diag: Vec<f64> = (0..k).map(|i| m[(i, i)]).collect();
        // Round-off of a column that is nil (a joint's turn that moves no
        // probe) is not information: judged against the largest column.
        let largest = diag.iter().copied().fold(0.0, f64::max);
        if !(diag[k - 1] > 1e-20 * largest && diag[k - 1].is_finite()) {
            held.push((c, "moves no residual: these data do not see it".to_string()));
            continue;
        }
        let s = nalgebra::DMatrix::from_fn(k, k, |i, j| {
            let d = (diag[i] * diag[j]).sqrt();
            if d > 0.0 { m[(i, j)] / d } else { 0.0 }
        });
        let bb = s.view((0, 0), (k - 1, k - 1)).into_owned();
        let bc = s.view((0, k - 1), (k - 1, 1)).into_owned();
        let share = match bb.clone().cholesky() {
            Some(ch) => 1.0 - (bc.transpose() * ch.solve(&bc))[(0, 0)],
            None => 0.0,
        };
        if share >= CORRECTION_SEPARATION {
            base.push(c);
            continue;
        }
        // The column it is most like, by the cosine of their columns.
        let like = (0..k - 1)
            .max_by(|&a, &b| bc[(a, 0)].abs().total_cmp(&bc[(b, 0)].abs()))
            .map(|a| format!(" (most like {}: cos {:+.4})", name(cols[a]), bc[(a, 0)]))
            .unwrap_or_default();
        held.push((
            c,
            format!(
                "not separable from the fitted parameters by these data: {:.1e} of its \
                 information is its own{like}",
                share.max(0.0)
            ),
        ));
    }
    let mut out: Vec<usize> = base;
    out.sort_unstable();
    Ok((out, held))
}
