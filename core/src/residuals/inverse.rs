//! `N⁻¹` from the Cholesky factor of `N` — the covariance, the outlier
//! test's leverage, the plan's information inverses — bit for bit what
//! nalgebra's `Cholesky::inverse` returns, but with the columns of the
//! identity solved side by side.
//!
//! nalgebra solves one right-hand side after the other, so each step waits
//! on the last division of its own column (a chain of about 2p divisions
//! and p dot products): the inverse was a twentieth of a 100-touch fit.
//! The columns are independent, so here every step runs across all of them
//! at once, each column with exactly nalgebra's operations in nalgebra's
//! order — the forward solve's `y ← (−c)·l·1 + 1·y` axpy and the back
//! solve's dot product with eight accumulators — hence the same bits.
//!
//! The factorisation itself ([`cholesky`]) likewise: nalgebra's
//! left-looking columns, each column's updates in its order, on plain
//! slices in a function compiled for AVX2.

use nalgebra::linalg::Cholesky;
use nalgebra::{DMatrix, Dyn};

/// The Cholesky factorisation of the symmetric `m` (its lower triangle
/// read), bit for bit what `m.cholesky()` (nalgebra's `Cholesky::new`)
/// returns, `None` where it does: a pivot that is zero, negative or NaN.
///
/// nalgebra's generic loop (a view, a clone and an index check per
/// element, no SIMD) was a twentieth of the LM solve at 100 touches: a
/// damped `p × p` factor per trial step.
pub(crate) fn cholesky(mut m: DMatrix<f64>) -> Option<Cholesky<f64, Dyn>> {
    assert!(m.is_square(), "The input matrix must be square.");
    let n = m.nrows();
    // The padded copy's buffer, kept by the thread between calls (taken
    // out, so that the factorisation is inlined into the AVX2 function and
    // not into the thread-local's accessor).
    let mut padded = PADDED.with_borrow_mut(std::mem::take);
    let ok = crate::simd::with_avx2(
        #[inline(always)]
        || factor_in_place(m.as_mut_slice(), n, &mut padded),
    );
    PADDED.with_borrow_mut(|kept| *kept = padded);
    ok.then(|| Cholesky::pack_dirty(m))
}

/// `Cholesky::new_internal` without a substitute, on the column-major
/// `n × n` slice `m`: column `j` gets, for each `k < j` in order, the
/// axpy `y ← (−L_jk)·L_·k·1 + 1·y` over its rows `j..` (the factors `1`
/// are exact, so they are left out), then its pivot's square root and the
/// division of the rows below by it. `false` at a pivot nalgebra refuses
/// (zero by `is_zero`, else negative or NaN by `try_sqrt`); `m` is then
/// left as it was (the caller drops it).
///
/// Each entry's updates are a chain of its own, so here they run entry by
/// entry, four rows side by side in registers, the `k` in nalgebra's
/// order: the same operations on every entry, without nalgebra's load and
/// store of the whole column per `k` (which made this slower than
/// nalgebra's own loop on a 21-column matrix). The lower triangle is
/// factored in a copy whose columns have three rows of scratch below, so
/// that every four rows are a whole four, the last ones too (what lands in
/// the scratch rows is never read into a real one).
#[inline(always)]
fn factor_in_place(m: &mut [f64], n: usize, padded: &mut Vec<f64>) -> bool {
    let stride = n + LANES - 1;
    // Kept by the thread from one factorisation to the next: a fit makes
    // one per LM trial (zeroing a fresh copy cost a third as much as the
    // factorisation). Only the rows each column reads are written: the
    // lower triangle, and zeros in the scratch rows, so no stale value
    // enters a call (scratch rows feed only scratch rows).
    if padded.len() < n * stride {
        padded.resize(n * stride, 0.0);
    }
    let w = &mut padded[..n * stride];
    for j in 0..n {
        let col = &mut w[j * stride..(j + 1) * stride];
        col[j..n].copy_from_slice(&m[j * n + j..(j + 1) * n]);
        col[n..].fill(0.0);
    }
    let ok = factor_padded(w, n, stride);
    if ok {
        for j in 0..n {
            m[j * n + j..(j + 1) * n].copy_from_slice(&w[j * stride + j..j * stride + n]);
        }
    }
    ok
}

