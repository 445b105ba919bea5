//! Experiment design: which poses to measure, and how well a calibration
//! will know the arm where it is used.
//!
//! A plan picks `K` rows of a pool of candidate poses (touches of sockets,
//! or positions an instrument will see) greedily, each step taking the
//! candidate that most lowers the **mean predicted variance of a probe
//! position over the workspace** (I-optimality, `tr(W C)`: `C` the free
//! geometry's covariance given the rows, `W` the mean `JᵀJ` of the poses
//! where the arm will be used — the candidates themselves unless a
//! workspace is given). D-optimality (`ln det M`) rewards the extreme poses
//! that stretch the information ellipsoid, and those are where the errors
//! no geometric model explains (compliance, bending, heat) are largest: it
//! gains at a few poses and loses at many. The default criterion
//! ([`Criterion::Robust`]) guards against that by representing the pool:
//! the candidates are split into `K` strata of look-alike poses (k-means on
//! each joint's `cos q`, `sin q`) and each stratum gives one row, the one
//! that lowers the criterion most. A fit to rows that represent the
//! workspace averages the unexplained errors as the fit to every pose
//! would; rows gathered where the information is largest fit those poses'
//! errors instead. Measured (`examples/plan_compare.rs`, docs/plan.md): on
//! the UR5 tracker data the free I-optimal choice loses to random subsets
//! by up to a fifth, the stratified one does not. An optional hedge `τ`
//! further counts each candidate's rows as noisier by `1 + τ² h_i/h̄`
//! (`h_i` its leverage within the pool; from a previous calibration's
//! `σ̂₀` when given).
//!
//! The rows are those of [`crate::residuals`]: positions through the
//! instrument's frame (fitted with the arm, so its six columns are in the
//! design), touches with each socket's centre eliminated (a socket's first
//! touch tells nothing; each later one its difference from the mean of
//! those before). The free columns are [`crate::identify`]'s for the whole
//! pool, or a given calibration's.

// The 95 % radii live with the statistics, where the calibration's
// assessment finds them too; here under the name plans have used.
pub use crate::stats::coverage;
mod greedy;
pub mod map;
mod pending;
pub(crate) mod pool;
mod rows;
mod strata;
pub(crate) mod summary;

use nalgebra::DMatrix;
use rand::seq::SliceRandom;
use serde::{Deserialize, Serialize};

pub use map::{
    InFrame, MapPoint, Prediction, Region, UncertaintyMap, position_covariances, sample_poses,
    uncertainty_map, uncertainty_map_at_tool, uncertainty_map_in_frame,
};

pub(crate) use map::reading_ranges;
pub use pool::{
    DEFAULT_SOCKETS, Pool, SampleError, sample_positions, sample_sphere_points, sample_touches,
    sample_touches_observed, sphere_candidates,
};
pub use summary::{GivenNote, SummaryContext, summary};

use crate::dataset::DataSet;
use crate::domain::{DEFAULT_FRAME, Poses, Positions};
use crate::kernel::{ArmKernel, PreparedPoses};
use crate::params::{ChainShape, DhParams};
use crate::residuals::Noise;
use greedy::{Gain, Greedy};
use rows::{Blocks, jacobians, mean_gram, scaled, unit_scale};

/// What the campaign will measure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum Measure {
    /// Positions an instrument sees (laser tracker, artefact), in its frame.
    Positions,
    /// Touches of sockets; the candidates' labels are the sockets.
    Touches,
    /// Points probed on the surface of reference spheres; the candidates'
    /// labels are the spheres (placements), each one's centre — and its
    /// diameter unless [`PlanSettings::sphere_diameter_stated`] — fitted
    /// with the arm.
    Spheres,
}

/// What a plan optimises.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Criterion {
    /// The mean predicted position variance over the workspace, one row
    /// from each of `K` strata of look-alike candidates (see the module):
    /// the default.
    Robust,
    /// The same over all candidates freely (plain I-optimality).
    Prediction,
    /// Greedy D-optimality, for comparison.
    Determinant,
}

/// Touches a plan gives each socket it uses at least.
pub(crate) const MIN_TOUCHES_PER_SOCKET: usize = 3;

/// Workspace poses the criterion and the reported spreads use at most (an
/// even sample of a larger workspace).
pub const WORKSPACE_POSES: usize = 500;

/// The weak prior `ε I` (scaled columns, unit noise) that makes the first
/// steps' covariance finite.
const EPSILON: f64 = 1e-6;

/// How a plan is made.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanSettings {
    /// Rows to choose.
    pub count: usize,
    /// Touches or positions.
    pub(crate) measure: Measure,
    /// What is optimised.
    pub criterion: Criterion,
    /// `τ`: the unexplained error at a pose of average leverage, in units
    /// of the noise (used by [`Criterion::Robust`]).
    pub hedge: f64,
    /// Noise of one row per coordinate, mm: scales every predicted
    /// uncertainty (not the choice).
    pub sigma_mm: f64,
    /// Random subsets of the same size the plan is compared with.
    pub random_sets: usize,
    /// The greedy continues to this many rows to show where more stops
    /// paying (at least `count`).
    pub curve_to: usize,
    /// Seed of the random subsets.
    pub seed: u64,
    /// Workspace poses the criterion and the reported spreads use at most
    /// (an even sample of a larger workspace): each costs a Jacobian and
    /// its share of every step's work.
    pub workspace_limit: usize,
    /// Spheres: their diameter will be stated to the calibration, so that
    /// only each sphere's centre is fitted, not its size (default: fitted).
    pub sphere_diameter_stated: bool,
}

impl PlanSettings {
    /// `count` rows of `measure`, robust criterion, τ = 0, σ = 0.01 mm,
    /// 10 random sets, the curve to twice the count, seed 1, at most
    /// [`WORKSPACE_POSES`] workspace poses.
    pub fn new(count: usize, measure: Measure) -> PlanSettings {
        PlanSettings {
            count,
            measure,
            criterion: Criterion::Robust,
            hedge: 0.0,
            sigma_mm: 0.01,
            random_sets: 10,
            curve_to: 2 * count,
            seed: 1,
            workspace_limit: WORKSPACE_POSES,
            sphere_diameter_stated: false,
        }
    }
}

