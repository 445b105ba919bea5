//! Simulated reference positions: a laser tracker (or several stations)
//! seeing the true arm's probe in random poses, with a known truth.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::SimError;
use super::sockets::random_configuration;
use super::truth::normal;
use crate::domain::{Arm, DEFAULT_FRAME, Positions};
use crate::kernel::{ArmKernel, PreparedPoses};
use crate::residuals::{Frame, Noise};

/// What a simulated tracker campaign measures.
#[derive(Clone, Debug, PartialEq)]
pub struct PositionSettings {
    /// Poses per frame.
    pub poses: usize,
    /// Frames (instrument stations): one is named
    /// [`crate::domain::DEFAULT_FRAME`], several `station1`, `station2`, ….
    pub frames: usize,
    /// The noise: `position_mm` (A) and `position_mm_per_m` (B) of
    /// `σ = A + B·distance` per coordinate.
    pub noise: Noise,
    /// Seed of every draw.
    pub seed: u64,
}

/// A simulated campaign: the positions and each frame's true registration.
#[derive(Clone, Debug, PartialEq)]
pub struct PositionCampaign {
    /// The rows, as a file would hold them (no uncertainty column: the
    /// noise model states it).
    pub positions: Positions,
    /// Per frame, its true `[rx, ry, rz, tx, ty, tz]` (rad, mm).
    pub frames: Vec<(String, [f64; 6])>,
}

/// The file a simulated tracker campaign writes its positions to.
pub const POSITIONS_FILE: &str = "positions.csv";

/// A true arm drawn from `errors` about `nominal` (seeded by
/// `settings.seed`) and its tracker campaign (seeded by the next seed):
/// what `aacmm simulate --positions` writes.
///
/// # Errors
///
/// As [`super::true_arm`] and [`simulate_positions`].
pub fn simulate_tracker(
    nominal: &Arm,
    errors: &super::ErrorModel,
    settings: &PositionSettings,
) -> Result<(Arm, PositionCampaign), SimError> {
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    let truth = super::true_arm(nominal, errors, &mut rng)?;
    let next = PositionSettings {
        seed: super::seeds::of(settings.seed, super::seeds::POSITIONS),
        ..settings.clone()
    };
    let campaign = simulate_positions(&truth, &next)?;
    Ok((truth, campaign))
}

/// [`simulate_tracker`] of a session recording `conditions`, the base
/// drifting by `drift` (mm/h): the true arm drawn as there, its campaign
/// as [`simulate_session`] makes it.
///
/// # Errors
///
/// As [`simulate_tracker`] and [`simulate_session`].
pub fn simulate_tracker_session(
    nominal: &Arm,
    errors: &super::ErrorModel,
    settings: &PositionSettings,
    conditions: &ConditionSettings,
    drift: Option<[f64; 3]>,
) -> Result<(Arm, PositionCampaign), SimError> {
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    let truth = super::true_arm(nominal, errors, &mut rng)?;
    let next = PositionSettings {
        seed: super::seeds::of(settings.seed, super::seeds::POSITIONS),
        ..settings.clone()
    };
    let campaign = simulate_session(&truth, &next, conditions, drift)?;
    Ok((truth, campaign))
}

/// The frames of a campaign as an arm file carries them (no σ: the truth).
pub fn true_frames(campaign: &PositionCampaign) -> Vec<crate::io::frames::FrameRecord> {
    campaign
        .frames
        .iter()
        .map(|(name, x)| crate::io::frames::FrameRecord {
            name: name.clone(),
            rotation_deg: [x[0], x[1], x[2]].map(f64::to_degrees),
            translation_mm: [x[3], x[4], x[5]],
            small_rotation_sigma_deg: None,
            translation_sigma_mm: None,
        })
        .collect()
}

/// A random frame: any orientation, 2–4 m from the arm (where a tracker
/// stands).
fn random_frame(rng: &mut ChaCha8Rng) -> [f64; 6] {
    let unit = |rng: &mut ChaCha8Rng| {
        let v = [normal(rng), normal(rng), normal(rng)];
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt().max(1e-12);
        v.map(|x| x / n)
    };
    let axis = unit(rng);
    let angle = rng.random_range(0.0..std::f64::consts::PI * 0.95);
    let dir = unit(rng);
    let distance = rng.random_range(2000.0..4000.0);
    [
        axis[0] * angle,
        axis[1] * angle,
        axis[2] * angle,
        dir[0] * distance,
        dir[1] * distance,
        dir[2] * distance,
    ]
}

