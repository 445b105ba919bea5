//! Stated 1σ tolerances of a nominal geometry: what a maker knows from
//! machining and assembly, per class (`length`, `angle`), per kind (`a`,
//! `d`, `alpha`, `theta`, `probe`) or per parameter (`theta5`). They are
//! read from an arm file's `[prior]` table or a `--prior` flag, and enter a
//! fit as a prior (the residual term of [`crate::residuals`]); this module
//! only holds and checks them, so both readers and fits can use it.

use serde::{Deserialize, Serialize};

use crate::error::{OptionError, quoted, short};
use crate::params::{DhParams, ParamId, ParamKind};
use crate::setting::Setting;

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
    pub(crate) fn is_length(self) -> bool {
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
            "tolerance of {name} must be a finite number > 0 (got {} {unit}); leave a \
             parameter out to give it no prior",
            short(value)
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
            "tolerance of {name} = {} {unit} is not representable",
            short(value)
        ));
    }
    if let Some(why) = out_of_range(internal) {
        return Err(format!(
            "tolerance of {name} = {} {unit}: {why}",
            short(value)
        ));
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
/// use aacmm_core::tolerances::Tolerances;
/// let t = Tolerances::parse("length=0.5mm, angle=0.1deg, theta5=0.05deg", 6).unwrap().unwrap();
/// let s = t.sigmas(6);
/// assert_eq!(s[0], Some(0.5)); // a1
/// assert!((s[18 + 4].unwrap() - 0.05f64.to_radians()).abs() < 1e-18); // theta5
/// assert!((s[18].unwrap() - 0.1f64.to_radians()).abs() < 1e-18); // theta1
/// assert_eq!(Tolerances::parse("none", 6).unwrap(), None);
/// let e = Tolerances::parse("theta5=0.05mm", 6).unwrap_err();
/// assert_eq!(e.field(), "prior");
/// assert!(e.reason.contains("theta5 is an angle"), "{e}");
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Tolerances {
    /// `(target, σ in mm or rad)`, in the order given; a later entry for the
    /// same target replaces an earlier one.
    entries: Vec<(String, f64)>,
}

/// Where the unit of `value` (`0.5mm`, `nanmm`, `1e-3 m`) starts: before a
/// known unit at its end, else at its first letter other than an exponent's
/// (`inf` and `nan` are numbers, so `nanmm` is `nan` in `mm`).
///
/// ```text
/// nanmm → nan | mm,  0.5mm → 0.5 | mm,  1e-3m → 1e-3 | m,  2furlong → 2 | furlong
/// ```
fn unit_start(value: &str) -> usize {
    if let Some(unit) = ["mm", "deg", "rad", "m"]
        .iter()
        .find(|u| value.ends_with(*u))
    {
        return value.len() - unit.len();
    }
    value
        .find(|c: char| c.is_ascii_alphabetic() && c != 'e' && c != 'E')
        .or_else(|| value.find(|c: char| c.is_ascii_alphabetic()))
        .unwrap_or(value.len())
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
        let refuse = |why: String| OptionError::new(Setting::Prior, s, why);
        let mut t = Tolerances::new();
        for item in s.split(',').map(str::trim).filter(|i| !i.is_empty()) {
            let (name, value) = item.split_once('=').ok_or_else(|| {
                refuse(format!(
                    "{}: expected TARGET=VALUEUNIT, e.g. length=0.5mm or theta5=0.05deg \
                     (or `none`)",
                    quoted(item)
                ))
            })?;
            let (name, value) = (name.trim(), value.trim());
            let target = Target::parse(name, n).ok_or_else(|| refuse(unknown_target(name, n)))?;
            let split = unit_start(value);
            let (number, unit) = value.split_at(split);
            let number: f64 = number.trim().parse().map_err(|_| {
                refuse(format!(
                    "{}: {} is not a number followed by a unit (mm, m, deg, rad)",
                    quoted(item),
                    quoted(number.trim())
                ))
            })?;
            if unit.trim().is_empty() {
                return Err(refuse(format!(
                    "{}: no unit; write it after the number ({} for {name})",
                    quoted(item),
                    if target.is_length() { "mm" } else { "deg" }
                )));
            }
            t.set(target, number, unit.trim())
                .map_err(|why| refuse(format!("{}: {why}", quoted(item))))?;
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
    pub(crate) fn check_for(&self, params: &DhParams) -> Result<(), OptionError> {
        let n = params.joint_count();
        self.check(n)?;
        for (name, _) in &self.entries {
            if let Some(why) = Target::parse(name, n).and_then(|t| not_in_arm(t, name, params)) {
                return Err(OptionError::new(Setting::Prior, name, why));
            }
        }
        Ok(())
    }

    /// Checks the entries for an `n`-joint arm (each target exists, each
    /// σ finite and positive); the error names the field `prior`.
    pub fn check(&self, n: usize) -> Result<(), OptionError> {
        for (name, s) in &self.entries {
            if Target::parse(name, n).is_none() {
                return Err(OptionError::new(
                    Setting::Prior,
                    name,
                    unknown_target(name, n),
                ));
            }
            if !(s.is_finite() && *s > 0.0) {
                return Err(OptionError::new(
                    Setting::Prior,
                    format!("{name}={s}"),
                    "a tolerance must be a finite number > 0",
                ));
            }
            if let Some(why) = out_of_range(*s) {
                return Err(OptionError::new(Setting::Prior, format!("{name}={s}"), why));
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

/// Why a target name is refused.
pub(crate) fn unknown_target(name: &str, n: usize) -> String {
    let last = ParamId::all(n)
        .last()
        .map_or(String::new(), |p| p.to_string());
    format!(
        "unknown target {}: use length, angle, a, d, alpha, theta, probe, or a \
         parameter name (a1 … {last})",
        quoted(name)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A number spelled in letters (`nan`, `inf`) is the number, and the
    /// message shows it rather than an empty token.
    #[test]
    fn a_value_spelled_in_letters_is_shown() {
        let e = Tolerances::parse("length=nanmm", 6).unwrap_err();
        assert!(e.reason.starts_with("`length=nanmm`: "), "{e}");
        assert!(!e.reason.contains("``"), "{e}");
        let e = Tolerances::parse("angle=infdeg", 6).unwrap_err();
        assert!(!e.reason.contains("``"), "{e}");
        let t = Tolerances::parse("length=1e-3m,angle=0.1deg", 6)
            .unwrap()
            .unwrap();
        assert_eq!(t.describe(6), "length=1mm, angle=0.1deg");
        let e = Tolerances::parse("length=2furlong", 6).unwrap_err();
        assert!(e.reason.contains("furlong"), "{e}");
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn tolerances_tolerances_check_for() {
        use crate::{
            params::{DhParams, JointModel},
            tolerances::Tolerances,
        };
        let mut arm = DhParams::paper_nominal();
        arm.joints[1].model = JointModel::Hayati;
        let t = Tolerances::parse("hbeta2=0.1deg", 6).unwrap().unwrap();
        assert!(t.check_for(&arm).is_ok());
        let e = Tolerances::parse("d2=1mm", 6)
            .unwrap()
            .unwrap()
            .check_for(&arm)
            .unwrap_err();
        assert!(
            e.reason
                .contains("joint 2 is a Hayati joint: its d-slot is `hbeta2`"),
            "{e}"
        );
        let e = t.check_for(&DhParams::paper_nominal()).unwrap_err();
        assert!(
            e.reason
                .contains("joint 2 is a D-H joint: its d-slot is `d2`"),
            "{e}"
        );
    }
}
