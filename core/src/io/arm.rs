//! Arm files: the nominal (or calibrated) geometry of a D-H chain, in TOML.
//!
//! ```toml
//! name = "paper-table-1"
//! length_unit = "mm"      # "mm" or "m"; required, never guessed
//! angle_unit = "deg"      # "deg" or "rad"; required, never guessed
//!
//! [[joint]]               # one per joint, base to probe (1 to 12 joints)
//! theta = 0.0             # encoder zero offset θ⁰
//! alpha = -90.0           # link twist (the paper's β; `beta` is accepted instead)
//! a = 50.0
//! d = 375.0
//! limits = [-180.0, 180.0]   # optional limits of the encoder reading q
//!
//! [[joint]]               # a slide: the reading is a length added to d
//! type = "prismatic"      # "revolute" (the default) or "prismatic"
//! theta = 0.0
//! alpha = 90.0
//! a = 0.0
//! d = 0.0                 # the offset of d at reading 0
//! limits = [0.0, 800.0]   # a slide's limits are lengths, in length_unit
//!
//! [[joint]]               # a joint whose axis is (nearly) parallel to the previous
//! model = "hayati"        # A = Rz(θ+q)·Tx(a)·Rx(α)·Ry(β): no `d`, `hbeta` instead
//! theta = 0.0
//! alpha = 0.2
//! a = 300.0
//! hbeta = 0.0             # rotation β about the link's y axis, in angle_unit
//!
//! [probe]                 # probe centre in the last joint's frame
//! x = 0.0
//! y = 0.0
//! z = 100.0
//!
//! [[tool]]                # optional: more tool points (markers, SMRs, styli)
//! name = "smr2"
//! offset_mm = [40.0, 0.0, 95.0]   # mm, in the last joint's frame
//! ```
//!
//! `[[tool]]` tables are described in [`super::tools`].
//!
//! `name` is optional (default empty). Lengths (`a`, `d`, probe) are in
//! `length_unit`, angles (`theta`, `alpha`, `hbeta`, `limits`) in `angle_unit`.
//! `type` is `"revolute"` (the default: the reading is an angle added to θ)
//! or `"prismatic"` (the reading is a length added to `d`, in `length_unit`,
//! as are its `limits`); see [`JointKind`].
//! `model` is `"dh"` (the default: `d` required, no `hbeta`) or `"hayati"`
//! (`hbeta` required, no `d`); see [`JointModel`].
//! `hbeta`, not `beta`: `beta` is the paper's name of the twist `α`.
//! Integers are accepted where numbers are expected. Unknown keys are errors
//! (a typo is never ignored), as are non-finite numbers, a missing key, a
//! joint count the toolkit has no kernel for (none, or more than
//! [`MAX_JOINTS`]), and limits with
//! `min >= max`. A unit that looks wrong (lengths over 10 m in metres, angles
//! over a full turn in radians) gives a [`Warning`].
//!
//! The schema is a serde type; serde's messages are reworded here so that
//! every error names the key, its line, and the joint or table it is in.

use std::ops::Range;
use std::path::Path;

use serde::{Deserialize, Serialize};
use toml::Spanned;
use toml::de::{DeTable, DeValue};

use super::Warning;
use super::text::{line_of, parse_toml, read_settings, suggest};
use super::units::{AngleUnit, LengthUnit};
use super::verdict::Rejected;
use crate::corrections::{Harmonic, MAX_HARMONIC_ORDER, Mass, Physics};
use crate::error::{InputError, quoted, shown};
use crate::params::{DhJoint, DhParams, JointKind, JointModel, MAX_JOINTS, supports_joints};
use crate::tolerances::Tolerances;

/// In an arm file in metres, a length above this (m) draws a warning: no
/// measuring arm is that long, so the lengths are likely millimetres.
pub(crate) const PLAUSIBLE_METRES: f64 = 10.0;

/// An arm: its name, its geometry (mm, rad) and its optional joint limits.
#[derive(Clone, Debug, PartialEq)]
pub struct Arm {
    /// Free-form name (may be empty).
    pub name: String,
    /// Geometry, mm and rad.
    pub params: DhParams,
    /// Per joint, the optional `[min, max]` of the encoder reading `q`, rad.
    /// Has one entry per joint when read from a file.
    pub limits: Vec<Option<[f64; 2]>>,
    /// The stated tolerances of the nominal geometry (the arm file's
    /// `[prior]` table), if any: a fit uses them as a prior unless told
    /// otherwise.
    pub prior: Option<Tolerances>,
    /// What the arm states beyond its geometry: masses, gravity and the
    /// corrections' values ([`crate::corrections`]); empty by default.
    /// Boxed: most arms have none, and an arm is moved by value often.
    pub physics: Box<Physics>,
    /// The diameter of the probe's ball, mm (`[probe] ball_diameter_mm`),
    /// if stated: points probed on a surface lie a ball radius from the
    /// probe centre the chain ends in (sphere surfaces, [`crate::residuals::spheres`]).
    pub ball_diameter_mm: Option<f64>,
    /// The named tool points beyond the probe (`[[tool]]`,
    /// [`super::tools`]), in file order; empty for most arms.
    pub tools: Vec<super::tools::Tool>,
}

/// The largest probe ball an arm file may state, mm: a stylus ball is
/// 0.5–8 mm, a tracker's target 38.1 mm (1.5 in).
pub(crate) const MAX_BALL_DIAMETER_MM: f64 = 100.0;
/// The smallest, mm: below it the value was most likely written in metres
/// (a 6 mm ball as `0.006`); the field is in mm whatever `length_unit` says.
pub(crate) const MIN_BALL_DIAMETER_MM: f64 = 0.1;

impl Arm {
    /// An arm without joint limits.
    ///
    /// ```
    /// use aacmm_core::{io::Arm, params::DhParams};
    /// let arm = Arm::without_limits("nominal", DhParams::paper_nominal());
    /// assert_eq!(arm.limits, vec![None; 6]);
    /// ```
    pub fn without_limits(name: impl Into<String>, params: DhParams) -> Arm {
        let n = params.joint_count();
        Arm {
            name: name.into(),
            params,
            limits: vec![None; n],
            prior: None,
            physics: Box::default(),
            ball_diameter_mm: None,
            tools: Vec::new(),
        }
    }
}

/// Reads an arm file (standard input for `-`); returns the arm and any
/// warnings (for the caller to print). Messages name the file as
/// [`source_name`](super::source_name) gives it.
///
/// ```no_run
/// let (arm, warnings) = aacmm_core::io::read_arm(std::path::Path::new("arm.toml"))?;
/// println!("{} joints", arm.params.joint_count());
/// # Ok::<(), aacmm_core::error::InputError>(())
/// ```
pub fn read_arm(path: &Path) -> Result<(Arm, Vec<Warning>), InputError> {
    read_arm_with(path, Rejected::Refuse)
}

/// [`read_arm`], with a file whose `[verdict]` says NOT usable (a refused
/// calibration's `calibrated.toml`) refused or read with a warning
/// ([`super::verdict`]).
pub fn read_arm_with(path: &Path, rejected: Rejected) -> Result<(Arm, Vec<Warning>), InputError> {
    let (file, text) = read_settings(path)?;
    parse_arm_with(&text, &file, rejected)
}

/// Parses the text of an arm file; `file` is the name used in messages.
/// Returns the arm and any warnings.
///
/// ```
/// let joint = "[[joint]]\ntheta = 0\nalpha = 90\na = 0.05\nd = 0.375\nlimits = [-90, 90]\n";
/// let text = format!(
///     "length_unit = \"m\"\nangle_unit = \"deg\"\n{}[probe]\nx = 0\ny = 0\nz = 0.1\n",
///     joint.repeat(6)
/// );
/// let (arm, warnings) = aacmm_core::io::parse_arm(&text, "arm.toml").unwrap();
/// assert_eq!(arm.params.joints[0].d, 375.0);
/// assert_eq!(arm.params.joints[0].alpha, std::f64::consts::FRAC_PI_2);
/// assert_eq!(arm.params.probe, [0.0, 0.0, 100.0]);
/// assert_eq!(arm.limits[0].unwrap()[1], std::f64::consts::FRAC_PI_2);
/// assert!(warnings.is_empty());
///
/// let err = aacmm_core::io::parse_arm(&text.replacen("alpha", "alpah", 1), "arm.toml");
/// assert!(err.unwrap_err().to_string().starts_with("arm.toml:5: field `alpah`: unknown key"));
/// let thirteen = text.replace("[probe]", &format!("{}[probe]", joint.repeat(7)));
/// assert_eq!(
///     aacmm_core::io::parse_arm(&thirteen, "arm.toml").unwrap_err().to_string(),
///     "arm.toml:75: field `joint`: 13 joints; at most 12 are supported (the toolkit \
///      computes chains of 1 to 12 joints)"
/// );
/// ```
pub fn parse_arm(text: &str, file: &str) -> Result<(Arm, Vec<Warning>), InputError> {
    parse_arm_with(text, file, Rejected::Refuse)
}

/// [`parse_arm`], with a file whose `[verdict]` says NOT usable refused or
/// read with a warning ([`super::verdict`]).
pub(crate) fn parse_arm_with(
    text: &str,
    file: &str,
    rejected: Rejected,
) -> Result<(Arm, Vec<Warning>), InputError> {
    let doc = parse_toml(text, file)?;
    // First: a refused calibration's file is refused for that, whatever
    // else it holds.
    let verdict = super::verdict::check(doc.get_ref(), text, file, rejected)?;
    let schema = ArmFile::deserialize(toml::de::Deserializer::from(doc.clone()))
        .map_err(|e| schema_error(text, file, doc.get_ref(), &e))?;
    let (mut arm, mut warnings) = schema.to_arm(text, file)?;
    warnings.extend(verdict);
    if doc.get_ref().contains_key("prior") {
        // Read with the arm, so every front end fits with it: a typo is
        // never ignored, and no reader can leave the tolerances behind.
        arm.prior =
            super::prior::parse_prior_of(text, file, arm.params.joint_count(), Some(&arm.params))?;
    }
    Ok((arm, warnings))
}

