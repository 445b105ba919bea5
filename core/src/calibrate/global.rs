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
//!    accepted at once, so a good start costs one LM. With a robust loss,
//!    a start that misses the floor is judged by its robust refit too (IRLS
//!    from its minimum, as the final fit runs it): at the floor by the
//!    robust scale's test, and plausible, it is accepted
//!    ([`GlobalStop::RobustFloor`]) — a few gross touches, not a wrong
//!    basin, kept its plain cost off the floor.
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
//! (`normalize_signs`).

use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

use super::lm::{LmOptions, LmResult, levenberg_marquardt_cancellable, levenberg_marquardt_until};
use super::{CalibrationError, Phase};
use crate::error::OptionError;
use crate::objective::Objective;
use crate::params::{DhParams, ParamId, ParamKind};
use crate::setting::Setting;

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
            (Setting::GlobalGridCells, self.grid_cells),
            (Setting::GlobalStarts, self.max_starts),
            (Setting::GlobalConfirmations, self.confirmations),
            (Setting::GlobalStartIterations, self.start_iterations),
        ] {
            if v == 0 {
                return Err(OptionError::new(field, 0, "at least 1"));
            }
        }
        if self.confirmations > self.max_starts + self.candidates + 1 {
            return Err(OptionError::new(
                Setting::GlobalConfirmations,
                self.confirmations,
                format!(
                    "more than the {} starts there can be ({} random, {} grid, the start arm)",
                    self.max_starts + self.candidates + 1,
                    self.max_starts,
                    self.candidates
                ),
            ));
        }
        crate::error::check_nonnegative(Setting::GlobalNoiseFloorK, self.noise_floor_k, false)
    }
}

/// Why the global method stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GlobalStop {
    /// A fit at the stated noise floor.
    NoiseFloor,
    /// With a robust loss: a start's robust refit at the stated noise
    /// floor (a few gross touches kept its plain cost off it).
    RobustFloor,
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
            GlobalStop::RobustFloor => {
                "fit at the stated noise floor once the robust loss weighs the outliers down"
            }
            GlobalStop::Agreement => "lowest cost reached from independent starts",
            GlobalStop::StartBudget => "start budget spent without confirmation",
        }
    }

    /// Whether the minimum is confirmed.
    pub(crate) fn confirmed(self) -> bool {
        !matches!(self, GlobalStop::StartBudget)
    }
}

/// The account of a global run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GlobalTrace {
    /// Settings.
    pub(crate) options: GlobalOptions,
    /// Why it stopped.
    pub stop: GlobalStop,
    /// The zero offsets searched on their circles.
    pub(crate) circles: Vec<String>,
    /// Angles per circle of the grid (0 when the start sufficed).
    pub(crate) grid_angles: usize,
    /// Cost of each start's minimum, in order (the first from the start
    /// arm, then the grid candidates, then random starts), with the weights
    /// at that minimum.
    pub minima: Vec<f64>,
    /// Grid cells refined (after the start arm).
    pub(crate) grid_starts: usize,
    /// Random starts refined (after the grid).
    pub(crate) random_starts: usize,
    /// Restarts from the nominal geometry with the zeros of a mirror-image
    /// minimum (after the random starts).
    pub(crate) twin_restarts: usize,
    /// Starts that reached the lowest cost.
    pub best_hits: usize,
    /// Of `best_hits`, those whose minimum agreed with the lowest at the
    /// fit's noise level only (cost within `cost/dof`, arm within its
    /// joint uncertainty), not to LM's convergence.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub(crate) noise_level_hits: usize,
    /// The noise-floor cost, when the noise is stated.
    pub noise_floor_cost: Option<f64>,
    /// Parameters whose sign was changed to the nominal convention.
    pub(crate) sign_changes: Vec<String>,
}

/// Two costs from one minimum (equal within LM's convergence).
fn same_minimum(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * a.abs().max(b.abs()) + 1e-12
}

