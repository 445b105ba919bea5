//! A calibration that converges from unknown encoder zeros (method.md §8.3).
//!
//! On a newly assembled arm any zero offset may be anywhere in ±180°, while
//! lengths and twists sit within a millimetre or a degree of nominal. The
//! cost is smooth in every parameter, but on the torus of the zero offsets
//! it has many basins; LM from nominal finds the right one rarely. So:
//!
//! 1. **LM from the start** (nominal). When the noise is stated, a fit at
//!    the noise floor — `σ̂² ≤ 1 + k·sqrt(2/dof)`, `k` standard deviations of
//!    `χ²/dof` above 1 — cannot be beaten by more than noise: accepted at
//!    once, so a good start costs one LM.
//! 2. **Multi-start on the torus.** Each start draws the free zero offsets
//!    uniformly on their circles (everything else at the start values), then
//!    runs coordinate sweeps — each zero offset in turn set to the best of
//!    `K` equally spaced angles, the cost being cheap (positions only) — an
//!    LM over the zero offsets alone, and a full LM. The sweeps exploit that
//!    each unknown is an angle: a sweep sees the whole circle, where a
//!    gradient sees only the slope underfoot.
//! 3. **Stopping rule.** Stop at the noise floor (stated noise), or when the
//!    lowest cost found has been reached from `confirmations` different
//!    starts (minima compared by cost: equivalent parameter sets — `θ_i + π`
//!    with `a_i`, `α_i` negated — fit identically), or after `max_starts`.
//!
//! The result is reported in the nominal arm's sign convention
//! ([`normalize_signs`]).

use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

use super::lm::{LmOptions, LmResult, levenberg_marquardt};
use super::{CalibrationError, Phase};
use crate::dataset::DataSet;
use crate::kernel::ArmKernel;
use crate::params::{DhParams, ParamId, ParamKind};
use crate::residuals::{Weights, cost};

/// Settings of the global method; a builder. Defaults: 200 starts at most,
/// 2 confirmations, 12 angles per sweep, 2 sweep passes, noise floor at 5
/// standard deviations.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GlobalOptions {
    /// Most multi-start runs.
    pub max_starts: usize,
    /// Starts that must reach the lowest cost before it is accepted.
    pub confirmations: usize,
    /// Angles per circle sweep.
    pub sweep_angles: usize,
    /// Passes of sweeps over the zero offsets per start.
    pub sweep_passes: usize,
    /// Noise floor: `σ̂² ≤ 1 + k·sqrt(2/dof)` with this `k`.
    pub noise_floor_k: f64,
}

impl Default for GlobalOptions {
    fn default() -> Self {
        GlobalOptions {
            max_starts: 200,
            confirmations: 2,
            sweep_angles: 12,
            sweep_passes: 2,
            noise_floor_k: 5.0,
        }
    }
}

impl GlobalOptions {
    /// Sets the start budget.
    pub fn max_starts(mut self, n: usize) -> Self {
        self.max_starts = n;
        self
    }
    /// Sets the confirmations.
    pub fn confirmations(mut self, n: usize) -> Self {
        self.confirmations = n.max(1);
        self
    }
}

/// Why the global method stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GlobalStop {
    /// A fit at the stated noise floor.
    NoiseFloor,
    /// The lowest cost was reached from enough starts.
    Agreement,
    /// The start budget ran out before either.
    StartBudget,
}

impl GlobalStop {
    /// A sentence for summaries.
    pub fn describe(self) -> &'static str {
        match self {
            GlobalStop::NoiseFloor => "fit at the stated noise floor",
            GlobalStop::Agreement => "lowest cost reached from independent starts",
            GlobalStop::StartBudget => "start budget spent without confirmation",
        }
    }

    /// Whether the minimum is confirmed.
    pub fn confirmed(self) -> bool {
        !matches!(self, GlobalStop::StartBudget)
    }
}

/// The account of a global run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GlobalTrace {
    /// Settings.
    pub options: GlobalOptions,
    /// Why it stopped.
    pub stop: GlobalStop,
    /// The zero offsets searched on their circles.
    pub circles: Vec<String>,
    /// Cost of each start's minimum, in order (the first from the start arm).
    pub minima: Vec<f64>,
    /// Starts that reached the lowest cost.
    pub best_hits: usize,
    /// The noise-floor cost, when the noise is stated.
    pub noise_floor_cost: Option<f64>,
    /// Parameters whose sign was changed to the nominal convention.
    pub sign_changes: Vec<String>,
}

/// Two costs from one minimum (equal within LM's convergence).
fn same_minimum(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * a.abs().max(b.abs()) + 1e-12
}

