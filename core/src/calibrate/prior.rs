//! Prior knowledge of the arm: stated tolerances of the nominal geometry,
//! entering the least squares as whitened pseudo-observations (a maximum a
//! posteriori fit).
//!
//! A tolerance `σ_k` (1σ, what the manufacturer knows from machining and
//! assembly) on a FREE parameter adds the residual `r_k = (p_k − p0_k)/σ_k`,
//! `p0` the nominal (start) arm's value, angles wrapped to ±π:
//!
//! ```text
//! JᵀJ += diag(1/σ²)      Jᵀr += (p − p0)/σ²      cost += Σ r_k²
//! ```
//!
//! Each such row counts in the degrees of freedom (`m + prior rows − p`), so
//! χ² and σ̂ stay honest, and the covariance comes from the augmented normal
//! matrix. A direction the data barely see is then held near nominal by its
//! tolerance instead of absorbing noise; a well-determined one hardly moves
//! (its data information dwarfs `1/σ²`).
//!
//! Where the prior acts: every Levenberg–Marquardt fit (hence `lm`, the
//! final LM of `hybrid` and `global`, and `global`'s comparison of minima,
//! which are LM costs), the covariance and the degrees of freedom. The
//! annealer's energy ignores it (the annealer only finds a start; its LM
//! polish, and a `sa` result's covariance, include it).
//!
//! `fix = auto` is decided on the data alone: parameters the data can never
//! determine (base motion, the redundant last link, scale without a length)
//! stay fixed — a prior would only split a data-determined sum between them
//! by their tolerances; weak but identifiable directions were already free
//! and are now regularised by the prior.
//!
//! Tolerances are given per class, per kind or per parameter
//! ([`Tolerances`]); the most specific applies.

use serde::{Deserialize, Serialize};

use super::OptionError;
use crate::params::{DhParams, ParamId, ParamKind, wrap};
use crate::residuals::Normal;

/// The kinds' names as targets (not a `match`, so that a new kind
/// elsewhere does not break this file).
const KINDS: [(&str, ParamKind); 5] = [
    ("a", ParamKind::A),
    ("d", ParamKind::D),
    ("alpha", ParamKind::Alpha),
    ("theta", ParamKind::Theta),
    ("probe", ParamKind::Probe),
];

/// What a tolerance applies to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Target {
    /// Every length (`a`, `d`, probe).
    Length,
    /// Every angle (`alpha`, `theta`).
    Angle,
    /// Every parameter of one kind (`a`, `d`, `alpha`, `theta`, `probe`).
    Kind(ParamKind),
    /// One parameter.
    Param(ParamId),
}

impl Target {
    /// Parses a target name for an `n`-joint arm: `length`, `angle`, `a`,
    /// `d`, `alpha` (or `beta`), `theta`, `probe`, or a parameter name
    /// (`a1`, `theta5`, `Bz`).
    pub fn parse(name: &str, n: usize) -> Option<Target> {
        if let Some((_, k)) = KINDS.iter().find(|(k, _)| *k == name) {
            return Some(Target::Kind(*k));
        }
        Some(match name {
            "length" => Target::Length,
            "angle" => Target::Angle,
            "beta" => Target::Kind(ParamKind::Alpha),
            "B" => Target::Kind(ParamKind::Probe),
            _ => Target::Param(ParamId::parse(name, n)?),
        })
    }

    /// Whether the target is lengths (mm) rather than angles.
    pub fn is_length(self) -> bool {
        match self {
            Target::Length => true,
            Target::Angle => false,
            Target::Kind(k) => k.is_length(),
            Target::Param(id) => id.kind.is_length(),
        }
    }

    /// How specific the target is (a parameter beats its kind, a kind its
    /// class).
    fn rank(self) -> u8 {
        match self {
            Target::Length | Target::Angle => 0,
            Target::Kind(_) => 1,
            Target::Param(_) => 2,
        }
    }