thread_local! {
    /// [`factor_in_place`]'s padded copy.
    static PADDED: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// [`factor_in_place`] on `w`, columns of `stride ≥ n + 3` rows.
#[inline(always)]
fn factor_padded(w: &mut [f64], n: usize, stride: usize) -> bool {
    for j in 0..n {
        let (finished, from_j) = w.split_at_mut(j * stride);
        let col_j = &mut from_j[..stride];
        let mut r = j;
        while r < n {
            let four: &mut [f64; LANES] = (&mut col_j[r..r + LANES]).try_into().expect("four");
            let mut acc = *four;
            // (Checked here, so that the loop over `k` checks nothing.)
            assert!(j < stride && r + LANES <= stride);
            for col_k in finished.chunks_exact(stride) {
                // The axpy's factor `−L_jk`, and its rows `r..r+4` of `L_·k`.
                let f = -col_k[j];
                let x: &[f64; LANES] = col_k[r..r + LANES].try_into().expect("four rows");
                for l in 0..LANES {
                    acc[l] += f * x[l];
                }
            }
            *four = acc;
            r += LANES;
        }
        let diag = col_j[j];
        // `is_zero` (±0), then `try_sqrt` (a square root only of `v ≥ 0`,
        // so not of a NaN).
        if diag <= 0.0 || diag.is_nan() {
            return false;
        }
        let denom = diag.sqrt();
        col_j[j] = denom;
        for v in &mut col_j[j + 1..n] {
            *v /= denom;
        }
    }
    true
}

/// Rows of a column updated side by side in [`factor_in_place`].
const LANES: usize = 4;

/// `x` of `N x = b` into `b`, from `ch`, the Cholesky factorisation of `N`:
/// bit for bit nalgebra's `ch.solve_mut(b)` (its forward solve's axpy and
/// its back solve's dot product with eight accumulators, as
/// [`cholesky_inverse`] does for each column), without its generic loops:
/// a damped step's solve per LM trial.
pub(crate) fn cholesky_solve(ch: &Cholesky<f64, Dyn>, b: &mut [f64]) {
    let l = ch.l_dirty();
    let d = l.nrows();
    assert_eq!(b.len(), d, "one right-hand side of the factor's size");
    let l = l.as_slice();
    // L y = b: `solve_lower_triangular_vector_unchecked_mut`.
    for i in 0..d {
        let col = &l[i * d..(i + 1) * d];
        let coeff = b[i] / col[i];
        b[i] = coeff;
        for (y, &x) in b[i + 1..].iter_mut().zip(&col[i + 1..]) {
            // axcpy(a = −coeff, x, c = 1, b = 1): a·x·c + b·y.
            *y += -coeff * x;
        }
    }
    // Lᵀ x = y: `xx_solve_lower_triangular_vector_unchecked_mut` with `dotc`.
    for i in (0..d).rev() {
        let col = &l[i * d + i + 1..(i + 1) * d];
        let rest = &b[i + 1..];
        let whole = col.len() / 8 * 8;
        let mut acc = [0.0; 8];
        for (c, v) in col[..whole].chunks_exact(8).zip(rest.chunks_exact(8)) {
            for k in 0..8 {
                acc[k] += c[k] * v[k];
            }
        }
        let mut dot = dot_of_accumulators(&acc);
        for (c, v) in col[whole..].iter().zip(&rest[whole..]) {
            dot += c * v;
        }
        b[i] = (b[i] - dot) / l[i * d + i];
    }
}

/// nalgebra's `dotx` closing its eight accumulators: (0+4), (1+5), (2+6),
/// (3+7) added in turn to a sum started at zero. The bits of every dot
/// product here depend on this order.
#[inline(always)]
fn dot_of_accumulators(a: &[f64; 8]) -> f64 {
    let mut res = 0.0;
    res += a[0] + a[4];
    res += a[1] + a[5];
    res += a[2] + a[6];
    res += a[3] + a[7];
    res
}

/// `N⁻¹` from `ch`, the Cholesky factorisation of `N` (p × p): in the AVX2
/// copy where the CPU has it (the same operations, no fused multiply-add:
/// the same bits), the columns four to a register.
pub(crate) fn cholesky_inverse(ch: &Cholesky<f64, nalgebra::Dyn>) -> DMatrix<f64> {
    crate::simd::with_avx2(
        #[inline(always)]
        || inverse_of(ch),
    )
}

#[inline(always)]
fn inverse_of(ch: &Cholesky<f64, nalgebra::Dyn>) -> DMatrix<f64> {
    let l = ch.l_dirty();
    let d = l.nrows();
    // x[r * d + k]: row r of the solution's column k (the identity at first).
    let mut x = vec![0.0; d * d];
    for r in 0..d {
        x[r * d + r] = 1.0;
    }
    // L y = e_k: nalgebra's `solve_lower_triangular_vector_unchecked_mut`.
    let mut coeff = vec![0.0; d];
    for i in 0..d {
        let diag = l[(i, i)];
        let (head, tail) = x.split_at_mut((i + 1) * d);
        let row_i = &mut head[i * d..];
        for (c, v) in coeff.iter_mut().zip(row_i.iter_mut()) {
            *c = *v / diag;
            *v = *c;
        }
        for (j, row_j) in (i + 1..d).zip(tail.chunks_exact_mut(d)) {
            let lji = l[(j, i)];
            for (y, &c) in row_j.iter_mut().zip(&coeff) {
                // axcpy(a = −c, x = l, c = 1, b = 1): a·x·c + b·y.
                *y = -c * lji * 1.0 + 1.0 * *y;
            }
        }
    }
    // Lᵀ z = y: `xx_solve_lower_triangular_vector_unchecked_mut` with
    // `dotc`, whose dot product runs eight accumulators over whole chunks of
    // eight, adds them as (0+4), (1+5), (2+6), (3+7) into a sum started at
    // zero, then the rest one by one.
    let mut acc = vec![[0.0; 8]; d];
    let mut dot = vec![0.0; d];
    for i in (0..d).rev() {
        let len = d - i - 1;
        let whole = len / 8 * 8;
        acc.iter_mut().for_each(|a| *a = [0.0; 8]);
        for m in 0..whole {
            let r = i + 1 + m;
            let lri = l[(r, i)];
            let row = &x[r * d..(r + 1) * d];
            for (a, &v) in acc.iter_mut().zip(row) {
                a[m % 8] += lri * v;
            }
        }
        for (s, a) in dot.iter_mut().zip(&acc) {
            *s = dot_of_accumulators(a);
        }
        for m in whole..len {
            let r = i + 1 + m;
            let lri = l[(r, i)];
            let row = &x[r * d..(r + 1) * d];
            for (s, &v) in dot.iter_mut().zip(row) {
                *s += lri * v;
            }
        }
        let diag = l[(i, i)];
        for (v, &s) in x[i * d..(i + 1) * d].iter_mut().zip(&dot) {
            *v = (*v - s) / diag;
        }
    }
    DMatrix::from_row_slice(d, d, &x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::RngExt;

    /// A random symmetric positive-definite `d × d` matrix whose scales
    /// span `10^spread`.
    fn spd(rng: &mut impl rand::Rng, d: usize, spread: f64) -> DMatrix<f64> {
        let a = DMatrix::from_fn(d + 3, d, |_, _| rng.random_range(-1.0..1.0));
        let s = DMatrix::from_fn(d, d, |r, c| {
            if r == c {
                10f64.powf(spread * (r as f64 / d as f64 - 0.5))
            } else {
                0.0
            }
        });
        &s * a.transpose() * &a * &s + DMatrix::identity(d, d) * 1e-9
    }

    /// The same bits as nalgebra's factor, on symmetric positive-definite
    /// matrices of every size up to 30, badly scaled and well; the same
    /// refusal of matrices nalgebra refuses (a zero, a negative and a NaN
    /// pivot, first or later); and the strict upper triangle left as given.
    #[test]
    fn the_same_factor_as_nalgebras() {
        let mut rng = crate::random::rng(6, 0);
        let bits = |m: &DMatrix<f64>| m.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        for d in 1..=30 {
            for scale_spread in [0.0, 6.0] {
                let mut n = spd(&mut rng, d, scale_spread);
                // An upper triangle unlike the lower: neither reads it.
                for c in 1..d {
                    n[(0, c)] = 7.0 + c as f64;
                }
                let ours = cholesky(n.clone()).expect("positive definite");
                let theirs = n.clone().cholesky().expect("positive definite");
                assert_eq!(
                    bits(&ours.unpack_dirty()),
                    bits(&theirs.unpack_dirty()),
                    "d = {d}"
                );
            }
        }
        for (d, at, pivot) in [
            (1, 0, 0.0),
            (4, 0, -1.0),
            (5, 2, 0.0),
            (6, 3, -2.0),
            (6, 5, f64::NAN),
            (3, 1, -0.0),
        ] {
            let mut n = DMatrix::<f64>::identity(d, d) * 2.0;
            n[(at, at)] = pivot;
            assert!(n.clone().cholesky().is_none(), "nalgebra: d = {d}, at {at}");
            assert!(cholesky(n).is_none(), "d = {d}, at {at}");
        }
        // Indefinite through the updates, not a given pivot.
        let n = DMatrix::from_row_slice(3, 3, &[1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
        assert!(n.clone().cholesky().is_none() && cholesky(n).is_none());
    }

    /// The same bits as nalgebra's `solve_mut`, sizes 1 to 30 (dot products
    /// shorter than eight, whole chunks of eight and a rest).
    #[test]
    fn the_same_solve_as_nalgebras() {
        let mut rng = crate::random::rng(7, 0);
        for d in 1..=30 {
            let ch = spd(&mut rng, d, 6.0).cholesky().expect("positive definite");
            let b = nalgebra::DVector::from_fn(d, |_, _| rng.random_range(-1e3..1e3));
            let mut theirs = b.clone();
            ch.solve_mut(&mut theirs);
            let mut ours = b.clone();
            cholesky_solve(&ch, ours.as_mut_slice());
            let bits =
                |v: &nalgebra::DVector<f64>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&ours), bits(&theirs), "d = {d}");
        }
    }

    /// The same bits as nalgebra's inverse, on symmetric positive-definite
    /// matrices of every size up to 30 (chunks of eight and the rest),
    /// badly scaled and well, and on one with exact zeros off the diagonal.
    #[test]
    fn the_same_bits_as_nalgebras_inverse() {
        let mut rng = crate::random::rng(5, 0);
        for d in 1..=30 {
            for scale_spread in [0.0, 6.0] {
                let n = spd(&mut rng, d, scale_spread);
                let ch = n.clone().cholesky().expect("positive definite");
                let (ours, theirs) = (cholesky_inverse(&ch), ch.inverse());
                let bits = |m: &DMatrix<f64>| m.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&ours), bits(&theirs), "d = {d}");
            }
        }
        let diag = DMatrix::from_diagonal(&nalgebra::DVector::from_fn(9, |i, _| 1.0 + i as f64));
        let ch = diag.cholesky().unwrap();
        let bits = |m: &DMatrix<f64>| m.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&cholesky_inverse(&ch)), bits(&ch.inverse()));
    }
}
