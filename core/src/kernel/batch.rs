//! The batch loops: a chain's generated (or generic) functions run on
//! [`LANES`] poses at a time, with a scalar tail, giving the one-pose
//! functions' results bit for bit.

use super::lanes::{Batch, LANES, Two};
use super::{Chain, Consts, Pose, Post, PreparedParams, PreparedPoses};
use crate::params::MAX_JOINTS;

/// Room for any chain's parameter columns (`4 n + 3` for `n` ≤
/// [`MAX_JOINTS`]): the per-visit lane and tile buffers live on the stack,
/// because a visit is one chunk of a pass and allocating and zeroing them on
/// the heap each time was 2–3 % of a 100-touch calibration (callgrind).
const MAX_PARAMS: usize = 4 * MAX_JOINTS + 3;

/// The most columns [`for_each_lane_free_jacobian`]'s stack tile holds
/// (a model beyond geometry may ask for a chain column more than once).
pub(crate) const MAX_FREE: usize = MAX_PARAMS.div_ceil(LANES) * LANES;

/// What [`for_each_lane_jacobian`] calls per pose: its index, position
/// and parameter Jacobian.
pub(crate) type JacobianVisitor<'a> = dyn FnMut(usize, &[f64; 3], &[[f64; 3]]) + 'a;

