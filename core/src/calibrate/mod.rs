//! Calibration: the parameters that make the touches agree.
//!
//! [`calibrate`] fits the free parameters by Levenberg–Marquardt ([`lm`]) on
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
pub mod energy;
pub mod global;
pub mod lm;
pub mod validate;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

pub use anneal::{AnnealOptions, AnnealStep, AnnealStop, AnnealTrace, SwitchRule};
pub use global::{GlobalOptions, GlobalStop, GlobalTrace};
pub use lm::{
    LmIteration, LmOptions, LmResult, Termination, levenberg_marquardt, levenberg_marquardt_from,
};

use crate::dataset::DataSet;
use crate::identify::{
    Correlation, Identification, identify_from, open_directions_from, strong_correlations, to_user,
    unit,
};
use crate::kernel::{ArmKernel, KernelError};
use crate::params::{DhParams, ParamId, ParamKind};
use crate::residuals::{Noise, Weights, normal_equations};

/// Why a calibration could not run.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    /// The kernel refused the arm or the data.
    #[error(transparent)]
    Kernel(#[from] KernelError),
    /// A parameter vector of the wrong length (a bug, not user input).
    #[error("internal: parameter vector of the wrong length")]
    Shape,
    /// The start arm gives non-finite positions.
    #[error("the start arm gives positions that are not finite numbers")]
    NonFiniteStart,
    /// A name in the fixed set is not a parameter of the arm.
    #[error("unknown parameter `{name}`; parameters are {expected}")]
    UnknownParameter {
        /// The name given.
        name: String,
        /// The accepted names.
        expected: String,
    },
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
         parameters (--fix auto chooses them)",
        directions.join("; ")
    )]
    Unidentifiable {
        /// The open directions, in words.
        directions: Vec<String>,
    },
    /// Cross-validation folds that cannot be made.
    #[error("{0}")]
    Folds(String),
    /// A solver setting out of range.
    #[error("{0}")]
    Options(String),
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
        }
    }

    /// The method of a name.
    pub fn parse(s: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == s)
    }
}

/// Work and time of one phase of a solver. The time is not serialised, so
/// that the same seed gives the same `calibration.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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

    fn add_lm(&mut self, fit: &LmResult, seconds: f64) {
        self.cost_evaluations += fit.cost_evaluations;
        self.jacobian_evaluations += fit.jacobian_evaluations;
        self.seconds += seconds;
    }
}

/// Which parameters stay at their start values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FixSpec {
    /// [`identify`](crate::identify::identify)'s recommended set.
    Auto,
    /// These parameters (by their position in the fixed order).
    Columns(Vec<usize>),
}

impl FixSpec {
    /// Parses `auto` or comma-separated names (`theta1,d1,Bx`; `beta…` is
    /// accepted for `alpha…`) for an `n`-joint arm.
    ///
    /// ```
    /// use aacmm_core::calibrate::FixSpec;
    /// assert_eq!(FixSpec::parse("auto", 6).unwrap(), FixSpec::Auto);
    /// assert_eq!(FixSpec::parse("theta1, d1,beta6", 6).unwrap(), FixSpec::Columns(vec![18, 6, 17]));
    /// assert!(FixSpec::parse("theta9", 6).unwrap_err().to_string().contains("unknown parameter `theta9`"));
    /// ```
    pub fn parse(s: &str, joints: usize) -> Result<FixSpec, CalibrationError> {
        if s.trim() == "auto" {
            return Ok(FixSpec::Auto);
        }
        let names: Vec<String> = ParamId::all(joints).map(|p| p.to_string()).collect();
        s.split(',')
            .map(str::trim)
            .filter(|t| !t.is_empty())
            .map(|t| {
                let canonical = match t.strip_prefix("beta") {
                    Some(rest) => format!("alpha{rest}"),
                    None => t.to_string(),
                };
                names.iter().position(|n| *n == canonical).ok_or_else(|| {
                    CalibrationError::UnknownParameter {
                        name: t.to_string(),
                        expected: format!("{} … {}", names[0], names[names.len() - 1]),
                    }
                })
            })
            .collect::<Result<Vec<usize>, _>>()
            .map(FixSpec::Columns)
    }
}

