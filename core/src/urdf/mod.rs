//! A nominal D-H arm from a URDF robot description.
//!
//! Robot makers publish their kinematics as URDF: a tree of links joined by
//! joints, each joint placed in its parent link's frame by an `origin`
//! (`xyz` in metres, `rpy` in radians, `R = Rz(yaw)·Ry(pitch)·Rx(roll)`) and
//! turning about its `axis`. This module reads the subset that describes a
//! serial chain — `revolute`, `continuous` (a revolute joint without
//! limits) and `prismatic` joints, `fixed` joints (flanges, tools, the probe
//! ball, folded into their neighbours), their origins, axes and limits —
//! follows the chain from a root link to a tip link (the probe centre), and
//! converts it to the toolkit's standard D-H arm (`A_i = Rz(θ_i + q_i)·
//! Tz(d_i)·Tx(a_i)·Rx(α_i)`; a prismatic joint's reading, mm, adds to `d_i`;
//! probe `B` in the last frame; see [`crate::params`]). A URDF reading is in
//! radians or metres, the arm's in radians or millimetres: a prismatic
//! joint's `q` is its URDF reading × 1000, its limits likewise.
//!
//! The conversion is exact: with the same joint readings `q`, the D-H arm's
//! probe and the URDF's tip agree up to one fixed rigid motion, the
//! [`DhConversion::base`] (the D-H base frame must have its z axis on the
//! first joint axis; the URDF root frame need not); the arm's tool frame
//! (its last D-H frame) and the tip link's frame differ by one fixed
//! rotation, [`DhConversion::tool`]. Calibration figures —
//! the spread of a socket's touches, distances between sockets — do not
//! depend on that rigid motion, so the arm file needs only the D-H part.
//!
//! Conventions of the conversion, so that the same URDF always gives the same
//! arm: frame 0 has its origin at the point of the first axis nearest the
//! root origin and its x axis along the root x axis made perpendicular to the
//! first axis; where two consecutive axes are parallel, the common normal is
//! taken through the previous frame's origin (`d = 0`, the textbook choice);
//! where they are nearly parallel, so that their common normal is more than
//! [`HAYATI_BEYOND_M`] away and D-H would need a `d` of that size (unbounded
//! as the axes become parallel), the joint gets the Hayati convention
//! (`Rz(θ + q)·Tx(a)·Rx(α)·Ry(β)`, [`crate::params::JointModel::Hayati`]):
//! its next frame's origin is where the next axis crosses the plane normal
//! to this one through the previous origin; a prismatic joint's axis is the
//! line through its URDF joint origin (any parallel line would do: only its
//! direction moves the tool); the last joint has `a = d = α = θ = 0`, so the
//! probe vector is the tip in the frame of the last axis at `q_n = 0`.
//!
//! Published URDFs often round right angles (`1.5708` for π/2, `3.1416` for
//! π). Taken literally, two axes meant to be parallel become skew by 10⁻⁵ rad
//! and meet kilometres away: the conversion stays exact (a Hayati joint with
//! `β` of 10⁻⁵ rad), but the arm is not the one its maker meant.
//! [`UrdfOptions::snap_rad`] rounds every `rpy` component within that
//! distance of a multiple of π/2 to it and reports each rounding
//! ([`Urdf::snapped`]).
//!
//! Masses: each `<link>`'s `<inertial>` (`<mass value>`, kg, and the centre
//! of mass at its `<origin xyz>`, m, in the link frame) is carried by the
//! chain part it moves with ([`Chain::masses`], [`Carrier`]): the link after
//! joint `j` is the child link of joint `j` with every link fixed to it (off
//! the chain too: a flange, a finger on a `fixed` joint); after the last
//! joint, its child link is the last link's and the rest is the tool's (the
//! probe's). [`Chain::to_dh`] sums each part's masses and puts their centre
//! in that link's D-H frame ([`DhConversion::masses`]: what an arm file's
//! `mass_kg` and `com_mm` state, `crate::corrections::Physics`; this module
//! sits below it and does not use it). Links before the
//! first joint load no joint and are left out; a link behind a joint off the
//! chain that moves (a gripper's prismatic finger) is taken at that joint's
//! zero. Gravity is the URDF root's −z (ROS's convention, REP 103).

pub mod export;

use std::collections::HashMap;

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};

use crate::error::{InputError, quoted, shown};
use crate::params::{DhJoint, DhParams, JointModel, MAX_JOINTS};

/// How [`parse_urdf`] reads angles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UrdfOptions {
    /// `rpy` components within this many radians of a multiple of π/2 are
    /// set to it; `0` keeps every value as written.
    pub snap_rad: f64,
}

impl Default for UrdfOptions {
    /// Rounds within 10⁻⁴ rad: `1.5708` and `3.1416` (off by 4·10⁻⁶ and
    /// 7·10⁻⁶) are snapped, deliberate small angles of a calibrated URDF
    /// (10⁻³ rad and up) are not.
    fn default() -> Self {
        UrdfOptions { snap_rad: 1e-4 }
    }
}

/// The kind of a URDF joint, as far as a serial arm needs it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointKind {
    /// Turns about its axis (`revolute` or `continuous`).
    Revolute,
    /// Slides along its axis (`prismatic`).
    Prismatic,
    /// Rigid (`fixed`).
    Fixed,
    /// Anything else (`floating`, `planar`): readable, but not part of a
    /// chain this toolkit models.
    Other,
}

impl JointKind {
    /// The arm's kind of a movable joint; `None` for a fixed or other one.
    pub fn movable(self) -> Option<crate::params::JointKind> {
        match self {
            JointKind::Revolute => Some(crate::params::JointKind::Revolute),
            JointKind::Prismatic => Some(crate::params::JointKind::Prismatic),
            JointKind::Fixed | JointKind::Other => None,
        }
    }
}

/// One joint of a URDF file.
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfJoint {
    /// The joint's name.
    pub name: String,
    /// The `type` attribute as written.
    pub(crate) type_name: String,
    /// What the type means here.
    pub kind: JointKind,
    /// Parent link.
    pub parent: String,
    /// Child link.
    pub child: String,
    /// The child frame in the parent frame (metres), after snapping.
    pub origin: Isometry3<f64>,
    /// Unit axis in the child frame.
    pub axis: Vector3<f64>,
    /// `[lower, upper]` of a `revolute` (rad) or `prismatic` (m) joint,
    /// when its `<limit>` states them and `lower < upper`.
    pub limits: Option<[f64; 2]>,
    /// 1-based line of the `<joint>` element.
    pub(crate) line: usize,
}

/// A link's `<inertial>`: its mass and where its centre is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Inertial {
    /// `<mass value>`, kg (finite, ≥ 0).
    pub(crate) kg: f64,
    /// The centre of mass in the link frame (`<origin xyz>`), metres.
    pub(crate) com: Vector3<f64>,
}

/// One `<link>` element of a URDF file.
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfLink {
    /// The link's name.
    pub name: String,
    /// Its mass, when it has an `<inertial>`.
    pub(crate) inertial: Option<Inertial>,
    /// 1-based line of the `<link>` element.
    pub line: usize,
}

/// A parsed URDF: its joints and links, in file order.
#[derive(Clone, Debug, PartialEq)]
pub struct Urdf {
    /// The file name used in messages.
    pub(crate) file: String,
    /// The robot's `name` attribute.
    pub name: String,
    /// Every joint.
    pub joints: Vec<UrdfJoint>,
    /// Every `<link>` element (a link named only by joints has none).
    pub links: Vec<UrdfLink>,
    /// One note per `rpy` component [`UrdfOptions::snap_rad`] rounded:
    /// `line 12: joint_3 roll -3.1416 → -π (7.3e-6 rad)`.
    pub snapped: Vec<String>,
}

/// Parses the joints and links of a URDF; `file` names it in messages.
///
/// # Errors
/// Malformed XML (at its line); a root element other than `<robot>`; a joint
/// without a name, type, parent or child; an `xyz`, `rpy` or `axis` that is
/// not three finite numbers; a zero axis; a link that is the child of two
/// joints; a `<link>` without a name or defined twice; an `<inertial>`
/// without `<mass>`, or whose `value` is not a finite number ≥ 0.
///
/// ```
/// use aacmm_core::urdf::{parse_urdf, UrdfOptions};
/// let text = r#"<robot name="r">
///   <joint name="j1" type="revolute">
///     <parent link="base"/><child link="l1"/>
///     <origin xyz="0 0 0.1" rpy="0 0 0"/><axis xyz="0 0 1"/>
///   </joint>
///   <joint name="j2" type="revolute">
///     <parent link="l1"/><child link="l2"/>
///     <origin xyz="0 0 0.2" rpy="1.5708 0 0"/><axis xyz="0 0 1"/>
///   </joint>
/// </robot>"#;
/// let urdf = parse_urdf(text, "r.urdf", UrdfOptions::default()).unwrap();
/// assert_eq!(urdf.joints.len(), 2);
/// assert_eq!(urdf.snapped.len(), 1); // 1.5708 → π/2
/// let bad = text.replace("0 0 0.2", "0 0 x");
/// let e = parse_urdf(&bad, "r.urdf", UrdfOptions::default()).unwrap_err();
/// assert!(e.to_string().starts_with("r.urdf:8: field `xyz`"), "{e}");
/// ```
pub fn parse_urdf(text: &str, file: &str, options: UrdfOptions) -> Result<Urdf, InputError> {
    let doc = roxmltree::Document::parse(text).map_err(|e| {
        InputError::line_error(
            file,
            e.pos().row as usize,
            // The parser's message quotes names from the file: bounded.
            format!("not well-formed XML: {}", shown(&e.to_string())),
        )
    })?;
    let root = robot_element(&doc, file)?;
    let mut urdf = Urdf {
        file: file.to_string(),
        name: root.attribute("name").unwrap_or_default().to_string(),
        joints: Vec::new(),
        links: Vec::new(),
        snapped: Vec::new(),
    };
    for node in root.children().filter(|n| n.has_tag_name("link")) {
        let link = read_link(&doc, node, file)?;
        if let Some(other) = urdf.links.iter().find(|l| l.name == link.name) {
            return Err(InputError::field(
                file,
                link.line,
                "name",
                format!(
                    "link {} is already defined (line {}); a URDF names each link once",
                    quoted(&link.name),
                    other.line
                ),
            ));
        }
        urdf.links.push(link);
    }
    let mut child_of: HashMap<String, usize> = HashMap::new();
    for node in root.children().filter(|n| n.has_tag_name("joint")) {
        let element = JointElement {
            doc: &doc,
            node,
            file,
            at: line(&doc, node),
        };
        let joint = element.read(options, &mut urdf.snapped)?;
        if let Some(&other) = child_of.get(&joint.child) {
            return Err(InputError::field(
                file,
                joint.line,
                "child",
                format!(
                    "link {} is already the child of joint {} (line {}); a URDF is a tree",
                    quoted(&joint.child),
                    quoted(&urdf.joints[other].name),
                    urdf.joints[other].line
                ),
            ));
        }
        child_of.insert(joint.child.clone(), urdf.joints.len());
        urdf.joints.push(joint);
    }
    Ok(urdf)
}