/// A previous calibration the plan adds to: what it knows already.
#[derive(Clone, Debug, PartialEq)]
pub struct Given {
    /// Its free geometry columns.
    pub(crate) free: Vec<usize>,
    /// Their covariance, mm and rad.
    pub(crate) cov: DMatrix<f64>,
    /// σ of one new row per coordinate (its own estimate), mm.
    pub(crate) sigma_mm: f64,
    /// Its `σ̂₀` (residuals against the stated noise), when noise was stated.
    pub(crate) sigma0: Option<f64>,
    /// Whether it fitted an instrument frame: new positions are taken in
    /// that frame, as known.
    pub(crate) frame_known: bool,
}

/// Why a plan cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// Settings or candidates that make no plan.
    #[error("{0}")]
    Invalid(String),
    /// The kernel's.
    #[error(transparent)]
    Kernel(#[from] crate::kernel::KernelError),
    /// The identifiability analysis of the pool.
    #[error("identifiability of the candidates: {0}")]
    Identify(String),
}

/// The predicted uncertainty of a design over the workspace: the 95 %
/// radius ([`coverage::radius`]) pose by pose.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// RMS over the workspace, mm.
    pub(crate) rms_mm: f64,
    /// Median, mm.
    pub(crate) median_mm: f64,
    /// Largest, mm.
    pub(crate) max_mm: f64,
}

impl Spread {
    /// RMS of the 95 % radius over the workspace, mm.
    pub fn rms_mm(&self) -> f64 {
        self.rms_mm
    }

    /// Its median, mm.
    pub fn median_mm(&self) -> f64 {
        self.median_mm
    }

    /// Its largest, mm.
    pub fn max_mm(&self) -> f64 {
        self.max_mm
    }
}

/// One chosen row, in the order chosen.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Step {
    /// Row of the pool (0-based).
    pub row: usize,
    /// Its label.
    pub label: String,
    /// The mean predicted variance over the workspace with the rows up to
    /// this one (plain, without the hedge), as the 95 % radius of an
    /// isotropic error of that variance, mm; `None` while the rows do not
    /// determine every free parameter.
    pub criterion_mm: Option<f64>,
}

/// The predicted uncertainty after the first `rows` choices.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurvePoint {
    /// Rows chosen.
    pub rows: usize,
    /// The workspace's RMS 95 % radius, mm; `None` while the rows do not
    /// yet determine every free parameter.
    pub(crate) rms_mm: Option<f64>,
}

/// How far a joint turns over the chosen rows against the pool.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointSpan {
    /// Joint, from 1.
    pub joint: usize,
    /// Range of the chosen readings, degrees (mm for a prismatic joint).
    pub chosen_deg: f64,
    /// Range of the pool's, degrees (mm for a prismatic joint).
    pub pool_deg: f64,
    /// Whether the joint is prismatic: its spans are mm.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub prismatic: bool,
}

/// The random subsets a plan is compared with.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct RandomBaseline {
    /// Subsets drawn.
    pub(crate) sets: usize,
    /// Those whose rows determine every free parameter.
    pub(crate) determined: usize,
    /// The median subset's spread (undetermined ones count as worst).
    pub(crate) median: Option<Spread>,
}

/// A plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// What is measured.
    pub(crate) measure: Measure,
    /// What was optimised.
    pub(crate) criterion: Criterion,
    /// Candidates in the pool.
    pub(crate) candidates: usize,
    /// Rows chosen (the first `count` of [`Plan::steps`]).
    pub count: usize,
    /// The rows chosen, then those the curve continued with.
    pub steps: Vec<Step>,
    /// The parameters the design is for (free geometry, then the frame's).
    pub parameters: Vec<String>,
    /// Noise of a row per coordinate, mm.
    pub(crate) sigma_mm: f64,
    /// `τ` of the robust criterion (0 for the others).
    pub(crate) hedge: f64,
    /// Strata the robust criterion took one row from each of (0 for the
    /// others).
    pub(crate) strata: usize,
    /// Whether a previous calibration's knowledge was the start.
    pub(crate) given: bool,
    /// The workspace the spreads are over, in words, and its poses.
    pub(crate) workspace: String,
    /// Poses of the workspace used.
    pub(crate) workspace_poses: usize,
    /// Poses of the workspace given (or candidates): more than
    /// [`Plan::workspace_poses`] when an even sample of them was used
    /// ([`PlanSettings::workspace_limit`]).
    #[serde(default)]
    pub(crate) workspace_total: usize,
    /// The predicted uncertainty with the chosen rows.
    pub planned: Option<Spread>,
    /// With every candidate.
    pub all: Option<Spread>,
    /// With the given calibration alone, before any new row (`None`
    /// without one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<Spread>,
    /// With random subsets of the same size.
    pub(crate) random: RandomBaseline,
    /// The predicted uncertainty as rows are added.
    pub curve: Vec<CurvePoint>,
    /// Rows chosen per socket or sphere (touches and sphere points only).
    pub sockets: Vec<(String, usize)>,
    /// How far each joint turns over the chosen rows.
    pub joints: Vec<JointSpan>,
    /// What the user should know.
    pub warnings: Vec<String>,
}

impl Plan {
    /// What the plan is for: positions, touches or sphere points.
    pub fn measure(&self) -> Measure {
        self.measure
    }

    /// The spread of the median random subset of the plan's size
    /// (undetermined subsets counted as the worst); `None` when none was
    /// drawn or the median one does not determine every parameter.
    pub fn random_median(&self) -> Option<Spread> {
        self.random.median
    }

    /// The chosen rows of the pool, in the order chosen.
    pub fn chosen(&self) -> Vec<usize> {
        self.steps[..self.count].iter().map(|s| s.row).collect()
    }

    /// The fewest rows of the curve that determine every free parameter
    /// (`None` when none of its points does).
    pub fn rows_needed(&self) -> Option<usize> {
        self.curve
            .iter()
            .find(|c| c.rms_mm.is_some())
            .map(|c| c.rows)
    }

