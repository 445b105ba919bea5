//! The campaign simulator: a known true arm touches sockets in many
//! articulations, and the encoders record what a real campaign would give.
//!
//! 1. **True arm** ([`true_arm`]): the nominal plus the paper's Table 2
//!    errors, random errors (optionally with zero offsets anywhere in ±180°:
//!    a newly assembled arm), or a given arm.
//! 2. **Sockets** ([`place_sockets`]): spread over the true arm's
//!    comfortable volume (near/middle/far from the base axis, well apart), or
//!    given.
//! 3. **Touches**: for each socket, `N` articulations by
//!    inverse kinematics on the true arm ([`solve_point`], Levenberg–Marquardt
//!    on the kernel's joint Jacobian) from random starts, within joint limits,
//!    each at least [`CampaignSettings::min_pose_separation_deg`] from the
//!    others in some joint. The probe seats at the socket centre plus
//!    Gaussian noise; the encoders read the true angles plus Gaussian noise.
//! 4. **Reference lengths** ([`reference_lengths`]): true distances between
//!    distinct socket pairs, optionally with their own noise and uncertainty.
//!
//! With zero noise, the true arm puts the probe centre on each socket centre
//! to within 1e-9 mm at every recorded pose.
//!
//! **Determinism.** Every draw comes from a ChaCha8 generator seeded with
//! [`CampaignSettings::seed`], one stream per purpose (true arm, sockets,
//! seating, IK starts, encoders, lengths), each used in a fixed
//! order. The same settings give the same bytes (same build and platform);
//! and changing one purpose's setting does not change the others' draws, so
//! e.g. the same seed with more encoder noise gives the same true arm and
//! sockets.
//!
//! ```
//! use aacmm_core::{domain::Arm, kernel, params::DhParams, simulate::*};
//! let nominal = Arm::without_limits("nominal", DhParams::paper_nominal());
//! let settings = CampaignSettings::new(42, ErrorModel::Paper, 3, 4);
//! let c = simulate(&nominal, &settings).unwrap();
//! assert_eq!(c.poses.len(), 12);
//! assert_eq!(c.poses.label(4), "S2");
//! // Zero noise: the true arm reproduces the socket at every pose.
//! let rows: Vec<&[f64]> = c.poses.rows().collect();
//! let p = kernel::ArmKernel::new(&c.true_arm.params).unwrap().positions_of(&rows).unwrap();
//! let s2 = c.sockets[1].1;
//! assert!((0..3).all(|i| (p[4][i] - s2[i]).abs() < 1e-9));
//! ```

mod acceptance;
mod chain;
mod error;
mod files;
mod ik;
mod lengths;
mod positions;
mod separation;
mod settings;
mod sockets;
mod spheres;
mod tools;
mod touches;
mod truth;

#[cfg(test)]
mod tests;

/// The seeds the parts of a campaign draw from, as offsets added to the
/// user's seed (`aacmm simulate --seed`): each part its own generator, so
/// that adding a part to a campaign changes nothing else of it, and no two
/// parts share draws. The numbers are part of the output format: changing
/// one changes every file made with that seed.
pub mod seeds {
    /// A tracker's positions (the true arm draws from the seed itself).
    pub const POSITIONS: u64 = 1;
    /// The noise of a 6-D target's orientations.
    pub const ORIENTATIONS: u64 = 2;
    /// The 6-D target's mount on the flange.
    pub const MOUNT: u64 = 3;
    /// The markers `--tools` places on the flange.
    pub const MARKERS: u64 = 4;
    /// The markers' true offsets about their nominal ones.
    pub const MARKER_ERRORS: u64 = 5;
    /// Which markers each pose sees, and their noise.
    pub const MARKER_NOISE: u64 = 6;
    /// The points on reference spheres.
    pub const SPHERES: u64 = 7;
    /// The acceptance tests' placements (`L_Dia`, the ball bar).
    pub const ACCEPTANCE: u64 = 8;
    /// The placements each `[[tool]]` stylus probes (`--sphere-tools`).
    pub const SPHERE_TOOLS: u64 = 9;

    /// The seed of the part `offset` (one of the above) of a campaign
    /// seeded by `seed`.
    pub fn of(seed: u64, offset: u64) -> u64 {
        seed.wrapping_add(offset)
    }

