//! Simulated annealing as the paper runs it (method.md §5, Steps 1–8), and
//! the paper's switching rule for its hybrid (§6).
//!
//! - energy: [`Energy`] (the paper's OA plus the reference-length RMS), mm;
//! - moves: every free parameter at once, each by Ingber's generating
//!   distribution — the Cauchy-like law on `[−1, 1]` the paper describes,
//!   `y = sgn(u − ½)·τ·((1 + 1/τ)^{|2u−1|} − 1)` at relative temperature
//!   `τ = T/T0` — times the parameter's range (`step_mm`, `twist_step_deg`,
//!   `zero_step_deg`), so moves shrink as it cools but keep fat tails;
//! - Metropolis acceptance on `ΔE`, `L` moves per temperature, `T ← αT`;
//! - stop when `E < ε`, `T < T_min`, the evaluation budget is spent, or (the
//!   hybrid) the fitness `P = 1/(1 + E_best)` has stopped changing:
//!   `|s0·P_m − Σ_{j=1..s0} P_{m−j}| / (1 + P_m) ≤ ε1`.
//!
//! The loop allocates nothing: one parameter set is edited in place, the
//! kernel prepared from it (a few sin/cos), the energy computed into
//! [`Energy`]'s buffers.

use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

use super::CalibrationError;
use super::energy::Energy;
use crate::dataset::DataSet;
use crate::error::{OptionError, check_nonnegative};
use crate::kernel::ArmKernel;
use crate::params::{DhParams, ParamId, ParamKind};
use crate::setting::Setting;

/// Settings of the annealer; a builder. Defaults (documented in
/// docs/calibration.md): `T0 = 1 mm`, `α = 0.9`, `L = 100`,
/// `T_min = 1e-4 mm`, `ε = 0` (off: the noise sets a floor no one knows
/// beforehand), ranges 0.05 mm, 0.005°, 0.05° (the best of those tried on
/// the paper's campaign: wider ranges leave the acceptance at a few per
/// cent and the annealing stalls), at most 10⁶ evaluations.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AnnealOptions {
    /// Start temperature `T0`, mm (energy units).
    pub t0: f64,
    /// Cooling factor `α` (0 < α < 1).
    pub cooling: f64,
    /// Moves per temperature `L`.
    pub chain: usize,
    /// Lowest temperature `T_min`, mm.
    pub t_min: f64,
    /// Stopping energy `ε`, mm.
    pub target: f64,
    /// Move range of lengths (`a`, `d`, probe), mm.
    pub step_mm: f64,
    /// Move range of twists, degrees.
    pub twist_step_deg: f64,
    /// Move range of zero offsets, degrees.
    pub zero_step_deg: f64,
    /// Energy evaluation budget.
    pub max_evaluations: usize,
}

impl Default for AnnealOptions {
    fn default() -> Self {
        AnnealOptions {
            t0: 1.0,
            cooling: 0.9,
            chain: 100,
            t_min: 1e-4,
            target: 0.0,
            step_mm: 0.05,
            twist_step_deg: 0.005,
            zero_step_deg: 0.05,
            max_evaluations: 1_000_000,
        }
    }
}

setters!(AnnealOptions {
    t0: f64, "Sets `T0`.";
    cooling: f64, "Sets `α`.";
    chain: usize, "Sets `L`.";
    t_min: f64, "Sets `T_min`.";
    target: f64, "Sets `ε`.";
});

impl AnnealOptions {
    /// Checks the settings; the error names the setting (`anneal.t0`, …).
    ///
    /// ```
    /// use aacmm_core::calibrate::AnnealOptions;
    /// assert!(AnnealOptions::default().check().is_ok());
    /// let e = AnnealOptions::default().cooling(1.0).check().unwrap_err();
    /// assert_eq!(e.to_string(), "anneal.cooling = 1: must lie strictly between 0 and 1");
    /// ```
    pub fn check(&self) -> Result<(), OptionError> {
        for (field, v) in [
            (Setting::AnnealT0, self.t0),
            (Setting::AnnealTMin, self.t_min),
            (Setting::AnnealStepMm, self.step_mm),
            (Setting::AnnealTwistStep, self.twist_step_deg),
            (Setting::AnnealZeroStep, self.zero_step_deg),
        ] {
            check_nonnegative(field, v, false)?;
        }
        if !(self.cooling > 0.0 && self.cooling < 1.0) {
            return Err(OptionError::new(
                Setting::AnnealCooling,
                self.cooling,
                "must lie strictly between 0 and 1",
            ));
        }
        if self.chain == 0 {
            return Err(OptionError::new(
                Setting::AnnealChain,
                0,
                "at least one move per temperature",
            ));
        }
        if self.max_evaluations == 0 {
            return Err(OptionError::new(
                Setting::AnnealMaxEvaluations,
                0,
                "at least one evaluation",
            ));
        }
        check_nonnegative(Setting::AnnealTarget, self.target, true)
    }
}