/// Whether two minima agree at the fit's noise level: their costs differ
/// by less than one unit of its variance `s² = cost / dof` (a Δχ² of 1,
/// what one σ along one direction costs), and the arms are within their
/// joint uncertainty of each other — `δᵀ N δ / s²` (`N` the normal matrix
/// at the lower, `δ` their difference, signs in one convention, angles
/// wrapped) below `p + 3 sqrt(2p)`, the χ²_p mean plus three standard
/// deviations. On real data, where the model never fits exactly, LM from
/// different starts stops at costs that differ in the fourth digit; the
/// data cannot tell such minima apart, so they confirm each other.
fn agree_at_noise(
    (lower, other): (f64, f64),
    n: &crate::residuals::Normal,
    dof: usize,
    delta: &[f64],
) -> bool {
    let s2 = lower / dof.max(1) as f64;
    if !(s2 > 0.0 && s2.is_finite()) || (other - lower).abs() > s2 {
        return false;
    }
    let p = n.free.len();
    if delta.len() != p {
        return false;
    }
    let quad: f64 = (0..p)
        .map(|a| {
            (0..p)
                .map(|b| delta[a] * n.jtj[a * p + b] * delta[b])
                .sum::<f64>()
        })
        .sum();
    let bound = p as f64 + 3.0 * (2.0 * p as f64).sqrt();
    quad.is_finite() && quad / s2 <= bound
}

/// What [`global`] needs beyond the start.
pub(crate) struct GlobalProblem<'a, 'o> {
    /// The objective, weighed at the start arm (each minimum is weighed
    /// at itself again).
    pub(crate) objective: &'a Objective<'o>,
    /// Free columns.
    pub(crate) free: &'a [usize],
    /// LM tolerances.
    pub(crate) lm: &'a LmOptions,
    /// Degrees of freedom; with stated noise, enables the noise floor.
    pub(crate) stated_dof: Option<usize>,
    /// Degrees of freedom, stated noise or not: minima are told apart in
    /// units of the fit's own noise, `cost / dof`.
    pub(crate) dof: usize,
    /// The normal equations at the start over `free`, when already computed.
    pub(crate) start_normal: Option<crate::residuals::Normal>,
    /// The robust loss the fit ends with, if any: with stated noise, a
    /// start whose plain minimum misses the noise floor is judged by its
    /// robust refit too ([`Search::robust_floor`]), as the final fit will be.
    pub(crate) robust: Option<super::robust::Robust>,
    /// Set from another thread to stop the search: every LM of it checks.
    pub(crate) cancel: Option<super::Cancel>,
}

impl GlobalProblem<'_, '_> {
    /// Every column of the point whose geometry is `arm`, the auxiliary
    /// blocks at their start values (the search moves zero offsets only).
    fn point(&self, arm: &DhParams) -> Vec<f64> {
        let mut x = arm.to_vec();
        let layout = self.objective.layout();
        x.extend(&layout.start()[layout.geometry_columns()..]);
        x
    }

    /// LM of the objective `objective` from `x` over `free`, stopped
    /// ([`CalibrationError::Cancelled`]) once the search is cancelled.
    fn lm(
        &self,
        objective: &Objective<'_>,
        x: &[f64],
        free: &[usize],
        options: &LmOptions,
    ) -> Result<LmResult, CalibrationError> {
        levenberg_marquardt_until(objective, x, free, options, self.cancel.as_ref())
    }
}

/// The minima found so far.
#[derive(Default)]
struct Found {
    best: Option<Minimum>,
    hits: usize,
    /// Of `hits`, those that agreed with the best at the noise level only
    /// ([`agree_at_noise`]), not to LM's convergence.
    noise_hits: usize,
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
    fn record(
        &mut self,
        m: Minimum,
        floor: Option<(f64, f64)>,
        plausible: bool,
        agree: impl Fn(&Minimum, &Minimum) -> bool,
    ) -> bool {
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
            Some(b) if agree(&m, b) => {
                self.hits += 1;
                self.noise_hits += 1;
                if m.cost < b.cost {
                    self.best = Some(m);
                }
            }
            Some(b) if m.cost > b.cost => {}
            _ => {
                self.best = Some(m);
                self.hits = 1;
                self.noise_hits = 0;
            }
        }
        at_floor
    }

    /// The implausible minimum, when it is lower than every plausible one.
    fn lowest_implausible(&self) -> Option<&Minimum> {
        let i = self.implausible.as_ref()?;
        self.best
            .as_ref()
            .is_none_or(|b| i.cost < b.cost)
            .then_some(i)
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
    problem: &GlobalProblem<'_, '_>,
    options: &GlobalOptions,
    rng: &mut R,
    progress: &mut dyn FnMut(f64),
) -> Result<(LmResult, GlobalTrace, Vec<Phase>), CalibrationError> {
    options.check()?;
    let search = Search::new(start, problem, options);
    let mut tally = Tally::new();
    let stop = search.run(&mut tally, rng, progress)?;
    progress(1.0);
    search.finish(tally, stop)
}

/// The phases of [`Tally::phases`], by index.
const START_PHASE: usize = 0;
const GRID_PHASE: usize = 1;
const ZEROS_PHASE: usize = 2;
const LM_PHASE: usize = 3;

