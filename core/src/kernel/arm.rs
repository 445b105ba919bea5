//! [`ArmKernel`]: the one runtime-sized entry to the generated chains. Its
//! `chains!` list is the only place that maps a joint count to a chain; every
//! operation is a [`KernelOp`] run on the chain the arm has.

use std::ops::Range;

use super::lanes::{self, Batch, LaneOp};
use super::{
    Chain, Dh, Hayati, Jacobians, KernelError, PreparedParams, PreparedPoses,
    for_each_lane_jacobian, jacobians_impl, positions_impl,
};
use crate::params::DhParams;

/// An operation on a generated chain of any supported joint count: what
/// [`ArmKernel::apply`] runs with the arm's `N`.
pub(crate) trait KernelOp {
    /// What the operation returns.
    type Output;
    /// Runs the operation on the prepared parameters of an `N`-joint arm
    /// with its chain `C` ([`Dh`], or [`Hayati`] when a joint is Hayati).
    fn run<const N: usize, C: Chain<N>>(self, k: &PreparedParams<N>) -> Self::Output;
}

macro_rules! chains {
    ($($n:literal => $variant:ident),*) => {
        #[derive(Clone, Debug, PartialEq)]
        enum Prepared {
            $($variant(PreparedParams<$n>)),*
        }

        /// The joint counts `chains!` instantiates, for the test that they
        /// agree with [`SUPPORTED_JOINTS`](crate::params::SUPPORTED_JOINTS).
        #[cfg(test)]
        const CHAINS: &[usize] = &[$($n),*];

        impl ArmKernel {
            /// Prepares `params` for the generated chain of its joint count.
            ///
            /// ```
            /// use aacmm_core::{kernel::{ArmKernel, KernelError}, params::DhParams};
            /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
            /// assert_eq!((k.joints(), k.param_count()), (6, 27));
            /// let five = DhParams::from_slice(&[0.0; 23]).unwrap();
            /// assert_eq!(ArmKernel::new(&five), Err(KernelError::Unsupported(5)));
            /// ```
            pub fn new(params: &DhParams) -> Result<ArmKernel, KernelError> {
                let inner = match params.joint_count() {
                    $($n => Prepared::$variant(PreparedParams::<$n>::new(params)?),)*
                    n => return Err(KernelError::Unsupported(n)),
                };
                Ok(ArmKernel { inner })
            }

            /// Runs `op` on this arm's chain: the D-H one unless a joint is
            /// Hayati (the D-H chain stays as fast as it was).
            pub(crate) fn apply<O: KernelOp>(&self, op: O) -> O::Output {
                match &self.inner {
                    $(Prepared::$variant(k) => if k.has_hayati() {
                        op.run::<$n, Hayati>(k)
                    } else {
                        op.run::<$n, Dh>(k)
                    },)*
                }
            }
        }
    };
}

chains!(6 => Six, 7 => Seven);

/// An arm's geometry prepared for the generated kernel of its joint count:
/// the type every runtime caller (simulator, metrics, solvers, C ABI) uses.
/// Preparing costs a few sin/cos and allocates nothing, so solvers make one
/// per parameter set.
#[derive(Clone, Debug, PartialEq)]
pub struct ArmKernel {
    inner: Prepared,
}

struct Joints;
impl KernelOp for Joints {
    type Output = usize;
    fn run<const N: usize, C: Chain<N>>(self, _: &PreparedParams<N>) -> usize {
        N
    }
}

/// One pose: position, and optionally a Jacobian (parameter or joint).
struct OnePose<'a> {
    q: &'a [f64],
    jac: Option<(&'a mut [[f64; 3]], bool)>,
}

impl KernelOp for OnePose<'_> {
    type Output = Result<[f64; 3], KernelError>;
    fn run<const N: usize, C: Chain<N>>(self, k: &PreparedParams<N>) -> Self::Output {
        let q: &[f64; N] = self.q.try_into().map_err(|_| KernelError::JointCount {
            expected: N,
            got: self.q.len(),
        })?;
        let (cq, sq) = (q.map(f64::cos), q.map(f64::sin));
        match self.jac {
            None => Ok(C::position(k, &cq, &sq)),
            Some((jac, true)) => {
                check_len(C::PARAMS, jac.len())?;
                Ok(C::position_jacobian(k, &cq, &sq, jac))
            }
            Some((jac, false)) => {
                check_len(N, jac.len())?;
                // Invariant: `check_len` just returned Ok for length N.
                let jac: &mut [[f64; 3]; N] = jac.try_into().expect("length checked");
                Ok(C::joint_jacobian(k, &cq, &sq, jac))
            }
        }
    }
}

