//! The settings of a calibration, and the one place that checks them.
//!
//! Two homes, one for each side: [`ModelOptions`] (what is fitted and how
//! the result is judged: noise, fixed set, loss, tolerances — the problem
//! holds them) and [`SolverSettings`] (how it is solved: method, LM,
//! annealing, global search, threads, seed). Every setting is checked before
//! any work starts; a setting out of range is an [`OptionError`] naming the
//! setting's path in its struct (`noise.probe_mm`, `anneal.cooling`, `fix`,
//! `threads`). Front ends map those paths to their own spelling: the command
//! line to its flags, the C API to its option names.

use serde::{Deserialize, Serialize};

use super::{AnnealOptions, GlobalOptions, LmOptions, Method, SwitchRule};
use crate::error::{MAX_SEED, OptionError, seed_bound};
use crate::params::{ParamId, param_count};
use crate::residuals::Noise;
use crate::setting::Setting;

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
    /// let e = FixSpec::parse("theta9", 6).unwrap_err();
    /// assert_eq!(e.field(), "fix");
    /// assert!(e.reason.contains("unknown parameter `theta9`"));
    /// let e = FixSpec::parse("auto,theta1", 6).unwrap_err();
    /// assert!(e.reason.contains("`auto` stands alone"), "{e}");
    /// let e = FixSpec::parse("a1, theta1,a1", 6).unwrap_err();
    /// assert_eq!(e.to_string(), "fix = a1, theta1,a1: `a1` is listed twice");
    /// ```
    pub fn parse(s: &str, joints: usize) -> Result<FixSpec, OptionError> {
        let names: Vec<String> = ParamId::all(joints).map(|p| p.to_string()).collect();
        FixSpec::parse_names(s, &names, |t| {
            ParamId::parse(t, joints).map(|id| id.column(joints))
        })
    }

    /// [`FixSpec::parse`] for `arm`: a Hayati joint's d-slot is `hbeta…`
    /// and has no `d…` (and a D-H joint no `hbeta…`), so a name of the
    /// other model is refused rather than fixing the slot silently.
    pub(crate) fn parse_for(
        s: &str,
        arm: &crate::params::DhParams,
    ) -> Result<FixSpec, OptionError> {
        let names: Vec<String> = arm.param_ids().map(|p| p.to_string()).collect();
        let n = arm.joint_count();
        let fix = FixSpec::parse_names(s, &names, |t| arm.parse_param(t).map(|id| id.column(n)));
        // Say why a name of the other model is unknown.
        if fix.is_err()
            && let Some((t, id)) = s.split(',').map(str::trim).find_map(|t| {
                ParamId::parse(t, n)
                    .filter(|&id| id.kind.is_d_slot() && !arm.has_param(id))
                    .map(|id| (t, id))
            })
        {
            let j = id.index + 1;
            let reason = match id.kind {
                crate::params::ParamKind::D => {
                    format!("joint {j} is a Hayati joint: its d-slot is `hbeta{j}`, not `{t}`")
                }
                _ => format!("joint {j} is a D-H joint: its d-slot is `d{j}`, not `{t}`"),
            };
            return Err(OptionError::new(Setting::Fix, s, reason));
        }
        fix
    }

    fn parse_names(
        s: &str,
        names: &[String],
        column: impl Fn(&str) -> Option<usize>,
    ) -> Result<FixSpec, OptionError> {
        if s.trim() == "auto" {
            return Ok(FixSpec::Auto);
        }
        s.split(',')
            .map(str::trim)
            .filter(|t| !t.is_empty())
            .map(|t| {
                if t == "auto" {
                    return Err(OptionError::new(
                        Setting::Fix,
                        s,
                        "`auto` stands alone (the recommended set); otherwise list the \
                         parameters to fix",
                    ));
                }
                column(t).ok_or_else(|| {
                    OptionError::new(
                        Setting::Fix,
                        s,
                        format!(
                            "unknown parameter {}; parameters are {} … {}",
                            crate::error::quoted(t),
                            names.first().map_or("", String::as_str),
                            names.last().map_or("", String::as_str)
                        ),
                    )
                })
            })
            .collect::<Result<Vec<usize>, _>>()
            .and_then(|columns| {
                // Named as given: `a1` listed twice, not column 0.
                match columns
                    .iter()
                    .enumerate()
                    .find(|(i, c)| columns[..*i].contains(c))
                {
                    Some((_, &c)) => Err(OptionError::new(
                        Setting::Fix,
                        s,
                        format!(
                            "`{}` is listed twice",
                            names.get(c).map_or("?", String::as_str)
                        ),
                    )),
                    None => Ok(FixSpec::Columns(columns)),
                }
            })
    }
}

