//! The Hayati parameterisation for (nearly) parallel consecutive axes.
//!
//! When joint `i`'s twist `α_i` is 0 or 180°, axes `i` and `i + 1` are
//! parallel and D-H's `d_i` is arbitrary (any common normal will do); near
//! that, a tiny tilt moves the common normal far along the axis, so `d_i`
//! and `d_{i+1}` swing by large, opposite amounts and the fit's σ of `d`
//! explodes. Hayati & Mirmirani (1985) replace `Tz(d_i)` by a rotation
//! `Ry(β_i)` about the link's y axis: `A_i = Rz(θ_i + q_i)·Tx(a_i)·Rx(α_i)·
//! Ry(β_i)`, which is smooth through parallel axes
//! ([`JointModel::Hayati`]).
//!
//! This module converts a D-H joint to a Hayati one exactly where that is
//! exact ([`DhParams::with_hayati`], parallel axes), and says which joints a
//! user should switch ([`candidates`], and the recommendations made of them), which
//! [`identify`](crate::identify) and the calibration report print.

use thiserror::Error;

use crate::domain::Arm;
use crate::params::{DhParams, JointModel};

/// A D-H joint whose `|α|` is within this many degrees of 0 or 180° is
/// recommended for the Hayati parameterisation: 1°, where D-H's `d` already
/// moves 57 mm per millimetre of tilt along a 1 m link.
pub(crate) const HAYATI_THRESHOLD_DEG: f64 = 1.0;

/// Why a joint cannot be converted exactly.
#[derive(Clone, Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum HayatiError {
    /// No such joint.
    #[error("joint {joint}: the arm has {joints} joints")]
    NoSuchJoint {
        /// The joint asked for (1-based).
        joint: usize,
        /// Joints of the arm.
        joints: usize,
    },
    /// The joint is Hayati already.
    #[error("joint {joint} is already a Hayati joint")]
    AlreadyHayati {
        /// The joint (1-based).
        joint: usize,
    },
    /// The axes are not exactly parallel, so `d` cannot move to the next
    /// link without changing positions.
    #[error(
        "joint {joint}: α = {alpha_deg}° is not exactly 0 or 180°, so its d cannot move to the \
         next link without changing positions (set the nominal twist to 0 or 180° first, if \
         the axes are parallel by design)"
    )]
    NotParallel {
        /// The joint (1-based).
        joint: usize,
        /// Its twist, degrees.
        alpha_deg: f64,
    },
    /// The next joint has no `d` to take this one's.
    #[error(
        "joint {joint}: the next joint is a Hayati joint, which has no d to take this joint's \
         d = {d_mm} mm; convert the joints from the probe end first"
    )]
    NextHasNoD {
        /// The joint (1-based).
        joint: usize,
        /// Its `d`, mm.
        d_mm: f64,
    },
}

/// The sign of `cos α` when `α` is exactly 0 or 180° (within rounding of
/// the angle itself), else `None`.
fn parallel_sign(alpha: f64) -> Option<f64> {
    // sin(π) in f64 is 1.2e-16: a twist read as 180° is parallel.
    (alpha.sin().abs() <= 1e-15).then(|| alpha.cos().signum())
}

impl DhParams {
    /// This arm with joint `joint` (0-based) in the Hayati
    /// parameterisation, positions unchanged: for parallel axes (`α` = 0 or
    /// 180°) `Tz(d)` commutes through `Tx(a)·Rx(α)` as `Tz(±d)` and joins the
    /// next joint's `d` (or the probe's `z` after the last joint); β = 0.
    ///
    /// ```
    /// use aacmm_core::params::{DhParams, JointModel};
    /// let mut arm = DhParams::paper_nominal();
    /// arm.joints[1].alpha = 0.0; // axes 2 and 3 parallel
    /// let h = arm.with_hayati(1).unwrap();
    /// assert_eq!(h.joints[1].model, JointModel::Hayati);
    /// assert_eq!(h.joints[2].d, arm.joints[2].d + arm.joints[1].d);
    /// assert!(DhParams::paper_nominal().with_hayati(1).is_err()); // α = 90°
    /// ```
    pub fn with_hayati(&self, joint: usize) -> Result<DhParams, HayatiError> {
        let n = self.joint_count();
        let j = self.joints.get(joint).ok_or(HayatiError::NoSuchJoint {
            joint: joint + 1,
            joints: n,
        })?;
        if j.model == JointModel::Hayati {
            return Err(HayatiError::AlreadyHayati { joint: joint + 1 });
        }
        let sign = parallel_sign(j.alpha).ok_or(HayatiError::NotParallel {
            joint: joint + 1,
            alpha_deg: j.alpha.to_degrees(),
        })?;
        let shift = sign * j.d;
        let mut out = self.clone();
        match out.joints.get_mut(joint + 1) {
            Some(next) if next.model == JointModel::Hayati && shift != 0.0 => {
                return Err(HayatiError::NextHasNoD {
                    joint: joint + 1,
                    d_mm: j.d,
                });
            }
            Some(next) if next.model == JointModel::Hayati => {}
            Some(next) => next.d += shift,
            None => out.probe[2] += shift,
        }
        let h = &mut out.joints[joint];
        h.model = JointModel::Hayati;
        h.d = 0.0;
        h.beta = 0.0;
        Ok(out)
    }
}