/// Positions of `truth`'s probe in random poses (uniform within its joint
/// limits, or ±180°), seen from `settings.frames` random stations with the
/// noise model's σ per coordinate. Labels `P1`, `P2`, … per frame.
///
/// ```
/// use aacmm_core::{domain::Arm, params::DhParams, residuals::Noise, simulate::*};
/// let arm = Arm::without_limits("t", DhParams::paper_nominal());
/// let noise = Noise { position_mm: Some(0.015), position_mm_per_m: Some(0.006), ..Noise::default() };
/// let s = PositionSettings { poses: 50, frames: 2, noise, seed: 3 };
/// let c = simulate_positions(&arm, &s).unwrap();
/// assert_eq!((c.positions.len(), c.positions.frames().len()), (100, 2));
/// ```
///
/// # Errors
///
/// Settings without a pose, frame or stated noise; the kernel's.
pub fn simulate_positions(
    truth: &Arm,
    settings: &PositionSettings,
) -> Result<PositionCampaign, SimError> {
    let a = settings.noise.position_mm.unwrap_or(-1.0);
    let b = settings.noise.position_mm_per_m.unwrap_or(0.0);
    if settings.poses < 3 || settings.frames == 0 || !(a >= 0.0 && b >= 0.0) {
        return Err(SimError::setting(
            "positions",
            "at least 3 poses per frame, one frame, and a position noise A ≥ 0 (B ≥ 0)",
        ));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    let frames: Vec<(String, [f64; 6])> = (0..settings.frames)
        .map(|f| {
            let name = if settings.frames == 1 {
                DEFAULT_FRAME.to_string()
            } else {
                format!("station{}", f + 1)
            };
            (name, random_frame(&mut rng))
        })
        .collect();
    let positions = seen_from(truth, settings, &frames, &mut rng)?;
    Ok(PositionCampaign { positions, frames })
}

/// How a simulated 6-D target sees the tool's orientation
/// ([`orient_positions`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrientationSettings {
    /// The target's mount on the flange, the rotation vector of `R_m`
    /// (rad): the target's frame in the arm's last frame
    /// (`crate::residuals::Mount`). `[0; 3]`: mounted square.
    pub mount: [f64; 3],
    /// σ per axis of the small rotation that turns each orientation seen,
    /// rad.
    pub sigma_rad: f64,
    /// Seed of the noise (its own stream: the positions are what they
    /// were).
    pub seed: u64,
}

/// A random mount of a 6-D target, a rotation vector (rad): its axis
/// uniform on the sphere, its angle uniform in `[0, max_rad]` (seeded by
/// `seed`). `max_rad = 0` mounts it square (the identity); π, any way.
///
/// ```
/// use aacmm_core::simulate::random_mount;
/// let m = random_mount(0.5, 7);
/// let angle = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
/// assert!(angle <= 0.5 && angle > 0.0);
/// assert_eq!(random_mount(0.0, 7), [0.0; 3]);
/// ```
pub fn random_mount(max_rad: f64, seed: u64) -> [f64; 3] {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let v = [normal(&mut rng), normal(&mut rng), normal(&mut rng)];
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt().max(1e-12);
    let angle = max_rad * rng.random_range(0.0..1.0);
    v.map(|x| x / n * angle)
}