/// Writes an arm in the arm-file schema with the given units: deterministic
/// bytes, numbers with the fewest digits that read back to the same value
/// (bit-exact in mm and rad; in deg and m bit-exact whenever some decimal
/// converts back exactly, else within 1 ulp — see
/// [`AngleUnit::from_internal_exact`]). Missing `limits` entries are written
/// as no limits; non-finite values are written as TOML `nan`/`inf`, which the
/// reader rejects.
///
/// ```
/// use aacmm_core::io::{Arm, AngleUnit, LengthUnit, arm_to_toml, parse_arm};
/// use aacmm_core::params::DhParams;
/// let arm = Arm::without_limits("nominal", DhParams::paper_nominal());
/// let text = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg);
/// assert!(text.contains("alpha = -90.0\na = 50.0\nd = 375.0\n"));
/// assert_eq!(parse_arm(&text, "out.toml").unwrap().0, arm);
/// ```
pub fn arm_to_toml(arm: &Arm, length_unit: LengthUnit, angle_unit: AngleUnit) -> String {
    // Invariant: an `ArmFile` holds only strings, floats (TOML has inf and
    // nan), arrays and tables, which always serialize.
    toml::to_string(&ArmFile::new(arm, length_unit, angle_unit))
        .expect("strings, numbers, arrays and tables always serialize to TOML")
}

/// Writes an arm file (see [`arm_to_toml`]).
///
/// ```no_run
/// use aacmm_core::io::{Arm, AngleUnit, LengthUnit, write_arm};
/// let arm = Arm::without_limits("nominal", aacmm_core::params::DhParams::paper_nominal());
/// write_arm(std::path::Path::new("arm.toml"), &arm, LengthUnit::Mm, AngleUnit::Deg)?;
/// # Ok::<(), aacmm_core::error::InputError>(())
/// ```
pub fn write_arm(
    path: &Path,
    arm: &Arm,
    length_unit: LengthUnit,
    angle_unit: AngleUnit,
) -> Result<(), InputError> {
    super::write_atomic(path, arm_to_toml(arm, length_unit, angle_unit))
        .map_err(|e| InputError::io(path.display().to_string(), e))
}

/// The arm-file schema, values in the file's units, with their places in
/// the text (for messages).
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ArmFile {
    #[serde(default)]
    name: String,
    #[serde(serialize_with = "by_name", deserialize_with = "from_name")]
    length_unit: LengthUnit,
    #[serde(serialize_with = "by_name", deserialize_with = "from_name")]
    angle_unit: AngleUnit,
    /// Gravity's direction in the base frame (default −z).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gravity: Option<Spanned<Vec<Spanned<f64>>>>,
    /// Thermal expansion coefficient of the lengths, 1/K.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    cte_per_k: Option<Spanned<f64>>,
    /// The temperature the lengths are at, °C (default 20).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    reference_temperature_c: Option<Spanned<f64>>,
    joint: Spanned<Vec<Spanned<JointFile>>>,
    probe: ProbeFile,
    /// The named tool points ([`super::tools`]); absent when none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    tool: Vec<Spanned<ToolFile>>,
    /// Stated tolerances: read by [`super::prior`], never written.
    #[serde(rename = "prior", default, skip_serializing)]
    _prior: Option<serde::de::IgnoredAny>,
    /// A calibration's frame registrations: read by [`super::frames`],
    /// never written here.
    #[serde(rename = "frame", default, skip_serializing)]
    _frame: Option<serde::de::IgnoredAny>,
    /// A calibration's tool mount of orientations: read by
    /// [`super::frames::parse_mount`], never written here.
    #[serde(rename = "mount", default, skip_serializing)]
    _mount: Option<serde::de::IgnoredAny>,
    /// A calibration's verdict: read by [`super::verdict`], never written
    /// here.
    #[serde(rename = "verdict", default, skip_serializing)]
    _verdict: Option<serde::de::IgnoredAny>,
}

/// An array of `[x, y, z]`-like number arrays, each located.
type Arrays = Spanned<Vec<Spanned<Vec<Spanned<f64>>>>>;

/// One `[[joint]]` table.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
struct JointFile {
    /// `revolute` (absent: the default) or `prismatic`.
    #[serde(default, rename = "type", skip_serializing_if = "Option::is_none")]
    kind: Option<Spanned<String>>,
    /// `dh` (absent: the default) or `hayati`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    model: Option<Spanned<String>>,
    theta: Spanned<f64>,
    #[serde(alias = "beta")]
    alpha: Spanned<f64>,
    a: Spanned<f64>,
    /// Required for a D-H joint, refused for a Hayati joint (checked in
    /// [`ArmFile::to_arm`], which locates the message).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    d: Option<Spanned<f64>>,
    /// Hayati β: required for a Hayati joint, refused for a D-H joint.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    hbeta: Option<Spanned<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    limits: Option<Spanned<Vec<Spanned<f64>>>>,
    /// The mass of the link after the joint, kg.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    mass_kg: Option<Spanned<f64>>,
    /// Its centre of mass in the link's D-H frame, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    com_mm: Option<Spanned<Vec<Spanned<f64>>>>,
    /// The joint's compliance, rad per N·m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    compliance_rad_per_nm: Option<Spanned<f64>>,
    /// Encoder harmonics `[order, sin, cos]`, amplitudes in angle_unit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    harmonics: Option<Arrays>,
    /// The joint's backlash (half-play), angle_unit (length_unit for a
    /// prismatic joint).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    backlash: Option<Spanned<f64>>,
}

impl JointFile {
    /// The joint's type (`revolute` when absent), or a located message
    /// (joint `i`, 0-based).
    fn kind(&self, i: usize, text: &str, file: &str) -> Result<JointKind, InputError> {
        let Some(k) = &self.kind else {
            return Ok(JointKind::Revolute);
        };
        match k.get_ref().as_str() {
            "revolute" => Ok(JointKind::Revolute),
            "prismatic" => Ok(JointKind::Prismatic),
            other => Err(InputError::field(
                file,
                line_of(text, k.span().start),
                "type",
                format!(
                    "joint {}: unknown type {}; expected \"revolute\" (turns: the reading is an \
                     angle added to θ) or \"prismatic\" (slides: the reading is a length added \
                     to d)",
                    i + 1,
                    quoted(other)
                ),
            )),
        }
    }

    /// The joint at its reading (mm, rad) from the file's values.
    fn joint(&self, model: JointModel, kind: JointKind, lu: LengthUnit, au: AngleUnit) -> DhJoint {
        let [theta, alpha] = [&self.theta, &self.alpha].map(|v| au.to_internal(*v.get_ref()));
        let a = lu.to_internal(*self.a.get_ref());
        let joint = match model {
            JointModel::Dh => {
                let d = self
                    .d
                    .as_ref()
                    .map_or(0.0, |d| lu.to_internal(*d.get_ref()));
                DhJoint::dh(a, d, alpha, theta)
            }
            JointModel::Hayati => {
                let beta = (self.hbeta.as_ref()).map_or(0.0, |b| au.to_internal(*b.get_ref()));
                DhJoint::hayati(a, alpha, theta, beta)
            }
        };
        joint.with_kind(kind)
    }

    /// The joint's limits (mm for a slide, rad for a turn), checked
    /// (joint `i`, 0-based).
    fn limits(
        &self,
        i: usize,
        kind: JointKind,
        (lu, au): (LengthUnit, AngleUnit),
        text: &str,
        file: &str,
    ) -> Result<Option<[f64; 2]>, InputError> {
        // A slide's limits are lengths, a turn's angles.
        let unit = JointUnit { kind, lu, au };
        Ok(
            match self.limits.as_ref().map(|l| (l, l.get_ref().as_slice())) {
                None => None,
                Some((_, [lo, hi])) if lo.get_ref() < hi.get_ref() => {
                    Some([lo, hi].map(|x| unit.to_internal(*x.get_ref())))
                }
                Some((l, values)) => {
                    let message = match values {
                        [lo, hi] => format!(
                            "min {} must be less than max {}",
                            lo.get_ref(),
                            hi.get_ref()
                        ),
                        _ => format!(
                            "expected `[min, max]` in {}, found {} values",
                            unit.name(),
                            values.len()
                        ),
                    };
                    let line = line_of(text, l.span().start);
                    return Err(InputError::field(
                        file,
                        line,
                        "limits",
                        format!("joint {}: {message}", i + 1),
                    ));
                }
            },
        )
    }