/// One pose of prepared poses: its joint Jacobian from the stored sin/cos.
struct OnePrepared<'a> {
    poses: &'a PreparedPoses,
    i: usize,
    jac: &'a mut [[f64; 3]],
}

impl KernelOp for OnePrepared<'_> {
    type Output = Result<[f64; 3], KernelError>;
    fn run<const N: usize, C: Chain<N>>(self, k: &PreparedParams<N>) -> Self::Output {
        check_len(N, self.jac.len())?;
        // Invariant: `check_len` above.
        let jac: &mut [[f64; 3]; N] = self.jac.try_into().expect("length checked");
        let (cq, sq) = self.poses.trig::<N>(self.i);
        Ok(C::joint_jacobian(k, &cq, &sq, jac))
    }
}

/// A batch operation with the arm's chain known: the [`LaneOp`] that
/// [`lanes::run`] runs on the widest lanes the CPU has.
struct OnChain<'k, const N: usize, C, O> {
    k: &'k PreparedParams<N>,
    op: O,
    chain: std::marker::PhantomData<C>,
}

impl<'k, const N: usize, C, O> OnChain<'k, N, C, O> {
    fn new(k: &'k PreparedParams<N>, op: O) -> Self {
        OnChain {
            k,
            op,
            chain: std::marker::PhantomData,
        }
    }
}

struct Positions<'a> {
    poses: &'a PreparedPoses,
    start: usize,
    out: &'a mut [[f64; 3]],
}

impl KernelOp for Positions<'_> {
    type Output = ();
    fn run<const N: usize, C: Chain<N>>(self, k: &PreparedParams<N>) {
        lanes::run(OnChain::<N, C, _>::new(k, self))
    }
}

impl<const N: usize, C: Chain<N>> LaneOp for OnChain<'_, N, C, Positions<'_>> {
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        let Positions { poses, start, out } = self.op;
        positions_impl::<N, C, L>(self.k, poses, start, out)
    }
}

struct AllJacobians<'a> {
    poses: &'a PreparedPoses,
    out: &'a mut Jacobians,
}

impl KernelOp for AllJacobians<'_> {
    type Output = Result<(), KernelError>;
    fn run<const N: usize, C: Chain<N>>(self, k: &PreparedParams<N>) -> Self::Output {
        check_len(C::PARAMS, self.out.params())?;
        lanes::run(OnChain::<N, C, _>::new(k, self));
        Ok(())
    }
}

impl<const N: usize, C: Chain<N>> LaneOp for OnChain<'_, N, C, AllJacobians<'_>> {
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        let AllJacobians { poses, out } = self.op;
        jacobians_impl::<N, C, L>(self.k, poses, out)
    }
}

struct EachJacobian<'a, F> {
    poses: &'a PreparedPoses,
    range: Range<usize>,
    f: F,
}

impl<F: FnMut(usize, &[f64; 3], &[[f64; 3]])> KernelOp for EachJacobian<'_, F> {
    type Output = ();
    fn run<const N: usize, C: Chain<N>>(self, k: &PreparedParams<N>) {
        lanes::run(OnChain::<N, C, _>::new(k, self))
    }
}

impl<const N: usize, C: Chain<N>, F: FnMut(usize, &[f64; 3], &[[f64; 3]])> LaneOp
    for OnChain<'_, N, C, EachJacobian<'_, F>>
{
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        let EachJacobian { poses, range, f } = self.op;
        for_each_lane_jacobian::<N, C, L>(self.k, poses, range, f)
    }
}

struct EachJointJacobian<'a, F> {
    poses: &'a PreparedPoses,
    range: Range<usize>,
    f: F,
}

impl<F: FnMut(usize, &[[f64; 3]])> KernelOp for EachJointJacobian<'_, F> {
    type Output = ();
    fn run<const N: usize, C: Chain<N>>(self, k: &PreparedParams<N>) {
        lanes::run(OnChain::<N, C, _>::new(k, self))
    }
}

impl<const N: usize, C: Chain<N>, F: FnMut(usize, &[[f64; 3]])> LaneOp
    for OnChain<'_, N, C, EachJointJacobian<'_, F>>
{
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        let EachJointJacobian {
            poses,
            range,
            mut f,
        } = self.op;
        super::for_each_lane_joint_jacobian::<N, C, L>(self.k, poses, range, |i, jq| f(i, jq))
    }
}

