//! The arm-file schema: a serde type whose values are in the file's units,
//! with their places in the text, and its conversion to an [`Arm`] and back.

use std::ops::Range;

use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::messages::unsupported;
use super::{MAX_BALL_DIAMETER_MM, MIN_BALL_DIAMETER_MM, PLAUSIBLE_METRES};
use crate::corrections::{Harmonic, MAX_HARMONIC_ORDER, Mass, Physics};
use crate::domain::Arm;
use crate::error::{InputError, quoted};
use crate::io::Warning;
use crate::io::text::line_of;
use crate::io::units::{AngleUnit, LengthUnit};
use crate::params::{DhJoint, DhParams, JointKind, JointModel, MAX_JOINTS, supports_joints};

mod read;

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
    /// The named tool points ([`crate::io::tools`]); absent when none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    tool: Vec<Spanned<ToolFile>>,
    /// Stated tolerances: read by [`crate::io::prior`], never written.
    #[serde(rename = "prior", default, skip_serializing)]
    _prior: Option<serde::de::IgnoredAny>,
    /// A calibration's frame registrations: read by [`crate::io::frames`],
    /// never written here.
    #[serde(rename = "frame", default, skip_serializing)]
    _frame: Option<serde::de::IgnoredAny>,
    /// A calibration's tool mount of orientations: read by
    /// [`crate::io::frames::parse_mount`], never written here.
    #[serde(rename = "mount", default, skip_serializing)]
    _mount: Option<serde::de::IgnoredAny>,
    /// A calibration's verdict: read by [`crate::io::verdict`], never written
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

/// One `[[tool]]` table: a named tool point ([`crate::io::tools`]).
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

/// A unit from its name, with [`UnknownUnit`](crate::io::UnknownUnit)'s message.
fn from_name<'de, D, U>(d: D) -> Result<U, D::Error>
where
    D: serde::Deserializer<'de>,
    U: std::str::FromStr<Err = crate::io::UnknownUnit>,
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
}