/// The document's root element, which must be `<robot>`.
fn robot_element<'a, 'input>(
    doc: &'a roxmltree::Document<'input>,
    file: &str,
) -> Result<roxmltree::Node<'a, 'input>, InputError> {
    let root = doc.root_element();
    if root.tag_name().name() != "robot" {
        return Err(InputError::line_error(
            file,
            line(doc, root),
            format!(
                "the root element is <{}>; a URDF has <robot>",
                shown(root.tag_name().name())
            ),
        ));
    }
    Ok(root)
}

/// A `<link>` element: its name and its `<inertial>`'s mass and centre
/// (the inertia tensor is not needed and not read).
fn read_link(
    doc: &roxmltree::Document,
    node: roxmltree::Node,
    file: &str,
) -> Result<UrdfLink, InputError> {
    let at = line(doc, node);
    let name = node
        .attribute("name")
        .map(str::to_string)
        .ok_or_else(|| InputError::field(file, at, "name", "missing on <link>"))?;
    let Some(el) = node.children().find(|c| c.has_tag_name("inertial")) else {
        return Ok(UrdfLink {
            name,
            inertial: None,
            line: at,
        });
    };
    let inertial_at = line(doc, el);
    let com = match el.children().find(|c| c.has_tag_name("origin")) {
        Some(o) => {
            let l = line(doc, o);
            // The rpy turns the inertia tensor only; read to refuse a
            // malformed one.
            triple(o.attribute("rpy"), [0.0; 3], file, l, "rpy")?;
            triple(o.attribute("xyz"), [0.0; 3], file, l, "xyz")?
        }
        None => [0.0; 3],
    };
    let mass = el
        .children()
        .find(|c| c.has_tag_name("mass"))
        .ok_or_else(|| {
            InputError::field(
                file,
                inertial_at,
                "mass",
                format!("link {}: <inertial> without <mass>", quoted(&name)),
            )
        })?;
    let mass_at = line(doc, mass);
    let text = mass.attribute("value").ok_or_else(|| {
        InputError::field(
            file,
            mass_at,
            "mass",
            format!("link {}: <mass> without `value`", quoted(&name)),
        )
    })?;
    let kg = match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => v,
        _ => {
            return Err(InputError::field(
                file,
                mass_at,
                "mass",
                format!(
                    "link {}: {} is not a mass (a finite number of kg, ≥ 0)",
                    quoted(&name),
                    quoted(text)
                ),
            ));
        }
    };
    Ok(UrdfLink {
        name,
        inertial: Some(Inertial {
            kg,
            com: Vector3::from(com),
        }),
        line: at,
    })
}

/// A `<joint>` element being read, and where it is, for messages.
struct JointElement<'a, 'input> {
    doc: &'a roxmltree::Document<'input>,
    node: roxmltree::Node<'a, 'input>,
    file: &'a str,
    /// The line of `<joint>`.
    at: usize,
}

impl<'a, 'input> JointElement<'a, 'input> {
    /// The joint, its `rpy` snapped by `options` (each rounding noted in
    /// `snapped`).
    fn read(
        &self,
        options: UrdfOptions,
        snapped: &mut Vec<String>,
    ) -> Result<UrdfJoint, InputError> {
        let name = self.attribute("name")?;
        let type_name = self.attribute("type")?;
        let kind = match type_name.as_str() {
            "revolute" | "continuous" => JointKind::Revolute,
            "prismatic" => JointKind::Prismatic,
            "fixed" => JointKind::Fixed,
            _ => JointKind::Other,
        };
        let parent = self.link(&name, "parent")?;
        let child = self.link(&name, "child")?;
        let origin = self.origin(&name, options.snap_rad, snapped)?;
        let axis = self.axis(&name, kind)?;
        Ok(UrdfJoint {
            limits: self.limits(&name, &type_name)?,
            name,
            type_name,
            kind,
            parent,
            child,
            origin,
            axis,
            line: self.at,
        })
    }

    fn attribute(&self, attribute: &str) -> Result<String, InputError> {
        self.node
            .attribute(attribute)
            .map(str::to_string)
            .ok_or_else(|| InputError::field(self.file, self.at, attribute, "missing on <joint>"))
    }

    fn child(&self, tag: &str) -> Option<roxmltree::Node<'a, 'input>> {
        self.node.children().find(|c| c.has_tag_name(tag))
    }

    /// The `link` of the `<parent>` or `<child>` element (`tag`) of the
    /// joint `name`.
    fn link(&self, name: &str, tag: &str) -> Result<String, InputError> {
        let el = self.child(tag).ok_or_else(|| {
            InputError::field(
                self.file,
                self.at,
                tag,
                format!("joint {} has no <{tag}>", quoted(name)),
            )
        })?;
        el.attribute("link").map(str::to_string).ok_or_else(|| {
            InputError::field(
                self.file,
                line(self.doc, el),
                "link",
                format!("<{tag}> without `link`"),
            )
        })
    }

    /// The child frame in the parent frame, its `rpy` within `snap_rad`
    /// of a multiple of π/2 set to it (each rounding noted in `snapped`).
    fn origin(
        &self,
        name: &str,
        snap_rad: f64,
        snapped: &mut Vec<String>,
    ) -> Result<Isometry3<f64>, InputError> {
        let origin_el = self.child("origin");
        let (xyz, rpy) = match origin_el {
            Some(el) => {
                let l = line(self.doc, el);
                (
                    triple(el.attribute("xyz"), [0.0; 3], self.file, l, "xyz")?,
                    triple(el.attribute("rpy"), [0.0; 3], self.file, l, "rpy")?,
                )
            }
            None => ([0.0; 3], [0.0; 3]),
        };
        let rpy = snap(rpy, snap_rad, |i, from, to, by| {
            snapped.push(format!(
                "line {}: {} {} {from} → {to} ({by:.1e} rad)",
                origin_el.map_or(self.at, |el| line(self.doc, el)),
                shown(name),
                ["roll", "pitch", "yaw"][i]
            ));
        });
        Ok(Isometry3::from_parts(
            Translation3::from(Vector3::from(xyz)),
            UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
        ))
    }

    /// The unit axis (URDF's default is x); a movable joint's must not be
    /// zero.
    fn axis(&self, name: &str, kind: JointKind) -> Result<Vector3<f64>, InputError> {
        let axis_el = self.child("axis");
        let axis = match axis_el {
            Some(el) => triple(
                el.attribute("xyz"),
                [1.0, 0.0, 0.0],
                self.file,
                line(self.doc, el),
                "axis",
            )?,
            None => [1.0, 0.0, 0.0],
        };
        let axis = Vector3::from(axis);
        if kind.movable().is_some() && axis.norm() == 0.0 {
            let moves = match kind {
                JointKind::Prismatic => "slides along",
                _ => "turns about",
            };
            return Err(InputError::field(
                self.file,
                axis_el.map_or(self.at, |el| line(self.doc, el)),
                "axis",
                format!("joint {} {moves} a zero axis", quoted(name)),
            ));
        }
        Ok(if axis.norm() > 0.0 {
            axis.normalize()
        } else {
            axis
        })
    }

    /// `[lower, upper]` of a `revolute` or `prismatic` joint, when both are
    /// stated and `lower < upper` (URDF's default for either is 0, so a
    /// `<limit>` without them, or with both 0, states no range).
    ///
    /// # Errors
    /// A stated `lower` or `upper` that is not a finite number, or a
    /// `lower` above `upper`.
    fn limits(&self, name: &str, type_name: &str) -> Result<Option<[f64; 2]>, InputError> {
        let Some(el) = self.child("limit") else {
            return Ok(None);
        };
        let at = line(self.doc, el);
        let bound = |field: &str| -> Result<Option<f64>, InputError> {
            let Some(text) = el.attribute(field) else {
                return Ok(None);
            };
            match text.trim().parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(Some(v)),
                _ => Err(InputError::field(
                    self.file,
                    at,
                    field,
                    format!(
                        "joint {}: {} is not a limit (a finite number, {})",
                        quoted(name),
                        quoted(text),
                        if type_name == "prismatic" { "m" } else { "rad" }
                    ),
                )),
            }
        };
        let (lo, hi) = (bound("lower")?, bound("upper")?);
        if !matches!(type_name, "revolute" | "prismatic") {
            return Ok(None);
        }
        match (lo, hi) {
            (Some(lo), Some(hi)) if lo > hi => Err(InputError::field(
                self.file,
                at,
                "upper",
                format!("joint {}: upper {hi} is below lower {lo}", quoted(name)),
            )),
            (Some(lo), Some(hi)) if lo < hi => Ok(Some([lo, hi])),
            _ => Ok(None),
        }
    }
}

fn line(doc: &roxmltree::Document, node: roxmltree::Node) -> usize {
    doc.text_pos_at(node.range().start).row as usize
}

