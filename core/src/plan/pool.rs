//! The candidates a plan chooses from: read from a poses file, or drawn —
//! positions uniformly within the arm's joint limits, or touches of
//! sockets found on the arm itself by inverse kinematics.
//!
//! Drawn touches meet at their sockets exactly (the arm is its own true
//! arm, without noise): the identifiability analysis the plan starts from
//! takes their exact scale invariance for what it is
//! ([`crate::identify`]), so no noise is added to keep the residuals off
//! zero.

use crate::domain::{Arm, Poses, Spheres};
use crate::params::ChainShape;
use crate::residuals::Noise;
use crate::simulate::{
    CampaignSettings, ErrorModel, MIN_POSES_PER_SOCKET, PositionSettings, SimError, SocketPlan,
    simulate_observed, simulate_positions,
};

/// Sockets of a drawn touch pool when none are given.
pub const DEFAULT_SOCKETS: usize = 5;

/// The candidates, and where they come from.
#[derive(Clone, Debug, PartialEq)]
pub struct Pool {
    /// The candidate poses.
    pub poses: Poses,
    /// Where they come from, in words, for the summary (`from pool.csv`,
    /// `drawn uniformly within …`).
    pub(crate) origin: String,
    /// Whether the rows are lines of a file (the ranking then names them).
    pub(crate) from_file: bool,
}

impl Pool {
    /// Candidates read from the file `file` (its name as the user gave it).
    pub fn from_file(poses: Poses, file: &str) -> Pool {
        Pool {
            poses,
            origin: format!("from {file}"),
            from_file: true,
        }
    }
}

/// Why no pool could be drawn.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SampleError {
    /// No candidate asked for.
    #[error("draw at least one candidate")]
    Nothing,
    /// Touch sampling with no socket.
    #[error("at least one socket")]
    NoSocket,
    /// Fewer candidates than the sockets need.
    #[error(
        "{sockets} sockets need at least {} touches ({MIN_POSES_PER_SOCKET} per socket)",
        MIN_POSES_PER_SOCKET * sockets
    )]
    TooFewForSockets {
        /// The sockets.
        sockets: usize,
    },
    /// The simulator's refusal (a setting it names, sockets it cannot
    /// place or touch).
    #[error(transparent)]
    Simulate(#[from] SimError),
}

/// `n` poses uniformly within `arm`'s joint limits (±180° where none),
/// labelled `P1…Pn`: the poses `simulate_positions` draws. `arm_file`
/// names the arm in the summary's words.
///
/// # Errors
///
/// [`SampleError::Nothing`] for `n` = 0, the simulator's.
pub fn sample_positions(
    arm: &Arm,
    n: usize,
    seed: u64,
    arm_file: &str,
) -> Result<Pool, SampleError> {
    if n == 0 {
        return Err(SampleError::Nothing);
    }
    let settings = PositionSettings {
        poses: n,
        frames: 1,
        // The instrument's readings are not used: only the poses.
        noise: Noise {
            position_mm: Some(0.0),
            ..Default::default()
        },
        seed,
    };
    let rows = simulate_positions(arm, &settings)?.positions;
    let mut poses = Poses::with_capacity(rows.joints(), rows.len());
    if let Ok(shape) = arm.params.shape() {
        poses = poses.with_shape(shape);
    }
    for i in 0..rows.len() {
        poses.push(rows.label(i), rows.reading(i), i + 2);
    }
    let limits = arm.limits.iter().filter(|l| l.is_some()).count();
    let within = match limits {
        0 => "±180° on every joint".to_string(),
        l if l == rows.joints() => format!("the joint limits of {arm_file}"),
        _ => format!("the joint limits of {arm_file} (±180° where none)"),
    };
    Ok(Pool {
        poses,
        origin: format!("drawn uniformly within {within} (seed {seed})"),
        from_file: false,
    })
}

/// About `n` touches of `sockets` (`n` rounded up to a multiple of their
/// count), each found by inverse kinematics on `arm` itself: the simulator
/// with `arm` as the true arm, no error and no noise.
///
/// # Errors
///
/// No socket, fewer than `MIN_POSES_PER_SOCKET` touches a socket, the
/// simulator's (sockets it cannot place or touch).
pub fn sample_touches(
    arm: &Arm,
    sockets: SocketPlan,
    n: usize,
    seed: u64,
) -> Result<Pool, SampleError> {
    sample_touches_observed(arm, sockets, n, seed, &mut |_| {})
}

/// [`sample_touches`], telling `progress` the fraction of the touches found
/// as it goes (a large pool takes seconds: for a progress bar). The pool is
/// the same bytes.
///
/// # Errors
///
/// As [`sample_touches`].
pub fn sample_touches_observed(
    arm: &Arm,
    sockets: SocketPlan,
    n: usize,
    seed: u64,
    progress: &mut dyn FnMut(f64),
) -> Result<Pool, SampleError> {
    let count = sockets.count();
    if count == 0 {
        return Err(SampleError::NoSocket);
    }
    let per = n.div_ceil(count);
    if per < MIN_POSES_PER_SOCKET {
        return Err(SampleError::TooFewForSockets { sockets: count });
    }
    let placed = match &sockets {
        SocketPlan::Given {
            file: Some(file), ..
        } => format!("from {file}"),
        SocketPlan::Given { file: None, .. } => "given".to_string(),
        SocketPlan::Spread { .. } => "spread over the reachable volume".to_string(),
    };
    let errors = ErrorModel::File { arm: arm.clone() };
    let mut settings = CampaignSettings::new(seed, errors, count, per);
    settings.sockets = sockets;
    settings.reference_lengths = 0;
    let campaign = simulate_observed(arm, &settings, progress)?;
    Ok(Pool {
        origin: format!(
            "{count} sockets {placed}, {per} touches each found on the arm by inverse \
             kinematics (seed {seed})"
        ),
        poses: campaign.poses,
        from_file: false,
    })
}

