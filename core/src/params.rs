//! Geometric parameters of a D-H chain with a probe offset, and the chain's
//! shape: how many joints, which of them revolute and which prismatic.
//!
//! Inside the toolkit lengths are millimetres and angles radians; units are
//! converted only where a user touches them (files, flags, reports).
//! The parameter order is fixed and is the paper's column order (method.md §2):
//! `a1..an, d1..dn, α1..αn, θ1..θn, Bx, By, Bz`.

use std::fmt;

use thiserror::Error;

/// What a joint's reading moves.
///
/// A revolute joint turns about the previous z axis: its reading `q` (rad)
/// adds to `θ`. A prismatic joint slides along it: its reading (mm) adds to
/// `d`, and its constant parameters are `θ`, `a`, `α` and `d`'s offset (the
/// reading's zero). The parameter vector and its names are the same for
/// both; only what `q` means differs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum JointKind {
    /// Turns: `A = Rz(θ + q)·Tz(d)·…`.
    #[default]
    Revolute,
    /// Slides: `A = Rz(θ)·Tz(d + q)·…`.
    Prismatic,
}

impl JointKind {
    /// The name in files: `revolute` or `prismatic`.
    pub(crate) fn name(self) -> &'static str {
        match self {
            JointKind::Revolute => "revolute",
            JointKind::Prismatic => "prismatic",
        }
    }

    /// The letter in a [`ChainShape`]: `R` or `P`.
    pub fn letter(self) -> char {
        match self {
            JointKind::Revolute => 'R',
            JointKind::Prismatic => 'P',
        }
    }

    /// The unit of the joint's reading in files and reports: `deg` for a
    /// revolute joint, `mm` for a prismatic one (whatever the angle unit).
    pub(crate) fn reading_unit(self) -> &'static str {
        match self {
            JointKind::Revolute => "deg",
            JointKind::Prismatic => "mm",
        }
    }
}

/// As in files: `"revolute"` or `"prismatic"`.
impl serde::Serialize for JointKind {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for JointKind {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<JointKind, D::Error> {
        let name = String::deserialize(d)?;
        [JointKind::Revolute, JointKind::Prismatic]
            .into_iter()
            .find(|k| k.name() == name)
            .ok_or_else(|| {
                serde::de::Error::custom(format!(
                    "joint type `{name}`: `revolute` or `prismatic` expected"
                ))
            })
    }
}

/// Most joints a chain may have. Every chain of 1 to `MAX_JOINTS` joints,
/// any of them prismatic, has a kernel: a generated one for the common
/// shapes ([`crate::kernel::SHIPPED_SHAPES`]), a closed-form per-joint one
/// for the rest.
pub const MAX_JOINTS: usize = 12;

/// A chain's shape: its joint count (1 to [`MAX_JOINTS`]) and which joints
/// are prismatic. Written as one letter per joint, base first: `R`
/// revolute, `P` prismatic (`"PRRRRRR"`: a robot of six revolute joints on
/// a linear track; `"RRPR"`: a SCARA).
///
/// ```
/// use aacmm_core::params::{ChainShape, DhParams, JointKind};
/// let scara: ChainShape = "RRPR".parse().unwrap();
/// assert_eq!((scara.joints(), scara.kind(2)), (4, JointKind::Prismatic));
/// assert_eq!(scara.to_string(), "RRPR");
/// assert_eq!(DhParams::paper_nominal().shape().unwrap().to_string(), "RRRRRR");
/// assert!("RRXR".parse::<ChainShape>().is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ChainShape {
    joints: u8,
    /// Bit `i`: joint `i` is prismatic.
    prismatic: u16,
}