/// The paper's switch from annealing to LM (method.md §6). Defaults:
/// `s0 = 5` temperatures, `ε1 = 1e-4`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SwitchRule {
    /// Window `s0` of best fitness values.
    pub window: usize,
    /// Threshold `ε1`.
    pub epsilon: f64,
}

impl Default for SwitchRule {
    fn default() -> Self {
        SwitchRule {
            window: 5,
            epsilon: 1e-4,
        }
    }
}

impl SwitchRule {
    /// Checks the rule; the error names the setting (`switch.window`,
    /// `switch.epsilon`).
    ///
    /// ```
    /// use aacmm_core::calibrate::SwitchRule;
    /// assert!(SwitchRule::default().check().is_ok());
    /// let e = SwitchRule { window: 0, epsilon: 1e-4 }.check().unwrap_err();
    /// assert_eq!(e.to_string(), "switch.window = 0: at least one temperature");
    /// ```
    pub fn check(&self) -> Result<(), OptionError> {
        if self.window == 0 {
            return Err(OptionError::new(
                Setting::SwitchWindow,
                0,
                "at least one temperature",
            ));
        }
        check_nonnegative(Setting::SwitchEpsilon, self.epsilon, true)
    }

    /// Whether the fitness history `p` (one per temperature, newest last)
    /// has stopped changing.
    ///
    /// ```
    /// use aacmm_core::calibrate::SwitchRule;
    /// let rule = SwitchRule { window: 3, epsilon: 1e-4 };
    /// assert!(!rule.switches(&[0.1, 0.2, 0.3, 0.4]));
    /// assert!(rule.switches(&[0.1, 0.5, 0.5, 0.5, 0.5]));
    /// assert!(!rule.switches(&[0.5, 0.5])); // not a full window yet
    /// ```
    pub fn switches(&self, p: &[f64]) -> bool {
        let s0 = self.window.max(1);
        if p.len() <= s0 {
            return false;
        }
        let m = p.len() - 1;
        let past: f64 = p[m - s0..m].iter().sum();
        (s0 as f64 * p[m] - past).abs() / (1.0 + p[m]) <= self.epsilon
    }
}

/// Why the annealing stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AnnealStop {
    /// The energy fell below `ε`.
    EnergyTarget,
    /// The temperature fell below `T_min`.
    Cooled,
    /// The evaluation budget ran out.
    EvaluationBudget,
    /// The hybrid's switching rule fired.
    Switched,
}

impl AnnealStop {
    /// A sentence for summaries.
    pub fn describe(self) -> &'static str {
        match self {
            AnnealStop::EnergyTarget => "energy below the stopping value",
            AnnealStop::Cooled => "temperature below the minimum",
            AnnealStop::EvaluationBudget => "evaluation budget spent",
            AnnealStop::Switched => "best fitness stopped changing (switch to LM)",
        }
    }
}

/// One temperature of an annealing run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AnnealStep {
    /// Temperature, mm.
    pub(crate) temperature: f64,
    /// Energy of the current state after the chain, mm.
    pub(crate) energy: f64,
    /// Best energy so far, mm.
    pub best: f64,
    /// Fraction of the chain's moves accepted.
    pub(crate) acceptance: f64,
}

/// The account of an annealing run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AnnealTrace {
    /// Settings.
    pub(crate) options: AnnealOptions,
    /// The switching rule, if the hybrid ran.
    pub(crate) switch_rule: Option<SwitchRule>,
    /// Why it stopped.
    pub stop: AnnealStop,
    /// Energy of the start, mm.
    pub start_energy: f64,
    /// Best energy, mm.
    pub best_energy: f64,
    /// Energy evaluations.
    pub(crate) evaluations: usize,
    /// One entry per temperature.
    pub temperatures: Vec<AnnealStep>,
}

/// Anneals the parameters `free` of `start` on `data`; with `switch`, stops
/// where the hybrid hands over. Returns the best parameters seen.
///
/// ```
/// use aacmm_core::{calibrate::*, calibrate::anneal::anneal, domain::Arm, params::DhParams, simulate::*};
/// use rand::SeedableRng;
/// let nominal = Arm::without_limits("n", DhParams::paper_nominal());
/// let campaign = simulate(&nominal, &CampaignSettings::new(3, ErrorModel::Paper, 6, 8)).unwrap();
/// let data = campaign.data_set().unwrap();
/// let free: Vec<usize> = (0..27).filter(|&c| ![6, 18, 23, 17, 24, 25].contains(&c)).collect();
/// let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
/// let options = AnnealOptions::default().chain(20);
/// let (best, trace) = anneal(&nominal.params, &data, &free, &options, None, &mut rng).unwrap();
/// assert!(trace.best_energy < trace.start_energy);
/// assert_eq!(trace.stop, AnnealStop::Cooled);
/// # let _ = best;
/// ```
pub fn anneal<R: Rng>(
    start: &DhParams,
    data: &DataSet,
    free: &[usize],
    options: &AnnealOptions,
    switch: Option<&SwitchRule>,
    rng: &mut R,
) -> Result<(DhParams, AnnealTrace), CalibrationError> {
    anneal_observed(start, data, free, options, switch, rng, &mut |_| Ok(()))
}