impl FixSpec {
    /// In words: `auto`, or the names of the parameters fixed.
    ///
    /// ```
    /// use aacmm_core::calibrate::FixSpec;
    /// assert_eq!(FixSpec::Columns(vec![18, 6]).describe(6), "theta1,d1");
    /// ```
    pub fn describe(&self, joints: usize) -> String {
        match self {
            FixSpec::Auto => "auto".to_string(),
            FixSpec::Columns(c) => c
                .iter()
                .filter_map(|&c| ParamId::from_column(joints, c))
                .map(|id| id.to_string())
                .collect::<Vec<_>>()
                .join(","),
        }
    }

    /// [`FixSpec::describe`] with `arm`'s names (`hbeta…` for a Hayati
    /// joint's d-slot).
    pub(crate) fn describe_for(&self, arm: &crate::params::DhParams) -> String {
        match self {
            FixSpec::Auto => "auto".to_string(),
            FixSpec::Columns(c) => c
                .iter()
                .filter_map(|&c| arm.param_id(c))
                .map(|id| id.to_string())
                .collect::<Vec<_>>()
                .join(","),
        }
    }
}

/// What a calibration fits and how its result is judged: the model's side
/// of the settings, which the problem holds (the data's noise, the fixed
/// set, the loss, the stated tolerances, the verdict's policy). How it is
/// solved is [`SolverSettings`]'s.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelOptions {
    /// The fixed set.
    pub fix: FixSpec,
    /// What is known of the noise.
    pub noise: Noise,
    /// Call a fit usable even when its χ² is far outside the stated noise or
    /// the calibrated arm is worse than the nominal on its own data (never
    /// a mirror-image or collapsed arm).
    #[serde(default)]
    pub accept_poor_fit: bool,
    /// A robust fit (IRLS with a Huber or Cauchy loss) after the solver;
    /// `None`, plain least squares (the default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robust: Option<super::robust::Robust>,
    /// Stated tolerances of the nominal geometry: a prior
    /// ([`super::prior`]); `None` (the default) fits the data alone.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prior: Option<crate::tolerances::Tolerances>,
    /// Models beyond geometry the fit estimates (compliance, encoder
    /// harmonics, thermal expansion, drift: [`crate::corrections`]); none
    /// by default.
    #[serde(default, skip_serializing_if = "crate::corrections::Beyond::is_empty")]
    pub beyond: crate::corrections::Beyond,
}

impl Default for ModelOptions {
    fn default() -> Self {
        ModelOptions {
            fix: FixSpec::Auto,
            noise: Noise::default(),
            accept_poor_fit: false,
            robust: None,
            prior: None,
            beyond: crate::corrections::Beyond::default(),
        }
    }
}

impl ModelOptions {
    /// Checks every setting for an arm of `joints` joints: the first one
    /// out of range is refused by its path.
    ///
    /// ```
    /// use aacmm_core::calibrate::{FixSpec, ModelOptions};
    /// assert!(ModelOptions::default().check(6).is_ok());
    /// let o = ModelOptions { fix: FixSpec::Columns(vec![3, 27]), ..Default::default() };
    /// assert_eq!(o.check(6).unwrap_err().field(), "fix");
    /// ```
    pub fn check(&self, joints: usize) -> Result<(), OptionError> {
        self.noise.check()?;
        if let FixSpec::Columns(columns) = &self.fix {
            check_fixed_columns(columns, joints)?;
        }
        if let Some(t) = &self.prior {
            t.check(joints)?;
        }
        self.beyond.check(joints)?;
        match &self.robust {
            Some(r) => r.check(),
            None => Ok(()),
        }
    }

    /// [`ModelOptions::check`] for the arm `arm`, and the prior's
    /// parameters are the arm's (`crate::tolerances::Tolerances::check_for`:
    /// a Hayati joint has `hbeta…`, not `d…`).
    pub fn check_for(&self, arm: &crate::params::DhParams) -> Result<(), OptionError> {
        self.check(arm.joint_count())?;
        match &self.prior {
            Some(t) => t.check_for(arm),
            None => Ok(()),
        }
    }
}

/// Refuses fixed columns out of range for a `joints`-joint arm, or listed
/// twice.
fn check_fixed_columns(columns: &[usize], joints: usize) -> Result<(), OptionError> {
    let count = param_count(joints);
    if let Some(&c) = columns.iter().find(|&&c| c >= count) {
        return Err(OptionError::new(
            Setting::Fix,
            c,
            format!(
                "column {c}: a {joints}-joint arm has parameters 0 to {}",
                count - 1
            ),
        ));
    }
    let mut sorted = columns.to_vec();
    sorted.sort_unstable();
    if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
        let name = ParamId::from_column(joints, w[0]).map_or(String::new(), |p| format!(" ({p})"));
        return Err(OptionError::new(
            Setting::Fix,
            w[0],
            format!("column {}{name} is listed twice", w[0]),
        ));
    }
    Ok(())
}