fn check_len(expected: usize, got: usize) -> Result<(), KernelError> {
    if expected == got {
        Ok(())
    } else {
        Err(KernelError::OutputLength { expected, got })
    }
}

impl ArmKernel {
    /// Number of joints.
    pub fn joints(&self) -> usize {
        self.apply(Joints)
    }

    /// Number of geometric parameters, `4n + 3`.
    pub fn param_count(&self) -> usize {
        crate::params::param_count(self.joints())
    }

    /// Probe position of one pose with readings `q` (rad), mm.
    ///
    /// ```
    /// use aacmm_core::{kernel::ArmKernel, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let p = k.position(&[0.0; 6]).unwrap();
    /// assert!((p[2] - 995.0).abs() < 1e-9);
    /// assert!(k.position(&[0.0; 7]).is_err());
    /// ```
    pub fn position(&self, q: &[f64]) -> Result<[f64; 3], KernelError> {
        self.apply(OnePose { q, jac: None })
    }

    /// Probe position and `∂p/∂parameter` (the `4n + 3` columns in the fixed
    /// order of [`crate::params`]) of one pose, into `jac`.
    ///
    /// ```
    /// use aacmm_core::{kernel::ArmKernel, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let mut jac = [[0.0; 3]; 27];
    /// k.position_jacobian(&[0.2; 6], &mut jac).unwrap();
    /// assert_eq!(jac[6], [0.0, 0.0, 1.0]); // ∂p/∂d1
    /// ```
    pub fn position_jacobian(
        &self,
        q: &[f64],
        jac: &mut [[f64; 3]],
    ) -> Result<[f64; 3], KernelError> {
        self.apply(OnePose {
            q,
            jac: Some((jac, true)),
        })
    }

    /// Probe position and `∂p/∂q_j` of one pose into `jac` (one column per
    /// joint): what inverse kinematics needs.
    ///
    /// ```
    /// use aacmm_core::{kernel::ArmKernel, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let mut jq = [[0.0; 3]; 6];
    /// k.joint_jacobian(&[0.0; 6], &mut jq).unwrap();
    /// assert!((jq[0][1] + 5.0).abs() < 1e-9); // joint 1 moves the probe along −y
    /// ```
    pub fn joint_jacobian(&self, q: &[f64], jac: &mut [[f64; 3]]) -> Result<[f64; 3], KernelError> {
        self.apply(OnePose {
            q,
            jac: Some((jac, false)),
        })
    }

    /// [`ArmKernel::joint_jacobian`] of pose `i` of `poses`, from their
    /// stored sin/cos (the same bits as from the readings: both are the
    /// sin/cos of the same values).
    ///
    /// ```
    /// use aacmm_core::{kernel::{ArmKernel, PreparedPoses}, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let q = [[0.1, 0.2, 0.3, 0.4, 0.5, 0.6], [0.5; 6]];
    /// let poses = PreparedPoses::new(6, &q).unwrap();
    /// let (mut a, mut b) = ([[0.0; 3]; 6], [[0.0; 3]; 6]);
    /// let p = k.joint_jacobian_at(&poses, 1, &mut a).unwrap();
    /// assert_eq!((p, a), (k.joint_jacobian(&q[1], &mut b).unwrap(), b));
    /// assert!(k.joint_jacobian_at(&poses, 2, &mut a).is_err());
    /// ```
    pub fn joint_jacobian_at(
        &self,
        poses: &PreparedPoses,
        i: usize,
        jac: &mut [[f64; 3]],
    ) -> Result<[f64; 3], KernelError> {
        self.check_poses(poses, &(i..i + 1))?;
        let p = self.apply(OnePrepared {
            poses,
            i,
            jac: &mut *jac,
        })?;
        match poses.post() {
            None => Ok(p),
            Some(post) => {
                let s = post.scale[i];
                for c in jac.iter_mut() {
                    *c = c.map(|v| s * v);
                }
                Ok(post.at(i, &p))
            }
        }
    }

    fn check_poses(&self, poses: &PreparedPoses, range: &Range<usize>) -> Result<(), KernelError> {
        if poses.joints() != self.joints() {
            return Err(KernelError::JointCount {
                expected: self.joints(),
                got: poses.joints(),
            });
        }
        if range.start > range.end || range.end > poses.len() {
            return Err(KernelError::Range {
                start: range.start,
                end: range.end,
                len: poses.len(),
            });
        }
        Ok(())
    }

