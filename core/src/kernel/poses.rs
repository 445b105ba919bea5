//! A data set's joint readings prepared for the kernel: the sin/cos of the
//! revolute joints' readings (computed once per data set), the prismatic
//! joints' readings themselves, and what follows the chain ([`Post`]).

use super::KernelError;
use super::lanes::{Batch, LANES};
use crate::params::{ChainShape, MAX_JOINTS};

/// Encoder readings of a data set with their sin/cos, computed once and laid
/// out joint by joint (structure of arrays) so that four poses load as one
/// SIMD vector.
///
/// A prismatic joint's column holds its readings (mm) where a revolute
/// joint's holds their cos, and no sin: a data set of revolute joints takes
/// as much memory as it always did, one of prismatic joints less.
#[derive(Clone, Debug, PartialEq)]
pub struct PreparedPoses {
    joints: usize,
    /// Bit `j`: joint `j` is prismatic (its `cos` column holds the
    /// readings, its `sin` column is empty).
    prismatic: u16,
    len: usize,
    /// `cos[j][i]`: cos of joint `j`'s reading at pose `i` (the reading of
    /// a prismatic joint).
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
/// every Jacobian column (`offset` does not depend on the arm); a tool's
/// orientation, and the rotation rows of a pose Jacobian, it leaves alone
/// (neither scaling nor translation turns anything).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Post {
    /// Per pose, the scale (1 when none).
    pub scale: Vec<f64>,
    /// Per pose, the offset, mm.
    pub offset: Vec<[f64; 3]>,
}

impl Post {
    /// Pose `i`'s position `p` of the chain as seen: `scale_i·p + offset_i`.
    #[inline]
    pub(crate) fn at(&self, i: usize, p: &[f64; 3]) -> [f64; 3] {
        let (s, off) = (self.scale[i], self.offset[i]);
        std::array::from_fn(|r| s * p[r] + off[r])
    }
}

/// Whether joint `j` is among the prismatic joints `prismatic` (bit `j`).
fn slides(prismatic: u16, j: usize) -> bool {
    j < MAX_JOINTS && prismatic & (1 << j) != 0
}

impl PreparedPoses {
    /// Prepares readings (rad) of revolute joints, one row of `joints`
    /// readings per pose. (A chain with prismatic joints prepares its
    /// readings with [`PreparedPoses::for_shape`].)
    ///
    /// ```
    /// use aacmm_core::kernel::PreparedPoses;
    /// let poses = PreparedPoses::new(6, &[[0.0; 6], [0.5; 6]]).unwrap();
    /// assert_eq!((poses.len(), poses.joints()), (2, 6));
    /// assert!(PreparedPoses::new(6, &[vec![0.0; 7]]).is_err());
    /// ```
    pub fn new<R: AsRef<[f64]>>(joints: usize, rows: &[R]) -> Result<Self, KernelError> {
        PreparedPoses::with_mask(joints, 0, rows)
    }

    /// Prepares readings of a chain of `shape`, one row per pose: radians
    /// for a revolute joint, mm for a prismatic one.
    ///
    /// ```
    /// use aacmm_core::{kernel::PreparedPoses, params::ChainShape};
    /// let shape: ChainShape = "PRR".parse().unwrap();
    /// let poses = PreparedPoses::for_shape(shape, &[[250.0, 0.1, 0.2]]).unwrap();
    /// assert_eq!(poses.shape(), Some(shape));
    /// assert!(PreparedPoses::for_shape(shape, &[[0.0; 4]]).is_err());
    /// ```
    pub fn for_shape<R: AsRef<[f64]>>(shape: ChainShape, rows: &[R]) -> Result<Self, KernelError> {
        PreparedPoses::with_mask(shape.joints(), shape.prismatic_mask(), rows)
    }

    fn with_mask<R: AsRef<[f64]>>(
        joints: usize,
        prismatic: u16,
        rows: &[R],
    ) -> Result<Self, KernelError> {
        if let Some(r) = rows.iter().find(|r| r.as_ref().len() != joints) {
            return Err(KernelError::JointCount {
                expected: joints,
                got: r.as_ref().len(),
            });
        }
        // Direct calls, not a function pointer: whether LLVM sees through a
        // pointer depends on the crate that instantiates `new` (the C ABI's
        // copy kept an indirect call per reading, a few percent of its batch).
        Ok(PreparedPoses::from_columns(
            joints,
            prismatic,
            rows.len(),
            |j| rows.iter().map(move |r| r.as_ref()[j]),
        ))
    }