/// A shape that is not one: no joints, too many, or a letter other than
/// `R` and `P`.
#[derive(Clone, Debug, Error, PartialEq, Eq)]
pub enum ShapeError {
    /// A chain has 1 to [`MAX_JOINTS`] joints.
    #[error("a chain has 1 to {MAX_JOINTS} joints, not {0}")]
    Joints(usize),
    /// A letter other than `R` and `P`.
    #[error(
        "{} at joint {joint}: a shape has one letter per joint, R (revolute) or P (prismatic)",
        crate::error::quoted(&letter.to_string())
    )]
    Letter {
        /// The letter.
        letter: char,
        /// Its joint, 1-based.
        joint: usize,
    },
    /// Prismatic bits past the joint count.
    #[error("prismatic joints {mask:#b} past the chain's {joints} joints")]
    Mask {
        /// The bits given.
        mask: u16,
        /// The joint count.
        joints: usize,
    },
}

impl ChainShape {
    /// `joints` revolute joints.
    ///
    /// ```
    /// use aacmm_core::params::ChainShape;
    /// assert_eq!(ChainShape::revolute(7).unwrap().to_string(), "RRRRRRR");
    /// assert!(ChainShape::revolute(13).is_err());
    /// ```
    pub fn revolute(joints: usize) -> Result<ChainShape, ShapeError> {
        ChainShape::from_mask(joints, 0)
    }

    /// A shape from its joint count and its prismatic joints (bit `i` for
    /// joint `i`).
    pub fn from_mask(joints: usize, prismatic: u16) -> Result<ChainShape, ShapeError> {
        if !(1..=MAX_JOINTS).contains(&joints) {
            return Err(ShapeError::Joints(joints));
        }
        if prismatic >> joints != 0 {
            return Err(ShapeError::Mask {
                mask: prismatic,
                joints,
            });
        }
        Ok(ChainShape {
            joints: joints as u8,
            prismatic,
        })
    }

    /// The shape of joints of `kinds`, base first.
    pub fn new(kinds: impl IntoIterator<Item = JointKind>) -> Result<ChainShape, ShapeError> {
        let mut joints = 0;
        let mut prismatic = 0u16;
        for (i, kind) in kinds.into_iter().enumerate() {
            if i < MAX_JOINTS && kind == JointKind::Prismatic {
                prismatic |= 1 << i;
            }
            joints = i + 1;
        }
        ChainShape::from_mask(joints, prismatic)
    }

    /// Number of joints.
    pub fn joints(self) -> usize {
        self.joints as usize
    }

    /// The prismatic joints: bit `i` for joint `i`.
    pub fn prismatic_mask(self) -> u16 {
        self.prismatic
    }

    /// Whether joint `i` (0-based) is prismatic.
    pub fn is_prismatic(self, i: usize) -> bool {
        i < MAX_JOINTS && self.prismatic & (1 << i) != 0
    }

    /// Joint `i`'s kind.
    pub fn kind(self, i: usize) -> JointKind {
        if self.is_prismatic(i) {
            JointKind::Prismatic
        } else {
            JointKind::Revolute
        }
    }

    /// The joints' kinds, base first.
    pub fn kinds(self) -> impl Iterator<Item = JointKind> {
        (0..self.joints()).map(move |i| self.kind(i))
    }
}

impl fmt::Display for ChainShape {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.kinds().try_for_each(|k| write!(f, "{}", k.letter()))
    }
}

impl std::str::FromStr for ChainShape {
    type Err = ShapeError;

    fn from_str(text: &str) -> Result<ChainShape, ShapeError> {
        let kinds = text
            .chars()
            .enumerate()
            .map(|(i, c)| match c {
                'R' => Ok(JointKind::Revolute),
                'P' => Ok(JointKind::Prismatic),
                letter => Err(ShapeError::Letter {
                    letter,
                    joint: i + 1,
                }),
            })
            .collect::<Result<Vec<JointKind>, ShapeError>>()?;
        ChainShape::new(kinds)
    }
}

