//! What [`ArmKernel`] offers: construction, one pose's position, pose and
//! Jacobians, and batches over prepared poses.

use std::ops::Range;

use super::{
    ArmKernel, BatchOp, DynChain, EachFreeJacobianInlined, EachJacobianInlined,
    EachJointJacobianInlined, KernelKind, OnUser, Op, Prepared, UserChain, check_len,
};
use crate::kernel::batch::{FreeRows, JacobianVisitor, MAX_FREE, gather_free};
use crate::kernel::lanes::LANES;
use crate::kernel::{
    Chain, ChainShape, Jacobians, KernelError, Pose, Post, PreparedParams, PreparedPoses, computes,
};
use crate::params::DhParams;

impl ArmKernel {
    /// Prepares `params` for its chain's kernel: the generated one of its
    /// shape if the library ships it ([`SHIPPED_SHAPES`](super::SHIPPED_SHAPES)),
    /// else the closed-form per-joint one ([`Generic`](crate::kernel::Generic)).
    /// Any chain of 1 to 12 joints, revolute and prismatic mixed.
    ///
    /// ```
    /// use aacmm_core::{kernel::{ArmKernel, KernelError, KernelKind}, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// assert_eq!((k.joints(), k.param_count(), k.kind()), (6, 27, KernelKind::Generated));
    /// let nine = DhParams::from_slice(&[0.1; 39]).unwrap();
    /// assert_eq!(ArmKernel::new(&nine).unwrap().kind(), KernelKind::Generic);
    /// let thirteen = DhParams::from_slice(&[0.0; 55]).unwrap();
    /// assert_eq!(ArmKernel::new(&thirteen), Err(KernelError::Unsupported(13)));
    /// ```
    pub fn new(params: &DhParams) -> Result<ArmKernel, KernelError> {
        let shape = params
            .shape()
            .map_err(|_| KernelError::Unsupported(params.joint_count()))?;
        Ok(ArmKernel {
            inner: Prepared::new(params)?,
            shape,
        })
    }