    fn covers(self, id: ParamId) -> bool {
        match self {
            Target::Length => id.kind.is_length(),
            Target::Angle => !id.kind.is_length(),
            Target::Kind(k) => id.kind == k,
            Target::Param(p) => p == id,
        }
    }

    /// The name users write.
    pub fn name(self) -> String {
        match self {
            Target::Length => "length".into(),
            Target::Angle => "angle".into(),
            Target::Kind(k) => KINDS
                .iter()
                .find(|(_, kind)| *kind == k)
                .map_or_else(|| format!("{k:?}").to_lowercase(), |(n, _)| n.to_string()),
            Target::Param(id) => id.to_string(),
        }
    }
}

/// Why a tolerance is refused (the front end adds the place: file, line
/// and key, or the flag).
fn check_value(target: Target, value: f64, unit: &str) -> Result<f64, String> {
    let name = target.name();
    if !value.is_finite() || value <= 0.0 {
        return Err(format!(
            "tolerance of {name} must be a finite number > 0 (got {value} {unit}); leave a \
             parameter out to give it no prior"
        ));
    }
    let internal = match (target.is_length(), unit) {
        (true, "mm") => value,
        (true, "m") => value * 1000.0,
        (false, "deg") => value.to_radians(),
        (false, "rad") => value,
        (true, _) => return Err(format!("{name} is a length: give its tolerance in mm or m")),
        (false, _) => {
            return Err(format!(
                "{name} is an angle: give its tolerance in deg or rad"
            ));
        }
    };
    if !(internal.is_finite() && internal > 0.0) {
        return Err(format!(
            "tolerance of {name} = {value} {unit} is not representable"
        ));
    }
    if let Some(why) = out_of_range(internal) {
        return Err(format!("tolerance of {name} = {value} {unit}: {why}"));
    }
    Ok(internal)
}

/// The tolerances a prior can carry, mm or rad: a pseudo-observation
/// `Δ/σ` must stay far from overflow for any correction (σ = 1e-300 made
/// the cost infinite), and one beyond 1e12 constrains nothing.
const SIGMA_RANGE: std::ops::RangeInclusive<f64> = 1e-12..=1e12;

/// Why a tolerance `sigma` (mm or rad) is out of [`SIGMA_RANGE`], if it is.
fn out_of_range(sigma: f64) -> Option<&'static str> {
    if sigma < *SIGMA_RANGE.start() {
        Some(
            "below 1e-12 (mm or rad): a parameter known that well should be fixed, not given a tolerance",
        )
    } else if sigma > *SIGMA_RANGE.end() {
        Some(
            "above 1e12 (mm or rad): that constrains nothing; leave the parameter out to give it no prior",
        )
    } else {
        None
    }
}

/// Why `target` (written `name`) is not a parameter of the arm `params`, if
/// it is not: the d-slot of a Hayati joint is `hbeta…`, of a D-H joint `d…`.
pub(crate) fn not_in_arm(target: Target, name: &str, params: &DhParams) -> Option<String> {
    let Target::Param(id) = target else {
        return None;
    };
    if params.has_param(id) {
        return None;
    }
    let j = id.index + 1;
    Some(match id.kind {
        ParamKind::D => {
            format!("joint {j} is a Hayati joint: its d-slot is `hbeta{j}`, not `{name}`")
        }
        _ => format!("joint {j} is a D-H joint: its d-slot is `d{j}`, not `{name}`"),
    })
}

