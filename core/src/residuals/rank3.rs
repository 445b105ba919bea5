//! The normal matrix's rank-3 updates `Σ (AJ)ᵀ J` of one observation of a
//! 3-D position after another, a block of observations per sweep over the
//! matrix (the touches' `JᵀAJ`, the reference positions' `JᵀJ`).
//!
//! Each entry's terms are still added one observation at a time in
//! observation order, every term `x·b₀ + y·b₁ + z·b₂` in that order: the
//! same bits as the row-by-row loop, without loading and storing every entry
//! once per observation, and over whole lanes of contiguous memory (four
//! `f64` in one AVX2 register, where the caller's loop is compiled for it).

// Entries of a row are updated a lane group at a time (one AVX2 register
// of f64, the kernel's lanes); the stride is a whole number of lanes, so
// a caller may run the kernel's lanes over a padded slot.
use crate::kernel::LANES;

/// Observations whose terms are added in one sweep over the matrix: each
/// entry is loaded and stored once per block.
pub(super) const BLOCK: usize = 8;

/// Up to [`BLOCK`] observations' columns, not yet in the matrix: the
/// columns of `J` and of `A·J`, one padded row per observation and
/// coordinate, so the update runs over whole lanes of contiguous memory.
pub(super) struct Rank3 {
    /// Columns updated (`p`).
    columns: usize,
    /// Row stride of the padded matrix and of the scratch: `p` rounded up
    /// to a whole number of [`LANES`].
    stride: usize,
    j: [Vec<f64>; 3],
    aj: [Vec<f64>; 3],
    /// Observations held in the scratch.
    pending: usize,
}

/// The next observation's rows in a [`Rank3`]'s scratch, `p` columns each:
/// `j[k]` is coordinate `k` of `J`, `aj[k]` of `A·J`.
pub(super) struct Slot<'a> {
    pub(super) j: [&'a mut [f64]; 3],
    pub(super) aj: [&'a mut [f64]; 3],
}

impl Slot<'_> {
    /// Column `u` of an observation whose weight `A` is the identity: the
    /// same values in `J` and `A·J`.
    #[inline(always)]
    pub(super) fn set_both(&mut self, u: usize, d: [f64; 3]) {
        for (k, &v) in d.iter().enumerate() {
            self.j[k][u] = v;
            self.aj[k][u] = v;
        }
    }

    /// Zeros in every column (an observation that fills only some).
    #[inline(always)]
    pub(super) fn clear(&mut self) {
        for c in self.j.iter_mut().chain(self.aj.iter_mut()) {
            c.fill(0.0);
        }
    }
}

impl Rank3 {
    /// Scratch for `p` columns.
    pub(super) fn new(p: usize) -> Rank3 {
        let stride = p.div_ceil(LANES) * LANES;
        Rank3 {
            columns: p,
            stride,
            j: std::array::from_fn(|_| vec![0.0; BLOCK * stride]),
            aj: std::array::from_fn(|_| vec![0.0; BLOCK * stride]),
            pending: 0,
        }
    }

    /// Columns updated (`p`).
    pub(super) fn columns(&self) -> usize {
        self.columns
    }

    /// Row stride of the padded lower triangle the updates go to: `p` rows
    /// of this many entries.
    pub(super) fn stride(&self) -> usize {
        self.stride
    }

    /// A zeroed padded lower triangle for [`Rank3::add`].
    pub(super) fn matrix(&self) -> Vec<f64> {
        vec![0.0; self.columns * self.stride]
    }

    /// The next observation's rows to fill; [`Rank3::add`] takes them in.
    #[inline(always)]
    pub(super) fn slot(&mut self) -> Slot<'_> {
        self.slot_of(self.columns)
    }

    /// The next observation's rows to fill, each [`Rank3::stride`] long: a
    /// caller may run whole lanes over them. Their padding columns past
    /// `p` in `J` must stay zero: a caller writes zeros there or nothing
    /// (only `A·J`'s padding may hold other values, and the sums never
    /// read it).
    #[inline(always)]
    pub(super) fn padded_slot(&mut self) -> Slot<'_> {
        self.slot_of(self.stride)
    }

    /// The next observation's rows, `width` columns each.
    #[inline(always)]
    fn slot_of(&mut self, width: usize) -> Slot<'_> {
        let at = self.pending * self.stride;
        let end = at + width;
        let [jx, jy, jz] = &mut self.j;
        let [ax, ay, az] = &mut self.aj;
        Slot {
            j: [&mut jx[at..end], &mut jy[at..end], &mut jz[at..end]],
            aj: [&mut ax[at..end], &mut ay[at..end], &mut az[at..end]],
        }
    }

    /// Takes in the slot just filled; a full block goes into `jtj` (the
    /// padded lower triangle).
    #[inline(always)]
    pub(super) fn add(&mut self, jtj: &mut [f64]) {
        self.pending += 1;
        if self.pending == BLOCK {
            self.flush(jtj);
        }
    }

    /// The held observations' terms into the lower triangle of `jtj`: row
    /// `i` gets `(AJ)_iᵀ J_b` for `b ≤ i`, a lane at a time (the entries
    /// past the diagonal in a row's last lane are upper-triangle scratch).
    #[inline(always)]
    pub(super) fn flush(&mut self, jtj: &mut [f64]) {
        let (n, w) = (self.pending, self.stride);
        if n == 0 || w == 0 {
            // Nothing held, or no column to update (rows of stride 0
            // cannot be cut).
            self.pending = 0;
            return;
        }
        // The observations' rows, walked once per lane group: made here and
        // copied for each, since making them (six slices cut into rows,
        // zipped) cost more than a small group's sums.
        let rows = self.rows(n);
        for i in 0..self.columns {
            let row = &mut jtj[i * w..i * w + w];
            // Up to four lanes at once: independent sums, so the additions'
            // latency overlaps (one lane's sum is a chain over the block).
            let mut c = 0;
            while c <= i {
                c += match (i - c) / LANES + 1 {
                    1 => lanes::<1>(rows.clone(), row, i, c, w),
                    2 => lanes::<2>(rows.clone(), row, i, c, w),
                    3 => lanes::<3>(rows.clone(), row, i, c, w),
                    _ => lanes::<4>(rows.clone(), row, i, c, w),
                };
            }
        }
        // The rows borrow the scratch, which the count below belongs to.
        drop(rows);
        self.pending = 0;
    }

    /// The first `n` observations' padded rows: `((J_x, J_y, J_z), (AJ_x,
    /// AJ_y, AJ_z))`.
    #[inline(always)]
    fn rows(&self, n: usize) -> impl Iterator<Item = Rows<'_>> + Clone {
        let w = self.stride;
        let [jx, jy, jz] = &self.j;
        let [ax, ay, az] = &self.aj;
        (jx.chunks_exact(w)
            .zip(jy.chunks_exact(w))
            .zip(jz.chunks_exact(w)))
        .zip(
            ax.chunks_exact(w)
                .zip(ay.chunks_exact(w))
                .zip(az.chunks_exact(w)),
        )
        .take(n)
    }

    /// Entry `(a, b)`, `b ≤ a`, of the padded lower triangle `jtj`.
    #[inline(always)]
    pub(super) fn entry(&self, jtj: &[f64], a: usize, b: usize) -> f64 {
        jtj[a * self.stride + b]
    }
}

