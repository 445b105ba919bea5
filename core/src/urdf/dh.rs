//! A URDF chain as a D-H arm: each joint's frame from its axis and the
//! previous one (Hayati's where axes are parallel), and the chain's masses
//! in those frames.

use super::chain::Step;
use super::*;

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