/// Points on about `n` / 25 spheres of `diameter_mm` (`n` rounded up to
/// a multiple of 25), placed and probed as `aacmm simulate --spheres`
/// places and probes them (ISO 10360-5's 25 directions each), found on
/// `arm` itself by inverse kinematics with its ball (none when the arm
/// file states none), without noise: labels `S1`, `S2`, ….
///
/// # Errors
///
/// [`SampleError::Nothing`] for `n` = 0; the simulator's (a diameter out
/// of range, spheres it cannot place or probe).
pub fn sample_sphere_points(
    arm: &Arm,
    n: usize,
    diameter_mm: f64,
    seed: u64,
) -> Result<Pool, SampleError> {
    if n == 0 {
        return Err(SampleError::Nothing);
    }
    let per = crate::simulate::iso_sphere_pattern().len();
    let settings = crate::simulate::SphereSettings {
        placements: n.div_ceil(per),
        diameter_mm,
        ball_diameter_mm: arm.ball_diameter_mm.unwrap_or(0.0),
        encoder_rad: 0.0,
        probe_mm: 0.0,
        seed,
    };
    let spheres = crate::simulate::simulate_spheres(arm, &settings)?.spheres;
    let poses = sphere_candidates(&spheres);
    Ok(Pool {
        origin: format!(
            "{} spheres of {diameter_mm} mm placed through the arm's volume, {per} points each \
             found on the arm by inverse kinematics (seed {seed})",
            settings.placements
        ),
        poses,
        from_file: false,
    })
}

/// Points on spheres as a plan's candidates ([`super::Measure::Spheres`]):
/// each row labelled by its sphere, with its readings and line.
pub fn sphere_candidates(rows: &Spheres) -> Poses {
    let mut poses = Poses::with_capacity(rows.joints(), rows.len());
    if let Ok(shape) = ChainShape::from_mask(rows.joints(), rows.prismatic_mask()) {
        poses = poses.with_shape(shape);
    }
    for i in 0..rows.len() {
        poses.push(
            &rows.spheres()[rows.sphere(i)],
            rows.reading(i),
            rows.line(i),
        );
    }
    poses
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::DhParams;

    /// Drawn touches are exact (no noise): every touch of a socket puts the
    /// probe at its centre, and the plan on them determines every free
    /// parameter — the analysis takes exact scale invariance for scale,
    /// not for a redundancy.
    #[test]
    fn exact_touches_make_a_determined_plan() {
        let arm = Arm::without_limits("paper", DhParams::paper_nominal());
        let spread = SocketPlan::Spread { count: 4 };
        let pool = sample_touches(&arm, spread, 80, 3).unwrap();
        assert_eq!(pool.poses.len(), 80);
        let kernel = crate::kernel::ArmKernel::new(&arm.params).unwrap();
        let centre = kernel.position(pool.poses.reading(0)).unwrap();
        for i in (0..pool.poses.len()).filter(|&i| pool.poses.label(i) == pool.poses.label(0)) {
            let p = kernel.position(pool.poses.reading(i)).unwrap();
            let d = (0..3).map(|k| (p[k] - centre[k]).powi(2)).sum::<f64>();
            assert!(d.sqrt() < 1e-8, "touch {i} {} mm off", d.sqrt());
        }
        let settings = super::super::PlanSettings::new(20, super::super::Measure::Touches);
        let plan = super::super::plan(&arm.params, &pool.poses, None, None, &settings).unwrap();
        assert!(plan.planned.is_some(), "{:?}", plan.warnings);
        assert!(plan.all.is_some());
        // 27 less base motion (2), scale (1) and the probe's redundancies (4).
        assert_eq!(plan.parameters.len(), 20, "{:?}", plan.parameters);
    }

    #[test]
    fn refusals_name_what_is_wrong() {
        let arm = Arm::without_limits("paper", DhParams::paper_nominal());
        let e = sample_touches(&arm, SocketPlan::Spread { count: 0 }, 10, 1).unwrap_err();
        assert!(matches!(e, SampleError::NoSocket), "{e}");
        let e = sample_touches(&arm, SocketPlan::Spread { count: 5 }, 10, 1).unwrap_err();
        assert_eq!(
            e.to_string(),
            "5 sockets need at least 15 touches (3 per socket)"
        );
        let e = sample_positions(&arm, 0, 1, "arm.toml").unwrap_err();
        assert!(matches!(e, SampleError::Nothing), "{e}");
        let pool = sample_positions(&arm, 7, 1, "arm.toml").unwrap();
        assert_eq!(pool.poses.len(), 7);
        assert_eq!(
            pool.origin,
            "drawn uniformly within ±180° on every joint (seed 1)"
        );
    }
}
