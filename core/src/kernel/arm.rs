//! [`ArmKernel`]: the one runtime-sized entry to the kernels. Its `chains!`
//! list is the only place that says which shapes have a generated kernel;
//! every other shape of 1 to 12 joints runs on [`Generic`]. Every
//! operation is an [`Op`] run on the chain the arm has, so each chain's
//! code is instantiated once per operation, whatever calls it.

use std::any::Any;
use std::fmt;
use std::marker::PhantomData;
use std::ops::Range;

use super::batch::{
    FreeRows, JacobianVisitor, Jacobians, PoseJacobianVisitor, for_each_lane_free_jacobian,
    for_each_lane_jacobian, for_each_lane_joint_jacobian, for_each_lane_pose_jacobian,
    jacobians_impl, poses_impl, positions_impl,
};
use super::lanes::{self, Batch, LaneOp};
use super::{Chain, ChainShape, Generic, KernelError, Pose, PreparedParams, PreparedPoses};
use crate::params::DhParams;

/// A function of one pose's readings (`q`, rad or mm per joint) and its
/// outputs, or a batch over prepared poses: everything [`ArmKernel`] does,
/// as one value. Callbacks are `dyn`: a chain's batch loops are compiled
/// once, not once per caller's closure (the measuring arms' excepted, see
/// `Prepared::run_inlined`).
pub(crate) enum Op<'a> {
    Position {
        q: &'a [f64],
        out: &'a mut [f64; 3],
    },
    PositionJacobian {
        q: &'a [f64],
        jac: &'a mut [[f64; 3]],
        out: &'a mut [f64; 3],
    },
    JointJacobian {
        q: &'a [f64],
        jac: &'a mut [[f64; 3]],
        out: &'a mut [f64; 3],
    },
    JointJacobianAt {
        poses: &'a PreparedPoses,
        i: usize,
        jac: &'a mut [[f64; 3]],
        out: &'a mut [f64; 3],
    },
    Pose {
        q: &'a [f64],
        out: &'a mut Pose,
    },
    PoseJacobian {
        q: &'a [f64],
        jac: &'a mut [[f64; 6]],
        out: &'a mut Pose,
    },
    JointPoseJacobian {
        q: &'a [f64],
        jac: &'a mut [[f64; 6]],
        out: &'a mut Pose,
    },
    Batch(BatchOp<'a>),
}

/// The operations over prepared poses, each run in SIMD lanes.
pub(crate) enum BatchOp<'a> {
    Positions {
        poses: &'a PreparedPoses,
        start: usize,
        out: &'a mut [[f64; 3]],
    },
    Poses {
        poses: &'a PreparedPoses,
        start: usize,
        out: &'a mut [Pose],
    },
    Jacobians {
        poses: &'a PreparedPoses,
        out: &'a mut Jacobians,
    },
    EachJacobian {
        poses: &'a PreparedPoses,
        range: Range<usize>,
        f: &'a mut JacobianVisitor<'a>,
    },
    EachJointJacobian {
        poses: &'a PreparedPoses,
        range: Range<usize>,
        f: &'a mut dyn FnMut(usize, &[[f64; 3]]),
    },
    EachPoseJacobian {
        poses: &'a PreparedPoses,
        range: Range<usize>,
        f: &'a mut PoseJacobianVisitor<'a>,
    },
}

/// `q` as the `N` readings of the arm.
fn readings<const N: usize>(q: &[f64]) -> Result<&[f64; N], KernelError> {
    q.try_into().map_err(|_| KernelError::JointCount {
        expected: N,
        got: q.len(),
    })
}

/// `jac` as `N` columns, or the length error.
fn sized<const N: usize, const R: usize>(
    jac: &mut [[f64; R]],
) -> Result<&mut [[f64; R]; N], KernelError> {
    let got = jac.len();
    jac.try_into()
        .map_err(|_| KernelError::OutputLength { expected: N, got })
}

fn check_len(expected: usize, got: usize) -> Result<(), KernelError> {
    if expected == got {
        Ok(())
    } else {
        Err(KernelError::OutputLength { expected, got })
    }
}

