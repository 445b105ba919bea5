//! The generated kernel: closed-form probe position and Jacobians of the 6- and
//! 7-joint chains, expanded at compile time by `dh_chain!`, behind one
//! runtime-sized type, [`ArmKernel`], that every caller uses.
//!
//! Trig is split by how often it changes: sin/cos of the encoder readings once
//! per data set ([`PreparedPoses`]), of the zero offsets and twists once per
//! parameter set (inside [`ArmKernel`]); the per-pose code only multiplies and
//! adds. Batches run four poses at a time in SIMD lanes (a crate-private
//! module: nothing outside the crate can run a lane instruction the CPU might
//! lack); the lanes do exactly the scalar operations, so results are
//! bit-identical to the one-pose functions whatever the CPU.
//!
//! [`ArmKernel`] is the only place that knows which joint counts have a
//! generated chain ([`SUPPORTED_JOINTS`](crate::params::SUPPORTED_JOINTS));
//! the const-generic layer below it ([`Chain`], [`PreparedParams`],
//! [`position`], [`joint_jacobian`]) is public for oracles and tests.
//!
//! ```compile_fail
//! // The SIMD lanes are not reachable from outside the crate.
//! use aacmm_core::kernel::lanes::Avx;
//! ```

mod arm;
mod lanes;

use std::ops::{Add, Mul, Neg, Sub};

use thiserror::Error;

use crate::params::{DhParams, JointModel};
use lanes::{Batch, LANES, Two};

aacmm_dh_macros::dh_chain! {
    /// The 6-joint measuring arm (27 parameters).
    pub mod arm6 { joints = 6, probe = true }
}

aacmm_dh_macros::dh_chain! {
    /// The 7-joint (7-axis) arm (31 parameters).
    pub mod arm7 { joints = 7, probe = true }
}

aacmm_dh_macros::dh_chain! {
    /// The 6-joint arm with any subset of Hayati joints (27 parameters).
    pub mod arm6h { joints = 6, probe = true, hayati = true }
}

aacmm_dh_macros::dh_chain! {
    /// The 7-joint arm with any subset of Hayati joints (31 parameters).
    pub mod arm7h { joints = 7, probe = true, hayati = true }
}

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
    /// No generated kernel for this many joints.
    #[error(
        "no kernel for {0} joints: the toolkit generates kernels for {text}",
        text = crate::params::supported_joints_text()
    )]
    Unsupported(usize),
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
/// sin/cos of the zero offsets and twists; for the extended chain
/// ([`Hayati`]) also the sin/cos of the Hayati rotations and which joints
/// are Hayati (the D-H chain ignores those).
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
    /// d, mm (0 for a Hayati joint).
    pub d: [S; N],
    /// cos β (1 for a D-H joint).
    pub cb: [S; N],
    /// sin β (0 for a D-H joint).
    pub sb: [S; N],
    /// Whether joint `i` is Hayati: its d-slot's Jacobian column is `∂p/∂β`.
    pub hayati: [bool; N],
    /// Probe offset, mm.
    pub b: [S; 3],
}

/// A parameter set prepared for the kernel: trig computed once.
pub type PreparedParams<const N: usize> = Consts<f64, N>;

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
            b: params.probe,
        })
    }

    /// Whether some joint is Hayati, so that only the extended chain
    /// ([`Hayati`]) computes this arm.
    pub fn has_hayati(&self) -> bool {
        self.hayati.contains(&true)
    }

    /// The same constants in another scalar type (every lane the same).
    pub fn splat<S: From<f64>>(&self) -> Consts<S, N> {
        let s = |v: &[f64; N]| v.map(S::from);
        Consts {
            ct: s(&self.ct),
            st: s(&self.st),
            ca: s(&self.ca),
            sa: s(&self.sa),
            a: s(&self.a),
            d: s(&self.d),
            cb: s(&self.cb),
            sb: s(&self.sb),
            hayati: self.hayati,
            b: self.b.map(S::from),
        }
    }
}