/// What the search has found and spent so far.
struct Tally {
    found: Found,
    /// The work of [`START_PHASE`], [`GRID_PHASE`], [`ZEROS_PHASE`] and
    /// [`LM_PHASE`].
    phases: Vec<Phase>,
    /// Angles per circle of the grid (0 while there is none).
    grid_angles: usize,
    grid_starts: usize,
    random_starts: usize,
    twin_restarts: usize,
}

impl Tally {
    fn new() -> Tally {
        Tally {
            found: Found::default(),
            phases: vec![
                Phase::new("lm from start"),
                Phase::new("torus grid"),
                Phase::new("zero-offset lm"),
                Phase::new("lm"),
            ],
            grid_angles: 0,
            grid_starts: 0,
            random_starts: 0,
            twin_restarts: 0,
        }
    }

    /// The grid cells and random draws refined so far: the progress made.
    fn started(&self) -> usize {
        self.grid_starts + self.random_starts
    }
}

/// What one global search holds fixed: the problem, the circles searched,
/// the noise floor and the LM settings of each start.
struct Search<'a, 'o> {
    start: &'a DhParams,
    problem: &'a GlobalProblem<'a, 'o>,
    options: &'a GlobalOptions,
    /// The free zero offsets (columns): the circles of the torus.
    circles: Vec<usize>,
    /// The band of costs the stated noise explains.
    floor: Option<(f64, f64)>,
    /// A cut-off start within this cost of the floor is finished.
    promising: Option<f64>,
    /// LM from each start: the start arm, a grid cell, a random draw.
    start_lm: LmOptions,
    /// LM over the zero offsets alone, from a grid cell or random draw.
    zero_lm: LmOptions,
}

impl<'a, 'o> Search<'a, 'o> {
    fn new(
        start: &'a DhParams,
        problem: &'a GlobalProblem<'a, 'o>,
        options: &'a GlobalOptions,
    ) -> Search<'a, 'o> {
        let joints = start.joint_count();
        let lm = problem.lm;
        let circles: Vec<usize> = problem
            .free
            .iter()
            .copied()
            .filter(|&c| {
                ParamId::from_column(joints, c).is_some_and(|id| id.kind == ParamKind::Theta)
            })
            .collect();
        // The band of costs the stated noise explains: χ²/dof within k standard
        // deviations of 1. Below it the noise is overstated and every basin
        // looks like the floor, so none is accepted on that ground.
        let floor = problem.stated_dof.map(|dof| {
            let dof = dof.max(1) as f64;
            let k = options.noise_floor_k * (2.0 / dof).sqrt();
            (dof * (1.0 - k).max(0.0), dof * (1.0 + k))
        });
        // From a good start LM converges in a handful of iterations; one that
        // wanders longer is in the wrong basin, and the grid will do better.
        let start_lm = if circles.is_empty() {
            *lm
        } else {
            lm.max_iterations(lm.max_iterations.min(options.start_iterations))
        };
        let zero_lm = LmOptions {
            max_iterations: 50,
            ftol: 1e-8,
            xtol: 1e-8,
            gtol: 1e-8,
        };
        Search {
            start,
            problem,
            options,
            circles,
            floor,
            promising: floor.map(|(_, hi)| 10.0 * hi),
            start_lm,
            zero_lm,
        }
    }

    /// The search, phase by phase, until one of them stops it.
    fn run<R: Rng>(
        &self,
        tally: &mut Tally,
        rng: &mut R,
        progress: &mut dyn FnMut(f64),
    ) -> Result<GlobalStop, CalibrationError> {
        if let Some(stop) = self.start_arm(tally)? {
            return Ok(stop);
        }
        let cells = self.grid(tally)?;
        let planned = cells.len() + self.options.max_starts;
        if let Some(stop) = self.grid_candidates(cells, planned, tally, progress)? {
            return Ok(stop);
        }
        if let Some(stop) = self.random_starts(planned, tally, rng, progress)? {
            return Ok(stop);
        }
        Ok(self
            .twin_restarts(tally)?
            .unwrap_or(GlobalStop::StartBudget))
    }