/// Three whitespace-separated finite numbers, or `default` when absent.
fn triple(
    value: Option<&str>,
    default: [f64; 3],
    file: &str,
    line: usize,
    field: &str,
) -> Result<[f64; 3], InputError> {
    let Some(text) = value else {
        return Ok(default);
    };
    let parsed: Vec<Option<f64>> = text
        .split_whitespace()
        .map(|t| t.parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect();
    match parsed.as_slice() {
        [Some(a), Some(b), Some(c)] => Ok([*a, *b, *c]),
        _ => Err(InputError::field(
            file,
            line,
            field,
            format!("{} is not three finite numbers", quoted(text)),
        )),
    }
}

/// Rounds components within `tol` of a multiple of π/2; `note(i, from, to,
/// by)` for each one changed.
fn snap(v: [f64; 3], tol: f64, mut note: impl FnMut(usize, f64, String, f64)) -> [f64; 3] {
    let h = std::f64::consts::FRAC_PI_2;
    let mut out = v;
    for (i, x) in v.iter().enumerate() {
        let k = (x / h).round();
        let to = k * h;
        let by = (x - to).abs();
        if by > 0.0 && by <= tol {
            out[i] = to;
            let name = match k as i64 {
                0 => "0".to_string(),
                1 => "π/2".to_string(),
                -1 => "-π/2".to_string(),
                2 => "π".to_string(),
                -2 => "-π".to_string(),
                k if k % 2 == 0 => format!("{}π", k / 2),
                k => format!("{k}π/2"),
            };
            note(i, *x, name, by);
        }
    }
    out
}

/// One step of a chain, root to tip.
#[derive(Clone, Debug, PartialEq)]
enum Step {
    /// A rigid transform (a fixed joint's origin, or a revolute joint's
    /// origin before its rotation).
    Rigid(Isometry3<f64>),
    /// A rotation by the next reading about this unit axis.
    Turn(Vector3<f64>),
    /// A translation by the next reading (m) along this unit axis.
    Slide(Vector3<f64>),
}

/// The serial chain from a root link to a tip link.
#[derive(Clone, Debug, PartialEq)]
pub struct Chain {
    /// The movable joints, root to tip: the columns `q1..qn` of a poses file.
    pub joints: Vec<String>,
    /// Whether each turns or slides.
    pub kinds: Vec<crate::params::JointKind>,
    /// Each one's `type` as written (`revolute`, `continuous`, `prismatic`).
    pub types: Vec<String>,
    /// Each one's line in the file.
    pub lines: Vec<usize>,
    /// Their `[lower, upper]` limits, rad or m, where the URDF states them.
    pub limits: Vec<Option<[f64; 2]>>,
    /// The `fixed` joints folded into the arm: entry `k < n` those just
    /// before movable joint `k` (entry 0: into the base, the others: into
    /// the link of joint `k − 1`), entry `n` those after the last one (into
    /// the tool).
    pub folded: Vec<Vec<String>>,
    steps: Vec<Step>,
    /// The URDF file's name, for messages.
    file: String,
    /// The masses of the links that move with the chain (or sit on its
    /// root side), in the file's order of `<link>` elements.
    pub masses: Vec<ChainMass>,
}

/// The part of a chain a link moves with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Carrier {
    /// The root side, before the first joint: it loads no joint.
    Base,
    /// The link after joint `j` (0-based): that joint's child link and
    /// every link fixed to it (for the last joint, its child link only).
    Link(usize),
    /// The tool: what is fixed after the last joint, but for that joint's
    /// child link.
    Tool,
}

/// A link's mass as a chain carries it.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainMass {
    /// The link.
    pub link: String,
    /// What it moves with.
    pub carrier: Carrier,
    /// Its mass, kg.
    pub kg: f64,
    /// Its centre of mass in the root frame with every reading zero, m.
    pub com: Point3<f64>,
    /// The joints off the chain between it and the chain that are not
    /// `fixed` (each taken at its zero), nearest the link first.
    pub moving: Vec<String>,
}

impl Urdf {
    /// Whether a joint names `link` as its parent or child.
    fn joins(&self, link: &str) -> bool {
        self.joints
            .iter()
            .any(|j| j.child == link || j.parent == link)
    }

    /// The chain from `root` (or, without one, the link that is no joint's
    /// child above `tip`) down to `tip`.
    ///
    /// # Errors
    /// An unknown tip or root link; a root not above the tip (both named,
    /// and where going up from the tip ends); a joint on the way that is
    /// neither revolute, continuous, prismatic nor fixed (named, with its
    /// line).
    pub fn chain(&self, root: Option<&str>, tip: &str) -> Result<Chain, InputError> {
        for (link, what) in [(Some(tip), "tip"), (root, "base")] {
            match link {
                Some(link) if !self.joins(link) => {
                    return Err(InputError::file_error(
                        &self.file,
                        format!(
                            "no link {} is joined to the robot (the {what} must be a link's name)",
                            quoted(link)
                        ),
                    ));
                }
                _ => {}
            }
        }
        let path = self.path_up(root, tip)?;
        let mut chain = Chain {
            joints: Vec::new(),
            kinds: Vec::new(),
            types: Vec::new(),
            lines: Vec::new(),
            limits: Vec::new(),
            folded: vec![Vec::new()],
            steps: Vec::new(),
            file: self.file.clone(),
            masses: self.masses_along(&path),
        };
        for j in path {
            chain.steps.push(Step::Rigid(j.origin));
            let Some(kind) = j.kind.movable() else {
                if j.kind == JointKind::Fixed {
                    chain
                        .folded
                        .last_mut()
                        .expect("one entry")
                        .push(j.name.clone());
                    continue;
                }
                return Err(InputError::field(
                    &self.file,
                    j.line,
                    "type",
                    format!(
                        "joint {} on the way to {} is {}; a serial chain has revolute, \
                         continuous, prismatic and fixed joints only",
                        quoted(&j.name),
                        quoted(tip),
                        quoted(&j.type_name)
                    ),
                ));
            };
            chain.steps.push(match kind {
                crate::params::JointKind::Revolute => Step::Turn(j.axis),
                crate::params::JointKind::Prismatic => Step::Slide(j.axis),
            });
            chain.joints.push(j.name.clone());
            chain.kinds.push(kind);
            chain.types.push(j.type_name.clone());
            chain.lines.push(j.line);
            chain.limits.push(j.limits);
            chain.folded.push(Vec::new());
        }
        Ok(chain)
    }

    /// The joints from `root` (or the top) down to `tip`, root first.
    fn path_up(&self, root: Option<&str>, tip: &str) -> Result<Vec<&UrdfJoint>, InputError> {
        let by_child: HashMap<&str, &UrdfJoint> =
            self.joints.iter().map(|j| (j.child.as_str(), j)).collect();
        let mut path: Vec<&UrdfJoint> = Vec::new();
        let mut link = tip;
        while Some(link) != root {
            match by_child.get(link) {
                Some(j) if path.len() == self.joints.len() => {
                    return Err(InputError::field(
                        &self.file,
                        j.line,
                        "parent",
                        format!(
                            "going up from {} never ends: joint {} is on a loop of \
                             joints; a URDF is a tree",
                            quoted(tip),
                            quoted(&j.name)
                        ),
                    ));
                }
                Some(j) => {
                    path.push(j);
                    link = &j.parent;
                }
                None if root.is_none() => break,
                None => return Err(self.not_connected(root.unwrap_or_default(), tip, &path)),
            }
        }
        path.reverse();
        Ok(path)
    }

    /// The error of a `root` that is not above `tip`, after going up from
    /// the tip through `path` (tip first) to the top.
    fn not_connected(&self, root: &str, tip: &str, path: &[&UrdfJoint]) -> InputError {
        let top = path.last().map_or(tip, |j| j.parent.as_str());
        let through: Vec<String> = path.iter().map(|j| quoted(&j.name)).collect();
        let message = format!(
            "the chain does not connect base link {} to tip link {}: going up from {} \
             {}ends at {}, the top of its tree, without meeting {}",
            quoted(root),
            quoted(tip),
            quoted(tip),
            if through.is_empty() {
                String::new()
            } else {
                format!("through joints {} ", shown(&through.join(", ")))
            },
            quoted(top),
            quoted(root)
        );
        match path.last() {
            Some(j) => InputError::field(&self.file, j.line, "parent", message),
            None => InputError::file_error(&self.file, message),
        }
    }
}

impl Urdf {
    /// The links with a mass that move with the chain `path` (joints, root
    /// to tip), each with its carrier and its centre at `q = 0`.
    fn masses_along(&self, path: &[&UrdfJoint]) -> Vec<ChainMass> {
        let Some(first) = path.first() else {
            return Vec::new();
        };
        let turning = path.iter().filter(|j| j.kind.movable().is_some()).count();
        // Each link of the chain: its carrier and its frame at q = 0.
        let mut on_chain: HashMap<&str, (Carrier, Isometry3<f64>)> = HashMap::new();
        let (mut carrier, mut t, mut turned) = (Carrier::Base, Isometry3::identity(), 0);
        on_chain.insert(first.parent.as_str(), (carrier, t));
        for j in path {
            t *= j.origin;
            if j.kind.movable().is_some() {
                carrier = Carrier::Link(turned);
                turned += 1;
            } else if turned == turning && turned > 0 {
                carrier = Carrier::Tool;
            }
            on_chain.insert(j.child.as_str(), (carrier, t));
        }
        let by_child: HashMap<&str, &UrdfJoint> =
            self.joints.iter().map(|j| (j.child.as_str(), j)).collect();
        let mut out = Vec::new();
        for link in &self.links {
            let Some(inertial) = link.inertial else {
                continue;
            };
            // Up from the link to the chain; a link that never reaches it
            // (above the root, another tree) does not move with it.
            let mut up: Vec<&UrdfJoint> = Vec::new();
            let mut at = link.name.as_str();
            let attached = loop {
                if let Some(&found) = on_chain.get(at) {
                    break Some(found);
                }
                match by_child.get(at) {
                    Some(j) if up.len() < self.joints.len() => {
                        up.push(j);
                        at = &j.parent;
                    }
                    // No parent, or a loop of joints (which `chain` refuses
                    // on the way to the tip; off it, the link is left out).
                    _ => break None,
                }
            };
            let Some((mut carrier, mut t)) = attached else {
                continue;
            };
            if !up.is_empty() && turning > 0 && carrier == Carrier::Link(turning - 1) {
                carrier = Carrier::Tool;
            }
            for j in up.iter().rev() {
                t *= j.origin;
            }
            out.push(ChainMass {
                link: link.name.clone(),
                carrier,
                kg: inertial.kg,
                com: t * Point3::from(inertial.com),
                moving: up
                    .iter()
                    .filter(|j| j.kind != JointKind::Fixed)
                    .map(|j| j.name.clone())
                    .collect(),
            });
        }
        out
    }
}

