//! The covariance of the fitted parameters and what is read from it: the
//! geometry's block, the correlations, the predicted position uncertainty.

use nalgebra::DMatrix;

use crate::calibrate::CalibrationError;
use crate::dataset::DataSet;
use crate::kernel::{ArmKernel, PreparedPoses};
use crate::params::DhParams;
use crate::residuals::Normal;
use crate::stats::coverage::{COVERAGE, K_ISOTROPIC, eigenvalues, radius};

use super::{Fit, Setup};

/// The free columns' covariance and the variance factor σ̂.
pub(super) struct Covariance {
    pub(super) cov: DMatrix<f64>,
    pub(super) sigma0: f64,
    pub(super) dof: usize,
    /// `N⁻¹` of the fit's own normal equations, when the covariance is
    /// `σ̂² N⁻¹` of them (no prior, no robust sandwich): the outlier test's
    /// leverage needs the same inverse and takes it from here.
    pub(super) normal_inverse: Option<DMatrix<f64>>,
}

/// `σ̂² N⁻¹`, or with a prior `(N_data/σ̂² + P)⁻¹`; robust: the sandwich
/// `σ̂² κ K² (J̃ᵀ B J̃)⁻¹` ([`crate::calibrate::robust`]), σ̂ the robust scale — in the
/// same forms, with `J̃ᵀ B J̃` for `N` and `σ̂² κ K²` for `σ̂²`.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
pub(super) fn covariance(fit: &Fit<'_>, setup: &Setup<'_>) -> Covariance {
    let dof = setup.counts.dof();
    let (sigma0, variance, normal, own) = match (&fit.robust, &fit.curvature) {
        (Some((robust, _)), Some(curvature)) => (
            robust.scale,
            robust.scale * robust.scale * robust.sandwich,
            curvature,
            false,
        ),
        _ => {
            let s = (fit.normal.cost() / dof as f64).sqrt();
            (s, s * s, &fit.normal, true)
        }
    };
    let p = setup.free.len();
    let n = DMatrix::from_row_slice(p, p, &normal.jtj);
    let invert = |m: DMatrix<f64>| match crate::residuals::cholesky(m) {
        Some(ch) => crate::residuals::cholesky_inverse(&ch),
        None => DMatrix::from_element(p, p, f64::INFINITY),
    };
    let (cov, normal_inverse) = match fit.objective.prior() {
        // The stated tolerances are absolute: σ̂ rescales the data's
        // information, not the prior's — (N_data/σ̂² + P)⁻¹. Scaling the
        // whole σ̂²·N⁻¹ made a parameter the prior holds (data share 5 %)
        // 30 % more certain than its tolerance under a robust scale of 0.68.
        Some(term) if variance.is_finite() && variance > 0.0 => {
            let mut m = n / variance;
            for (a, &c) in setup.free.iter().enumerate() {
                if let Some(s) = term.sigma(c) {
                    m[(a, a)] += (1.0 - 1.0 / variance) / (s * s);
                }
            }
            (invert(m), None)
        }
        _ => {
            let inverse = invert(n);
            (&inverse * variance, own.then_some(inverse))
        }
    };
    Covariance {
        cov,
        sigma0,
        dof,
        normal_inverse,
    }
}

/// The free columns below `arm` — the geometry's and the corrections'
/// beyond it — and their covariance: what moves a probe position.
pub(super) fn geometry_covariance(
    free: &[usize],
    geometry: usize,
    cov: &DMatrix<f64>,
) -> (Vec<usize>, DMatrix<f64>) {
    let at: Vec<usize> = (0..free.len()).filter(|&a| free[a] < geometry).collect();
    let cols = at.iter().map(|&a| free[a]).collect();
    let sub = DMatrix::from_fn(at.len(), at.len(), |a, b| cov[(at[a], at[b])]);
    (cols, sub)
}