/// Stated 1σ tolerances of the nominal geometry (mm, rad inside): per class
/// (`length`, `angle`), per kind (`a`, `d`, `alpha`, `theta`, `probe`) and
/// per parameter (`theta5`); the most specific applies. Empty = no prior.
///
/// ```
/// use aacmm_core::calibrate::Tolerances;
/// let t = Tolerances::parse("length=0.5mm, angle=0.1deg, theta5=0.05deg", 6).unwrap().unwrap();
/// let s = t.sigmas(6);
/// assert_eq!(s[0], Some(0.5)); // a1
/// assert!((s[18 + 4].unwrap() - 0.05f64.to_radians()).abs() < 1e-18); // theta5
/// assert!((s[18].unwrap() - 0.1f64.to_radians()).abs() < 1e-18); // theta1
/// assert_eq!(Tolerances::parse("none", 6).unwrap(), None);
/// let e = Tolerances::parse("theta5=0.05mm", 6).unwrap_err();
/// assert_eq!(e.field, "prior");
/// assert!(e.reason.contains("theta5 is an angle"), "{e}");
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Tolerances {
    /// `(target, σ in mm or rad)`, in the order given; a later entry for the
    /// same target replaces an earlier one.
    entries: Vec<(String, f64)>,
}

impl Tolerances {
    /// No tolerances.
    pub fn new() -> Tolerances {
        Tolerances::default()
    }

    /// Whether no tolerance is stated.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Sets the tolerance of `target` to `value` in `unit` (`mm`, `m`,
    /// `deg`, `rad`), replacing an earlier one for the same target. The
    /// error is a reason, for the caller to place.
    pub fn set(&mut self, target: Target, value: f64, unit: &str) -> Result<(), String> {
        let sigma = check_value(target, value, unit)?;
        let name = target.name();
        self.entries.retain(|(n, _)| *n != name);
        self.entries.push((name, sigma));
        Ok(())
    }

    /// Removes the tolerance of the target named `name` (as written:
    /// `d2`, `length`); whether there was one.
    pub fn remove(&mut self, name: &str) -> bool {
        let before = self.entries.len();
        self.entries.retain(|(n, _)| n != name);
        self.entries.len() != before
    }

    /// These tolerances, each replaced or extended by `other`'s (the command
    /// line over the arm file).
    pub fn overridden_by(mut self, other: &Tolerances) -> Tolerances {
        for (name, sigma) in &other.entries {
            self.entries.retain(|(n, _)| n != name);
            self.entries.push((name.clone(), *sigma));
        }
        self
    }

    /// Parses the command line's `--prior`: `none` (no prior, `Ok(None)`),
    /// or comma-separated `TARGET=VALUEUNIT` (`length=0.5mm,angle=0.1deg,
    /// theta5=0.05deg`, units `mm`, `m`, `deg`, `rad`) for an `n`-joint arm.
    /// Errors name the field `prior`.
    pub fn parse(s: &str, n: usize) -> Result<Option<Tolerances>, OptionError> {
        if s.trim() == "none" {
            return Ok(None);
        }
        let refuse = |why: String| OptionError::new("prior", s, why);
        let mut t = Tolerances::new();
        for item in s.split(',').map(str::trim).filter(|i| !i.is_empty()) {
            let (name, value) = item.split_once('=').ok_or_else(|| {
                refuse(format!(
                    "`{item}`: expected TARGET=VALUEUNIT, e.g. length=0.5mm or theta5=0.05deg \
                     (or `none`)"
                ))
            })?;
            let (name, value) = (name.trim(), value.trim());
            let target = Target::parse(name, n).ok_or_else(|| refuse(unknown_target(name, n)))?;
            let split = value
                .find(|c: char| c.is_ascii_alphabetic() && c != 'e' && c != 'E')
                .or_else(|| {
                    // `inf`, `nan` and a trailing unit all start with a letter.
                    value.find(|c: char| c.is_ascii_alphabetic())
                })
                .unwrap_or(value.len());
            let (number, unit) = value.split_at(split);
            let number: f64 = number.trim().parse().map_err(|_| {
                refuse(format!(
                    "`{item}`: `{}` is not a number followed by a unit (mm, m, deg, rad)",
                    number.trim()
                ))
            })?;
            if unit.trim().is_empty() {
                return Err(refuse(format!(
                    "`{item}`: no unit; write it after the number ({} for {name})",
                    if target.is_length() { "mm" } else { "deg" }
                )));
            }
            t.set(target, number, unit.trim())
                .map_err(|why| refuse(format!("`{item}`: {why}")))?;
        }
        if t.is_empty() {
            return Err(refuse(
                "no tolerance given; write e.g. length=0.5mm,angle=0.1deg (or `none`)".into(),
            ));
        }
        Ok(Some(t))
    }