    /// Why no subset of the candidates can make a plan, when even all of
    /// them do not determine every free parameter; `None` when they do.
    pub fn pool_undetermined(&self) -> Option<String> {
        if self.all.is_some() {
            return None;
        }
        Some(format!(
            "even all {} candidates do not determine the {} parameters ({}): no subset can; \
             add candidates that turn the joints further{}",
            self.candidates,
            self.parameters.len(),
            self.parameters.join(", "),
            match self.measure {
                Measure::Touches => ", or touches of more sockets",
                Measure::Spheres => ", or points on more spheres",
                Measure::Positions => "",
            }
        ))
    }
}

/// The design problem: the candidates' scaled rows, the workspace, groups.
struct Design {
    blocks: Blocks,
    /// Per candidate its stratum ([`strata`]); empty without strata.
    stratum: Vec<usize>,
    scale: Vec<f64>,
    workspace: Blocks,
    w: Vec<f64>,
    group: Vec<usize>,
    sockets: Vec<String>,
    touches: bool,
    /// Rows a group (socket, sphere) opens with; `None` for positions.
    seeds: Option<usize>,
    /// Columns each sphere adds after the geometry's (0 for touches and
    /// positions).
    per_sphere: usize,
    /// The candidates' nominal probe positions (spheres only: their seeds
    /// are spread over the surface).
    positions: Vec<[f64; 3]>,
    geometry: usize,
    sigma: f64,
}

impl Design {
    /// Whether a group's rows tell the arm anything when `n` of them are
    /// chosen: a sphere's only beyond its own unknowns (spheres only ask:
    /// a socket's mean is eliminated through its deviations instead).
    fn informs(&self, n: usize) -> bool {
        n > self.per_sphere
    }
}

/// Chooses `settings.count` rows of `pool` for `params`; `workspace` is
/// where the arm will be used (the pool when `None`), `given` a previous
/// calibration to add to.
///
/// # Errors
///
/// A pool of another joint count, fewer candidates than the count, a pool
/// that determines nothing, the kernel's.
pub fn plan(
    params: &DhParams,
    pool: &Poses,
    workspace: Option<&Poses>,
    given: Option<&Given>,
    settings: &PlanSettings,
) -> Result<Plan, PlanError> {
    check(params, pool, workspace, settings)?;
    let (free, frame) = columns(params, pool, given, settings)?;
    let design = design(params, pool, workspace, &free, frame, given, settings)?;
    let hedge = hedge_of(given, settings);
    let weight = hedge_weights(&design, hedge);
    let prior = given.map(|g| prior_information(g, &design));
    let gain = match settings.criterion {
        Criterion::Determinant => Gain::Determinant,
        _ => Gain::Prediction,
    };
    let mut greedy = Greedy::new(
        &design.blocks,
        &design.w,
        &weight,
        &design.group,
        design.touches,
        prior.as_ref(),
        EPSILON,
        gain,
    )
    .ok_or_else(|| PlanError::Invalid("the candidates' information is not finite".into()))?;
    let to = settings.curve_to.clamp(settings.count, pool.len());
    let rows = choose(&mut greedy, &design, settings.count, to);
    let chosen = &rows[..settings.count];
    let report = Evaluation {
        design: &design,
        prior: prior.as_ref(),
    };
    // Each prefix's covariance once: its criterion for the ranking, and at
    // the curve's checkpoints (the count among them) its spread.
    let marks = checkpoints(settings.count, to);
    let (mut steps, mut curve, mut planned) = (Vec::new(), Vec::new(), None);
    for (k, c) in (1..=rows.len()).zip(report.prefix_covariances(&rows)) {
        steps.push(Step {
            row: rows[k - 1],
            label: pool.label(rows[k - 1]).to_string(),
            criterion_mm: c.as_ref().map(|c| report.criterion_of(c)),
        });
        if marks.contains(&k) {
            let spread = c.as_ref().map(|c| report.spread_of(c));
            curve.push(CurvePoint {
                rows: k,
                rms_mm: spread.map(|s| s.rms_mm),
            });
            if k == settings.count {
                planned = spread;
            }
        }
    }
    let all = report.spread(&(0..pool.len()).collect::<Vec<_>>());
    let start = given.and_then(|_| report.spread(&[]));
    let random = report.random(pool.len(), settings);
    let joints = joint_spans(pool, chosen);
    let sockets = socket_counts(&design, chosen);
    let warnings = warnings(&joints, planned.is_none(), settings);
    Ok(Plan {
        measure: settings.measure,
        criterion: settings.criterion,
        candidates: pool.len(),
        count: settings.count,
        steps,
        parameters: [
            parameter_names(params, &free, frame),
            sphere_parameter_names(&design),
        ]
        .concat(),
        sigma_mm: design.sigma,
        hedge,
        strata: design.stratum.iter().max().map_or(0, |m| m + 1),
        given: given.is_some(),
        workspace: if workspace.is_some() {
            "the given workspace"
        } else {
            "the candidates"
        }
        .to_string(),
        workspace_poses: design.workspace.len(),
        workspace_total: workspace.unwrap_or(pool).len(),
        planned,
        all,
        start,
        random,
        curve,
        sockets,
        joints,
        warnings,
    })
}

/// `τ` of the hedge: the setting's, or a given calibration's
/// `sqrt(σ̂₀² − 1)` when larger; 0 for the criteria without the hedge.
fn hedge_of(given: Option<&Given>, settings: &PlanSettings) -> f64 {
    match settings.criterion {
        Criterion::Robust => given.and_then(|g| g.sigma0).map_or(settings.hedge, |s0| {
            (s0 * s0 - 1.0).max(0.0).sqrt().max(settings.hedge)
        }),
        _ => 0.0,
    }
}

/// The design's columns by name: the free geometry's, then the frame's.
fn parameter_names(params: &DhParams, free: &[usize], frame: bool) -> Vec<String> {
    let ids: Vec<String> = params.param_ids().map(|i| i.to_string()).collect();
    let mut names: Vec<String> = free.iter().map(|&c| ids[c].clone()).collect();
    if frame {
        names.extend(["rx", "ry", "rz", "tx", "ty", "tz"].map(|n| format!("frame {n}")));
    }
    names
}