/// `positions` (rows of `truth`'s probe seen from `frames`, as
/// [`simulate_positions`] draws them) with the tool's orientation seen on
/// every row: the true target's frame (the arm's last frame turned by
/// `settings.mount`) turned into the row's frame, then by a small random
/// rotation of σ `settings.sigma_rad` per axis — a 6-D target.
///
/// # Errors
///
/// A σ that is not finite and positive, a mount that is not finite, a row
/// whose frame is not among `frames`, a true arm with corrections beyond
/// geometry (their turn of the tool is not simulated), the kernel's.
pub fn orient_positions(
    truth: &Arm,
    positions: &Positions,
    frames: &[(String, [f64; 6])],
    settings: &OrientationSettings,
) -> Result<Positions, SimError> {
    let sigma_rad = settings.sigma_rad;
    if !(sigma_rad.is_finite() && sigma_rad > 0.0) {
        return Err(SimError::setting(
            "orientation",
            "an orientation noise σ > 0 (a tracker's 6-D target: about 0.01°)",
        ));
    }
    if !settings.mount.iter().all(|v| v.is_finite()) {
        return Err(SimError::setting("orientation", "a finite mount"));
    }
    if truth.physics.corrects() {
        return Err(SimError::setting(
            "orientation",
            "orientations of a true arm with corrections beyond geometry are not simulated",
        ));
    }
    let model = |e: String| SimError::Model(e);
    let kernel = ArmKernel::new(&truth.params).map_err(|e| model(e.to_string()))?;
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    let mut mount = [0.0; 6];
    mount[..3].copy_from_slice(&settings.mount);
    let mut seen = Vec::with_capacity(positions.len());
    for i in 0..positions.len() {
        let name = &positions.frames()[positions.frame(i)];
        let Some((_, x)) = frames.iter().find(|(f, _)| f == name) else {
            return Err(model(format!(
                "row {} is in frame {name}, not simulated",
                i + 1
            )));
        };
        let tool = kernel
            .pose(positions.reading(i))
            .map_err(|e| model(e.to_string()))?;
        // The target's frame, `R_t R_m`: the mount turns it on the right.
        let mut target = tool;
        let r = Frame::rotation(&mount);
        target.rotation = std::array::from_fn(|a| {
            std::array::from_fn(|b| (0..3).map(|k| tool.rotation[a][k] * r[(k, b)]).sum())
        });
        let turned = Frame::apply_pose(x, &target);
        // The seen frame: the true one turned by a small rotation `n`.
        let noise = [0; 3].map(|_| sigma_rad * normal(&mut rng));
        let mut turn = [0.0; 6];
        turn[..3].copy_from_slice(&noise);
        seen.push(Some(Frame::apply_pose(&turn, &turned).quaternion()));
    }
    Ok(positions.clone().with_orientations(seen))
}

/// [`simulate_positions`] of a session recording `conditions`, the base
/// drifting by `drift` (mm/h): the stations drawn as there, the rows as in
/// [`simulate_positions_in`].
///
/// # Errors
///
/// As [`simulate_positions_in`].
pub fn simulate_session(
    truth: &Arm,
    settings: &PositionSettings,
    conditions: &ConditionSettings,
    drift: Option<[f64; 3]>,
) -> Result<PositionCampaign, SimError> {
    let stations = simulate_positions(
        &Arm {
            physics: Box::default(),
            ..truth.clone()
        },
        &PositionSettings {
            poses: 3,
            ..settings.clone()
        },
    )?;
    let positions = simulate_positions_in(truth, settings, &stations.frames, conditions, drift)?;
    Ok(PositionCampaign {
        positions,
        frames: stations.frames,
    })
}

/// Positions of `truth`'s probe in `settings.poses` random poses per frame,
/// seen from the given `frames` (`[rx, ry, rz, tx, ty, tz]`, rad, mm) with
/// the noise model of `settings` (its frame count is not used): new poses
/// from stations already placed, for held-out data.
///
/// # Errors
///
/// As [`simulate_positions`].
pub fn simulate_positions_from(
    truth: &Arm,
    settings: &PositionSettings,
    frames: &[(String, [f64; 6])],
) -> Result<Positions, SimError> {
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    seen_from(truth, settings, frames, &mut rng)
}

/// What a simulated session records beside each pose: its temperature,
/// time and the direction each joint approached it from. Default: none.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ConditionSettings {
    /// Temperatures drawn uniformly in `[low, high]`, °C.
    pub temperature_c: Option<[f64; 2]>,
    /// Rows taken one after another, evenly over this many hours.
    pub session_h: Option<f64>,
    /// Each joint approaches each pose from a random side (`+` or `-`,
    /// even odds), written as the `approach` column: a true arm's
    /// backlash rests on that flank, whatever the gravity torque.
    pub approach: bool,
}

/// [`simulate_positions_from`] of a session recording `conditions`: the
/// true arm's corrections beyond geometry (its [`Arm::physics`]: compliance,
/// harmonics, expansion) act on every row, and the rows carry their
/// temperature and time columns. `drift` (mm/h) moves the base against
/// the instrument over the session.
///
/// # Errors
///
/// As [`simulate_positions`]; an expansion without temperatures, a drift
/// without a session time.
pub fn simulate_positions_in(
    truth: &Arm,
    settings: &PositionSettings,
    frames: &[(String, [f64; 6])],
    conditions: &ConditionSettings,
    drift: Option<[f64; 3]>,
) -> Result<Positions, SimError> {
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    let mut physics = truth.physics.clone();
    physics.drift_mm_per_h = drift;
    draw_rows(truth, &physics, settings, frames, conditions, &mut rng)
}