/// One observation's padded rows, as [`Rank3::rows`] gives them.
type Rows<'a> = (
    ((&'a [f64], &'a [f64]), &'a [f64]),
    ((&'a [f64], &'a [f64]), &'a [f64]),
);

/// `K` lanes of `row` (row `i` of `JᵀAJ`, of stride `w`) from column `c`,
/// the observations `rows` added in order; returns the columns done.
#[inline(always)]
fn lanes<'a, const K: usize>(
    rows: impl Iterator<Item = Rows<'a>>,
    row: &mut [f64],
    i: usize,
    c: usize,
    w: usize,
) -> usize {
    let m = K * LANES;
    let out = &mut row[c..c + m];
    let mut r: [[f64; LANES]; K] =
        std::array::from_fn(|k| std::array::from_fn(|l| out[k * LANES + l]));
    // One observation's padded rows at a time: the column ranges are
    // checked once here, not once per observation.
    assert!(
        i < w && c + m <= w,
        "row {i}, columns {c}.. within the stride {w}"
    );
    for (((jx, jy), jz), ((ax, ay), az)) in rows {
        let (x, y, z) = (ax[i], ay[i], az[i]);
        let (bx, by, bz) = (&jx[c..c + m], &jy[c..c + m], &jz[c..c + m]);
        for (k, rk) in r.iter_mut().enumerate() {
            for (l, v) in rk.iter_mut().enumerate() {
                let b = k * LANES + l;
                *v += x * bx[b] + y * by[b] + z * bz[b];
            }
        }
    }
    for (o, rk) in out.chunks_exact_mut(LANES).zip(&r) {
        o.copy_from_slice(rk);
    }
    m
}

#[cfg(test)]
mod tests {
    use super::{BLOCK, Rank3};

    /// Blocked, the sums are the row-by-row loop's bit for bit, for
    /// matrices whose rows are not whole lanes, narrower and wider than the
    /// four lane groups a row runs at once, and more observations than a
    /// block.
    #[test]
    fn blocked_sums_are_the_row_by_row_bits() {
        for p in [1, 7, 8, 21, 27] {
            blocked_sums_of(p);
        }
    }

    fn blocked_sums_of(p: usize) {
        let n = 2 * BLOCK + 3;
        let value = |t: usize, k: usize, c: usize| ((t * 31 + k * 7 + c * 3) as f64 * 0.37).sin();
        let mut rank3 = Rank3::new(p);
        let mut jtj = rank3.matrix();
        let mut plain = vec![0.0; p * p];
        for t in 0..n {
            let slot = rank3.slot();
            let [jx, jy, jz] = slot.j;
            let [ax, ay, az] = slot.aj;
            for c in 0..p {
                (jx[c], jy[c], jz[c]) = (value(t, 0, c), value(t, 1, c), value(t, 2, c));
                (ax[c], ay[c], az[c]) = (value(t, 3, c), value(t, 4, c), value(t, 5, c));
            }
            rank3.add(&mut jtj);
            for a in 0..p {
                for b in 0..=a {
                    let v = value(t, 3, a) * value(t, 0, b)
                        + value(t, 4, a) * value(t, 1, b)
                        + value(t, 5, a) * value(t, 2, b);
                    plain[a * p + b] += v;
                }
            }
        }
        rank3.flush(&mut jtj);
        for a in 0..p {
            for b in 0..=a {
                assert_eq!(
                    rank3.entry(&jtj, a, b).to_bits(),
                    plain[a * p + b].to_bits(),
                    "({a}, {b})"
                );
            }
        }
    }
}