/// The generated functions of an `N`-joint chain. Implemented by [`Dh`] and
/// [`Hayati`] for the chains the toolkit generates (6 and 7 joints).
pub trait Chain<const N: usize> {
    /// Number of geometric parameters, `4N + 3`.
    const PARAMS: usize;
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
}

/// The generated D-H kernels; see [`Chain`]. They ignore the β inputs, so
/// they compute an arm only when no joint is Hayati.
#[derive(Clone, Copy, Debug)]
pub struct Dh;

/// The generated extended kernels (`Ry(β)` in every link, the d-slot's
/// column chosen per joint); see [`Chain`]. Correct for any arm, D-H
/// included, but dearer: [`ArmKernel`] uses them only for an arm with a
/// Hayati joint.
#[derive(Clone, Copy, Debug)]
pub struct Hayati;

/// `Chain<$n>` for `$model` over the generated module `$m`: `$geo` are the
/// geometry constants its functions take (in order, before the joints'
/// cos/sin), `$col` those only its parameter Jacobian takes after them.
macro_rules! impl_chain {
    ($model:ident, $n:literal, $m:ident, [$($geo:ident),*], [$($col:ident),*]) => {
        impl Chain<$n> for $model {
            const PARAMS: usize = $m::PARAMS;

            #[inline(always)]
            fn position<S: Scalar>(k: &Consts<S, $n>, cq: &[S; $n], sq: &[S; $n]) -> [S; 3] {
                $m::position($(&k.$geo,)* cq, sq)
            }

            #[inline(always)]
            fn position_jacobian<S: Scalar>(
                k: &Consts<S, $n>,
                cq: &[S; $n],
                sq: &[S; $n],
                jac: &mut [[S; 3]],
            ) -> [S; 3] {
                // Invariant: every caller sizes `jac` from the chain's
                // PARAMS (the public entry points check the length first).
                let jac: &mut [[S; 3]; $m::PARAMS] = jac
                    .try_into()
                    .expect("jacobian buffer holds 4n + 3 columns");
                $m::position_jacobian($(&k.$geo,)* cq, sq, $(&k.$col,)* jac)
            }

            #[inline(always)]
            fn joint_jacobian<S: Scalar>(
                k: &Consts<S, $n>,
                cq: &[S; $n],
                sq: &[S; $n],
                jac: &mut [[S; 3]; $n],
            ) -> [S; 3] {
                $m::joint_jacobian($(&k.$geo,)* cq, sq, jac)
            }
        }
    };
}

impl_chain!(Dh, 6, arm6, [ct, st, ca, sa, a, d, b], []);
impl_chain!(Dh, 7, arm7, [ct, st, ca, sa, a, d, b], []);
impl_chain!(
    Hayati,
    6,
    arm6h,
    [ct, st, ca, sa, a, d, cb, sb, b],
    [hayati]
);
impl_chain!(
    Hayati,
    7,
    arm7h,
    [ct, st, ca, sa, a, d, cb, sb, b],
    [hayati]
);

/// Encoder readings of a data set with their sin/cos, computed once and laid
/// out joint by joint (structure of arrays) so that four poses load as one
/// SIMD vector.
#[derive(Clone, Debug, PartialEq)]
pub struct PreparedPoses {
    joints: usize,
    len: usize,
    /// `cos[j][i]`: cos of joint `j`'s reading at pose `i`.
    cos: Vec<Vec<f64>>,
    sin: Vec<Vec<f64>>,
    /// What follows the chain at each pose, if anything (a thermal scale,
    /// a drift): see [`Post`].
    post: Option<Box<Post>>,
}

/// A per-pose transform after the chain: the position seen is
/// `scale_i · p(q_i) + offset_i` — the whole arm grown by a temperature
/// (every length scales, so the probe's position about the base does), or
/// its base drifted in time. The kernel applies it to positions and to
/// every Jacobian column (`offset` does not depend on the arm).
#[derive(Clone, Debug, PartialEq)]
pub struct Post {
    /// Per pose, the scale (1 when none).
    pub scale: Vec<f64>,
    /// Per pose, the offset, mm.
    pub offset: Vec<[f64; 3]>,
}

