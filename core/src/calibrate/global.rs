//! A calibration that converges from unknown encoder zeros (method.md §8.3).
//!
//! On a newly assembled arm any zero offset may be anywhere in ±180°, while
//! lengths and twists sit within a millimetre or a degree of nominal. The
//! cost is smooth in every parameter, but on the torus of the zero offsets
//! it has many basins; LM from nominal finds the right one rarely. So:
//!
//! 1. **LM from the start** (nominal), at most 30 iterations. When the noise is stated, a fit at
//!    the noise floor — `χ² ≤ dof·(1 + k·sqrt(2/dof))`, `k` standard
//!    deviations of `χ²/dof` above 1, with the touches weighed at the fit
//!    (the weights carry the encoder noise through the arm's joint Jacobian,
//!    so they depend on the zeros) — cannot be beaten by more than noise:
//!    accepted at once, so a good start costs one LM.
//! 2. **A grid over the torus.** Each unknown is an angle, so the free zero
//!    offsets live on a torus, which a coarse grid covers completely: `K`
//!    angles per circle (6 for the 4 free zeros of a 6-joint arm: 1296
//!    cells), the cost at each cell with everything else at the start
//!    values — positions only, about 2 µs per cell for 100 touches. The right cell is within `π/K` of the truth in every zero,
//!    inside the basin of an LM over the zeros alone, and lengths and twists
//!    near nominal keep it among the lowest. The lowest grid cells that are
//!    local minima among their neighbours are refined, lowest first, by that
//!    zeros-only LM and then the full LM (at most 30 iterations, as from
//!    the start), until one reaches the noise floor.
//! 3. **Random starts, and the stopping rule.** Without stated noise (or if
//!    no candidate reaches the floor), random zeros on the circles, refined
//!    the same way, until the lowest cost has been reached from
//!    `confirmations` starts (minima compared by cost: equivalent parameter
//!    sets — `θ_i + π` with `a_i`, `α_i` negated — fit identically), or the
//!    start budget is spent (then the result is flagged unconfirmed).
//!
//! The result is reported in the nominal arm's sign convention
//! ([`normalize_signs`]).

use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

use super::lm::{LmOptions, LmResult, levenberg_marquardt, levenberg_marquardt_from};
use super::{CalibrationError, Phase};
use crate::dataset::DataSet;
use crate::error::OptionError;
use crate::kernel::ArmKernel;
use crate::params::{DhParams, ParamId, ParamKind};
use crate::residuals::{Noise, Weights, cost};

/// Settings of the global method; a builder. Defaults: a torus grid of at
/// most 1296 cells (6 angles per circle for 4 circles), 8 grid
/// candidates refined, then at most 100 random starts, 2 confirmations,
/// the noise floor at 5 standard deviations.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GlobalOptions {
    /// Most cells of the grid over the zero-offset torus (the angles per
    /// circle are the most that keep `angles^circles` within it, at least 4).
    pub grid_cells: usize,
    /// Lowest grid cells (local minima of the grid) refined by LM.
    pub candidates: usize,
    /// Most random starts after the grid candidates.
    pub max_starts: usize,
    /// Starts that must reach the lowest cost before it is accepted
    /// (without stated noise, or when the noise floor is not reached).
    pub confirmations: usize,
    /// Noise floor: `σ̂² ≤ 1 + k·sqrt(2/dof)` with this `k`.
    pub noise_floor_k: f64,
    /// Iteration limit of the LM from each start — the start arm, a grid
    /// cell, a random draw (one that needs more is in a wrong basin; where
    /// it stopped is still recorded).
    pub start_iterations: usize,
}

impl Default for GlobalOptions {
    fn default() -> Self {
        GlobalOptions {
            grid_cells: 1296,
            candidates: 8,
            max_starts: 100,
            confirmations: 2,
            noise_floor_k: 5.0,
            start_iterations: 30,
        }
    }
}

