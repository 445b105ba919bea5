//! The search itself: its tally, the grid over the zero offsets' circles,
//! the zero offsets' LM from each cell, random starts, and each start's
//! minimum settled and reweighed.

use super::grid::torus_grid;
use super::*;

/// The phases of [`Tally::phases`], by index.
const START_PHASE: usize = 0;
const GRID_PHASE: usize = 1;
const ZEROS_PHASE: usize = 2;
const LM_PHASE: usize = 3;

/// What the search has found and spent so far.
pub(super) struct Tally {
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
    pub(super) fn new() -> Tally {
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
pub(super) struct Search<'a, 'o> {
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
    pub(super) fn new(
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
    pub(super) fn run<R: Rng>(
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
        let out = crate::calibrate::robust::irls(
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
        let plausible = (crate::calibrate::checks::gross_corrections(
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
        let plausible = (crate::calibrate::checks::gross_corrections(
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
    pub(super) fn finish(
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
        if best.fit.termination == crate::calibrate::Termination::MaxIterations
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
    if fit.termination == crate::calibrate::Termination::MaxIterations
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
    if fit.termination == crate::calibrate::Termination::MaxIterations {
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