/// How a joint's link is parameterised.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum JointModel {
    /// Standard Denavit–Hartenberg: `A = Rz(θ + q)·Tz(d)·Tx(a)·Rx(α)`.
    #[default]
    Dh,
    /// Hayati & Mirmirani (1985): `A = Rz(θ + q)·Tx(a)·Rx(α)·Ry(β)`, for a
    /// joint whose axis is (nearly) parallel to the previous one, where D-H's
    /// `d` is ill-determined. `d` is structurally 0 and the d-slot of the
    /// parameter vector holds `β` ([`ParamKind::Beta`]).
    ///
    /// A prismatic joint may be Hayati too: `A = Rz(θ)·Tz(q)·Tx(a)·Rx(α)·Ry(β)`.
    /// Its link's next axis is nearly parallel to the slide, so where along
    /// the slide the common normal sits — `d`'s offset, the reading's zero —
    /// is as ill-determined as a revolute joint's `d`; it is structurally 0,
    /// and the next link's `d` (or, at the end of the chain, the probe's z)
    /// carries it, exactly as for a revolute Hayati joint.
    Hayati,
}

impl JointModel {
    /// The name in arm files: `dh` or `hayati`.
    pub(crate) fn name(self) -> &'static str {
        match self {
            JointModel::Dh => "dh",
            JointModel::Hayati => "hayati",
        }
    }
}

/// One link of the chain: standard Denavit–Hartenberg,
/// `A = Rz(θ + q) · Tz(d) · Tx(a) · Rx(α)`, or with
/// [`JointModel::Hayati`] `A = Rz(θ + q) · Tx(a) · Rx(α) · Ry(β)`; for a
/// [`JointKind::Prismatic`] joint the reading `q` (mm) moves to `d`:
/// `Rz(θ) · Tz(d + q) · …` (Hayati: `Rz(θ) · Tz(q) · …`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DhJoint {
    /// Common-normal length `a`, mm.
    pub a: f64,
    /// Offset along the previous z axis `d`, mm.
    pub d: f64,
    /// Link twist `α` (the paper's β), rad.
    pub alpha: f64,
    /// Encoder zero offset `θ⁰`, rad: the joint angle is `q + θ`.
    pub theta: f64,
    /// Rotation about the link's y axis `β`, rad (Hayati joints; 0 and
    /// unused for a D-H joint, whose `d` is used instead).
    pub beta: f64,
    /// The link's parameterisation.
    pub model: JointModel,
    /// Whether the joint turns or slides.
    pub kind: JointKind,
}

impl DhJoint {
    /// A D-H joint (β = 0).
    ///
    /// ```
    /// use aacmm_core::params::{DhJoint, JointModel};
    /// let j = DhJoint::dh(10.0, 5.0, 0.0, 0.0);
    /// assert_eq!((j.d, j.model), (5.0, JointModel::Dh));
    /// ```
    pub fn dh(a: f64, d: f64, alpha: f64, theta: f64) -> DhJoint {
        DhJoint {
            a,
            d,
            alpha,
            theta,
            beta: 0.0,
            model: JointModel::Dh,
            kind: JointKind::Revolute,
        }
    }

    /// A revolute Hayati joint (d = 0).
    pub fn hayati(a: f64, alpha: f64, theta: f64, beta: f64) -> DhJoint {
        DhJoint {
            a,
            d: 0.0,
            alpha,
            theta,
            beta,
            model: JointModel::Hayati,
            kind: JointKind::Revolute,
        }
    }

    /// This joint with another kind (revolute or prismatic).
    ///
    /// ```
    /// use aacmm_core::params::{DhJoint, JointKind};
    /// let slide = DhJoint::dh(0.0, 100.0, 0.0, 0.0).with_kind(JointKind::Prismatic);
    /// assert_eq!((slide.d, slide.kind), (100.0, JointKind::Prismatic));
    /// ```
    pub fn with_kind(self, kind: JointKind) -> DhJoint {
        DhJoint { kind, ..self }
    }

    /// The joint's d-slot parameter kind: [`ParamKind::D`] or, for a Hayati
    /// joint, [`ParamKind::Beta`].
    pub(crate) fn slot_kind(&self) -> ParamKind {
        match self.model {
            JointModel::Dh => ParamKind::D,
            JointModel::Hayati => ParamKind::Beta,
        }
    }
}

/// The kind of a geometric parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ParamKind {
    /// Link length `a` (mm).
    A,
    /// Link offset `d` (mm).
    D,
    /// Link twist `α` (rad).
    Alpha,
    /// Encoder zero offset `θ` (rad).
    Theta,
    /// Probe offset component in the last frame (mm).
    Probe,
    /// Hayati rotation `β` about the link's y axis (rad): the d-slot of a
    /// [`JointModel::Hayati`] joint.
    Beta,
}