    #[cfg(test)]
    mod tests {
        /// No two parts share a generator, nor the true arm's (offset 0).
        #[test]
        fn every_part_has_its_own_seed() {
            use super::*;
            let all = [
                0,
                POSITIONS,
                ORIENTATIONS,
                MOUNT,
                MARKERS,
                MARKER_ERRORS,
                MARKER_NOISE,
                SPHERES,
                ACCEPTANCE,
            ];
            let mut sorted = all.to_vec();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), all.len(), "{all:?}");
        }
    }
}

pub use crate::params::wrap;
pub use acceptance::{
    AcceptanceCampaign, AcceptanceSettings, BAR_LENGTHS_FILE, DEFAULT_BAR_LENGTH_MM,
    with_acceptance,
};
pub use chain::random_arm;
pub use error::SimError;
pub use files::{
    CAMPAIGN_FILE, LENGTHS_FILE, POSES_FILE, SOCKETS_FILE, TRUE_ARM_FILE, parse_campaign,
    read_campaign, write_campaign,
};
pub use ik::{IkSolution, solve_point};
pub use lengths::reference_lengths;
pub use positions::{
    ConditionSettings, OrientationSettings, POSITIONS_FILE, PositionCampaign, PositionSettings,
    orient_positions, random_mount, simulate_positions, simulate_positions_from,
    simulate_positions_in, simulate_session, simulate_tracker, simulate_tracker_session,
    true_frames,
};
pub(crate) use settings::MIN_POSES_PER_SOCKET;
pub use settings::{
    CampaignSettings, DEFAULT_LENGTH_SIGMA_MM, DEFAULT_TWIST_SIGMA_DEG, DEFAULT_ZERO_SIGMA_DEG,
    ErrorModel, SocketPlan, SocketPoint, pair_count,
};
use sockets::round_nm;
pub use sockets::{place_sockets, shoulder};
pub(crate) use spheres::iso_sphere_pattern;
pub use spheres::{
    DEFAULT_SPHERE_DIAMETER_MM, SPHERES_FILE, SphereCampaign, SphereSettings,
    simulate_sphere_campaign, simulate_spheres, with_tool_placements,
};
pub use tools::{perturbed_tools, random_tools, seen_at_markers};
pub use touches::Touch;
use touches::{TouchPlan, find_touches};
pub use truth::true_arm;

use crate::dataset::DataSet;
use crate::domain::{Arm, Poses, ReferenceLength};
use crate::error::InputError;
use crate::io::AngleUnit;
use crate::kernel::ArmKernel;

pub(crate) use crate::random::{rng, streams};

/// Counts of the touch search, for summaries.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SimStats {
    /// Inverse-kinematics starts tried.
    pub ik_starts: usize,
    /// Iterations over all starts.
    pub(crate) ik_iterations: usize,
    /// Starts that did not converge.
    pub not_converged: usize,
    /// Converged solutions outside the joint limits.
    pub outside_limits: usize,
    /// Converged solutions too close to an earlier touch of the socket.
    pub too_close: usize,
    /// Largest distance between the true arm's probe centre at a touch's
    /// true readings (through the true arm's corrections: harmonics,
    /// compliance) and the point touched, mm.
    pub max_residual_mm: f64,
}

/// A simulated campaign.
#[derive(Clone, Debug, PartialEq)]
pub struct Campaign {
    /// The nominal arm (what a calibration starts from).
    pub nominal: Arm,
    /// The true arm (what a calibration should find).
    pub true_arm: Arm,
    /// True socket centres, mm, in order (`S1..SK` unless given).
    pub sockets: Vec<(String, [f64; 3])>,
    /// Every touch: the point seated and the true readings.
    pub touches: Vec<Touch>,
    /// What the encoders read, rad, one row per touch, labelled by socket —
    /// the true readings plus encoder noise, wrapped to `[-π, π)` for joints
    /// without limits, and rounded to values that `poses.csv` (degrees)
    /// holds exactly.
    pub poses: Poses,
    /// Reference lengths between sockets.
    pub lengths: Vec<ReferenceLength>,
    /// Counts of the touch search.
    pub stats: SimStats,
}

