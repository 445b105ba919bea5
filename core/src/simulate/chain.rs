//! A random nominal arm of any chain shape (`aacmm simulate --chain
//! PRRRRRR`): for simulated campaigns of machines no arm file describes.
//!
//! The recipe, every draw from the seed's own stream (same seed and
//! shape, same arm, bit for bit):
//!
//! - a link scale `ℓ = 2400 mm / (revolute joints + 1)`, kept within
//!   100–600 mm, so that the reach is a real robot's (1–2 m) whatever the
//!   joint count;
//! - every joint's twist `α` is ±90° (sign at random), the last joint's 0:
//!   no two consecutive axes are parallel, so every joint is well posed in
//!   the D-H convention;
//! - a revolute joint: `θ = 0`, `a` uniform in `[0.3ℓ, ℓ]`, `d` uniform in
//!   `[0, 0.5ℓ]`, no limits (a full turn);
//! - a prismatic joint: `θ` 0° or 90° at random, `a = 0`, `d` (the
//!   reading's zero) uniform in `[0, 0.5ℓ]`, a stroke `[0, S]` with `S`
//!   uniform in 400–1200 mm;
//! - a probe `(0, 0, z)`, `z` uniform in 50–150 mm.
//!
//! Lengths are rounded to 0.1 mm, and the arm is the one its mm/degree
//! arm file reads back as.

use rand::RngExt;

use crate::domain::Arm;
use crate::io::{AngleUnit, LengthUnit, arm_to_toml, parse_arm};
use crate::params::{ChainShape, DhJoint, DhParams, JointKind};
use crate::random::{rng, streams};

/// The random nominal arm of `shape` for `seed` (see the module docs).
///
/// ```
/// use aacmm_core::simulate::random_arm;
/// let track = random_arm("PRRRRRR".parse().unwrap(), 7);
/// assert_eq!(track.params.shape().unwrap().to_string(), "PRRRRRR");
/// assert!(track.limits[0].is_some() && track.limits[1].is_none());
/// assert_eq!(track, random_arm("PRRRRRR".parse().unwrap(), 7));
/// assert_ne!(track, random_arm("PRRRRRR".parse().unwrap(), 8));
/// ```
pub fn random_arm(shape: ChainShape, seed: u64) -> Arm {
    let mut rng = rng(seed, streams::CHAIN);
    let n = shape.joints();
    let revolute = (0..n).filter(|&j| !shape.is_prismatic(j)).count();
    let scale = (2400.0 / (revolute + 1) as f64).clamp(100.0, 600.0);
    let mm = |x: f64| (x * 10.0).round() / 10.0;
    let quarter = std::f64::consts::FRAC_PI_2;
    let mut joints = Vec::with_capacity(n);
    let mut limits = Vec::with_capacity(n);
    for j in 0..n {
        let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let alpha = if j + 1 == n { 0.0 } else { sign * quarter };
        if shape.is_prismatic(j) {
            let theta = if rng.random_bool(0.5) { quarter } else { 0.0 };
            let d = mm(rng.random_range(0.0..=0.5 * scale));
            let stroke = mm(rng.random_range(400.0..=1200.0));
            joints.push(DhJoint::dh(0.0, d, alpha, theta).with_kind(JointKind::Prismatic));
            limits.push(Some([0.0, stroke]));
        } else {
            let a = mm(rng.random_range(0.3 * scale..=scale));
            let d = mm(rng.random_range(0.0..=0.5 * scale));
            joints.push(DhJoint::dh(a, d, alpha, 0.0));
            limits.push(None);
        }
    }
    let probe = [0.0, 0.0, mm(rng.random_range(50.0..=150.0))];
    let arm = Arm {
        limits,
        ..Arm::without_limits(
            format!("random {shape} (seed {seed})"),
            DhParams { joints, probe },
        )
    };
    let text = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg);
    match parse_arm(&text, "random arm") {
        Ok((canonical, _)) => canonical,
        Err(_) => arm,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::ArmKernel;

    /// Every shape of 1 to 12 joints gives an arm the kernel computes,
    /// with a reach of a real robot's order and a stroke per slide.
    #[test]
    fn random_arms_are_computable_and_robot_sized() {
        for (i, text) in [
            "R",
            "PR",
            "RRPR",
            "RRRRR",
            "PRRRRRR",
            "PRRRRRRR",
            "RRPRRPRRRPRR",
        ]
        .iter()
        .enumerate()
        {
            let shape: ChainShape = text.parse().unwrap();
            let arm = random_arm(shape, i as u64);
            assert_eq!(arm.params.shape().unwrap(), shape);
            ArmKernel::new(&arm.params).unwrap();
            let reach = arm.params.reach();
            assert!((100.0..4000.0).contains(&reach), "{text}: reach {reach}");
            for j in 0..shape.joints() {
                assert_eq!(arm.limits[j].is_some(), shape.is_prismatic(j), "{text} {j}");
            }
        }
    }
}