/// How a calibration is solved: the method and its settings, the worker
/// threads and the seed — each in this one place. Results never depend on
/// the threads; the same seed gives the same bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverSettings {
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
    /// Worker threads (≥ 1); the default is every core the system offers.
    pub threads: usize,
    /// Seed of every random draw (annealing moves, starts, folds).
    pub seed: u64,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            method: Method::default(),
            lm: LmOptions::default(),
            anneal: AnnealOptions::default(),
            switch: SwitchRule::default(),
            global: GlobalOptions::default(),
            threads: available_threads(),
            seed: 0,
        }
    }
}

/// The cores the system offers this process (1 when it cannot tell), at
/// most [`MAX_THREADS`].
///
/// ```
/// use aacmm_core::calibrate::{MAX_THREADS, available_threads};
/// assert!((1..=MAX_THREADS).contains(&available_threads()));
/// ```
pub fn available_threads() -> usize {
    crate::parallel::every_core().min(MAX_THREADS)
}

/// Most worker threads a caller may ask for (`threads`, `--threads`), in
/// every front end: more than the cores of any machine the library runs
/// on, and few enough that starting them cannot exhaust a process's
/// threads or address space (a hostile `threads = 2^62` is refused, not
/// attempted).
pub const MAX_THREADS: usize = 1024;

/// Refuses a worker count outside `1..=`[`MAX_THREADS`], naming `threads`
/// (front ends name their own spelling of it).
///
/// ```
/// use aacmm_core::calibrate::{MAX_THREADS, check_threads};
/// assert!(check_threads(1).is_ok() && check_threads(MAX_THREADS).is_ok());
/// assert_eq!(check_threads(0).unwrap_err().to_string(), "threads = 0: at least 1");
/// assert_eq!(
///     check_threads(1 << 62).unwrap_err().to_string(),
///     "threads = 4611686018427387904: at most 1024 worker threads (more than the cores \
///      give no speed)"
/// );
/// ```
pub fn check_threads(threads: usize) -> Result<(), OptionError> {
    match threads {
        0 => Err(OptionError::new(Setting::Threads, 0, "at least 1")),
        n if n > MAX_THREADS => Err(OptionError::new(
            Setting::Threads,
            n,
            format!("at most {MAX_THREADS} worker threads (more than the cores give no speed)"),
        )),
        _ => Ok(()),
    }
}

impl SolverSettings {
    /// Checks every setting: the first one out of range is refused by its
    /// path (`lm.ftol`, `anneal.cooling`, `global.max_starts`, `threads`, …).
    ///
    /// ```
    /// use aacmm_core::calibrate::SolverSettings;
    /// assert!(SolverSettings::default().check().is_ok());
    /// let s = SolverSettings { threads: 0, ..Default::default() };
    /// assert_eq!(s.check().unwrap_err().field(), "threads");
    /// ```
    pub fn check(&self) -> Result<(), OptionError> {
        check_threads(self.threads)?;
        if self.seed > MAX_SEED {
            return Err(OptionError::new(
                Setting::Seed,
                self.seed,
                seed_bound(self.seed),
            ));
        }
        if self.method == Method::External {
            return Err(OptionError::new(
                Setting::Method,
                self.method.name(),
                "the library has no solver of that name: pass yours to session::run",
            ));
        }
        self.lm.check()?;
        self.anneal.check()?;
        self.switch.check()?;
        self.global.check()
    }

    /// These settings with `method`.
    pub fn with_method(self, method: Method) -> SolverSettings {
        SolverSettings { method, ..self }
    }

    /// These settings with `seed`.
    pub fn with_seed(self, seed: u64) -> SolverSettings {
        SolverSettings { seed, ..self }
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn calibrate_options_fixspec_parse_for() {
        use crate::{
            calibrate::FixSpec,
            params::{DhParams, JointModel},
        };
        let mut arm = DhParams::paper_nominal();
        arm.joints[1].model = JointModel::Hayati;
        assert_eq!(
            FixSpec::parse_for("hbeta2", &arm).unwrap(),
            FixSpec::Columns(vec![7])
        );
        let e = FixSpec::parse_for("d2", &arm).unwrap_err();
        assert!(
            e.reason
                .contains("joint 2 is a Hayati joint: its d-slot is `hbeta2`"),
            "{e}"
        );
    }
}
