//! The radius that covers 95 % of a 3-D Gaussian error.
//!
//! A position error `e ~ N(0, Σ)` (3-D) lies within `r` of the true point
//! with probability `P(Σ λ_i z_i² ≤ r²)`, `λ_i` the eigenvalues of `Σ`. For
//! an isotropic error (`λ_i = σ²`) that is the χ² law with 3 degrees of
//! freedom, and the 95 % radius is `2.7955 σ` — not the `2 σ` of one
//! coordinate. For an error along one direction it is `1.96 σ`. Between the
//! two, the weighted sum is matched by a scaled χ² of the same mean and
//! variance (Satterthwaite: `c·χ²_ν`, `c = Σλ²/Σλ`, `ν = (Σλ)²/Σλ²`), exact
//! at both ends; its quantile comes from the regularised incomplete gamma
//! function.

/// Coverage probability of every radius aacmm reports.
pub const COVERAGE: f64 = 0.95;

/// The 95 % radius of an isotropic 3-D Gaussian in units of its
/// per-coordinate σ: `sqrt(χ²₃(0.95))`.
pub(crate) const K_ISOTROPIC: f64 = 2.795_483_482_915_108;

/// The radius covering [`COVERAGE`] of a 3-D Gaussian error whose
/// covariance has the eigenvalues `lambda` (mm²): 0 for no error.
pub fn radius(lambda: [f64; 3]) -> f64 {
    let l = lambda.map(|v| v.max(0.0));
    let (s1, s2) = (l.iter().sum::<f64>(), l.iter().map(|v| v * v).sum::<f64>());
    if s1 <= 0.0 || !s1.is_finite() || !s2.is_finite() {
        return if s1.is_finite() { 0.0 } else { f64::INFINITY };
    }
    let c = s2 / s1;
    let nu = s1 * s1 / s2;
    (c * quantile_95(nu)).sqrt()
}

/// Nodes per degree of freedom of [`quantile_95`]'s table.
const NODES_PER_DOF: f64 = 64.0;

/// The 95 % quantile of `χ²_ν` for `ν ∈ [1, 3]` (what three eigenvalues
/// give): a table of the exact quantiles every 1/64, computed once, and
/// 4-point Lagrange interpolation between (error below 1e-8 relative, far
/// below Satterthwaite's own). A calibration asks for one per pose, and a
/// quantile costs some ten incomplete-gamma evaluations: at 100 touches
/// they were most of the fit's time.
fn quantile_95(nu: f64) -> f64 {
    static TABLE: std::sync::OnceLock<Vec<f64>> = std::sync::OnceLock::new();
    if !(1.0..=3.0).contains(&nu) {
        return chi_square_quantile(COVERAGE, nu);
    }
    let table = TABLE.get_or_init(|| {
        // One node beyond each end, for the 4-point stencil.
        let n = (2.0 * NODES_PER_DOF) as usize + 3;
        (0..n)
            .map(|i| chi_square_quantile(COVERAGE, 1.0 + (i as f64 - 1.0) / NODES_PER_DOF))
            .collect()
    });
    let t = (nu - 1.0) * NODES_PER_DOF;
    let i = (t.floor() as usize).min(2 * NODES_PER_DOF as usize - 1);
    let u = t - i as f64;
    let y = &table[i..i + 4];
    // Lagrange on the nodes -1, 0, 1, 2 (relative to node i) at u.
    -u * (u - 1.0) * (u - 2.0) / 6.0 * y[0] + (u + 1.0) * (u - 1.0) * (u - 2.0) / 2.0 * y[1]
        - (u + 1.0) * u * (u - 2.0) / 2.0 * y[2]
        + (u + 1.0) * u * (u - 1.0) / 6.0 * y[3]
}

/// The eigenvalues of a symmetric 3×3 matrix (closed form, trigonometric).
pub fn eigenvalues(m: [[f64; 3]; 3]) -> [f64; 3] {
    let p1 = m[0][1].powi(2) + m[0][2].powi(2) + m[1][2].powi(2);
    let q = (m[0][0] + m[1][1] + m[2][2]) / 3.0;
    if p1 <= 1e-30 * q.abs().max(1e-300) {
        return [m[0][0], m[1][1], m[2][2]];
    }
    let p2 = (m[0][0] - q).powi(2) + (m[1][1] - q).powi(2) + (m[2][2] - q).powi(2) + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    let b: [[f64; 3]; 3] = std::array::from_fn(|i| {
        std::array::from_fn(|j| (m[i][j] - if i == j { q } else { 0.0 }) / p)
    });
    let det = b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1])
        - b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0])
        + b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]);
    let phi = (det / 2.0).clamp(-1.0, 1.0).acos() / 3.0;
    let e1 = q + 2.0 * p * phi.cos();
    let e3 = q + 2.0 * p * (phi + 2.0 * std::f64::consts::PI / 3.0).cos();
    [e1, 3.0 * q - e1 - e3, e3]
}

