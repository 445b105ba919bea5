//! The kinematic kernel: closed-form probe position, tool pose and their
//! Jacobians of any serial chain of 1 to 12 revolute and prismatic joints,
//! behind one runtime-sized type, [`ArmKernel`], that every caller uses.
//!
//! The common shapes ([`SHIPPED_SHAPES`]: 6R, 7R, a track before 6R and
//! 7R, SCARA, 5R) have kernels expanded at compile time by `dh_chain!`, a
//! D-H one and an extended one (for arms with Hayati joints) each; every
//! other chain runs through [`Generic`], closed-form per link. A user's own
//! shape can be generated in their crate with [`dh_kernel!`](crate::dh_kernel)
//! and handed over with [`ArmKernel::with_chain`].
//!
//! Trig is split by how often it changes: sin/cos of the encoder readings once
//! per data set ([`PreparedPoses`]; a prismatic joint's reading is used as it
//! is), of the zero offsets and twists once per parameter set (inside
//! [`ArmKernel`]); the per-pose code only multiplies and adds. Batches run
//! four poses at a time in SIMD lanes (a crate-private module: nothing
//! outside the crate can run a lane instruction the CPU might lack); the
//! lanes do exactly the scalar operations, so results are bit-identical to
//! the one-pose functions whatever the CPU.
//!
//! The const-generic layer below [`ArmKernel`] ([`Chain`],
//! [`PreparedParams`], [`position`], [`joint_jacobian`]) is public for
//! oracles, tests and users' chains.
//!
//! ```compile_fail
//! // The SIMD lanes are not reachable from outside the crate.
//! use aacmm_core::kernel::lanes::Avx;
//! ```

mod arm;
mod batch;
mod generic;
mod lanes;
mod poses;

use std::ops::{Add, Mul, Neg, Sub};

use thiserror::Error;

pub use crate::params::ChainShape;
use crate::params::{DhParams, JointKind, JointModel};

pub use arm::{ArmKernel, KernelKind, SHIPPED_SHAPES};
pub(crate) use batch::FreeRows;
pub use batch::Jacobians;
pub use generic::Generic;
/// The portable lanes, for tests that run a lane loop on them whatever
/// the CPU has.
#[cfg(test)]
pub(crate) use lanes::Lanes;
/// The token-gated lanes, for batch loops outside the kernel (the plan's
/// rank-3 updates, the position term's cost, the gravity torques): the
/// same bits on any lane type.
pub(crate) use lanes::{Batch, LANES, LaneOp, run as run_lanes, to_arrays};
pub(crate) use poses::Post;
pub use poses::PreparedPoses;

/// Wrong shapes handed to the kernel.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum KernelError {
    /// The arm and the data disagree on the number of joints.
    #[error("the arm has {expected} joints but the data has {got}")]
    JointCount {
        /// The arm's joints.
        expected: usize,
        /// The data's joints.
        got: usize,
    },
    /// A parameter vector of the wrong length.
    #[error("expected {expected} parameters, got {got}")]
    ParamCount {
        /// Parameters of the arm.
        expected: usize,
        /// Parameters given.
        got: usize,
    },
    /// No kernel for this many joints.
    #[error(
        "no kernel for {0} joints: the toolkit computes {text}",
        text = crate::params::supported_joints_text()
    )]
    Unsupported(usize),
    /// The arm and the data (or a chain type) disagree on which joints
    /// are prismatic.
    #[error("the arm's chain is {expected} but {what} is {got}")]
    Shape {
        /// The arm's shape.
        expected: ChainShape,
        /// The other's.
        got: ChainShape,
        /// What the other is: `the data`, `the chain type`.
        what: &'static str,
    },
    /// A chain type that cannot compute the arm's Hayati joints (a
    /// D-H-only generated chain, `hayati = false`).
    #[error("the chain type computes D-H joints only, and joint {joint} is Hayati")]
    NotExtended {
        /// The first Hayati joint, 1-based.
        joint: usize,
    },
    /// An output buffer of the wrong length.
    #[error("output holds {got} entries, {expected} needed")]
    OutputLength {
        /// Entries needed.
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// A pose range beyond the data.
    #[error("poses {start}..{end} requested of {len}")]
    Range {
        /// First pose requested.
        start: usize,
        /// One past the last pose requested.
        end: usize,
        /// Poses available.
        len: usize,
    },
    /// The stated noise gives weights that are not finite numbers (a σ so
    /// large that its square overflows, or so small that it vanishes): the
    /// message names the noise concerned.
    #[error("{message}")]
    Noise {
        /// Which weights: the touches' (encoder and probe noise) or a
        /// reference length's (its uncertainty, or the length weight).
        of: NoiseOf,
        /// What is wrong, with the values concerned.
        message: String,
    },
}