    /// Probe positions of poses `range`, in order, into `out` (one per pose).
    /// Solvers split a data set into ranges to work on them in parallel.
    ///
    /// ```
    /// use aacmm_core::{kernel::{ArmKernel, PreparedPoses}, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let q: Vec<[f64; 6]> = (0..9).map(|i| [0.1 * i as f64; 6]).collect();
    /// let poses = PreparedPoses::new(6, &q).unwrap();
    /// let mut out = vec![[0.0; 3]; 9];
    /// k.positions(&poses, 0..9, &mut out).unwrap();
    /// assert_eq!(out[7], k.position(&q[7]).unwrap()); // bit-identical to one pose
    /// let mut tail = vec![[0.0; 3]; 3];
    /// k.positions(&poses, 6..9, &mut tail).unwrap();
    /// assert_eq!(tail[1], out[7]);
    /// ```
    pub fn positions(
        &self,
        poses: &PreparedPoses,
        range: Range<usize>,
        out: &mut [[f64; 3]],
    ) -> Result<(), KernelError> {
        self.check_poses(poses, &range)?;
        check_len(range.len(), out.len())?;
        let start = range.start;
        self.apply(Positions {
            poses,
            start,
            out: &mut *out,
        });
        if let Some(post) = poses.post() {
            for (k, o) in out.iter_mut().enumerate() {
                *o = post.at(start + k, o);
            }
        }
        Ok(())
    }

    /// Positions and parameter Jacobians of every pose into `out`, made with
    /// [`Jacobians::new`]`(poses.len(), self.param_count())`.
    ///
    /// ```
    /// use aacmm_core::{kernel::{ArmKernel, Jacobians, PreparedPoses}, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let poses = PreparedPoses::new(6, &[[0.2; 6]; 6]).unwrap();
    /// let mut out = Jacobians::new(6, 27);
    /// k.jacobians(&poses, &mut out).unwrap();
    /// assert_eq!(out.column(5, 6), [0.0, 0.0, 1.0]); // ∂p/∂d1 of the last pose
    /// assert_eq!(out.row(6, 2), &[1.0; 6]);
    /// ```
    pub fn jacobians(&self, poses: &PreparedPoses, out: &mut Jacobians) -> Result<(), KernelError> {
        self.check_poses(poses, &(0..poses.len()))?;
        check_len(poses.len(), out.len())?;
        self.apply(AllJacobians {
            poses,
            out: &mut *out,
        })?;
        if let Some(post) = poses.post() {
            out.apply_post(post);
        }
        Ok(())
    }

    /// Calls `f(pose, position, jacobian)` for every pose of `range` in order,
    /// with the `3 × (4n+3)` parameter Jacobian as columns — the form a
    /// least-squares solver uses to accumulate `JᵀJ` and `Jᵀr` without
    /// materialising `J`, one range per worker.
    ///
    /// ```
    /// use aacmm_core::{kernel::{ArmKernel, PreparedPoses}, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let poses = PreparedPoses::new(6, &[[0.0; 6]; 5]).unwrap();
    /// let mut seen = Vec::new();
    /// k.for_each_jacobian(&poses, 1..5, |i, p, jac| {
    ///     assert_eq!(jac.len(), 27);
    ///     assert_eq!(jac[6], [0.0, 0.0, 1.0]); // ∂p/∂d1
    ///     assert!((p[2] - 995.0).abs() < 1e-9);
    ///     seen.push(i);
    /// }).unwrap();
    /// assert_eq!(seen, [1, 2, 3, 4]);
    /// ```
    pub fn for_each_jacobian(
        &self,
        poses: &PreparedPoses,
        range: Range<usize>,
        f: impl FnMut(usize, &[f64; 3], &[[f64; 3]]),
    ) -> Result<(), KernelError> {
        self.check_poses(poses, &range)?;
        match poses.post() {
            None => self.apply(EachJacobian { poses, range, f }),
            Some(post) => self.each_jacobian_after(poses, post, range, f),
        }
        Ok(())
    }

    /// [`ArmKernel::for_each_jacobian`] of poses with a transform after the
    /// chain (a model beyond geometry is on): one copy of the columns per
    /// pose, scaled. Out of line, so that the plain path compiles as before.
    #[cold]
    #[inline(never)]
    fn each_jacobian_after(
        &self,
        poses: &PreparedPoses,
        post: &crate::kernel::Post,
        range: Range<usize>,
        mut f: impl FnMut(usize, &[f64; 3], &[[f64; 3]]),
    ) {
        let mut scaled = vec![[0.0; 3]; self.param_count()];
        let g = |i: usize, p: &[f64; 3], jac: &[[f64; 3]]| {
            for (o, c) in scaled.iter_mut().zip(jac) {
                *o = c.map(|v| post.scale[i] * v);
            }
            f(i, &post.at(i, p), &scaled);
        };
        self.apply(EachJacobian { poses, range, f: g })
    }