impl Op<'_> {
    /// Runs the operation on the prepared parameters of an `N`-joint arm
    /// with its chain `C`.
    fn run<const N: usize, C: Chain<N>>(self, k: &PreparedParams<N>) -> Result<(), KernelError> {
        match self {
            Op::Position { q, out } => {
                let (cq, sq) = k.joint_inputs(readings::<N>(q)?);
                *out = C::position(k, &cq, &sq);
            }
            Op::PositionJacobian { q, jac, out } => {
                let (cq, sq) = k.joint_inputs(readings::<N>(q)?);
                check_len(C::PARAMS, jac.len())?;
                *out = C::position_jacobian(k, &cq, &sq, jac);
            }
            Op::JointJacobian { q, jac, out } => {
                let (cq, sq) = k.joint_inputs(readings::<N>(q)?);
                *out = C::joint_jacobian(k, &cq, &sq, sized::<N, 3>(jac)?);
            }
            Op::JointJacobianAt { poses, i, jac, out } => {
                let jac = sized::<N, 3>(jac)?;
                let (cq, sq) = poses.trig::<N>(i);
                *out = C::joint_jacobian(k, &cq, &sq, jac);
            }
            Op::Pose { q, out } => {
                let (cq, sq) = k.joint_inputs(readings::<N>(q)?);
                *out = Pose::from_transform(C::pose(k, &cq, &sq));
            }
            Op::PoseJacobian { q, jac, out } => {
                let (cq, sq) = k.joint_inputs(readings::<N>(q)?);
                check_len(C::PARAMS, jac.len())?;
                *out = Pose::from_transform(C::pose_jacobian(k, &cq, &sq, jac));
            }
            Op::JointPoseJacobian { q, jac, out } => {
                let (cq, sq) = k.joint_inputs(readings::<N>(q)?);
                let t = C::joint_pose_jacobian(k, &cq, &sq, sized::<N, 6>(jac)?);
                *out = Pose::from_transform(t);
            }
            Op::Batch(op) => op.run::<N, C>(k)?,
        }
        Ok(())
    }
}

impl BatchOp<'_> {
    fn run<const N: usize, C: Chain<N>>(self, k: &PreparedParams<N>) -> Result<(), KernelError> {
        match self {
            BatchOp::Positions { poses, start, out } => {
                lanes::run(OnChain::<N, C, _>::new(k, Positions { poses, start, out }));
            }
            BatchOp::Poses { poses, start, out } => {
                lanes::run(OnChain::<N, C, _>::new(k, Poses { poses, start, out }));
            }
            BatchOp::Jacobians { poses, out } => {
                check_len(C::PARAMS, out.params())?;
                lanes::run(OnChain::<N, C, _>::new(k, AllJacobians { poses, out }));
            }
            BatchOp::EachJacobian { poses, range, f } => {
                lanes::run(OnChain::<N, C, _>::new(k, EachJacobian { poses, range, f }));
            }
            BatchOp::EachJointJacobian { poses, range, f } => {
                lanes::run(OnChain::<N, C, _>::new(
                    k,
                    EachJointJacobian { poses, range, f },
                ));
            }
            BatchOp::EachPoseJacobian { poses, range, f } => {
                lanes::run(OnChain::<N, C, _>::new(
                    k,
                    EachPoseJacobian { poses, range, f },
                ));
            }
        }
        Ok(())
    }
}

/// Which kind of kernel computes an arm.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KernelKind {
    /// A generated kernel the library ships ([`SHIPPED_SHAPES`]).
    Generated,
    /// The closed-form per-joint kernel of any shape ([`Generic`]).
    Generic,
    /// A chain handed over with [`ArmKernel::with_chain`].
    User,
}

