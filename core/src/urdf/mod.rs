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

mod chain;
mod dh;
mod parse;

pub use chain::{Carrier, Chain, ChainMass};
pub use dh::{DhConversion, DhMass, DhMasses, HAYATI_BEYOND_M};
pub use parse::parse_urdf;

#[cfg(test)]
mod tests;
