//! The geometric least-squares sphere: the centre (and radius, unless held)
//! minimising the sum of squared orthogonal distances of the points from
//! the sphere's surface, `Σ (|p_i − c| − R)²` — the fit ISO 10360-5 and
//! 10360-12 name ("least-squares sphere"), not the algebraic one, which
//! only starts it.
//!
//! Levenberg–Marquardt on `r_i = |p_i − c| − R`, Jacobian rows
//! `[−n̂_iᵀ, −1]` (`n̂_i` the unit vector from the centre to the point; no
//! `−1` column with the radius held). The start: the algebraic sphere
//! ([`algebraic_sphere`]); with the radius held, its centre moved along
//! the line from the points' centroid through it to where a sphere of the
//! held radius would pass through the points (a small patch's algebraic
//! radius is poor, its side of the patch is not).
//!
//! **σ**: `σ̂² = Σ r_i² / (n − p)` (`p` = 3 or 4 unknowns), the covariance
//! of the unknowns `σ̂² (JᵀJ)⁻¹` at the solution — the fit's own statement
//! of the points' noise, as a least-squares fit states it.

use nalgebra::{Matrix4, Vector3, Vector4};
use serde::{Deserialize, Serialize};

use crate::residuals::spheres::algebraic_sphere;

/// Why a sphere fit stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub(crate) enum FitStop {
    /// The step fell below 1e-13 of the centre's size (plus 1 mm): the
    /// minimum, to the last bits.
    Converged,
    /// No step lowered the cost any more (the cost is flat to rounding).
    NoDecrease,
    /// [`MAX_ITERATIONS`] steps without either: the result is the best met.
    MaxIterations,
}

/// Steps of the fit before it stops.
pub(crate) const MAX_ITERATIONS: usize = 200;

/// Why there is no sphere.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub(crate) enum FitError {
    /// Too few points for the unknowns (3 with the radius held, 4 free).
    #[error("{points} points fix no sphere: at least {needed} are needed")]
    TooFewPoints {
        /// Points given.
        points: usize,
        /// Points needed.
        needed: usize,
    },
    /// The points fix no sphere (on one circle, a line, or one point).
    #[error("the points fix no sphere (on one circle, a line, or at one point)")]
    Degenerate,
}

/// A fitted sphere.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct SphereFit {
    /// The centre, mm.
    pub centre: [f64; 3],
    /// The radius, mm: fitted, or the held one.
    pub radius: f64,
    /// Whether the radius was held.
    pub(crate) radius_held: bool,
    /// Per point, `|p_i − c| − R`, mm, in the points' order.
    pub residuals: Vec<f64>,
    /// `σ̂ = sqrt(Σ r_i² / (n − p))`, mm; `None` without degrees of
    /// freedom (`n = p`).
    pub sigma: Option<f64>,
    /// `(JᵀJ)⁻¹` of the unknowns `(c_x, c_y, c_z, R)` (the `R` row and
    /// column zero when held), mm² per mm² of σ: times `σ²` the covariance.
    pub(crate) normal_inverse: [[f64; 4]; 4],
    /// Why the fit stopped.
    pub stop: FitStop,
    /// Steps taken.
    pub(crate) iterations: usize,
}

impl SphereFit {
    /// The covariance of `(c_x, c_y, c_z, R)` at a point noise `sigma`, mm².
    pub(crate) fn covariance(&self, sigma: f64) -> Matrix4<f64> {
        Matrix4::from_fn(|i, j| self.normal_inverse[i][j]) * (sigma * sigma)
    }

    /// The fitted diameter's σ at the fit's own σ̂, mm (`0` with the radius
    /// held or without degrees of freedom).
    pub(crate) fn diameter_sigma(&self) -> f64 {
        match (self.radius_held, self.sigma) {
            (false, Some(s)) => 2.0 * s * self.normal_inverse[3][3].max(0.0).sqrt(),
            _ => 0.0,
        }
    }

    /// The range of the radial residuals, mm: the form seen.
    pub(crate) fn form(&self) -> f64 {
        let (lo, hi) = min_max(&self.residuals);
        hi - lo
    }
}

/// The smallest and largest of `v` (`(0, 0)` for none).
pub(crate) fn min_max(v: &[f64]) -> (f64, f64) {
    if v.is_empty() {
        return (0.0, 0.0);
    }
    v.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        })
}