/// The shapes with generated kernels, their modules in [`shipped`]
/// (`…h`: the extended chain, for arms with Hayati joints), and the
/// arm's prepared parameters by joint count. Every count of 1 to
/// [`MAX_JOINTS`](crate::params::MAX_JOINTS) has a variant; a shape
/// without a generated kernel runs on [`Generic`].
macro_rules! chains {
    (
        shapes: {
            $($n:literal => $variant:ident [$($dh:ident, $ext:ident: $shape:literal, $what:literal);*]),* $(,)?
        },
        inlined: {
            $($hn:literal => $hvariant:ident [$hdh:ident, $hext:ident]),* $(,)?
        } $(,)?
    ) => {
        /// The generated kernels of the shipped shapes ([`SHIPPED_SHAPES`]):
        /// for each a D-H chain and an extended one (`…h`), which also
        /// computes Hayati joints. Internal: [`ArmKernel::new`] chooses
        /// among them, and a user's own chain is made with
        /// [`dh_kernel!`](crate::dh_kernel) (the same generator, so the same
        /// code and bits).
        #[allow(dead_code)]
        pub(crate) mod shipped {
            $($(
                aacmm_dh_macros::dh_chain! {
                    #[doc = concat!("The generated kernel of ", $what, " (`", $shape, "`), D-H joints.")]
                    pub mod $dh { joints = $shape, core = crate }
                }
                aacmm_dh_macros::dh_chain! {
                    #[doc = concat!("The generated kernel of ", $what, " (`", $shape, "`) with any subset of Hayati joints.")]
                    pub mod $ext { joints = $shape, hayati = true, core = crate }
                }
            )*)*
        }

        /// The shapes the library ships generated kernels for, base first
        /// (`R` revolute, `P` prismatic): every other shape runs on
        /// [`Generic`].
        pub const SHIPPED_SHAPES: &[&str] = &[$($($shape,)*)*];

        #[derive(Clone, Debug, PartialEq)]
        enum Prepared {
            $($variant(PreparedParams<$n>),)*
            User(UserChain),
        }

        impl Prepared {
            fn new(params: &DhParams) -> Result<Prepared, KernelError> {
                Ok(match params.joint_count() {
                    $($n => Prepared::$variant(PreparedParams::<$n>::new(params)?),)*
                    n => return Err(KernelError::Unsupported(n)),
                })
            }

            fn joints(&self) -> usize {
                match self {
                    $(Prepared::$variant(_) => $n,)*
                    Prepared::User(u) => u.0.joints(),
                }
            }

            fn kind(&self) -> KernelKind {
                match self {
                    $(Prepared::$variant(k) => {
                        let mask = k.prismatic_mask();
                        if [$(shipped::$dh::PRISMATIC),*].contains(&mask) {
                            KernelKind::Generated
                        } else {
                            KernelKind::Generic
                        }
                    })*
                    Prepared::User(_) => KernelKind::User,
                }
            }

            /// Runs `op` on this arm's chain: its shape's generated one if
            /// the library ships it (D-H unless a joint is Hayati: the
            /// D-H chain is the faster), else the generic one.
            fn run(&self, op: Op<'_>) -> Result<(), KernelError> {
                match self {
                    $(Prepared::$variant(k) => {
                        $(
                            if k.prismatic_mask() == shipped::$dh::PRISMATIC {
                                return if k.has_hayati() {
                                    op.run::<$n, shipped::$ext::Kernel>(k)
                                } else {
                                    op.run::<$n, shipped::$dh::Kernel>(k)
                                };
                            }
                        )*
                        op.run::<$n, Generic>(k)
                    })*
                    Prepared::User(u) => u.0.run(op),
                }
            }

            /// Runs `op` with its callback inlined into the batch loop if
            /// the arm's chain is one of the measuring arms' (6R, 7R): the
            /// callback then compiles inside the lane function, with its
            /// AVX2 (a solver's accumulation of `JᵀJ` is vectorised there).
            /// Every other chain gets `op` back, to run it through [`Op`]
            /// with a `dyn` callback: compiled once per chain, not once per
            /// chain and caller.
            fn run_inlined<O: InlinedOp>(&self, op: O) -> Result<(), O> {
                match self {
                    $(Prepared::$hvariant(k) if k.prismatic_mask() == shipped::$hdh::PRISMATIC => {
                        if k.has_hayati() {
                            op.run::<$hn, shipped::$hext::Kernel>(k)
                        } else {
                            op.run::<$hn, shipped::$hdh::Kernel>(k)
                        }
                        Ok(())
                    })*
                    _ => Err(op),
                }
            }
        }
    };
}

/// A batch loop whose callback is the caller's own closure type, for
/// [`Prepared::run_inlined`].
pub(crate) trait InlinedOp {
    /// Runs the loop on chain `C` of `N` joints.
    fn run<const N: usize, C: Chain<N>>(self, k: &PreparedParams<N>);
}

/// [`BatchOp::EachJacobian`] with the caller's closure.
pub(crate) struct EachJacobianInlined<'a, F> {
    pub(crate) poses: &'a PreparedPoses,
    pub(crate) range: Range<usize>,
    pub(crate) f: F,
}

impl<F: FnMut(usize, &[f64; 3], &[[f64; 3]])> InlinedOp for EachJacobianInlined<'_, F> {
    fn run<const N: usize, C: Chain<N>>(self, k: &PreparedParams<N>) {
        lanes::run(OnChain::<N, C, _>::new(k, self))
    }
}

