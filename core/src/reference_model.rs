//! The generic reference model: the textbook product of 4×4 homogeneous
//! matrices with nalgebra, written once over any [`DualNum`], so `f64` gives
//! positions and dual numbers give exact derivatives. This is the oracle the
//! generated kernel is checked against, not the fast path.

use nalgebra::{Matrix4, SVector, Vector4};
use num_dual::{DualNum, DualSVec64, jacobian};

use crate::kernel::KernelError;
use crate::params::{DhParams, JointModel, param_count};

/// Probe position of an `n`-joint chain: `params` in the fixed order
/// (`4n + 3` values, mm and rad), `q` the `n` encoder readings (rad).
///
/// # Panics
/// If `params.len() != 4·q.len() + 3` (a programming error: callers build
/// both from one arm).
///
/// ```
/// use aacmm_core::{params::DhParams, reference_model};
/// let arm = DhParams::paper_nominal().to_vec();
/// // All readings zero: the arm stands straight up; x sums the a's and z
/// // the d's plus the 100 mm probe.
/// let p = reference_model::position(&arm, &[0.0; 6]);
/// assert!((p[0] + 5.0).abs() < 1e-9 && p[1].abs() < 1e-9);
/// assert!((p[2] - 995.0).abs() < 1e-9);
/// ```
pub fn position<D: DualNum<Primitive = f64> + Copy>(params: &[D], q: &[D]) -> [D; 3] {
    position_with(params, q, &vec![JointModel::Dh; q.len()])
}

/// [`position`] of a chain whose joints have `models`: a
/// [`JointModel::Hayati`] joint's d-slot holds `β` (rad) and its link is
/// `Rz(θ + q)·Tx(a)·Rx(α)·Ry(β)`.
///
/// # Panics
/// As [`position`], or if `models.len() != q.len()`.
pub fn position_with<D: DualNum<Primitive = f64> + Copy>(
    params: &[D],
    q: &[D],
    models: &[JointModel],
) -> [D; 3] {
    let n = q.len();
    assert_eq!(params.len(), param_count(n), "parameter vector length");
    assert_eq!(models.len(), n, "one model per joint");
    let mut t = Matrix4::<D>::identity();
    for (j, &qj) in q.iter().enumerate() {
        let (a, slot, alpha, theta) = (
            params[j],
            params[n + j],
            params[2 * n + j],
            params[3 * n + j],
        );
        let (st, ct) = (qj + theta).sin_cos();
        let (sa, ca) = alpha.sin_cos();
        let zero = D::from(0.0);
        let one = D::from(1.0);
        let d = match models[j] {
            JointModel::Dh => slot,
            JointModel::Hayati => zero,
        };
        #[rustfmt::skip]
        let link = Matrix4::new(
            ct,   -ca * st, sa * st,  a * ct,
            st,   ca * ct,  -sa * ct, a * st,
            zero, sa,       ca,       d,
            zero, zero,     zero,     one,
        );
        t *= link;
        if models[j] == JointModel::Hayati {
            let (sb, cb) = slot.sin_cos();
            #[rustfmt::skip]
            let ry = Matrix4::new(
                cb,   zero, sb,   zero,
                zero, one,  zero, zero,
                -sb,  zero, cb,   zero,
                zero, zero, zero, one,
            );
            t *= ry;
        }
    }
    let b = &params[4 * n..];
    let p = t * Vector4::new(b[0], b[1], b[2], D::from(1.0));
    [p[0], p[1], p[2]]
}

fn check(params: &DhParams, q: &[f64]) -> Result<(), KernelError> {
    if q.len() == params.joint_count() {
        Ok(())
    } else {
        Err(KernelError::JointCount {
            expected: params.joint_count(),
            got: q.len(),
        })
    }
}