    /// LM from the start arm; it stops the search when it reaches the noise
    /// floor, or when there is no zero offset to search.
    fn start_arm(&self, tally: &mut Tally) -> Result<Option<GlobalStop>, CalibrationError> {
        let problem = self.problem;
        let (objective, x) = (problem.objective, problem.point(self.start));
        let timer = std::time::Instant::now();
        let first = match problem.start_normal.clone() {
            Some(normal) => levenberg_marquardt_cancellable(
                objective,
                &x,
                normal,
                &self.start_lm,
                problem.cancel.as_ref(),
            )?,
            None => problem.lm(objective, &x, problem.free, &self.start_lm)?,
        };
        let phase = &mut tally.phases[START_PHASE];
        phase.add_lm(&first, timer.elapsed().as_secs_f64());
        let first = settle(first, self.problem, phase, self.promising)?;
        if let Some(stop) = self.judge_start(tally, first)? {
            return Ok(Some(stop));
        }
        Ok(self.circles.is_empty().then_some(GlobalStop::Agreement))
    }

    /// The grid over the torus: its lowest local minima, lowest first.
    fn grid(&self, tally: &mut Tally) -> Result<Vec<DhParams>, CalibrationError> {
        let timer = std::time::Instant::now();
        let (angles, cells) = torus_grid(self.start, &self.circles, self.problem, self.options)?;
        tally.grid_angles = angles;
        let phase = &mut tally.phases[GRID_PHASE];
        phase.cost_evaluations += angles.pow(self.circles.len() as u32);
        phase.seconds += timer.elapsed().as_secs_f64();
        Ok(cells)
    }

    /// Refines the grid's `cells` in turn (`planned`: the starts there can
    /// be, for the progress).
    fn grid_candidates(
        &self,
        cells: Vec<DhParams>,
        planned: usize,
        tally: &mut Tally,
        progress: &mut dyn FnMut(f64),
    ) -> Result<Option<GlobalStop>, CalibrationError> {
        // As many cells side by side as there are threads, so that the
        // progress moves on; the noise floor can stop the grid after any.
        let window = self.problem.objective.threads().max(1);
        let mut count = |tally: &mut Tally| {
            tally.grid_starts += 1;
            progress(tally.started() as f64 / planned as f64);
        };
        for cells in cells.chunks(window) {
            let judged = self.refine_in_order(cells, tally, &mut count, &|_| None)?;
            if judged.is_some() {
                return Ok(judged);
            }
        }
        Ok(self.agreement(&tally.found))
    }

    /// Random starts until the lowest cost is confirmed, as many at a time
    /// as the objective has threads (the draws are this search's own: the
    /// stream ends with it, so a window's unused draws change nothing else).
    fn random_starts<R: Rng>(
        &self,
        planned: usize,
        tally: &mut Tally,
        rng: &mut R,
        progress: &mut dyn FnMut(f64),
    ) -> Result<Option<GlobalStop>, CalibrationError> {
        let joints = self.start.joint_count();
        let threads = self.problem.objective.threads().max(1);
        let mut count = |tally: &mut Tally| {
            tally.random_starts += 1;
            progress(tally.started() as f64 / planned as f64);
        };
        let confirmed = |tally: &Tally| {
            (tally.found.hits >= self.options.confirmations).then_some(GlobalStop::Agreement)
        };
        let mut left = self.options.max_starts;
        while left > 0 {
            let window = threads.min(left);
            left -= window;
            let mut starts = vec![self.start.clone(); window];
            for x in &mut starts {
                for &c in &self.circles {
                    let id = ParamId::from_column(joints, c).ok_or(CalibrationError::Shape)?;
                    *x.get_mut(id) = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
                }
            }
            let judged = self.refine_in_order(&starts, tally, &mut count, &confirmed)?;
            if judged.is_some() {
                return Ok(judged);
            }
        }
        Ok(None)
    }

    /// Refines `starts` side by side on the objective's threads and judges
    /// their minima one after the other in order: each minimum depends on
    /// its start alone, so the same minima are judged in the same order as
    /// one at a time. `before` runs before each judgement (the counts, the
    /// progress), `after` after it (a stop of the caller's). A stop leaves
    /// the window's later starts unjudged and their evaluations uncounted,
    /// as if they had never run.
    fn refine_in_order(
        &self,
        starts: &[DhParams],
        tally: &mut Tally,
        before: &mut dyn FnMut(&mut Tally),
        after: &dyn Fn(&Tally) -> Option<GlobalStop>,
    ) -> Result<Option<GlobalStop>, CalibrationError> {
        let timer = std::time::Instant::now();
        let threads = self.problem.objective.threads();
        let refined = crate::parallel::parallel_map_each(starts, threads, |x| {
            let mut phases: Vec<Phase> =
                (tally.phases.iter()).map(|p| Phase::new(&p.name)).collect();
            self.refine(x, &mut phases).map(|m| (m, phases))
        });
        let wall = wall_share(&refined, timer.elapsed().as_secs_f64());
        for m in refined {
            before(tally);
            let (m, mut phases) = m?;
            for (all, one) in tally.phases.iter_mut().zip(&mut phases) {
                one.seconds *= wall;
                all.add(one);
            }
            if let Some(stop) = self.judge_start(tally, m)? {
                return Ok(Some(stop));
            }
            if let Some(stop) = after(tally) {
                return Ok(Some(stop));
            }
        }
        Ok(None)
    }