/// Largest probe seating noise, as a fraction of the arm's reach: beyond it
/// the seated points scatter out of the workspace, and inverse kinematics
/// would blame the sockets.
pub(crate) const MAX_PROBE_NOISE_OF_REACH: f64 = 0.01;

/// Refuses a probe seating noise that is no seating noise (see
/// [`MAX_PROBE_NOISE_OF_REACH`]), naming the setting.
fn check_probe_noise(nominal: &Arm, sigma_mm: f64) -> Result<(), SimError> {
    let reach = nominal.params.reach();
    let max = MAX_PROBE_NOISE_OF_REACH * reach;
    if sigma_mm > max {
        return Err(SimError::setting(
            "probe_noise_mm",
            format!(
                "σ = {} mm is more than {}% of the arm's reach ({reach:.0} mm), at most {max:.1} mm: \
                 the ball would be seated that far from its socket, out of the workspace \
                 (a real seating noise is 0.001–0.05 mm)",
                crate::error::short(sigma_mm),
                MAX_PROBE_NOISE_OF_REACH * 100.0
            ),
        ));
    }
    Ok(())
}

/// Simulates a campaign of `settings` on `nominal` (any chain of 1 to 12
/// joints; a prismatic joint needs its stroke, `limits`). Errors,
/// never panics, on bad settings or an impossible campaign.
///
/// ```
/// use aacmm_core::{domain::Arm, params::DhParams, simulate::*};
/// let nominal = Arm::without_limits("n", DhParams::paper_nominal());
/// let bad = CampaignSettings::new(1, ErrorModel::Paper, 0, 10);
/// let e = simulate(&nominal, &bad).unwrap_err();
/// assert_eq!(e.to_string(), "setting `sockets`: at least one socket is needed");
/// ```
pub fn simulate(nominal: &Arm, settings: &CampaignSettings) -> Result<Campaign, SimError> {
    simulate_observed(nominal, settings, &mut |_| {})
}