impl Post {
    /// Pose `i`'s position `p` of the chain as seen: `scale_i·p + offset_i`.
    #[inline]
    pub fn at(&self, i: usize, p: &[f64; 3]) -> [f64; 3] {
        let (s, off) = (self.scale[i], self.offset[i]);
        std::array::from_fn(|r| s * p[r] + off[r])
    }
}

impl PreparedPoses {
    /// Prepares readings (rad), one row of `joints` readings per pose.
    ///
    /// ```
    /// use aacmm_core::kernel::PreparedPoses;
    /// let poses = PreparedPoses::new(6, &[[0.0; 6], [0.5; 6]]).unwrap();
    /// assert_eq!((poses.len(), poses.joints()), (2, 6));
    /// assert!(PreparedPoses::new(6, &[vec![0.0; 7]]).is_err());
    /// ```
    pub fn new<R: AsRef<[f64]>>(joints: usize, rows: &[R]) -> Result<Self, KernelError> {
        if let Some(r) = rows.iter().find(|r| r.as_ref().len() != joints) {
            return Err(KernelError::JointCount {
                expected: joints,
                got: r.as_ref().len(),
            });
        }
        // Direct calls, not a function pointer: whether LLVM sees through a
        // pointer depends on the crate that instantiates `new` (the C ABI's
        // copy kept an indirect call per reading, a few percent of its batch).
        Ok(PreparedPoses::from_columns(joints, rows.len(), |j| {
            rows.iter().map(move |r| r.as_ref()[j])
        }))
    }

    /// sin and cos of every joint's column of readings; generic over the
    /// column, so each caller gets its own direct-call loop.
    fn from_columns<I: Iterator<Item = f64>>(
        joints: usize,
        len: usize,
        column: impl Fn(usize) -> I,
    ) -> Self {
        PreparedPoses {
            joints,
            len,
            cos: (0..joints)
                .map(|j| column(j).map(f64::cos).collect())
                .collect(),
            sin: (0..joints)
                .map(|j| column(j).map(f64::sin).collect())
                .collect(),
            post: None,
        }
    }

    /// Poses from the cos and sin of their readings, joint by joint
    /// (`cos[j][i]`): readings corrected by small angles through the angle
    /// sums, without a transcendental call per reading.
    pub(crate) fn from_trig(
        joints: usize,
        len: usize,
        cos: Vec<Vec<f64>>,
        sin: Vec<Vec<f64>>,
    ) -> Self {
        debug_assert!(cos.len() == joints && sin.len() == joints);
        PreparedPoses {
            joints,
            len,
            cos,
            sin,
            post: None,
        }
    }

    /// The cos and sin of joint `j`'s readings, pose by pose.
    pub(crate) fn column_trig(&self, j: usize) -> (&[f64], &[f64]) {
        (&self.cos[j], &self.sin[j])
    }

    /// These poses with `post` applied after the chain.
    ///
    /// # Panics
    ///
    /// When `post` has another length than the poses (a bug, not input).
    pub fn with_post(mut self, post: Post) -> Self {
        assert!(
            post.scale.len() == self.len && post.offset.len() == self.len,
            "one scale and offset per pose"
        );
        self.post = Some(Box::new(post));
        self
    }

    /// The transform after the chain, if any.
    pub fn post(&self) -> Option<&Post> {
        self.post.as_deref()
    }

    /// Prepares `len` poses of `joints` readings (rad), row after row in
    /// `q`: [`PreparedPoses::new`] without a slice per row.
    pub(crate) fn from_flat(joints: usize, len: usize, q: &[f64]) -> Self {
        // Invariant: the data set passes its own `len` rows of `joints`.
        assert_eq!(q.len(), joints * len, "readings of {len} poses");
        PreparedPoses::from_columns(joints, len, |j| (0..len).map(move |i| q[i * joints + j]))
    }

    /// Number of poses.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are no poses.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Readings per pose.
    pub fn joints(&self) -> usize {
        self.joints
    }