setters!(GlobalOptions {
    max_starts: usize, "Sets the random-start budget.";
    confirmations: usize, "Sets the confirmations.";
});

impl GlobalOptions {
    /// Checks the settings; the error names the setting
    /// (`global.max_starts`, …).
    ///
    /// ```
    /// use aacmm_core::calibrate::GlobalOptions;
    /// assert!(GlobalOptions::default().check().is_ok());
    /// let e = GlobalOptions::default().confirmations(0).check().unwrap_err();
    /// assert_eq!(e.to_string(), "global.confirmations = 0: at least 1");
    /// ```
    pub fn check(&self) -> Result<(), OptionError> {
        for (field, v) in [
            ("global.grid_cells", self.grid_cells),
            ("global.max_starts", self.max_starts),
            ("global.confirmations", self.confirmations),
            ("global.start_iterations", self.start_iterations),
        ] {
            if v == 0 {
                return Err(OptionError::new(field, 0, "at least 1"));
            }
        }
        if self.confirmations > self.max_starts + self.candidates + 1 {
            return Err(OptionError::new(
                "global.confirmations",
                self.confirmations,
                format!(
                    "more than the {} starts there can be ({} random, {} grid, the start arm)",
                    self.max_starts + self.candidates + 1,
                    self.max_starts,
                    self.candidates
                ),
            ));
        }
        crate::error::check_nonnegative("global.noise_floor_k", self.noise_floor_k, false)
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
    /// Angles per circle of the grid (0 when the start sufficed).
    pub grid_angles: usize,
    /// Cost of each start's minimum, in order (the first from the start
    /// arm, then the grid candidates, then random starts), with the weights
    /// at that minimum.
    pub minima: Vec<f64>,
    /// Grid cells refined (after the start arm).
    pub grid_starts: usize,
    /// Random starts refined (after the grid).
    pub random_starts: usize,
    /// Restarts from the nominal geometry with the zeros of a mirror-image
    /// minimum (after the random starts).
    pub twin_restarts: usize,
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

/// What [`global`] needs beyond the start.
pub(crate) struct GlobalProblem<'a> {
    /// The data.
    pub data: &'a DataSet,
    /// The noise, to weigh the touches at each minimum.
    pub noise: &'a Noise,
    /// The weights at the start arm.
    pub weights: &'a Weights,
    /// Free columns.
    pub free: &'a [usize],
    /// LM tolerances.
    pub lm: &'a LmOptions,
    /// Worker threads of the normal equations.
    pub threads: usize,
    /// Degrees of freedom; with stated noise, enables the noise floor.
    pub stated_dof: Option<usize>,
    /// The normal equations at the start over `free`, when already computed.
    pub start_normal: Option<crate::residuals::Normal>,
}

/// The minima found so far.
#[derive(Default)]
struct Found {
    best: Option<Minimum>,
    hits: usize,
    minima: Vec<f64>,
    /// The lowest minimum whose geometry is implausible (a mirror image, a
    /// collapsed arm): never accepted, returned only when no plausible
    /// minimum was found, for the checks to refuse it by name.
    implausible: Option<Minimum>,
}

impl Found {
    /// Records a start's minimum; whether it is at the noise floor (`floor`:
    /// the band of costs the stated noise explains). A minimum whose
    /// geometry is implausible is recorded but neither accepted nor
    /// counted.
    fn record(&mut self, m: Minimum, floor: Option<(f64, f64)>, plausible: bool) -> bool {
        self.minima.push(m.cost);
        if !plausible {
            if self.implausible.as_ref().is_none_or(|b| m.cost < b.cost) {
                self.implausible = Some(m);
            }
            return false;
        }
        let at_floor = floor.is_some_and(|(lo, hi)| (lo..=hi).contains(&m.cost));
        match &self.best {
            Some(b) if same_minimum(m.cost, b.cost) => self.hits += 1,
            Some(b) if m.cost > b.cost => {}
            _ => {
                self.best = Some(m);
                self.hits = 1;
            }
        }
        at_floor
    }
}

/// One start's minimum, weighed at itself.
struct Minimum {
    fit: LmResult,
    cost: f64,
}

/// Runs the global method from `start`; returns the best LM result (in the
/// start's sign convention), its account, and the work per phase.
pub(crate) fn global<R: Rng>(
    start: &DhParams,
    problem: &GlobalProblem,
    options: &GlobalOptions,
    rng: &mut R,
    progress: &mut dyn FnMut(f64),
) -> Result<(LmResult, GlobalTrace, Vec<Phase>), CalibrationError> {
    options.check()?;
    let GlobalProblem {
        data,
        weights,
        free,
        lm,
        threads,
        stated_dof,
        ..
    } = *problem;
    let joints = start.joint_count();
    let circles: Vec<usize> = free
        .iter()
        .copied()
        .filter(|&c| ParamId::from_column(joints, c).is_some_and(|id| id.kind == ParamKind::Theta))
        .collect();
    // The band of costs the stated noise explains: χ²/dof within k standard
    // deviations of 1. Below it the noise is overstated and every basin
    // looks like the floor, so none is accepted on that ground.
    let floor = stated_dof.map(|dof| {
        let dof = dof.max(1) as f64;
        let k = options.noise_floor_k * (2.0 / dof).sqrt();
        (dof * (1.0 - k).max(0.0), dof * (1.0 + k))
    });
    // A minimum is a candidate only if its geometry is the nominal arm's
    // kind (not its mirror image, not collapsed): the cost cannot tell.
    // (`gross_corrections` compares twists modulo 2π.)
    let judge = |found: &mut Found, m: Minimum| {
        let mut p = m.fit.params.clone();
        normalize_signs(&mut p, start, free);
        let plausible = super::checks::gross_corrections(&p, start, free).is_empty();
        found.record(m, floor, plausible)
    };
    let mut phases = vec![
        Phase::new("lm from start"),
        Phase::new("torus grid"),
        Phase::new("zero-offset lm"),
        Phase::new("lm"),
    ];
    let mut found = Found::default();
    let timer = std::time::Instant::now();
    // From a good start LM converges in a handful of iterations; one that
    // wanders longer is in the wrong basin, and the grid will do better.
    let start_lm = if circles.is_empty() {
        *lm
    } else {
        lm.max_iterations(lm.max_iterations.min(options.start_iterations))
    };
    let first = match problem.start_normal.clone() {
        Some(normal) => levenberg_marquardt_from(start, normal, data, weights, &start_lm, threads)?,
        None => levenberg_marquardt(start, data, weights, free, &start_lm, threads)?,
    };
    phases[0].add_lm(&first, timer.elapsed().as_secs_f64());
    // A cut-off start within this cost of the floor is finished.
    let promising = floor.map(|(_, hi)| 10.0 * hi);
    let first = settle(first, problem, &mut phases[0], promising)?;
    let mut angles = 0;
    let (mut grid_starts, mut random_starts, mut twin_restarts) = (0, 0, 0);
    let stop = 'search: {
        if judge(&mut found, first) {
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
        };
        let refine = |x: &DhParams, phases: &mut Vec<Phase>| -> Result<Minimum, CalibrationError> {
            let timer = std::time::Instant::now();
            let zeros = levenberg_marquardt(x, data, weights, &circles, &zero_lm, threads)?;
            phases[2].add_lm(&zeros, timer.elapsed().as_secs_f64());
            let timer = std::time::Instant::now();
            let fit = levenberg_marquardt(&zeros.params, data, weights, free, &start_lm, threads)?;
            phases[3].add_lm(&fit, timer.elapsed().as_secs_f64());
            settle(fit, problem, &mut phases[3], promising)
        };
        // The grid over the torus, and its lowest local minima.
        let timer = std::time::Instant::now();
        let (grid_angles, cells) = torus_grid(start, &circles, problem, options)?;
        angles = grid_angles;
        phases[1].cost_evaluations += grid_angles.pow(circles.len() as u32);
        phases[1].seconds += timer.elapsed().as_secs_f64();
        let total = cells.len() + options.max_starts;
        let mut tried = 0;
        for x in cells {
            tried += 1;
            grid_starts += 1;
            progress(tried as f64 / total as f64);
            let m = refine(&x, &mut phases)?;
            if judge(&mut found, m) {
                break 'search GlobalStop::NoiseFloor;
            }
        }
        if floor.is_none() && found.hits >= options.confirmations {
            break 'search GlobalStop::Agreement;
        }
        // Random starts until the lowest cost is confirmed.
        let mut x = start.clone();
        for _ in 0..options.max_starts {
            tried += 1;
            random_starts += 1;
            progress(tried as f64 / total as f64);
            x.clone_from(start);
            for &c in &circles {
                let id = ParamId::from_column(joints, c).ok_or(CalibrationError::Shape)?;
                *x.get_mut(id) = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
            }
            let m = refine(&x, &mut phases)?;
            if judge(&mut found, m) {
                break 'search GlobalStop::NoiseFloor;
            }
            if found.hits >= options.confirmations {
                break 'search GlobalStop::Agreement;
            }
        }
        // Only implausible minima at the floor (a mirror image of the arm
        // fits exactly as well): restart from the nominal geometry with
        // that minimum's zero offsets, as they are and reversed, which
        // leads into the proper twin's basin.
        let lowest_implausible = |f: &Found| match (&f.implausible, &f.best) {
            (Some(i), Some(b)) => i.cost < b.cost,
            (Some(_), None) => true,
            _ => false,
        };
        if lowest_implausible(&found)
            && let Some(m) = &found.implausible
        {
            // Its zero offsets in the nominal sign convention (the flips
            // that keep positions put back), so that they pair with the
            // nominal lengths and twists.
            let mut zeros = m.fit.params.clone();
            normalize_signs(&mut zeros, start, free);
            let twins: Vec<DhParams> = [1.0, -1.0]
                .iter()
                .map(|&sign| {
                    let mut x = start.clone();
                    for &c in &circles {
                        if let Some(id) = ParamId::from_column(joints, c) {
                            *x.get_mut(id) = crate::params::wrap(sign * zeros.get(id));
                        }
                    }
                    x
                })
                .collect();
            for x in twins {
                // Weighed at the restart itself: its zeros are the minimum's,
                // and weights from the start arm's zeros would slow LM down
                // past any cap.
                let timer = std::time::Instant::now();
                let mut here = Weights::new(&ArmKernel::new(&x)?, data, problem.noise, 1.0)?;
                here.prior = problem.weights.prior.clone();
                let fit = levenberg_marquardt(&x, data, &here, free, lm, threads)?;
                phases[3].add_lm(&fit, timer.elapsed().as_secs_f64());
                let m = reweigh(fit, problem, &mut phases[3])?;
                twin_restarts += 1;
                if judge(&mut found, m) {
                    break 'search GlobalStop::NoiseFloor;
                }
            }
            if floor.is_none() && found.hits >= options.confirmations {
                break 'search GlobalStop::Agreement;
            }
        }
        GlobalStop::StartBudget
    };
    progress(1.0);
    phases.retain(|p| p.cost_evaluations + p.jacobian_evaluations > 0);
    let names = |cols: &[usize]| -> Vec<String> {
        cols.iter()
            .filter_map(|&c| start.param_id(c))
            .map(|id| id.to_string())
            .collect()
    };
    // The lowest minimum, plausible or not: an implausible one (a mirror
    // image) is then refused by the checks by name, not hidden behind a
    // worse plausible start.
    let mut best = match (found.best, found.implausible) {
        (Some(b), Some(i)) if i.cost < b.cost && stop == GlobalStop::StartBudget => i,
        (Some(b), _) => b,
        (None, i) => i.ok_or(CalibrationError::Shape)?,
    };
    if best.fit.termination == super::Termination::MaxIterations {
        // The lowest start was cut off by the per-start cap: finish its
        // descent with the full LM rather than report it unconverged.
        let timer = std::time::Instant::now();
        let fit = levenberg_marquardt(&best.fit.params, data, weights, free, lm, threads)?;
        phases.push(Phase::new("lm, best start finished"));
        let last = phases.len() - 1;
        phases[last].add_lm(&fit, timer.elapsed().as_secs_f64());
        best = reweigh(fit, problem, &mut phases[last])?;
    }
    let trace = GlobalTrace {
        options: *options,
        stop,
        circles: names(&circles),
        grid_angles: angles,
        minima: found.minima,
        grid_starts,
        random_starts,
        twin_restarts,
        best_hits: found.hits,
        noise_floor_cost: floor.map(|(_, hi)| hi),
        sign_changes: Vec::new(),
    };
    Ok((best.fit, trace, phases))
}

