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

mod grid;
mod search;
mod signs;

use search::{Search, Tally};
pub(crate) use signs::normalize_signs;

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