/// [`anneal`], reporting the fraction of the cooling schedule done after
/// each temperature to `progress`, which stops the annealing with its
/// error (a cancellation).
pub(crate) fn anneal_observed<R: Rng>(
    start: &DhParams,
    data: &DataSet,
    free: &[usize],
    options: &AnnealOptions,
    switch: Option<&SwitchRule>,
    rng: &mut R,
    progress: &mut dyn FnMut(f64) -> Result<(), CalibrationError>,
) -> Result<(DhParams, AnnealTrace), CalibrationError> {
    options.check()?;
    if let Some(rule) = switch {
        rule.check()?;
    }
    let ids: Vec<ParamId> = free
        .iter()
        .map(|&c| start.param_id(c).ok_or(CalibrationError::Shape))
        .collect::<Result<_, _>>()?;
    let ranges: Vec<f64> = ids
        .iter()
        .map(|id| match id.kind {
            ParamKind::Alpha | ParamKind::Beta => options.twist_step_deg.to_radians(),
            ParamKind::Theta => options.zero_step_deg.to_radians(),
            _ => options.step_mm,
        })
        .collect();
    let mut energy = Energy::new(data);
    let mut current = start.clone();
    let mut trial = start.clone();
    let mut e_current = energy.of(&current, data)?;
    if !e_current.is_finite() {
        return Err(CalibrationError::NonFiniteStart);
    }
    let start_energy = e_current;
    let mut best = current.clone();
    let mut e_best = e_current;
    let mut t = options.t0;
    let mut temperatures = Vec::new();
    let mut fitness = Vec::new();
    let span = (options.t0 / options.t_min).ln().max(f64::MIN_POSITIVE);
    let stop = loop {
        if e_best < options.target {
            break AnnealStop::EnergyTarget;
        }
        if t < options.t_min {
            break AnnealStop::Cooled;
        }
        if energy.evaluations >= options.max_evaluations {
            break AnnealStop::EvaluationBudget;
        }
        let tau = t / options.t0;
        let mut accepted = 0usize;
        for _ in 0..options.chain {
            // Every move rewrites all free parameters of `trial` from
            // `current` and the fixed ones never change, so `trial` needs no
            // resync after a rejection or a swap.
            for (id, range) in ids.iter().zip(&ranges) {
                *trial.get_mut(*id) = current.get(*id) + range * generate(tau, rng);
            }
            let e_trial = energy.of_kernel(&ArmKernel::new(&trial)?, data);
            let delta = e_trial - e_current;
            let accept =
                e_trial.is_finite() && (delta <= 0.0 || rng.random::<f64>() < (-delta / t).exp());
            if accept {
                accepted += 1;
                std::mem::swap(&mut current, &mut trial);
                e_current = e_trial;
                if e_current < e_best {
                    e_best = e_current;
                    best.clone_from(&current);
                }
            }
            if energy.evaluations >= options.max_evaluations {
                break;
            }
        }
        temperatures.push(AnnealStep {
            temperature: t,
            energy: e_current,
            best: e_best,
            acceptance: accepted as f64 / options.chain as f64,
        });
        fitness.push(1.0 / (1.0 + e_best));
        progress(((options.t0 / t).ln() / span).clamp(0.0, 1.0))?;
        if let Some(rule) = switch
            && rule.switches(&fitness)
        {
            break AnnealStop::Switched;
        }
        t *= options.cooling;
    };
    Ok((
        best,
        AnnealTrace {
            options: *options,
            switch_rule: switch.copied(),
            stop,
            start_energy,
            best_energy: e_best,
            evaluations: energy.evaluations,
            temperatures,
        },
    ))
}

/// Ingber's generating distribution at relative temperature `tau`: on
/// `[−1, 1]`, concentrated near 0 as `tau` falls, with Cauchy-like tails.
fn generate<R: Rng>(tau: f64, rng: &mut R) -> f64 {
    let u: f64 = rng.random();
    let y = tau * ((1.0 + 1.0 / tau).powf((2.0 * u - 1.0).abs()) - 1.0);
    if u < 0.5 { -y } else { y }
}