/// The least-squares sphere through `points` (mm), its radius `held` when
/// given, else fitted: see the module's documentation.
///
/// # Errors
///
/// Fewer points than the unknowns, or points that fix no sphere.
pub(crate) fn fit_sphere_ls(points: &[[f64; 3]], held: Option<f64>) -> Result<SphereFit, FitError> {
    let unknowns = if held.is_some() { 3 } else { 4 };
    if points.len() < unknowns.max(4) {
        return Err(FitError::TooFewPoints {
            points: points.len(),
            needed: unknowns.max(4),
        });
    }
    let (c0, r0) = algebraic_sphere(points).ok_or(FitError::Degenerate)?;
    let start = match held {
        Some(r) => held_start(points, c0, r),
        None => Vector4::new(c0[0], c0[1], c0[2], r0),
    };
    let (x, stop, iterations) = minimise(points, start, held.is_some());
    let (n_inv, residuals) =
        normal_inverse(points, &x, held.is_some()).ok_or(FitError::Degenerate)?;
    let dof = points.len() - unknowns;
    let ss: f64 = residuals.iter().map(|r| r * r).sum();
    Ok(SphereFit {
        centre: [x[0], x[1], x[2]],
        radius: x[3],
        radius_held: held.is_some(),
        residuals,
        sigma: (dof > 0).then(|| (ss / dof as f64).sqrt()),
        normal_inverse: std::array::from_fn(|i| std::array::from_fn(|j| n_inv[(i, j)])),
        stop,
        iterations,
    })
}

/// The start of a held-radius fit: the algebraic centre `c0` moved along
/// the line from the points' centroid through it to `sqrt(R² − s²)` from
/// the centroid (`s` the points' RMS distance from their centroid).
fn held_start(points: &[[f64; 3]], c0: [f64; 3], r: f64) -> Vector4<f64> {
    let g = Vector3::from(crate::geometry::centroid(points));
    let s2 = points
        .iter()
        .map(|p| (Vector3::from(*p) - g).norm_squared())
        .sum::<f64>()
        / points.len() as f64;
    let d = Vector3::from(c0) - g;
    let c = match d.try_normalize(0.0) {
        Some(u) => g + u * (r * r - s2).max(0.0).sqrt(),
        None => Vector3::from(c0),
    };
    Vector4::new(c[0], c[1], c[2], r)
}

/// The cost and normal equations at `x`: `(Σ r², JᵀJ, Jᵀr)` over the
/// unknowns (the radius's row and column zero when held).
fn normal_equations(
    points: &[[f64; 3]],
    x: &Vector4<f64>,
    held: bool,
) -> (f64, Matrix4<f64>, Vector4<f64>) {
    let c = Vector3::new(x[0], x[1], x[2]);
    let (mut cost, mut jtj, mut jtr) = (0.0, Matrix4::zeros(), Vector4::zeros());
    for p in points {
        let v = Vector3::from(*p) - c;
        let d = v.norm();
        let u = if d > 0.0 { v / d } else { v };
        let r = d - x[3];
        let j = Vector4::new(-u[0], -u[1], -u[2], if held { 0.0 } else { -1.0 });
        cost += r * r;
        jtj += j * j.transpose();
        jtr += j * r;
    }
    (cost, jtj, jtr)
}

/// Levenberg–Marquardt from `x`: the solution, why it stopped, steps.
fn minimise(
    points: &[[f64; 3]],
    mut x: Vector4<f64>,
    held: bool,
) -> (Vector4<f64>, FitStop, usize) {
    let mut lambda = 1e-6;
    let (mut cost, mut jtj, mut jtr) = normal_equations(points, &x, held);
    for it in 0..MAX_ITERATIONS {
        let mut a = jtj;
        for k in 0..4 {
            a[(k, k)] += lambda * jtj[(k, k)].max(1e-30);
        }
        if held {
            a[(3, 3)] = 1.0;
        }
        let Some(chol) = a.cholesky() else {
            return (x, FitStop::NoDecrease, it);
        };
        let step = chol.solve(&(-jtr));
        let trial = x + step;
        let (c2, j2, r2) = normal_equations(points, &trial, held);
        if c2 <= cost {
            let small = step.norm() <= 1e-13 * (1.0 + x.fixed_rows::<3>(0).norm() + x[3].abs());
            (x, cost, jtj, jtr) = (trial, c2, j2, r2);
            lambda = (lambda * 0.1).max(1e-12);
            if small {
                return (x, FitStop::Converged, it + 1);
            }
        } else {
            lambda *= 10.0;
            if lambda > 1e12 {
                return (x, FitStop::NoDecrease, it + 1);
            }
        }
    }
    (x, FitStop::MaxIterations, MAX_ITERATIONS)
}