impl<const N: usize, C: Chain<N>, F: FnMut(usize, &[f64; 3], &[[f64; 3]])> LaneOp
    for OnChain<'_, N, C, EachJacobianInlined<'_, F>>
{
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        let EachJacobianInlined { poses, range, f } = self.op;
        for_each_lane_jacobian::<N, C, L>(self.k, poses, range, f)
    }
}

/// [`ArmKernel::for_each_free_jacobian`]'s loop with the caller's closure.
pub(crate) struct EachFreeJacobianInlined<'a, F> {
    pub(crate) poses: &'a PreparedPoses,
    pub(crate) range: Range<usize>,
    pub(crate) free: &'a [usize],
    pub(crate) f: F,
}

impl<F: FnMut(usize, &[f64; 3], FreeRows<'_>)> InlinedOp for EachFreeJacobianInlined<'_, F> {
    fn run<const N: usize, C: Chain<N>>(self, k: &PreparedParams<N>) {
        lanes::run(OnChain::<N, C, _>::new(k, self))
    }
}

impl<const N: usize, C: Chain<N>, F: FnMut(usize, &[f64; 3], FreeRows<'_>)> LaneOp
    for OnChain<'_, N, C, EachFreeJacobianInlined<'_, F>>
{
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        let EachFreeJacobianInlined {
            poses,
            range,
            free,
            f,
        } = self.op;
        for_each_lane_free_jacobian::<N, C, L>(self.k, poses, range, free, f)
    }
}

/// [`BatchOp::EachJointJacobian`] with the caller's closure.
pub(crate) struct EachJointJacobianInlined<'a, F> {
    pub(crate) poses: &'a PreparedPoses,
    pub(crate) range: Range<usize>,
    pub(crate) f: F,
}

impl<F: FnMut(usize, &[[f64; 3]])> InlinedOp for EachJointJacobianInlined<'_, F> {
    fn run<const N: usize, C: Chain<N>>(self, k: &PreparedParams<N>) {
        lanes::run(OnChain::<N, C, _>::new(k, self))
    }
}

impl<const N: usize, C: Chain<N>, F: FnMut(usize, &[[f64; 3]])> LaneOp
    for OnChain<'_, N, C, EachJointJacobianInlined<'_, F>>
{
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        let EachJointJacobianInlined { poses, range, f } = self.op;
        for_each_lane_joint_jacobian::<N, C, L>(self.k, poses, range, f)
    }
}

chains! {
    shapes: {
        1 => One [],
        2 => Two [],
        3 => Three [],
        4 => Four [scara, scarah: "RRPR", "a SCARA"],
        5 => Five [arm5, arm5h: "RRRRR", "a 5-axis arm"],
        6 => Six [arm6, arm6h: "RRRRRR", "the 6-joint arm (27 parameters)"],
        7 => Seven [
            arm7, arm7h: "RRRRRRR", "the 7-joint arm (31 parameters)";
            track6, track6h: "PRRRRRR", "a 6-joint robot on a linear track"
        ],
        8 => Eight [track7, track7h: "PRRRRRRR", "a 7-joint arm on a lift or track"],
        9 => Nine [],
        10 => Ten [],
        11 => Eleven [],
        12 => Twelve [],
    },
    // The measuring arms: a solver's per-pose callbacks are inlined into
    // their batch loops (see `Prepared::run_inlined`).
    inlined: {
        6 => Six [arm6, arm6h],
        7 => Seven [arm7, arm7h],
    },
}

/// A chain handed over by a user ([`ArmKernel::with_chain`]): its
/// prepared parameters behind a trait object, every operation one dynamic
/// call.
#[derive(Clone, Debug)]
struct UserChain(Box<dyn DynChain>);

impl PartialEq for UserChain {
    fn eq(&self, other: &UserChain) -> bool {
        self.0.same(&*other.0)
    }
}

trait DynChain: fmt::Debug + Send + Sync + dyn_clone::DynClone + Any {
    fn joints(&self) -> usize;
    fn run(&self, op: Op<'_>) -> Result<(), KernelError>;
    /// The same chain type with the same constants.
    fn same(&self, other: &dyn DynChain) -> bool;
}

dyn_clone::clone_trait_object!(DynChain);

/// An `N`-joint arm prepared for the user's chain `C`.
struct OnUser<const N: usize, C> {
    k: PreparedParams<N>,
    chain: PhantomData<fn() -> C>,
}

impl<const N: usize, C> Clone for OnUser<N, C> {
    fn clone(&self) -> Self {
        OnUser {
            k: self.k,
            chain: PhantomData,
        }
    }
}

impl<const N: usize, C> fmt::Debug for OnUser<N, C> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("OnUser")
            .field("chain", &std::any::type_name::<C>())
            .field("k", &self.k)
            .finish()
    }
}