/// A start's result: reweighed ([`reweigh`]) when its LM converged; one
/// cut off by the iteration cap is in a wrong basin (or crawling), and is
/// recorded where it stopped, its cost under the weights at that point.
fn settle(
    fit: LmResult,
    problem: &GlobalProblem,
    phase: &mut Phase,
    promising: Option<f64>,
) -> Result<Minimum, CalibrationError> {
    if fit.termination == super::Termination::MaxIterations
        && promising.is_some_and(|p| fit.normal.cost() <= p)
    {
        // Cut off close to the noise floor: a good basin crawled into
        // slowly. Finish the descent, so that the geometry judged is the
        // minimum's, not a point on the way to it.
        let timer = std::time::Instant::now();
        let done = levenberg_marquardt(
            &fit.params,
            problem.data,
            problem.weights,
            problem.free,
            problem.lm,
            problem.threads,
        )?;
        phase.add_lm(&done, timer.elapsed().as_secs_f64());
        return settle(done, problem, phase, None);
    }
    if fit.termination == super::Termination::MaxIterations {
        // Compared with converged starts, which are weighed at themselves:
        // weigh this one at itself too (no refit), or a start whose weights
        // happen to be kind looks lowest.
        let cost = match problem.stated_dof {
            Some(_) => {
                let kernel = ArmKernel::new(&fit.params)?;
                let mut weights = Weights::new(&kernel, problem.data, problem.noise, 1.0)?;
                weights.prior = problem.weights.prior.clone();
                let mut xyz = vec![[0.0; 3]; problem.data.len()];
                phase.cost_evaluations += 1;
                super::prior::cost_at(&fit.params, problem.data, &weights, problem.free, &mut xyz)?
            }
            None => fit.normal.cost(),
        };
        return Ok(Minimum { fit, cost });
    }
    reweigh(fit, problem, phase)
}