/// Which noise made weights that are not finite (see [`KernelError::Noise`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoiseOf {
    /// The touches': encoder and probe noise, or the assumed touch σ.
    Touches,
    /// A reference length's: its uncertainty or the length weight.
    Lengths,
}

/// What the generated code computes with: `f64`, SIMD lanes, dual numbers.
pub trait Scalar:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self> + From<f64>
{
}

impl<S> Scalar for S where
    S: Copy + Add<Output = S> + Sub<Output = S> + Mul<Output = S> + Neg<Output = S> + From<f64>
{
}

/// Per-parameter-set inputs of the generated code: lengths (mm) and the
/// sin/cos of the zero offsets and twists; for the extended chain also the
/// sin/cos of the Hayati rotations and which joints are Hayati (the D-H
/// chain ignores those); which joints are prismatic (read by [`Generic`];
/// a generated chain knows its own).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Consts<S, const N: usize> {
    /// cos θ⁰.
    pub ct: [S; N],
    /// sin θ⁰.
    pub st: [S; N],
    /// cos α.
    pub ca: [S; N],
    /// sin α.
    pub sa: [S; N],
    /// a, mm.
    pub a: [S; N],
    /// d, mm (0 for a Hayati joint; a prismatic joint's reading adds to it).
    pub d: [S; N],
    /// cos β (1 for a D-H joint).
    pub cb: [S; N],
    /// sin β (0 for a D-H joint).
    pub sb: [S; N],
    /// Whether joint `i` is Hayati: its d-slot's Jacobian column is `∂p/∂β`.
    pub hayati: [bool; N],
    /// Whether joint `i` is prismatic.
    pub prismatic: [bool; N],
    /// Probe offset, mm.
    pub b: [S; 3],
}

/// A parameter set prepared for the kernel: trig computed once.
pub type PreparedParams<const N: usize> = Consts<f64, N>;

/// `v` in scalar type `S`, one value per lane set; inlined into its caller
/// (see [`Consts::splat`]).
#[inline(always)]
fn each<S: From<f64> + Copy, const M: usize>(v: &[f64; M]) -> [S; M] {
    let mut out = [S::from(0.0); M];
    for (o, &x) in out.iter_mut().zip(v) {
        *o = S::from(x);
    }
    out
}

impl<const N: usize> Consts<f64, N> {
    /// Prepares `params`; fails if the arm does not have `N` joints.
    ///
    /// ```
    /// use aacmm_core::{kernel::PreparedParams, params::DhParams};
    /// let k = PreparedParams::<6>::new(&DhParams::paper_nominal()).unwrap();
    /// assert_eq!(k.ca[0], (-std::f64::consts::FRAC_PI_2).cos());
    /// assert!(PreparedParams::<7>::new(&DhParams::paper_nominal()).is_err());
    /// ```
    pub fn new(params: &DhParams) -> Result<Self, KernelError> {
        if params.joint_count() != N {
            return Err(KernelError::JointCount {
                expected: N,
                got: params.joint_count(),
            });
        }
        let j = &params.joints;
        let hayati: [bool; N] = std::array::from_fn(|i| j[i].model == JointModel::Hayati);
        // The structural zeros: d of a Hayati joint, β of a D-H joint.
        let beta: [f64; N] = std::array::from_fn(|i| if hayati[i] { j[i].beta } else { 0.0 });
        Ok(Consts {
            ct: std::array::from_fn(|i| j[i].theta.cos()),
            st: std::array::from_fn(|i| j[i].theta.sin()),
            ca: std::array::from_fn(|i| j[i].alpha.cos()),
            sa: std::array::from_fn(|i| j[i].alpha.sin()),
            a: std::array::from_fn(|i| j[i].a),
            d: std::array::from_fn(|i| if hayati[i] { 0.0 } else { j[i].d }),
            cb: beta.map(f64::cos),
            sb: beta.map(f64::sin),
            hayati,
            prismatic: std::array::from_fn(|i| j[i].kind == JointKind::Prismatic),
            b: params.probe,
        })
    }