/// What [`global`] needs beyond the data.
pub struct GlobalProblem<'a> {
    /// The data.
    pub data: &'a DataSet,
    /// The weights.
    pub weights: &'a Weights,
    /// Free columns.
    pub free: &'a [usize],
    /// LM tolerances.
    pub lm: &'a LmOptions,
    /// Degrees of freedom; with stated noise, enables the noise floor.
    pub stated_dof: Option<usize>,
}

/// Runs the global method from `start`; returns the best LM result (in the
/// start's sign convention), its account, and the work per phase.
pub fn global<R: Rng>(
    start: &DhParams,
    problem: &GlobalProblem,
    options: &GlobalOptions,
    rng: &mut R,
    progress: &mut dyn FnMut(f64),
) -> Result<(LmResult, GlobalTrace, Vec<Phase>), CalibrationError> {
    let GlobalProblem {
        data,
        weights,
        free,
        lm,
        stated_dof,
    } = *problem;
    let joints = start.joint_count();
    let circles: Vec<usize> = free
        .iter()
        .copied()
        .filter(|&c| ParamId::from_column(joints, c).is_some_and(|id| id.kind == ParamKind::Theta))
        .collect();
    let floor = stated_dof.map(|dof| {
        let dof = dof.max(1) as f64;
        dof * (1.0 + options.noise_floor_k * (2.0 / dof).sqrt())
    });
    let mut phases = vec![
        Phase::new("lm from start"),
        Phase::new("circle sweeps"),
        Phase::new("zero-offset lm"),
        Phase::new("multi-start lm"),
    ];
    let timer = std::time::Instant::now();
    let first = levenberg_marquardt(start, data, weights, free, lm)?;
    phases[0].add_lm(&first, timer.elapsed().as_secs_f64());
    let mut minima = vec![first.normal.cost()];
    let mut best = first;
    let mut hits = 1;
    let stop = 'search: {
        if floor.is_some_and(|f| best.normal.cost() <= f) {
            break 'search GlobalStop::NoiseFloor;
        }
        if circles.is_empty() {
            break 'search GlobalStop::Agreement;
        }
        let zero_lm = LmOptions {
            max_iterations: 50,
            ftol: 1e-8,
            xtol: 1e-8,
            gtol: 1e-8,
            ..*lm
        };
        let mut xyz = vec![[0.0; 3]; data.len()];
        let mut x = start.clone();
        for s in 1..options.max_starts {
            progress(s as f64 / options.max_starts as f64);
            x.clone_from(start);
            for &c in &circles {
                let id = ParamId::from_column(joints, c).ok_or(CalibrationError::Shape)?;
                *x.get_mut(id) = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
            }
            let timer = std::time::Instant::now();
            let evaluations = sweep(&mut x, &circles, problem, options, &mut xyz)?;
            phases[1].cost_evaluations += evaluations;
            phases[1].seconds += timer.elapsed().as_secs_f64();
            let timer = std::time::Instant::now();
            let zeros = levenberg_marquardt(&x, data, weights, &circles, &zero_lm)?;
            phases[2].add_lm(&zeros, timer.elapsed().as_secs_f64());
            let timer = std::time::Instant::now();
            let fit = levenberg_marquardt(&zeros.params, data, weights, free, lm)?;
            phases[3].add_lm(&fit, timer.elapsed().as_secs_f64());
            let f = fit.normal.cost();
            minima.push(f);
            let b = best.normal.cost();
            if same_minimum(f, b) {
                hits += 1;
            } else if f < b {
                best = fit;
                hits = 1;
            }
            if floor.is_some_and(|fl| best.normal.cost() <= fl) {
                break 'search GlobalStop::NoiseFloor;
            }
            if hits >= options.confirmations {
                break 'search GlobalStop::Agreement;
            }
        }
        GlobalStop::StartBudget
    };
    progress(1.0);
    phases.retain(|p| p.cost_evaluations + p.jacobian_evaluations > 0);
    let names = |cols: &[usize]| -> Vec<String> {
        cols.iter()
            .filter_map(|&c| ParamId::from_column(joints, c))
            .map(|id| id.to_string())
            .collect()
    };
    let trace = GlobalTrace {
        options: *options,
        stop,
        circles: names(&circles),
        minima,
        best_hits: hits,
        noise_floor_cost: floor,
        sign_changes: Vec::new(),
    };
    Ok((best, trace, phases))
}