impl ParamKind {
    /// Whether the parameter is a length (mm) rather than an angle (rad).
    ///
    /// ```
    /// use aacmm_core::params::ParamKind;
    /// assert!(ParamKind::Probe.is_length());
    /// assert!(!ParamKind::Theta.is_length());
    /// ```
    pub fn is_length(self) -> bool {
        matches!(self, ParamKind::A | ParamKind::D | ParamKind::Probe)
    }

    /// Whether the parameter sits in a joint's d-slot (`d` or Hayati `β`).
    pub(crate) fn is_d_slot(self) -> bool {
        matches!(self, ParamKind::D | ParamKind::Beta)
    }
}

/// One parameter of an `n`-joint chain: its kind and its joint (0-based), or
/// the probe axis (0 = x, 1 = y, 2 = z) for [`ParamKind::Probe`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ParamId {
    /// What the parameter is.
    pub kind: ParamKind,
    /// Joint index (0-based), or probe axis.
    pub index: usize,
}

impl ParamId {
    /// The parameter's position in the fixed order for an `n`-joint chain.
    ///
    /// ```
    /// use aacmm_core::params::{ParamId, ParamKind};
    /// let bz = ParamId { kind: ParamKind::Probe, index: 2 };
    /// assert_eq!(bz.column(6), 26);
    /// let theta1 = ParamId { kind: ParamKind::Theta, index: 0 };
    /// assert_eq!(theta1.column(6), 18);
    /// ```
    pub fn column(self, n: usize) -> usize {
        let block = match self.kind {
            ParamKind::A => 0,
            ParamKind::D | ParamKind::Beta => 1,
            ParamKind::Alpha => 2,
            ParamKind::Theta => 3,
            ParamKind::Probe => 4,
        };
        block * n + self.index
    }

    /// The parameter at `column` of an `n`-joint D-H chain, if there is one
    /// (the d-slot is always [`ParamKind::D`] here; an arm with Hayati joints
    /// names its columns with [`DhParams::param_id`]).
    pub(crate) fn from_column(n: usize, column: usize) -> Option<ParamId> {
        // A chain without joints has no columns (and `column / 0` no value).
        let (kind, index) = match column.checked_div(n)? {
            0 => (ParamKind::A, column % n),
            1 => (ParamKind::D, column % n),
            2 => (ParamKind::Alpha, column % n),
            3 => (ParamKind::Theta, column % n),
            _ if column < param_count(n) => (ParamKind::Probe, column - 4 * n),
            _ => return None,
        };
        Some(ParamId { kind, index })
    }

    /// All parameters of an `n`-joint chain in the fixed order.
    ///
    /// ```
    /// use aacmm_core::params::ParamId;
    /// let names: Vec<String> = ParamId::all(6).map(|p| p.to_string()).collect();
    /// assert_eq!(names.len(), 27);
    /// assert_eq!(names[12], "alpha1");
    /// assert_eq!(names[26], "Bz");
    /// ```
    pub fn all(n: usize) -> impl Iterator<Item = ParamId> {
        (0..param_count(n)).filter_map(move |c| ParamId::from_column(n, c))
    }

    /// The parameter of an `n`-joint chain named `name` (`a1`, `alpha3`,
    /// `theta6`, `Bz`, `hbeta2`; `beta…` is accepted for `alpha…`, the
    /// paper's name). Whether a joint has a `d` or an `hbeta` depends on its
    /// model: [`DhParams::parse_param`] checks that.
    ///
    /// ```
    /// use aacmm_core::params::{ParamId, ParamKind};
    /// assert_eq!(ParamId::parse("beta2", 6), Some(ParamId { kind: ParamKind::Alpha, index: 1 }));
    /// assert_eq!(ParamId::parse("theta7", 6), None);
    /// ```
    pub fn parse(name: &str, n: usize) -> Option<ParamId> {
        name.parse::<ParamId>()
            .ok()
            .filter(|id| id.index < if id.kind == ParamKind::Probe { 3 } else { n })
    }