fn seen_from(
    truth: &Arm,
    settings: &PositionSettings,
    frames: &[(String, [f64; 6])],
    rng: &mut ChaCha8Rng,
) -> Result<Positions, SimError> {
    let conditions = ConditionSettings::default();
    draw_rows(truth, &truth.physics, settings, frames, &conditions, rng)
}

/// Random poses per frame, each seen through the true arm's `physics`
/// under its drawn conditions, with the noise of `settings`.
fn draw_rows(
    truth: &Arm,
    physics: &crate::corrections::Physics,
    settings: &PositionSettings,
    frames: &[(String, [f64; 6])],
    conditions: &ConditionSettings,
    rng: &mut ChaCha8Rng,
) -> Result<Positions, SimError> {
    let a = settings.noise.position_mm.unwrap_or(-1.0);
    let b = settings.noise.position_mm_per_m.unwrap_or(0.0);
    let n = truth.params.joint_count();
    super::check_strokes(truth)?;
    let mut limits = truth.limits.clone();
    limits.resize(n, None);
    let model = |e: String| SimError::Model(e);
    let kernel = ArmKernel::new(&truth.params).map_err(|e| model(e.to_string()))?;
    let rows = frames.len() * settings.poses;
    let none = crate::corrections::Beyond::default();
    // The drift is the session's, from its first row: added per row below
    // (one row's own time would be its origin).
    let still = crate::corrections::Physics {
        drift_mm_per_h: None,
        ..physics.clone()
    };
    let mut positions = Positions::new(n).with_shape(kernel.shape());
    // Row by row — the pose, its conditions, the noise — so that a session
    // without conditions draws what it always drew.
    for (f, (name, x)) in frames.iter().enumerate() {
        for i in 0..settings.poses {
            let r = f * settings.poses + i;
            let q = random_configuration(&limits, rng);
            let temperature = conditions
                .temperature_c
                .map(|[lo, hi]| rng.random_range(lo..=hi));
            let time = (conditions.session_h)
                .map(|h| 3600.0 * h * r as f64 / rows.saturating_sub(1).max(1) as f64);
            let approach: Option<Vec<i8>> = (conditions.approach).then(|| {
                (0..n)
                    .map(|_| if rng.random_bool(0.5) { 1 } else { -1 })
                    .collect()
            });
            let p = if physics.corrects() {
                let recorded = crate::corrections::Conditions {
                    temperature_c: temperature.as_ref().map(std::slice::from_ref),
                    time_s: None,
                    approach: approach.as_deref(),
                };
                let seen = crate::corrections::Effects::new(
                    &truth.params,
                    &still,
                    &none,
                    &PreparedPoses::from_flat_with(n, kernel.shape().prismatic_mask(), 1, &q),
                    recorded,
                )
                .map_err(model)?;
                let mut p = [[0.0; 3]];
                kernel
                    .positions(&seen.poses, 0..1, &mut p)
                    .map_err(|e| model(e.to_string()))?;
                let hours = time.unwrap_or(0.0) / 3600.0;
                let v = physics.drift_mm_per_h.unwrap_or([0.0; 3]);
                std::array::from_fn(|k| p[0][k] + v[k] * hours)
            } else {
                kernel.position(&q).map_err(|e| model(e.to_string()))?
            };
            let y = Frame::apply(x, p);
            let distance = (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt() / 1000.0;
            let sigma = a + b * distance;
            let noisy = y.map(|v| v + sigma * normal(rng));
            positions.push(&format!("P{}", i + 1), name, &q, noisy, None, 0);
            positions.record(temperature, time);
            positions.record_approach(approach.as_deref());
        }
    }
    Ok(positions)
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn simulate_positions_orient_positions() {
        use crate::{domain::Arm, params::DhParams, residuals::Noise, simulate::*};
        let arm = Arm::without_limits("t", DhParams::paper_nominal());
        let noise = Noise {
            position_mm: Some(0.015),
            ..Noise::default()
        };
        let s = PositionSettings {
            poses: 5,
            frames: 1,
            noise,
            seed: 3,
        };
        let c = simulate_positions(&arm, &s).unwrap();
        let o = OrientationSettings {
            mount: [0.0, 0.0, 1.0],
            sigma_rad: 1e-4,
            seed: 4,
        };
        let p = orient_positions(&arm, &c.positions, &c.frames, &o).unwrap();
        assert_eq!(
            (p.oriented_rows(), p.position(2)),
            (5, c.positions.position(2))
        );
    }
}