/// The correlation matrix of `cov` (0 where it is not a number).
pub(super) fn correlations(cov: &DMatrix<f64>) -> Vec<Vec<f64>> {
    let p = cov.nrows();
    (0..p)
        .map(|a| {
            (0..p)
                .map(|b| {
                    let r = cov[(a, b)] / (cov[(a, a)] * cov[(b, b)]).sqrt();
                    if r.is_finite() { r } else { 0.0 }
                })
                .collect()
        })
        .collect()
}

/// The held directions as reported, each with the σ the data alone give it
/// at the fit: `σ̂ / sqrt(wᵀ N w − K)`, `w` its scaled unit vector in the
/// columns' units, `N` the normal matrix at the solution (which carries the
/// hold's own `K` along `w`, and no tolerance: held columns have none).
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
pub(super) fn held_directions(
    holds: Option<&crate::residuals::HoldTerm>,
    normal: &Normal,
    sigma0: f64,
) -> Vec<crate::residuals::HeldDirection> {
    let Some(term) = holds else {
        return Vec::new();
    };
    let p = normal.free.len();
    term.holds()
        .iter()
        .map(|h| {
            let w: Vec<(usize, f64)> = (0..h.cols.len())
                .filter_map(|i| {
                    let a = normal.free.iter().position(|&f| f == h.cols[i])?;
                    Some((a, h.v[i] * h.d[i]))
                })
                .collect();
            let nww: f64 = (w.iter())
                .flat_map(|&(a, wa)| w.iter().map(move |&(b, wb)| (a, b, wa * wb)))
                .map(|(a, b, ww)| normal.jtj[a * p + b] * ww)
                .sum();
            let info = nww - term.stiffness();
            crate::residuals::HeldDirection {
                relation: h.text.clone(),
                terms: h.terms.clone(),
                ratio: h.ratio,
                sigma_mm: (info > 0.0)
                    .then(|| sigma0 / info.sqrt())
                    .filter(|s| s.is_finite()),
            }
        })
        .collect()
}

/// The predicted position uncertainty of `params` (the 95 % radius of each
/// pose's 3-D error) over the poses of `data` (an even sample of at most [`crate::calibrate::checks::UNCERTAINTY_POSES`]),
/// from the free parameters' covariance `cov`.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
pub(super) fn position_uncertainty(
    params: &DhParams,
    data: &DataSet,
    effects: Option<&crate::corrections::Effects>,
    free: &[usize],
    cov: &DMatrix<f64>,
    touch_sigma: f64,
) -> Result<Option<crate::calibrate::checks::PositionUncertainty>, CalibrationError> {
    if data.is_empty() || cov.iter().any(|v| !v.is_finite()) {
        return Ok(None);
    }
    let kernel = ArmKernel::new(params)?;
    let step = data
        .len()
        .div_ceil(crate::calibrate::checks::UNCERTAINTY_POSES)
        .max(1);
    let q = free.len();
    let c = Factor::of(cov);
    // Every `step`-th pose from the first.
    let n = data.len().div_ceil(step);
    let mut sums = UncertaintySums {
        free,
        c,
        jf: vec![[[0.0; LANES]; 3]; q],
        sum: 0.0,
        max: 0.0,
    };
    // The Jacobians from the poses' stored sin/cos through the lanes kernel
    // (the same bits as `position_jacobian` of the readings, without their
    // trigonometry), the sampled poses in one call. The sums are inlined
    // into the kernel's loop, so they are compiled with its target
    // features (AVX2 where the CPU has it; no FMA, so the same bits as
    // without).
    let last = |l: usize, k: usize| (l + 1 == LANES || k + 1 == n).then_some(l + 1);
    let sample = |all: &PreparedPoses| (step > 1).then(|| all.every(step));
    if let Some(e) = effects {
        // With corrections beyond geometry: the poses as the chain saw
        // them, each Jacobian extended by the corrections' columns (of pose
        // `k · step` of the data).
        let mut ext = Vec::new();
        let sampled = sample(&e.poses);
        // Inlined as well: out of line, the sums ran without the kernel's
        // target features, a seventh of a fit with harmonics.
        kernel.for_each_jacobian(
            sampled.as_ref().unwrap_or(&e.poses),
            0..n,
            #[inline(always)]
            |k, pos, jac| {
                e.extend(k * step, pos, jac, &mut ext);
                sums.add(k % LANES, &ext, last(k % LANES, k));
            },
        )?;
    } else {
        let sampled = sample(data.poses());
        kernel.for_each_jacobian(
            sampled.as_ref().unwrap_or(data.poses()),
            0..n,
            #[inline(always)]
            |k, _, jac| sums.add(k % LANES, jac, last(k % LANES, k)),
        )?;
    }
    let (sum, max) = (sums.sum, sums.max);
    Ok(Some(crate::calibrate::checks::PositionUncertainty {
        coverage: COVERAGE,
        poses: n,
        rms_mm: (sum / n as f64).sqrt(),
        max_mm: max,
        touch_mm: K_ISOTROPIC * touch_sigma,
    }))
}