    /// The unit users see the parameter in: `mm` or `deg`.
    ///
    /// ```
    /// use aacmm_core::params::{ParamId, ParamKind};
    /// assert_eq!(ParamId { kind: ParamKind::Theta, index: 0 }.unit(), "deg");
    /// assert_eq!(ParamId { kind: ParamKind::Probe, index: 2 }.unit(), "mm");
    /// ```
    pub fn unit(self) -> &'static str {
        if self.kind.is_length() { "mm" } else { "deg" }
    }

    /// A value of this parameter (mm or rad) in user units (mm or deg).
    ///
    /// ```
    /// use aacmm_core::params::{ParamId, ParamKind};
    /// let alpha1 = ParamId { kind: ParamKind::Alpha, index: 0 };
    /// assert_eq!(alpha1.to_user(std::f64::consts::PI), 180.0);
    /// ```
    pub fn to_user(self, v: f64) -> f64 {
        if self.kind.is_length() {
            v
        } else {
            v.to_degrees()
        }
    }

    /// The inverse of [`ParamId::to_user`].
    ///
    /// ```
    /// use aacmm_core::params::{ParamId, ParamKind};
    /// let theta2 = ParamId { kind: ParamKind::Theta, index: 1 };
    /// assert_eq!(theta2.from_user(180.0), std::f64::consts::PI);
    /// ```
    pub fn from_user(self, v: f64) -> f64 {
        if self.kind.is_length() {
            v
        } else {
            v.to_radians()
        }
    }
}

/// Parameters appear in files by name (`a1`, `alpha3`, `Bz`).
impl serde::Serialize for ParamId {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> serde::Deserialize<'de> for ParamId {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<ParamId, D::Error> {
        let name = String::deserialize(d)?;
        name.parse().map_err(serde::de::Error::custom)
    }
}

impl std::str::FromStr for ParamId {
    type Err = String;

    /// A parameter by name, whatever the joint count (`a12` is the twelfth
    /// joint's `a`).
    ///
    /// ```
    /// use aacmm_core::params::{ParamId, ParamKind};
    /// let id: ParamId = "theta3".parse().unwrap();
    /// assert_eq!(id, ParamId { kind: ParamKind::Theta, index: 2 });
    /// assert!("q3".parse::<ParamId>().is_err());
    /// ```
    fn from_str(name: &str) -> Result<ParamId, String> {
        let probe = ["Bx", "By", "Bz"].iter().position(|b| *b == name);
        if let Some(index) = probe {
            return Ok(ParamId {
                kind: ParamKind::Probe,
                index,
            });
        }
        let kinds = [
            ("hbeta", ParamKind::Beta),
            ("alpha", ParamKind::Alpha),
            ("beta", ParamKind::Alpha),
            ("theta", ParamKind::Theta),
            ("a", ParamKind::A),
            ("d", ParamKind::D),
        ];
        for (prefix, kind) in kinds {
            if let Some(rest) = name.strip_prefix(prefix)
                && let Ok(i) = rest.parse::<usize>()
                && i >= 1
                && !rest.starts_with('0')
                && !rest.starts_with('+')
            {
                return Ok(ParamId { kind, index: i - 1 });
            }
        }
        Err(format!(
            "{} is not a parameter name",
            crate::error::quoted(name)
        ))
    }
}

impl fmt::Display for ParamId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let i = self.index + 1;
        match self.kind {
            ParamKind::A => write!(f, "a{i}"),
            ParamKind::D => write!(f, "d{i}"),
            ParamKind::Alpha => write!(f, "alpha{i}"),
            ParamKind::Theta => write!(f, "theta{i}"),
            ParamKind::Probe => write!(f, "B{}", ["x", "y", "z"][self.index]),
            ParamKind::Beta => write!(f, "hbeta{i}"),
        }
    }
}