/// The spheres' own columns by name, after the geometry's: each centre's
/// `x, y, z` and, when fitted, its radius.
fn sphere_parameter_names(design: &Design) -> Vec<String> {
    if design.per_sphere == 0 {
        return Vec::new();
    }
    let fitted = design.per_sphere == rows::sphere_columns(false);
    let mut names = Vec::new();
    for s in &design.sockets {
        names.extend(["x", "y", "z"].map(|k| format!("sphere.{s}.{k}")));
        if fitted {
            names.push(format!("sphere.{s}.radius"));
        }
    }
    names
}

fn check(
    params: &DhParams,
    pool: &Poses,
    workspace: Option<&Poses>,
    settings: &PlanSettings,
) -> Result<(), PlanError> {
    let n = params.joint_count();
    if pool.joints() != n || workspace.is_some_and(|w| w.joints() != n) {
        return Err(PlanError::Invalid(format!(
            "the arm has {n} joints, the candidates {} readings per row",
            pool.joints()
        )));
    }
    if settings.count == 0 || settings.count > pool.len() {
        return Err(PlanError::Invalid(format!(
            "count {}: choose between 1 and the {} candidates",
            settings.count,
            pool.len()
        )));
    }
    let sigma_ok = settings.sigma_mm > 0.0 && settings.sigma_mm.is_finite();
    if !(sigma_ok && settings.hedge >= 0.0 && settings.hedge.is_finite()) {
        return Err(PlanError::Invalid(
            "the noise must be positive and finite, the hedge τ ≥ 0".into(),
        ));
    }
    if settings.workspace_limit == 0 {
        return Err(PlanError::Invalid(
            "workspace limit 0: the criterion needs at least one workspace pose".into(),
        ));
    }
    if settings.measure == Measure::Touches && settings.count < MIN_TOUCHES_PER_SOCKET {
        return Err(PlanError::Invalid(format!(
            "count {}: touches need at least {MIN_TOUCHES_PER_SOCKET} touches of a socket",
            settings.count
        )));
    }
    if let (Measure::Spheres, Some(min)) = (settings.measure, seeds(settings))
        && settings.count < min
    {
        return Err(PlanError::Invalid(format!(
            "count {}: points on a sphere tell the arm something beyond the sphere's {} \
             unknowns from the next; a plan gives a sphere at least {min}",
            settings.count,
            min - SPHERE_ROWS_BEYOND
        )));
    }
    Ok(())
}

/// The free geometry columns (the given calibration's, or what the whole
/// pool determines), and whether a frame is estimated.
fn columns(
    params: &DhParams,
    pool: &Poses,
    given: Option<&Given>,
    settings: &PlanSettings,
) -> Result<(Vec<usize>, bool), PlanError> {
    let positions = settings.measure == Measure::Positions;
    if let Some(g) = given {
        return Ok((g.free.clone(), positions && !g.frame_known));
    }
    let id = if settings.measure == Measure::Spheres {
        sphere_identification(params, pool, settings)?
    } else {
        let data = pool_data(params, pool, positions)?;
        let noise = Noise {
            position_mm: Some(settings.sigma_mm),
            ..Noise::default()
        };
        crate::identify::identify(params, &data, &noise, 1)
            .map_err(|e| PlanError::Identify(e.to_string()))?
    };
    let free = id.free_columns();
    if free.is_empty() {
        return Err(PlanError::Invalid(
            "the candidates determine no parameter of the arm".into(),
        ));
    }
    Ok((free, positions))
}

/// What points on the pool's spheres determine: the analysis of the
/// sphere term alone, each sphere's centre (and, unless stated, its size)
/// eliminated. The stated size's value does not matter (the rows' normals
/// do not depend on it): the term is given one in range and a ball of 0.
fn sphere_identification(
    params: &DhParams,
    pool: &Poses,
    settings: &PlanSettings,
) -> Result<crate::identify::Identification, PlanError> {
    use crate::residuals::spheres::{SphereSize, SphereTerm, add_to};
    let mut spheres = crate::domain::Spheres::new(pool.joints(), pool.prismatic_mask());
    for i in 0..pool.len() {
        spheres.push(pool.label(i), pool.reading(i), pool.line(i), None);
    }
    let size = if settings.sphere_diameter_stated {
        SphereSize::Known(crate::simulate::DEFAULT_SPHERE_DIAMETER_MM)
    } else {
        SphereSize::Fitted
    };
    let noise = Noise {
        probe_mm: Some(settings.sigma_mm),
        ..Noise::default()
    };
    let add = |layout: &mut crate::residuals::Layout| {
        let term = SphereTerm::new(
            spheres.clone(),
            "<candidates>",
            params,
            size,
            Some(0.0),
            &noise,
            add_to(layout),
        )?;
        Ok(vec![Box::new(term) as Box<dyn crate::residuals::Term>])
    };
    let data = DataSet::without_touches(pool.joints(), pool.prismatic_mask());
    crate::identify::identify_with(params, &data, &noise, Some(&add), 1)
        .map_err(|e| PlanError::Identify(e.to_string()))
}

/// The pool as a data set the identifiability analysis reads: touches as
/// they are, positions where the nominal arm puts them.
fn pool_data(params: &DhParams, pool: &Poses, positions: bool) -> Result<DataSet, PlanError> {
    let bad = |e: crate::error::InputError| PlanError::Invalid(e.to_string());
    if !positions {
        return DataSet::from_poses(pool, "<candidates>").map_err(bad);
    }
    let kernel = ArmKernel::new(params)?;
    let mut rows = Positions::new(pool.joints());
    if let Ok(shape) = ChainShape::from_mask(pool.joints(), pool.prismatic_mask()) {
        rows = rows.with_shape(shape);
    }
    for i in 0..pool.len() {
        let q = pool.reading(i);
        rows.push(
            pool.label(i),
            DEFAULT_FRAME,
            q,
            kernel.position(q)?,
            None,
            pool.line(i),
        );
    }
    DataSet::from_positions(rows, "<candidates>").map_err(bad)
}

/// The poses of `poses` as the kernel takes them.
fn prepared(poses: &Poses) -> PreparedPoses {
    let prismatic = poses.prismatic_mask();
    PreparedPoses::from_flat_with(poses.joints(), prismatic, poses.len(), poses.readings())
}