/// A URDF chain as a D-H arm.
#[derive(Clone, Debug, PartialEq)]
pub struct DhConversion {
    /// The arm, mm and rad (its prismatic joints' readings in mm): its
    /// probe at `q` is the tip at `q` in the D-H base frame.
    pub params: DhParams,
    /// The D-H base frame in the URDF root frame (metres): tip in the root
    /// frame = `base · (D-H probe position / 1000)`.
    pub base: Isometry3<f64>,
    /// The tip link's frame in the arm's tool frame (its last D-H frame):
    /// the tip link's orientation in the root frame at `q` is `base ·
    /// R_tool(q) · tool`.
    pub tool: UnitQuaternion<f64>,
    /// The chain's masses as an arm file states them (see the module
    /// docs). Empty when no link after the first joint has a mass.
    pub masses: DhMasses,
}

/// A mass and its centre in a D-H frame: an arm file's `mass_kg` and
/// `com_mm`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DhMass {
    /// kg.
    pub kg: f64,
    /// The centre of mass in the link's D-H frame, mm.
    pub com_mm: [f64; 3],
}

/// A chain's masses as its D-H arm carries them: what an arm file states
/// in its `[[joint]]` tables, `[probe]` and `gravity`
/// (`crate::corrections::Physics`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DhMasses {
    /// Per joint, the link after it (its centre in that joint's frame
    /// `T_j`, which turns with it); empty when the chain carries no mass.
    pub links: Vec<Option<DhMass>>,
    /// The tool's, its centre in the last frame.
    pub tool: Option<DhMass>,
    /// Gravity's direction in the D-H base — the URDF root's −z — when that
    /// is not the base's −z and a mass is stated.
    pub gravity: Option<[f64; 3]>,
}

impl DhMasses {
    /// Whether no mass is stated.
    pub fn is_empty(&self) -> bool {
        self.tool.is_none() && self.links.iter().all(Option::is_none)
    }
}

/// Farther than this (m) from the previous frame, a common normal means two
/// axes meant to be parallel — no arm is that large — and D-H would need a
/// `d` of that size: the joint gets the Hayati convention instead.
pub const HAYATI_BEYOND_M: f64 = 10.0;

/// A joint axis: a point on it and its unit direction.
type Axis = (Point3<f64>, Vector3<f64>);

/// Below this, `|z_a × z_b|` counts two unit axes as parallel.
const PARALLEL: f64 = 1e-9;

/// A D-H frame being built, in the root frame: its origin, x and z axes.
#[derive(Clone, Copy, Debug)]
struct Frame {
    o: Point3<f64>,
    x: Vector3<f64>,
    z: Vector3<f64>,
}

impl Chain {
    /// The tip in the root frame at readings `q` (rad, or m for a prismatic
    /// joint: the URDF's units), metres.
    ///
    /// # Panics
    /// If `q` has not one reading per joint (a programming error).
    pub fn position(&self, q: &[f64]) -> [f64; 3] {
        let t = self.transform(q);
        let p = t.translation.vector;
        [p.x, p.y, p.z]
    }

    /// The tip link's frame in the root frame at readings `q` (rad, or m
    /// for a prismatic joint), metres: the URDF's own forward kinematics,
    /// one joint origin and one joint motion after the other.
    ///
    /// # Panics
    /// If `q` has not one reading per joint (a programming error).
    pub fn transform(&self, q: &[f64]) -> Isometry3<f64> {
        assert_eq!(q.len(), self.joints.len(), "one reading per joint");
        let mut t = Isometry3::identity();
        let mut next = q.iter();
        for s in &self.steps {
            match s {
                Step::Rigid(o) => t *= o,
                Step::Turn(axis) => {
                    let angle = *next.next().expect("checked length");
                    let r = UnitQuaternion::from_scaled_axis(axis * angle);
                    t *= Isometry3::from_parts(Translation3::identity(), r);
                }
                Step::Slide(axis) => {
                    let by = *next.next().expect("checked length");
                    t *= Translation3::from(axis * by);
                }
            }
        }
        t
    }

    /// This chain with a tool point `offset` (m, in the tip link's frame)
    /// after its tip: the tip moves there, its frame's orientation stays.
    pub fn with_tool(mut self, offset: [f64; 3]) -> Chain {
        self.steps.push(Step::Rigid(Isometry3::from_parts(
            Translation3::from(Vector3::from(offset)),
            UnitQuaternion::identity(),
        )));
        self
    }

    /// The joint axes at `q = 0` in the root frame: a point on each and its
    /// unit direction (a prismatic joint's: its joint origin); and the tip
    /// link's frame.
    fn axes(&self) -> (Vec<Axis>, Isometry3<f64>) {
        let mut t = Isometry3::identity();
        let mut axes = Vec::new();
        for s in &self.steps {
            match s {
                Step::Rigid(o) => t *= o,
                Step::Turn(axis) | Step::Slide(axis) => axes.push((
                    Point3::from(t.translation.vector),
                    (t.rotation * axis).normalize(),
                )),
            }
        }
        (axes, t)
    }

    /// The D-H arm of this chain (see the module docs for the conventions).
    ///
    /// # Errors
    /// A chain without movable joints or with more than
    /// [`MAX_JOINTS`]; two consecutive axes whose common
    /// normal is more than [`HAYATI_BEYOND_M`] away while they are not
    /// nearly parallel (a robot kilometres wide).
    ///
    /// ```
    /// use aacmm_core::urdf::{parse_urdf, UrdfOptions};
    /// let text = r#"<robot name="r">
    ///   <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    ///     <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/></joint>
    ///   <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    ///     <origin xyz="0.3 0 0"/><axis xyz="0 0 1"/></joint>
    ///   <joint name="tool" type="fixed"><parent link="l2"/><child link="ball"/>
    ///     <origin xyz="0.2 0 0"/></joint>
    /// </robot>"#;
    /// let urdf = parse_urdf(text, "r.urdf", UrdfOptions::default()).unwrap();
    /// let dh = urdf.chain(None, "ball").unwrap().to_dh().unwrap();
    /// // A planar two-link arm: a1 = 300 mm between the parallel axes.
    /// assert!((dh.params.joints[0].a - 300.0).abs() < 1e-9);
    /// assert!((dh.params.probe[0] - 200.0).abs() < 1e-9);
    /// ```
    pub fn to_dh(&self) -> Result<DhConversion, InputError> {
        let (axes, tip) = self.axes();
        let n = axes.len();
        if n == 0 || n > MAX_JOINTS {
            return Err(InputError::file_error(
                &self.file,
                format!(
                    "the chain has {n} movable (revolute, continuous or prismatic) joints; \
                     an arm has 1 to {MAX_JOINTS}"
                ),
            ));
        }
        // Frame 0: on axis 1, nearest the root origin; x from the root x axis.
        let (p1, z0) = axes[0];
        let o0 = p1 - z0 * p1.coords.dot(&z0);
        let x0 = perpendicular(Vector3::x(), z0).unwrap_or_else(|| {
            perpendicular(Vector3::y(), z0).expect("x and y cannot both be parallel to z0")
        });
        let base = frame(o0, x0, z0);
        let mut prev = Frame {
            o: o0,
            x: x0,
            z: z0,
        };
        let mut joints = Vec::with_capacity(n);
        for (i, &next) in axes.iter().enumerate().skip(1) {
            let (joint, to) = self.link(i, prev, next)?;
            joints.push(joint.with_kind(self.kinds[i - 1]));
            prev = to;
        }
        // The last joint: a = d = α = θ = 0, the probe in its frame.
        joints.push(DhJoint::default().with_kind(self.kinds[n - 1]));
        let last = frame(prev.o, prev.x, prev.z);
        let b = last
            .inverse_transform_point(&Point3::from(tip.translation.vector))
            .coords
            * 1000.0;
        let params = DhParams {
            joints,
            probe: [b.x, b.y, b.z],
        };
        Ok(DhConversion {
            masses: masses_in_dh(&self.masses, &params, &base),
            tool: last.rotation.inverse() * tip.rotation,
            params,
            base,
        })
    }

    /// The link from axis `i` (through `prev`'s origin along its z) to
    /// axis `i + 1`, `next`: its joint (D-H, or Hayati where the common
    /// normal is farther than [`HAYATI_BEYOND_M`]) and the next frame.
    fn link(&self, i: usize, prev: Frame, next: Axis) -> Result<(DhJoint, Frame), InputError> {
        let (point_next, z) = next;
        let c = prev.z.cross(&z);
        let (foot, x) = if c.norm() > PARALLEL {
            // Feet of the common normal: prev.o + s·prev.z on axis i.
            let w = point_next - prev.o;
            let b = prev.z.dot(&z);
            let s = (w.dot(&prev.z) - b * w.dot(&z)) / (1.0 - b * b);
            if s.abs() > HAYATI_BEYOND_M {
                if b.abs() > 0.5 {
                    return Ok(hayati_link(prev, next));
                }
                return Err(InputError::field(
                    &self.file,
                    self.lines[i],
                    "origin",
                    format!(
                        "the axes of {} and {} have their common normal {:.0} m away, and \
                         are {:.0}° apart: no arm is that large",
                        quoted(&self.joints[i - 1]),
                        quoted(&self.joints[i]),
                        s.abs(),
                        b.acos().to_degrees()
                    ),
                ));
            }
            (prev.o + prev.z * s, c.normalize())
        } else {
            let x = perpendicular(point_next - prev.o, prev.z).unwrap_or(prev.x);
            (prev.o, x)
        };
        let a = (point_next - foot).dot(&x);
        let joint = DhJoint {
            a: a * 1000.0,
            d: (foot - prev.o).dot(&prev.z) * 1000.0,
            alpha: signed_angle(prev.z, z, x),
            theta: signed_angle(prev.x, x, prev.z),
            ..DhJoint::default()
        };
        Ok((
            joint,
            Frame {
                o: foot + x * a,
                x,
                z,
            },
        ))
    }
}

/// The Hayati link from `prev` to the nearly parallel axis `next`
/// (`Rz(θ)·Tx(a)·Rx(α)·Ry(β)`): the next origin where that axis crosses the
/// plane normal to `prev.z` through `prev.o`, `x` towards it.
fn hayati_link(prev: Frame, next: Axis) -> (DhJoint, Frame) {
    let (point_next, z) = next;
    let along = (point_next - prev.o).dot(&prev.z) / z.dot(&prev.z);
    let o = point_next - z * along;
    let x = perpendicular(o - prev.o, prev.z).unwrap_or(prev.x);
    let a = (o - prev.o).dot(&x);
    // The next z in the frame turned by θ: (x, y, z) components.
    let y = prev.z.cross(&x);
    let (zx, zy, zz) = (z.dot(&x), z.dot(&y), z.dot(&prev.z));
    let beta = zx.clamp(-1.0, 1.0).asin();
    let alpha = (-zy).atan2(zz);
    let joint = DhJoint::hayati(a * 1000.0, alpha, signed_angle(prev.x, x, prev.z), beta);
    // Ry(β) turns x to cos β·x − sin β·z; Rx(α) then turns the frame's y, z.
    let (sa, ca) = alpha.sin_cos();
    let (sb, cb) = beta.sin_cos();
    let x_next = x * cb + y * (sb * sa) - prev.z * (sb * ca);
    (
        joint,
        Frame {
            o,
            x: x_next.normalize(),
            z,
        },
    )
}