/// Coordinate sweeps: each zero offset in `circles` set, in turn, to the
/// best of `K` equally spaced angles (its current value competing).
/// Returns the cost evaluations.
fn sweep(
    x: &mut DhParams,
    circles: &[usize],
    problem: &GlobalProblem,
    options: &GlobalOptions,
    xyz: &mut [[f64; 3]],
) -> Result<usize, CalibrationError> {
    let joints = x.joint_count();
    let k = options.sweep_angles.max(2);
    let mut evaluations = 0;
    let mut f_best = cost(&ArmKernel::new(x)?, problem.data, problem.weights, xyz)?;
    evaluations += 1;
    for _ in 0..options.sweep_passes {
        for &c in circles {
            let id = ParamId::from_column(joints, c).ok_or(CalibrationError::Shape)?;
            let keep = x.get(id);
            let mut best_angle = keep;
            for step in 1..k {
                let angle = keep + std::f64::consts::TAU * step as f64 / k as f64;
                *x.get_mut(id) = angle;
                let f = cost(&ArmKernel::new(x)?, problem.data, problem.weights, xyz)?;
                evaluations += 1;
                if f < f_best {
                    f_best = f;
                    best_angle = angle;
                }
            }
            *x.get_mut(id) = crate::simulate::wrap(best_angle);
        }
    }
    Ok(evaluations)
}

/// Puts `params` into the sign convention of `nominal` where the fit left a
/// joint in the equivalent flipped form, returning the names changed.
///
/// `Rot_z(θ+π)·Trans_z(d)·Trans_x(−a)·Rot_x(−α)` equals
/// `Rot_z(θ)·Trans_z(d)·Trans_x(a)·Rot_x(α)·Rot_z(π)`: joint `i` with
/// `θ_i + π`, `−a_i`, `−α_i` leaves a half turn about the next `z` axis,
/// which the next zero offset absorbs (`θ_{i+1} + π`), or which passes
/// through the next joint by negating its `a` and `α`, or reaches the probe
/// as `(−Bx, −By)`. Only free parameters (`free`, columns) are changed, so a
/// fixed one keeps its value; probe positions are unchanged.
///
/// ```
/// use aacmm_core::{calibrate::global::normalize_signs, kernel::ArmKernel, params::DhParams};
/// let nominal = DhParams::paper_nominal();
/// let mut flipped = nominal.clone();
/// flipped.joints[2].theta += std::f64::consts::PI;
/// flipped.joints[2].a = -flipped.joints[2].a;
/// flipped.joints[2].alpha = -flipped.joints[2].alpha;
/// flipped.joints[3].theta += std::f64::consts::PI;
/// let q = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6];
/// let before = ArmKernel::new(&flipped).unwrap().position(&q).unwrap();
/// let all: Vec<usize> = (0..27).collect();
/// let changed = normalize_signs(&mut flipped, &nominal, &all);
/// assert_eq!(changed, ["theta3", "a3", "alpha3", "theta4"]);
/// assert!((flipped.joints[2].alpha - nominal.joints[2].alpha).abs() < 1e-12);
/// let after = ArmKernel::new(&flipped).unwrap().position(&q).unwrap();
/// assert!((0..3).all(|k| (before[k] - after[k]).abs() < 1e-9));
/// ```
pub fn normalize_signs(params: &mut DhParams, nominal: &DhParams, free: &[usize]) -> Vec<String> {
    let n = params.joint_count();
    let id = |kind, index| ParamId { kind, index };
    let is_free = |p: ParamId| free.contains(&p.column(n));
    let reach = crate::identify::reach(nominal);
    let mut changed = Vec::new();
    for i in 0..n {
        let (a, al) = (params.joints[i].a, params.joints[i].alpha);
        let (na, nal) = (nominal.joints[i].a, nominal.joints[i].alpha);
        let dist =
            |a: f64, al: f64| ((a - na) / reach).powi(2) + crate::simulate::wrap(al - nal).powi(2);
        if dist(-a, -al) >= dist(a, al) {
            continue;
        }
        // The half turn to absorb: find where, through free parameters only.
        let mut plan = vec![
            id(ParamKind::Theta, i),
            id(ParamKind::A, i),
            id(ParamKind::Alpha, i),
        ];
        let mut absorbed = false;
        for j in i + 1..n {
            if is_free(id(ParamKind::Theta, j)) {
                plan.push(id(ParamKind::Theta, j));
                absorbed = true;
                break;
            }
            plan.extend([id(ParamKind::A, j), id(ParamKind::Alpha, j)]);
        }
        if !absorbed {
            plan.extend([id(ParamKind::Probe, 0), id(ParamKind::Probe, 1)]);
        }
        let zero = |p: &ParamId| p.kind != ParamKind::Theta && params.get(*p) == 0.0;
        if !plan.iter().all(|p| is_free(*p) || zero(p)) {
            continue;
        }
        for p in plan {
            let v = params.get_mut(p);
            if p.kind == ParamKind::Theta {
                *v = crate::simulate::wrap(*v + std::f64::consts::PI);
            } else if *v != 0.0 {
                *v = -*v;
            } else {
                continue;
            }
            changed.push(p.to_string());
        }
    }
    changed
}