    /// sin and cos of every revolute joint's column of readings, the
    /// readings of every prismatic one; generic over the column, so each
    /// caller gets its own direct-call loop.
    fn from_columns<I: Iterator<Item = f64>>(
        joints: usize,
        prismatic: u16,
        len: usize,
        column: impl Fn(usize) -> I,
    ) -> Self {
        let slides = |j| slides(prismatic, j);
        PreparedPoses {
            joints,
            prismatic,
            len,
            cos: (0..joints)
                .map(|j| {
                    if slides(j) {
                        column(j).collect()
                    } else {
                        column(j).map(f64::cos).collect()
                    }
                })
                .collect(),
            sin: (0..joints)
                .map(|j| {
                    if slides(j) {
                        Vec::new()
                    } else {
                        column(j).map(f64::sin).collect()
                    }
                })
                .collect(),
            post: None,
        }
    }

    /// Poses from the cos and sin of their readings, joint by joint
    /// (`cos[j][i]`; a prismatic joint's readings in `cos[j]`, `sin[j]`
    /// empty): readings corrected by small angles through the angle sums,
    /// without a transcendental call per reading.
    pub(crate) fn from_trig(
        joints: usize,
        prismatic: u16,
        len: usize,
        cos: Vec<Vec<f64>>,
        sin: Vec<Vec<f64>>,
    ) -> Self {
        debug_assert!(cos.len() == joints && sin.len() == joints);
        PreparedPoses {
            joints,
            prismatic,
            len,
            cos,
            sin,
            post: None,
        }
    }

    /// The cos and sin of joint `j`'s readings, pose by pose; for a
    /// prismatic joint its readings (mm) and an empty slice.
    pub(crate) fn column_trig(&self, j: usize) -> (&[f64], &[f64]) {
        (&self.cos[j], &self.sin[j])
    }

    /// These poses with `post` applied after the chain.
    ///
    /// # Panics
    ///
    /// When `post` has another length than the poses (a bug, not input).
    pub(crate) fn with_post(mut self, post: Post) -> Self {
        assert!(
            post.scale.len() == self.len && post.offset.len() == self.len,
            "one scale and offset per pose"
        );
        self.post = Some(Box::new(post));
        self
    }

    /// Every `step`-th of these poses (`step` ≥ 1), from the first: the
    /// same cos, sin and transform after the chain, so the kernel gives
    /// each the same bits as in the whole set — in one call, four to a
    /// batch, where a call per sampled pose would fill one lane of four.
    pub(crate) fn every(&self, step: usize) -> PreparedPoses {
        fn pick<T: Copy>(v: &[T], step: usize) -> Vec<T> {
            v.iter().step_by(step).copied().collect()
        }
        PreparedPoses {
            joints: self.joints,
            prismatic: self.prismatic,
            len: self.len.div_ceil(step),
            cos: self.cos.iter().map(|c| pick(c, step)).collect(),
            sin: self.sin.iter().map(|s| pick(s, step)).collect(),
            post: self.post.as_ref().map(|p| {
                Box::new(Post {
                    scale: pick(&p.scale, step),
                    offset: pick(&p.offset, step),
                })
            }),
        }
    }

    /// The transform after the chain, if any.
    pub(crate) fn post(&self) -> Option<&Post> {
        self.post.as_deref()
    }

    /// Prepares `len` poses of `joints` readings, row after row in `q`
    /// ([`PreparedPoses::new`] without a slice per row), of a chain whose
    /// joints of the bits `prismatic` slide (their readings in mm).
    pub(crate) fn from_flat_with(joints: usize, prismatic: u16, len: usize, q: &[f64]) -> Self {
        // Invariant: the data set passes its own `len` rows of `joints`.
        assert_eq!(q.len(), joints * len, "readings of {len} poses");
        PreparedPoses::from_columns(joints, prismatic, len, |j| {
            (0..len).map(move |i| q[i * joints + j])
        })
    }