    /// cos and sin of pose `i`'s readings; the caller has checked `N`.
    #[inline(always)]
    pub(crate) fn trig<const N: usize>(&self, i: usize) -> ([f64; N], [f64; N]) {
        (
            std::array::from_fn(|j| self.cos[j][i]),
            std::array::from_fn(|j| self.sin[j][i]),
        )
    }

    /// The sin/cos of `count` whole batches of poses from `start`, cut
    /// once per call so that the batch loops load without checks; the
    /// caller has checked `N` and the range.
    #[inline(always)]
    fn batches<const N: usize>(&self, start: usize, count: usize) -> Batches<'_, N> {
        let end = start + count * LANES;
        let mut cos: [&[[f64; LANES]]; N] = [&[]; N];
        let mut sin: [&[[f64; LANES]]; N] = [&[]; N];
        // Plain loops, not `array::from_fn`: its closure is not always
        // inlined. `[..count]` makes every column's length the loop bound
        // itself, so the loads in `Batches::get` need no check.
        for j in 0..N {
            cos[j] = &self.cos[j][start..end].as_chunks().0[..count];
            sin[j] = &self.sin[j][start..end].as_chunks().0[..count];
        }
        Batches { count, cos, sin }
    }
}

/// Whole batches of [`LANES`] poses of a [`PreparedPoses`], column by
/// column: what the batch loops index. The runtime-sized storage behind
/// `PreparedPoses` (a `Vec` of columns) would otherwise cost a joint-count
/// check, a pointer load and a range check for every load of every batch —
/// as many scalar instructions as the position kernel has vector ones.
struct Batches<'a, const N: usize> {
    /// Number of batches: the length of every column.
    count: usize,
    cos: [&'a [[f64; LANES]]; N],
    sin: [&'a [[f64; LANES]]; N],
}

impl<const N: usize> Batches<'_, N> {
    /// cos and sin of batch `b`'s readings, one lane per pose.
    // Plain loops, not `array::from_fn`: its closure is not always inlined,
    // and out of line the AVX loads become calls.
    #[inline(always)]
    fn get<L: Batch>(&self, b: usize) -> ([L; N], [L; N]) {
        let mut c = [L::from(0.0); N];
        let mut s = [L::from(0.0); N];
        for j in 0..N {
            c[j] = L::load(&self.cos[j][b]);
            s[j] = L::load(&self.sin[j][b]);
        }
        (c, s)
    }
}

/// Probe position of one pose with readings `q` (rad).
///
/// ```
/// use aacmm_core::{kernel, params::DhParams};
/// let k = kernel::PreparedParams::<6>::new(&DhParams::paper_nominal()).unwrap();
/// let p = kernel::position(&k, &[0.0; 6]);
/// assert!((p[2] - 995.0).abs() < 1e-9);
/// ```
pub fn position<const N: usize>(k: &PreparedParams<N>, q: &[f64; N]) -> [f64; 3]
where
    Dh: Chain<N>,
    Hayati: Chain<N>,
{
    let (cq, sq) = (q.map(f64::cos), q.map(f64::sin));
    if k.has_hayati() {
        Hayati::position(k, &cq, &sq)
    } else {
        Dh::position(k, &cq, &sq)
    }
}

/// Probe position and `∂p/∂q` of one pose (rad); what inverse kinematics needs.
///
/// ```
/// use aacmm_core::{kernel, params::DhParams};
/// let k = kernel::PreparedParams::<6>::new(&DhParams::paper_nominal()).unwrap();
/// let (_, jq) = kernel::joint_jacobian(&k, &[0.0; 6]);
/// assert!((jq[0][1] + 5.0).abs() < 1e-9); // joint 1 moves the probe along −y
/// ```
pub fn joint_jacobian<const N: usize>(
    k: &PreparedParams<N>,
    q: &[f64; N],
) -> ([f64; 3], [[f64; 3]; N])
where
    Dh: Chain<N>,
    Hayati: Chain<N>,
{
    let mut jac = [[0.0; 3]; N];
    let (cq, sq) = (q.map(f64::cos), q.map(f64::sin));
    let p = if k.has_hayati() {
        Hayati::joint_jacobian(k, &cq, &sq, &mut jac)
    } else {
        Dh::joint_jacobian(k, &cq, &sq, &mut jac)
    };
    (p, jac)
}

