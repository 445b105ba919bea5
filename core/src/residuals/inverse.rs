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

use nalgebra::DMatrix;
use nalgebra::linalg::Cholesky;

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
            let mut res = 0.0;
            res += a[0] + a[4];
            res += a[1] + a[5];
            res += a[2] + a[6];
            res += a[3] + a[7];
            *s = res;
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

    /// The same bits as nalgebra's inverse, on symmetric positive-definite
    /// matrices of every size up to 30 (chunks of eight and the rest),
    /// badly scaled and well, and on one with exact zeros off the diagonal.
    #[test]
    fn the_same_bits_as_nalgebras_inverse() {
        let mut rng = crate::random::rng(5, 0);
        for d in 1..=30 {
            for scale_spread in [0.0, 6.0] {
                let a = DMatrix::from_fn(d + 3, d, |_, _| rng.random_range(-1.0..1.0));
                let s = DMatrix::from_fn(d, d, |r, c| {
                    if r == c {
                        10f64.powf(scale_spread * (r as f64 / d as f64 - 0.5))
                    } else {
                        0.0
                    }
                });
                let n = &s * a.transpose() * &a * &s + DMatrix::identity(d, d) * 1e-9;
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