/// Settings of [`calibrate`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CalibrateOptions {
    /// The fixed set.
    pub fix: FixSpec,
    /// What is known of the noise.
    pub noise: Noise,
    /// The solver.
    pub method: Method,
    /// LM's tolerances (every method but `sa` ends with LM).
    pub lm: LmOptions,
    /// The annealer's settings (`sa`, `hybrid`).
    pub anneal: AnnealOptions,
    /// The hybrid's switching rule.
    pub switch: SwitchRule,
    /// The global method's settings.
    pub global: GlobalOptions,
    /// Seed of every random draw (annealing moves, starts).
    pub seed: u64,
}

impl Default for CalibrateOptions {
    fn default() -> Self {
        CalibrateOptions {
            fix: FixSpec::Auto,
            noise: Noise {
                length_default_mm: DEFAULT_LENGTH_SIGMA_MM,
                ..Noise::default()
            },
            method: Method::default(),
            lm: LmOptions::default(),
            anneal: AnnealOptions::default(),
            switch: SwitchRule::default(),
            global: GlobalOptions::default(),
            seed: 0,
        }
    }
}

/// Largest relative change of the weights at the solution, against those of
/// the fit, that needs no refit: the estimate moves by about this fraction
/// of its σ.
pub const REWEIGH_TOLERANCE: f64 = 0.05;

/// σ of a reference length whose file states none, mm.
pub const DEFAULT_LENGTH_SIGMA_MM: f64 = 0.001;

/// One parameter's result, in user units (mm or deg).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
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
    /// Standard uncertainty; `None` for a fixed parameter.
    pub sigma: Option<f64>,
    /// Why it is fixed; `None` for a free parameter.
    pub fixed: Option<String>,
}

/// Residual and unknown counts, and the a-posteriori variance factor.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Dof {
    /// Touch residual rows (3 per touch).
    pub touch_rows: usize,
    /// Length residual rows.
    pub length_rows: usize,
    /// Free parameters.
    pub free_parameters: usize,
    /// Eliminated centre coordinates (3 per point).
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
}

/// The solver's account of itself.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SolverSummary {
    /// The method that ran.
    pub method: Method,
    /// Why the final LM stopped (`sa`: the annealing's stop, mapped to
    /// [`Termination::Annealed`]).
    pub termination: Termination,
    /// Whether that is a converged minimum.
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
    pub options: LmOptions,
    /// Work per phase, in order.
    pub phases: Vec<Phase>,
    /// The annealing (`sa`, `hybrid`).
    pub anneal: Option<AnnealTrace>,
    /// The global search (`global`).
    pub global: Option<GlobalTrace>,
}

/// The correlation matrix of the free parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CorrelationMatrix {
    /// The free parameters, in the fixed order.
    pub parameters: Vec<String>,
    /// `ρ_ij`, row by row.
    pub rho: Vec<Vec<f64>>,
}

/// What [`calibrate`] returns.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Calibration {
    /// The calibrated geometry (mm, rad; zero offsets wrapped to ±180°).
    #[serde(skip)]
    pub params: DhParams,
    /// Per parameter, in the fixed order.
    pub parameters: Vec<Estimate>,
    /// Free-parameter pairs with `|ρ| > 0.9`.
    pub correlations: Vec<Correlation>,
    /// Every correlation of the free parameters.
    pub correlation_matrix: CorrelationMatrix,
    /// Counts and the variance factor.
    pub dof: Dof,
    /// The solver.
    pub solver: SolverSummary,
    /// The identifiability analysis behind `--fix auto`.
    pub identification: Option<Identification>,
}

/// Calibrates `start` (the nominal arm) on `data`.
///
/// ```
/// use aacmm_core::{calibrate::*, io::Arm, params::DhParams, simulate::*};
/// let nominal = Arm::without_limits("nominal", DhParams::paper_nominal());
/// let mut settings = CampaignSettings::new(1, ErrorModel::Paper, 8, 10);
/// settings.reference_lengths = 3;
/// let campaign = simulate(&nominal, &settings).unwrap();
/// let data = campaign.data_set().unwrap();
/// let c = calibrate(&nominal.params, &data, &CalibrateOptions::default()).unwrap();
/// assert!(c.solver.successful);
/// assert_eq!(c.parameters.iter().filter(|p| p.fixed.is_none()).count(), 21);
/// ```
pub fn calibrate(
    start: &DhParams,
    data: &DataSet,
    options: &CalibrateOptions,
) -> Result<Calibration, CalibrationError> {
    calibrate_observed(start, data, options, &mut |_, _| {})
}