impl<const N: usize, C: Chain<N> + 'static> DynChain for OnUser<N, C> {
    fn joints(&self) -> usize {
        N
    }

    fn run(&self, op: Op<'_>) -> Result<(), KernelError> {
        op.run::<N, C>(&self.k)
    }

    fn same(&self, other: &dyn DynChain) -> bool {
        let other: &dyn Any = other;
        other.downcast_ref::<Self>().is_some_and(|o| o.k == self.k)
    }
}

/// An arm's geometry prepared for its kernel: the type every runtime
/// caller (simulator, metrics, solvers, C ABI) uses. Preparing costs a few
/// sin/cos and allocates nothing (a user's chain excepted), so solvers
/// make one per parameter set.
#[derive(Clone, Debug, PartialEq)]
pub struct ArmKernel {
    inner: Prepared,
    shape: ChainShape,
}

/// A batch operation with the arm's chain known: the [`LaneOp`] that
/// [`lanes::run`] runs on the widest lanes the CPU has.
struct OnChain<'k, const N: usize, C, O> {
    k: &'k PreparedParams<N>,
    op: O,
    chain: PhantomData<C>,
}

impl<'k, const N: usize, C, O> OnChain<'k, N, C, O> {
    fn new(k: &'k PreparedParams<N>, op: O) -> Self {
        OnChain {
            k,
            op,
            chain: PhantomData,
        }
    }
}

struct Positions<'a> {
    poses: &'a PreparedPoses,
    start: usize,
    out: &'a mut [[f64; 3]],
}

impl<const N: usize, C: Chain<N>> LaneOp for OnChain<'_, N, C, Positions<'_>> {
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        let Positions { poses, start, out } = self.op;
        positions_impl::<N, C, L>(self.k, poses, start, out)
    }
}

struct Poses<'a> {
    poses: &'a PreparedPoses,
    start: usize,
    out: &'a mut [Pose],
}

impl<const N: usize, C: Chain<N>> LaneOp for OnChain<'_, N, C, Poses<'_>> {
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        let Poses { poses, start, out } = self.op;
        poses_impl::<N, C, L>(self.k, poses, start, out)
    }
}

struct AllJacobians<'a> {
    poses: &'a PreparedPoses,
    out: &'a mut Jacobians,
}

impl<const N: usize, C: Chain<N>> LaneOp for OnChain<'_, N, C, AllJacobians<'_>> {
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        let AllJacobians { poses, out } = self.op;
        jacobians_impl::<N, C, L>(self.k, poses, out)
    }
}

struct EachJacobian<'a> {
    poses: &'a PreparedPoses,
    range: Range<usize>,
    f: &'a mut JacobianVisitor<'a>,
}

impl<const N: usize, C: Chain<N>> LaneOp for OnChain<'_, N, C, EachJacobian<'_>> {
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        let EachJacobian { poses, range, f } = self.op;
        for_each_lane_jacobian::<N, C, L>(self.k, poses, range, f)
    }
}

struct EachJointJacobian<'a> {
    poses: &'a PreparedPoses,
    range: Range<usize>,
    f: &'a mut dyn FnMut(usize, &[[f64; 3]]),
}

impl<const N: usize, C: Chain<N>> LaneOp for OnChain<'_, N, C, EachJointJacobian<'_>> {
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        let EachJointJacobian { poses, range, f } = self.op;
        for_each_lane_joint_jacobian::<N, C, L>(self.k, poses, range, f)
    }
}

struct EachPoseJacobian<'a> {
    poses: &'a PreparedPoses,
    range: Range<usize>,
    f: &'a mut PoseJacobianVisitor<'a>,
}

impl<const N: usize, C: Chain<N>> LaneOp for OnChain<'_, N, C, EachPoseJacobian<'_>> {
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        let EachPoseJacobian { poses, range, f } = self.op;
        for_each_lane_pose_jacobian::<N, C, L>(self.k, poses, range, f)
    }
}

mod api;