impl Arm {
    /// [`DhParams::with_hayati`] of this arm's geometry (limits and name
    /// kept).
    pub fn with_hayati(&self, joint: usize) -> Result<Arm, HayatiError> {
        Ok(Arm {
            params: self.params.with_hayati(joint)?,
            ..self.clone()
        })
    }
}

/// The D-H joints (0-based; not the last, whose twist leads to the probe)
/// whose `|α|` is within 1° of 0 or 180°.
///
/// ```
/// let mut arm = aacmm_core::params::DhParams::paper_nominal();
/// arm.joints[2].alpha = 0.3f64.to_radians();
/// assert_eq!(aacmm_core::hayati::candidates(&arm), [2]);
/// ```
pub fn candidates(params: &DhParams) -> Vec<usize> {
    let threshold = HAYATI_THRESHOLD_DEG.to_radians();
    // The last twist leads to the probe's frame, not to another axis: no
    // pair of axes to be parallel (the probe offset carries it).
    let axes_after = params.joints.len().saturating_sub(1);
    params
        .joints
        .iter()
        .enumerate()
        .take(axes_after)
        .filter(|(_, j)| j.model == JointModel::Dh)
        .filter(|(_, j)| {
            let a = crate::params::wrap(j.alpha).abs();
            a <= threshold || std::f64::consts::PI - a <= threshold
        })
        .map(|(i, _)| i)
        .collect()
}