    /// The joint's model, or a located message (joint `i`, 0-based).
    fn model(
        &self,
        span: Range<usize>,
        i: usize,
        text: &str,
        file: &str,
    ) -> Result<JointModel, InputError> {
        let ctx = format!("joint {}: ", i + 1);
        let at = |span: Range<usize>, field: &str, message: String| {
            InputError::field(
                file,
                line_of(text, span.start),
                field,
                format!("{ctx}{message}"),
            )
        };
        let model = match &self.model {
            None => JointModel::Dh,
            Some(m) => match m.get_ref().as_str() {
                "dh" => JointModel::Dh,
                "hayati" => JointModel::Hayati,
                other => {
                    return Err(at(
                        m.span(),
                        "model",
                        format!(
                            "unknown model {}; expected \"dh\" or \"hayati\"",
                            quoted(other)
                        ),
                    ));
                }
            },
        };
        match (model, &self.d, &self.hbeta) {
            (JointModel::Dh, Some(_), None) | (JointModel::Hayati, None, Some(_)) => Ok(model),
            (JointModel::Dh, None, _) => Err(at(
                span,
                "d",
                "missing; every [[joint]] needs `theta`, `alpha` (or `beta`), `a` and `d` \
                 (a joint with `model = \"hayati\"` needs `hbeta` instead of `d`)"
                    .to_string(),
            )),
            (JointModel::Dh, Some(_), Some(b)) => Err(at(
                b.span(),
                "hbeta",
                "`hbeta` is the Hayati rotation: it needs `model = \"hayati\"` (and no `d`); \
                 the paper's β, the twist, is written `alpha` or `beta`"
                    .to_string(),
            )),
            (JointModel::Hayati, Some(d), _) => Err(at(
                d.span(),
                "d",
                "a Hayati joint (model = \"hayati\") has no `d`: its link is \
                 Rz(θ+q)·Tx(a)·Rx(α)·Ry(β); remove `d` (for axes exactly parallel to the \
                 previous one, move it to the next joint's `d`) and give `hbeta`"
                    .to_string(),
            )),
            (JointModel::Hayati, None, None) => Err(at(
                span,
                "hbeta",
                "missing; a Hayati joint (model = \"hayati\") needs `hbeta`, the rotation \
                 about the link's y axis, in angle_unit"
                    .to_string(),
            )),
        }
    }
}

/// The `[probe]` table.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table ([probe] with x, y, z)")]
struct ProbeFile {
    x: Spanned<f64>,
    y: Spanned<f64>,
    z: Spanned<f64>,
    /// The tool's mass, kg.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    mass_kg: Option<Spanned<f64>>,
    /// Its centre of mass in the last joint's frame, mm (default: the probe).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    com_mm: Option<Spanned<Vec<Spanned<f64>>>>,
    /// The diameter of its ball, mm (whatever `length_unit` says).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    ball_diameter_mm: Option<Spanned<f64>>,
}

/// One `[[tool]]` table: a named tool point ([`super::tools`]).
#[derive(Serialize, Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table ([[tool]] with name, offset_mm)"
)]
struct ToolFile {
    name: Spanned<String>,
    /// Its centre in the last joint's frame, mm (whatever `length_unit`
    /// says).
    offset_mm: Spanned<Vec<Spanned<f64>>>,
    /// The diameter of its ball when it is a probe's, mm (whatever
    /// `length_unit` says).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    ball_diameter_mm: Option<Spanned<f64>>,
}

/// A ball diameter `d` of `ctx` (`[probe]`, a `[[tool]]`), checked: in mm,
/// between [`MIN_BALL_DIAMETER_MM`] (below it, metres) and
/// [`MAX_BALL_DIAMETER_MM`]. (Finite: checked with every number first.)
fn checked_ball(d: &Spanned<f64>, ctx: &str, text: &str, file: &str) -> Result<f64, InputError> {
    let v = *d.get_ref();
    let why = if v <= 0.0 {
        format!("{ctx}: a ball's diameter is positive, got {v}")
    } else if v < MIN_BALL_DIAMETER_MM {
        format!(
            "{ctx}: a ball of {v} mm is no probe's (the smallest are {MIN_BALL_DIAMETER_MM} mm): \
             in metres? the field is in mm whatever length_unit says ({} mm)",
            crate::error::short(v * 1000.0)
        )
    } else if v > MAX_BALL_DIAMETER_MM {
        format!("{ctx}: a ball of {v} mm is more than any probe's ({MAX_BALL_DIAMETER_MM} mm)")
    } else {
        return Ok(v);
    };
    Err(InputError::field(
        file,
        line_of(text, d.span().start),
        "ball_diameter_mm",
        why,
    ))
}

/// A unit by its name.
fn by_name<S: serde::Serializer>(unit: &impl std::fmt::Display, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(unit)
}

/// A unit from its name, with [`UnknownUnit`](super::UnknownUnit)'s message.
fn from_name<'de, D, U>(d: D) -> Result<U, D::Error>
where
    D: serde::Deserializer<'de>,
    U: std::str::FromStr<Err = super::UnknownUnit>,
{
    String::deserialize(d)?
        .parse()
        .map_err(serde::de::Error::custom)
}

/// A value to write (its place in a text is not known yet).
fn new<T>(value: T) -> Spanned<T> {
    Spanned::new(0..0, value)
}

/// A joint's own quantity in a file — its limits, its backlash: a length
/// (length_unit) for a slide, an angle (angle_unit) for a turn. The one
/// place that switches on the kind for a unit.
#[derive(Clone, Copy, Debug)]
struct JointUnit {
    kind: JointKind,
    lu: LengthUnit,
    au: AngleUnit,
}

impl JointUnit {
    /// The file's value `x` in mm or rad.
    fn to_internal(self, x: f64) -> f64 {
        match self.kind {
            JointKind::Revolute => self.au.to_internal(x),
            JointKind::Prismatic => self.lu.to_internal(x),
        }
    }

    /// The value to write for `x` (mm or rad), reading back exactly.
    fn written(self, x: f64) -> f64 {
        match self.kind {
            JointKind::Revolute => self.au.from_internal_exact(x),
            JointKind::Prismatic => self.lu.from_internal_exact(x),
        }
    }

    /// The unit's name in messages.
    fn name(self) -> String {
        match self.kind {
            JointKind::Revolute => self.au.to_string(),
            JointKind::Prismatic => self.lu.to_string(),
        }
    }
}

impl ArmFile {
    /// `arm` in the given units, to write.
    pub(crate) fn new(arm: &Arm, lu: LengthUnit, au: AngleUnit) -> ArmFile {
        let len = |x: f64| new(lu.from_internal_exact(x));
        let ang = |x: f64| au.from_internal_exact(x);
        let joints = arm.params.joints.iter().enumerate();
        let [x, y, z] = arm.params.probe;
        let physics = &arm.physics;
        let triple = |v: [f64; 3]| new(v.map(new).to_vec());
        let link_mass = |i: usize| physics.link_masses.get(i).copied().flatten();
        let harmonics = |i: usize| {
            let of: Vec<_> = (physics.harmonics.iter())
                .filter(|h| h.joint == i)
                .map(|h| {
                    new(vec![
                        new(f64::from(h.order)),
                        new(ang(h.sin)),
                        new(ang(h.cos)),
                    ])
                })
                .collect();
            (!of.is_empty()).then(|| new(of))
        };
        ArmFile {
            name: arm.name.clone(),
            length_unit: lu,
            angle_unit: au,
            gravity: physics.gravity.map(triple),
            cte_per_k: physics.cte_per_k.map(new),
            reference_temperature_c: physics.reference_temperature_c.map(new),
            joint: new(joints
                .map(|(i, j)| {
                    let hayati = j.model == JointModel::Hayati;
                    let slides = j.kind == JointKind::Prismatic;
                    let unit = JointUnit {
                        kind: j.kind,
                        lu,
                        au,
                    };
                    let limit = |x: f64| unit.written(x);
                    new(JointFile {
                        // Absent for revolute joints: their files read as before.
                        kind: slides.then(|| new(JointKind::Prismatic.name().to_string())),
                        // Absent for D-H joints: their files read as before.
                        model: hayati.then(|| new(JointModel::Hayati.name().to_string())),
                        theta: new(ang(j.theta)),
                        alpha: new(ang(j.alpha)),
                        a: len(j.a),
                        d: (!hayati).then(|| len(j.d)),
                        hbeta: hayati.then(|| new(ang(j.beta))),
                        limits: arm
                            .limits
                            .get(i)
                            .copied()
                            .flatten()
                            .map(|[lo, hi]| new(vec![new(limit(lo)), new(limit(hi))])),
                        mass_kg: link_mass(i).map(|m| new(m.kg)),
                        com_mm: link_mass(i).and_then(|m| m.com_mm).map(triple),
                        compliance_rad_per_nm: physics
                            .compliance
                            .get(i)
                            .copied()
                            .flatten()
                            .map(new),
                        harmonics: harmonics(i),
                        backlash: (physics.backlash.get(i).copied().flatten())
                            .map(|b| new(limit(b))),
                    })
                })
                .collect()),
            probe: ProbeFile {
                x: len(x),
                y: len(y),
                z: len(z),
                mass_kg: physics.probe_mass.map(|m| new(m.kg)),
                com_mm: physics.probe_mass.and_then(|m| m.com_mm).map(triple),
                ball_diameter_mm: arm.ball_diameter_mm.map(new),
            },
            tool: (arm.tools.iter())
                .map(|t| {
                    new(ToolFile {
                        name: new(t.name.clone()),
                        offset_mm: triple(t.offset),
                        ball_diameter_mm: t.ball_diameter_mm.map(new),
                    })
                })
                .collect(),
            _prior: None,
            _frame: None,
            _mount: None,
            _verdict: None,
        }
    }

    /// `arm` in mm and degrees if that reads back to exactly `arm`, else in
    /// mm and radians (always exact): how a campaign stores its arms.
    pub(crate) fn exact(arm: &Arm) -> ArmFile {
        let deg = ArmFile::new(arm, LengthUnit::Mm, AngleUnit::Deg);
        match deg.to_arm("", "") {
            Ok((back, _)) if back == *arm => deg,
            _ => ArmFile::new(arm, LengthUnit::Mm, AngleUnit::Rad),
        }
    }