/// What [`for_each_lane_pose_jacobian`] calls per pose: its index, tool
/// pose and 6-row parameter Jacobian.
pub(crate) type PoseJacobianVisitor<'a> = dyn FnMut(usize, &Pose, &[[f64; 6]]) + 'a;

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
pub(crate) fn positions_impl<const N: usize, C: Chain<N>, L: Batch>(
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

/// The tool poses of `out.len()` poses from `start`, in lanes.
#[inline(always)]
pub(crate) fn poses_impl<const N: usize, C: Chain<N>, L: Batch>(
    k: &PreparedParams<N>,
    poses: &PreparedPoses,
    start: usize,
    out: &mut [Pose],
) {
    let kl: Consts<L, N> = k.splat();
    let (whole, rest) = out.as_chunks_mut::<LANES>();
    let batches = poses.batches::<N>(start, whole.len());
    for (b, dst) in whole.iter_mut().enumerate() {
        let (cq, sq) = batches.get::<L>(b);
        *dst = pose_lanes(C::pose(&kl, &cq, &sq));
    }
    let tail = start + batches.count * LANES;
    for (o, slot) in rest.iter_mut().enumerate() {
        let (cq, sq) = poses.trig::<N>(tail + o);
        *slot = Pose::from_transform(C::pose(k, &cq, &sq));
    }
}

/// Chain `C`'s parameter count, checked at compile time to fit
/// [`MAX_PARAMS`].
const fn room<const N: usize, C: Chain<N>>() -> usize {
    assert!(
        C::PARAMS <= MAX_PARAMS,
        "a chain with more columns than MAX_PARAMS"
    );
    C::PARAMS
}

/// Lanes of `[R | p]` to one [`Pose`] per lane.
#[inline(always)]
fn pose_lanes<L: Batch>(t: [[L; 4]; 3]) -> [Pose; LANES] {
    let mut rows = [[[0.0; LANES]; 4]; 3];
    for (r, row) in rows.iter_mut().zip(&t) {
        *r = super::to_arrays(row);
    }
    std::array::from_fn(|l| Pose::from_transform(rows.map(|row| row.map(|v| v[l]))))
}

/// Batch `b`'s four values of a row of `len` values per pose (one
/// coordinate of the positions or of a Jacobian column).
#[inline(always)]
fn lanes_of(row: &mut [f64], b: usize) -> &mut [f64; LANES] {
    &mut row.as_chunks_mut().0[b]
}

#[inline(always)]
pub(crate) fn jacobians_impl<const N: usize, C: Chain<N>, L: Batch>(
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

/// The whole batches of `range`: each one's first pose, positions (one
/// per pose) and Jacobian lanes to `each`; returns where the scalar tail
/// starts.
#[inline(always)]
fn each_batch<const N: usize, C: Chain<N>, L: Batch>(
    k: &PreparedParams<N>,
    poses: &PreparedPoses,
    range: &std::ops::Range<usize>,
    mut each: impl FnMut(usize, &[[f64; 3]; LANES], &[[L; 3]]),
) -> usize {
    let kl: Consts<L, N> = k.splat();
    let params = const { room::<N, C>() };
    let mut jl_room = [[L::from(0.0); 3]; MAX_PARAMS];
    let jl = &mut jl_room[..params];
    let mut pos = [[0.0; 3]; LANES];
    let batches = poses.batches::<N>(range.start, range.len() / LANES);
    for b in 0..batches.count {
        let (cq, sq) = batches.get::<L>(b);
        let p = C::position_jacobian(&kl, &cq, &sq, jl);
        transpose(&[p], &mut pos);
        each(range.start + b * LANES, &pos, jl);
    }
    range.start + batches.count * LANES
}

#[inline(always)]
pub(crate) fn for_each_lane_jacobian<const N: usize, C: Chain<N>, L: Batch>(
    k: &PreparedParams<N>,
    poses: &PreparedPoses,
    range: std::ops::Range<usize>,
    mut f: impl FnMut(usize, &[f64; 3], &[[f64; 3]]),
) {
    let params = const { room::<N, C>() };
    let mut tile_room = [[0.0; 3]; LANES * MAX_PARAMS];
    let tile = &mut tile_room[..LANES * params];
    let tail = each_batch::<N, C, L>(
        k,
        poses,
        &range,
        #[inline(always)]
        |i, pos, jl| {
            transpose(jl, tile);
            for (l, cols) in tile.chunks_exact(params).enumerate() {
                f(i + l, &pos[l], cols);
            }
        },
    );
    for i in tail..range.end {
        let (cq, sq) = poses.trig::<N>(i);
        let p = C::position_jacobian(k, &cq, &sq, &mut tile[..params]);
        f(i, &p, &tile[..params]);
    }
}

/// What [`for_each_lane_free_jacobian`] hands over per pose: the chosen
/// columns of its parameter Jacobian by coordinate (`rows[k][g]` holds
/// coordinate `k` of the columns `free[4g..4g + 4]`), the last group padded
/// with zeros. Mutable, so that a caller may finish some columns in place
/// before it reads them (a model beyond geometry scales a chain column
/// into its correction's): the loop writes every group afresh per pose.
pub(crate) type FreeRows<'a> = [&'a mut [[f64; LANES]]; 3];

/// [`for_each_lane_jacobian`] of the columns `free` only (each below the
/// chain's column count, a column twice if asked, at most [`MAX_FREE`]),
/// compacted by coordinate: what a
/// solver's `JᵀAJ` over its free columns reads. Four free columns of four
/// poses are one 4 × 4 transpose of the kernel's lanes; a pose's whole
/// Jacobian transposed and then picked column by column cost over twice
/// the instructions (callgrind, `lm-solve/100`: about 320 a touch against
/// 140 with the copy into the rank-3 slot). The values are the kernel's,
/// moved only.
#[inline(always)]
pub(crate) fn for_each_lane_free_jacobian<const N: usize, C: Chain<N>, L: Batch>(
    k: &PreparedParams<N>,
    poses: &PreparedPoses,
    range: std::ops::Range<usize>,
    free: &[usize],
    mut f: impl FnMut(usize, &[f64; 3], FreeRows<'_>),
) {
    const GROUPS: usize = MAX_FREE / LANES;
    let params = const { room::<N, C>() };
    let groups = free.len().div_ceil(LANES);
    // Per pose, per coordinate, the free columns in groups of four lanes.
    let mut tile = [[[[0.0; LANES]; GROUPS]; 3]; LANES];
    let tail = each_batch::<N, C, L>(
        k,
        poses,
        &range,
        #[inline(always)]
        |i, pos, jl| {
            // Whole groups of four columns, then the last one padded; `c` is
            // a coordinate of each column of the group.
            let (whole, last) = free.as_chunks::<LANES>();
            for (g, cols) in whole.iter().enumerate() {
                for c in [0, 1, 2] {
                    put_group(&mut tile, c, g, cols.map(|j| jl[j][c]));
                }
            }
            if !last.is_empty() {
                for c in [0, 1, 2] {
                    let v =
                        std::array::from_fn(|u| last.get(u).map_or(L::from(0.0), |&j| jl[j][c]));
                    put_group(&mut tile, c, whole.len(), v);
                }
            }
            for (l, (rows, pos)) in tile.iter_mut().zip(pos).enumerate() {
                f(i + l, pos, rows.each_mut().map(|r| &mut r[..groups]));
            }
        },
    );
    let tail = tail..range.end;
    if tail.is_empty() {
        return;
    }
    let mut cols = [[0.0; 3]; MAX_PARAMS];
    let cols = &mut cols[..params];
    for i in tail {
        let (cq, sq) = poses.trig::<N>(i);
        let p = C::position_jacobian(k, &cq, &sq, cols);
        gather_free(cols, free, tile[0].each_mut().map(|r| &mut r[..]));
        f(i, &p, tile[0].each_mut().map(|r| &mut r[..groups]));
    }
}

/// Coordinate `c` of four poses' free columns `4g..4g+4` (`v`, a lane per
/// column) into each pose's row of `tile`. A function of its own, not a
/// closure: LLVM kept the closure out of line, compiled without the batch
/// loop's target features, each intrinsic a call.
#[inline(always)]
fn put_group<L: Batch, const G: usize>(
    tile: &mut [[[[f64; LANES]; G]; 3]; LANES],
    c: usize,
    g: usize,
    v: [L; LANES],
) {
    for (t, row) in L::transpose4(v).into_iter().zip(tile) {
        t.store(&mut row[c][g]);
    }
}

/// `jac`'s columns `free` into `rows` as [`FreeRows`] lays them out (one
/// pose's): for the batch loop's tail, and for the chains whose batch loops
/// call a `dyn` visitor or whose poses have a transform after the chain.
#[inline(always)]
pub(crate) fn gather_free(jac: &[[f64; 3]], free: &[usize], rows: [&mut [[f64; LANES]]; 3]) {
    for (c, row) in rows.into_iter().enumerate() {
        for (dst, cols) in row.iter_mut().zip(free.chunks(LANES)) {
            *dst = std::array::from_fn(|u| cols.get(u).map_or(0.0, |&j| jac[j][c]));
        }
    }
}

/// [`for_each_lane_jacobian`] for `∂p/∂q`: each pose's joint Jacobian
/// (`N` columns) to `f`, in pose order, a batch of lanes at a time.
#[inline(always)]
pub(crate) fn for_each_lane_joint_jacobian<const N: usize, C: Chain<N>, L: Batch>(
    k: &PreparedParams<N>,
    poses: &PreparedPoses,
    range: std::ops::Range<usize>,
    mut f: impl FnMut(usize, &[[f64; 3]]),
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

/// [`for_each_lane_jacobian`] for the tool pose: each pose's [`Pose`] and
/// its 6-row parameter Jacobian to `f`, in pose order.
#[inline(always)]
pub(crate) fn for_each_lane_pose_jacobian<const N: usize, C: Chain<N>, L: Batch>(
    k: &PreparedParams<N>,
    poses: &PreparedPoses,
    range: std::ops::Range<usize>,
    f: &mut PoseJacobianVisitor<'_>,
) {
    let kl: Consts<L, N> = k.splat();
    let params = const { room::<N, C>() };
    let mut jl_room = [[L::from(0.0); 6]; MAX_PARAMS];
    let jl = &mut jl_room[..params];
    let mut tile_room = [[0.0; 6]; LANES * MAX_PARAMS];
    let tile = &mut tile_room[..LANES * params];
    let batches = poses.batches::<N>(range.start, range.len() / LANES);
    for b in 0..batches.count {
        let (cq, sq) = batches.get::<L>(b);
        let pose = pose_lanes(C::pose_jacobian(&kl, &cq, &sq, jl));
        transpose6(jl, tile);
        let i = range.start + b * LANES;
        for (l, cols) in tile.chunks_exact(params).enumerate() {
            f(i + l, &pose[l], cols);
        }
    }
    for i in range.start + batches.count * LANES..range.end {
        let (cq, sq) = poses.trig::<N>(i);
        let t = C::pose_jacobian(k, &cq, &sq, &mut tile[..params]);
        f(i, &Pose::from_transform(t), &tile[..params]);
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

/// [`transpose`] of 6-row columns.
#[inline(always)]
fn transpose6<L: Batch>(cols: &[[L; 6]], dst: &mut [[f64; 6]]) {
    let c_count = cols.len();
    let dst = &mut dst[..LANES * c_count];
    for (c, col) in cols.iter().enumerate() {
        let rows = super::to_arrays(col);
        for l in 0..LANES {
            dst[l * c_count + c] = rows.map(|r| r[l]);
        }
    }
}