/// Poses whose uncertainties [`position_uncertainty`] sums side by side:
/// independent chains, so they run together (each in its own order: the
/// same bits as one at a time).
const LANES: usize = 8;

/// The covariance as [`UncertaintySums`] reads it.
enum Factor {
    /// `Lᵀ` row-major (`C = L Lᵀ`, `L` lower triangular): a pose's
    /// `J C Jᵀ` is `Z Zᵀ` with `Z = J L`, whose row `b` needs `J`'s columns
    /// from `b` on only.
    Cholesky(Vec<f64>),
    /// `C` itself, row-major: a covariance too near singular for its
    /// Cholesky factor (never so for a fit's, which is `N⁻¹` scaled).
    Full(Vec<f64>),
}

impl Factor {
    fn of(cov: &DMatrix<f64>) -> Factor {
        let q = cov.nrows();
        match crate::residuals::cholesky(cov.clone()) {
            Some(ch) => {
                let l = ch.l_dirty();
                Factor::Cholesky((0..q * q).map(|i| l[(i % q, i / q)]).collect())
            }
            None => Factor::Full((0..q * q).map(|i| cov[(i / q, i % q)]).collect()),
        }
    }
}

/// [`position_uncertainty`]'s running sums: the covariance's factor, the
/// free columns of [`LANES`] poses' position Jacobians side by side.
struct UncertaintySums<'a> {
    free: &'a [usize],
    c: Factor,
    jf: Vec<[[f64; LANES]; 3]>,
    sum: f64,
    max: f64,
}

/// The six distinct entries (xx, yy, zz, xy, xz, yz) of a position's 3 × 3
/// covariance, as pairs of coordinates.
const PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

impl UncertaintySums<'_> {
    /// Pose `l` of the group from its Jacobian; with the group's last, its
    /// `n` poses' 95 % radii ([`radius`]) into the sums.
    #[inline(always)]
    fn add(&mut self, l: usize, jac: &[[f64; 3]], n: Option<usize>) {
        for (a, &ca) in self.free.iter().enumerate() {
            for (lane, &jk) in self.jf[a].iter_mut().zip(&jac[ca]) {
                lane[l] = jk;
            }
        }
        let Some(n) = n else { return };
        // The position's covariance J C Jᵀ, its six distinct entries per
        // lane: its eigenvalues, not only its trace, give the radius that
        // covers 95 % of a 3-D error.
        let m = match &self.c {
            Factor::Cholesky(lt) => self.factored(lt),
            Factor::Full(c) => self.full(c),
        };
        for l in 0..n {
            let [xx, yy, zz, xy, xz, yz] = m.map(|e| e[l]);
            let u = radius(eigenvalues([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]));
            self.sum += u * u;
            self.max = self.max.max(u);
        }
    }

    /// `Z Zᵀ` with `Z = J L`, one column `b` of `Z` at a time (`Σ_{a ≥ b}
    /// J_a L_ab`): 1.5q² + 6q products a pose, half of `J (C Jᵀ)`'s, and a
    /// sum of squares, so never an indefinite result from rounding.
    #[inline(always)]
    fn factored(&self, lt: &[f64]) -> [[f64; LANES]; 6] {
        let (jf, q) = (&self.jf, self.free.len());
        let mut m = [[0.0; LANES]; 6];
        for (b, row) in lt.chunks_exact(q).enumerate() {
            let z = combination(&jf[b..], &row[b..]);
            add_pairs(&mut m, &z, &z);
        }
        m
    }

    /// `J (C Jᵀ)`, one row of `C Jᵀ` at a time: 3q² + 6q products a pose.
    #[inline(always)]
    fn full(&self, c: &[f64]) -> [[f64; LANES]; 6] {
        let (jf, q) = (&self.jf, self.free.len());
        let mut m = [[0.0; LANES]; 6];
        for (b, jb) in jf.iter().enumerate() {
            let y = combination(jf, &c[b * q..(b + 1) * q]);
            add_pairs(&mut m, jb, &y);
        }
        m
    }
}