    /// [`PreparedPoses::from_flat_with`] on up to `threads` threads, in
    /// fixed chunks of poses: each reading's sin and cos are those of one
    /// thread (the same calls, so the same bits). Few poses run on the
    /// calling thread ([`crate::parallel::threads_for`]).
    pub(crate) fn from_flat_on(
        joints: usize,
        prismatic: u16,
        len: usize,
        q: &[f64],
        threads: usize,
    ) -> Self {
        /// Poses a work item: 4 096 × 6 sin and cos, about a millisecond.
        const CHUNK: usize = 4096;
        let chunks = len.div_ceil(CHUNK);
        if crate::parallel::threads_for(chunks, threads) <= 1 {
            return PreparedPoses::from_flat_with(joints, prismatic, len, q);
        }
        assert_eq!(q.len(), joints * len, "readings of {len} poses");
        let slides = |j| slides(prismatic, j);
        let mut cos: Vec<Vec<f64>> = (0..joints).map(|_| vec![0.0; len]).collect();
        let mut sin: Vec<Vec<f64>> = (0..joints)
            .map(|j| {
                if slides(j) {
                    Vec::new()
                } else {
                    vec![0.0; len]
                }
            })
            .collect();
        // Work item `c`: chunk `c` of every column (a prismatic joint's sin
        // column is empty, its part too).
        type Parts<'a> = (usize, Vec<&'a mut [f64]>, Vec<&'a mut [f64]>);
        let mut items: Vec<Parts> = (0..chunks).map(|c| (c, Vec::new(), Vec::new())).collect();
        for (column, is_cos) in
            (cos.iter_mut().map(|c| (c, true))).chain(sin.iter_mut().map(|s| (s, false)))
        {
            let mut parts = column.chunks_mut(CHUNK);
            for item in &mut items {
                let part = parts.next().unwrap_or_default();
                if is_cos { &mut item.1 } else { &mut item.2 }.push(part);
            }
        }
        crate::parallel::parallel_map_mut(&mut items, threads, |(c, cos, sin)| {
            for j in 0..joints {
                for (i, cos) in (*c * CHUNK..).zip(cos[j].iter_mut()) {
                    let x = q[i * joints + j];
                    *cos = if slides(j) { x } else { x.cos() };
                }
                for (i, sin) in (*c * CHUNK..).zip(sin[j].iter_mut()) {
                    *sin = q[i * joints + j].sin();
                }
            }
        });
        drop(items);
        PreparedPoses::from_trig(joints, prismatic, len, cos, sin)
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

    /// The prismatic joints: bit `j` for joint `j` (0 for revolute data).
    pub(crate) fn prismatic_mask(&self) -> u16 {
        self.prismatic
    }

    /// The shape of chain these poses are readings of; `None` for a joint
    /// count no chain has (no readings at all, or more than
    /// [`MAX_JOINTS`]).
    pub fn shape(&self) -> Option<ChainShape> {
        ChainShape::from_mask(self.joints, self.prismatic).ok()
    }

    /// cos and sin of pose `i`'s readings (a prismatic joint's reading and
    /// 0); the caller has checked `N`.
    #[inline(always)]
    pub(crate) fn trig<const N: usize>(&self, i: usize) -> ([f64; N], [f64; N]) {
        (
            std::array::from_fn(|j| self.cos[j][i]),
            std::array::from_fn(|j| self.sin[j].get(i).copied().unwrap_or(0.0)),
        )
    }

    /// The sin/cos of `count` whole batches of poses from `start`, cut
    /// once per call so that the batch loops load without checks; the
    /// caller has checked `N` and the range.
    #[inline(always)]
    pub(crate) fn batches<const N: usize>(&self, start: usize, count: usize) -> Batches<'_, N> {
        let end = start + count * LANES;
        let mut cos: [&[[f64; LANES]]; N] = [&[]; N];
        let mut sin: [&[[f64; LANES]]; N] = [&[]; N];
        // Plain loops, not `array::from_fn`: its closure is not always
        // inlined. `[..count]` makes every column's length the loop bound
        // itself, so the loads in `Batches::get` need no check.
        for j in 0..N {
            cos[j] = &self.cos[j][start..end].as_chunks().0[..count];
            // A prismatic joint has no sin column: its reading stands in
            // (the kernels do not read a prismatic joint's sin).
            let sin_j = if self.sin[j].is_empty() {
                &self.cos[j]
            } else {
                &self.sin[j]
            };
            sin[j] = &sin_j[start..end].as_chunks().0[..count];
        }
        Batches { count, cos, sin }
    }
}