/// `(JᵀJ)⁻¹` at `x` (the radius's block zero when held) and the residuals.
fn normal_inverse(
    points: &[[f64; 3]],
    x: &Vector4<f64>,
    held: bool,
) -> Option<(Matrix4<f64>, Vec<f64>)> {
    let (_, mut jtj, _) = normal_equations(points, x, held);
    if held {
        jtj[(3, 3)] = 1.0;
    }
    let mut inv = jtj.try_inverse()?;
    if held {
        inv[(3, 3)] = 0.0;
    }
    let c = Vector3::new(x[0], x[1], x[2]);
    let residuals = points
        .iter()
        .map(|p| (Vector3::from(*p) - c).norm() - x[3])
        .collect();
    inv.iter()
        .all(|v| v.is_finite())
        .then_some((inv, residuals))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on a sphere of radius `r` about `c` at the ISO pattern's
    /// directions over a cap, each moved radially by `noise[i]`.
    fn on_sphere(c: [f64; 3], r: f64, noise: &[f64]) -> Vec<[f64; 3]> {
        (0..noise.len())
            .map(|i| {
                let (a, b) = (
                    i as f64 * 2.39996,
                    0.2 + 1.2 * i as f64 / noise.len() as f64,
                );
                let d = [b.sin() * a.cos(), b.sin() * a.sin(), b.cos()];
                std::array::from_fn(|k| c[k] + (r + noise[i]) * d[k])
            })
            .collect()
    }

    #[test]
    fn the_fit_is_the_minimum_of_the_orthogonal_distances() {
        let noise: Vec<f64> = (0..25)
            .map(|i| 0.01 * ((i * 7 % 11) as f64 - 5.0) / 5.0)
            .collect();
        let p = on_sphere([100.0, -50.0, 300.0], 15.7, &noise);
        let f = fit_sphere_ls(&p, None).unwrap();
        assert_eq!(f.stop, FitStop::Converged);
        // At the minimum the gradient Jᵀr vanishes: Σ r_i n̂_i = 0, Σ r_i = 0.
        let c = Vector3::from(f.centre);
        let mut g = Vector4::zeros();
        for (pi, r) in p.iter().zip(&f.residuals) {
            let u = (Vector3::from(*pi) - c).normalize();
            g += Vector4::new(u[0], u[1], u[2], 1.0) * *r;
        }
        assert!(g.norm() < 1e-10, "{g}");
        // Any nudge raises the cost.
        let cost = |c: [f64; 3], r: f64| {
            p.iter()
                .map(|q| (crate::geometry::distance(q, &c) - r).powi(2))
                .sum::<f64>()
        };
        let best = cost(f.centre, f.radius);
        for k in 0..4 {
            let mut c2 = f.centre;
            let mut r2 = f.radius;
            if k < 3 {
                c2[k] += 1e-4
            } else {
                r2 += 1e-4
            }
            assert!(cost(c2, r2) > best);
        }
        assert!(f.sigma.unwrap() > 0.0 && f.diameter_sigma() > 0.0);
        assert!(
            (f.form()
                - (f.residuals.iter().cloned().fold(f64::MIN, f64::max)
                    - f.residuals.iter().cloned().fold(f64::MAX, f64::min)))
            .abs()
                < 1e-15
        );
        // Held: the radius stays, the centre is still the minimum.
        let h = fit_sphere_ls(&p, Some(15.7)).unwrap();
        assert_eq!(
            (h.radius, h.radius_held, h.diameter_sigma()),
            (15.7, true, 0.0)
        );
        assert!(crate::geometry::distance(&h.centre, &[100.0, -50.0, 300.0]) < 0.01);
    }

    #[test]
    fn a_five_point_patch_with_the_radius_held_and_bad_sets() {
        let p = on_sphere([0.0, 0.0, 0.0], 20.0, &[0.0; 5]);
        let h = fit_sphere_ls(&p, Some(20.0)).unwrap();
        assert!(h.centre.iter().all(|v| v.abs() < 1e-9), "{:?}", h.centre);
        assert!(matches!(
            fit_sphere_ls(&p[..3], None),
            Err(FitError::TooFewPoints {
                points: 3,
                needed: 4
            })
        ));
        let circle: Vec<[f64; 3]> = (0..6)
            .map(|i| {
                let a = i as f64;
                [a.cos(), a.sin(), 0.0]
            })
            .collect();
        assert_eq!(fit_sphere_ls(&circle, None), Err(FitError::Degenerate));
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn acceptance_fit_fit_sphere_ls() {
        use crate::acceptance::fit_sphere_ls;
        let p = [
            [11.0, 2.0, 3.0],
            [1.0, 12.0, 3.0],
            [1.0, 2.0, 13.0],
            [-9.0, 2.0, 3.0],
            [1.0, -8.0, 3.0],
        ];
        let s = fit_sphere_ls(&p, None).unwrap();
        assert!((s.centre[0] - 1.0).abs() < 1e-12 && (s.radius - 10.0).abs() < 1e-12);
        assert!(s.residuals.iter().all(|r| r.abs() < 1e-12));
    }
}
