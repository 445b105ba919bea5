//! Inverse kinematics for a point: damped least squares (Levenberg–Marquardt)
//! on the kernel's analytic `3 × N` joint Jacobian.
//!
//! An arm of more than three joints is redundant for a point (three
//! constraints), so the solution reached depends on the start: random starts
//! give genuinely different articulations of the same point. A prismatic
//! joint's variable (mm) is scaled to a metre for the step, so that one
//! damping suits slides and turns.

use nalgebra::{Matrix3, Vector3};

use crate::damping::Damping;
use crate::kernel::{ArmKernel, KernelError};

/// Residual below which a solution is accepted, mm.
pub(crate) const IK_TOLERANCE_MM: f64 = 1e-10;
/// The length (mm) a prismatic joint's variable is counted in by the
/// solver: a metre, as a radian of a metre-long link.
const SLIDE_SCALE_MM: f64 = 1000.0;
/// Iterations allowed per start.
pub(crate) const IK_MAX_ITERATIONS: usize = 200;

/// The outcome of one inverse-kinematics run.
#[derive(Clone, Debug, PartialEq)]
pub struct IkSolution {
    /// Encoder readings reached, rad (not wrapped).
    pub q: Vec<f64>,
    /// Distance from the probe centre to the target, mm.
    pub(crate) residual_mm: f64,
    /// Iterations used.
    pub(crate) iterations: usize,
}

impl IkSolution {
    /// Whether the residual is below 1e-10 mm.
    pub fn converged(&self) -> bool {
        self.residual_mm < IK_TOLERANCE_MM
    }
}

/// Readings `q` that put the probe centre of the arm `k` at `target` (mm),
/// starting from `start`: Levenberg–Marquardt with the step
/// `Δq = Jᵀ (J Jᵀ + μI)⁻¹ r`, `μ` divided by 3 after a step that lowers the
/// residual and multiplied by 4 after one that does not. Stops when the
/// residual is below 1e-10 mm or after 200 iterations.
///
/// ```
/// use aacmm_core::{kernel::ArmKernel, params::DhParams, simulate::solve_point};
/// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
/// let target = k.position(&[0.3, -0.5, 0.2, 1.0, -0.4, 0.7]).unwrap();
/// let s = solve_point(&k, target, &[0.0, -1.0, 0.5, 0.5, 0.0, 0.0]).unwrap();
/// assert!(s.converged());
/// let p = k.position(&s.q).unwrap();
/// assert!((0..3).all(|i| (p[i] - target[i]).abs() < 1e-10));
/// ```
pub fn solve_point(
    k: &ArmKernel,
    target: [f64; 3],
    start: &[f64],
) -> Result<IkSolution, KernelError> {
    // A prismatic joint moves in mm, a revolute one in rad: its variable
    // is taken in metres (its column times 1000 mm), so that one damping
    // suits both (1 m of slide moves the probe as much as 1 rad of a 1 m
    // link). A revolute column is multiplied by 1: exact.
    let scale: Vec<f64> = (0..start.len())
        .map(|j| {
            if k.shape().is_prismatic(j) {
                SLIDE_SCALE_MM
            } else {
                1.0
            }
        })
        .collect();
    // Buffers for the current and the trial pose, swapped on a step that
    // lowers the residual: nothing is allocated per iteration.
    let mut q = start.to_vec();
    let mut jac = vec![[0.0; 3]; q.len()];
    let mut trial = q.clone();
    let mut jac_trial = jac.clone();
    let mut r = residual(k, target, &q, &scale, &mut jac)?;
    let mut err = r.norm();
    let mut mu = Damping::fixed_factors(1e-3 * jjt(&jac).trace() / 3.0, 3.0, 4.0);
    let mut iterations = 0;
    while err >= IK_TOLERANCE_MM && iterations < IK_MAX_ITERATIONS {
        iterations += 1;
        let a = jjt(&jac) + Matrix3::identity() * mu.value();
        let mut lower = None;
        if let Some(y) = a.lu().solve(&r) {
            for (j, t) in trial.iter_mut().enumerate() {
                let c = &jac[j];
                *t = if scale[j] == 1.0 {
                    // The revolute step as it always was, to the bit.
                    q[j] + c[0] * y[0] + c[1] * y[1] + c[2] * y[2]
                } else {
                    q[j] + (c[0] * y[0] + c[1] * y[1] + c[2] * y[2]) * scale[j]
                };
            }
            let r_new = residual(k, target, &trial, &scale, &mut jac_trial)?;
            let err_new = r_new.norm();
            lower = (err_new < err).then_some((r_new, err_new));
        }
        match lower {
            Some((r_new, err_new)) => {
                std::mem::swap(&mut q, &mut trial);
                std::mem::swap(&mut jac, &mut jac_trial);
                (r, err) = (r_new, err_new);
                // The fixed factors do not look at the gain ratio.
                mu.accept(f64::NAN);
            }
            None => mu.reject(),
        }
    }
    Ok(IkSolution {
        q,
        residual_mm: err,
        iterations,
    })
}

/// `target − p(q)`, and the columns `∂p/∂q_j` (times `scale[j]`) in `jac`.
fn residual(
    k: &ArmKernel,
    target: [f64; 3],
    q: &[f64],
    scale: &[f64],
    jac: &mut [[f64; 3]],
) -> Result<Vector3<f64>, KernelError> {
    let p = k.joint_jacobian(q, jac)?;
    for (col, c) in jac.iter_mut().zip(scale) {
        *col = col.map(|v| v * c);
    }
    Ok(Vector3::new(
        target[0] - p[0],
        target[1] - p[1],
        target[2] - p[2],
    ))
}

/// `J Jᵀ` of the columns `∂p/∂q_j`.
fn jjt(jac: &[[f64; 3]]) -> Matrix3<f64> {
    let mut m = Matrix3::zeros();
    for col in jac {
        let c = Vector3::from(*col);
        m += c * c.transpose();
    }
    m
}