/// One sentence per [`candidates`] joint: what to do and why.
pub(crate) fn recommendations(params: &DhParams) -> Vec<String> {
    candidates(params)
        .into_iter()
        .map(|i| {
            let alpha = params.joints[i].alpha.to_degrees();
            format!(
                "joint {j}: α = {alpha:.4}° is within {HAYATI_THRESHOLD_DEG}° of {parallel}, so \
                 axes {j} and {k} are nearly parallel and d{j} is ill-determined in the D-H \
                 model; consider `model = \"hayati\"` for joint {j} in the arm file (β about \
                 the link's y axis instead of d{j}; `DhParams::with_hayati` converts exactly \
                 when α is 0 or 180°)",
                j = i + 1,
                k = i + 2,
                parallel = if alpha.abs() < 90.0 { "0°" } else { "180°" },
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::ArmKernel;
    use crate::params::DhJoint;
    use rand::{RngExt, SeedableRng};
    use std::f64::consts::PI;

    /// A random arm of `n` joints with joint `i`'s axis parallel to the next
    /// (α = 0 or π).
    fn parallel_arm(rng: &mut impl rand::Rng, n: usize, i: usize, flip: bool) -> DhParams {
        let mut p = DhParams {
            joints: (0..n)
                .map(|_| {
                    DhJoint::dh(
                        rng.random_range(-300.0..300.0),
                        rng.random_range(-300.0..300.0),
                        rng.random_range(-PI..PI),
                        rng.random_range(-PI..PI),
                    )
                })
                .collect(),
            probe: [
                rng.random_range(-50.0..50.0),
                rng.random_range(-50.0..50.0),
                rng.random_range(50.0..150.0),
            ],
        };
        p.joints[i].alpha = if flip { PI } else { 0.0 };
        p
    }

    #[test]
    fn conversion_keeps_positions_for_parallel_axes() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(16);
        for n in [6, 7] {
            for i in 0..n {
                for flip in [false, true] {
                    let dh = parallel_arm(&mut rng, n, i, flip);
                    let h = dh.with_hayati(i).unwrap();
                    assert_eq!(h.joints[i].model, JointModel::Hayati);
                    let (kd, kh) = (ArmKernel::new(&dh).unwrap(), ArmKernel::new(&h).unwrap());
                    for _ in 0..50 {
                        let q: Vec<f64> = (0..n).map(|_| rng.random_range(-PI..PI)).collect();
                        let (a, b) = (kd.position(&q).unwrap(), kh.position(&q).unwrap());
                        for k in 0..3 {
                            assert!((a[k] - b[k]).abs() < 1e-9, "n={n} i={i}: {a:?} {b:?}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn conversion_refuses_what_is_not_exact() {
        let arm = DhParams::paper_nominal();
        assert!(matches!(
            arm.with_hayati(2),
            Err(HayatiError::NotParallel { joint: 3, .. })
        ));
        assert!(matches!(
            arm.with_hayati(6),
            Err(HayatiError::NoSuchJoint { joint: 7, .. })
        ));
        let mut two = arm.clone();
        two.joints[1].alpha = 0.0;
        two.joints[2].alpha = 0.0;
        let h = two.with_hayati(2).unwrap();
        assert_eq!(
            h.with_hayati(2),
            Err(HayatiError::AlreadyHayati { joint: 3 })
        );
        // Joint 2's d (−55 → d2 = 0 in the paper arm) moves nowhere: allowed.
        assert!(h.with_hayati(1).is_ok());
        let mut h = h;
        h.joints[1].d = 5.0;
        assert!(matches!(
            h.with_hayati(1),
            Err(HayatiError::NextHasNoD { joint: 2, .. })
        ));
    }

    /// `Rz(π)` passes through a Hayati link as `θ + π, −a, −α, −β` (what
    /// `normalize_signs` undoes): positions unchanged both ways.
    #[test]
    fn a_flipped_hayati_joint_is_the_same_arm_and_is_normalised() {
        use crate::calibrate::global::normalize_signs;
        let mut nominal = DhParams::paper_nominal();
        nominal.joints[1].alpha = 0.0;
        let mut nominal = nominal.with_hayati(1).unwrap();
        nominal.joints[1].beta = 0.01;
        nominal.joints[1].alpha = 0.002; // nearly parallel
        let mut flipped = nominal.clone();
        let j = &mut flipped.joints[1];
        j.theta += PI;
        (j.a, j.alpha, j.beta) = (-j.a, -j.alpha, -j.beta);
        flipped.joints[2].theta += PI;
        let (k0, k1) = (
            ArmKernel::new(&nominal).unwrap(),
            ArmKernel::new(&flipped).unwrap(),
        );
        let q = [0.1, -0.7, 1.3, 0.4, -2.0, 0.6];
        let (p0, p1) = (k0.position(&q).unwrap(), k1.position(&q).unwrap());
        assert!(
            (0..3).all(|k| (p0[k] - p1[k]).abs() < 1e-9),
            "{p0:?} {p1:?}"
        );
        let all: Vec<usize> = (0..27).collect();
        let changed = normalize_signs(&mut flipped, &nominal, &all);
        assert_eq!(changed, ["theta2", "a2", "alpha2", "hbeta2", "theta3"]);
        assert!((flipped.joints[1].beta - 0.01).abs() < 1e-15);
        let p2 = ArmKernel::new(&flipped).unwrap().position(&q).unwrap();
        assert!(
            (0..3).all(|k| (p0[k] - p2[k]).abs() < 1e-9),
            "{p0:?} {p2:?}"
        );
    }

    #[test]
    fn candidates_within_the_threshold_only() {
        let mut arm = DhParams::paper_nominal();
        assert!(candidates(&arm).is_empty());
        arm.joints[1].alpha = (180.0 - 0.9f64).to_radians();
        arm.joints[3].alpha = 1.1f64.to_radians();
        arm.joints[4].alpha = -0.5f64.to_radians();
        arm.joints[5].alpha = 0.0;
        assert_eq!(candidates(&arm), [1, 4], "the last twist has no next axis");
        let notes = recommendations(&arm);
        assert!(notes[0].starts_with("joint 2: α = 179.1000° is within 1° of 180°"));
        assert!(notes[1].contains("axes 5 and 6"));
        arm.joints[4].model = JointModel::Hayati;
        assert_eq!(candidates(&arm), [1]);
    }
}