/// The masses `masses` summed per carrier, each centre in its D-H frame
/// (`params` at `q = 0`, its base at `base` in the root frame); gravity the
/// root's −z.
fn masses_in_dh(masses: &[ChainMass], params: &DhParams, base: &Isometry3<f64>) -> DhMasses {
    let n = params.joints.len();
    // Σ m and Σ m·r (root frame, m) per link after joint k (k < n) and the
    // tool (n).
    let mut sums = vec![(0.0, Vector3::zeros()); n + 1];
    for m in masses {
        let slot = match m.carrier {
            Carrier::Base => continue,
            Carrier::Link(k) => k,
            Carrier::Tool => n,
        };
        sums[slot].0 += m.kg;
        sums[slot].1 += m.com.coords * m.kg;
    }
    // The D-H frames at q = 0 in the root frame: base·A_1…A_j.
    let mut frames = vec![*base];
    for j in &params.joints {
        let last = frames[frames.len() - 1];
        frames.push(last * dh_link(j));
    }
    let mass = |slot: usize, frame: &Isometry3<f64>| {
        let (kg, moment): (f64, Vector3<f64>) = sums[slot];
        (kg > 0.0).then(|| {
            let c = frame
                .inverse_transform_point(&Point3::from(moment / kg))
                .coords
                * 1000.0;
            DhMass {
                kg,
                com_mm: [c.x, c.y, c.z],
            }
        })
    };
    let out = DhMasses {
        links: (0..n).map(|k| mass(k, &frames[k + 1])).collect(),
        tool: mass(n, &frames[n]),
        gravity: None,
    };
    if out.is_empty() {
        return DhMasses::default();
    }
    let down = base.rotation.inverse() * -Vector3::z();
    DhMasses {
        gravity: ((down + Vector3::z()).norm() > 1e-12).then(|| [down.x, down.y, down.z]),
        ..out
    }
}

/// A link at `q = 0`, metres: `Rz(θ)·Tz(d)·Tx(a)·Rx(α)`, or a Hayati
/// one's `Rz(θ)·Tx(a)·Rx(α)·Ry(β)`.
fn dh_link(j: &DhJoint) -> Isometry3<f64> {
    let rz = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), j.theta);
    let rx = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), j.alpha);
    let (d, ry) = match j.model {
        JointModel::Hayati => (
            0.0,
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), j.beta),
        ),
        JointModel::Dh => (j.d, UnitQuaternion::identity()),
    };
    Isometry3::from_parts(Translation3::identity(), rz)
        * Isometry3::from_parts(
            Translation3::new(j.a / 1000.0, 0.0, d / 1000.0),
            UnitQuaternion::identity(),
        )
        * Isometry3::from_parts(Translation3::identity(), rx * ry)
}

/// `v` made perpendicular to the unit `z` and normalised, unless (nearly) zero.
fn perpendicular(v: Vector3<f64>, z: Vector3<f64>) -> Option<Vector3<f64>> {
    let p = v - z * v.dot(&z);
    (p.norm() > 1e-12).then(|| p.normalize())
}

/// The angle turning unit `from` into unit `to` about unit `about` (both
/// perpendicular to it).
fn signed_angle(from: Vector3<f64>, to: Vector3<f64>, about: Vector3<f64>) -> f64 {
    from.cross(&to).dot(&about).atan2(from.dot(&to))
}