/// Whole batches of [`LANES`] poses of a [`PreparedPoses`], column by
/// column: what the batch loops index. The runtime-sized storage behind
/// `PreparedPoses` (a `Vec` of columns) would otherwise cost a joint-count
/// check, a pointer load and a range check for every load of every batch —
/// as many scalar instructions as the position kernel has vector ones.
pub(crate) struct Batches<'a, const N: usize> {
    /// Number of batches: the length of every column.
    pub(crate) count: usize,
    cos: [&'a [[f64; LANES]]; N],
    sin: [&'a [[f64; LANES]]; N],
}

impl<const N: usize> Batches<'_, N> {
    /// cos and sin of batch `b`'s readings, one lane per pose.
    // Plain loops, not `array::from_fn`: its closure is not always inlined,
    // and out of line the AVX loads become calls.
    #[inline(always)]
    pub(crate) fn get<L: Batch>(&self, b: usize) -> ([L; N], [L; N]) {
        let mut c = [L::from(0.0); N];
        let mut s = [L::from(0.0); N];
        for j in 0..N {
            c[j] = L::load(&self.cos[j][b]);
            s[j] = L::load(&self.sin[j][b]);
        }
        (c, s)
    }
}

#[cfg(test)]
mod tests {
    use super::{Post, PreparedPoses};

    /// Every `step`-th pose, taken out with its transform after the chain,
    /// has the same position and Jacobian bits through the kernel as in the
    /// whole set (in another lane of another batch), prismatic joint or not.
    #[test]
    fn every_step_th_pose_is_the_same_bits_as_in_the_whole_set() {
        use crate::kernel::ArmKernel;
        use crate::params::DhParams;
        let params = DhParams::paper_nominal();
        let kernel = ArmKernel::new(&params).unwrap();
        let len = 23;
        let q: Vec<f64> = (0..len * 6)
            .map(|i| (i as f64 * 0.37).sin() * 3.0)
            .collect();
        let post = Post {
            scale: (0..len).map(|i| 1.0 + i as f64 * 1e-5).collect(),
            offset: (0..len).map(|i| [i as f64 * 0.01, -0.02, 0.5]).collect(),
        };
        let all = PreparedPoses::from_flat_with(6, 0, len, &q).with_post(post);
        let mut whole = Vec::new();
        kernel
            .for_each_jacobian(&all, 0..len, |_, p, j| whole.push((*p, j.to_vec())))
            .unwrap();
        for step in [1, 2, 3, 5, 22, 23, 40] {
            let some = all.every(step);
            assert_eq!(some.len(), len.div_ceil(step), "step {step}");
            let mut k = 0;
            kernel
                .for_each_jacobian(&some, 0..some.len(), |i, p, j| {
                    let (wp, wj) = &whole[i * step];
                    assert_eq!(p.map(f64::to_bits), wp.map(f64::to_bits), "step {step}");
                    let bits = |j: &[[f64; 3]]| -> Vec<[u64; 3]> {
                        j.iter().map(|c| c.map(f64::to_bits)).collect()
                    };
                    assert_eq!(bits(j), bits(wj), "step {step}, pose {i}");
                    k += 1;
                })
                .unwrap();
            assert_eq!(k, some.len());
        }
    }

    /// The sin and cos shared between threads in chunks of poses are those
    /// of one thread, to the bit, a prismatic joint's column its readings:
    /// 10 000 poses are 3 chunks (one thread), 40 000 are 10 (two).
    #[test]
    fn the_trig_on_several_threads_is_the_trig_on_one() {
        for (len, prismatic) in [(10_000, 0), (40_000, 0), (40_000, 0b101)] {
            let q: Vec<f64> = (0..len * 3)
                .map(|i| (i as f64 * 0.37).sin() * 3.0)
                .collect();
            let one = PreparedPoses::from_flat_with(3, prismatic, len, &q);
            for threads in [2, 3, 4] {
                let many = PreparedPoses::from_flat_on(3, prismatic, len, &q, threads);
                assert_eq!(many, one, "{len} poses, {threads} threads");
            }
            assert_eq!(one.column_trig(1).1[7], q[7 * 3 + 1].sin());
            if prismatic != 0 {
                assert_eq!(
                    one.column_trig(0),
                    (
                        &q.iter().step_by(3).copied().collect::<Vec<_>>()[..],
                        &[][..]
                    )
                );
            }
        }
        let (chunks, split) = (40_000usize.div_ceil(4096), crate::parallel::threads_for);
        assert_eq!(split(chunks, 2), 2, "40 000 poses split");
    }
}