/// The scaled rows of the pool and the workspace.
#[allow(clippy::too_many_arguments)]
fn design(
    params: &DhParams,
    pool: &Poses,
    workspace: Option<&Poses>,
    free: &[usize],
    frame: bool,
    given: Option<&Given>,
    settings: &PlanSettings,
) -> Result<Design, PlanError> {
    let (group, sockets) = groups(pool);
    let spheres = settings.measure == Measure::Spheres;
    let stated = settings.sphere_diameter_stated;
    let (raw, positions) = if spheres {
        let (b, at) = rows::sphere_rows(params, &prepared(pool), free, &group, &sockets, stated)?;
        (b, at)
    } else {
        (
            jacobians(params, &prepared(pool), free, frame)?.0,
            Vec::new(),
        )
    };
    let scale = unit_scale(&raw);
    let blocks = scaled(raw, &scale);
    let ws = workspace.unwrap_or(pool);
    let step = ws.len().div_ceil(settings.workspace_limit).max(1);
    let mut sample = ws.empty_like(0);
    for i in (0..ws.len()).step_by(step) {
        sample.push(ws.label(i), ws.reading(i), ws.line(i));
    }
    let (wraw, _) = jacobians(params, &prepared(&sample), free, frame)?;
    let mut wraw = rows::widened(wraw, blocks.p);
    // Where the arm is used, only the geometry moves the probe: the frame
    // is the instrument's, not the arm's.
    let g = free.len();
    for row in wraw.j.chunks_exact_mut(wraw.p) {
        row[g..].iter_mut().for_each(|v| *v = 0.0);
    }
    let workspace = scaled(wraw, &scale);
    let w = mean_gram(&workspace);
    let stratum = match settings.criterion {
        Criterion::Robust => strata::strata(
            pool,
            settings.count.div_ceil(ROWS_PER_STRATUM),
            settings.seed,
        ),
        _ => Vec::new(),
    };
    Ok(Design {
        blocks,
        stratum,
        scale,
        workspace,
        w,
        group,
        sockets,
        touches: settings.measure == Measure::Touches,
        seeds: seeds(settings),
        per_sphere: if spheres {
            rows::sphere_columns(stated)
        } else {
            0
        },
        positions,
        geometry: g,
        sigma: given.map_or(settings.sigma_mm, |g| g.sigma_mm),
    })
}

/// Rows a group opens with: [`MIN_TOUCHES_PER_SOCKET`] touches of a
/// socket; a sphere's own unknowns and [`SPHERE_ROWS_BEYOND`] points more;
/// `None` for positions.
fn seeds(settings: &PlanSettings) -> Option<usize> {
    match settings.measure {
        Measure::Positions => None,
        Measure::Touches => Some(MIN_TOUCHES_PER_SOCKET),
        Measure::Spheres => {
            Some(rows::sphere_columns(settings.sphere_diameter_stated) + SPHERE_ROWS_BEYOND)
        }
    }
}

/// Points a plan gives each sphere beyond its own unknowns at least: the
/// rows that inform the arm (and show a point off the sphere).
pub(crate) const SPHERE_ROWS_BEYOND: usize = 2;

/// Each candidate's group (its label's place among the labels, in order
/// of first appearance), and the labels.
fn groups(pool: &Poses) -> (Vec<usize>, Vec<String>) {
    let mut labels: Vec<String> = Vec::new();
    let mut index: std::collections::HashMap<String, usize> = std::collections::HashMap::new();
    let group = (0..pool.len())
        .map(|i| {
            let l = pool.label(i);
            *index.entry(l.to_string()).or_insert_with(|| {
                labels.push(l.to_string());
                labels.len() - 1
            })
        })
        .collect();
    (group, labels)
}

/// Each candidate's weight `1/(1 + τ² h_i/h̄)`, `h_i` its leverage within
/// the whole pool (its rows' `tr(d M⁻¹ dᵀ)`, touches about their socket's
/// mean).
fn hedge_weights(design: &Design, tau: f64) -> Vec<f64> {
    let n = design.blocks.len();
    if tau == 0.0 {
        return vec![1.0; n];
    }
    let rows = deviations(design, &(0..n).collect::<Vec<_>>());
    let p = design.blocks.p;
    let m = gram(&rows, p) + DMatrix::identity(p, p) * EPSILON;
    let Some(c) = m.cholesky().map(|c| crate::residuals::cholesky_inverse(&c)) else {
        return vec![1.0; n];
    };
    let h: Vec<f64> = rows
        .iter()
        .map(|(_, d)| {
            let s = map::sandwich(d, &c, p);
            s[0][0] + s[1][1] + s[2][2]
        })
        .collect();
    let mean = h.iter().sum::<f64>() / n.max(1) as f64;
    h.iter()
        .map(|&v| 1.0 / (1.0 + tau * tau * v / mean.max(f64::MIN_POSITIVE)))
        .collect()
}

/// The rows of `chosen` as the fit sees them: positions as they are,
/// touches less their socket's mean over `chosen`.
fn deviations(design: &Design, chosen: &[usize]) -> Vec<(usize, Vec<f64>)> {
    let p = design.blocks.p;
    let mut rows: Vec<(usize, Vec<f64>)> = chosen
        .iter()
        .map(|&i| (i, design.blocks.at(i).to_vec()))
        .collect();
    if design.touches {
        for s in 0..design.sockets.len() {
            let idx: Vec<usize> = (0..rows.len())
                .filter(|&r| design.group[rows[r].0] == s)
                .collect();
            let mut mean = vec![0.0; 3 * p];
            for &r in &idx {
                for (m, v) in mean.iter_mut().zip(&rows[r].1) {
                    *m += v / idx.len() as f64;
                }
            }
            for &r in &idx {
                for (v, m) in rows[r].1.iter_mut().zip(&mean) {
                    *v -= m;
                }
            }
        }
    }
    rows
}

/// `Σ dᵀ d` of 3 × p blocks.
fn gram(rows: &[(usize, Vec<f64>)], p: usize) -> DMatrix<f64> {
    let mut m = DMatrix::zeros(p, p);
    for (_, d) in rows {
        add_block(&mut m, d, p);
    }
    m
}