    /// The arm (mm, rad) and the warnings, after the checks serde cannot
    /// express; `text` and `file` locate the messages.
    pub(crate) fn to_arm(&self, text: &str, file: &str) -> Result<(Arm, Vec<Warning>), InputError> {
        let joints = self.joint.get_ref();
        // Per-joint keys first, as serde's missing-key errors came before
        // the joint count when `d` was required by the schema.
        let models = joints
            .iter()
            .enumerate()
            .map(|(i, j)| {
                let model = j.get_ref().model(j.span(), i, text, file)?;
                Ok((model, j.get_ref().kind(i, text, file)?))
            })
            .collect::<Result<Vec<(JointModel, JointKind)>, InputError>>()?;
        if !supports_joints(joints.len()) {
            // Blame the first joint too many, or the last.
            let blamed = joints.get(MAX_JOINTS).or(joints.last());
            let line = line_of(text, blamed.map_or(self.joint.span(), |j| j.span()).start);
            return Err(InputError::field(
                file,
                line,
                "joint",
                unsupported(joints.len()),
            ));
        }
        let numbers = self.numbers();
        if let Some((ctx, field, v)) = numbers.iter().find(|(_, _, v)| !v.get_ref().is_finite()) {
            let line = line_of(text, v.span().start);
            let raw = text.get(v.span()).unwrap_or("?");
            let message = format!("{ctx}{} is not a finite number", quoted(raw));
            return Err(InputError::field(file, line, *field, message));
        }

        let (lu, au) = (self.length_unit, self.angle_unit);
        let mut arm = Arm {
            name: self.name.clone(),
            params: DhParams {
                joints: Vec::with_capacity(joints.len()),
                probe: [&self.probe.x, &self.probe.y, &self.probe.z]
                    .map(|v| lu.to_internal(*v.get_ref())),
            },
            limits: Vec::with_capacity(joints.len()),
            prior: None,
            physics: Box::default(),
            ball_diameter_mm: self.ball_diameter(text, file)?,
            tools: self.tools(text, file)?,
        };
        for (i, (j, &(model, kind))) in joints.iter().map(Spanned::get_ref).zip(&models).enumerate()
        {
            arm.params.joints.push(j.joint(model, kind, lu, au));
            let limits = j.limits(i, kind, (lu, au), text, file)?;
            arm.limits.push(limits);
        }
        arm.physics = Box::new(self.physics(text, file)?);
        Ok((arm, self.unit_warnings(text, file)))
    }

    /// The `[[tool]]` tables, checked: a name not empty, not the default
    /// tool's, not repeated; an offset of three numbers (finite: checked
    /// with every number first).
    fn tools(&self, text: &str, file: &str) -> Result<Vec<super::tools::Tool>, InputError> {
        let mut seen: Vec<&str> = Vec::new();
        let mut out = Vec::with_capacity(self.tool.len());
        for t in self.tool.iter().map(Spanned::get_ref) {
            let name = t.name.get_ref();
            if let Some(why) = super::tools::name_refused(name, &seen) {
                let line = line_of(text, t.name.span().start);
                return Err(InputError::field(file, line, "name", why));
            }
            seen.push(name);
            let offset = match t.offset_mm.get_ref()[..] {
                [ref x, ref y, ref z] => [x, y, z].map(|c| *c.get_ref()),
                ref other => {
                    return Err(InputError::field(
                        file,
                        line_of(text, t.offset_mm.span().start),
                        "offset_mm",
                        format!(
                            "[[tool]] {}: expected [x, y, z] (mm), found {} values",
                            quoted(name),
                            other.len()
                        ),
                    ));
                }
            };
            let ctx = format!("[[tool]] {}", quoted(name));
            let ball = (t.ball_diameter_mm.as_ref())
                .map(|d| checked_ball(d, &ctx, text, file))
                .transpose()?;
            out.push(super::tools::Tool {
                name: name.clone(),
                offset,
                ball_diameter_mm: ball,
            });
        }
        Ok(out)
    }

    /// `[probe] ball_diameter_mm`, checked: in mm, between
    /// [`MIN_BALL_DIAMETER_MM`] (below it, metres) and
    /// [`MAX_BALL_DIAMETER_MM`]. (Finite: checked with every number first.)
    fn ball_diameter(&self, text: &str, file: &str) -> Result<Option<f64>, InputError> {
        (self.probe.ball_diameter_mm.as_ref())
            .map(|d| checked_ball(d, "[probe]", text, file))
            .transpose()
    }

    /// The masses, gravity and corrections the file states, checked.
    fn physics(&self, text: &str, file: &str) -> Result<Physics, InputError> {
        let at = |span: Range<usize>, field: &str, message: String| {
            InputError::field(file, line_of(text, span.start), field, message)
        };
        let triple = |v: &Spanned<Vec<Spanned<f64>>>, field: &str, ctx: &str| match v.get_ref()[..]
        {
            [ref x, ref y, ref z] => Ok([x, y, z].map(|c| *c.get_ref())),
            ref other => Err(at(
                v.span(),
                field,
                format!("{ctx}expected [x, y, z], found {} values", other.len()),
            )),
        };
        let mass = |kg: &Option<Spanned<f64>>,
                    com: &Option<Spanned<Vec<Spanned<f64>>>>,
                    ctx: &str|
         -> Result<Option<Mass>, InputError> {
            let com_mm = com.as_ref().map(|c| triple(c, "com_mm", ctx)).transpose()?;
            match kg {
                None if com_mm.is_some() => Err(at(
                    com.as_ref().map_or(0..0, Spanned::span),
                    "com_mm",
                    format!("{ctx}a centre of mass without `mass_kg`"),
                )),
                None => Ok(None),
                Some(m) if *m.get_ref() < 0.0 => Err(at(
                    m.span(),
                    "mass_kg",
                    format!("{ctx}a mass is not negative, got {}", m.get_ref()),
                )),
                Some(m) => Ok(Some(Mass {
                    kg: *m.get_ref(),
                    com_mm,
                })),
            }
        };
        let au = self.angle_unit;
        let mut physics = Physics::default();
        for (i, j) in self
            .joint
            .get_ref()
            .iter()
            .map(Spanned::get_ref)
            .enumerate()
        {
            let ctx = format!("joint {}: ", i + 1);
            physics.link_masses.push(mass(&j.mass_kg, &j.com_mm, &ctx)?);
            physics
                .compliance
                .push(j.compliance_rad_per_nm.as_ref().map(|c| *c.get_ref()));
            for h in j.harmonics.iter().flat_map(|h| h.get_ref()) {
                let order = match h.get_ref()[..] {
                    [ref k, _, _] => *k.get_ref(),
                    _ => f64::NAN,
                };
                if !(order.fract() == 0.0 && (1.0..=f64::from(MAX_HARMONIC_ORDER)).contains(&order))
                {
                    return Err(at(
                        h.span(),
                        "harmonics",
                        format!(
                            "{ctx}expected [order, sin, cos] with a whole order from 1 to                              {MAX_HARMONIC_ORDER} and amplitudes in {au}"
                        ),
                    ));
                }
                let v = h.get_ref();
                physics.harmonics.push(Harmonic {
                    joint: i,
                    order: order as u32,
                    sin: au.to_internal(*v[1].get_ref()),
                    cos: au.to_internal(*v[2].get_ref()),
                });
            }
        }
        if physics.link_masses.iter().all(Option::is_none) {
            physics.link_masses.clear();
        }
        if physics.compliance.iter().all(Option::is_none) {
            physics.compliance.clear();
        }
        physics.probe_mass = mass(&self.probe.mass_kg, &self.probe.com_mm, "[probe]: ")?;
        self.read_backlash(&mut physics, &at)?;
        if let Some(g) = &self.gravity {
            let v = triple(g, "gravity", "")?;
            if v.iter().all(|c| *c == 0.0) {
                return Err(at(g.span(), "gravity", "a direction, not zero".into()));
            }
            physics.gravity = Some(v);
        }
        physics.cte_per_k = self.cte_per_k.as_ref().map(|c| *c.get_ref());
        physics.reference_temperature_c =
            (self.reference_temperature_c.as_ref()).map(|c| *c.get_ref());
        Ok(physics)
    }