    /// Per column of an `n`-joint arm (the fixed order), the tolerance
    /// (mm or rad) that applies, if any.
    pub fn sigmas(&self, n: usize) -> Vec<Option<f64>> {
        self.sigmas_of(n, ParamId::all(n))
    }

    /// Per column of the arm `params`, the tolerance (mm or rad) that
    /// applies, if any: as [`Tolerances::sigmas`], with a Hayati joint's
    /// d-slot the angle `hbeta…` (covered by `angle`, not `length` or `d`).
    pub fn sigmas_for(&self, params: &DhParams) -> Vec<Option<f64>> {
        self.sigmas_of(params.joint_count(), params.param_ids())
    }

    fn sigmas_of(&self, n: usize, ids: impl Iterator<Item = ParamId>) -> Vec<Option<f64>> {
        let targets: Vec<(Target, f64)> = self
            .entries
            .iter()
            .filter_map(|(name, s)| Some((Target::parse(name, n)?, *s)))
            .collect();
        ids.map(|id| {
            targets
                .iter()
                .filter(|(t, _)| t.covers(id))
                .max_by_key(|(t, _)| t.rank())
                .map(|(_, s)| *s)
        })
        .collect()
    }

    /// [`Tolerances::check`] for the arm `params`, and each parameter named
    /// exists in it: a Hayati joint's d-slot is `hbeta…` and has no `d…`
    /// (a D-H joint no `hbeta…`), so a tolerance of the other model would
    /// hold nothing — and the fit would count its direction as held.
    ///
    /// ```
    /// use aacmm_core::{calibrate::Tolerances, params::{DhParams, JointModel}};
    /// let mut arm = DhParams::paper_nominal();
    /// arm.joints[1].model = JointModel::Hayati;
    /// let t = Tolerances::parse("hbeta2=0.1deg", 6).unwrap().unwrap();
    /// assert!(t.check_for(&arm).is_ok());
    /// let e = Tolerances::parse("d2=1mm", 6).unwrap().unwrap().check_for(&arm).unwrap_err();
    /// assert!(e.reason.contains("joint 2 is a Hayati joint: its d-slot is `hbeta2`"), "{e}");
    /// let e = t.check_for(&DhParams::paper_nominal()).unwrap_err();
    /// assert!(e.reason.contains("joint 2 is a D-H joint: its d-slot is `d2`"), "{e}");
    /// ```
    pub fn check_for(&self, params: &DhParams) -> Result<(), OptionError> {
        let n = params.joint_count();
        self.check(n)?;
        for (name, _) in &self.entries {
            if let Some(why) = Target::parse(name, n).and_then(|t| not_in_arm(t, name, params)) {
                return Err(OptionError::new("prior", name, why));
            }
        }
        Ok(())
    }

    /// Checks the entries for an `n`-joint arm (each target exists, each
    /// σ finite and positive); the error names the field `prior`.
    pub fn check(&self, n: usize) -> Result<(), OptionError> {
        for (name, s) in &self.entries {
            if Target::parse(name, n).is_none() {
                return Err(OptionError::new("prior", name, unknown_target(name, n)));
            }
            if !(s.is_finite() && *s > 0.0) {
                return Err(OptionError::new(
                    "prior",
                    format!("{name}={s}"),
                    "a tolerance must be a finite number > 0",
                ));
            }
            if let Some(why) = out_of_range(*s) {
                return Err(OptionError::new("prior", format!("{name}={s}"), why));
            }
        }
        Ok(())
    }

