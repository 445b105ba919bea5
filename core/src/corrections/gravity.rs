//! Gravity torques about the joint axes: what loads a compliant joint.
//!
//! For a pose, the chain's frames are `T_0 = I` (the base) and `T_j =
//! T_{j−1}·A_j` (a D-H link `Rz(θ+q)·Tz(d)·Tx(a)·Rx(α)`, a Hayati link
//! `Rz(θ+q)·Tx(a)·Rx(α)·Ry(β)`); joint `j` turns about the z axis of
//! `T_{j−1}` through its origin `o_{j−1}`. Link `j` (after joint `j`) has
//! its centre of mass at `T_j·com` when stated, else halfway between
//! `o_{j−1}` and `o_j`; the tool's mass sits at the probe unless its `com`
//! (in the last frame) is stated. The torque of gravity about joint `j`,
//! from the masses outboard of it, is
//!
//! ```text
//! τ_j = z_{j−1} · Σ_{i ≥ j} (r_i − o_{j−1}) × m_i g
//!     = z_{j−1} · ((S_j − M_j o_{j−1}) × g),   S_j = Σ m_i r_i, M_j = Σ m_i
//! ```
//!
//! — linear in the joints, from running sums from the tip. Lengths are mm
//! inside, so the sum is N·mm and is returned in N·m.

use super::{Mass, Physics};
use crate::kernel::Scalar;
use crate::params::{DhJoint, DhParams, JointKind, JointModel};

/// Standard gravity, m/s².
pub(crate) const STANDARD_GRAVITY: f64 = 9.80665;

/// The numbers the torques are computed in: `f64`, one pose, or the
/// kernel's lanes ([`Batch`](crate::kernel::Batch)), four poses side by
/// side — each lane the same IEEE operations in the same order as one
/// pose, so the same bits.
pub(crate) trait Num: Scalar + std::ops::Div<Output = Self> {
    /// `v` in every lane.
    #[inline(always)]
    fn splat(v: f64) -> Self {
        Self::from(v)
    }
}

impl<T: Scalar + std::ops::Div<Output = T>> Num for T {}

/// A rigid transform: rotation (rows) and translation, mm.
#[derive(Clone, Copy)]
pub(crate) struct Pose3<T> {
    r: [[T; 3]; 3],
    t: [T; 3],
}

impl<T: Num> Pose3<T> {
    #[inline(always)]
    fn identity() -> Pose3<T> {
        let (o, z) = (T::splat(1.0), T::splat(0.0));
        Pose3 {
            r: [[o, z, z], [z, o, z], [z, z, o]],
            t: [z; 3],
        }
    }

    #[inline(always)]
    fn apply(&self, v: &[T; 3]) -> [T; 3] {
        // Written out (as below): `from_fn` of four-pose values was not
        // inlined.
        let (r, t) = (&self.r, &self.t);
        [
            dot(&r[0], v) + t[0],
            dot(&r[1], v) + t[1],
            dot(&r[2], v) + t[2],
        ]
    }

    #[inline(always)]
    fn then(&self, b: &Pose3<T>) -> Pose3<T> {
        Pose3 {
            // `(0..3).map(..).sum()` as it was: a float sum starts at −0.0,
            // and −0.0 + x is x, so it is `(x₀ + x₁) + x₂`.
            r: [
                self.row_times(0, b),
                self.row_times(1, b),
                self.row_times(2, b),
            ],
            t: self.apply(&b.t),
        }
    }

    /// Row `i` of `self.r · b.r`.
    #[inline(always)]
    fn row_times(&self, i: usize, b: &Pose3<T>) -> [T; 3] {
        let (a, r) = (&self.r[i], &b.r);
        let at = |j: usize| a[0] * r[0][j] + a[1] * r[1][j] + a[2] * r[2][j];
        [at(0), at(1), at(2)]
    }

    #[inline(always)]
    fn z(&self) -> [T; 3] {
        [self.r[0][2], self.r[1][2], self.r[2][2]]
    }
}