    /// Only implausible minima at the floor (a mirror image of the arm
    /// fits exactly as well): restart from the nominal geometry with
    /// that minimum's zero offsets, as they are and reversed, which
    /// leads into the proper twin's basin.
    fn twin_restarts(&self, tally: &mut Tally) -> Result<Option<GlobalStop>, CalibrationError> {
        let Some(m) = tally.found.lowest_implausible() else {
            return Ok(None);
        };
        for x in self.twins(m) {
            let m = self.restart(&x, &mut tally.phases)?;
            tally.twin_restarts += 1;
            if let Some(stop) = self.judge_start(tally, m)? {
                return Ok(Some(stop));
            }
        }
        Ok(self.agreement(&tally.found))
    }

    /// The nominal geometry with the zero offsets of the implausible
    /// minimum `m`, as they are and reversed.
    fn twins(&self, m: &Minimum) -> Vec<DhParams> {
        let joints = self.start.joint_count();
        // Its zero offsets in the nominal sign convention (the flips
        // that keep positions put back), so that they pair with the
        // nominal lengths and twists.
        let mut zeros = m.fit.params.clone();
        normalize_signs(&mut zeros, self.start, self.problem.free);
        [1.0, -1.0]
            .iter()
            .map(|&sign| {
                let mut x = self.start.clone();
                for &c in &self.circles {
                    if let Some(id) = ParamId::from_column(joints, c) {
                        *x.get_mut(id) = crate::params::wrap(sign * zeros.get(id));
                    }
                }
                x
            })
            .collect()
    }

    /// The full LM from a twin `x`, weighed at `x` itself: its zeros are the
    /// minimum's, and weights from the start arm's zeros would slow LM down
    /// past any cap.
    fn restart(&self, x: &DhParams, phases: &mut [Phase]) -> Result<Minimum, CalibrationError> {
        let problem = self.problem;
        let timer = std::time::Instant::now();
        let x = problem.point(x);
        let here = problem.objective.reweighed(&x, 1.0)?;
        let fit = problem.lm(&here, &x, problem.free, problem.lm)?;
        phases[LM_PHASE].add_lm(&fit, timer.elapsed().as_secs_f64());
        reweigh(fit, problem, &mut phases[LM_PHASE])
    }

    /// A grid cell's or random draw's minimum: LM over the zero offsets
    /// alone, then the full LM.
    fn refine(&self, x: &DhParams, phases: &mut [Phase]) -> Result<Minimum, CalibrationError> {
        let problem = self.problem;
        let objective = problem.objective;
        let timer = std::time::Instant::now();
        let zeros = problem.lm(objective, &problem.point(x), &self.circles, &self.zero_lm)?;
        phases[ZEROS_PHASE].add_lm(&zeros, timer.elapsed().as_secs_f64());
        let timer = std::time::Instant::now();
        let fit = problem.lm(objective, &zeros.x, problem.free, &self.start_lm)?;
        phases[LM_PHASE].add_lm(&fit, timer.elapsed().as_secs_f64());
        settle(fit, self.problem, &mut phases[LM_PHASE], self.promising)
    }

    /// Records a start's minimum `m`; the stop when it is at the noise
    /// floor, or (with a robust loss) when its robust refit is — then the
    /// refit is the answer.
    fn judge_start(
        &self,
        tally: &mut Tally,
        m: Minimum,
    ) -> Result<Option<GlobalStop>, CalibrationError> {
        let robust = self.robust_floor(&m, &mut tally.phases)?;
        if self.judge(&mut tally.found, m) {
            return Ok(Some(GlobalStop::NoiseFloor));
        }
        Ok(robust.map(|r| {
            let found = &mut tally.found;
            (found.best, found.hits, found.noise_hits) = (Some(r), 1, 0);
            GlobalStop::RobustFloor
        }))
    }