/// Probe positions and parameter Jacobians of a batch of poses, stored
/// structure-of-arrays: for each output (a position coordinate, or one row of
/// one parameter column) the values of all poses are contiguous, which is how
/// the SIMD lanes produce them.
#[derive(Clone, Debug, PartialEq)]
pub struct Jacobians {
    len: usize,
    params: usize,
    /// `[coordinate][pose]`.
    pos: Vec<f64>,
    /// `[parameter][coordinate][pose]`.
    jac: Vec<f64>,
}

impl Jacobians {
    /// Zeroed storage for `len` poses and `params` parameters.
    pub fn new(len: usize, params: usize) -> Jacobians {
        Jacobians {
            len,
            params,
            pos: vec![0.0; 3 * len],
            jac: vec![0.0; 3 * params * len],
        }
    }

    /// Number of poses.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are no poses.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Number of parameters (columns).
    pub fn params(&self) -> usize {
        self.params
    }

    /// Probe position of pose `i` (mm).
    pub fn position(&self, i: usize) -> [f64; 3] {
        [0, 1, 2].map(|r| self.pos[r * self.len + i])
    }

    /// `∂p/∂parameter_c` of pose `i`.
    pub fn column(&self, i: usize, c: usize) -> [f64; 3] {
        [0, 1, 2].map(|r| self.jac[(3 * c + r) * self.len + i])
    }

    /// `∂p_r/∂parameter_c` of every pose, contiguous.
    pub fn row(&self, c: usize, r: usize) -> &[f64] {
        let start = (3 * c + r) * self.len;
        &self.jac[start..start + self.len]
    }

    /// `post` applied to every pose's position and columns.
    pub(crate) fn apply_post(&mut self, post: &Post) {
        let n = self.len;
        for i in 0..n {
            let s = post.scale[i];
            let p = post.at(i, &self.position(i));
            for (r, v) in p.into_iter().enumerate() {
                self.pos[r * n + i] = v;
            }
            for c in 0..self.params {
                for r in 0..3 {
                    self.jac[(3 * c + r) * n + i] *= s;
                }
            }
        }
    }

    #[inline(always)]
    fn set(&mut self, i: usize, p: [f64; 3], cols: &[[f64; 3]]) {
        for (r, v) in p.into_iter().enumerate() {
            self.pos[r * self.len + i] = v;
        }
        for (c, col) in cols.iter().enumerate() {
            for (r, &v) in col.iter().enumerate() {
                self.jac[(3 * c + r) * self.len + i] = v;
            }
        }
    }
}

#[inline(always)]
fn positions_impl<const N: usize, C: Chain<N>, L: Batch>(
    k: &PreparedParams<N>,
    poses: &PreparedPoses,
    start: usize,
    out: &mut [[f64; 3]],
) {
    let kl: Consts<L, N> = k.splat();
    let k2: Consts<Two<L>, N> = k.splat();
    let (whole, rest) = out.as_chunks_mut::<LANES>();
    let batches = poses.batches::<N>(start, whole.len());
    // Two batches at a time (see `Two`), then an odd one.
    let mut pairs = whole.chunks_exact_mut(2);
    for (b, dst) in (0..batches.count).step_by(2).zip(&mut pairs) {
        let ((c0, s0), (c1, s1)) = (batches.get::<L>(b), batches.get::<L>(b + 1));
        let mut cq = [Two(c0[0], c1[0]); N];
        let mut sq = [Two(s0[0], s1[0]); N];
        for j in 0..N {
            cq[j] = Two(c0[j], c1[j]);
            sq[j] = Two(s0[j], s1[j]);
        }
        let [x, y, z] = C::position(&k2, &cq, &sq);
        transpose(&[[x.0, y.0, z.0]], &mut dst[0]);
        transpose(&[[x.1, y.1, z.1]], &mut dst[1]);
    }
    if let [dst] = pairs.into_remainder() {
        let (cq, sq) = batches.get::<L>(batches.count - 1);
        let p = C::position(&kl, &cq, &sq);
        transpose(&[p], dst);
    }
    let tail = start + batches.count * LANES;
    for (o, slot) in rest.iter_mut().enumerate() {
        let (cq, sq) = poses.trig::<N>(tail + o);
        *slot = C::position(k, &cq, &sq);
    }
}