    /// Each joint's `backlash` (angle_unit; length_unit for a slide) into
    /// `physics`, after its masses: a play needs a mass to press one of its
    /// flanks ([`crate::corrections`]). A negative value (not physical: the
    /// link against its load) is read as written, since a calibrated arm
    /// file carries what its fit found.
    fn read_backlash(
        &self,
        physics: &mut Physics,
        at: &impl Fn(Range<usize>, &'static str, String) -> InputError,
    ) -> Result<(), InputError> {
        let joints = self.joint.get_ref().iter().map(Spanned::get_ref);
        for (i, j) in joints.enumerate() {
            let Some(b) = &j.backlash else {
                physics.backlash.push(None);
                continue;
            };
            if !physics.has_masses() {
                return Err(at(
                    b.span(),
                    "backlash",
                    format!(
                        "joint {}: a backlash needs masses: their gravity torque decides which \
                         flank the joint rests on; state `mass_kg` of the links and of the tool \
                         ([probe])",
                        i + 1
                    ),
                ));
            }
            let slides = j.kind.as_ref().is_some_and(|k| k.get_ref() == "prismatic");
            let unit = JointUnit {
                kind: if slides {
                    JointKind::Prismatic
                } else {
                    JointKind::Revolute
                },
                lu: self.length_unit,
                au: self.angle_unit,
            };
            physics.backlash.push(Some(unit.to_internal(*b.get_ref())));
        }
        if physics.backlash.iter().all(Option::is_none) {
            physics.backlash.clear();
        }
        Ok(())
    }

    /// Every number of the file, base to probe, with its context and key.
    fn numbers(&self) -> Vec<(String, &'static str, &Spanned<f64>)> {
        let mut out = Vec::new();
        for (i, j) in self
            .joint
            .get_ref()
            .iter()
            .map(Spanned::get_ref)
            .enumerate()
        {
            let ctx = format!("joint {}: ", i + 1);
            for (field, v) in [("theta", &j.theta), ("alpha", &j.alpha), ("a", &j.a)] {
                out.push((ctx.clone(), field, v));
            }
            if let Some(d) = &j.d {
                out.push((ctx.clone(), "d", d));
            }
            if let Some(b) = &j.hbeta {
                out.push((ctx.clone(), "hbeta", b));
            }
            for v in j.limits.iter().flat_map(|l| l.get_ref()) {
                out.push((ctx.clone(), "limits", v));
            }
            if let Some(m) = &j.mass_kg {
                out.push((ctx.clone(), "mass_kg", m));
            }
            if let Some(c) = &j.compliance_rad_per_nm {
                out.push((ctx.clone(), "compliance_rad_per_nm", c));
            }
            if let Some(b) = &j.backlash {
                out.push((ctx.clone(), "backlash", b));
            }
            for v in j.com_mm.iter().flat_map(|c| c.get_ref()) {
                out.push((ctx.clone(), "com_mm", v));
            }
            for v in (j.harmonics.iter().flat_map(|h| h.get_ref())).flat_map(|h| h.get_ref()) {
                out.push((ctx.clone(), "harmonics", v));
            }
        }
        for (field, v) in [
            ("cte_per_k", &self.cte_per_k),
            ("reference_temperature_c", &self.reference_temperature_c),
            ("mass_kg", &self.probe.mass_kg),
            ("ball_diameter_mm", &self.probe.ball_diameter_mm),
        ] {
            if let Some(v) = v {
                out.push((String::new(), field, v));
            }
        }
        for v in self.gravity.iter().flat_map(|g| g.get_ref()) {
            out.push((String::new(), "gravity", v));
        }
        for v in self.probe.com_mm.iter().flat_map(|g| g.get_ref()) {
            out.push(("[probe]: ".to_string(), "com_mm", v));
        }
        let p = &self.probe;
        for (field, v) in [("x", &p.x), ("y", &p.y), ("z", &p.z)] {
            out.push(("[probe]: ".to_string(), field, v));
        }
        for t in self.tool.iter().map(Spanned::get_ref) {
            let ctx = format!("[[tool]] {}: ", quoted(t.name.get_ref()));
            for v in t.offset_mm.get_ref() {
                out.push((ctx.clone(), "offset_mm", v));
            }
            if let Some(v) = &t.ball_diameter_mm {
                out.push((ctx.clone(), "ball_diameter_mm", v));
            }
        }
        out
    }

    /// Warnings where the stated unit looks wrong: a length over
    /// [`PLAUSIBLE_METRES`] in metres, a twist or zero offset over a full
    /// turn in radians.
    fn unit_warnings(&self, text: &str, file: &str) -> Vec<Warning> {
        let numbers = self.numbers();
        let first = |fields: &[&str], limit: f64| {
            numbers
                .iter()
                .find(|(_, f, v)| fields.contains(f) && v.get_ref().abs() > limit)
        };
        let long = (self.length_unit == LengthUnit::M)
            .then(|| first(&["a", "d", "x", "y", "z"], PLAUSIBLE_METRES))
            .flatten()
            .map(|(_, field, v)| {
                let message = format!(
                    "lengths declared in metres (length_unit = \"m\"), but |{}| m is longer \
                     than any arm ({PLAUSIBLE_METRES} m): these lengths look like millimetres; \
                     write length_unit = \"mm\" if so",
                    v.get_ref()
                );
                (field, v, message)
            });
        let turn = (self.angle_unit == AngleUnit::Rad)
            .then(|| first(&["theta", "alpha", "hbeta"], std::f64::consts::TAU))
            .flatten()
            .map(|(_, field, v)| {
                let message = format!(
                    "angles declared in radians (angle_unit = \"rad\"), but |{}| is more than \
                     a full turn (2π): these angles look like degrees; write angle_unit = \"deg\" \
                     if so",
                    v.get_ref()
                );
                (field, v, message)
            });
        (long.into_iter().chain(turn))
            .map(|(field, v, message)| Warning {
                file: file.to_string(),
                line: Some(line_of(text, v.span().start)),
                field: Some(field.to_string()),
                message,
            })
            .collect()
    }
}

/// Why an arm with `n` joints cannot be used (`n` not supported).
fn unsupported(n: usize) -> String {
    if n == 0 {
        return "no joints: add one [[joint]] table per joint, base to probe".into();
    }
    format!(
        "{n} joints; at most {MAX_JOINTS} are supported (the toolkit computes {})",
        crate::params::supported_joints_text()
    )
}

/// The tables of an arm file.
#[derive(Clone, Copy)]
enum Place {
    Top,
    Joint(usize),
    Probe,
}

/// Where `offset` is in the arm file: the table that holds it, and the key
/// there whose key or value spans it.
fn locate<'a>(root: &'a DeTable<'a>, offset: usize) -> (Place, &'a DeTable<'a>, Option<String>) {
    let covers = |s: Range<usize>| s.contains(&offset) || s.start == offset;
    let key_at = |t: &DeTable<'_>| {
        t.iter()
            .find(|(k, v)| covers(k.span()) || covers(v.span()))
            .map(|(k, _)| k.get_ref().to_string())
    };
    if let Some(DeValue::Array(items)) = root.get("joint").map(Spanned::get_ref) {
        for (i, item) in items.iter().enumerate() {
            match item.get_ref() {
                DeValue::Table(t) if covers(item.span()) || key_at(t).is_some() => {
                    return (Place::Joint(i + 1), t, key_at(t));
                }
                _ if covers(item.span()) => {
                    return (Place::Joint(i + 1), root, Some("joint".into()));
                }
                _ => {}
            }
        }
    }
    if let Some((_, v)) = root.get_key_value("probe")
        && let DeValue::Table(t) = v.get_ref()
        && (covers(v.span()) || key_at(t).is_some())
    {
        return (Place::Probe, t, key_at(t));
    }
    (Place::Top, root, key_at(root))
}

/// A serde error in the arm file's terms: the key, its line, the joint or
/// table it is in, and what is expected.
fn schema_error(text: &str, file: &str, root: &DeTable<'_>, e: &toml::de::Error) -> InputError {
    let message = e.message();
    let span = e.span().unwrap_or(0..0);
    let line = line_of(text, span.start);
    let (place, table, key) = locate(root, span.start);
    let ctx = match place {
        Place::Top => String::new(),
        Place::Joint(i) => format!("joint {i}: "),
        Place::Probe => "[probe]: ".to_string(),
    };
    // serde puts names in backticks: "unknown field `alpah`, expected one of `theta`, …".
    let names: Vec<&str> = message.split('`').skip(1).step_by(2).collect();
    let name = names.first().copied().unwrap_or("?");
    if message.starts_with("unknown field") {
        let known = names.get(1..).unwrap_or_default();
        // serde reports the first unknown key in key order; report the first in the file.
        let first = (table.iter())
            .filter(|(k, _)| !known.contains(&&**k.get_ref()))
            .min_by_key(|(k, _)| k.span().start);
        let (key, line) = first.map_or((name.to_string(), line), |(k, _)| {
            (k.get_ref().to_string(), line_of(text, k.span().start))
        });
        let place = match place {
            Place::Top => "at the top level".to_string(),
            Place::Joint(i) => format!("in joint {i}"),
            Place::Probe => "in [probe]".to_string(),
        };
        let hint = suggest(&key, known).map(|s| format!(" (did you mean `{s}`?)"));
        let expected: Vec<String> = known.iter().map(|k| format!("`{k}`")).collect();
        let message = format!(
            "unknown key {place}{}; expected one of {}",
            hint.unwrap_or_default(),
            expected.join(", ")
        );
        return InputError::field(file, line, key, message);
    }
    if message.starts_with("missing field") {
        let whole_file = ["length_unit", "angle_unit", "joint", "probe"].contains(&name);
        let line = if whole_file { 0 } else { line };
        return InputError::field(file, line, name, missing(name, &ctx));
    }
    if message.starts_with("duplicate field `alpha`") {
        let beta = table.get_key_value("beta");
        let line = beta.map_or(line, |(k, _)| line_of(text, k.span().start));
        let message = format!(
            "{ctx}both `alpha` and `beta` given; they name the same parameter (the link \
             twist), keep one"
        );
        return InputError::field(file, line, "beta", message);
    }
    let Some(key) = key else {
        return InputError::line_error(file, line, format!("{ctx}{message}"));
    };
    let raw = text.get(span.clone()).unwrap_or("?");
    let problem = if message == "floating-point number overflowed" {
        format!("{} is not a finite number", quoted(raw))
    } else if message.starts_with("invalid type: integer") && message.contains(" as ") {
        format!("integer {} out of range; write it as a float", quoted(raw))
    } else if let Some((found, expected)) =
        (message.strip_prefix("invalid type: ")).and_then(|m| m.rsplit_once(", expected "))
    {
        // Where the error is about the whole value, its TOML type (serde
        // calls a datetime a map).
        let value = table.get(key.as_str()).filter(|v| v.span() == span);
        let found = value.map_or(found, |v| v.get_ref().type_str());
        // Limits are in the file's angle unit, if it names one.
        let angle_unit = match root.get("angle_unit").map(Spanned::get_ref) {
            Some(DeValue::String(unit)) => format!(" in {}", shown(unit)),
            _ => String::new(),
        };
        invalid_type(&key, found, expected, &angle_unit)
    } else {
        message.to_string()
    };
    InputError::field(file, line, key, format!("{ctx}{problem}"))
}

/// What to say about the missing key `key` (`ctx`: the joint it is missing from).
fn missing(key: &str, ctx: &str) -> String {
    match key {
        "joint" => "no joints: add one [[joint]] table per joint, base to probe".to_string(),
        "probe" => "missing [probe] table: the probe centre `x`, `y`, `z` in the last joint's \
                    frame, in length_unit"
            .to_string(),
        "x" | "y" | "z" => "[probe]: missing; [probe] needs `x`, `y` and `z`".to_string(),
        _ => match unit_choices(key) {
            Some(choices) => format!("missing; add {choices} (units are never guessed)"),
            None => format!(
                "{ctx}missing; every [[joint]] needs `theta`, `alpha` (or `beta`), `a` and `d`"
            ),
        },
    }
}