    /// Calls `f(pose, ∂p/∂q)` for every pose of `range` in order, with the
    /// `3 × n` joint Jacobian (mm/rad) as columns: what carries encoder
    /// noise into a touch's covariance. A batch of SIMD lanes at a time, the
    /// same bits as [`ArmKernel::joint_jacobian_at`] one pose at a time.
    ///
    /// ```
    /// use aacmm_core::{kernel::{ArmKernel, PreparedPoses}, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let poses = PreparedPoses::new(6, &[[0.0; 6]; 5]).unwrap();
    /// let mut seen = Vec::new();
    /// k.for_each_joint_jacobian(&poses, 0..5, |i, jq| {
    ///     assert_eq!(jq.len(), 6);
    ///     // Joint 1 turns the probe, 5 mm off the base axis, about z.
    ///     assert!((jq[0][0] - 0.0).abs() < 1e-12 && (jq[0][1] + 5.0).abs() < 1e-9);
    ///     seen.push(i);
    /// }).unwrap();
    /// assert_eq!(seen, [0, 1, 2, 3, 4]);
    /// ```
    pub fn for_each_joint_jacobian(
        &self,
        poses: &PreparedPoses,
        range: Range<usize>,
        mut f: impl FnMut(usize, &[[f64; 3]]),
    ) -> Result<(), KernelError> {
        self.check_poses(poses, &range)?;
        match poses.post() {
            None => self.apply(EachJointJacobian { poses, range, f }),
            Some(post) => {
                let mut scaled = vec![[0.0; 3]; self.joints()];
                let g = |i: usize, jq: &[[f64; 3]]| {
                    for (o, c) in scaled.iter_mut().zip(jq) {
                        *o = c.map(|v| post.scale[i] * v);
                    }
                    f(i, &scaled);
                };
                self.apply(EachJointJacobian { poses, range, f: g })
            }
        }
        Ok(())
    }

    /// Probe positions of every row of readings (rad), in row order: the
    /// convenience for callers holding plain rows.
    ///
    /// ```
    /// use aacmm_core::{kernel::ArmKernel, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let p = k.positions_of(&[vec![0.0; 6]]).unwrap();
    /// assert!((p[0][2] - 995.0).abs() < 1e-9);
    /// assert!(k.positions_of(&[vec![0.0; 7]]).is_err());
    /// ```
    pub fn positions_of<R: AsRef<[f64]>>(&self, rows: &[R]) -> Result<Vec<[f64; 3]>, KernelError> {
        let poses = PreparedPoses::new(self.joints(), rows)?;
        let mut out = vec![[0.0; 3]; poses.len()];
        self.positions(&poses, 0..poses.len(), &mut out)?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::SUPPORTED_JOINTS;

    #[test]
    fn chains_are_the_supported_joint_counts() {
        assert_eq!(CHAINS, SUPPORTED_JOINTS);
        for n in 0..=9 {
            let params = DhParams::from_slice(&vec![0.1; 4 * n + 3]);
            let made = params.map(|p| ArmKernel::new(&p));
            match made {
                Some(Ok(k)) => {
                    assert!(SUPPORTED_JOINTS.contains(&n));
                    assert_eq!(k.joints(), n);
                }
                _ => assert!(!SUPPORTED_JOINTS.contains(&n), "{n}"),
            }
        }
    }

    #[test]
    fn shapes_are_checked() {
        let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
        let poses = PreparedPoses::new(6, &[[0.0; 6]; 3]).unwrap();
        let mut out = vec![[0.0; 3]; 2];
        assert!(k.positions(&poses, 0..3, &mut out).is_err());
        assert!(k.positions(&poses, 2..4, &mut out).is_err());
        assert!(k.positions(&poses, 1..3, &mut out).is_ok());
        let seven = PreparedPoses::new(7, &[[0.0; 7]; 2]).unwrap();
        assert!(k.positions(&seven, 0..2, &mut out).is_err());
        assert!(k.jacobians(&poses, &mut Jacobians::new(3, 31)).is_err());
        assert!(k.joint_jacobian(&[0.0; 6], &mut [[0.0; 3]; 7]).is_err());
        assert!(k.position_jacobian(&[0.0; 6], &mut [[0.0; 3]; 26]).is_err());
    }
}