    /// In words, user units: `length=0.5mm, angle=0.1deg, theta5=0.05deg`.
    pub fn describe(&self, n: usize) -> String {
        self.entries
            .iter()
            .map(|(name, s)| match Target::parse(name, n) {
                Some(t) if !t.is_length() => format!("{name}={}deg", short(s.to_degrees())),
                _ => format!("{name}={}mm", short(*s)),
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

fn short(v: f64) -> String {
    crate::residuals::short(v)
}

/// Why a target name is refused.
pub(crate) fn unknown_target(name: &str, n: usize) -> String {
    let last = ParamId::all(n)
        .last()
        .map_or(String::new(), |p| p.to_string());
    format!(
        "unknown target `{name}`: use length, angle, a, d, alpha, theta, probe, or a \
         parameter name (a1 … {last})"
    )
}

/// The resolved prior of one fit: nominal values and tolerances per column.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PriorTerm {
    nominal: Vec<f64>,
    sigma: Vec<Option<f64>>,
    angle: Vec<bool>,
}

impl PriorTerm {
    /// The prior of `tolerances` around the arm `nominal`; `None` when no
    /// tolerance applies to any parameter.
    pub fn new(tolerances: &Tolerances, nominal: &DhParams) -> Option<PriorTerm> {
        let sigma = tolerances.sigmas_for(nominal);
        if sigma.iter().all(Option::is_none) {
            return None;
        }
        Some(PriorTerm {
            nominal: nominal.to_vec(),
            sigma,
            angle: nominal.param_ids().map(|id| !id.kind.is_length()).collect(),
        })
    }

    /// The tolerance of column `c`.
    pub fn sigma(&self, c: usize) -> Option<f64> {
        self.sigma.get(c).copied().flatten()
    }

    /// `(p_c − p0_c)/σ_c` at `x` (angles wrapped), if `c` has a tolerance.
    fn residual(&self, c: usize, x: &[f64]) -> Option<f64> {
        let s = self.sigma(c)?;
        let d = x[c] - self.nominal[c];
        Some(if self.angle[c] { wrap(d) } else { d } / s)
    }

    /// Pseudo-observation rows among the columns `free`.
    pub fn rows(&self, free: &[usize]) -> usize {
        free.iter().filter(|&&c| self.sigma(c).is_some()).count()
    }

    /// `Σ r_k²` at `x` over the columns `free`.
    pub fn cost(&self, free: &[usize], x: &[f64]) -> f64 {
        free.iter()
            .filter_map(|&c| self.residual(c, x))
            .map(|r| r * r)
            .sum()
    }

    /// Adds the pseudo-observations at `x` to `normal` (over its columns).
    pub fn add_to(&self, normal: &mut Normal, x: &[f64]) {
        let p = normal.free.len();
        let mut cost = 0.0;
        for (a, &c) in normal.free.iter().enumerate() {
            if let (Some(r), Some(s)) = (self.residual(c, x), self.sigma(c)) {
                normal.jtj[a * p + a] += 1.0 / (s * s);
                normal.jtr[a] += r / s;
                cost += r * r;
            }
        }
        normal.prior_cost = cost;
    }
}

/// The normal equations at `params` under `weights`, with their prior if
/// any: what every fit uses.
pub(crate) fn normal_at(
    params: &DhParams,
    data: &crate::dataset::DataSet,
    weights: &crate::residuals::Weights,
    free: &[usize],
    threads: usize,
) -> Result<Normal, super::CalibrationError> {
    let kernel = crate::kernel::ArmKernel::new(params)?;
    let mut normal = crate::residuals::normal_equations(&kernel, data, weights, free, threads)?;
    if let Some(p) = &weights.prior {
        p.add_to(&mut normal, &params.to_vec());
    }
    Ok(normal)
}

/// The cost at `params` under `weights`, with the prior over `free` if any.
pub(crate) fn cost_at(
    params: &DhParams,
    data: &crate::dataset::DataSet,
    weights: &crate::residuals::Weights,
    free: &[usize],
    xyz: &mut [[f64; 3]],
) -> Result<f64, super::CalibrationError> {
    let kernel = crate::kernel::ArmKernel::new(params)?;
    let data_cost = crate::residuals::cost(&kernel, data, weights, xyz)?;
    let prior = weights
        .prior
        .as_ref()
        .map_or(0.0, |p| p.cost(free, &params.to_vec()));
    let total = data_cost + prior;
    Ok(if total.is_finite() {
        total
    } else {
        f64::INFINITY
    })
}

/// One parameter's prior and what the data made of it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PriorEstimate {
    /// Parameter name (`a1`, `theta5`, `Bz`).
    pub name: String,
    /// `mm` or `deg`.
    pub unit: String,
    /// The stated tolerance (1σ).
    pub tolerance: f64,
    /// Posterior standard uncertainty, `unit`: the parameter's σ of the
    /// result, from the augmented normal matrix with the data's part scaled
    /// by σ̂² and the prior's not; 0 (and `data_share` 0) when that matrix
    /// is singular (never NaN).
    pub posterior_sigma: f64,
    /// The data's share of the information: `1 − posterior variance /
    /// prior variance` (1 = the data alone determine it, 0 = the prior
    /// alone).
    pub data_share: f64,
    /// `(calibrated − nominal) / tolerance`: how far the data moved it, in
    /// tolerances.
    pub shift: f64,
}

/// The prior of a calibration, as reported.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PriorReport {
    /// The tolerances as given, in words.
    pub tolerances: String,
    /// Pseudo-observation rows (free parameters with a tolerance).
    pub rows: usize,
    /// `Σ r_k²` of the prior at the result.
    pub cost: f64,
    /// Per free parameter with a tolerance, in the fixed order.
    pub parameters: Vec<PriorEstimate>,
}

impl PriorReport {
    /// The report of `prior` at the result `x`, from the covariance of the
    /// free parameters (`inverse`, free columns `free`).
    pub(crate) fn new(
        tolerances: &Tolerances,
        prior: &PriorTerm,
        x: &[f64],
        free: &[usize],
        inverse: &nalgebra::DMatrix<f64>,
        arm: &DhParams,
    ) -> PriorReport {
        let parameters = free
            .iter()
            .enumerate()
            .filter_map(|(a, &c)| {
                let s = prior.sigma(c)?;
                let id = arm.param_id(c)?;
                let var = inverse[(a, a)];
                let finite = var.is_finite() && var >= 0.0;
                Some(PriorEstimate {
                    name: id.to_string(),
                    unit: id.unit().to_string(),
                    tolerance: id.to_user(s),
                    posterior_sigma: if finite { id.to_user(var.sqrt()) } else { 0.0 },
                    data_share: if finite {
                        (1.0 - var / (s * s)).clamp(0.0, 1.0)
                    } else {
                        0.0
                    },
                    shift: prior.residual(c, x).unwrap_or(0.0),
                })
            })
            .collect();
        PriorReport {
            tolerances: tolerances.describe(arm.joint_count()),
            rows: prior.rows(free),
            cost: prior.cost(free, x),
            parameters,
        }
    }

