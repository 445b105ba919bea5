//! The generic reference model: the textbook product of 4×4 homogeneous
//! matrices with nalgebra, written once over any [`DualNum`], so `f64` gives
//! positions and dual numbers give exact derivatives. This is the oracle the
//! generated kernel is checked against, not the fast path.

use nalgebra::{Matrix4, SVector, Vector4};
use num_dual::{DualNum, DualSVec64, jacobian};

use crate::kernel::KernelError;
use crate::params::{DhParams, JointKind, JointModel, param_count};

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
pub(crate) fn position_with<D: DualNum<Primitive = f64> + Copy>(
    params: &[D],
    q: &[D],
    models: &[JointModel],
) -> [D; 3] {
    let t = tool_with(params, q, models, &vec![JointKind::Revolute; q.len()]);
    [t[(0, 3)], t[(1, 3)], t[(2, 3)]]
}

/// The tool's homogeneous transform (the last frame turned, its origin
/// moved to the probe) of a chain whose joints have `models` and `kinds`:
/// a [`JointKind::Prismatic`] joint's reading (mm) adds to `d` and its
/// angle is `θ` alone.
///
/// # Panics
/// As `position_with`, or if `kinds.len() != q.len()`.
///
/// ```
/// use aacmm_core::{params::{DhParams, JointKind, JointModel}, reference_model};
/// let arm = DhParams::paper_nominal().to_vec();
/// let mut kinds = vec![JointKind::Revolute; 6];
/// kinds[0] = JointKind::Prismatic;
/// // Joint 1 slides 100 mm along the base z axis (and turns by θ1 = 0).
/// let t = reference_model::tool_with(&arm, &[100.0, 0.0, 0.0, 0.0, 0.0, 0.0], &[JointModel::Dh; 6], &kinds);
/// assert!((t[(2, 3)] - 1095.0).abs() < 1e-9);
/// ```
pub fn tool_with<D: DualNum<Primitive = f64> + Copy>(
    params: &[D],
    q: &[D],
    models: &[JointModel],
    kinds: &[JointKind],
) -> Matrix4<D> {
    let n = q.len();
    assert_eq!(params.len(), param_count(n), "parameter vector length");
    assert_eq!(models.len(), n, "one model per joint");
    assert_eq!(kinds.len(), n, "one kind per joint");
    let zero = D::from(0.0);
    let one = D::from(1.0);
    let mut t = Matrix4::<D>::identity();
    for (j, &qj) in q.iter().enumerate() {
        let (a, slot, alpha, theta) = (
            params[j],
            params[n + j],
            params[2 * n + j],
            params[3 * n + j],
        );
        let d = match models[j] {
            JointModel::Dh => slot,
            JointModel::Hayati => zero,
        };
        let (angle, d) = match kinds[j] {
            JointKind::Revolute => (qj + theta, d),
            JointKind::Prismatic => (theta, d + qj),
        };
        let (st, ct) = angle.sin_cos();
        let (sa, ca) = alpha.sin_cos();
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
    let p = t * Vector4::new(b[0], b[1], b[2], one);
    for r in 0..3 {
        t[(r, 3)] = p[r];
    }
    t
}

/// The tool transform of `params` (its joints' models and kinds) at `q`.
fn tool_of<D: DualNum<Primitive = f64> + Copy>(params: &DhParams, x: &[D], q: &[D]) -> Matrix4<D> {
    let kinds: Vec<JointKind> = params.joints.iter().map(|j| j.kind).collect();
    tool_with(x, q, &params.models(), &kinds)
}

/// The 12 numbers of `[R | p]`, row-major.
fn top_rows<D: DualNum<Primitive = f64> + Copy>(t: &Matrix4<D>) -> nalgebra::SVector<D, 12> {
    nalgebra::SVector::<D, 12>::from_fn(|k, _| t[(k / 4, k % 4)])
}

/// A 6-row column from the derivative `dt` of `[R | p]` (row-major, as
/// [`top_rows`]) and `R`: the position's derivative, then `ω` with
/// `dR = [ω]× R`, the axial vector of `dR·Rᵀ`.
fn six_row(dt: impl Fn(usize, usize) -> f64, r: impl Fn(usize, usize) -> f64) -> [f64; 6] {
    let w = |i: usize, j: usize| (0..3).map(|k| dt(i, k) * r(j, k)).sum::<f64>();
    [
        dt(0, 3),
        dt(1, 3),
        dt(2, 3),
        (w(2, 1) - w(1, 2)) / 2.0,
        (w(0, 2) - w(2, 0)) / 2.0,
        (w(1, 0) - w(0, 1)) / 2.0,
    ]
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
    param_pose_jacobian_dual::<P>(params, q).map(position_rows)
}

/// The position rows of 6-row columns.
fn position_rows(cols: Vec<[f64; 6]>) -> Vec<[f64; 3]> {
    cols.iter().map(|c| [c[0], c[1], c[2]]).collect()
}

/// The tool pose's 6-row parameter Jacobian (position rows, then the small
/// rotation `ω` with `δR = [ω]× R`) by forward-mode autodiff; `P` must be
/// `4n + 3`.
///
/// ```
/// use aacmm_core::{params::DhParams, reference_model};
/// let arm = DhParams::paper_nominal();
/// let jac = reference_model::param_pose_jacobian_dual::<27>(&arm, &[0.0; 6]).unwrap();
/// assert_eq!(jac[18][3..], [0.0, 0.0, 1.0]); // θ1 turns the tool about the base z axis
/// ```
pub fn param_pose_jacobian_dual<const P: usize>(
    params: &DhParams,
    q: &[f64],
) -> Result<Vec<[f64; 6]>, KernelError> {
    check(params, q)?;
    if params.param_count() != P {
        return Err(KernelError::ParamCount {
            expected: params.param_count(),
            got: P,
        });
    }
    let x = SVector::<f64, P>::from_iterator(params.to_vec());
    let (value, jac) = jacobian(
        |x: SVector<DualSVec64<P>, P>| {
            let q: Vec<DualSVec64<P>> = q.iter().map(|&v| DualSVec64::from(v)).collect();
            top_rows(&tool_of(params, x.as_slice(), &q))
        },
        &x,
    );
    Ok((0..P)
        .map(|c| six_row(|i, j| jac[(4 * i + j, c)], |i, j| value[4 * i + j]))
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
    param_pose_jacobian_central(params, q, h).map(position_rows)
}

/// The tool pose's 6-row parameter Jacobian by central differences of
/// [`tool_with`] with step `h`.
pub fn param_pose_jacobian_central(
    params: &DhParams,
    q: &[f64],
    h: f64,
) -> Result<Vec<[f64; 6]>, KernelError> {
    check(params, q)?;
    Ok(central_columns(&params.to_vec(), h, |x| {
        tool_of(params, x, q)
    }))
}

/// The tool pose's 6-row joint Jacobian by central differences with step
/// `h` (rad, or mm for a prismatic joint).
pub fn joint_pose_jacobian_central(
    params: &DhParams,
    q: &[f64],
    h: f64,
) -> Result<Vec<[f64; 6]>, KernelError> {
    check(params, q)?;
    let x = params.to_vec();
    Ok(central_columns(q, h, |q| tool_of(params, &x, q)))
}

/// The 6-row columns of the tool transform `tool` by central differences
/// in each value of `at`, step `h`.
fn central_columns(at: &[f64], h: f64, tool: impl Fn(&[f64]) -> Matrix4<f64>) -> Vec<[f64; 6]> {
    let here = tool(at);
    let mut shifted = at.to_vec();
    (0..at.len())
        .map(|c| {
            shifted[c] = at[c] + h;
            let plus = tool(&shifted);
            shifted[c] = at[c] - h;
            let minus = tool(&shifted);
            shifted[c] = at[c];
            six_row(
                |i, j| (plus[(i, j)] - minus[(i, j)]) / (2.0 * h),
                |i, j| here[(i, j)],
            )
        })
        .collect()
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
    joint_pose_jacobian_dual::<N>(params, q).map(position_rows)
}

/// The tool pose's 6-row joint Jacobian by forward-mode autodiff; `N` must
/// be the joint count.
pub fn joint_pose_jacobian_dual<const N: usize>(
    params: &DhParams,
    q: &[f64],
) -> Result<Vec<[f64; 6]>, KernelError> {
    check(params, q)?;
    if N != q.len() {
        return Err(KernelError::JointCount {
            expected: q.len(),
            got: N,
        });
    }
    let x = SVector::<f64, N>::from_column_slice(q);
    let p = params.to_vec();
    let (value, jac) = jacobian(
        |q: SVector<DualSVec64<N>, N>| {
            let x: Vec<DualSVec64<N>> = p.iter().map(|&v| DualSVec64::from(v)).collect();
            top_rows(&tool_of(params, &x, q.as_slice()))
        },
        &x,
    );
    Ok((0..N)
        .map(|c| six_row(|i, j| jac[(4 * i + j, c)], |i, j| value[4 * i + j]))
        .collect())
}