use super::chi_square_quantile;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_quantiles_match_the_tables() {
        // χ² tables: 3.8415 (1 dof), 5.9915 (2), 7.8147 (3), 18.307 (10).
        for (nu, q) in [
            (1.0, 3.841_459),
            (2.0, 5.991_465),
            (3.0, 7.814_728),
            (10.0, 18.307_04),
        ] {
            assert!((chi_square_quantile(0.95, nu) - q).abs() < 1e-5, "{nu}");
        }
        assert!((K_ISOTROPIC - chi_square_quantile(0.95, 3.0).sqrt()).abs() < 1e-9);
    }

    /// The fraction of `n` draws of `N(0, m)` within the radius of `m`'s
    /// eigenvalues — the radius as the position uncertainty of a
    /// calibration computes it (`radius(eigenvalues(J C Jᵀ))`), the draws
    /// through `m`'s Cholesky factor (seeded).
    fn covered(m: [[f64; 3]; 3], seed: u64, n: usize) -> f64 {
        use rand_distr::{Distribution, StandardNormal};
        let r = radius(eigenvalues(m));
        let l = nalgebra::Matrix3::from_fn(|i, j| m[i][j])
            .cholesky()
            .expect("positive definite")
            .l();
        let mut rng = crate::random::rng(seed, 0);
        let inside = (0..n)
            .filter(|_| {
                let z = nalgebra::Vector3::from_fn(|_, _| StandardNormal.sample(&mut rng));
                (l * z).norm() <= r
            })
            .count();
        inside as f64 / n as f64
    }

    #[test]
    fn the_tabled_quantile_is_the_exact_one() {
        for k in 0..=1000 {
            let nu = 1.0 + 2.0 * k as f64 / 1000.0;
            let (t, e) = (quantile_95(nu), chi_square_quantile(COVERAGE, nu));
            assert!((t - e).abs() <= 1e-8 * e, "{nu}: {t} against {e}");
        }
    }

    #[test]
    fn the_radius_is_exact_at_both_ends_and_covers_between() {
        assert!((radius([1.0, 1.0, 1.0]) - K_ISOTROPIC).abs() < 1e-9);
        assert!((radius([4.0, 0.0, 0.0]) - 2.0 * 1.959_964).abs() < 1e-5);
        // Between, and with the axes turned as a position's covariance
        // `J C Jᵀ` has them: 95 ± 1 % by Monte Carlo (100 000 draws: the
        // count's own σ is 0.07 %, so a miss is the radius's, not chance's).
        let turn = |lambda: [f64; 3]| {
            // Rotated by 0.7 rad about (1, 2, 3).
            let axis = nalgebra::Unit::new_normalize(nalgebra::Vector3::new(1.0, 2.0, 3.0));
            let q = nalgebra::Rotation3::from_axis_angle(&axis, 0.7);
            let m = q * nalgebra::Matrix3::from_diagonal(&lambda.into()) * q.transpose();
            std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)]))
        };
        let cases: [(&str, [f64; 3]); 6] = [
            ("isotropic", [1.0, 1.0, 1.0]),
            ("one dominant", [1.0, 1e-3, 1e-3]),
            ("one dominant, the rest equal to a tenth", [1.0, 0.1, 0.1]),
            ("two dominant", [1.0, 1.0, 0.01]),
            ("mixed", [1.0, 0.3, 0.05]),
            ("mixed, mm² of a calibrated arm", [4e-4, 1.5e-4, 2e-5]),
        ];
        for (seed, (what, lambda)) in cases.into_iter().enumerate() {
            let f = covered(turn(lambda), seed as u64 + 7, 100_000);
            assert!((f - 0.95).abs() < 0.01, "{what}: {f}");
        }
    }

    #[test]
    fn the_eigenvalues_are_the_matrix_s() {
        let m = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 1.0]];
        let e = eigenvalues(m);
        let n = nalgebra::Matrix3::from_fn(|i, j| m[i][j]).symmetric_eigen();
        let mut want: Vec<f64> = n.eigenvalues.iter().copied().collect();
        want.sort_by(|a, b| b.total_cmp(a));
        for (a, b) in e.iter().zip(&want) {
            assert!((a - b).abs() < 1e-12, "{e:?} {want:?}");
        }
    }
}