/// Whether the toolkit computes a chain of `n` joints: 1 to [`MAX_JOINTS`].
/// File readers, the kernel and the front ends share this one rule; an arm
/// with another count is rejected where it is read, naming its file.
///
/// ```
/// use aacmm_core::params::supports_joints;
/// assert!(supports_joints(6) && supports_joints(1) && supports_joints(12));
/// assert!(!supports_joints(0) && !supports_joints(13));
/// ```
pub fn supports_joints(n: usize) -> bool {
    (1..=MAX_JOINTS).contains(&n)
}

/// The supported joint counts in words, for messages.
///
/// ```
/// assert_eq!(aacmm_core::params::supported_joints_text(), "chains of 1 to 12 joints");
/// ```
pub fn supported_joints_text() -> String {
    format!("chains of 1 to {MAX_JOINTS} joints")
}

/// Number of geometric parameters of an `n`-joint chain with a probe offset.
///
/// ```
/// assert_eq!(aacmm_core::params::param_count(6), 27);
/// assert_eq!(aacmm_core::params::param_count(7), 31);
/// ```
pub fn param_count(n: usize) -> usize {
    // Saturating: no chain has that many joints, and a count from hostile
    // input must not wrap to a small one.
    n.saturating_mul(4).saturating_add(3)
}

/// The geometry of a D-H chain: its joints (base to probe) and the probe
/// centre in the last frame (mm). The default has no joints.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DhParams {
    /// Links, base to probe.
    pub joints: Vec<DhJoint>,
    /// Probe centre in the last link's frame, mm.
    pub probe: [f64; 3],
}

impl DhParams {
    /// The paper's nominal 6-joint arm (Table 1 of method.md): twists ∓90°,
    /// probe 100 mm along the last z axis.
    ///
    /// ```
    /// let arm = aacmm_core::params::DhParams::paper_nominal();
    /// assert_eq!(arm.joints[0].d, 375.0);
    /// assert_eq!(arm.probe, [0.0, 0.0, 100.0]);
    /// ```
    pub fn paper_nominal() -> DhParams {
        let h = std::f64::consts::FRAC_PI_2;
        let rows = [
            (-h, 50.0, 375.0),
            (h, -55.0, 0.0),
            (-h, 35.0, 250.0),
            (h, -35.0, 0.0),
            (-h, 35.0, 270.0),
            (h, -35.0, 0.0),
        ];
        DhParams {
            joints: rows
                .iter()
                .map(|&(alpha, a, d)| DhJoint::dh(a, d, alpha, 0.0))
                .collect(),
            probe: [0.0, 0.0, 100.0],
        }
    }

    /// Number of joints.
    pub fn joint_count(&self) -> usize {
        self.joints.len()
    }

    /// Number of parameters, `4n + 3`.
    pub fn param_count(&self) -> usize {
        param_count(self.joints.len())
    }

    /// The chain's shape; an error for no joints or more than
    /// [`MAX_JOINTS`].
    pub fn shape(&self) -> Result<ChainShape, ShapeError> {
        ChainShape::new(self.joints.iter().map(|j| j.kind))
    }

    /// Whether any joint is prismatic.
    pub fn has_prismatic(&self) -> bool {
        self.joints.iter().any(|j| j.kind == JointKind::Prismatic)
    }

    /// The value of one parameter (mm or rad).
    ///
    /// ```
    /// use aacmm_core::params::{DhParams, ParamId, ParamKind};
    /// let arm = DhParams::paper_nominal();
    /// assert_eq!(arm.get(ParamId { kind: ParamKind::A, index: 1 }), -55.0);
    /// ```
    pub fn get(&self, id: ParamId) -> f64 {
        match id.kind {
            ParamKind::A => self.joints[id.index].a,
            ParamKind::D => self.joints[id.index].d,
            ParamKind::Alpha => self.joints[id.index].alpha,
            ParamKind::Theta => self.joints[id.index].theta,
            ParamKind::Probe => self.probe[id.index],
            ParamKind::Beta => self.joints[id.index].beta,
        }
    }