/// [`simulate`], telling `progress` the fraction of the sockets whose
/// touches were found, as it goes (a large campaign takes seconds: for a
/// progress bar). The campaign is the same bytes.
///
/// # Errors
///
/// As [`simulate`].
pub fn simulate_observed(
    nominal: &Arm,
    settings: &CampaignSettings,
    progress: &mut dyn FnMut(f64),
) -> Result<Campaign, SimError> {
    let n = nominal.params.joint_count();
    check_limits(nominal)?;
    settings.validate(n)?;
    check_probe_noise(nominal, settings.probe_noise_mm)?;
    ArmKernel::new(&nominal.params)?;
    let seed = settings.seed;
    let true_arm = true_arm(nominal, &settings.errors, &mut rng(seed, streams::TRUE_ARM))?;
    check_limits(&true_arm)?;
    let sockets = match &settings.sockets {
        SocketPlan::Spread { count } => {
            place_sockets(&true_arm, *count, &mut rng(seed, streams::SOCKETS))?
        }
        SocketPlan::Given { points, .. } => points
            .iter()
            .map(|p| (p.label.clone(), [p.x, p.y, p.z].map(round_nm)))
            .collect(),
    };
    let plan = TouchPlan {
        poses: settings.poses_per_socket,
        probe_noise_mm: settings.probe_noise_mm,
        min_separation: settings.min_pose_separation_deg.to_radians(),
        starts_per_pose: settings.starts_per_pose,
    };
    let mut stats = SimStats::default();
    let touches = find_touches(
        &true_arm,
        &sockets,
        &plan,
        &mut rng(seed, streams::SEATING),
        &mut rng(seed, streams::IK_STARTS),
        &mut stats,
        progress,
    )?;

    let k = ArmKernel::new(&true_arm.params)?;
    let mut enc = rng(seed, streams::ENCODERS);
    let sigma = settings.encoder_noise_deg.to_radians();
    let shape = k.shape();
    let mut poses = Poses::with_capacity(n, touches.len()).with_shape(shape);
    let mut q = Vec::with_capacity(n);
    let corrects = true_arm.physics.corrects();
    for (i, t) in touches.iter().enumerate() {
        // What was simulated: the readings through the true arm's own
        // corrections (harmonics, compliance), as the chain sees them.
        let p = if corrects {
            k.position(&crate::corrections::angles_for(
                &true_arm.params,
                &true_arm.physics,
                &t.q,
            ))?
        } else {
            k.position(&t.q)?
        };
        let r = (0..3)
            .map(|i| (p[i] - t.point[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        stats.max_residual_mm = stats.max_residual_mm.max(r);
        q.clear();
        q.extend(
            (t.q.iter().zip(&true_arm.limits).enumerate()).map(|(j, (&x, lim))| {
                if shape.is_prismatic(j) {
                    // A slide's scale: mm, written as they are.
                    return x + SLIDE_NOISE_MM * truth::normal(&mut enc);
                }
                let read = x + sigma * truth::normal(&mut enc);
                exact_in_degrees(if lim.is_some() { read } else { wrap(read) })
            }),
        );
        poses.push(&sockets[t.socket].0, &q, i + 2);
    }
    let lengths = reference_lengths(
        &sockets,
        settings.reference_lengths,
        settings.length_uncertainty_mm,
        &mut rng(seed, streams::LENGTHS),
    )?;
    Ok(Campaign {
        nominal: nominal.clone(),
        true_arm,
        sockets,
        touches,
        poses,
        lengths,
        stats,
    })
}

impl Campaign {
    /// The campaign as the data set a calibration reads: touches grouped by
    /// socket, reference lengths, and the source named as the campaign's
    /// files ([`POSES_FILE`], [`LENGTHS_FILE`]) with their lines.
    ///
    /// ```
    /// use aacmm_core::{domain::Arm, params::DhParams, simulate::*};
    /// let nominal = Arm::without_limits("nominal", DhParams::paper_nominal());
    /// let mut settings = CampaignSettings::new(3, ErrorModel::Paper, 3, 4);
    /// settings.reference_lengths = 2;
    /// let data = simulate(&nominal, &settings).unwrap().data_set().unwrap();
    /// assert_eq!((data.points().len(), data.len(), data.references().len()), (3, 12, 2));
    /// assert_eq!(data.source().touch(4).to_string(), "poses.csv:6");
    /// ```
    pub fn data_set(&self) -> Result<DataSet, InputError> {
        DataSet::from_poses(&self.poses, POSES_FILE)?.with_lengths(&self.lengths, LENGTHS_FILE)
    }
}

/// The nearest angle (rad) that a degree value in `poses.csv` reads back to
/// exactly.
fn exact_in_degrees(x: f64) -> f64 {
    AngleUnit::Deg.to_internal(AngleUnit::Deg.from_internal_exact(x))
}

/// σ of a prismatic joint's reading (its linear scale), mm: a glass or
/// magnetic scale's noise; the simulator's only noise on a slide.
pub const SLIDE_NOISE_MM: f64 = 1e-3;

/// Joint limits must be finite with `min < max`; a prismatic joint must
/// have them ([`check_strokes`]).
fn check_limits(arm: &Arm) -> Result<(), SimError> {
    check_strokes(arm)?;
    for (j, lim) in arm.limits.iter().enumerate() {
        if let Some([lo, hi]) = lim
            && !(lo.is_finite() && hi.is_finite() && lo < hi)
        {
            return Err(SimError::Model(format!(
                "arm {}, joint {}: limits [{lo}, {hi}] (rad; mm for a prismatic joint) must be \
                 finite with min < max",
                crate::error::quoted(&arm.name),
                j + 1
            )));
        }
    }
    Ok(())
}

/// A prismatic joint must have limits: its stroke, where the simulator
/// draws its positions.
pub(crate) fn check_strokes(arm: &Arm) -> Result<(), SimError> {
    // A chain of no shape (too many joints) is the kernel's to refuse.
    let Ok(shape) = arm.params.shape() else {
        return Ok(());
    };
    let missing = (0..shape.joints())
        .find(|&j| shape.is_prismatic(j) && !matches!(arm.limits.get(j), Some(Some(_))));
    match missing {
        Some(j) => Err(SimError::Model(format!(
            "arm {}, joint {}: a prismatic joint needs its stroke (`limits`, in the arm file's \
             length unit) for the simulator to draw its positions",
            crate::error::quoted(&arm.name),
            j + 1
        ))),
        None => Ok(()),
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn simulate_seeds_of() {
        use crate::simulate::seeds;
        assert_eq!(seeds::of(u64::MAX, seeds::POSITIONS), 0);
    }
}