/// "expected …, found …" for a value of the wrong type; `found` and
/// `expected` are serde's words (`integer `7``, `f64`, `a sequence`) or a
/// TOML type name; `in_angle_unit` (` in deg`) completes the limits' shape.
fn invalid_type(key: &str, found: &str, expected: &str, in_angle_unit: &str) -> String {
    let expected = match (expected, key) {
        ("a sequence", "joint") => "[[joint]] tables (an array of tables, one per joint)".into(),
        ("a sequence", _) => format!("`[min, max]`{in_angle_unit}"),
        ("f64", _) => "a number".into(),
        (e, k) => unit_choices(k).map_or(e.to_string(), |c| format!("{e} ({c})")),
    };
    let serde_words = [
        ("floating point", "float"),
        ("sequence", "array"),
        ("map", "table"),
    ];
    let found = serde_words
        .iter()
        .find(|(w, _)| found.starts_with(w))
        .map_or(found, |(_, t)| t);
    let found = found.split(' ').next().unwrap_or(found);
    let article = if found.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    };
    format!("expected {expected}, found {article} {found}")
}

/// `` `length_unit = "mm"` or `length_unit = "m"` `` for a unit key.
fn unit_choices(key: &str) -> Option<String> {
    let names = match key {
        "length_unit" => LengthUnit::NAMES,
        "angle_unit" => AngleUnit::NAMES,
        _ => return None,
    };
    let choices: Vec<String> = names.iter().map(|n| format!("`{key} = \"{n}\"`")).collect();
    Some(choices.join(" or "))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    const F: &str = "my-arm.toml";

    const GOOD: &str = r#"name = "paper-table-1"
length_unit = "mm"
angle_unit = "deg"

[[joint]]
theta = 0.0
alpha = -90.0
a = 50.0
d = 375.0
limits = [-180.0, 180.0]

[[joint]]
theta = 0.5
beta = 90
a = -55.0
d = 0.0

[[joint]]
theta = 0.0
alpha = -90.0
a = 35.0
d = 250.0

[[joint]]
theta = 0.0
alpha = 90.0
a = -35.0
d = 0.0

[[joint]]
theta = 0.0
alpha = -90.0
a = 35.0
d = 270.0

[[joint]]
theta = 0.0
alpha = 90.0
a = -35.0
d = 0.0

[probe]
x = 0.0
y = 0.0
z = 100.0
"#;

    fn err(text: &str) -> InputError {
        parse_arm(text, F).unwrap_err()
    }

    /// `GOOD` with `from` replaced by `to` (which must occur).
    fn edit(from: &str, to: &str) -> String {
        assert!(GOOD.contains(from), "{from}");
        GOOD.replacen(from, to, 1)
    }

    #[track_caller]
    fn assert_at(e: &InputError, line: usize, field: Option<&str>, needle: &str) {
        crate::io::testing::assert_at(e, F, line, field, needle);
    }

    #[test]
    fn parses_good_file() {
        let (arm, warnings) = parse_arm(GOOD, F).unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        assert_eq!(arm.name, "paper-table-1");
        let j = &arm.params.joints;
        assert_eq!(j.len(), 6);
        assert_eq!(j[0].alpha, -std::f64::consts::FRAC_PI_2);
        assert_eq!((j[0].a, j[0].d, j[0].theta), (50.0, 375.0, 0.0));
        assert_eq!(j[1].alpha, std::f64::consts::FRAC_PI_2); // from `beta`, an integer
        assert_eq!(j[1].theta, 0.5f64.to_radians());
        assert_eq!(arm.params.probe, [0.0, 0.0, 100.0]);
        let pi = std::f64::consts::PI;
        assert_eq!(
            arm.limits,
            vec![Some([-pi, pi]), None, None, None, None, None]
        );
    }

    #[test]
    fn units_convert() {
        let text = edit("length_unit = \"mm\"", "length_unit = \"m\"")
            .replace("angle_unit = \"deg\"", "angle_unit = \"rad\"");
        let (arm, _) = parse_arm(&text, F).unwrap();
        assert_eq!(arm.params.joints[0].d, 375_000.0);
        assert_eq!(arm.params.joints[0].alpha, -90.0);
        assert_eq!(arm.params.probe[2], 100_000.0);
        assert_eq!(arm.limits[0], Some([-180.0, 180.0]));
    }

    #[test]
    fn name_is_optional() {
        let (arm, _) = parse_arm(&edit("name = \"paper-table-1\"\n", ""), F).unwrap();
        assert_eq!(arm.name, "");
        assert_at(
            &err(&edit("\"paper-table-1\"", "7")),
            1,
            Some("name"),
            "expected a string, found an integer",
        );
    }

    #[test]
    fn syntax_errors_are_located() {
        assert_at(
            &err(&edit("d = 375.0", "d = 375.0.0")),
            9,
            None,
            "TOML syntax",
        );
        assert_at(
            &err(&edit("a = -55.0", "a = -55.0\na = 1")),
            16,
            None,
            "TOML syntax: duplicate key",
        );
        assert_at(
            &err(&edit("limits = [-180.0, 180.0]", "limits = [-180.0,")),
            13, // where the parser notices: arrays may span lines
            None,
            "TOML syntax",
        );
        assert_at(&err("x = \"unterminated\n"), 1, None, "TOML syntax");
    }

    #[test]
    fn units_are_required_and_checked() {
        assert_at(
            &err(&edit("length_unit = \"mm\"\n", "")),
            0,
            Some("length_unit"),
            "missing; add `length_unit = \"mm\"` or `length_unit = \"m\"` (units are never guessed)",
        );
        assert_at(
            &err(&edit("angle_unit = \"deg\"\n", "")),
            0,
            Some("angle_unit"),
            "units are never guessed",
        );
        assert_at(
            &err(&edit("\"mm\"", "\"inch\"")),
            2,
            Some("length_unit"),
            "unknown length unit `inch`; accepted: `mm`, `m`",
        );
        assert_at(
            &err(&edit("\"deg\"", "\"degrees\"")),
            3,
            Some("angle_unit"),
            "unknown angle unit `degrees`; accepted: `deg`, `rad`",
        );
        assert_at(
            &err(&edit("\"deg\"", "1")),
            3,
            Some("angle_unit"),
            "expected a string",
        );
    }

    #[test]
    fn unknown_keys_are_errors() {
        assert_at(
            &err(&edit("alpha", "alpah")),
            7,
            Some("alpah"),
            "unknown key in joint 1 (did you mean `alpha`?)",
        );
        assert_at(
            &err(&edit("theta = 0.5", "theta = 0.5\nbeta_err = 1")),
            14,
            Some("beta_err"),
            "unknown key in joint 2",
        );
        assert_at(
            &err(&edit("z = 100.0", "z = 100.0\nw = 1")),
            46,
            Some("w"),
            "unknown key in [probe]",
        );
        assert_at(
            &err(&format!("units = 1\n{GOOD}")),
            1,
            Some("units"),
            "unknown key at the top level",
        );
        assert_at(
            &err(&format!("{GOOD}[extra]\n")),
            46,
            Some("extra"),
            "unknown key at the top level",
        );
        // The first unknown key in file order is reported.
        assert_at(
            &err(&edit("a = 50.0", "zz = 1\na = 50.0\nbb = 2")),
            8,
            Some("zz"),
            "unknown key",
        );
    }

    #[test]
    fn missing_joint_fields() {
        assert_at(
            &err(&edit("d = 375.0\n", "")),
            5,
            Some("d"),
            "joint 1: missing; every [[joint]] needs",
        );
        assert_at(
            &err(&edit("theta = 0.5\n", "")),
            12,
            Some("theta"),
            "joint 2: missing",
        );
        assert_at(
            &err(&edit("beta = 90\n", "")),
            12,
            Some("alpha"),
            "joint 2: missing",
        );
        assert_at(
            &err(&edit("a = -55.0\n", "")),
            12,
            Some("a"),
            "joint 2: missing",
        );
    }

    #[test]
    fn alpha_and_beta_both() {
        assert_at(
            &err(&edit("alpha = -90.0", "alpha = -90.0\nbeta = -90.0")),
            8,
            Some("beta"),
            "both `alpha` and `beta`",
        );
    }

    #[test]
    fn bad_values() {
        assert_at(
            &err(&edit("a = 50.0", "a = nan")),
            8,
            Some("a"),
            "joint 1: `nan` is not a finite number",
        );
        assert_at(
            &err(&edit("d = 375.0", "d = -inf")),
            9,
            Some("d"),
            "`-inf` is not a finite number",
        );
        assert_at(
            &err(&edit("d = 375.0", "d = 1e400")),
            9,
            Some("d"),
            "`1e400` is not a finite number",
        );
        assert_at(
            &err(&edit("a = 50.0", "a = \"50\"")),
            8,
            Some("a"),
            "expected a number, found a string",
        );
        assert_at(
            &err(&edit("z = 100.0", "z = true")),
            45,
            Some("z"),
            "[probe]: expected a number, found a boolean",
        );
        assert_at(
            &err(&edit("z = 100.0", "z = 99999999999999999999")),
            45,
            Some("z"),
            "[probe]: integer `99999999999999999999` out of range; write it as a float",
        );
        assert_at(
            &err(&edit("theta = 0.5", "theta = 1979-05-27")),
            13,
            Some("theta"),
            "joint 2: expected a number, found a datetime",
        );
        // Integers in other radixes are numbers.
        let (arm, _) = parse_arm(&edit("d = 375.0", "d = 0x10"), F).unwrap();
        assert_eq!(arm.params.joints[0].d, 16.0);
    }

    #[test]
    fn limits() {
        assert_at(
            &err(&edit("[-180.0, 180.0]", "[180.0, -180.0]")),
            10,
            Some("limits"),
            "min 180 must be less than max -180",
        );
        assert_at(
            &err(&edit("[-180.0, 180.0]", "[10, 10]")),
            10,
            Some("limits"),
            "must be less than",
        );
        assert_at(
            &err(&edit("[-180.0, 180.0]", "[-180.0]")),
            10,
            Some("limits"),
            "expected `[min, max]` in deg, found 1 values",
        );
        assert_at(
            &err(&edit("[-180.0, 180.0]", "180.0")),
            10,
            Some("limits"),
            "expected `[min, max]` in deg, found a float",
        );
        assert_at(
            &err(&edit("[-180.0, 180.0]", "[-180.0, inf]")),
            10,
            Some("limits"),
            "not a finite number",
        );
        assert_at(
            &err(&edit("[-180.0, 180.0]", "[-180.0, \"x\"]")),
            10,
            Some("limits"),
            "expected a number",
        );
    }

    #[test]
    fn joint_count() {
        let no_joints =
            "length_unit = \"mm\"\nangle_unit = \"deg\"\n[probe]\nx = 0\ny = 0\nz = 0\n";
        assert_at(&err(no_joints), 0, Some("joint"), "no joints");
        assert_at(
            &err(&format!("joint = []\n{no_joints}")),
            1,
            Some("joint"),
            "no joints",
        );
        assert_at(
            &err(&format!("{no_joints}[joint]\na = 1\n")),
            7,
            Some("joint"),
            "expected [[joint]] tables",
        );
        assert_at(
            &err(&format!("joint = [1]\n{no_joints}")),
            1,
            Some("joint"),
            "joint 1: expected a table, found an integer",
        );
        let joint = "[[joint]]\ntheta = 0\nalpha = 0\na = 0\nd = 1\n";
        let twelve = format!("{no_joints}{}", joint.repeat(12));
        assert_eq!(parse_arm(&twelve, F).unwrap().0.params.joint_count(), 12);
        let thirteen = format!("{twelve}{joint}");
        // The thirteenth [[joint]] header is on line 6 + 12 * 5 + 1.
        assert_at(
            &err(&thirteen),
            67,
            Some("joint"),
            "13 joints; at most 12 are supported",
        );
    }

    #[test]
    fn every_joint_count_of_a_chain_is_read() {
        // Five joints and one: chains the kernel computes (they used to be
        // refused, with 6 and 7 the only counts).
        let five = edit(
            "\n[[joint]]\ntheta = 0.0\nalpha = 90.0\na = -35.0\nd = 0.0\n\n[probe]",
            "\n[probe]",
        );
        assert_eq!(parse_arm(&five, F).unwrap().0.params.joint_count(), 5);
        let one = "length_unit = \"mm\"\nangle_unit = \"deg\"\n[[joint]]\ntheta = 0\nalpha = 0\n\
                   a = 0\nd = 1\n[probe]\nx = 0\ny = 0\nz = 0\n";
        assert_eq!(parse_arm(one, F).unwrap().0.params.joint_count(), 1);
        assert_eq!(
            unsupported(13),
            "13 joints; at most 12 are supported (the toolkit computes chains of 1 to 12 joints)"
        );
    }

    #[test]
    fn implausible_units_warn() {
        // Millimetre values declared as metres: |d| = 375 m.
        let text = edit("length_unit = \"mm\"", "length_unit = \"m\"");
        let (_, w) = parse_arm(&text, F).unwrap();
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!((w[0].line, w[0].field.as_deref()), (Some(8), Some("a")));
        assert!(
            w[0].to_string()
                .starts_with("my-arm.toml:8: field `a`: lengths declared in metres"),
            "{}",
            w[0]
        );
        assert!(w[0].message.contains("look like millimetres"), "{}", w[0]);
        // Degree values declared as radians: |alpha| = 90.
        let text = edit("angle_unit = \"deg\"", "angle_unit = \"rad\"");
        let (_, w) = parse_arm(&text, F).unwrap();
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!((w[0].line, w[0].field.as_deref()), (Some(7), Some("alpha")));
        assert!(w[0].message.contains("look like degrees"), "{}", w[0]);
        // Plausible values in m and rad: no warning; the probe counts as a length.
        let arm = Arm::without_limits("n", DhParams::paper_nominal());
        let text = arm_to_toml(&arm, LengthUnit::M, AngleUnit::Rad);
        assert_eq!(parse_arm(&text, F).unwrap().1, vec![]);
        let far = text.replace("z = 0.1\n", "z = -12.5\n");
        let (_, w) = parse_arm(&far, F).unwrap();
        assert_eq!(w[0].field.as_deref(), Some("z"), "{w:?}");
        assert!(w[0].message.contains("|-12.5| m"), "{}", w[0]);
    }

    #[test]
    fn probe_required() {
        let text = GOOD[..GOOD.find("[probe]").unwrap()].to_string();
        assert_at(&err(&text), 0, Some("probe"), "missing [probe] table");
        assert_at(
            &err(&edit("y = 0.0\n", "")),
            42,
            Some("y"),
            "[probe]: missing",
        );
        assert_at(
            &err(&format!("probe = 3\n{text}")),
            1,
            Some("probe"),
            "expected a table",
        );
        // Other TOML spellings of the same table are fine.
        let (arm, _) = parse_arm(&format!("probe = {{ x = 1, y = 2, z = 3 }}\n{text}"), F).unwrap();
        assert_eq!(arm.params.probe, [1.0, 2.0, 3.0]);
    }

    #[test]
    fn write_is_deterministic_and_round_trips_bits() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for n in [1, 5, 6, 7, 12] {
            // Every third joint Hayati: its β round-trips too.
            let joints = (0..n)
                .map(|i| {
                    let j = DhJoint {
                        a: rng.random_range(-100.0..100.0),
                        d: rng.random_range(-400.0..400.0),
                        alpha: rng.random_range(-3.2..3.2),
                        theta: rng.random_range(-0.1..0.1),
                        ..DhJoint::default()
                    };
                    let j = if i % 3 == 1 {
                        DhJoint::hayati(j.a, j.alpha, j.theta, rng.random_range(-0.1..0.1))
                    } else {
                        j
                    };
                    // Every fourth joint slides (some of them Hayati too).
                    if i % 4 == 1 {
                        j.with_kind(JointKind::Prismatic)
                    } else {
                        j
                    }
                })
                .collect();
            let limits = (0..n)
                .map(|i| {
                    (i % 2 == 0 || i % 4 == 1).then(|| {
                        let scale = if i % 4 == 1 { 300.0 } else { 1.0 };
                        [-3.0, 1.0].map(|x| scale * rng.random_range(x..x + 2.0))
                    })
                })
                .collect();
            let arm = Arm {
                name: "quote \" backslash \\ tab\t nl\n ctl\u{1} é".to_string(),
                params: DhParams {
                    joints,
                    probe: [rng.random(), rng.random(), 1e-12],
                },
                limits,
                prior: None,
                physics: Box::default(),
                ball_diameter_mm: None,
                tools: Vec::new(),
            };
            let text = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Rad);
            let (back, _) = parse_arm(&text, F).unwrap();
            assert_eq!(back.name, arm.name);
            assert_eq!(back.limits, arm.limits);
            let bits = |a: &Arm| {
                a.params
                    .to_vec()
                    .iter()
                    .map(|x| x.to_bits())
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(&back), bits(&arm));
            assert_eq!(back.params, arm.params);
            assert_eq!(arm_to_toml(&back, LengthUnit::Mm, AngleUnit::Rad), text);
            // Through deg and m: within 1 ulp.
            let (back, _) =
                parse_arm(&arm_to_toml(&arm, LengthUnit::M, AngleUnit::Deg), F).unwrap();
            for (x, y) in back.params.to_vec().iter().zip(arm.params.to_vec()) {
                assert!((x - y).abs() <= y.abs() * f64::EPSILON, "{x} {y}");
            }
            let kinds = |a: &Arm| a.params.joints.iter().map(|j| j.kind).collect::<Vec<_>>();
            assert_eq!(kinds(&back), kinds(&arm));
            // A slide's limits go through metres, a turn's through degrees.
            for (x, y) in back
                .limits
                .iter()
                .flatten()
                .zip(arm.limits.iter().flatten())
            {
                for (x, y) in x.iter().zip(y) {
                    assert!((x - y).abs() <= 2.0 * y.abs() * f64::EPSILON, "{x} {y}");
                }
            }
        }
    }

    #[test]
    fn a_prismatic_joint_reads_its_limits_as_lengths() {
        let text = edit(
            "theta = 0.5\nbeta = 90\na = -55.0\nd = 0.0\n",
            "type = \"prismatic\"\ntheta = 0.5\nbeta = 90\na = -55.0\nd = 0.0\n\
             limits = [-200, 650]\n",
        );
        let (arm, _) = parse_arm(&text, F).unwrap();
        let j = &arm.params.joints;
        assert_eq!(j[1].kind, JointKind::Prismatic);
        assert!(
            j.iter()
                .enumerate()
                .all(|(i, j)| i == 1 || j.kind == JointKind::Revolute)
        );
        assert_eq!(arm.limits[1], Some([-200.0, 650.0]));
        let written = arm_to_toml(&arm, LengthUnit::M, AngleUnit::Deg);
        assert!(written.contains("type = \"prismatic\""), "{written}");
        assert!(written.contains("limits = [-0.2, 0.65]"), "{written}");
        // Revolute joints are written as before: no `type` key.
        assert_eq!(written.matches("type =").count(), 1, "{written}");
        let bad = text.replace("\"prismatic\"", "\"sliding\"");
        assert_at(
            &err(&bad),
            13,
            Some("type"),
            "joint 2: unknown type `sliding`; expected \"revolute\"",
        );
    }

    /// A joint's `backlash` is in angle_unit (a slide's in length_unit),
    /// kept on writing; it needs a mass to press a flank (refused at its
    /// line without); a fit's negative value reads back.
    #[test]
    fn a_backlash_reads_writes_and_needs_masses() {
        let joint2 = "theta = 0.5\nbeta = 90\na = -55.0\nd = 0.0\n";
        let text = edit(joint2, &format!("{joint2}backlash = 0.02\nmass_kg = 3.0\n"));
        let (arm, _) = parse_arm(&text, F).unwrap();
        assert_eq!(arm.physics.backlash.len(), 6);
        assert!((arm.physics.backlash_of(1) - 0.02f64.to_radians()).abs() < 1e-18);
        assert_eq!(arm.physics.backlash_of(0), 0.0);
        let written = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg);
        assert!(written.contains("backlash = 0.02"), "{written}");
        let back = parse_arm(&written, F).unwrap().0;
        assert_eq!(back.physics.backlash, arm.physics.backlash);
        // A slide's play is a length.
        let slide = text.replacen("theta = 0.5", "type = \"prismatic\"\ntheta = 0.5", 1);
        let (arm, _) =
            parse_arm(&slide.replacen("backlash = 0.02", "backlash = 0.05", 1), F).unwrap();
        assert_eq!(arm.physics.backlash_of(1), 0.05);
        let no_mass = edit(joint2, &format!("{joint2}backlash = 0.02\n"));
        assert_at(
            &err(&no_mass),
            17,
            Some("backlash"),
            "joint 2: a backlash needs masses",
        );
        let negative = text.replacen("backlash = 0.02", "backlash = -0.02", 1);
        let arm = parse_arm(&negative, F).unwrap().0;
        assert!((arm.physics.backlash_of(1) + 0.02f64.to_radians()).abs() < 1e-18);
        // A slide's limits and play in metres, written back in metres and
        // radians: lengths both ways, never angles.
        let limited = slide.replacen("d = 0.0\n", "d = 0.0\nlimits = [0.0, 1500.0]\n", 1);
        let (arm, _) = parse_arm(&limited, F).unwrap();
        assert_eq!(arm.limits[1], Some([0.0, 1500.0]));
        let metres = arm_to_toml(&arm, LengthUnit::M, AngleUnit::Rad);
        assert!(metres.contains("limits = [0.0, 1.5]"), "{metres}");
        assert!(metres.contains("backlash = 0.00002"), "{metres}");
        let back = parse_arm(&metres, F).unwrap().0;
        assert_eq!(back.limits[1], arm.limits[1]);
        assert_eq!(back.physics.backlash_of(1), 0.02);
    }

    /// `GOOD` with joint 2 (α = 90°) written as a Hayati joint.
    fn hayati_text() -> String {
        edit(
            "theta = 0.5\nbeta = 90\na = -55.0\nd = 0.0\n",
            "model = \"hayati\"\ntheta = 0.5\nalpha = 90\na = -55.0\nhbeta = 0.25\n",
        )
    }

    #[test]
    fn hayati_joints_read_and_write_back() {
        let (arm, _) = parse_arm(&hayati_text(), F).unwrap();
        let j = arm.params.joints[1];
        assert_eq!(j.model, JointModel::Hayati);
        assert_eq!((j.beta, j.d), (0.25f64.to_radians(), 0.0));
        assert_eq!(arm.params.joints[0].model, JointModel::Dh);
        let text = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg);
        assert!(
            text.contains(
                "model = \"hayati\"\ntheta = 0.5\nalpha = 90.0\na = -55.0\nhbeta = 0.25\n"
            ),
            "{text}"
        );
        assert_eq!(
            text.matches("model").count(),
            1,
            "D-H joints write no model"
        );
        assert_eq!(parse_arm(&text, F).unwrap().0, arm);
        // `model = "dh"` is the default, spelled out.
        let dh = edit("theta = 0.5\n", "model = \"dh\"\ntheta = 0.5\n");
        assert_eq!(parse_arm(&dh, F).unwrap().0, parse_arm(GOOD, F).unwrap().0);
    }

    #[test]
    fn hayati_mistakes_are_located() {
        let h = hayati_text();
        let bad = |from: &str, to: &str| {
            assert!(h.contains(from), "{from}");
            err(&h.replacen(from, to, 1))
        };
        assert_at(
            &bad("model = \"hayati\"", "model = \"hayat\""),
            13,
            Some("model"),
            "joint 2: unknown model `hayat`; expected \"dh\" or \"hayati\"",
        );
        assert_at(
            &bad("hbeta = 0.25\n", "hbeta = 0.25\nd = 1.0\n"),
            18,
            Some("d"),
            "joint 2: a Hayati joint (model = \"hayati\") has no `d`",
        );
        assert_at(
            &bad("hbeta = 0.25\n", ""),
            12,
            Some("hbeta"),
            "joint 2: missing; a Hayati joint",
        );
        assert_at(
            &bad("model = \"hayati\"\n", ""),
            12,
            Some("d"),
            "joint 2: missing; every [[joint]] needs",
        );
        assert_at(
            &err(&edit("d = 375.0\n", "d = 375.0\nhbeta = 1.0\n")),
            10,
            Some("hbeta"),
            "joint 1: `hbeta` is the Hayati rotation: it needs `model = \"hayati\"`",
        );
        assert_at(
            &bad("hbeta = 0.25", "hbeta = inf"),
            17,
            Some("hbeta"),
            "joint 2: `inf` is not a finite number",
        );
    }

    #[test]
    fn user_file_round_trips_in_its_units() {
        let (arm, _) = parse_arm(GOOD, F).unwrap();
        let text = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg);
        // The user's numbers come back as written (integers as floats, `beta` as `alpha`).
        let expected = GOOD.replace("beta = 90", "alpha = 90.0");
        assert_eq!(text, expected);
        assert_eq!(parse_arm(&text, F).unwrap().0, arm);
    }

    #[test]
    fn nominal_in_metres() {
        let arm = Arm::without_limits("nominal", DhParams::paper_nominal());
        let text = arm_to_toml(&arm, LengthUnit::M, AngleUnit::Deg);
        assert!(text.contains("a = 0.05\nd = 0.375\n"), "{text}");
        assert!(text.contains("z = 0.1\n"), "{text}");
        assert_eq!(parse_arm(&text, F).unwrap(), (arm, vec![]));
    }

    #[test]
    fn non_finite_written_as_toml_and_rejected() {
        let mut arm = Arm::without_limits("x", DhParams::paper_nominal());
        arm.params.joints[2].a = f64::NAN;
        arm.params.probe[0] = f64::NEG_INFINITY;
        let text = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg);
        assert!(
            text.contains("a = nan\n") && text.contains("x = -inf\n"),
            "{text}"
        );
        let e = parse_arm(&text, F).unwrap_err();
        assert_eq!(e.field_name(), Some("a"));
        assert!(
            e.to_string()
                .contains("joint 3: `nan` is not a finite number"),
            "{e}"
        );
    }

    #[test]
    fn files_on_disk() {
        let dir = std::env::temp_dir().join(format!("aacmm-io-arm-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("arm.toml");
        let arm = Arm::without_limits("nominal", DhParams::paper_nominal());
        write_arm(&path, &arm, LengthUnit::Mm, AngleUnit::Deg).unwrap();
        assert_eq!(read_arm(&path).unwrap(), (arm.clone(), vec![]));
        std::fs::write(
            &path,
            "length_unit = \"mm\"\nangle_unit = \"deg\"\n[[joint]]\nalpah = 1\n",
        )
        .unwrap();
        let e = read_arm(&path).unwrap_err();
        assert!(
            e.to_string()
                .starts_with(&format!("{}:4: field `alpah`", path.display())),
            "{e}"
        );
        let e = read_arm(&dir.join("nope.toml")).unwrap_err();
        assert!(matches!(e, InputError::Io { .. }), "{e}");
        let e = write_arm(
            &dir.join("no/such/dir.toml"),
            &arm,
            LengthUnit::Mm,
            AngleUnit::Deg,
        )
        .unwrap_err();
        assert!(e.to_string().contains("no/such/dir.toml"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// `[probe] ball_diameter_mm`: read in mm whatever `length_unit` says,
    /// written back only when stated (a file without it reads and writes as
    /// before), and refused by line and field when it cannot be a ball's.
    #[test]
    fn the_probe_ball_diameter_round_trips_and_is_checked() {
        let (plain, _) = parse_arm(GOOD, F).unwrap();
        assert_eq!(plain.ball_diameter_mm, None);
        assert!(!arm_to_toml(&plain, LengthUnit::Mm, AngleUnit::Deg).contains("ball"));
        let with =
            |v: &str| GOOD.replace("[probe]\n", &format!("[probe]\nball_diameter_mm = {v}\n"));
        let (arm, _) = parse_arm(&with("6.0"), F).unwrap();
        assert_eq!(arm.ball_diameter_mm, Some(6.0));
        // In a file in metres the field is still mm.
        let metres = with("6.0").replace("length_unit = \"mm\"", "length_unit = \"m\"");
        assert_eq!(parse_arm(&metres, F).unwrap().0.ball_diameter_mm, Some(6.0));
        for unit in [LengthUnit::Mm, LengthUnit::M] {
            let text = arm_to_toml(&arm, unit, AngleUnit::Deg);
            assert!(text.contains("ball_diameter_mm = 6.0"), "{text}");
            assert_eq!(parse_arm(&text, F).unwrap().0.ball_diameter_mm, Some(6.0));
        }
        let line = GOOD[..GOOD.find("[probe]").unwrap()].lines().count() + 2;
        for (v, why) in [
            ("0.006", "in metres?"),
            ("0", "positive"),
            ("-2", "positive"),
            ("150", "more than any probe"),
        ] {
            let e = parse_arm(&with(v), F).unwrap_err();
            assert_at(&e, line, Some("ball_diameter_mm"), why);
        }
        let e = parse_arm(&with("nan"), F).unwrap_err();
        assert_at(&e, line, Some("ball_diameter_mm"), "not a finite number");
    }
}