/// Batch `b`'s four values of a row of `len` values per pose (one
/// coordinate of the positions or of a Jacobian column).
#[inline(always)]
fn lanes_of(row: &mut [f64], b: usize) -> &mut [f64; LANES] {
    &mut row.as_chunks_mut().0[b]
}

#[inline(always)]
fn jacobians_impl<const N: usize, C: Chain<N>, L: Batch>(
    k: &PreparedParams<N>,
    poses: &PreparedPoses,
    out: &mut Jacobians,
) {
    let kl: Consts<L, N> = k.splat();
    let params = <C as Chain<N>>::PARAMS;
    let len = out.len;
    let mut jl = vec![[L::from(0.0); 3]; params];
    let batches = poses.batches::<N>(0, poses.len() / LANES);
    for b in 0..batches.count {
        let (cq, sq) = batches.get::<L>(b);
        let p = C::position_jacobian(&kl, &cq, &sq, &mut jl);
        // Rows of `len` values, one per output: `len ≥ LANES` here.
        for (row, v) in out.pos.chunks_exact_mut(len).zip(p) {
            v.store(lanes_of(row, b));
        }
        for (row, v) in out.jac.chunks_exact_mut(len).zip(jl.iter().flatten()) {
            v.store(lanes_of(row, b));
        }
    }
    let mut cols = vec![[0.0; 3]; params];
    for i in batches.count * LANES..poses.len() {
        let (cq, sq) = poses.trig::<N>(i);
        let p = C::position_jacobian(k, &cq, &sq, &mut cols);
        out.set(i, p, &cols);
    }
}

#[inline(always)]
fn for_each_lane_jacobian<const N: usize, C: Chain<N>, L: Batch>(
    k: &PreparedParams<N>,
    poses: &PreparedPoses,
    range: std::ops::Range<usize>,
    mut f: impl FnMut(usize, &[f64; 3], &[[f64; 3]]),
) {
    let kl: Consts<L, N> = k.splat();
    let params = <C as Chain<N>>::PARAMS;
    let mut jl = vec![[L::from(0.0); 3]; params];
    let mut tile = vec![[0.0; 3]; LANES * params];
    let mut pos = [[0.0; 3]; LANES];
    let batches = poses.batches::<N>(range.start, range.len() / LANES);
    for b in 0..batches.count {
        let (cq, sq) = batches.get::<L>(b);
        let p = C::position_jacobian(&kl, &cq, &sq, &mut jl);
        transpose(&[p], &mut pos);
        transpose(&jl, &mut tile);
        let i = range.start + b * LANES;
        for (l, cols) in tile.chunks_exact(params).enumerate() {
            f(i + l, &pos[l], cols);
        }
    }
    for i in range.start + batches.count * LANES..range.end {
        let (cq, sq) = poses.trig::<N>(i);
        let p = C::position_jacobian(k, &cq, &sq, &mut tile[..params]);
        f(i, &p, &tile[..params]);
    }
}