/// `∂p/∂parameter` by forward-mode autodiff (num-dual), one column per
/// parameter; `P` must be `4n + 3`.
///
/// ```
/// use aacmm_core::{params::DhParams, reference_model};
/// let arm = DhParams::paper_nominal();
/// let jac = reference_model::param_jacobian_dual::<27>(&arm, &[0.0; 6]).unwrap();
/// assert_eq!(jac[6], [0.0, 0.0, 1.0]); // ∂p/∂d1 is the base z axis
/// ```
pub fn param_jacobian_dual<const P: usize>(
    params: &DhParams,
    q: &[f64],
) -> Result<Vec<[f64; 3]>, KernelError> {
    check(params, q)?;
    if params.param_count() != P {
        return Err(KernelError::ParamCount {
            expected: params.param_count(),
            got: P,
        });
    }
    let x = SVector::<f64, P>::from_iterator(params.to_vec());
    let models = params.models();
    let (_, jac) = jacobian(
        |x: SVector<DualSVec64<P>, P>| {
            let q: Vec<DualSVec64<P>> = q.iter().map(|&v| DualSVec64::from(v)).collect();
            let p = position_with(x.as_slice(), &q, &models);
            nalgebra::Vector3::new(p[0], p[1], p[2])
        },
        &x,
    );
    Ok((0..P)
        .map(|c| [jac[(0, c)], jac[(1, c)], jac[(2, c)]])
        .collect())
}

/// `∂p/∂parameter` by central differences of [`position`] with step `h`
/// (mm for lengths, rad for angles) — the slow, independent check.
///
/// ```
/// use aacmm_core::{params::DhParams, reference_model};
/// let arm = DhParams::paper_nominal();
/// let jac = reference_model::param_jacobian_central(&arm, &[0.0; 6], 1e-6).unwrap();
/// assert!((jac[26][2] - 1.0).abs() < 1e-6); // ∂pz/∂Bz at the folded pose
/// ```
pub fn param_jacobian_central(
    params: &DhParams,
    q: &[f64],
    h: f64,
) -> Result<Vec<[f64; 3]>, KernelError> {
    check(params, q)?;
    let x = params.to_vec();
    let models = params.models();
    let mut shifted = x.clone();
    Ok((0..x.len())
        .map(|c| {
            shifted[c] = x[c] + h;
            let plus = position_with(&shifted, q, &models);
            shifted[c] = x[c] - h;
            let minus = position_with(&shifted, q, &models);
            shifted[c] = x[c];
            [0, 1, 2].map(|r| (plus[r] - minus[r]) / (2.0 * h))
        })
        .collect())
}

/// `∂p/∂q_i` by forward-mode autodiff, one column per joint; `N` must be
/// the joint count.
///
/// ```
/// use aacmm_core::{params::DhParams, reference_model};
/// let arm = DhParams::paper_nominal();
/// let jac = reference_model::joint_jacobian_dual::<6>(&arm, &[0.0; 6]).unwrap();
/// // Joint 1 turns about the base z axis through the origin; the probe sits
/// // at (−5, 0, 995), so it moves along −y at 5 mm/rad.
/// assert!((jac[0][1] + 5.0).abs() < 1e-9);
/// ```
pub fn joint_jacobian_dual<const N: usize>(
    params: &DhParams,
    q: &[f64],
) -> Result<Vec<[f64; 3]>, KernelError> {
    check(params, q)?;
    if N != q.len() {
        return Err(KernelError::JointCount {
            expected: q.len(),
            got: N,
        });
    }
    let x = SVector::<f64, N>::from_column_slice(q);
    let p = params.to_vec();
    let models = params.models();
    let (_, jac) = jacobian(
        |q: SVector<DualSVec64<N>, N>| {
            let params: Vec<DualSVec64<N>> = p.iter().map(|&v| DualSVec64::from(v)).collect();
            let r = position_with(&params, q.as_slice(), &models);
            nalgebra::Vector3::new(r[0], r[1], r[2])
        },
        &x,
    );
    Ok((0..N)
        .map(|c| [jac[(0, c)], jac[(1, c)], jac[(2, c)]])
        .collect())
}