    /// A mutable reference to one parameter.
    pub fn get_mut(&mut self, id: ParamId) -> &mut f64 {
        match id.kind {
            ParamKind::A => &mut self.joints[id.index].a,
            ParamKind::D => &mut self.joints[id.index].d,
            ParamKind::Alpha => &mut self.joints[id.index].alpha,
            ParamKind::Theta => &mut self.joints[id.index].theta,
            ParamKind::Probe => &mut self.probe[id.index],
            ParamKind::Beta => &mut self.joints[id.index].beta,
        }
    }

    /// The parameter at `column` of this arm: `ParamId::from_column` with
    /// a Hayati joint's d-slot named [`ParamKind::Beta`].
    pub fn param_id(&self, column: usize) -> Option<ParamId> {
        let id = ParamId::from_column(self.joint_count(), column)?;
        Some(match id.kind {
            ParamKind::D => ParamId {
                kind: self.joints[id.index].slot_kind(),
                index: id.index,
            },
            _ => id,
        })
    }

    /// This arm's parameters in the fixed order (see [`DhParams::param_id`]).
    pub fn param_ids(&self) -> impl Iterator<Item = ParamId> + '_ {
        (0..self.param_count()).filter_map(|c| self.param_id(c))
    }

    /// Whether `id` is a parameter of this arm: in range, and `d…`/`hbeta…`
    /// only for a joint of that model.
    pub(crate) fn has_param(&self, id: ParamId) -> bool {
        let n = self.joint_count();
        match id.kind {
            ParamKind::Probe => id.index < 3,
            ParamKind::D | ParamKind::Beta => {
                id.index < n && self.joints[id.index].slot_kind() == id.kind
            }
            _ => id.index < n,
        }
    }

    /// The parameter of this arm named `name` (see [`ParamId::parse`]); a
    /// `d…` of a Hayati joint or an `hbeta…` of a D-H joint is `None`.
    pub fn parse_param(&self, name: &str) -> Option<ParamId> {
        name.parse::<ParamId>()
            .ok()
            .filter(|&id| self.has_param(id))
    }

    /// The models of the joints, base to probe.
    pub fn models(&self) -> Vec<JointModel> {
        self.joints.iter().map(|j| j.model).collect()
    }

    /// This arm with its parameters set from `v` (the fixed order, as
    /// [`DhParams::to_vec`] gives): the joints keep their models and kinds. `None`
    /// unless `v` has [`DhParams::param_count`] values.
    ///
    /// ```
    /// use aacmm_core::params::{DhParams, JointModel};
    /// let mut arm = DhParams::paper_nominal();
    /// arm.joints[1].model = JointModel::Hayati;
    /// arm.joints[1].beta = 0.01;
    /// assert_eq!(arm.with_values(&arm.to_vec()), Some(arm.clone()));
    /// assert_eq!(arm.to_vec()[7], 0.01); // the d-slot holds β
    /// ```
    pub fn with_values(&self, v: &[f64]) -> Option<DhParams> {
        if v.len() != self.param_count() {
            return None;
        }
        let mut p = self.clone();
        for (c, &x) in v.iter().enumerate() {
            let id = self.param_id(c)?;
            *p.get_mut(id) = x;
        }
        Some(p)
    }

    /// The arm's reach, a length scale for its parameters: `Σ|a| + Σ|d| +
    /// |B|`, mm (at least 1).
    ///
    /// ```
    /// let arm = aacmm_core::params::DhParams::paper_nominal();
    /// assert_eq!(arm.reach(), 50.0 + 55.0 + 35.0 * 4.0 + 375.0 + 250.0 + 270.0 + 100.0);
    /// ```
    pub fn reach(&self) -> f64 {
        // A Hayati joint's d is 0 (its `d` field is unused).
        let links: f64 = self
            .joints
            .iter()
            .map(|j| {
                j.a.abs()
                    + if j.model == JointModel::Dh {
                        j.d.abs()
                    } else {
                        0.0
                    }
            })
            .sum();
        let b = self.probe.iter().map(|v| v * v).sum::<f64>().sqrt();
        (links + b).max(1.0)
    }

    /// The explicit conversion to the flat vector in the fixed order.
    ///
    /// ```
    /// let v = aacmm_core::params::DhParams::paper_nominal().to_vec();
    /// assert_eq!(v.len(), 27);
    /// assert_eq!(v[6], 375.0); // d1
    /// ```
    pub fn to_vec(&self) -> Vec<f64> {
        self.param_ids().map(|id| self.get(id)).collect()
    }

    /// An arm from named values: each value goes to the parameter it
    /// names, and a joint named with an `hbeta…` is a Hayati joint (its `d`
    /// structurally 0). `None` unless the names are exactly the `4n + 3` of
    /// an `n`-joint arm, each once.
    pub fn from_named(values: impl IntoIterator<Item = (ParamId, f64)>) -> Option<DhParams> {
        let values: Vec<(ParamId, f64)> = values.into_iter().collect();
        let n = values.len().checked_sub(3)? / 4;
        if n == 0 || values.len() != param_count(n) {
            return None;
        }
        let mut p = DhParams {
            joints: vec![DhJoint::default(); n],
            probe: [0.0; 3],
        };
        for (id, _) in &values {
            if id.kind == ParamKind::Beta {
                p.joints.get_mut(id.index)?.model = JointModel::Hayati;
            }
        }
        let mut seen = vec![false; values.len()];
        for &(id, v) in &values {
            if !p.has_param(id) {
                return None;
            }
            let c = id.column(n);
            if std::mem::replace(&mut seen[c], true) {
                return None;
            }
            *p.get_mut(id) = v;
        }
        Some(p)
    }

    /// The inverse of [`DhParams::to_vec`] for a D-H arm (every joint
    /// [`JointModel::Dh`]; [`DhParams::with_values`] keeps an arm's models);
    /// `None` unless `v.len() == 4n + 3` for some `n ≥ 1`.
    ///
    /// ```
    /// use aacmm_core::params::DhParams;
    /// let arm = DhParams::paper_nominal();
    /// assert_eq!(DhParams::from_slice(&arm.to_vec()), Some(arm));
    /// assert_eq!(DhParams::from_slice(&[0.0; 5]), None);
    /// ```
    pub fn from_slice(v: &[f64]) -> Option<DhParams> {
        if v.len() < 7 || !(v.len() - 3).is_multiple_of(4) {
            return None;
        }
        let n = (v.len() - 3) / 4;
        let mut p = DhParams {
            joints: vec![DhJoint::default(); n],
            probe: [0.0; 3],
        };
        for (id, &x) in ParamId::all(n).zip(v) {
            *p.get_mut(id) = x;
        }
        Some(p)
    }
}