/// `m += dᵀ d` of one 3 × p block, row by row (so that adding blocks one at
/// a time is [`gram`]'s sum, bit for bit).
fn add_block(m: &mut DMatrix<f64>, d: &[f64], p: usize) {
    for k in 0..3 {
        let r = &d[k * p..(k + 1) * p];
        for a in 0..p {
            if r[a] == 0.0 {
                continue;
            }
            for b in 0..p {
                m[(a, b)] += r[a] * r[b];
            }
        }
    }
}

/// A given calibration's information in the plan's scaled columns (unit
/// noise): `σ² S C⁻¹ S`, its frame (if estimated) unknown.
fn prior_information(given: &Given, design: &Design) -> DMatrix<f64> {
    let p = design.blocks.p;
    let mut m = DMatrix::zeros(p, p);
    if let Some(info) = given.cov.clone().try_inverse() {
        let (s, g) = (&design.scale, design.geometry.min(info.nrows()));
        for a in 0..g {
            for b in 0..g {
                m[(a, b)] = info[(a, b)] * given.sigma_mm.powi(2) * s[a] * s[b];
            }
        }
    }
    m
}

/// The greedy's choices up to `to` rows (the first `count` exchanged);
/// touches and sphere points open their sockets or spheres (most
/// candidates first) with [`Design::seeds`] rows each, as many as the count
/// allows (spheres: as many as half the count seeds), and open the next
/// when the open ones run out of candidates. Measured on the paper's arm,
/// 200 candidates on 8 spheres: opening every sphere the count allows left
/// 40 and 60 points undetermined; seeds of half the count gave 0.040 and
/// 0.027 mm (diameter fitted), a third of it 0.048 and 0.030 mm.
fn choose(greedy: &mut Greedy, design: &Design, count: usize, to: usize) -> Vec<usize> {
    let sockets = design.sockets.len();
    let mut order = Vec::with_capacity(to);
    let mut open = vec![design.seeds.is_none(); sockets];
    let mut queue: Vec<usize> = Vec::new();
    if let Some(min) = design.seeds {
        let mut size = vec![0usize; sockets];
        design.group.iter().for_each(|&g| size[g] += 1);
        queue = (0..sockets).filter(|&s| size[s] >= 2).collect();
        queue.sort_by_key(|&s| std::cmp::Reverse(size[s]));
        queue.reverse();
        // A sphere's seeds are mostly its own unknowns: spheres open so
        // that their seeds take half the count, leaving the rest to
        // inform the arm.
        let share = if design.per_sphere > 0 { 2 * min } else { min };
        let first = (count / share).clamp(1, sockets);
        for _ in 0..first {
            if let Some(s) = queue.pop() {
                open[s] = true;
                seed(greedy, design, s, &mut order);
            }
        }
    }
    // One row per stratum while the count lasts (the touches' seeds take
    // theirs first).
    let mut used = vec![0; design.stratum.iter().max().map_or(0, |m| m + 1)];
    for &(k, _) in &order {
        if let Some(u) = design.stratum.get(k).and_then(|&s| used.get_mut(s)) {
            *u += 1;
        }
    }
    let mut grow =
        |greedy: &mut Greedy, order: &mut Vec<(usize, f64)>, open: &mut Vec<bool>, to: usize| {
            while order.len() < to {
                let free = |k: usize| open[design.group[k]];
                let fresh = |k: usize| {
                    free(k)
                        && design
                            .stratum
                            .get(k)
                            .is_some_and(|&s| used[s] < ROWS_PER_STRATUM)
                };
                let best = (order.len() < count)
                    .then(|| greedy.best(fresh))
                    .flatten()
                    .or_else(|| greedy.best(free));
                if let Some((k, _)) = best {
                    if let Some(u) = design.stratum.get(k).and_then(|&s| used.get_mut(s)) {
                        *u += 1;
                    }
                    greedy.add(k);
                    order.push((k, greedy.criterion));
                } else if let Some(s) = queue.pop() {
                    open[s] = true;
                    seed(greedy, design, s, order);
                } else {
                    break;
                }
            }
        };
    grow(greedy, &mut order, &mut open, count);
    order.truncate(count);
    exchange(greedy, design, &mut order, &open);
    grow(greedy, &mut order, &mut open, to);
    order.truncate(to);
    order.into_iter().map(|o| o.0).collect()
}

/// Rows a stratum gives the robust plan at most (`K / ROWS_PER_STRATUM`
/// strata).
const ROWS_PER_STRATUM: usize = 1;

/// Passes of [`exchange`] at most.
const EXCHANGE_PASSES: usize = 3;

/// Fedorov's exchange on the chosen rows: each in turn is taken out and
/// the best candidate put in its place (itself, when none is better), until
/// a pass changes nothing. The greedy's first choices are made against the
/// weak prior alone, before the rows determine the arm; the exchange
/// revisits them once they do.
fn exchange(greedy: &mut Greedy, design: &Design, order: &mut [(usize, f64)], open: &[bool]) {
    let stratified = !design.stratum.is_empty();
    for _ in 0..EXCHANGE_PASSES {
        let mut changed = false;
        for slot in order.iter_mut() {
            let k = slot.0;
            // A socket (sphere) at its fewest rows swaps within itself (its
            // seeds were chosen by distance, not by the criterion); other
            // rows within their stratum, when there are strata.
            let g = design.group[k];
            let least = design.seeds.is_some_and(|m| greedy.members(g).len() <= m);
            let before = greedy.value();
            greedy.remove(k);
            let same = |i: usize| {
                if least {
                    design.group[i] == g
                } else {
                    !stratified || design.stratum[i] == design.stratum[k]
                }
            };
            let best = greedy
                .best(|i| open[design.group[i]] && same(i))
                .map(|b| b.0);
            match best {
                Some(b) if b != k => {
                    greedy.add(b);
                    if greedy.value() < before - 1e-9 * before.abs() {
                        slot.0 = b;
                        changed = true;
                    } else {
                        greedy.remove(b);
                        greedy.add(k);
                    }
                }
                _ => greedy.add(k),
            }
        }
        if !changed {
            break;
        }
    }
}