    /// A note when the data contradict the tolerances: the prior's cost
    /// above `rows + 3·sqrt(2·rows)` (its χ² expectation plus three
    /// standard deviations), naming the parameter moved farthest.
    pub fn conflict(&self) -> Option<String> {
        let rows = self.rows as f64;
        if self.rows == 0 || self.cost <= rows + 3.0 * (2.0 * rows).sqrt() {
            return None;
        }
        let worst = self
            .parameters
            .iter()
            .max_by(|a, b| a.shift.abs().total_cmp(&b.shift.abs()))?;
        Some(format!(
            " — more than the tolerances allow: the data move {} by {:+.1} tolerances (tolerances \
             too tight for this arm, or a nominal that is off)",
            worst.name, worst.shift
        ))
    }

    /// The entry of a parameter, by name.
    pub fn of(&self, name: &str) -> Option<&PriorEstimate> {
        self.parameters.iter().find(|p| p.name == name)
    }
}

/// What a prior does to the conditioning (`identify` with tolerances): the
/// rank and condition number of the scaled normal matrix (angles as arcs at
/// the reach, as [`crate::identify`] scales them) with and without the
/// prior's `diag(1/σ²)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PriorConditioning {
    /// The tolerances, in words.
    pub tolerances: String,
    /// Parameters with a tolerance.
    pub parameters_with_tolerance: usize,
    /// Parameters in all.
    pub parameters: usize,
    /// Identifiable combinations from the data alone (after the structural
    /// rules: [`crate::identify::Identification::rank`]).
    pub rank_without: usize,
    /// Determined combinations with the prior, all parameters (singular
    /// values above `RANK_TOLERANCE × s_max`).
    pub rank_with: usize,
    /// Condition number (`s_max / s_min`) over the free parameters of
    /// `fix = auto`, data alone.
    pub condition_without: f64,
    /// The same with the prior.
    pub condition_with: f64,
}