/// A minimum's cost with the touches weighed at it: the encoder noise moves
/// the probe along directions that depend on the arm, and an arm whose
/// zeros were 90° off weighs its touches wrongly. With stated noise, refits
/// with those weights (one or two LM steps); without, the weights do not
/// depend on the arm.
fn reweigh(
    fit: LmResult,
    problem: &GlobalProblem,
    phase: &mut Phase,
) -> Result<Minimum, CalibrationError> {
    if problem.stated_dof.is_none() {
        let cost = fit.normal.cost();
        return Ok(Minimum { fit, cost });
    }
    let timer = std::time::Instant::now();
    let kernel = ArmKernel::new(&fit.params)?;
    let mut weights = Weights::new(&kernel, problem.data, problem.noise, 1.0)?;
    weights.prior = problem.weights.prior.clone();
    let refit = levenberg_marquardt(
        &fit.params,
        problem.data,
        &weights,
        problem.free,
        problem.lm,
        problem.threads,
    )?;
    phase.add_lm(&refit, timer.elapsed().as_secs_f64());
    let cost = refit.normal.cost();
    Ok(Minimum { fit: refit, cost })
}

/// The cost on a grid of `K` angles per circle (everything else at the
/// start); returns `K` and the lowest `candidates` grid cells that are
/// local minima among their `2·circles` neighbours, lowest first.
fn torus_grid(
    start: &DhParams,
    circles: &[usize],
    problem: &GlobalProblem,
    options: &GlobalOptions,
) -> Result<(usize, Vec<DhParams>), CalibrationError> {
    let joints = start.joint_count();
    let c = circles.len() as u32;
    let mut k = 4usize;
    while (k + 1)
        .checked_pow(c)
        .is_some_and(|n| n <= options.grid_cells)
    {
        k += 1;
    }
    let cells = k.pow(c);
    let ids: Vec<ParamId> = circles
        .iter()
        .map(|&col| ParamId::from_column(joints, col).ok_or(CalibrationError::Shape))
        .collect::<Result<_, _>>()?;
    // Cell index = Σ digit_axis · k^axis; digit i is the angle −π + 2πi/k.
    let strides: Vec<usize> = (0..c).map(|axis| k.pow(axis)).collect();
    let digit = |cell: usize, stride: usize| cell / stride % k;
    let place = |x: &mut DhParams, cell: usize| {
        for (id, &stride) in ids.iter().zip(&strides) {
            let i = digit(cell, stride);
            *x.get_mut(*id) = crate::params::wrap(
                std::f64::consts::TAU * i as f64 / k as f64 - std::f64::consts::PI,
            );
        }
    };
    let mut x = start.clone();
    let mut xyz = vec![[0.0; 3]; problem.data.len()];
    let mut costs = Vec::with_capacity(cells);
    for cell in 0..cells {
        place(&mut x, cell);
        // Never NaN: a non-finite cost is +∞.
        costs.push(cost(
            &ArmKernel::new(&x)?,
            problem.data,
            problem.weights,
            &mut xyz,
        )?);
    }
    let mut minima: Vec<usize> = (0..cells)
        .filter(|&cell| {
            strides.iter().all(|&stride| {
                let d = digit(cell, stride);
                [1, k - 1].iter().all(|&step| {
                    let other = cell - d * stride + (d + step) % k * stride;
                    costs[cell] <= costs[other]
                })
            })
        })
        .collect();
    minima.sort_by(|&a, &b| costs[a].total_cmp(&costs[b]).then(a.cmp(&b)));
    minima.truncate(options.candidates);
    Ok((
        k,
        minima
            .into_iter()
            .map(|cell| {
                let mut x = start.clone();
                place(&mut x, cell);
                x
            })
            .collect(),
    ))
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
    let reach = nominal.reach();
    let mut changed = Vec::new();
    for i in 0..n {
        let (a, al) = (params.joints[i].a, params.joints[i].alpha);
        let (na, nal) = (nominal.joints[i].a, nominal.joints[i].alpha);
        let dist =
            |a: f64, al: f64| ((a - na) / reach).powi(2) + crate::params::wrap(al - nal).powi(2);
        if dist(-a, -al) >= dist(a, al) {
            continue;
        }
        // The half turn to absorb: find where, through free parameters only.
        // A Hayati joint's Ry(β) turns with its twist: Rz(π) carries
        // through Tx(a)·Rx(α)·Ry(β) as Tx(−a)·Rx(−α)·Ry(−β).
        let hayati_beta = |j: usize| {
            (params.joints[j].model == crate::params::JointModel::Hayati)
                .then(|| id(ParamKind::Beta, j))
        };
        let mut plan = vec![
            id(ParamKind::Theta, i),
            id(ParamKind::A, i),
            id(ParamKind::Alpha, i),
        ];
        plan.extend(hayati_beta(i));
        let mut absorbed = false;
        for j in i + 1..n {
            if is_free(id(ParamKind::Theta, j)) {
                plan.push(id(ParamKind::Theta, j));
                absorbed = true;
                break;
            }
            plan.extend([id(ParamKind::A, j), id(ParamKind::Alpha, j)]);
            plan.extend(hayati_beta(j));
        }
        if !absorbed {
            plan.extend([id(ParamKind::Probe, 0), id(ParamKind::Probe, 1)]);
        }
        let zero = |p: &ParamId| p.kind != ParamKind::Theta && params.get(*p) == 0.0;
        if !plan.iter().all(|p| is_free(*p) || zero(p)) {
            // The half turn cannot pass the last joint by negating its twist
            // (held fixed): it passes as `−a_n` and a half turn of the probe
            // about `Rx(−α_n)·z`, when the parameters that moves are free.
            if !absorbed {
                last_joint_route(params, i, free, &mut changed);
            }
            continue;
        }
        for p in plan {
            let v = params.get_mut(p);
            if p.kind == ParamKind::Theta {
                *v = crate::params::wrap(*v + std::f64::consts::PI);
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

/// The flip of joint `i` (`θ_i + π`, `−a_i`, `−α_i`) with its half turn
/// carried through the joints after it by negating their `a` and `α` up to
/// the last joint, and through the last joint as `−a_n` with the probe
/// turned by π about `Rx(−α_n)·z` (`Rz(π)·Tx(a)·Rx(α)·B = Tx(−a)·Rx(α)·
/// R_u(π)·B`). Applied, and the names changed appended to `changed`, only
/// when every value it changes is free (or zero and stays zero).
fn last_joint_route(
    params: &mut DhParams,
    i: usize,
    free: &[usize],
    changed: &mut Vec<String>,
) -> bool {
    let n = params.joint_count();
    // Not derived for Hayati links (their Ry(β) sits between Rx(α) and the
    // probe): their sign convention is left as the fit found it.
    if params.joints[i..]
        .iter()
        .any(|j| j.model == crate::params::JointModel::Hayati)
    {
        return false;
    }
    let id = |kind, index| ParamId { kind, index };
    let is_free = |p: ParamId| free.contains(&p.column(n));
    let mut negate = vec![id(ParamKind::A, i), id(ParamKind::Alpha, i)];
    for j in i + 1..n - 1 {
        negate.extend([id(ParamKind::A, j), id(ParamKind::Alpha, j)]);
    }
    negate.push(id(ParamKind::A, n - 1));
    let alpha = params.joints[n - 1].alpha;
    let u = [0.0, alpha.sin(), alpha.cos()];
    let b = params.probe;
    let ub: f64 = (0..3).map(|k| u[k] * b[k]).sum();
    let turned: [f64; 3] = std::array::from_fn(|k| 2.0 * ub * u[k] - b[k]);
    let probe_ok = (0..3).all(|k| {
        is_free(id(ParamKind::Probe, k)) || (turned[k] - b[k]).abs() <= 1e-12 * b[k].abs().max(1.0)
    });
    let theta = id(ParamKind::Theta, i);
    let ok =
        is_free(theta) && probe_ok && negate.iter().all(|&p| is_free(p) || params.get(p) == 0.0);
    if !ok {
        return false;
    }
    let t = params.get_mut(theta);
    *t = crate::params::wrap(*t + std::f64::consts::PI);
    changed.push(theta.to_string());
    for p in negate {
        let v = params.get_mut(p);
        if *v != 0.0 {
            *v = -*v;
            changed.push(p.to_string());
        }
    }
    for (k, v) in turned.into_iter().enumerate() {
        if params.probe[k] != v {
            params.probe[k] = v;
            changed.push(id(ParamKind::Probe, k).to_string());
        }
    }
    true
}