/// A socket's first touches: the candidate farthest (in its rows) from the
/// socket's mean, the one farthest from that, then the best third. A
/// sphere's: spread over its surface ([`seed_sphere`]).
fn seed(greedy: &mut Greedy, design: &Design, s: usize, order: &mut Vec<(usize, f64)>) {
    let members: Vec<usize> = (0..design.group.len())
        .filter(|&i| design.group[i] == s && !greedy.is_taken(i))
        .collect();
    if design.per_sphere > 0 {
        return seed_sphere(greedy, design, s, &members, order);
    }
    let p3 = 3 * design.blocks.p;
    let mut mean = vec![0.0; p3];
    for &i in &members {
        for (m, v) in mean.iter_mut().zip(design.blocks.at(i)) {
            *m += v / members.len() as f64;
        }
    }
    let Some(a) = farthest(greedy, design, &members, &mean) else {
        return;
    };
    greedy.add(a);
    order.push((a, greedy.criterion));
    let from = design.blocks.at(a).to_vec();
    let Some(b) = farthest(greedy, design, &members, &from) else {
        return;
    };
    greedy.add(b);
    order.push((b, greedy.criterion));
    while greedy.members(s).len() < MIN_TOUCHES_PER_SOCKET {
        let Some((c, _)) = greedy.best(|k| design.group[k] == s) else {
            return;
        };
        greedy.add(c);
        order.push((c, greedy.criterion));
    }
}

/// A sphere's first points, [`Design::seeds`] of them, as far apart as its
/// candidates allow: the one farthest from their centroid, then each the
/// one farthest from those taken (the largest least distance). Until a
/// sphere has more points than its own unknowns the criterion cannot tell
/// them apart; points spread over the surface fix the sphere best.
fn seed_sphere(
    greedy: &mut Greedy,
    design: &Design,
    s: usize,
    members: &[usize],
    order: &mut Vec<(usize, f64)>,
) {
    let at = |i: usize| &design.positions[i];
    let points: Vec<[f64; 3]> = members.iter().map(|&i| *at(i)).collect();
    let mut from = vec![crate::geometry::centroid(&points)];
    let want = design.seeds.unwrap_or(0);
    while greedy.members(s).len() < want {
        let far = |i: usize| {
            from.iter()
                .map(|f| crate::geometry::distance(at(i), f))
                .fold(f64::INFINITY, f64::min)
        };
        let next = (members.iter().copied())
            .filter(|&i| !greedy.is_taken(i))
            .map(|i| (i, far(i)))
            .fold(None, |best: Option<(usize, f64)>, (i, d)| match best {
                Some((_, b)) if b >= d => best,
                _ => Some((i, d)),
            });
        let Some((i, _)) = next else { return };
        if greedy.members(s).is_empty() {
            from.clear();
        }
        from.push(*at(i));
        greedy.add(i);
        order.push((i, greedy.criterion));
    }
}

/// The untaken candidate of `members` whose rows are farthest from `from`.
fn farthest(greedy: &Greedy, design: &Design, members: &[usize], from: &[f64]) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for &i in members.iter().filter(|&&i| !greedy.is_taken(i)) {
        let d: f64 = (design.blocks.at(i).iter().zip(from))
            .map(|(a, b)| (a - b).powi(2))
            .sum();
        if best.is_none_or(|(_, b)| d > b) {
            best = Some((i, d));
        }
    }
    best.map(|(i, _)| i)
}

/// Predicted spreads of designs over the workspace.
struct Evaluation<'a> {
    design: &'a Design,
    prior: Option<&'a DMatrix<f64>>,
}