    /// Prepares `params` for a chain `C` generated elsewhere — a user's
    /// own shape, made in their crate with
    /// [`dh_kernel!`](crate::dh_kernel) — instead of the library's choice.
    /// Every operation then makes one dynamic call into `C`'s code.
    ///
    /// # Errors
    ///
    /// An arm of another joint count or shape than `C`'s, or with a
    /// Hayati joint when `C` is not extended.
    ///
    /// ```
    /// use aacmm_core::{kernel::{ArmKernel, KernelKind}, params::DhParams};
    /// aacmm_core::dh_kernel! { pub mod arm6 { joints = "RRRRRR" } }
    /// aacmm_core::dh_kernel! { pub mod scara { joints = "RRPR" } }
    /// let arm = DhParams::paper_nominal();
    /// let k = ArmKernel::with_chain::<arm6::Kernel, 6>(&arm).unwrap();
    /// assert_eq!(k.kind(), KernelKind::User);
    /// assert!(ArmKernel::with_chain::<scara::Kernel, 4>(&arm).is_err());
    /// ```
    pub fn with_chain<C: Chain<N> + 'static, const N: usize>(
        params: &DhParams,
    ) -> Result<ArmKernel, KernelError> {
        let shape = params
            .shape()
            .map_err(|_| KernelError::Unsupported(params.joint_count()))?;
        let k = PreparedParams::<N>::new(params)?;
        computes::<N, C>(&k)?;
        let chain: Box<dyn DynChain> = Box::new(OnUser::<N, C> {
            k,
            chain: std::marker::PhantomData,
        });
        Ok(ArmKernel {
            inner: Prepared::User(UserChain(chain)),
            shape,
        })
    }

    fn run(&self, op: Op<'_>) -> Result<(), KernelError> {
        self.inner.run(op)
    }

    /// Number of joints.
    pub fn joints(&self) -> usize {
        self.inner.joints()
    }

    /// The chain's shape: which joints are prismatic.
    pub fn shape(&self) -> ChainShape {
        self.shape
    }

    /// Which kernel computes this arm.
    pub fn kind(&self) -> KernelKind {
        self.inner.kind()
    }

    /// Number of geometric parameters, `4n + 3`.
    pub fn param_count(&self) -> usize {
        crate::params::param_count(self.joints())
    }

    /// Probe position of one pose with readings `q` (rad; mm for a
    /// prismatic joint), mm.
    ///
    /// ```
    /// use aacmm_core::{kernel::ArmKernel, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let p = k.position(&[0.0; 6]).unwrap();
    /// assert!((p[2] - 995.0).abs() < 1e-9);
    /// assert!(k.position(&[0.0; 7]).is_err());
    /// ```
    pub fn position(&self, q: &[f64]) -> Result<[f64; 3], KernelError> {
        let mut out = [0.0; 3];
        self.run(Op::Position { q, out: &mut out })?;
        Ok(out)
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
        let mut out = [0.0; 3];
        self.run(Op::PositionJacobian {
            q,
            jac,
            out: &mut out,
        })?;
        Ok(out)
    }

    /// Probe position and `∂p/∂q_j` of one pose into `jac` (one column per
    /// joint; mm/rad for a revolute joint, mm/mm for a prismatic one):
    /// what inverse kinematics needs.
    ///
    /// ```
    /// use aacmm_core::{kernel::ArmKernel, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let mut jq = [[0.0; 3]; 6];
    /// k.joint_jacobian(&[0.0; 6], &mut jq).unwrap();
    /// assert!((jq[0][1] + 5.0).abs() < 1e-9); // joint 1 moves the probe along −y
    /// ```
    pub fn joint_jacobian(&self, q: &[f64], jac: &mut [[f64; 3]]) -> Result<[f64; 3], KernelError> {
        let mut out = [0.0; 3];
        self.run(Op::JointJacobian {
            q,
            jac,
            out: &mut out,
        })?;
        Ok(out)
    }

    /// The tool's pose (its frame's orientation and the probe's position)
    /// of one pose with readings `q`.
    ///
    /// ```
    /// use aacmm_core::{kernel::ArmKernel, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let tool = k.pose(&[0.0; 6]).unwrap();
    /// assert_eq!(tool.position, k.position(&[0.0; 6]).unwrap().map(|v| v)); // within rounding
    /// // Six twists of ∓90° end where they began: the tool points up.
    /// assert!((tool.rotation[2][2] - 1.0).abs() < 1e-12);
    /// ```
    pub fn pose(&self, q: &[f64]) -> Result<Pose, KernelError> {
        let mut out = Pose::default();
        self.run(Op::Pose { q, out: &mut out })?;
        Ok(out)
    }

    /// The tool's pose and its 6-row parameter Jacobian into `jac` (`4n +
    /// 3` columns: the position's derivative, then the small rotation `ω`
    /// with `δR = [ω]× R` in the base frame).
    ///
    /// ```
    /// use aacmm_core::{kernel::ArmKernel, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let mut jac = [[0.0; 6]; 27];
    /// k.pose_jacobian(&[0.2; 6], &mut jac).unwrap();
    /// assert_eq!(jac[18][3..], [0.0, 0.0, 1.0]); // θ1 turns the tool about the base z axis
    /// assert_eq!(jac[6], [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]); // d1 only moves it
    /// ```
    pub fn pose_jacobian(&self, q: &[f64], jac: &mut [[f64; 6]]) -> Result<Pose, KernelError> {
        let mut out = Pose::default();
        self.run(Op::PoseJacobian {
            q,
            jac,
            out: &mut out,
        })?;
        Ok(out)
    }

    /// The tool's pose and its 6-row joint Jacobian into `jac`: per joint
    /// `[z × (p − o); z]` for a revolute one, `[z; 0]` for a prismatic one.
    ///
    /// ```
    /// use aacmm_core::{kernel::ArmKernel, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let mut jq = [[0.0; 6]; 6];
    /// k.joint_pose_jacobian(&[0.0; 6], &mut jq).unwrap();
    /// assert_eq!(jq[0][3..], [0.0, 0.0, 1.0]);
    /// ```
    pub fn joint_pose_jacobian(
        &self,
        q: &[f64],
        jac: &mut [[f64; 6]],
    ) -> Result<Pose, KernelError> {
        let mut out = Pose::default();
        self.run(Op::JointPoseJacobian {
            q,
            jac,
            out: &mut out,
        })?;
        Ok(out)
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
        let mut p = [0.0; 3];
        self.run(Op::JointJacobianAt {
            poses,
            i,
            jac: &mut *jac,
            out: &mut p,
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

    /// Refuses poses of another chain (joint count or shape) than this
    /// arm's, and a range beyond them.
    pub(crate) fn check_poses(
        &self,
        poses: &PreparedPoses,
        range: &Range<usize>,
    ) -> Result<(), KernelError> {
        if poses.joints() != self.joints() {
            return Err(KernelError::JointCount {
                expected: self.joints(),
                got: poses.joints(),
            });
        }
        if poses.prismatic_mask() != self.shape.prismatic_mask() {
            return Err(KernelError::Shape {
                expected: self.shape,
                // Invariant: the joint counts are equal, the arm's a chain's.
                got: poses.shape().expect("the arm's joint count"),
                what: "the data",
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
        self.one_per_pose(
            poses,
            range,
            out,
            |poses, start, out| BatchOp::Positions { poses, start, out },
            |p, post, i| post.at(i, p),
        )
    }

    /// A batch `op` over poses `range` with one output each into `out`,
    /// then `after` each through the poses' transform after the chain.
    fn one_per_pose<T>(
        &self,
        poses: &PreparedPoses,
        range: Range<usize>,
        out: &mut [T],
        op: impl for<'b> FnOnce(&'b PreparedPoses, usize, &'b mut [T]) -> BatchOp<'b>,
        after: impl Fn(&T, &Post, usize) -> T,
    ) -> Result<(), KernelError> {
        self.check_poses(poses, &range)?;
        check_len(range.len(), out.len())?;
        let start = range.start;
        self.run(Op::Batch(op(poses, start, &mut *out)))?;
        if let Some(post) = poses.post() {
            for (k, o) in out.iter_mut().enumerate() {
                *o = after(o, post, start + k);
            }
        }
        Ok(())
    }

    /// Tool poses of poses `range`, in order, into `out` (one per pose):
    /// the same bits as [`ArmKernel::pose`] one pose at a time.
    ///
    /// ```
    /// use aacmm_core::{kernel::{ArmKernel, Pose, PreparedPoses}, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let q: Vec<[f64; 6]> = (0..6).map(|i| [0.1 * i as f64; 6]).collect();
    /// let poses = PreparedPoses::new(6, &q).unwrap();
    /// let mut out = vec![Pose::default(); 6];
    /// k.poses(&poses, 0..6, &mut out).unwrap();
    /// assert_eq!(out[5], k.pose(&q[5]).unwrap());
    /// ```
    pub fn poses(
        &self,
        poses: &PreparedPoses,
        range: Range<usize>,
        out: &mut [Pose],
    ) -> Result<(), KernelError> {
        self.one_per_pose(
            poses,
            range,
            out,
            |poses, start, out| BatchOp::Poses { poses, start, out },
            |t, post, i| t.after(post, i),
        )
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
        self.run(Op::Batch(BatchOp::Jacobians {
            poses,
            out: &mut *out,
        }))?;
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
        mut f: impl FnMut(usize, &[f64; 3], &[[f64; 3]]),
    ) -> Result<(), KernelError> {
        self.check_poses(poses, &range)?;
        match poses.post() {
            None => {
                let op = EachJacobianInlined { poses, range, f };
                match self.inner.run_inlined(op) {
                    Ok(()) => Ok(()),
                    Err(EachJacobianInlined {
                        poses,
                        range,
                        mut f,
                    }) => self.run(Op::Batch(BatchOp::EachJacobian {
                        poses,
                        range,
                        f: &mut f,
                    })),
                }
            }
            Some(post) => self.each_jacobian_after(poses, post, range, &mut f),
        }
    }

    /// [`ArmKernel::for_each_jacobian`] of the columns `free` only (each
    /// below [`ArmKernel::param_count`], a column twice if asked), handed
    /// over compacted by coordinate ([`FreeRows`]): on the measuring arms'
    /// inlined loops, four poses' free columns are moved out of the
    /// kernel's lanes at once. The same values in the same pose order as
    /// picking them out of [`ArmKernel::for_each_jacobian`]'s columns.
    pub(crate) fn for_each_free_jacobian(
        &self,
        poses: &PreparedPoses,
        range: Range<usize>,
        free: &[usize],
        mut f: impl FnMut(usize, &[f64; 3], FreeRows<'_>),
    ) -> Result<(), KernelError> {
        self.check_poses(poses, &range)?;
        // More columns than the inlined loop's stack tile holds (a model
        // beyond geometry asks for one per fitted correction too): the
        // fallback's rows are sized to them.
        let range = if poses.post().is_none() && free.len() <= MAX_FREE {
            let op = EachFreeJacobianInlined {
                poses,
                range,
                free,
                f,
            };
            match self.inner.run_inlined(op) {
                Ok(()) => return Ok(()),
                Err(op) => {
                    f = op.f;
                    op.range
                }
            }
        } else {
            range
        };
        let groups = free.len().div_ceil(LANES);
        let mut rows = vec![[0.0; LANES]; 3 * groups];
        self.for_each_jacobian(poses, range, |i, pos, jac| {
            let (x, rest) = rows.split_at_mut(groups);
            let (y, z) = rest.split_at_mut(groups);
            gather_free(jac, free, [&mut *x, &mut *y, &mut *z]);
            f(i, pos, [x, y, z]);
        })
    }

    /// [`ArmKernel::for_each_jacobian`] of poses with a transform after the
    /// chain (a model beyond geometry is on): one copy of the columns per
    /// pose, scaled. Out of line, so that the plain path compiles as before.
    #[cold]
    #[inline(never)]
    fn each_jacobian_after(
        &self,
        poses: &PreparedPoses,
        post: &Post,
        range: Range<usize>,
        f: &mut JacobianVisitor<'_>,
    ) -> Result<(), KernelError> {
        let mut scaled = vec![[0.0; 3]; self.param_count()];
        let mut g = |i: usize, p: &[f64; 3], jac: &[[f64; 3]]| {
            for (o, c) in scaled.iter_mut().zip(jac) {
                *o = c.map(|v| post.scale[i] * v);
            }
            f(i, &post.at(i, p), &scaled);
        };
        self.run(Op::Batch(BatchOp::EachJacobian {
            poses,
            range,
            f: &mut g,
        }))
    }

    /// Calls `f(pose, ∂p/∂q)` for every pose of `range` in order, with the
    /// `3 × n` joint Jacobian (mm/rad, mm/mm for a prismatic joint) as
    /// columns: what carries encoder noise into a touch's covariance. A
    /// batch of SIMD lanes at a time, the same bits as
    /// [`ArmKernel::joint_jacobian_at`] one pose at a time.
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
            None => {
                let op = EachJointJacobianInlined { poses, range, f };
                match self.inner.run_inlined(op) {
                    Ok(()) => Ok(()),
                    Err(EachJointJacobianInlined {
                        poses,
                        range,
                        mut f,
                    }) => self.run(Op::Batch(BatchOp::EachJointJacobian {
                        poses,
                        range,
                        f: &mut f,
                    })),
                }
            }
            Some(post) => {
                let mut scaled = vec![[0.0; 3]; self.joints()];
                let mut g = |i: usize, jq: &[[f64; 3]]| {
                    for (o, c) in scaled.iter_mut().zip(jq) {
                        *o = c.map(|v| post.scale[i] * v);
                    }
                    f(i, &scaled);
                };
                self.run(Op::Batch(BatchOp::EachJointJacobian {
                    poses,
                    range,
                    f: &mut g,
                }))
            }
        }
    }

    /// Calls `f(pose, tool, jacobian)` for every pose of `range` in order,
    /// with the tool's [`Pose`] and its `6 × (4n+3)` parameter Jacobian as
    /// columns (position rows, then rotation rows): what a fit to 6-D
    /// targets (a tracker's, a camera's) accumulates. A batch of SIMD
    /// lanes at a time, the same bits as [`ArmKernel::pose_jacobian`].
    ///
    /// ```
    /// use aacmm_core::{kernel::{ArmKernel, PreparedPoses}, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let q = [[0.3; 6]; 5];
    /// let poses = PreparedPoses::new(6, &q).unwrap();
    /// let mut one = [[0.0; 6]; 27];
    /// let tool = k.pose_jacobian(&q[0], &mut one).unwrap();
    /// k.for_each_pose_jacobian(&poses, 0..5, |_, t, jac| {
    ///     assert_eq!((*t, jac), (tool, &one[..]));
    /// }).unwrap();
    /// ```
    pub fn for_each_pose_jacobian(
        &self,
        poses: &PreparedPoses,
        range: Range<usize>,
        mut f: impl FnMut(usize, &Pose, &[[f64; 6]]),
    ) -> Result<(), KernelError> {
        self.check_poses(poses, &range)?;
        match poses.post() {
            None => self.run(Op::Batch(BatchOp::EachPoseJacobian {
                poses,
                range,
                f: &mut f,
            })),
            Some(post) => {
                // Scaling the arm moves the probe, it turns nothing: only
                // the position rows scale.
                let mut scaled = vec![[0.0; 6]; self.param_count()];
                let mut g = |i: usize, t: &Pose, jac: &[[f64; 6]]| {
                    for (o, c) in scaled.iter_mut().zip(jac) {
                        *o = *c;
                        o[..3].iter_mut().for_each(|v| *v *= post.scale[i]);
                    }
                    f(i, &t.after(post, i), &scaled);
                };
                self.run(Op::Batch(BatchOp::EachPoseJacobian {
                    poses,
                    range,
                    f: &mut g,
                }))
            }
        }
    }

    /// Probe positions of every row of readings (rad; mm for a prismatic
    /// joint), in row order: the convenience for callers holding plain rows.
    ///
    /// ```
    /// use aacmm_core::{kernel::ArmKernel, params::DhParams};
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let p = k.positions_of(&[vec![0.0; 6]]).unwrap();
    /// assert!((p[0][2] - 995.0).abs() < 1e-9);
    /// assert!(k.positions_of(&[vec![0.0; 7]]).is_err());
    /// ```
    pub fn positions_of<R: AsRef<[f64]>>(&self, rows: &[R]) -> Result<Vec<[f64; 3]>, KernelError> {
        let poses = PreparedPoses::for_shape(self.shape, rows)?;
        let mut out = vec![[0.0; 3]; poses.len()];
        self.positions(&poses, 0..poses.len(), &mut out)?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::SHIPPED_SHAPES;
    use crate::params::{DhJoint, JointKind, MAX_JOINTS};

    /// An arm of `shape` with every parameter 0.1 (lengths, angles).
    fn arm_of(shape: ChainShape) -> DhParams {
        let joint = |kind| DhJoint::dh(0.1, 0.1, 0.1, 0.1).with_kind(kind);
        DhParams {
            joints: shape.kinds().map(joint).collect(),
            probe: [0.1; 3],
        }
    }

    #[test]
    fn every_chain_of_1_to_12_joints_has_a_kernel() {
        for n in 0..=MAX_JOINTS + 1 {
            let made = DhParams::from_slice(&vec![0.1; 4 * n + 3]).map(|p| ArmKernel::new(&p));
            match made {
                Some(Ok(k)) => {
                    assert!((1..=MAX_JOINTS).contains(&n));
                    assert_eq!(k.joints(), n);
                }
                Some(Err(e)) => assert_eq!(e, KernelError::Unsupported(n)),
                None => assert_eq!(n, 0),
            }
        }
        for mask in 0..1u16 << 6 {
            let shape = ChainShape::from_mask(6, mask).unwrap();
            let k = ArmKernel::new(&arm_of(shape)).unwrap();
            assert_eq!(k.shape(), shape);
            let generated = SHIPPED_SHAPES.contains(&shape.to_string().as_str());
            let kind = if generated {
                KernelKind::Generated
            } else {
                KernelKind::Generic
            };
            assert_eq!(k.kind(), kind, "{shape}");
        }
    }

    #[test]
    fn shipped_shapes_run_on_generated_kernels() {
        for shape in SHIPPED_SHAPES {
            let shape: ChainShape = shape.parse().unwrap();
            let k = ArmKernel::new(&arm_of(shape)).unwrap();
            assert_eq!(k.kind(), KernelKind::Generated, "{shape}");
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
        assert!(k.pose_jacobian(&[0.0; 6], &mut [[0.0; 6]; 26]).is_err());
        assert!(
            k.joint_pose_jacobian(&[0.0; 6], &mut [[0.0; 6]; 5])
                .is_err()
        );
        // Readings of a slide are not those of a turn.
        let slide: ChainShape = "RRPRRR".parse().unwrap();
        let sliding = PreparedPoses::for_shape(slide, &[[0.0; 6]; 2]).unwrap();
        let e = k.positions(&sliding, 0..2, &mut out).unwrap_err();
        assert_eq!(
            e.to_string(),
            "the arm's chain is RRRRRR but the data is RRPRRR"
        );
    }

    #[test]
    fn a_users_chain_must_fit_the_arm() {
        use crate::kernel::arm::shipped::{arm6, arm6h, track6};
        let mut arm = DhParams::paper_nominal();
        let k = ArmKernel::with_chain::<arm6::Kernel, 6>(&arm).unwrap();
        assert_eq!(k, k.clone());
        assert_ne!(k, ArmKernel::new(&arm).unwrap());
        let q = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6];
        assert_eq!(k.position(&q), ArmKernel::new(&arm).unwrap().position(&q));
        arm.joints[2].model = crate::params::JointModel::Hayati;
        assert_eq!(
            ArmKernel::with_chain::<arm6::Kernel, 6>(&arm),
            Err(KernelError::NotExtended { joint: 3 })
        );
        assert!(ArmKernel::with_chain::<arm6h::Kernel, 6>(&arm).is_ok());
        let e = ArmKernel::with_chain::<track6::Kernel, 7>(&arm).unwrap_err();
        assert_eq!(
            e,
            KernelError::JointCount {
                expected: 7,
                got: 6
            }
        );
        arm.joints
            .push(DhJoint::default().with_kind(JointKind::Revolute));
        let e = ArmKernel::with_chain::<track6::Kernel, 7>(&arm).unwrap_err();
        assert_eq!(
            e.to_string(),
            "the arm's chain is RRRRRRR but the chain type is PRRRRRR"
        );
    }

    /// The free columns by coordinate are [`ArmKernel::for_each_jacobian`]'s
    /// columns picked out, on the inlined 6R loop (AVX where the CPU has
    /// it), a 5R chain's `dyn` loop and a user's chain; a range with a tail.
    #[test]
    fn free_jacobian_rows_are_the_picked_columns() {
        let six = DhParams::paper_nominal();
        let mut five = six.clone();
        five.joints.pop();
        let kernels = [
            ArmKernel::new(&six).unwrap(),
            ArmKernel::new(&five).unwrap(),
            ArmKernel::with_chain::<crate::kernel::Generic, 6>(&six).unwrap(),
        ];
        for k in &kernels {
            let n = k.joints();
            let q: Vec<Vec<f64>> = (0..11)
                .map(|i| (0..n).map(|j| ((i * 7 + j) as f64 * 0.37).sin()).collect())
                .collect();
            let poses = PreparedPoses::new(n, &q).unwrap();
            // Not a whole number of groups of four: the last one padded.
            let some: Vec<usize> = (0..k.param_count()).filter(|c| c % 3 != 1).rev().collect();
            assert_ne!(some.len() % 4, 0, "{}", k.shape());
            // Each column asked for twice and more: past the stack tile.
            let repeated: Vec<usize> = (0..k.param_count()).cycle().take(MAX_FREE + 3).collect();
            for free in [some, repeated] {
                let mut want = Vec::new();
                k.for_each_jacobian(&poses, 2..11, |i, p, jac| {
                    let cols: Vec<[f64; 3]> = free.iter().map(|&c| jac[c]).collect();
                    want.push((i, *p, cols));
                })
                .unwrap();
                let mut got = Vec::new();
                k.for_each_free_jacobian(&poses, 2..11, &free, |i, p, rows| {
                    let [x, y, z] = rows.map(|r| r.as_flattened());
                    for row in [x, y, z] {
                        assert_eq!(row.len(), free.len().div_ceil(4) * 4);
                        assert!(row[free.len()..].iter().all(|v| v.to_bits() == 0));
                    }
                    let cols: Vec<[f64; 3]> = (0..free.len()).map(|u| [x[u], y[u], z[u]]).collect();
                    got.push((i, *p, cols));
                })
                .unwrap();
                assert_eq!(got, want, "{}", k.shape());
            }
        }
    }
}
