//! The true arm: the nominal plus an error model.

use std::f64::consts::PI;

use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use super::{ErrorModel, SimError};
use crate::domain::Arm;
use crate::io::{AngleUnit, LengthUnit, arm_to_toml, parse_arm};
use crate::params::{JointModel, wrap};

/// The paper's identified errors (method.md §7, Table 2), per joint:
/// `(Δθ deg, Δβ deg, Δa mm, Δd mm)`; joint 6 has no `Δθ`, `Δβ`.
pub(crate) const PAPER_TABLE_2: [(f64, f64, f64, f64); 6] = [
    (0.131, 0.124, 0.061, 0.186),
    (0.446, 0.065, -1.106, -0.416),
    (-0.735, -0.021, 0.121, 0.041),
    (0.126, -0.057, -0.673, -0.038),
    (-0.513, 0.034, -0.076, -0.124),
    (0.0, 0.0, 0.306, 0.177),
];

/// The paper's probe error `(ΔBx, ΔBy, ΔBz)`, mm.
pub(crate) const PAPER_PROBE_ERROR: [f64; 3] = [0.0, 0.0, 0.094];

/// The true arm for `model` on `nominal`, drawing from `rng` (only the random
/// model draws: per joint `a, d, α, θ`, then `Bx, By, Bz`). The result is
/// canonical: written as an arm file in mm and degrees and read back it is
/// the same arm, bit for bit. Joint limits are the nominal's, or for a given
/// true arm its own where it states them.
///
/// ```
/// use aacmm_core::{domain::Arm, params::DhParams, simulate::{ErrorModel, true_arm}};
/// use rand::SeedableRng;
/// let nominal = Arm::without_limits("n", DhParams::paper_nominal());
/// let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
/// let t = true_arm(&nominal, &ErrorModel::Paper, &mut rng).unwrap();
/// assert!((t.params.joints[1].a - (-55.0 - 1.106)).abs() < 1e-12);
/// assert!((t.params.probe[2] - 100.094).abs() < 1e-12);
/// ```
pub fn true_arm(nominal: &Arm, model: &ErrorModel, rng: &mut ChaCha8Rng) -> Result<Arm, SimError> {
    let n = nominal.params.joint_count();
    let deg = |x: f64| x.to_radians();
    let mut arm = nominal.clone();
    arm.limits.resize(n, None);
    match model {
        ErrorModel::Paper => {
            if n != 6 {
                return Err(SimError::Model(format!(
                    "the paper's Table 2 errors are for a 6-joint arm; the nominal arm has {n} \
                     joints"
                )));
            }
            // Table 2's d errors have no slot in a Hayati joint (its d-slot
            // is the angle β): applying them would drop some silently.
            if let Some(k) = arm
                .params
                .joints
                .iter()
                .position(|j| j.model == JointModel::Hayati)
            {
                return Err(SimError::Model(format!(
                    "the paper's Table 2 errors are for its D-H arm, and joint {} of the nominal \
                     arm is Hayati (no d to err); use the random errors or a true arm file",
                    k + 1
                )));
            }
            for (j, &(dt, db, da, dd)) in arm.params.joints.iter_mut().zip(&PAPER_TABLE_2) {
                j.theta += deg(dt);
                j.alpha += deg(db);
                j.a += da;
                j.d += dd;
            }
            for (b, db) in arm.params.probe.iter_mut().zip(PAPER_PROBE_ERROR) {
                *b += db;
            }
            arm.name = format!("true: {} + paper Table 2 errors", nominal.name);
        }
        ErrorModel::Random {
            length_sigma_mm: sl,
            twist_sigma_deg: st,
            zero_sigma_deg: sz,
            zero_uniform,
        } => {
            for j in arm.params.joints.iter_mut() {
                j.a += sl * normal(rng);
                // The d-slot's draw: a length for D-H, a twist for Hayati's
                // β (one draw either way, so D-H arms keep their streams).
                let slot = normal(rng);
                match j.model {
                    JointModel::Dh => j.d += sl * slot,
                    JointModel::Hayati => j.beta += deg(st * slot),
                }
                j.alpha += deg(st * normal(rng));
                j.theta = if *zero_uniform {
                    wrap(j.theta + rng.random_range(-PI..PI))
                } else {
                    j.theta + deg(sz * normal(rng))
                };
            }
            for b in arm.params.probe.iter_mut() {
                *b += sl * normal(rng);
            }
            arm.name = format!("true: {} + {}", nominal.name, model.describe());
        }
        ErrorModel::File { arm: given } => {
            if given.params.joint_count() != n {
                return Err(SimError::Model(format!(
                    "the true arm {} has {} joints, the nominal arm {n}",
                    crate::error::quoted(&given.name),
                    given.params.joint_count()
                )));
            }
            arm.params = given.params.clone();
            // Its errors beyond geometry (compliance, harmonics, an
            // expansion) are the true arm's too.
            if given.physics.corrects() || given.physics.has_masses() {
                arm.physics = given.physics.clone();
            }
            for (lim, own) in arm.limits.iter_mut().zip(&given.limits) {
                if own.is_some() {
                    *lim = *own;
                }
            }
            arm.name = given.name.clone();
        }
    }
    Ok(canonical(arm))
}

/// The arm as it reads back from its own mm/degree arm file.
fn canonical(arm: Arm) -> Arm {
    match parse_arm(
        &arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg),
        "true arm",
    ) {
        Ok((canonical, _)) => canonical,
        Err(_) => arm,
    }
}

/// A standard normal draw.
pub(crate) fn normal(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}