    /// With a robust loss and stated noise, the robust refit (IRLS, as the
    /// final fit runs it) of a minimum `m` that misses the plain noise
    /// floor, when its scale is within the floor's `k` standard deviations
    /// of the stated noise and its geometry is plausible. A gross touch (a
    /// mislabelled socket) keeps every start's plain cost far off the
    /// floor and pulls its geometry, so the plain search alone would end on
    /// whichever minimum accommodates that touch best — a wrong one — and
    /// the robust refit after it would stay there; judged robustly, the
    /// right basin is found at once. `None` otherwise.
    fn robust_floor(
        &self,
        m: &Minimum,
        phases: &mut Vec<Phase>,
    ) -> Result<Option<Minimum>, CalibrationError> {
        let problem = self.problem;
        let (Some(robust), Some((lo, hi))) = (problem.robust, self.floor) else {
            return Ok(None);
        };
        if (lo..=hi).contains(&m.cost) || !m.cost.is_finite() {
            return Ok(None);
        }
        let timer = std::time::Instant::now();
        let base = problem.objective.reweighed(&m.fit.x, 1.0)?;
        let normal = base.normal(&m.fit.x, problem.free)?;
        let out = super::robust::irls(
            robust,
            &m.fit.x,
            (&base, &normal),
            problem.free,
            problem.lm,
            (true, 0.0),
        )?;
        // The refits' LM work, plus the normal equations here and the
        // standardised residuals before each refit and after the last.
        let name = format!("{} (judging a start)", out.phase.name);
        let at = match phases.iter().position(|p| p.name == name) {
            Some(at) => at,
            None => {
                phases.push(Phase::new(&name));
                phases.len() - 1
            }
        };
        let phase = &mut phases[at];
        phase.cost_evaluations += out.phase.cost_evaluations;
        phase.jacobian_evaluations += out.phase.jacobian_evaluations + out.fit.passes + 2;
        phase.seconds += timer.elapsed().as_secs_f64();
        if !out.within_floor(self.options.noise_floor_k) {
            return Ok(None);
        }
        let fit = out.last;
        let candidate = Minimum {
            cost: fit.normal.cost(),
            fit,
        };
        let plausible = (super::checks::gross_corrections(
            &self.in_start_signs(&candidate),
            self.start,
            problem.free,
        ))
        .is_empty();
        Ok(plausible.then_some(candidate))
    }

    /// Records `m` in `found`; whether it is at the noise floor. A minimum
    /// is a candidate only if its geometry is the nominal arm's kind (not
    /// its mirror image, not collapsed): the cost cannot tell.
    /// (`gross_corrections` compares twists modulo 2π.)
    fn judge(&self, found: &mut Found, m: Minimum) -> bool {
        let plausible = (super::checks::gross_corrections(
            &self.in_start_signs(&m),
            self.start,
            self.problem.free,
        ))
        .is_empty();
        let agree = |a: &Minimum, b: &Minimum| {
            let (lower, other) = if a.cost <= b.cost { (a, b) } else { (b, a) };
            let delta = self.difference(lower, other);
            let costs = (lower.cost, other.cost);
            agree_at_noise(costs, &lower.fit.normal, self.problem.dof, &delta)
        };
        found.record(m, self.floor, plausible, agree)
    }

    /// A minimum's geometry in the start's sign convention.
    fn in_start_signs(&self, m: &Minimum) -> DhParams {
        let mut p = m.fit.params.clone();
        normalize_signs(&mut p, self.start, self.problem.free);
        p
    }

    /// `other − lower` over the free columns, both geometries in the
    /// start's sign convention, angles wrapped.
    fn difference(&self, lower: &Minimum, other: &Minimum) -> Vec<f64> {
        let point = |m: &Minimum| {
            let mut x = m.fit.x.clone();
            let g = self.in_start_signs(m).to_vec();
            x[..g.len()].copy_from_slice(&g);
            x
        };
        let (a, b) = (point(lower), point(other));
        let geometry = self.start.param_count();
        (self.problem.free.iter())
            .map(|&c| {
                let d = b[c] - a[c];
                let angle = c < geometry
                    && self
                        .start
                        .param_id(c)
                        .is_some_and(|id| !id.kind.is_length());
                if angle { crate::params::wrap(d) } else { d }
            })
            .collect()
    }

    /// Agreement, without stated noise: the lowest cost reached from enough
    /// starts. (With stated noise only the floor stops the grid and the
    /// twins early.)
    fn agreement(&self, found: &Found) -> Option<GlobalStop> {
        (self.floor.is_none() && found.hits >= self.options.confirmations)
            .then_some(GlobalStop::Agreement)
    }