/// `x` wrapped to `[-π, π)`: zero offsets are angles on a circle.
///
/// ```
/// use aacmm_core::params::wrap;
/// assert!((wrap(3.0 * std::f64::consts::PI) + std::f64::consts::PI).abs() < 1e-12);
/// assert_eq!(wrap(0.5), 0.5);
/// ```
pub fn wrap(x: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    if (-PI..PI).contains(&x) {
        x
    } else {
        (x + PI).rem_euclid(TAU) - PI
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn params_paramid_from_column() {
        use crate::params::ParamId;
        assert_eq!(ParamId::from_column(6, 7).unwrap().to_string(), "d2");
        assert!(ParamId::from_column(6, 27).is_none());
        assert!(ParamId::from_column(0, 0).is_none());
    }

    #[test]
    fn params_dhparams_param_id() {
        use crate::params::{DhParams, JointModel};
        let mut arm = DhParams::paper_nominal();
        arm.joints[2].model = JointModel::Hayati;
        assert_eq!(arm.param_id(8).unwrap().to_string(), "hbeta3");
        assert_eq!(arm.param_id(7).unwrap().to_string(), "d2");
    }

    #[test]
    fn params_dhparams_from_named() {
        use crate::params::{DhParams, JointModel};
        let mut arm = DhParams::paper_nominal();
        arm.joints[1].model = JointModel::Hayati;
        arm.joints[1].beta = 0.01;
        arm.joints[1].d = 0.0;
        let named = arm.param_ids().map(|id| (id, arm.get(id)));
        assert_eq!(DhParams::from_named(named), Some(arm));
    }
}