    /// Whether some joint is Hayati, so that only an extended chain
    /// computes this arm.
    pub(crate) fn has_hayati(&self) -> bool {
        self.hayati.contains(&true)
    }

    /// The prismatic joints: bit `i` for joint `i`.
    pub(crate) fn prismatic_mask(&self) -> u16 {
        (self.prismatic.iter().enumerate())
            .filter(|(_, p)| **p)
            .fold(0, |m, (i, _)| m | (1 << i))
    }

    /// The same constants in another scalar type (every lane the same).
    /// Inlined, with a loop of its own rather than `array::map`: out of
    /// line it was compiled without the batch loop's target features, so
    /// each of its AVX broadcasts was a call (2 % of a 10⁴-touch fit).
    #[inline(always)]
    pub(crate) fn splat<S: From<f64> + Copy>(&self) -> Consts<S, N> {
        Consts {
            ct: each(&self.ct),
            st: each(&self.st),
            ca: each(&self.ca),
            sa: each(&self.sa),
            a: each(&self.a),
            d: each(&self.d),
            cb: each(&self.cb),
            sb: each(&self.sb),
            hayati: self.hayati,
            prismatic: self.prismatic,
            b: each(&self.b),
        }
    }

    /// The per-pose inputs of readings `q`: a revolute joint's cos and sin,
    /// a prismatic joint's reading (mm) and 0.
    #[inline(always)]
    pub fn joint_inputs(&self, q: &[f64; N]) -> ([f64; N], [f64; N]) {
        let mut c = [0.0; N];
        let mut s = [0.0; N];
        for j in 0..N {
            (c[j], s[j]) = if self.prismatic[j] {
                (q[j], 0.0)
            } else {
                (q[j].cos(), q[j].sin())
            };
        }
        (c, s)
    }
}

/// The functions of an `N`-joint chain, generic over the scalar: what
/// `dh_chain!`'s marker types (`…::Kernel`) and [`Generic`] implement, and
/// what [`ArmKernel`] runs.
///
/// Per pose every function takes `cq`, `sq`: for a revolute joint the cos
/// and sin of its reading, for a prismatic joint its reading (mm) in `cq`
/// (its `sq` is not read). A 6-row column is the position's derivative (3
/// rows) above the small rotation `ω` with `δR = [ω]× R` in the base frame;
/// a pose is the top three rows `[R | p]` of the tool's homogeneous
/// transform (`R` the last frame's axes as columns, `p` the probe, mm).
pub trait Chain<const N: usize> {
    /// The prismatic joints (bit `i` for joint `i`) of the one shape this
    /// chain computes; `None` when it computes any shape of `N` joints
    /// (reading [`Consts::prismatic`]).
    const PRISMATIC: Option<u16>;
    /// Whether it computes Hayati joints (every link ends in `Ry(β)`).
    const EXTENDED: bool;
    /// Number of geometric parameters, `4N + 3`.
    const PARAMS: usize = 4 * N + 3;
    /// Probe position (mm).
    fn position<S: Scalar>(k: &Consts<S, N>, cq: &[S; N], sq: &[S; N]) -> [S; 3];
    /// Probe position and `∂p/∂parameter` into `jac` (`PARAMS` columns).
    fn position_jacobian<S: Scalar>(
        k: &Consts<S, N>,
        cq: &[S; N],
        sq: &[S; N],
        jac: &mut [[S; 3]],
    ) -> [S; 3];
    /// Probe position and `∂p/∂q` into `jac`.
    fn joint_jacobian<S: Scalar>(
        k: &Consts<S, N>,
        cq: &[S; N],
        sq: &[S; N],
        jac: &mut [[S; 3]; N],
    ) -> [S; 3];
    /// The tool pose `[R | p]`.
    fn pose<S: Scalar>(k: &Consts<S, N>, cq: &[S; N], sq: &[S; N]) -> [[S; 4]; 3];
    /// The tool pose and its 6-row parameter Jacobian (`PARAMS` columns).
    fn pose_jacobian<S: Scalar>(
        k: &Consts<S, N>,
        cq: &[S; N],
        sq: &[S; N],
        jac: &mut [[S; 6]],
    ) -> [[S; 4]; 3];
    /// The tool pose and its 6-row joint Jacobian.
    fn joint_pose_jacobian<S: Scalar>(
        k: &Consts<S, N>,
        cq: &[S; N],
        sq: &[S; N],
        jac: &mut [[S; 6]; N],
    ) -> [[S; 4]; 3];
}