/// `Σ_a w_a J_a` over the lanes' Jacobian columns `jf`, in column order.
#[inline(always)]
fn combination(jf: &[[[f64; LANES]; 3]], w: &[f64]) -> [[f64; LANES]; 3] {
    let mut y = [[0.0; LANES]; 3];
    for (ja, &wa) in jf.iter().zip(w) {
        for s in 0..3 {
            for l in 0..LANES {
                y[s][l] += wa * ja[s][l];
            }
        }
    }
    y
}

/// `m[e] += u[r] v[s]` for each of the six distinct entries `(r, s)`
/// ([`PAIRS`]), per lane.
#[inline(always)]
fn add_pairs(m: &mut [[f64; LANES]; 6], u: &[[f64; LANES]; 3], v: &[[f64; LANES]; 3]) {
    for (e, &(r, s)) in PAIRS.iter().enumerate() {
        for l in 0..LANES {
            m[e][l] += u[r][l] * v[s][l];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`position_uncertainty`] one pose at a time, as before the poses went
    /// eight at a time: the reference the lanes must match bit for bit.
    /// With `factored`, `J C Jᵀ` as `Z Zᵀ` (`Z = J L`, `C = L Lᵀ`), else as
    /// `J (C Jᵀ)`.
    fn one_at_a_time(
        params: &DhParams,
        data: &DataSet,
        free: &[usize],
        cov: &DMatrix<f64>,
        factored: bool,
    ) -> (usize, f64, f64) {
        let kernel = ArmKernel::new(params).unwrap();
        let step = data
            .len()
            .div_ceil(crate::calibrate::checks::UNCERTAINTY_POSES)
            .max(1);
        let l = cov.clone().cholesky().map(|ch| ch.l());
        let mut jac = vec![[0.0; 3]; params.param_count()];
        let (mut sum, mut max, mut n) = (0.0, 0.0f64, 0usize);
        for i in (0..data.len()).step_by(step) {
            kernel.position_jacobian(data.reading(i), &mut jac).unwrap();
            let mut m = [[0.0; 3]; 3];
            for (b, &cb) in free.iter().enumerate() {
                let mut y = [0.0; 3];
                if factored {
                    // Column b of Z = J L: rows a ≥ b of L, in order.
                    let l = l.as_ref().expect("positive definite");
                    for (a, &ca) in free.iter().enumerate().skip(b) {
                        for (s, v) in y.iter_mut().enumerate() {
                            *v += l[(a, b)] * jac[ca][s];
                        }
                    }
                    for (r, mr) in m.iter_mut().enumerate() {
                        for (s, v) in mr.iter_mut().enumerate() {
                            *v += y[r] * y[s];
                        }
                    }
                } else {
                    // Row b of C Jᵀ summed over a in order, then m over b.
                    for (a, &ca) in free.iter().enumerate() {
                        for (s, v) in y.iter_mut().enumerate() {
                            *v += cov[(b, a)] * jac[ca][s];
                        }
                    }
                    for (r, mr) in m.iter_mut().enumerate() {
                        for (s, v) in mr.iter_mut().enumerate() {
                            *v += jac[cb][r] * y[s];
                        }
                    }
                }
            }
            // Symmetric as the lanes' (which sum the upper triangle only).
            (m[1][0], m[2][0], m[2][1]) = (m[0][1], m[0][2], m[1][2]);
            let u = radius(eigenvalues(m));
            sum += u * u;
            max = max.max(u);
            n += 1;
        }
        (n, (sum / n as f64).sqrt(), max)
    }

    /// A symmetric positive-definite covariance with correlations.
    fn correlated(q: usize) -> DMatrix<f64> {
        DMatrix::from_fn(q, q, |a, b| {
            let d = a.abs_diff(b) as f64;
            if a == b {
                1e-4 * (1.0 + a as f64)
            } else {
                1e-5 / (1.0 + d)
            }
        })
    }

    /// Pose counts that leave 1, 2, 3 and 4 poses in the last group, and one
    /// sampled (more than UNCERTAINTY_POSES touches): the same bits.
    #[test]
    fn position_uncertainty_in_lanes_is_the_same_bits() {
        let params = DhParams::paper_nominal();
        let free: Vec<usize> = (2..params.param_count() - 2).collect();
        let cov = correlated(free.len());
        for touches in [3usize, 5, 6, 7, 9, 4003] {
            // At least 3 touches a point.
            let points = (touches / 3).min(3);
            let data = crate::dataset::testing::spread_touches(touches, points);
            let u = position_uncertainty(&params, &data, None, &free, &cov, 0.01)
                .unwrap()
                .unwrap();
            let (n, rms, max) = one_at_a_time(&params, &data, &free, &cov, true);
            assert_eq!(u.poses, n, "{touches} touches");
            assert_eq!(u.rms_mm.to_bits(), rms.to_bits(), "{touches} touches");
            assert_eq!(u.max_mm.to_bits(), max.to_bits(), "{touches} touches");
            // The factor changes only the rounding: J (C Jᵀ) agrees to
            // within a few ulp of the radii.
            let (_, rms_full, max_full) = one_at_a_time(&params, &data, &free, &cov, false);
            assert!(
                (u.rms_mm - rms_full).abs() <= 1e-13 * rms_full,
                "{touches} touches"
            );
            assert!(
                (u.max_mm - max_full).abs() <= 1e-13 * max_full,
                "{touches} touches"
            );
        }
    }

    /// A covariance without a Cholesky factor (singular: one parameter a
    /// copy of another) is summed as `J (C Jᵀ)`, with that reference's bits.
    #[test]
    fn a_singular_covariance_is_summed_whole() {
        let params = DhParams::paper_nominal();
        let free: Vec<usize> = (2..params.param_count() - 2).collect();
        let q = free.len();
        let mut cov = correlated(q);
        for k in 0..q {
            cov[(q - 1, k)] = cov[(0, k)];
            cov[(k, q - 1)] = cov[(k, 0)];
        }
        cov[(q - 1, q - 1)] = cov[(0, 0)];
        assert!(cov.clone().cholesky().is_none(), "singular");
        assert!(matches!(Factor::of(&cov), Factor::Full(_)));
        let data = crate::dataset::testing::spread_touches(9, 3);
        let u = position_uncertainty(&params, &data, None, &free, &cov, 0.01)
            .unwrap()
            .unwrap();
        let (n, rms, max) = one_at_a_time(&params, &data, &free, &cov, false);
        assert_eq!(u.poses, n);
        assert_eq!(u.rms_mm.to_bits(), rms.to_bits());
        assert_eq!(u.max_mm.to_bits(), max.to_bits());
    }
}