impl Evaluation<'_> {
    /// The covariance (scaled columns, unit noise) with the rows `rows`
    /// and the prior; `None` when they do not determine every column.
    fn covariance(&self, rows: &[usize]) -> Option<DMatrix<f64>> {
        let d = self.design;
        if d.per_sphere > 0 {
            return self.sphere_covariance(rows);
        }
        let p = d.blocks.p;
        let mut m = gram(&deviations(d, rows), p);
        if let Some(prior) = self.prior {
            m += prior;
        }
        determined_inverse(m)
    }

    /// [`Evaluation::covariance`] of each prefix `rows[..k]`, `k` from 1.
    /// Positions' rows are as they are, so each prefix's information is
    /// the one before it and one more block (the same sums in the same
    /// order as [`gram`]'s, so the same bits); touches' and spheres' are
    /// made anew (a socket's mean, a sphere's unknowns, change with the
    /// set).
    fn prefix_covariances(&self, rows: &[usize]) -> Vec<Option<DMatrix<f64>>> {
        let d = self.design;
        if d.touches || d.per_sphere > 0 {
            return (1..=rows.len())
                .map(|k| self.covariance(&rows[..k]))
                .collect();
        }
        let p = d.blocks.p;
        let mut m = DMatrix::zeros(p, p);
        (rows.iter())
            .map(|&i| {
                add_block(&mut m, d.blocks.at(i), p);
                let mut with = m.clone();
                if let Some(prior) = self.prior {
                    with += prior;
                }
                determined_inverse(with)
            })
            .collect()
    }

    /// [`Evaluation::covariance`] of sphere points: a sphere with no more
    /// points than its own unknowns tells the arm nothing (they fit any
    /// points so few), so its rows and columns are left out; the others'
    /// unknowns are estimated with the arm. Their columns in the result
    /// are zero for the left-out spheres.
    fn sphere_covariance(&self, rows: &[usize]) -> Option<DMatrix<f64>> {
        let d = self.design;
        let mut count = vec![0usize; d.sockets.len()];
        rows.iter().for_each(|&i| count[d.group[i]] += 1);
        let kept: Vec<usize> = (rows.iter().copied())
            .filter(|&i| d.informs(count[d.group[i]]))
            .collect();
        let mut columns: Vec<usize> = (0..d.geometry).collect();
        for (s, &n) in count.iter().enumerate() {
            if d.informs(n) {
                columns.extend(d.geometry + d.per_sphere * s..d.geometry + d.per_sphere * (s + 1));
            }
        }
        let p = d.blocks.p;
        let mut m = gram(&deviations(d, &kept), p);
        if let Some(prior) = self.prior {
            m += prior;
        }
        let c = determined_inverse(m.select_rows(&columns).select_columns(&columns))?;
        let mut full = DMatrix::zeros(p, p);
        for (a, &ca) in columns.iter().enumerate() {
            for (b, &cb) in columns.iter().enumerate() {
                full[(ca, cb)] = c[(a, b)];
            }
        }
        Some(full)
    }

    /// `tr(W C)` of the covariance `c`, as an isotropic 95 % radius (mm).
    fn criterion_of(&self, c: &DMatrix<f64>) -> f64 {
        let p = self.design.blocks.p;
        let tr: f64 = (0..p * p)
            .map(|i| self.design.w[i] * c[(i / p, i % p)])
            .sum();
        coverage::K_ISOTROPIC * self.design.sigma * (tr.max(0.0) / 3.0).sqrt()
    }

    /// The spread with the rows `rows` (and the prior); `None` when they
    /// do not determine every column.
    fn spread(&self, rows: &[usize]) -> Option<Spread> {
        self.covariance(rows).map(|c| self.spread_of(&c))
    }

    /// The spread of the covariance `c` (scaled columns, unit noise).
    fn spread_of(&self, c: &DMatrix<f64>) -> Spread {
        let d = self.design;
        let p = d.blocks.p;
        let s2 = d.sigma * d.sigma;
        let mut radii: Vec<f64> = (0..d.workspace.len())
            .map(|i| {
                let s = map::sandwich(d.workspace.at(i), c, p).map(|r| r.map(|v| v * s2));
                coverage::radius(coverage::eigenvalues(s))
            })
            .collect();
        let n = radii.len().max(1) as f64;
        let rms = (radii.iter().map(|r| r * r).sum::<f64>() / n).sqrt();
        radii.sort_by(f64::total_cmp);
        Spread {
            rms_mm: rms,
            median_mm: radii.get(radii.len() / 2).copied().unwrap_or(0.0),
            max_mm: radii.last().copied().unwrap_or(0.0),
        }
    }

    /// Random subsets of `settings.count` of `n` candidates.
    fn random(&self, n: usize, settings: &PlanSettings) -> RandomBaseline {
        let mut rng = crate::random::rng(settings.seed, crate::random::streams::PLAN);
        let mut all: Vec<usize> = (0..n).collect();
        let mut spreads: Vec<Option<Spread>> = (0..settings.random_sets)
            .map(|_| {
                all.shuffle(&mut rng);
                let mut pick = all[..settings.count].to_vec();
                pick.sort_unstable();
                self.spread(&pick)
            })
            .collect();
        let determined = spreads.iter().filter(|s| s.is_some()).count();
        let key = |s: &Option<Spread>| s.map_or(f64::INFINITY, |s| s.rms_mm);
        spreads.sort_by(|a, b| key(a).total_cmp(&key(b)));
        RandomBaseline {
            sets: settings.random_sets,
            determined,
            median: spreads.get(spreads.len() / 2).copied().flatten(),
        }
    }
}

/// The inverse of the information `m`; `None` when it does not determine
/// every column (a pivot not well above rounding of the largest).
fn determined_inverse(m: DMatrix<f64>) -> Option<DMatrix<f64>> {
    let p = m.nrows();
    let top = m.diagonal().max();
    let chol = m.cholesky()?;
    let l = chol.l_dirty();
    let determined = top > 0.0 && (0..p).all(|a| l[(a, a)].powi(2) > 1e-12 * top);
    determined.then(|| crate::residuals::cholesky_inverse(&chol))
}

/// Row counts the curve is evaluated at: eighths of `to`, and `count`.
fn checkpoints(count: usize, to: usize) -> Vec<usize> {
    let mut k: Vec<usize> = (1..=8).map(|i| (to * i).div_ceil(8)).collect();
    k.push(count);
    k.retain(|&v| v >= 1 && v <= to);
    k.sort_unstable();
    k.dedup();
    k
}

/// Each joint's range over the chosen rows and the pool, degrees (mm for
/// a prismatic joint).
fn joint_spans(pool: &Poses, chosen: &[usize]) -> Vec<JointSpan> {
    let slides = |j: usize| j < 16 && pool.prismatic_mask() & (1 << j) != 0;
    let range = |rows: &mut dyn Iterator<Item = usize>, j: usize| {
        let (lo, hi) = rows.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), i| {
            let v = pool.reading(i)[j];
            (lo.min(v), hi.max(v))
        });
        let span = (hi - lo).max(0.0);
        if slides(j) { span } else { span.to_degrees() }
    };
    (0..pool.joints())
        .map(|j| JointSpan {
            joint: j + 1,
            chosen_deg: range(&mut chosen.iter().copied(), j),
            pool_deg: range(&mut (0..pool.len()), j),
            prismatic: slides(j),
        })
        .collect()
}

/// Rows chosen per socket or sphere (touches and sphere points only).
fn socket_counts(design: &Design, chosen: &[usize]) -> Vec<(String, usize)> {
    if design.seeds.is_none() {
        return Vec::new();
    }
    design
        .sockets
        .iter()
        .enumerate()
        .map(|(s, label)| {
            (
                label.clone(),
                chosen.iter().filter(|&&i| design.group[i] == s).count(),
            )
        })
        .filter(|(_, n)| *n > 0)
        .collect()
}

/// A joint turned less than this fraction of the pool's range is named.
const NARROW_JOINT: f64 = 0.25;

fn warnings(joints: &[JointSpan], undetermined: bool, settings: &PlanSettings) -> Vec<String> {
    let mut w = Vec::new();
    if undetermined {
        w.push(format!(
            "the {} chosen rows do not determine every free parameter: choose more",
            settings.count
        ));
    }
    for j in joints {
        if j.pool_deg > 0.0 && j.chosen_deg < NARROW_JOINT * j.pool_deg {
            let (moves, unit) = if j.prismatic {
                ("slides", " mm")
            } else {
                ("turns", "°")
            };
            w.push(format!(
                "joint {} {moves} {:.1}{unit} over the chosen rows, of the candidates' \
                 {:.1}{unit}: its errors are seen near those readings only",
                j.joint, j.chosen_deg, j.pool_deg
            ));
        }
    }
    w
}