/// Whether chain `C` computes an arm of these constants: its shape, and
/// Hayati joints only if it is extended.
pub(crate) fn computes<const N: usize, C: Chain<N>>(
    k: &PreparedParams<N>,
) -> Result<(), KernelError> {
    let shape = |m| ChainShape::from_mask(N, m).map_err(|_| KernelError::Unsupported(N));
    let arm = shape(k.prismatic_mask())?;
    if let Some(mask) = C::PRISMATIC
        && mask != k.prismatic_mask()
    {
        return Err(KernelError::Shape {
            expected: arm,
            got: shape(mask)?,
            what: "the chain type",
        });
    }
    match k.hayati.iter().position(|&h| h) {
        Some(i) if !C::EXTENDED => Err(KernelError::NotExtended { joint: i + 1 }),
        _ => Ok(()),
    }
}

/// The tool's pose: the orientation of its frame (the last link's axes)
/// and the probe's position, in the arm's base frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pose {
    /// Row-major rotation: `rotation[r][c]` is row `r` of the tool's axis
    /// `c` (x, y, z), so `R·v` turns a vector from tool to base frame.
    pub rotation: [[f64; 3]; 3],
    /// The probe's position, mm.
    pub position: [f64; 3],
}

impl Pose {
    /// From the top three rows of the homogeneous transform, `[R | p]`.
    #[inline(always)]
    pub fn from_transform(t: [[f64; 4]; 3]) -> Pose {
        Pose {
            rotation: t.map(|row| [row[0], row[1], row[2]]),
            position: t.map(|row| row[3]),
        }
    }

    /// The rotation as a unit quaternion `[w, x, y, z]`, with the sign
    /// that makes `w ≥ 0` (and, when `w` is 0, the first nonzero of `x, y,
    /// z` positive): one quaternion per orientation, so equal orientations
    /// print equal. Shepperd's method: from the largest of the trace and
    /// the diagonal, so no component is found by a difference of nearly
    /// equal numbers.
    ///
    /// ```
    /// use aacmm_core::kernel::Pose;
    /// // A half turn about z: w = 0, z = 1.
    /// let r = Pose { rotation: [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]], position: [0.0; 3] };
    /// assert_eq!(r.quaternion(), [0.0, 0.0, 0.0, 1.0]);
    /// // A quarter turn about x.
    /// let r = Pose { rotation: [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]], position: [0.0; 3] };
    /// let q = r.quaternion();
    /// let h = std::f64::consts::FRAC_1_SQRT_2;
    /// assert!((q[0] - h).abs() < 1e-15 && (q[1] - h).abs() < 1e-15 && q[2] == 0.0 && q[3] == 0.0);
    /// ```
    pub fn quaternion(&self) -> [f64; 4] {
        let m = &self.rotation;
        let trace = m[0][0] + m[1][1] + m[2][2];
        let q = if trace >= m[0][0].max(m[1][1]).max(m[2][2]) {
            let w4 = 2.0 * (1.0 + trace).max(0.0).sqrt();
            [
                w4 / 4.0,
                (m[2][1] - m[1][2]) / w4,
                (m[0][2] - m[2][0]) / w4,
                (m[1][0] - m[0][1]) / w4,
            ]
        } else if m[0][0] >= m[1][1] && m[0][0] >= m[2][2] {
            let x4 = 2.0 * (1.0 + m[0][0] - m[1][1] - m[2][2]).max(0.0).sqrt();
            [
                (m[2][1] - m[1][2]) / x4,
                x4 / 4.0,
                (m[0][1] + m[1][0]) / x4,
                (m[0][2] + m[2][0]) / x4,
            ]
        } else if m[1][1] >= m[2][2] {
            let y4 = 2.0 * (1.0 - m[0][0] + m[1][1] - m[2][2]).max(0.0).sqrt();
            [
                (m[0][2] - m[2][0]) / y4,
                (m[0][1] + m[1][0]) / y4,
                y4 / 4.0,
                (m[1][2] + m[2][1]) / y4,
            ]
        } else {
            let z4 = 2.0 * (1.0 - m[0][0] - m[1][1] + m[2][2]).max(0.0).sqrt();
            [
                (m[1][0] - m[0][1]) / z4,
                (m[0][2] + m[2][0]) / z4,
                (m[1][2] + m[2][1]) / z4,
                z4 / 4.0,
            ]
        };
        // Rounding leaves R a hair off orthonormal: normalise.
        let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        let q = q.map(|v| v / norm);
        let flip = match q.iter().find(|v| **v != 0.0) {
            Some(first) => *first < 0.0,
            None => false,
        };
        // −0 prints as "-0.000…": add +0 so a zero component is +0.
        q.map(|v| if flip { -v } else { v } + 0.0)
    }