    /// The lowest minimum, finished if the per-start cap cut it off, and
    /// the account of the search.
    fn finish(
        &self,
        tally: Tally,
        stop: GlobalStop,
    ) -> Result<(LmResult, GlobalTrace, Vec<Phase>), CalibrationError> {
        let Tally {
            found,
            mut phases,
            grid_angles,
            grid_starts,
            random_starts,
            twin_restarts,
        } = tally;
        phases.retain(|p| p.cost_evaluations + p.jacobian_evaluations > 0);
        let Found {
            best,
            hits,
            noise_hits,
            minima,
            implausible,
        } = found;
        // The lowest minimum, plausible or not: an implausible one (a mirror
        // image) is then refused by the checks by name, not hidden behind a
        // worse plausible start.
        let mut best = match (best, implausible) {
            (Some(b), Some(i)) if i.cost < b.cost && stop == GlobalStop::StartBudget => i,
            (Some(b), _) => b,
            (None, i) => i.ok_or(CalibrationError::Shape)?,
        };
        // (A robust refit's last LM is under its weights: finishing it
        // plainly would undo it.)
        if best.fit.termination == super::Termination::MaxIterations
            && stop != GlobalStop::RobustFloor
        {
            best = self.finish_cut_off(best, &mut phases)?;
        }
        let trace = GlobalTrace {
            options: *self.options,
            stop,
            circles: self
                .circles
                .iter()
                .filter_map(|&c| self.start.param_id(c))
                .map(|id| id.to_string())
                .collect(),
            grid_angles,
            minima,
            grid_starts,
            random_starts,
            twin_restarts,
            best_hits: hits,
            noise_level_hits: noise_hits,
            noise_floor_cost: self.floor.map(|(_, hi)| hi),
            sign_changes: Vec::new(),
        };
        Ok((best.fit, trace, phases))
    }

    /// The lowest start was cut off by the per-start cap: finish its
    /// descent with the full LM rather than report it unconverged.
    fn finish_cut_off(
        &self,
        best: Minimum,
        phases: &mut Vec<Phase>,
    ) -> Result<Minimum, CalibrationError> {
        let problem = self.problem;
        let timer = std::time::Instant::now();
        let fit = problem.lm(problem.objective, &best.fit.x, problem.free, problem.lm)?;
        phases.push(Phase::new("lm, best start finished"));
        let last = phases.len() - 1;
        phases[last].add_lm(&fit, timer.elapsed().as_secs_f64());
        reweigh(fit, problem, &mut phases[last])
    }
}