/// [`for_each_lane_jacobian`] for `∂p/∂q`: each pose's joint Jacobian
/// (`N` columns) to `f`, in pose order, a batch of lanes at a time.
#[inline(always)]
fn for_each_lane_joint_jacobian<const N: usize, C: Chain<N>, L: Batch>(
    k: &PreparedParams<N>,
    poses: &PreparedPoses,
    range: std::ops::Range<usize>,
    mut f: impl FnMut(usize, &[[f64; 3]; N]),
) {
    let kl: Consts<L, N> = k.splat();
    let mut jl = [[L::from(0.0); 3]; N];
    let mut tile = [[[0.0; 3]; N]; LANES];
    let batches = poses.batches::<N>(range.start, range.len() / LANES);
    for b in 0..batches.count {
        let (cq, sq) = batches.get::<L>(b);
        C::joint_jacobian(&kl, &cq, &sq, &mut jl);
        transpose(&jl, tile.as_flattened_mut());
        let i = range.start + b * LANES;
        for (l, cols) in tile.iter().enumerate() {
            f(i + l, cols);
        }
    }
    let mut cols = [[0.0; 3]; N];
    for i in range.start + batches.count * LANES..range.end {
        let (cq, sq) = poses.trig::<N>(i);
        C::joint_jacobian(k, &cq, &sq, &mut cols);
        f(i, &cols);
    }
}

/// Lanes (column-major across poses) to one block of columns per pose:
/// `dst[l·C + c] = cols[c]` of lane `l`, for `C = cols.len()` columns.
#[inline(always)]
fn transpose<L: Batch>(cols: &[[L; 3]], dst: &mut [[f64; 3]]) {
    let c_count = cols.len();
    let dst = &mut dst[..LANES * c_count];
    for (c, col) in cols.iter().enumerate() {
        let [x, y, z] = [col[0].to_array(), col[1].to_array(), col[2].to_array()];
        for l in 0..LANES {
            dst[l * c_count + c] = [x[l], y[l], z[l]];
        }
    }
}

pub use arm::ArmKernel;
#[cfg(test)]
mod tests {
    use super::lanes::Lanes;
    use super::*;

    /// The portable lanes (what CPUs without AVX2 run) give the one-pose
    /// results bit for bit, like the AVX path the integration tests see here.
    #[test]
    fn portable_lanes_equal_single_poses() {
        let mut hayati = DhParams::paper_nominal();
        hayati.joints[1].model = JointModel::Hayati;
        hayati.joints[1].beta = 0.01;
        portable_lanes_equal_single_poses_of::<Dh>(&DhParams::paper_nominal());
        portable_lanes_equal_single_poses_of::<Hayati>(&hayati);
    }

    fn portable_lanes_equal_single_poses_of<C: Chain<6>>(params: &DhParams) {
        let k = PreparedParams::<6>::new(params).unwrap();
        // 15 poses: a pair of batches, an odd batch and a tail of three.
        let q: Vec<[f64; 6]> = (0..15)
            .map(|i| std::array::from_fn(|j| ((i * 5 + j) as f64 * 0.61).sin() * 3.0))
            .collect();
        let poses = PreparedPoses::new(6, &q).unwrap();
        let mut pos = vec![[0.0; 3]; q.len()];
        positions_impl::<6, C, Lanes>(&k, &poses, 0, &mut pos);
        // From pose 1: one pair of batches and a tail of two.
        let mut from_one = vec![[0.0; 3]; 10];
        positions_impl::<6, C, Lanes>(&k, &poses, 1, &mut from_one);
        assert_eq!(from_one, pos[1..11]);
        let mut batch = Jacobians::new(q.len(), 27);
        jacobians_impl::<6, C, Lanes>(&k, &poses, &mut batch);
        let mut seen = 0;
        for_each_lane_jacobian::<6, C, Lanes>(&k, &poses, 0..q.len(), |i, p, cols| {
            assert_eq!(*p, batch.position(i));
            for (c, col) in cols.iter().enumerate() {
                assert_eq!(*col, batch.column(i, c));
            }
            seen += 1;
        });
        assert_eq!(seen, q.len());
        for (i, qi) in q.iter().enumerate() {
            assert_eq!(pos[i], position(&k, qi));
            let (cq, sq) = poses.trig::<6>(i);
            let mut cols = vec![[0.0; 3]; 27];
            let p = C::position_jacobian(&k, &cq, &sq, &mut cols);
            assert_eq!(p, batch.position(i));
            for (c, col) in cols.iter().enumerate() {
                assert_eq!(*col, batch.column(i, c));
            }
        }
    }
}