#[inline(always)]
fn dot<T: Num>(a: &[T; 3], b: &[T; 3]) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline(always)]
fn cross<T: Num>(a: &[T; 3], b: &[T; 3]) -> [T; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// A link's constants: everything but its joint's reading.
#[derive(Clone, Copy, Debug)]
struct Link {
    /// cos and sin of the zero offset θ.
    ct: f64,
    st: f64,
    ca: f64,
    sa: f64,
    /// cos and sin of a Hayati joint's β (1, 0 for a D-H joint).
    cb: f64,
    sb: f64,
    a: f64,
    d: f64,
    hayati: bool,
    /// A slide: its reading adds to `d`, its angle is θ alone.
    prismatic: bool,
}

impl Link {
    fn new(j: &DhJoint) -> Link {
        let (st, ct) = j.theta.sin_cos();
        let (sa, ca) = j.alpha.sin_cos();
        let hayati = j.model == JointModel::Hayati;
        let (sb, cb) = if hayati { j.beta.sin_cos() } else { (0.0, 1.0) };
        Link {
            ct,
            st,
            ca,
            sa,
            cb,
            sb,
            a: j.a,
            d: if hayati { 0.0 } else { j.d },
            hayati,
            prismatic: j.kind == JointKind::Prismatic,
        }
    }

    /// The link's transform at a reading with cos `cq` and sin `sq`: the
    /// joint angle `q + θ` through the angle sum, no transcendental call.
    /// A prismatic joint's reading (mm) comes as `cq` (`sq` unused): its
    /// angle is θ, its offset `d + q`.
    #[inline(always)]
    fn at<T: Num>(&self, cq: T, sq: T) -> Pose3<T> {
        let k = T::splat;
        let (ct, st, d) = if self.prismatic {
            (k(self.ct), k(self.st), k(self.d) + cq)
        } else {
            (
                cq * k(self.ct) - sq * k(self.st),
                sq * k(self.ct) + cq * k(self.st),
                k(self.d),
            )
        };
        let (ca, sa) = (k(self.ca), k(self.sa));
        let a = Pose3 {
            r: [
                [ct, -ca * st, sa * st],
                [st, ca * ct, -sa * ct],
                [k(0.0), sa, ca],
            ],
            t: [k(self.a) * ct, k(self.a) * st, d],
        };
        if !self.hayati {
            return a;
        }
        a.then(&Pose3 {
            r: [
                [k(self.cb), k(0.0), k(self.sb)],
                [k(0.0), k(1.0), k(0.0)],
                [-k(self.sb), k(0.0), k(self.cb)],
            ],
            t: [k(0.0); 3],
        })
    }
}

/// Gravity `g` (m/s², in the base frame) of `physics`: its stated
/// direction scaled to [`STANDARD_GRAVITY`], else −z.
pub(crate) fn gravity_vector(physics: &Physics) -> [f64; 3] {
    let dir = physics.gravity.unwrap_or([0.0, 0.0, -1.0]);
    let norm = dot(&dir, &dir).sqrt();
    dir.map(|v| STANDARD_GRAVITY * v / norm)
}

/// An arm's chain and masses, prepared once for the gravity torques of
/// many poses.
#[derive(Clone, Debug)]
pub(crate) struct Loads {
    links: Vec<Link>,
    probe: [f64; 3],
    masses: Vec<Option<Mass>>,
    tool: Option<Mass>,
    g: [f64; 3],
}

impl Loads {
    /// The loads of `physics`' masses on the chain of `arm`.
    pub(crate) fn new(arm: &DhParams, physics: &Physics) -> Loads {
        Loads {
            links: arm.joints.iter().map(Link::new).collect(),
            probe: arm.probe,
            masses: physics.link_masses.clone(),
            tool: physics.probe_mass,
            g: gravity_vector(physics),
        }
    }

    /// Gravity torque about each joint's axis (N·m) into `out`, at the
    /// pose whose readings have cos `cq(j)` and sin `sq(j)` (a prismatic
    /// joint's reading, mm, as `cq(j)`). A prismatic joint's entry is the
    /// gravity force along its axis, N (what presses a slide's flank: its
    /// backlash follows it; the compliance model refuses slides).
    #[inline(always)]
    pub(crate) fn torques<T: Num>(
        &self,
        cq: impl Fn(usize) -> T,
        sq: impl Fn(usize) -> T,
        out: &mut [T],
    ) {
        self.torques_with(cq, sq, out, &mut Vec::new());
    }

    /// [`Loads::torques`] with the chain's frames in `frames`, kept by a
    /// caller of many poses.
    #[inline(always)]
    pub(crate) fn torques_with<T: Num>(
        &self,
        cq: impl Fn(usize) -> T,
        sq: impl Fn(usize) -> T,
        out: &mut [T],
        frames: &mut Vec<Pose3<T>>,
    ) {
        let n = self.links.len();
        let k = T::splat;
        // Frames o_0..o_n (origins and the z axes of 0..n−1) and the
        // masses' centres, base to tip.
        frames.resize(n + 1, Pose3::identity());
        frames[0] = Pose3::identity();
        for (j, link) in self.links.iter().enumerate() {
            frames[j + 1] = frames[j].then(&link.at(cq(j), sq(j)));
        }
        let centre = |m: &Mass, frame: &Pose3<T>, default: [T; 3]| match m.com_mm {
            Some(c) => frame.apply(&c.map(k)),
            None => default,
        };
        // Running sums from the tip: S = Σ m r (kg·mm), M = Σ m (kg).
        let (mut s, mut m) = ([k(0.0); 3], k(0.0));
        if let Some(tool) = &self.tool {
            let tip = frames[n].apply(&self.probe.map(k));
            let r = centre(tool, &frames[n], tip);
            s = r.map(|v| k(tool.kg) * v);
            m = k(tool.kg);
        }
        let g = self.g.map(k);
        for j in (0..n).rev() {
            if let Some(Some(link)) = self.masses.get(j) {
                let (a, b) = (frames[j].t, frames[j + 1].t);
                let half = |i: usize| k(0.5) * (a[i] + b[i]);
                let mid = [half(0), half(1), half(2)];
                let r = centre(link, &frames[j + 1], mid);
                for i in 0..3 {
                    s[i] = s[i] + k(link.kg) * r[i];
                }
                m = m + k(link.kg);
            }
            let z = frames[j].z();
            out[j] = if self.links[j].prismatic {
                // A slide carries the force along its axis, not a torque.
                m * dot(&z, &g)
            } else {
                let o = frames[j].t;
                let lever = |i: usize| s[i] - m * o[i];
                let arm_of: [T; 3] = [lever(0), lever(1), lever(2)];
                dot(&z, &cross(&arm_of, &g)) / k(1000.0)
            };
        }
    }
}

/// Gravity torque about each joint's axis at readings `q` (rad; mm for a
/// prismatic joint), N·m (a slide's: the force along it, N), into `out` (one per joint): [`Loads::torques`]
/// of one pose.
#[cfg(test)]
pub(crate) fn torques(arm: &DhParams, physics: &Physics, q: &[f64], out: &mut [f64]) {
    let loads = Loads::new(arm, physics);
    let slides = |j: usize| arm.joints[j].kind == JointKind::Prismatic;
    let cq = |j: usize| if slides(j) { q[j] } else { q[j].cos() };
    let sq = |j: usize| if slides(j) { 0.0 } else { q[j].sin() };
    loads.torques(cq, sq, out);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::corrections::Mass;

    /// A horizontal two-link planar arm (a = 500 mm each, axes along z
    /// tilted to be horizontal by gravity along −y): 1 kg at each link's
    /// middle loads joint 1 with 1 kg·250 mm + 1 kg·750 mm.
    #[test]
    fn torques_are_lever_arms_times_weights() {
        let joint = DhJoint::dh(500.0, 0.0, 0.0, 0.0);
        let mut arm = DhParams::paper_nominal();
        arm.joints = vec![joint; 6];
        for j in &mut arm.joints[2..] {
            j.a = 0.0;
        }
        let physics = Physics {
            link_masses: vec![
                Some(Mass::at_middle(1.0)),
                Some(Mass::at_middle(1.0)),
                None,
                None,
                None,
                None,
            ],
            gravity: Some([0.0, -1.0, 0.0]),
            ..Physics::default()
        };
        let mut tau = [0.0; 6];
        torques(&arm, &physics, &[0.0; 6], &mut tau);
        // Links along +x, gravity along −y: torque about +z is negative.
        let expect = -STANDARD_GRAVITY * (0.25 + 0.75);
        assert!((tau[0] - expect).abs() < 1e-12, "{tau:?}");
        assert!((tau[1] + STANDARD_GRAVITY * 0.25).abs() < 1e-12);
        assert_eq!(tau[2], 0.0);
        // Turned a quarter up, the links hang along the gravity: no torque.
        torques(
            &arm,
            &physics,
            &[-std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, 0.0, 0.0],
            &mut tau,
        );
        assert!(tau[0].abs() < 1e-12 && tau[1].abs() < 1e-12);
    }

    /// A prismatic joint's reading moves its link along the previous z
    /// axis: the loads of a slide at `s` are those of the same link made
    /// revolute with `d + s` at a zero reading.
    #[test]
    fn a_slide_moves_its_link() {
        let mut arm = DhParams::paper_nominal();
        arm.joints[1] = arm.joints[1].with_kind(JointKind::Prismatic);
        let physics = Physics {
            link_masses: vec![Some(Mass::at_middle(2.0)); 6],
            probe_mass: Some(Mass::at_middle(0.5)),
            // Across the first joint's axis, so that it carries a load.
            gravity: Some([0.0, -1.0, 0.0]),
            ..Physics::default()
        };
        let q = [0.3, 120.0, -0.4, 0.5, 1.1, -0.2];
        let mut tau = [0.0; 6];
        torques(&arm, &physics, &q, &mut tau);
        let mut turned = arm.clone();
        turned.joints[1].kind = JointKind::Revolute;
        turned.joints[1].d += 120.0;
        let mut want = [0.0; 6];
        torques(
            &turned,
            &physics,
            &[0.3, 0.0, -0.4, 0.5, 1.1, -0.2],
            &mut want,
        );
        for (j, (t, w)) in tau.iter().zip(&want).enumerate() {
            // The slide's own entry is a force, not the torque.
            assert!(j == 1 || (t - w).abs() < 1e-9, "{tau:?} vs {want:?}");
        }
        // The slide changes the first joint's load (its lever arm).
        let mut other = [0.0; 6];
        torques(
            &arm,
            &physics,
            &[0.3, 320.0, -0.4, 0.5, 1.1, -0.2],
            &mut other,
        );
        assert!((other[0] - tau[0]).abs() > 1e-3, "{tau:?} vs {other:?}");
        // The slide carries the weight outboard of it along its axis (the
        // axis of joint 2 turns with joint 1, about z, across the gravity
        // along −y): its entry does not change with the slide's reading.
        let weight = 10.5 * STANDARD_GRAVITY;
        assert!((other[1] - tau[1]).abs() < 1e-9 && tau[1].abs() <= weight + 1e-9);
        let mut z = [0.0; 6];
        let mut straight = physics.clone();
        straight.gravity = Some([0.0, 0.0, -1.0]);
        torques(&arm, &straight, &q, &mut z);
        // Joint 1's axis is z: the slide's axis (α1 = −90°) lies in the
        // horizontal plane, no weight along it.
        assert!(z[1].abs() < 1e-9 * weight, "{z:?}");
    }
}