/// A start's result: reweighed ([`reweigh`]) when its LM converged; one
/// cut off by the iteration cap is in a wrong basin (or crawling), and is
/// recorded where it stopped, its cost under the weights at that point.
fn settle(
    fit: LmResult,
    problem: &GlobalProblem<'_, '_>,
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
        let done = problem.lm(problem.objective, &fit.x, problem.free, problem.lm)?;
        phase.add_lm(&done, timer.elapsed().as_secs_f64());
        return settle(done, problem, phase, None);
    }
    if fit.termination == super::Termination::MaxIterations {
        // Compared with converged starts, which are weighed at themselves:
        // weigh this one at itself too (no refit), or a start whose weights
        // happen to be kind looks lowest.
        let cost = match problem.stated_dof {
            Some(_) => {
                let here = problem.objective.reweighed(&fit.x, 1.0)?;
                phase.cost_evaluations += 1;
                here.cost(&fit.x, problem.free, &mut Vec::new())?
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
    problem: &GlobalProblem<'_, '_>,
    phase: &mut Phase,
) -> Result<Minimum, CalibrationError> {
    if problem.stated_dof.is_none() {
        let cost = fit.normal.cost();
        return Ok(Minimum { fit, cost });
    }
    let timer = std::time::Instant::now();
    let here = problem.objective.reweighed(&fit.x, 1.0)?;
    let refit = problem.lm(&here, &fit.x, problem.free, problem.lm)?;
    phase.add_lm(&refit, timer.elapsed().as_secs_f64());
    let cost = refit.normal.cost();
    Ok(Minimum { fit: refit, cost })
}

/// The factor that turns the threads' times of refined starts into their
/// share of the `wall` time they took side by side, so that the phases'
/// times add up to the fit's (but for the share of a start refined in vain
/// beside one that stopped the search).
fn wall_share(refined: &[Result<(Minimum, Vec<Phase>), CalibrationError>], wall: f64) -> f64 {
    let threads: f64 = (refined.iter().flatten())
        .flat_map(|(_, phases)| phases.iter().map(|p| p.seconds))
        .sum();
    if threads > 0.0 { wall / threads } else { 1.0 }
}

/// The cost on a grid of `K` angles per circle (everything else at the
/// start); returns `K` and the lowest `candidates` grid cells that are
/// local minima among their `2·circles` neighbours, lowest first.
fn torus_grid(
    start: &DhParams,
    circles: &[usize],
    problem: &GlobalProblem<'_, '_>,
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
    let angle = |cell: usize, stride: usize| {
        let i = digit(cell, stride);
        crate::params::wrap(std::f64::consts::TAU * i as f64 / k as f64 - std::f64::consts::PI)
    };
    let place = |x: &mut DhParams, cell: usize| {
        for (id, &stride) in ids.iter().zip(&strides) {
            *x.get_mut(*id) = angle(cell, stride);
        }
    };
    // Chunks of 64 cells on the objective's threads: a cell's cost depends
    // on that cell alone, so the same costs on any count. A cancellation is
    // seen within a chunk's costs.
    const CELLS: usize = 64;
    let chunks: Vec<usize> = (0..cells.div_ceil(CELLS)).collect();
    let threads = problem.objective.threads();
    let parts = crate::parallel::parallel_map(&chunks, threads, |&chunk| {
        super::Cancel::check(problem.cancel.as_ref())?;
        // The start's point, its circles' columns set cell by cell (the
        // point of the arm `place` makes, without building it each time).
        let (mut x, mut xyz) = (problem.point(start), Vec::new());
        (chunk * CELLS..((chunk + 1) * CELLS).min(cells))
            .map(|cell| {
                for (&column, &stride) in circles.iter().zip(&strides) {
                    x[column] = angle(cell, stride);
                }
                // The data's cost (the prior does not steer the scan);
                // never NaN: a non-finite cost is +∞.
                Ok(problem.objective.data_cost(&x, &mut xyz)?)
            })
            .collect::<Result<Vec<f64>, CalibrationError>>()
    });
    let mut costs = Vec::with_capacity(cells);
    for part in parts {
        costs.extend(part?);
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
pub(crate) fn normalize_signs(
    params: &mut DhParams,
    nominal: &DhParams,
    free: &[usize],
) -> Vec<String> {
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

fn is_zero(n: &usize) -> bool {
    *n == 0
}

#[cfg(test)]
mod tests {
    /// Minima agree at the noise level when their costs differ by less than
    /// `cost/dof` and the arms by less than their joint uncertainty; not
    /// when either is farther.
    #[test]
    fn minima_agree_at_the_noise_level_only_within_it() {
        use super::agree_at_noise;
        let mut n = crate::residuals::Normal::new(&[0, 1]);
        // Information 4 and 1 per unit (σ 0.5 and 1 at unit variance).
        n.jtj = vec![4.0, 0.0, 0.0, 1.0];
        // cost 100 on 100 dof: s² = 1; the bound for p = 2 is 2 + 3·2 = 8.
        assert!(agree_at_noise((100.0, 100.9), &n, 100, &[0.5, 1.0]));
        assert!(
            !agree_at_noise((100.0, 101.1), &n, 100, &[0.5, 1.0]),
            "cost"
        );
        assert!(
            !agree_at_noise((100.0, 100.5), &n, 100, &[1.5, 0.0]),
            "arm: 9 > 8"
        );
        assert!(
            agree_at_noise((100.0, 100.5), &n, 100, &[1.4, 0.0]),
            "7.84 ≤ 8"
        );
        assert!(
            !agree_at_noise((0.0, 0.0), &n, 100, &[0.0, 0.0]),
            "no noise level"
        );
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn calibrate_global_normalize_signs() {
        use crate::{calibrate::global::normalize_signs, kernel::ArmKernel, params::DhParams};
        let nominal = DhParams::paper_nominal();
        let mut flipped = nominal.clone();
        flipped.joints[2].theta += std::f64::consts::PI;
        flipped.joints[2].a = -flipped.joints[2].a;
        flipped.joints[2].alpha = -flipped.joints[2].alpha;
        flipped.joints[3].theta += std::f64::consts::PI;
        let q = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6];
        let before = ArmKernel::new(&flipped).unwrap().position(&q).unwrap();
        let all: Vec<usize> = (0..27).collect();
        let changed = normalize_signs(&mut flipped, &nominal, &all);
        assert_eq!(changed, ["theta3", "a3", "alpha3", "theta4"]);
        assert!((flipped.joints[2].alpha - nominal.joints[2].alpha).abs() < 1e-12);
        let after = ArmKernel::new(&flipped).unwrap().position(&q).unwrap();
        assert!((0..3).all(|k| (before[k] - after[k]).abs() < 1e-9));
    }
}