/// The rank and conditioning of `data` at `params` with and without the
/// prior `tolerances`, touches weighed from `noise` (without stated noise,
/// as a 0.01 mm touch, like [`crate::identify::identify`]: the prior's
/// weight relative to the data depends on that σ). `identification` is the
/// data's own analysis (its rank and recommended free set).
///
/// # Errors
///
/// The kernel's, for an arm it cannot evaluate or noise that overflows.
pub fn conditioning(
    params: &DhParams,
    data: &crate::dataset::DataSet,
    noise: &crate::residuals::Noise,
    tolerances: &Tolerances,
    identification: &crate::identify::Identification,
    threads: usize,
) -> Result<PriorConditioning, crate::kernel::KernelError> {
    use nalgebra::DMatrix;
    let n = params.joint_count();
    let weights =
        crate::residuals::Weights::new(&crate::kernel::ArmKernel::new(params)?, data, noise, 0.01)?;
    let full = crate::identify::full_normal(params, data, &weights, threads)?;
    let np = full.free.len();
    let reach = params.reach();
    let ids: Vec<ParamId> = params.param_ids().collect();
    let d: Vec<f64> = ids
        .iter()
        .map(|i| if i.kind.is_length() { 1.0 } else { 1.0 / reach })
        .collect();
    let sigma = tolerances.sigmas_for(params);
    let scaled = |cols: &[usize], with: bool| {
        DMatrix::from_fn(cols.len(), cols.len(), |a, b| {
            let (ca, cb) = (cols[a], cols[b]);
            let mut v = full.jtj[ca * np + cb];
            if with && ca == cb {
                v += sigma[ca].map_or(0.0, |s| 1.0 / (s * s));
            }
            v * d[ca] * d[cb]
        })
    };
    let singular = |m: DMatrix<f64>| -> Vec<f64> {
        if !m.iter().all(|v| v.is_finite()) {
            return vec![0.0; m.nrows()];
        }
        let mut s: Vec<f64> = m
            .symmetric_eigenvalues()
            .iter()
            .map(|e| e.max(0.0).sqrt())
            .collect();
        s.sort_by(|a, b| b.total_cmp(a));
        s
    };
    let condition = |s: &[f64]| {
        let (max, min) = (
            s.first().copied().unwrap_or(0.0),
            s.last().copied().unwrap_or(0.0),
        );
        if min > 0.0 { max / min } else { f64::INFINITY }
    };
    let all: Vec<usize> = (0..np).collect();
    let with_all = singular(scaled(&all, true));
    let smax = with_all.first().copied().unwrap_or(0.0);
    let rank_with = with_all
        .iter()
        .filter(|&&s| s > crate::identify::RANK_TOLERANCE * smax)
        .count();
    let free = identification.free_columns();
    Ok(PriorConditioning {
        tolerances: tolerances.describe(n),
        parameters_with_tolerance: sigma.iter().filter(|s| s.is_some()).count(),
        parameters: np,
        rank_without: identification.rank,
        rank_with,
        condition_without: condition(&singular(scaled(&free, false))),
        condition_with: condition(&singular(scaled(&free, true))),
    })
}