/// [`calibrate`], telling `progress` the phase running and the fraction of
/// it done (for a progress bar).
pub fn calibrate_observed(
    start: &DhParams,
    data: &DataSet,
    options: &CalibrateOptions,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<Calibration, CalibrationError> {
    let kernel = ArmKernel::new(start)?;
    let threads = options.lm.threads;
    let stated = options.noise.stated();
    let mut weights = Weights::new(&kernel, data, &options.noise, 1.0)?;
    // One pass over the data at the start serves the identifiability
    // analysis and, restricted to the free columns, the first LM step.
    let timer = std::time::Instant::now();
    let full = crate::identify::full_normal(start, data, &weights, threads)?;
    let (free, identification, reasons) = match &options.fix {
        FixSpec::Auto => {
            let id = identify_from(start, data, full.clone());
            let free = id.free_columns();
            let reasons: Vec<(String, String)> = id
                .fixed
                .iter()
                .map(|f| (f.name.clone(), f.reason.clone()))
                .collect();
            (free, Some(id), reasons)
        }
        FixSpec::Columns(fixed) => {
            let free: Vec<usize> = (0..start.param_count())
                .filter(|c| !fixed.contains(c))
                .collect();
            let directions = open_directions_from(start, data, full.clone(), &free);
            if !directions.is_empty() {
                return Err(CalibrationError::Unidentifiable { directions });
            }
            let reasons = fixed
                .iter()
                .filter_map(|&c| ParamId::from_column(start.joint_count(), c))
                .map(|id| (id.to_string(), "fixed by the user".to_string()))
                .collect();
            (free, None, reasons)
        }
    };
    let touch_rows = 3 * data.len();
    let length_rows = data.references().len();
    let centre_coordinates = 3 * data.points().len();
    let unknowns = free.len() + centre_coordinates;
    if touch_rows + length_rows <= unknowns {
        return Err(CalibrationError::TooFewResiduals {
            residuals: touch_rows + length_rows,
            unknowns,
            free: free.len(),
        });
    }
    let degrees_of_freedom = touch_rows + length_rows - unknowns;
    let identify_phase = Phase {
        jacobian_evaluations: 1,
        seconds: timer.elapsed().as_secs_f64(),
        ..Phase::new("identify")
    };
    let start_normal = full.restrict(&free).ok_or(CalibrationError::Shape)?;
    let solved = solve(
        start,
        start_normal,
        data,
        &weights,
        options,
        stated.then_some(degrees_of_freedom),
        progress,
    )?;
    let Solved {
        mut fit,
        mut phases,
        anneal,
        mut global,
    } = solved;
    phases.insert(0, identify_phase);
    let mut cost_evaluations: usize = phases.iter().map(|p| p.cost_evaluations).sum();
    let mut jacobian_evaluations: usize = phases.iter().map(|p| p.jacobian_evaluations).sum();
    let normal_at = |params: &DhParams, weights: &Weights| -> Result<_, CalibrationError> {
        Ok(normal_equations(
            &ArmKernel::new(params)?,
            data,
            weights,
            &free,
            threads,
        )?)
    };
    let sign_changes = global::normalize_signs(&mut fit.params, start, &free);
    if !sign_changes.is_empty() {
        // Same positions, other signs: the normal equations change sign
        // pattern, so recompute them for the covariance.
        fit.normal = normal_at(&fit.params, &weights)?;
        jacobian_evaluations += 1;
    }
    if let Some(g) = &mut global {
        g.sign_changes = sign_changes;
    }
    let mut touch_sigma = 1.0;
    if !stated {
        // Unit weights: the touch residuals are mm. Estimate σ so that the
        // lengths weigh right against the touches.
        let touch_dof = touch_rows
            .saturating_sub(centre_coordinates + free.len())
            .max(1);
        touch_sigma = (fit.normal.touch_cost / touch_dof as f64).sqrt().max(1e-9);
    }
    if stated || length_rows > 0 {
        // Weigh at the solution, not at the start: encoder noise moves the
        // probe along directions that depend on the arm, and the lengths'
        // weights on the centroids' directions — both far off when the
        // zeros were.
        let at_solution = Weights::new(
            &ArmKernel::new(&fit.params)?,
            data,
            &options.noise,
            touch_sigma,
        )?;
        let timer = std::time::Instant::now();
        // Weights that moved by under REWEIGH_TOLERANCE would move the
        // estimate by a like fraction of its σ and its σ not at all (shipped
        // campaign, lm: weights 3 % off moved no parameter by more than
        // 3.4 % of its σ, and σ by 1e-5 of itself): the fit's weights stand.
        let settled = stated && at_solution.relative_change(&weights) <= REWEIGH_TOLERANCE;
        if settled {
            // The fit's weights, normal equations and history stand.
        } else if options.method == Method::Sa {
            weights = at_solution;
            fit.normal = normal_at(&fit.params, &weights)?;
            jacobian_evaluations += 1;
        } else {
            weights = at_solution;
            let refit = levenberg_marquardt(&fit.params, data, &weights, &free, &options.lm)?;
            let mut phase = Phase::new("lm, weighed at the solution");
            phase.add_lm(&refit, timer.elapsed().as_secs_f64());
            // With stated noise the weights keep their units: one history,
            // the descent then the polish. Otherwise the units changed.
            fit = if stated { fit.then(refit) } else { refit };
            cost_evaluations += phase.cost_evaluations;
            jacobian_evaluations += phase.jacobian_evaluations;
            phases.push(phase);
        }
    } else {
        let w2 = 1.0 / (touch_sigma * touch_sigma);
        fit.normal.jtj.iter_mut().for_each(|v| *v *= w2);
        fit.normal.touch_cost *= w2;
        for h in &mut fit.history {
            h.cost *= w2;
        }
    }
    if stated {
        touch_sigma = weights.typical_touch_sigma();
    }
    // The start arm's cost under the final weights: "cost A -> B" compares
    // like with like whatever the method did in between.
    let mut xyz = vec![[0.0; 3]; data.len()];
    let mut initial_cost = crate::residuals::cost(&kernel, data, &weights, &mut xyz)?;
    cost_evaluations += 1;
    if !stated && length_rows == 0 {
        initial_cost /= touch_sigma * touch_sigma;
    }
    let sigma0 = (fit.normal.cost() / degrees_of_freedom as f64).sqrt();
    let p = free.len();
    let n = DMatrix::from_row_slice(p, p, &fit.normal.jtj);
    let cov = match n.cholesky() {
        Some(ch) => ch.inverse() * (sigma0 * sigma0),
        None => DMatrix::from_element(p, p, f64::INFINITY),
    };
    let joints = start.joint_count();
    let ids: Vec<ParamId> = ParamId::all(joints).collect();
    let names: Vec<String> = ids.iter().map(|i| i.to_string()).collect();
    let mut params = fit.params.clone();
    for j in &mut params.joints {
        j.theta = crate::simulate::wrap(j.theta);
    }
    let parameters = ids
        .iter()
        .enumerate()
        .map(|(c, &id)| {
            let (nominal, calibrated) = (to_user(id, start.get(id)), to_user(id, params.get(id)));
            let correction = if id.kind == ParamKind::Theta {
                crate::simulate::wrap(params.get(id) - start.get(id)).to_degrees()
            } else {
                calibrated - nominal
            };
            let sigma = free
                .iter()
                .position(|&f| f == c)
                .map(|a| to_user(id, cov[(a, a)].max(0.0).sqrt()));
            Estimate {
                name: names[c].clone(),
                unit: unit(id).into(),
                nominal,
                calibrated,
                correction,
                sigma: sigma.filter(|s| s.is_finite()),
                fixed: reasons
                    .iter()
                    .find(|(n, _)| *n == names[c])
                    .map(|(_, r)| r.clone()),
            }
        })
        .collect();
    let free_names: Vec<String> = free.iter().map(|&c| names[c].clone()).collect();
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
    let successful = fit.termination.was_successful()
        && global.as_ref().is_none_or(|g| g.stop.confirmed())
        && anneal
            .as_ref()
            .is_none_or(|a| a.stop != AnnealStop::EvaluationBudget);
    Ok(Calibration {
        parameters,
        correlations: strong_correlations(&cov, &free, &names),
        correlation_matrix: CorrelationMatrix {
            parameters: free_names,
            rho,
        },
        dof: Dof {
            touch_rows,
            length_rows,
            free_parameters: p,
            centre_coordinates,
            degrees_of_freedom,
            sigma0,
            touch_sigma_mm: touch_sigma,
            touch_sigma_estimated: !stated,
        },
        solver: SolverSummary {
            method: options.method,
            termination: fit.termination,
            successful,
            iterations: fit.iterations,
            cost_evaluations,
            jacobian_evaluations,
            initial_cost,
            final_cost: fit.normal.cost(),
            history: fit.history,
            options: options.lm,
            phases,
            anneal,
            global,
        },
        identification,
        params,
    })
}

/// What a solver hands back to [`calibrate`].
struct Solved {
    fit: LmResult,
    phases: Vec<Phase>,
    anneal: Option<AnnealTrace>,
    global: Option<GlobalTrace>,
}

/// Runs `options.method` on the free columns.
fn solve(
    start: &DhParams,
    start_normal: crate::residuals::Normal,
    data: &DataSet,
    weights: &Weights,
    options: &CalibrateOptions,
    stated_dof: Option<usize>,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<Solved, CalibrationError> {
    let free = &start_normal.free.clone();
    let mut rng = crate::simulate::rng(options.seed, SOLVER_STREAM);
    let timer = std::time::Instant::now();
    match options.method {
        Method::Lm => {
            let fit =
                lm::levenberg_marquardt_from(start, start_normal, data, weights, &options.lm)?;
            let mut phase = Phase::new("lm");
            phase.add_lm(&fit, timer.elapsed().as_secs_f64());
            Ok(Solved {
                fit,
                phases: vec![phase],
                anneal: None,
                global: None,
            })
        }
        Method::Sa | Method::Hybrid => {
            let hybrid = options.method == Method::Hybrid;
            let (best, trace) = anneal::anneal_observed(
                start,
                data,
                free,
                &options.anneal,
                hybrid.then_some(&options.switch),
                &mut rng,
                &mut |f| progress("anneal", f),
            )?;
            let mut phases = vec![Phase {
                cost_evaluations: trace.evaluations,
                seconds: timer.elapsed().as_secs_f64(),
                ..Phase::new("anneal")
            }];
            let fit = if hybrid {
                let timer = std::time::Instant::now();
                let fit = levenberg_marquardt(&best, data, weights, free, &options.lm)?;
                let mut phase = Phase::new("lm");
                phase.add_lm(&fit, timer.elapsed().as_secs_f64());
                phases.push(phase);
                fit
            } else {
                let normal = normal_equations(
                    &ArmKernel::new(&best)?,
                    data,
                    weights,
                    free,
                    options.lm.threads,
                )?;
                phases[0].jacobian_evaluations = 1;
                LmResult {
                    params: best,
                    termination: if trace.stop == AnnealStop::EvaluationBudget {
                        Termination::MaxIterations
                    } else {
                        Termination::Annealed
                    },
                    iterations: 0,
                    cost_evaluations: 0,
                    jacobian_evaluations: 1,
                    initial_cost: start_normal.cost(),
                    history: Vec::new(),
                    normal,
                }
            };
            Ok(Solved {
                fit,
                phases,
                anneal: Some(trace),
                global: None,
            })
        }
        Method::Global => {
            let problem = global::GlobalProblem {
                data,
                noise: &options.noise,
                weights,
                free,
                lm: &options.lm,
                stated_dof,
                start_normal: Some(start_normal),
            };
            let (fit, trace, phases) =
                global::global(start, &problem, &options.global, &mut rng, &mut |f| {
                    progress("global", f)
                })?;
            Ok(Solved {
                fit,
                phases,
                anneal: None,
                global: Some(trace),
            })
        }
    }
}

/// The random stream of the solvers (apart from the simulator's streams).
const SOLVER_STREAM: u64 = 0x50_4c_56;