    /// This pose as seen through `post` at pose `i`: the position scaled
    /// and moved, the orientation unchanged.
    pub(crate) fn after(&self, post: &Post, i: usize) -> Pose {
        Pose {
            rotation: self.rotation,
            position: post.at(i, &self.position),
        }
    }
}

/// Probe position of one pose with readings `q` (rad; mm for a prismatic
/// joint) on chain `C`.
///
/// ```
/// use aacmm_core::{kernel, params::DhParams};
/// aacmm_core::dh_kernel! { pub mod arm6 { joints = "RRRRRR" } }
/// let k = kernel::PreparedParams::<6>::new(&DhParams::paper_nominal()).unwrap();
/// let p = kernel::position::<arm6::Kernel, 6>(&k, &[0.0; 6]);
/// assert!((p[2] - 995.0).abs() < 1e-9);
/// ```
pub fn position<C: Chain<N>, const N: usize>(k: &PreparedParams<N>, q: &[f64; N]) -> [f64; 3] {
    let (cq, sq) = k.joint_inputs(q);
    C::position(k, &cq, &sq)
}

/// Probe position and `∂p/∂q` of one pose on chain `C`; what inverse
/// kinematics needs.
///
/// ```
/// use aacmm_core::{kernel::{self, Generic}, params::DhParams};
/// let k = kernel::PreparedParams::<6>::new(&DhParams::paper_nominal()).unwrap();
/// let (_, jq) = kernel::joint_jacobian::<Generic, 6>(&k, &[0.0; 6]);
/// assert!((jq[0][1] + 5.0).abs() < 1e-9); // joint 1 moves the probe along −y
/// ```
pub fn joint_jacobian<C: Chain<N>, const N: usize>(
    k: &PreparedParams<N>,
    q: &[f64; N],
) -> ([f64; 3], [[f64; 3]; N]) {
    let mut jac = [[0.0; 3]; N];
    let (cq, sq) = k.joint_inputs(q);
    let p = C::joint_jacobian(k, &cq, &sq, &mut jac);
    (p, jac)
}

