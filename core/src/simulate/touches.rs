//! Touches: for each socket, `N` genuinely different articulations found by
//! inverse kinematics on the true arm from random starts.

use rand_chacha::ChaCha8Rng;

use super::ik::solve_point;
use super::separation::Accepted;
use super::sockets::random_configuration;
use super::truth::normal;
use super::{SimError, SimStats};
use crate::domain::Arm;
use crate::kernel::ArmKernel;
use crate::params::wrap;

/// One simulated touch.
#[derive(Clone, Debug, PartialEq)]
pub struct Touch {
    /// Index of the socket touched.
    pub(crate) socket: usize,
    /// Where the probe centre actually sat (socket centre plus seating
    /// noise), mm.
    pub point: [f64; 3],
    /// The true readings that put the true arm's probe there, rad, each in
    /// `[-π, π)` (or shifted by a turn into the joint's limits).
    pub q: Vec<f64>,
}

/// What the touch search needs besides the arm and the sockets.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TouchPlan {
    /// Touches per socket.
    pub(crate) poses: usize,
    /// σ of the probe seating per axis, mm.
    pub(crate) probe_noise_mm: f64,
    /// Minimum pose separation (largest joint difference), rad.
    pub(crate) min_separation: f64,
    /// Budget of IK starts per requested touch.
    pub(crate) starts_per_pose: usize,
}

/// The touches of every socket, socket by socket. For each touch the seating
/// point is drawn first (`seat_rng`, three normal draws, even at zero
/// noise), then IK starts (`start_rng`) are tried until a solution converges
/// (residual < [`IK_TOLERANCE_MM`](super::IK_TOLERANCE_MM)), lies within the
/// joint limits and differs from every earlier touch of the socket by at
/// least `min_separation` in some joint (differences wrapped to ±π). A socket
/// gets `poses × starts_per_pose` starts in all; then
/// [`SimError::TooFewPoses`]. `progress` is told the fraction of the
/// sockets done after each.
pub(crate) fn find_touches(
    arm: &Arm,
    sockets: &[(String, [f64; 3])],
    plan: &TouchPlan,
    seat_rng: &mut ChaCha8Rng,
    start_rng: &mut ChaCha8Rng,
    stats: &mut SimStats,
    progress: &mut dyn FnMut(f64),
) -> Result<Vec<Touch>, SimError> {
    let k = ArmKernel::new(&arm.params)?;
    let prismatic = k.shape().prismatic_mask();
    let scales = separation_scales(arm, prismatic);
    let budget = plan.poses * plan.starts_per_pose;
    let mut touches = Vec::with_capacity(sockets.len() * plan.poses);
    for (s, (label, centre)) in sockets.iter().enumerate() {
        let mut accepted = Accepted::new(&scales, plan.min_separation, plan.poses);
        let mut attempts = 0;
        while accepted.len() < plan.poses {
            let point: [f64; 3] =
                std::array::from_fn(|i| centre[i] + plan.probe_noise_mm * normal(seat_rng));
            let q = loop {
                if attempts == budget {
                    return Err(SimError::TooFewPoses {
                        socket: label.clone(),
                        wanted: plan.poses,
                        found: accepted.len(),
                        attempts,
                        min_separation_deg: plan.min_separation.to_degrees(),
                    });
                }
                attempts += 1;
                stats.ik_starts += 1;
                let start = random_configuration(&arm.limits, start_rng);
                let sol = solve_point(&k, point, &start)?;
                stats.ik_iterations += sol.iterations;
                if !sol.converged() {
                    stats.not_converged += 1;
                    continue;
                }
                let Some(q) = within_limits(sol.q, &arm.limits, prismatic) else {
                    stats.outside_limits += 1;
                    continue;
                };
                if accepted.too_close(&q) {
                    stats.too_close += 1;
                    continue;
                }
                break q;
            };
            // A true arm with errors beyond geometry reads other angles in
            // this pose (the separation is judged on the pose itself).
            let reading = if arm.physics.corrects() {
                crate::corrections::readings_for(&arm.params, &arm.physics, &q)
            } else {
                q.clone()
            };
            touches.push(Touch {
                socket: s,
                point,
                q: reading,
            });
            accepted.push(q);
        }
        progress((s + 1) as f64 / sockets.len() as f64);
    }
    Ok(touches)
}

/// The readings wrapped to `[-π, π)` and, where a joint has limits, shifted
/// by a whole turn into them if that helps; `None` if some joint stays
/// outside its limits. A prismatic joint's reading (a bit of `prismatic`,
/// mm) is not wrapped: it must lie within its stroke.
pub(crate) fn within_limits(
    q: Vec<f64>,
    limits: &[Option<[f64; 2]>],
    prismatic: u16,
) -> Option<Vec<f64>> {
    use std::f64::consts::TAU;
    let slides = |j: usize| j < 16 && prismatic & (1 << j) != 0;
    let mut out: Vec<f64> = (q.into_iter().enumerate())
        .map(|(j, x)| if slides(j) { x } else { wrap(x) })
        .collect();
    for (j, x) in out.iter_mut().enumerate() {
        if let Some([lo, hi]) = limits.get(j).copied().flatten() {
            let turns: &[f64] = if slides(j) { &[0.0] } else { &[0.0, TAU, -TAU] };
            *x = (turns.iter().map(|t| *x + t)).find(|v| (lo..=hi).contains(v))?;
        }
    }
    Some(out)
}

/// The largest joint difference of two poses of revolute joints, each
/// wrapped to ±π, rad.
#[cfg(test)]
pub(crate) fn separation(a: &[f64], b: &[f64]) -> f64 {
    separation_scaled(a, b, &vec![0.0; a.len()])
}

/// Per joint, what a prismatic joint's difference (mm) is multiplied by to
/// count as an angle in [`separation_scaled`]: its whole stroke counts as
/// a full turn (the simulator requires a stroke; 1 m a radian without).
/// 0 for a revolute joint.
pub(crate) fn separation_scales(arm: &Arm, prismatic: u16) -> Vec<f64> {
    (0..arm.params.joint_count())
        .map(|j| match arm.limits.get(j).copied().flatten() {
            _ if j >= 16 || prismatic & (1 << j) == 0 => 0.0,
            Some([lo, hi]) if hi > lo => std::f64::consts::TAU / (hi - lo),
            _ => 1e-3,
        })
        .collect()
}

/// The largest joint difference of two poses: a revolute joint's wrapped
/// to ±π (rad), a prismatic one's (`scales[j] > 0`) times its scale.
pub(crate) fn separation_scaled(a: &[f64], b: &[f64], scales: &[f64]) -> f64 {
    (a.iter().zip(b).zip(scales))
        .map(|((x, y), &s)| {
            if s > 0.0 {
                (x - y).abs() * s
            } else {
                wrap(x - y).abs()
            }
        })
        .fold(0.0, f64::max)
}