/// The frame with origin `o`, x axis `x` and z axis `z` (orthonormal).
fn frame(o: Point3<f64>, x: Vector3<f64>, z: Vector3<f64>) -> Isometry3<f64> {
    let y = z.cross(&x);
    let r = Rotation3::from_basis_unchecked(&[x, y, z]);
    Isometry3::from_parts(
        Translation3::from(o.coords),
        UnitQuaternion::from_rotation_matrix(&r),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference_model::position;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random serial chain in URDF: every joint origin random (xyz within
    /// ±0.3 m, any rpy), random axes, fixed joints between, and a tool ball.
    /// With `mixed`, joints are also `continuous` or `prismatic`, and some
    /// follow the previous axis exactly (rpy 0, the same axis) or nearly
    /// (a 0.002 rad pitch: a Hayati joint).
    fn random_urdf(rng: &mut ChaCha8Rng, joints: usize, mixed: bool) -> String {
        let mut s = String::from("<robot name=\"random\">\n");
        let mut parent = "base".to_string();
        let num = |rng: &mut ChaCha8Rng, r: f64| rng.random_range(-r..r);
        let mut axis = [0.0, 0.0, 1.0];
        for j in 0..joints {
            let child = format!("l{j}");
            let xyz = [num(rng, 0.3), num(rng, 0.3), num(rng, 0.3)];
            let mut rpy = [num(rng, 3.2), num(rng, 1.5), num(rng, 3.2)];
            let follow = if mixed && j > 0 && parent.starts_with('l') {
                rng.random_range(0..3)
            } else {
                0
            };
            match follow {
                // Parallel to the previous axis (the same frame), or nearly.
                1 => rpy = [0.0; 3],
                2 => rpy = [0.0, 0.002, 0.0],
                _ => axis = [num(rng, 1.0), num(rng, 1.0), num(rng, 1.0)],
            }
            let kind = match (mixed, rng.random_range(0..4)) {
                (true, 0) => "prismatic",
                (true, 1) => "continuous",
                _ => "revolute",
            };
            s += &format!(
                "<joint name=\"j{j}\" type=\"{kind}\"><parent link=\"{parent}\"/>\
                 <child link=\"{child}\"/><origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>\
                 <axis xyz=\"{} {} {}\"/><limit lower=\"-3\" upper=\"3\"/></joint>\n",
                xyz[0], xyz[1], xyz[2], rpy[0], rpy[1], rpy[2], axis[0], axis[1], axis[2]
            );
            parent = child;
            if j % 3 == 1 {
                let f = format!("f{j}");
                s += &format!(
                    "<joint name=\"fix{j}\" type=\"fixed\"><parent link=\"{parent}\"/>\
                     <child link=\"{f}\"/><origin xyz=\"0.01 0.02 0.05\" rpy=\"0.3 -0.2 1.0\"/>\
                     </joint>\n"
                );
                parent = f;
            }
        }
        s += &format!(
            "<joint name=\"ball\" type=\"fixed\"><parent link=\"{parent}\"/>\
             <child link=\"ball_link\"/><origin xyz=\"0.01 -0.02 0.17\" rpy=\"0.1 0.2 0.3\"/>\
             </joint>\n</robot>\n"
        );
        s
    }

    /// Random readings of `chain` in the URDF's units: ±π rad, ±0.5 m.
    fn random_q(chain: &Chain, rng: &mut ChaCha8Rng) -> Vec<f64> {
        (chain.kinds.iter())
            .map(|k| match k {
                crate::params::JointKind::Revolute => {
                    rng.random_range(-std::f64::consts::PI..std::f64::consts::PI)
                }
                crate::params::JointKind::Prismatic => rng.random_range(-0.5..0.5),
            })
            .collect()
    }

    /// The largest distance, mm, between the URDF tip and the D-H probe
    /// mapped through the base, over `samples` random readings; the tool
    /// frame's orientation, mapped through the base and the tool rotation,
    /// must be the tip link's (within 1e-12 rad) at each.
    pub(crate) fn worst_mm(
        chain: &Chain,
        dh: &DhConversion,
        rng: &mut ChaCha8Rng,
        samples: usize,
    ) -> f64 {
        let kernel = crate::kernel::ArmKernel::new(&dh.params).unwrap();
        (0..samples)
            .map(|_| {
                let q = random_q(chain, rng);
                let urdf = chain.transform(&q);
                // The arm reads a slide in mm.
                let q_arm: Vec<f64> = (q.iter().zip(&chain.kinds))
                    .map(|(v, k)| match k {
                        crate::params::JointKind::Revolute => *v,
                        crate::params::JointKind::Prismatic => v * 1000.0,
                    })
                    .collect();
                let pose = kernel.pose(&q_arm).unwrap();
                let p = pose.position;
                let in_root = dh.base * Point3::new(p[0] / 1000.0, p[1] / 1000.0, p[2] / 1000.0);
                let r = Rotation3::from_matrix_unchecked(nalgebra::Matrix3::from_fn(|i, j| {
                    pose.rotation[i][j]
                }));
                let tool = dh.base.rotation * UnitQuaternion::from_rotation_matrix(&r) * dh.tool;
                // The matrices' difference: about the angle between them,
                // without acos's loss of digits near 0.
                let turn = (tool.to_rotation_matrix().matrix()
                    - urdf.rotation.to_rotation_matrix().matrix())
                .norm();
                assert!(turn < 1e-12, "orientation off by {turn} rad at {q:?}");
                (in_root.coords - urdf.translation.vector).norm() * 1000.0
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn random_chains_agree_to_a_nanometre() {
        let mut rng = ChaCha8Rng::seed_from_u64(16);
        for trial in 0..50 {
            let joints = if trial % 2 == 0 { 6 } else { 7 };
            let text = random_urdf(&mut rng, joints, false);
            let urdf = parse_urdf(&text, "random.urdf", UrdfOptions { snap_rad: 0.0 }).unwrap();
            let chain = urdf.chain(None, "ball_link").unwrap();
            assert_eq!(chain.joints.len(), joints);
            let dh = chain.to_dh().unwrap();
            let worst = worst_mm(&chain, &dh, &mut rng, 200);
            // 1e-9 m = 1e-6 mm.
            assert!(worst < 1e-6, "trial {trial}: {worst} mm\n{text}");
        }
    }

    /// Any chain of 1 to 12 joints — revolute, continuous and prismatic,
    /// fixed joints between, consecutive axes parallel and nearly parallel
    /// — converts exactly: the tip within 1 nm and the tool frame's
    /// orientation the tip link's at random readings; nearly parallel axes
    /// make Hayati joints, slides prismatic ones.
    #[test]
    fn any_chain_agrees_in_position_and_orientation() {
        let mut rng = ChaCha8Rng::seed_from_u64(39);
        let (mut hayati, mut prismatic) = (0, 0);
        for trial in 0..120 {
            let joints = 1 + trial % 12;
            let text = random_urdf(&mut rng, joints, true);
            let urdf = parse_urdf(&text, "random.urdf", UrdfOptions { snap_rad: 0.0 }).unwrap();
            let chain = urdf.chain(Some("base"), "ball_link").unwrap();
            assert_eq!(chain.joints.len(), joints);
            let dh = chain.to_dh().unwrap();
            for (j, kind) in dh.params.joints.iter().zip(&chain.kinds) {
                assert_eq!(j.kind, *kind);
                hayati += usize::from(j.model == JointModel::Hayati);
                prismatic += usize::from(*kind == crate::params::JointKind::Prismatic);
            }
            let worst = worst_mm(&chain, &dh, &mut rng, 50);
            assert!(worst < 1e-6, "trial {trial}: {worst} mm\n{text}");
        }
        assert!(
            hayati > 20 && prismatic > 100,
            "{hayati} Hayati, {prismatic} prismatic"
        );
    }

    /// The robots of examples/mukca, with the right angles snapped (as the
    /// arm files are made); as written, the Kinova's axes 2 and 3 (1.5708,
    /// -3.1416) meet 38 km away: joint 2 becomes a Hayati joint, exact too.
    #[test]
    fn shipped_urdfs_agree_to_a_nanometre() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/mukca/urdf");
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for (file, joints) in [("gen3lite.urdf", 6), ("panda.urdf", 7)] {
            let text = std::fs::read_to_string(dir.join(file)).unwrap();
            let urdf = parse_urdf(&text, file, UrdfOptions::default()).unwrap();
            let chain = urdf.chain(None, "ball_link").unwrap();
            assert_eq!(chain.joints.len(), joints);
            let dh = chain.to_dh().unwrap();
            let worst = worst_mm(&chain, &dh, &mut rng, 1000);
            assert!(worst < 1e-6, "{file}: {worst} mm");
            let as_written = parse_urdf(&text, file, UrdfOptions { snap_rad: 0.0 }).unwrap();
            let written = as_written.chain(None, "ball_link").unwrap();
            let dh = written.to_dh();
            if file == "gen3lite.urdf" {
                let dh = dh.unwrap();
                let models: Vec<JointModel> = dh.params.joints.iter().map(|j| j.model).collect();
                let mut want = vec![JointModel::Dh; 6];
                want[1] = JointModel::Hayati;
                assert_eq!(models, want);
                assert!((dh.params.joints[1].beta.abs() - 7.3e-6).abs() < 1e-7);
                let worst = worst_mm(&written, &dh, &mut rng, 1000);
                assert!(worst < 1e-6, "{file} as written: {worst} mm");
            } else {
                // The Panda's URDF writes π/2 to full precision: nothing to snap.
                assert_eq!(dh.unwrap().params, chain.to_dh().unwrap().params);
            }
        }
    }

    /// Consecutive parallel and intersecting axes: the special cases of the
    /// common normal.
    #[test]
    fn parallel_and_intersecting_axes_agree() {
        let text = r#"<robot name="p">
          <joint name="j1" type="revolute"><parent link="b"/><child link="l1"/>
            <origin xyz="0.1 0.2 0.3" rpy="0 0 0.4"/><axis xyz="0 0 1"/></joint>
          <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
            <origin xyz="0 0 0.2"/><axis xyz="0 0 1"/></joint>
          <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
            <origin xyz="0.25 0 0" rpy="3.141592653589793 0 0"/><axis xyz="0 0 1"/></joint>
          <joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/>
            <origin xyz="0 0 0.1" rpy="1.5707963267948966 0 0"/><axis xyz="0 0 1"/></joint>
          <joint name="j5" type="revolute"><parent link="l4"/><child link="l5"/>
            <origin xyz="0 0 0" rpy="0 1.5707963267948966 0"/><axis xyz="0 0 -1"/></joint>
          <joint name="j6" type="continuous"><parent link="l5"/><child link="l6"/>
            <origin xyz="0.05 0 0.1"/><axis xyz="1 0 0"/></joint>
          <joint name="tool" type="fixed"><parent link="l6"/><child link="ball"/>
            <origin xyz="0 0 0.15"/></joint>
        </robot>"#;
        let urdf = parse_urdf(text, "p.urdf", UrdfOptions::default()).unwrap();
        let chain = urdf.chain(Some("b"), "ball").unwrap();
        let dh = chain.to_dh().unwrap();
        // j1 ∥ j2 on one line: a1 = 0; j2 ∥ j3 (antiparallel), 250 mm apart.
        assert!(dh.params.joints[0].a.abs() < 1e-12);
        assert!((dh.params.joints[1].a.abs() - 250.0).abs() < 1e-9);
        assert!((dh.params.joints[1].alpha.abs() - std::f64::consts::PI).abs() < 1e-12);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        assert!(worst_mm(&chain, &dh, &mut rng, 500) < 1e-6);
    }

    #[test]
    // 1.5708 and 3.1416 are what published URDFs write; that is the point.
    #[allow(clippy::approx_constant)]
    fn snapping_rounds_right_angles_only() {
        let mut notes = Vec::new();
        let v = snap([1.5708, -3.1416, 0.001], 1e-4, |i, _, to, _| {
            notes.push((i, to))
        });
        assert_eq!(
            v,
            [std::f64::consts::FRAC_PI_2, -std::f64::consts::PI, 0.001]
        );
        assert_eq!(notes, [(0, "π/2".to_string()), (1, "-π".to_string())]);
    }

    #[test]
    fn bad_input_is_located() {
        let e = parse_urdf(
            "<robot><joint name=\"a\"/></robot>",
            "x.urdf",
            UrdfOptions::default(),
        )
        .unwrap_err();
        assert_eq!(e.to_string(), "x.urdf:1: field `type`: missing on <joint>");
        let e = parse_urdf(
            "<robot>\n<joint type=></robot>",
            "x.urdf",
            UrdfOptions::default(),
        )
        .unwrap_err();
        assert!(
            e.to_string().starts_with("x.urdf:2: not well-formed XML"),
            "{e}"
        );
        for kind in ["floating", "planar"] {
            let text = format!(
                "<robot>\n<joint name=\"j\" type=\"revolute\"><parent link=\"a\"/>\
                 <child link=\"b\"/></joint>\n<joint name=\"s\" type=\"{kind}\">\
                 <parent link=\"b\"/><child link=\"c\"/></joint></robot>"
            );
            let urdf = parse_urdf(&text, "s.urdf", UrdfOptions::default()).unwrap();
            let e = urdf.chain(None, "c").unwrap_err();
            assert_eq!(
                e.to_string(),
                format!(
                    "s.urdf:3: field `type`: joint `s` on the way to `c` is `{kind}`; a serial \
                     chain has revolute, continuous, prismatic and fixed joints only"
                )
            );
            // Beside the chain, it is no matter.
            assert!(urdf.chain(None, "b").is_ok());
        }
        let slider = r#"<robot><joint name="s" type="prismatic"><parent link="a"/>
            <child link="b"/></joint></robot>"#;
        let urdf = parse_urdf(slider, "s.urdf", UrdfOptions::default()).unwrap();
        let chain = urdf.chain(None, "b").unwrap();
        assert_eq!(chain.kinds, [crate::params::JointKind::Prismatic]);
        let e = urdf.chain(None, "nowhere").unwrap_err();
        assert!(e.to_string().contains("no link `nowhere`"), "{e}");
        let e = urdf.chain(Some("nowhere"), "b").unwrap_err();
        assert_eq!(
            e.to_string(),
            "s.urdf: no link `nowhere` is joined to the robot (the base must be a link's name)"
        );
    }

    /// A base that is not above the tip, a slide along a zero axis, limits
    /// that are not numbers or not in order: each named, at its line.
    #[test]
    fn bad_chains_and_limits_are_located() {
        let text = r#"<robot>
          <joint name="j1" type="revolute"><parent link="a"/><child link="b"/></joint>
          <joint name="j2" type="prismatic"><parent link="b"/><child link="c"/></joint>
          <joint name="side" type="revolute"><parent link="a"/><child link="d"/></joint>
        </robot>"#;
        let urdf = parse_urdf(text, "t.urdf", UrdfOptions::default()).unwrap();
        let e = urdf.chain(Some("d"), "c").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.urdf:2: field `parent`: the chain does not connect base link `d` to tip link \
             `c`: going up from `c` through joints `j2`, `j1` ends at `a`, the top of its tree, \
             without meeting `d`"
        );
        let joint = |kind: &str, body: &str| {
            format!(
                "<robot>\n<joint name=\"s\" type=\"{kind}\"><parent link=\"a\"/>\
                 <child link=\"b\"/>\n{body}</joint></robot>"
            )
        };
        let cases = [
            (
                joint("prismatic", "<axis xyz=\"0 0 0\"/>"),
                "z.urdf:3: field `axis`: joint `s` slides along a zero axis",
            ),
            (
                joint("prismatic", "<limit lower=\"-0.1\" upper=\"1,5\"/>"),
                "z.urdf:3: field `upper`: joint `s`: `1,5` is not a limit (a finite number, m)",
            ),
            (
                joint("revolute", "<limit lower=\"nan\" upper=\"1\"/>"),
                "z.urdf:3: field `lower`: joint `s`: `nan` is not a limit (a finite number, rad)",
            ),
            (
                joint("revolute", "<limit lower=\"1\" upper=\"-1\"/>"),
                "z.urdf:3: field `upper`: joint `s`: upper -1 is below lower 1",
            ),
        ];
        for (text, message) in cases {
            let e = parse_urdf(&text, "z.urdf", UrdfOptions::default()).unwrap_err();
            assert_eq!(e.to_string(), message);
        }
        // Thirteen movable joints, or none, are no arm.
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        let long = random_urdf(&mut rng, 13, true);
        let urdf = parse_urdf(&long, "long.urdf", UrdfOptions::default()).unwrap();
        let e = urdf.chain(None, "ball_link").unwrap().to_dh().unwrap_err();
        assert_eq!(
            e.to_string(),
            "long.urdf: the chain has 13 movable (revolute, continuous or prismatic) joints; \
             an arm has 1 to 12"
        );
        let e = urdf
            .chain(Some("l12"), "ball_link")
            .unwrap()
            .to_dh()
            .unwrap_err();
        assert!(
            e.to_string()
                .starts_with("long.urdf: the chain has 0 movable"),
            "{e}"
        );
        // Limits are kept in the URDF's units: a slide's in metres.
        let text = joint("prismatic", "<limit lower=\"-0.1\" upper=\"0.5\"/>");
        let urdf = parse_urdf(&text, "z.urdf", UrdfOptions::default()).unwrap();
        assert_eq!(urdf.chain(None, "b").unwrap().limits, [Some([-0.1, 0.5])]);
    }

    /// A random chain whose links have masses: a base mass before the
    /// first joint (on a mounting link above it), each joint's child link,
    /// links fixed to them beside the chain and on it, a link behind a
    /// prismatic joint beside the chain, the tool's links after the last
    /// joint (beside the chain and beyond the tip), a zero mass and a link
    /// without one. Returns the URDF and each massive link's carrier, in
    /// file order.
    fn random_massive_urdf(
        rng: &mut ChaCha8Rng,
        joints: usize,
    ) -> (String, Vec<(String, Carrier)>) {
        /// Adds a link of random mass and centre carried by `carrier`.
        fn massive(
            out: &mut (String, Vec<(String, Carrier)>),
            rng: &mut ChaCha8Rng,
            name: &str,
            carrier: Carrier,
        ) {
            let kg = rng.random_range(0.05..3.0);
            let c: [f64; 3] = std::array::from_fn(|_| rng.random_range(-0.2..0.2));
            out.0 += &format!(
                "<link name=\"{name}\"><inertial><origin xyz=\"{} {} {}\" rpy=\"0.3 -0.1 2\"/>\
                 <mass value=\"{kg}\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" \
                 iyz=\"0\" izz=\"1\"/></inertial></link>\n",
                c[0], c[1], c[2]
            );
            out.1.push((name.to_string(), carrier));
        }
        /// Adds a joint of kind `kind` at a random origin, about a random
        /// axis.
        fn joint(out: &mut String, rng: &mut ChaCha8Rng, [name, kind, parent, child]: [&str; 4]) {
            let xyz: [f64; 3] = std::array::from_fn(|_| rng.random_range(-0.3..0.3));
            let rpy = [
                rng.random_range(-3.2..3.2),
                rng.random_range(-1.5..1.5),
                rng.random_range(-3.2..3.2),
            ];
            let axis: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
            *out += &format!(
                "<joint name=\"{name}\" type=\"{kind}\"><parent link=\"{parent}\"/>\
                 <child link=\"{child}\"/><origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>\
                 <axis xyz=\"{} {} {}\"/></joint>\n",
                xyz[0], xyz[1], xyz[2], rpy[0], rpy[1], rpy[2], axis[0], axis[1], axis[2]
            );
        }
        let mut out = ("<link name=\"world\"/>\n".to_string(), Vec::new());
        let mut js = String::new();
        joint(&mut js, rng, ["mount", "fixed", "world", "base"]);
        massive(&mut out, rng, "base", Carrier::Base);
        let mut parent = "base".to_string();
        for j in 0..joints {
            let last = j + 1 == joints;
            let child = format!("l{j}");
            joint(
                &mut js,
                rng,
                [&format!("j{j}"), "revolute", &parent, &child],
            );
            massive(&mut out, rng, &child, Carrier::Link(j));
            let beside = if last {
                Carrier::Tool
            } else {
                Carrier::Link(j)
            };
            if j % 2 == 0 || last {
                let side = format!("side{j}");
                joint(
                    &mut js,
                    rng,
                    [&format!("fix_side{j}"), "fixed", &child, &side],
                );
                massive(&mut out, rng, &side, beside);
            }
            if j == 1 {
                joint(&mut js, rng, ["slide", "prismatic", &child, "slider"]);
                massive(&mut out, rng, "slider", beside);
            }
            parent = child;
            if j % 3 == 1 && !last {
                let f = format!("f{j}");
                joint(&mut js, rng, [&format!("fix{j}"), "fixed", &parent, &f]);
                massive(&mut out, rng, &f, Carrier::Link(j));
                parent = f;
            }
        }
        joint(&mut js, rng, ["ball", "fixed", &parent, "ball_link"]);
        massive(&mut out, rng, "ball_link", Carrier::Tool);
        joint(
            &mut js,
            rng,
            ["beyond_joint", "fixed", "ball_link", "beyond"],
        );
        massive(&mut out, rng, "beyond", Carrier::Tool);
        out.0 += "<link name=\"nothing\"><inertial><mass value=\"0\"/></inertial></link>\n";
        joint(&mut js, rng, ["nothing_joint", "fixed", "l0", "nothing"]);
        out.1.push(("nothing".into(), Carrier::Link(0)));
        (
            format!("<robot name=\"massive\">\n{}{js}</robot>\n", out.0),
            out.1,
        )
    }

    /// Each link's pose in the root frame at readings `q` of the chain's
    /// joints (by name), every other joint at its zero: the URDF tree walked
    /// directly, independently of [`Chain`].
    fn link_pose(urdf: &Urdf, chain: &Chain, q: &[f64], link: &str) -> Isometry3<f64> {
        match urdf.joints.iter().find(|j| j.child == link) {
            None => Isometry3::identity(),
            Some(j) => {
                let turn = (chain.joints.iter().position(|n| *n == j.name)).map_or(0.0, |i| q[i]);
                link_pose(urdf, chain, q, &j.parent)
                    * j.origin
                    * Isometry3::from_parts(
                        Translation3::identity(),
                        UnitQuaternion::from_scaled_axis(j.axis * turn),
                    )
            }
        }
    }

    /// The centre of mass of the links carried by `carrier` in the root
    /// frame at `q` through the URDF, m, and their mass.
    fn urdf_com(urdf: &Urdf, chain: &Chain, q: &[f64], carrier: Carrier) -> (f64, Vector3<f64>) {
        let (mut kg, mut moment) = (0.0, Vector3::zeros());
        for m in chain.masses.iter().filter(|m| m.carrier == carrier) {
            let link = urdf.links.iter().find(|l| l.name == m.link).unwrap();
            let inertial = link.inertial.unwrap();
            let r = link_pose(urdf, chain, q, &link.name) * Point3::from(inertial.com);
            kg += inertial.kg;
            moment += r.coords * inertial.kg;
        }
        (kg, moment / kg)
    }

    /// The mass `m` of the link after joint `k` (the tool: `k = n`) in the
    /// root frame at `q` through the D-H arm (its frame `k + 1`, the tool's
    /// the last), m: the arm cut after that frame with `com_mm` as its probe.
    fn dh_com(dh: &DhConversion, q: &[f64], k: usize, m: &DhMass) -> Vector3<f64> {
        let n = dh.params.joints.len();
        let frames = (k + 1).min(n);
        let mut arm = dh.params.clone();
        arm.joints.truncate(frames);
        arm.probe = m.com_mm;
        let p = position(&arm.to_vec(), &q[..frames]);
        (dh.base * Point3::new(p[0] / 1000.0, p[1] / 1000.0, p[2] / 1000.0)).coords
    }

    /// The largest distance, mm, between each carried centre of mass
    /// through the URDF and through the D-H arm, over `samples` random
    /// readings in ±π; and the masses must be the same.
    fn worst_com_mm(
        urdf: &Urdf,
        chain: &Chain,
        dh: &DhConversion,
        rng: &mut ChaCha8Rng,
        samples: usize,
    ) -> f64 {
        let n = chain.joints.len();
        let mut worst: f64 = 0.0;
        for _ in 0..samples {
            let q: Vec<f64> = (0..n)
                .map(|_| rng.random_range(-std::f64::consts::PI..std::f64::consts::PI))
                .collect();
            let stated = (dh.masses.links.iter().enumerate())
                .filter_map(|(k, m)| Some((Carrier::Link(k), k, (*m)?)))
                .chain(dh.masses.tool.map(|m| (Carrier::Tool, n, m)));
            for (carrier, k, m) in stated {
                let (kg, urdf_com) = urdf_com(urdf, chain, &q, carrier);
                assert!((kg - m.kg).abs() < 1e-12, "{carrier:?}: {kg} vs {}", m.kg);
                worst = worst.max((dh_com(dh, &q, k, &m) - urdf_com).norm() * 1000.0);
            }
        }
        worst
    }

    /// The masses as the corrections' [`crate::corrections::Physics`] (what
    /// an arm file with them reads as).
    fn physics_of(m: &DhMasses) -> crate::corrections::Physics {
        let mass = |d: &DhMass| crate::corrections::Mass {
            kg: d.kg,
            com_mm: Some(d.com_mm),
        };
        crate::corrections::Physics {
            link_masses: m.links.iter().map(|l| l.as_ref().map(mass)).collect(),
            probe_mass: m.tool.as_ref().map(mass),
            gravity: m.gravity,
            ..Default::default()
        }
    }

    /// Gravity (the root's −z) about each joint axis, N·m, from the URDF
    /// directly: the masses outboard of the joint, about a point on its
    /// axis.
    fn urdf_torques(urdf: &Urdf, chain: &Chain, q: &[f64]) -> Vec<f64> {
        let g = Vector3::new(0.0, 0.0, -crate::corrections::gravity::STANDARD_GRAVITY);
        (0..chain.joints.len())
            .map(|j| {
                let joint = urdf
                    .joints
                    .iter()
                    .find(|u| u.name == chain.joints[j])
                    .unwrap();
                let at = link_pose(urdf, chain, q, &joint.parent) * joint.origin;
                let (axis, point) = (at.rotation * joint.axis, at.translation.vector);
                let outboard = chain.masses.iter().filter(|m| match m.carrier {
                    Carrier::Link(k) => k >= j,
                    Carrier::Tool => true,
                    Carrier::Base => false,
                });
                outboard
                    .map(|m| {
                        let inertial = urdf
                            .links
                            .iter()
                            .find(|l| l.name == m.link)
                            .unwrap()
                            .inertial
                            .unwrap();
                        let r = link_pose(urdf, chain, q, &m.link) * Point3::from(inertial.com);
                        axis.dot(&(r.coords - point).cross(&(g * inertial.kg)))
                    })
                    .sum()
            })
            .collect()
    }

    /// Masses carried to the D-H frames: every link where it belongs, each
    /// carried centre of mass where the URDF puts it at any reading (within
    /// 1e-6 mm), and the gravity torques the toolkit computes from the
    /// converted arm those of the URDF (gravity its root's −z, stated in
    /// the D-H base, which the random first axis turns).
    #[test]
    fn random_chains_carry_their_masses() {
        let mut rng = ChaCha8Rng::seed_from_u64(29);
        for trial in 0..30 {
            let joints = if trial % 2 == 0 { 6 } else { 7 };
            let (text, expect) = random_massive_urdf(&mut rng, joints);
            let urdf = parse_urdf(&text, "massive.urdf", UrdfOptions { snap_rad: 0.0 }).unwrap();
            let chain = urdf.chain(None, "ball_link").unwrap();
            let carried: Vec<(String, Carrier)> = chain
                .masses
                .iter()
                .map(|m| (m.link.clone(), m.carrier))
                .collect();
            assert_eq!(carried, expect, "trial {trial}");
            let moving: Vec<&ChainMass> = chain
                .masses
                .iter()
                .filter(|m| !m.moving.is_empty())
                .collect();
            assert_eq!(moving.len(), 1);
            assert_eq!(
                (moving[0].link.as_str(), moving[0].moving.as_slice()),
                ("slider", &["slide".to_string()][..])
            );
            let dh = chain.to_dh().unwrap();
            assert_eq!(dh.masses.links.len(), joints);
            assert!(dh.masses.links.iter().all(Option::is_some));
            assert!(dh.masses.tool.is_some());
            let worst = worst_com_mm(&urdf, &chain, &dh, &mut rng, 50);
            assert!(worst < 1e-6, "trial {trial}: {worst} mm\n{text}");
            assert!(dh.masses.gravity.is_some(), "the base is turned");
            let physics = physics_of(&dh.masses);
            for _ in 0..20 {
                let q: Vec<f64> = (0..joints).map(|_| rng.random_range(-3.0..3.0)).collect();
                let mut tau = vec![0.0; joints];
                crate::corrections::gravity::torques(&dh.params, &physics, &q, &mut tau);
                let want = urdf_torques(&urdf, &chain, &q);
                for (j, (a, b)) in tau.iter().zip(&want).enumerate() {
                    assert!(
                        (a - b).abs() < 1e-9 * (1.0 + b.abs()),
                        "trial {trial} joint {j}: {a} vs {b}"
                    );
                }
            }
        }
    }

    /// The shipped URDFs' masses: the link after each joint, the gripper
    /// (and fingers) as the probe's, the base left out, gravity the base's
    /// −z; their centres where the URDF puts them at any reading.
    #[test]
    fn shipped_urdfs_carry_their_masses() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/mukca/urdf");
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        // Link after joint 2, the tool's mass, the base's.
        for (file, after_2, tool, base) in [
            (
                "gen3lite.urdf",
                1.17756164,
                0.1395 + 2.0 * (0.018385 + 0.010748),
                1.14608471,
            ),
            ("panda.urdf", 0.646926, 0.73 + 2.0 * 0.015, 0.629769),
        ] {
            let text = std::fs::read_to_string(dir.join(file)).unwrap();
            let urdf = parse_urdf(&text, file, UrdfOptions::default()).unwrap();
            let chain = urdf.chain(None, "ball_link").unwrap();
            let dh = chain.to_dh().unwrap();
            let p = &dh.masses;
            assert!((p.links[1].unwrap().kg - after_2).abs() < 1e-12, "{file}");
            assert!((p.tool.unwrap().kg - tool).abs() < 1e-12, "{file}");
            let left_out: Vec<f64> = (chain.masses.iter())
                .filter(|m| m.carrier == Carrier::Base)
                .map(|m| m.kg)
                .collect();
            assert_eq!(left_out, [base], "{file}");
            assert_eq!(p.gravity, None, "{file}: the D-H base is the URDF root");
            let worst = worst_com_mm(&urdf, &chain, &dh, &mut rng, 500);
            assert!(worst < 1e-6, "{file}: {worst} mm");
        }
    }

    #[test]
    fn bad_masses_are_located() {
        let parse = |links: &str| {
            let text = format!("<robot>\n{links}\n</robot>");
            parse_urdf(&text, "m.urdf", UrdfOptions::default())
        };
        let cases = [
            ("<link/>", "m.urdf:2: field `name`: missing on <link>"),
            (
                "<link name=\"a\">\n<inertial><origin xyz=\"0 0 0\"/></inertial></link>",
                "m.urdf:3: field `mass`: link `a`: <inertial> without <mass>",
            ),
            (
                "<link name=\"a\"><inertial>\n<mass/></inertial></link>",
                "m.urdf:3: field `mass`: link `a`: <mass> without `value`",
            ),
            (
                "<link name=\"a\"><inertial><mass value=\"-1\"/></inertial></link>",
                "m.urdf:2: field `mass`: link `a`: `-1` is not a mass (a finite number of kg, ≥ 0)",
            ),
            (
                "<link name=\"a\"><inertial><mass value=\"heavy\"/></inertial></link>",
                "m.urdf:2: field `mass`: link `a`: `heavy` is not a mass (a finite number of kg, ≥ 0)",
            ),
            (
                "<link name=\"a\"><inertial><mass value=\"inf\"/></inertial></link>",
                "m.urdf:2: field `mass`: link `a`: `inf` is not a mass (a finite number of kg, ≥ 0)",
            ),
            (
                "<link name=\"a\"><inertial>\n<origin xyz=\"0 0\"/><mass value=\"1\"/></inertial></link>",
                "m.urdf:3: field `xyz`: `0 0` is not three finite numbers",
            ),
            (
                "<link name=\"a\"><inertial>\n<origin rpy=\"0 x 0\"/><mass value=\"1\"/></inertial></link>",
                "m.urdf:3: field `rpy`: `0 x 0` is not three finite numbers",
            ),
            (
                "<link name=\"a\"/>\n<link name=\"a\"/>",
                "m.urdf:3: field `name`: link `a` is already defined (line 2); a URDF names each \
                 link once",
            ),
        ];
        for (links, message) in cases {
            let e = parse(links).unwrap_err();
            assert_eq!(e.to_string(), message);
            assert!(matches!(e, InputError::Field { .. }), "{e:?}");
        }
        // A link without <inertial> has no mass; a mass of 0 is a mass.
        let urdf = parse(
            "<link name=\"a\"/><link name=\"b\"><inertial><mass value=\"0\"/></inertial></link>",
        )
        .unwrap();
        assert_eq!(urdf.links[0].inertial, None);
        assert_eq!(urdf.links[1].inertial.map(|i| i.kg), Some(0.0));
        // Joints in a loop are refused, not followed forever.
        let text = r#"<robot>
            <joint name="j1" type="revolute"><parent link="a"/><child link="b"/></joint>
            <joint name="j2" type="revolute"><parent link="b"/><child link="a"/></joint>
            </robot>"#;
        let urdf = parse_urdf(text, "loop.urdf", UrdfOptions::default()).unwrap();
        let e = urdf.chain(None, "b").unwrap_err();
        assert!(e.to_string().contains("is on a loop of joints"), "{e}");
        // A chain without masses converts to an arm without any.
        let text = r#"<robot><link name="base"><inertial><mass value="2"/></inertial></link>
            <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
            <axis xyz="0 0 1"/></joint></robot>"#;
        let urdf = parse_urdf(text, "base.urdf", UrdfOptions::default()).unwrap();
        let chain = urdf.chain(None, "l1").unwrap();
        assert_eq!(chain.masses.len(), 1);
        assert_eq!(chain.to_dh().unwrap().masses, DhMasses::default());
    }

    /// Names, values and tips echoed in a message are bounded (cut to 80
    /// characters, their length said) and their control characters escaped,
    /// however long or garbled the file or the tip asked for.
    #[test]
    fn hostile_names_give_bounded_messages() {
        let long = "n".repeat(10_000);
        // A name with line breaks (as XML character references, the only
        // way an attribute keeps them) and a very long one.
        for name in ["a&#13;&#10;b", long.as_str()] {
            let link =
                |extra: &str| format!("<robot>\n<link name=\"{name}\">{extra}</link>\n</robot>");
            let joint = |kind: &str, body: &str| {
                format!("<robot>\n<joint name=\"{name}\" type=\"{kind}\">{body}</joint>\n</robot>")
            };
            let parts = "<parent link=\"base\"/><child link=\"tip\"/>";
            let texts = [
                format!("<robot>\n<link name=\"{name}\"/><link name=\"{name}\"/>\n</robot>"),
                link("<inertial><mass value=\"x\"/></inertial>"),
                link(&format!("<inertial><mass value=\"{name}\"/></inertial>")),
                link("<inertial/>"),
                link(&format!(
                    "<inertial><origin xyz=\"{name}\"/><mass value=\"1\"/></inertial>"
                )),
                joint("revolute", ""),
                joint("revolute", &format!("{parts}<axis xyz=\"0 0 0\"/>")),
                format!("<{}/>", name.replace("&#13;&#10;", "_")),
                format!(
                    "<robot><{0}></{0}x></robot>",
                    name.replace("&#13;&#10;", "_")
                ),
            ];
            let mut messages: Vec<String> = texts
                .iter()
                .map(|t| {
                    parse_urdf(t, "h.urdf", UrdfOptions::default())
                        .unwrap_err()
                        .to_string()
                })
                .collect();
            let urdf = parse_urdf(
                &joint(&format!("prismatic{name}"), parts),
                "h.urdf",
                UrdfOptions::default(),
            )
            .unwrap();
            messages.push(urdf.chain(None, "tip").unwrap_err().to_string());
            messages.push(urdf.chain(None, "t\r\n\0").unwrap_err().to_string());
            messages.push(urdf.chain(Some(&long), "tip").unwrap_err().to_string());
            for m in &messages {
                assert!(m.chars().count() < 600, "{} characters: {m:.700}", m.len());
                assert!(!m.contains(char::is_control), "{m:?}");
            }
            if name == long {
                let cut = messages.iter().filter(|m| m.contains("(10000 characters)"));
                assert!(cut.count() >= 8, "{messages:#?}");
            } else {
                assert!(
                    messages[0].contains("link `a\\r\\nb` is already defined"),
                    "{}",
                    messages[0]
                );
            }
        }
    }
}