/// Generates the kernel of a chain of any shape in the caller's crate, as
/// a module whose marker type `Kernel` implements
/// [`kernel::Chain`](crate::kernel::Chain) and so can be handed to
/// [`ArmKernel::with_chain`](crate::kernel::ArmKernel::with_chain): the
/// same closed-form code the library's shipped shapes have. The settings
/// are `dh_chain!`'s: `joints = "RPRRR"` (or `joints = N`, all revolute),
/// and `hayati = true` for the extended chain, which also computes arms
/// with Hayati joints.
///
/// ```
/// aacmm_core::dh_kernel! {
///     /// A gantry with a wrist.
///     pub mod gantry { joints = "PPPR" }
/// }
/// use aacmm_core::{kernel::ArmKernel, params::{DhJoint, DhParams, JointKind}};
/// let slide = |alpha: f64| DhJoint::dh(0.0, 0.0, alpha, 0.0).with_kind(JointKind::Prismatic);
/// let h = std::f64::consts::FRAC_PI_2;
/// let arm = DhParams {
///     joints: vec![slide(-h), slide(h), slide(0.0), DhJoint::dh(0.0, 0.0, 0.0, 0.0)],
///     probe: [0.0, 0.0, 50.0],
/// };
/// let mine = ArmKernel::with_chain::<gantry::Kernel, 4>(&arm).unwrap();
/// let q = [100.0, 200.0, 300.0, 0.3];
/// assert_eq!(mine.position(&q).unwrap(), ArmKernel::new(&arm).unwrap().position(&q).unwrap());
/// ```
#[macro_export]
macro_rules! dh_kernel {
    ($(#[$m:meta])* $vis:vis mod $name:ident { $($body:tt)* }) => {
        $crate::kernel::__dh_chain! {
            $(#[$m])* $vis mod $name { core = $crate, $($body)* }
        }
    };
}

#[doc(hidden)]
pub use aacmm_dh_macros::dh_chain as __dh_chain;

#[cfg(test)]
mod tests {
    use super::arm::shipped::{arm6, arm6h, scara, scarah, track6, track6h};
    use super::batch::{
        for_each_lane_free_jacobian, for_each_lane_jacobian, for_each_lane_pose_jacobian,
        jacobians_impl, poses_impl, positions_impl,
    };
    use super::lanes::Lanes;
    use super::*;
    use crate::params::DhJoint;

    /// The portable lanes (what CPUs without AVX2 run) give the one-pose
    /// results bit for bit, like the AVX path the integration tests see
    /// here: the generated chains of 6R, a track and 7R and a SCARA, D-H
    /// and extended, and the generic chain of each.
    #[test]
    fn portable_lanes_equal_single_poses() {
        let mut hayati = DhParams::paper_nominal();
        hayati.joints[1].model = JointModel::Hayati;
        hayati.joints[1].beta = 0.01;
        let six = DhParams::paper_nominal();
        same_bits::<arm6::Kernel, 6>(&six);
        same_bits::<arm6h::Kernel, 6>(&hayati);
        same_bits::<Generic, 6>(&six);
        same_bits::<Generic, 6>(&hayati);
        let track = track(&six);
        same_bits::<track6::Kernel, 7>(&track);
        same_bits::<Generic, 7>(&track);
        let mut track_h = track.clone();
        track_h.joints[0].model = JointModel::Hayati;
        track_h.joints[0].beta = -0.02;
        same_bits::<track6h::Kernel, 7>(&track_h);
        same_bits::<Generic, 7>(&track_h);
        let scara_arm = scara_arm();
        same_bits::<scara::Kernel, 4>(&scara_arm);
        same_bits::<Generic, 4>(&scara_arm);
        let mut scara_h = scara_arm.clone();
        scara_h.joints[1].model = JointModel::Hayati;
        scara_h.joints[1].beta = 0.003;
        same_bits::<scarah::Kernel, 4>(&scara_h);
        same_bits::<Generic, 4>(&scara_h);
    }

    /// `arm` on a linear track along the base's x axis.
    fn track(arm: &DhParams) -> DhParams {
        let h = std::f64::consts::FRAC_PI_2;
        let slide = DhJoint::dh(0.0, 0.0, h, h).with_kind(JointKind::Prismatic);
        let mut joints = vec![slide];
        joints.extend(arm.joints.iter().copied());
        DhParams {
            joints,
            probe: arm.probe,
        }
    }

    fn scara_arm() -> DhParams {
        let quill = DhJoint::dh(0.0, -20.0, 0.0, 0.0).with_kind(JointKind::Prismatic);
        DhParams {
            joints: vec![
                DhJoint::dh(350.0, 400.0, 0.0, 0.0),
                DhJoint::dh(300.0, 0.0, std::f64::consts::PI, 0.0),
                quill,
                DhJoint::dh(0.0, 50.0, 0.0, 0.0),
            ],
            probe: [1.0, 2.0, 30.0],
        }
    }

    fn same_bits<C: Chain<N>, const N: usize>(params: &DhParams) {
        let k = PreparedParams::<N>::new(params).unwrap();
        let shape = params.shape().unwrap();
        // 15 poses: a pair of batches, an odd batch and a tail of three.
        let q: Vec<[f64; N]> = (0..15)
            .map(|i| {
                std::array::from_fn(|j| {
                    let v = ((i * 5 + j) as f64 * 0.61).sin();
                    if shape.is_prismatic(j) {
                        300.0 * v
                    } else {
                        3.0 * v
                    }
                })
            })
            .collect();
        let poses = PreparedPoses::for_shape(shape, &q).unwrap();
        let mut pos = vec![[0.0; 3]; q.len()];
        positions_impl::<N, C, Lanes>(&k, &poses, 0, &mut pos);
        // From pose 1: one pair of batches and a tail of two.
        let mut from_one = vec![[0.0; 3]; 10];
        positions_impl::<N, C, Lanes>(&k, &poses, 1, &mut from_one);
        assert_eq!(from_one, pos[1..11]);
        let mut tools = vec![Pose::default(); q.len()];
        poses_impl::<N, C, Lanes>(&k, &poses, 0, &mut tools);
        let mut batch = Jacobians::new(q.len(), C::PARAMS);
        jacobians_impl::<N, C, Lanes>(&k, &poses, &mut batch);
        let mut seen = 0;
        for_each_lane_jacobian::<N, C, Lanes>(&k, &poses, 0..q.len(), |i, p: &[f64; 3], cols| {
            assert_eq!(*p, batch.position(i));
            for (c, col) in cols.iter().enumerate() {
                assert_eq!(*col, batch.column(i, c));
            }
            seen += 1;
        });
        assert_eq!(seen, q.len());
        free_columns_bits::<C, N>(&k, &poses, &batch);
        let mut six = Vec::new();
        for_each_lane_pose_jacobian::<N, C, Lanes>(&k, &poses, 0..q.len(), &mut |i, t, cols| {
            assert_eq!(*t, tools[i]);
            six.push(cols.to_vec());
        });
        for (i, qi) in q.iter().enumerate() {
            assert_eq!(pos[i], position::<C, N>(&k, qi));
            let (cq, sq) = k.joint_inputs(qi);
            let mut cols = vec![[0.0; 3]; C::PARAMS];
            let p = C::position_jacobian(&k, &cq, &sq, &mut cols);
            assert_eq!(p, batch.position(i));
            for (c, col) in cols.iter().enumerate() {
                assert_eq!(*col, batch.column(i, c));
            }
            let mut cols6 = vec![[0.0; 6]; C::PARAMS];
            let t = C::pose_jacobian(&k, &cq, &sq, &mut cols6);
            assert_eq!(Pose::from_transform(t), tools[i]);
            assert_eq!(Pose::from_transform(C::pose(&k, &cq, &sq)), tools[i]);
            assert_eq!(cols6, six[i]);
        }
    }

    /// The free columns, compacted by coordinate in groups of four and
    /// padded with zeros, are the batch's columns: every column, some in
    /// another order (a partial last group), none; from pose 1, so that
    /// the range ends in a tail.
    fn free_columns_bits<C: Chain<N>, const N: usize>(
        k: &PreparedParams<N>,
        poses: &PreparedPoses,
        batch: &Jacobians,
    ) {
        let all: Vec<usize> = (0..C::PARAMS).collect();
        let some: Vec<usize> = (0..C::PARAMS).rev().step_by(3).collect();
        for free in [all, some, Vec::new()] {
            let range = 1..poses.len();
            let mut seen = Vec::new();
            for_each_lane_free_jacobian::<N, C, Lanes>(
                k,
                poses,
                range.clone(),
                &free,
                |i, p, rows| {
                    assert_eq!(*p, batch.position(i));
                    for (c, row) in rows.iter().enumerate() {
                        assert_eq!(row.len(), free.len().div_ceil(LANES));
                        for (u, &v) in row.as_flattened().iter().enumerate() {
                            let want = free.get(u).map_or(0.0, |&j| batch.column(i, j)[c]);
                            assert_eq!(
                                v.to_bits(),
                                want.to_bits(),
                                "pose {i}, column {u}, row {c}"
                            );
                        }
                    }
                    seen.push(i);
                },
            );
            assert_eq!(seen, range.collect::<Vec<_>>());
        }
    }

    #[test]
    fn quaternions_have_one_sign() {
        let turn = |angle: f64| {
            let (s, c) = angle.sin_cos();
            Pose {
                rotation: [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
                position: [0.0; 3],
            }
        };
        // Past a half turn the sign flips back to w ≥ 0.
        let q = turn(1.5 * std::f64::consts::PI).quaternion();
        assert!(q[0] > 0.0 && q[3] < 0.0, "{q:?}");
        assert_eq!(turn(0.0).quaternion(), [1.0, 0.0, 0.0, 0.0]);
        // A half turn about −x is one about +x.
        let flip = Pose {
            rotation: [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]],
            position: [0.0; 3],
        };
        assert_eq!(flip.quaternion(), [0.0, 1.0, 0.0, 0.0]);
    }
}
