//! Simulated sphere-surface points: reference spheres placed through the
//! arm's volume, each probed at ISO 10360-5's 25 points by the true arm.
//!
//! A placement's centre is a ball radius plus the sphere's radius below
//! the probe centre of a random configuration (within the joint limits),
//! so that the pattern's pole is reachable from it. The pattern: one point
//! at the pole, 4 at 22.5° below it, 8 at 45°, 4 at 67.5°, 8 on the equator,
//! each ring turned 22.5° from the one above; the pole's direction is drawn
//! within about 35° of straight up (the reachable, upper hemisphere: a
//! sphere stands on a table). Each point is where the true arm's ball
//! touches the surface, its centre `(R + r_ball)` from the sphere's centre
//! along the normal, moved by the probe's seating noise (σ per axis); the
//! readings are the true arm's inverse kinematics of it, from the
//! placement's configuration turned by about 17° per joint (so the wrist
//! varies between points, as a user's does), plus the encoders' noise. A
//! point whose inverse kinematics does not converge is drawn again from
//! another start.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::SimError;
use super::ik::solve_point;
use super::sockets::random_configuration;
use super::truth::normal;
use crate::domain::{Arm, Spheres};
use crate::kernel::ArmKernel;

/// The file a simulated sphere campaign writes its points to.
pub const SPHERES_FILE: &str = "spheres.csv";

/// The sphere diameter `simulate --spheres` uses unless told, mm (1 in).
pub const DEFAULT_SPHERE_DIAMETER_MM: f64 = 25.4;

/// What a simulated sphere campaign probes.
#[derive(Clone, Debug, PartialEq)]
pub struct SphereSettings {
    /// Sphere placements (`S1`, `S2`, …), 25 points each.
    pub placements: usize,
    /// The spheres' diameter, mm.
    pub diameter_mm: f64,
    /// The probe ball's diameter, mm.
    pub ball_diameter_mm: f64,
    /// σ of each encoder reading, rad.
    pub encoder_rad: f64,
    /// σ of the probe's seating per axis, mm.
    pub probe_mm: f64,
    /// Seed of every draw.
    pub seed: u64,
}

/// A simulated sphere campaign: the points, and each placement's true
/// centre.
#[derive(Clone, Debug, PartialEq)]
pub struct SphereCampaign {
    /// The rows, as a file holds them.
    pub spheres: Spheres,
    /// Per placement, its label and true centre (mm).
    pub centres: Vec<(String, [f64; 3])>,
}

/// ISO 10360-5's 25 directions about the pole `+z`: the pole, 4 at 22.5°
/// from it, 8 at 45°, 4 at 67.5°, 8 on the equator, each ring turned 22.5°
/// from the one above.
pub(crate) fn iso_sphere_pattern() -> Vec<[f64; 3]> {
    let rings: [(f64, usize); 4] = [(22.5, 4), (45.0, 8), (67.5, 4), (90.0, 8)];
    let mut out = vec![[0.0, 0.0, 1.0]];
    for (k, &(polar, count)) in rings.iter().enumerate() {
        let polar = polar.to_radians();
        let turn = 22.5 * (k as f64 + 1.0);
        for j in 0..count {
            let a = (turn + 360.0 * j as f64 / count as f64).to_radians();
            let z = if k == 3 { 0.0 } else { polar.cos() };
            out.push([polar.sin() * a.cos(), polar.sin() * a.sin(), z]);
        }
    }
    out
}

/// The pattern turned so that its pole points along the unit vector `pole`.
pub(super) fn turned(pattern: &[[f64; 3]], pole: [f64; 3]) -> Vec<[f64; 3]> {
    let z = nalgebra::Vector3::new(0.0, 0.0, 1.0);
    let to = nalgebra::Unit::new_normalize(nalgebra::Vector3::from(pole));
    let r = nalgebra::Rotation3::rotation_between(&z, &to)
        .unwrap_or_else(|| nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::x_axis(), 0.0));
    (pattern.iter())
        .map(|d| (r * nalgebra::Vector3::from(*d)).into())
        .collect()
}

/// σ of the turn of each revolute joint from the placement's configuration
/// where the inverse kinematics of a point starts, rad: a user probing a
/// sphere turns the wrist and elbow between points.
const SPREAD_RAD: f64 = 1.0;

/// Tries per point before a placement is given up.
const STARTS_PER_POINT: usize = 20;

/// The sphere campaign of `settings` by the arm `truth`.
///
/// # Errors
///
/// A setting out of range (no placement, a diameter not positive), the
/// kernel's, and a placement whose points the arm cannot reach.
pub fn simulate_spheres(
    truth: &Arm,
    settings: &SphereSettings,
) -> Result<SphereCampaign, SimError> {
    if settings.placements == 0 {
        return Err(SimError::setting("spheres", "at least one placement"));
    }
    if !(settings.diameter_mm > 0.0 && settings.ball_diameter_mm >= 0.0) {
        return Err(SimError::setting(
            "sphere_diameter",
            "the sphere's diameter is positive, the ball's not negative (mm)",
        ));
    }
    let n = truth.params.joint_count();
    let kernel = ArmKernel::new(&truth.params)?;
    let shape = kernel.shape();
    let mut limits = truth.limits.clone();
    limits.resize(n, None);
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    let offset = (settings.diameter_mm + settings.ball_diameter_mm) / 2.0;
    let pattern = iso_sphere_pattern();
    let mut spheres = Spheres::new(n, shape.prismatic_mask());
    let mut centres = Vec::new();
    let mut line = 2;
    for s in 0..settings.placements {
        let name = format!("S{}", s + 1);
        let (c, rows) = place(&kernel, &limits, (offset, &pattern), settings, &mut rng)?;
        for read in rows {
            spheres.push(&name, &read, line, None);
            line += 1;
        }
        centres.push((name, c));
    }
    Ok(SphereCampaign { spheres, centres })
}

/// `spheres` (a campaign's rows) with `placements` more probed by each of
/// `truth`'s `[[tool]]` styli, at its true offset and with its ball (the
/// probe's when it states none): `S1.NAME`, `S2.NAME`, …, each row naming
/// its tool, each tool's placements drawn from a stream of its own (the
/// seed's [`super::seeds::SPHERE_TOOLS`] part, and the tool's place among
/// the arm's). The rows before keep their bytes; the new ones get an
/// articulation `1` when the rows before have the column. Returns every
/// row and the new placements' true centres.
///
/// # Errors
///
/// An arm without `[[tool]]`; as [`simulate_spheres`].
pub fn with_tool_placements(
    truth: &Arm,
    mut spheres: Spheres,
    settings: &SphereSettings,
) -> Result<SphereCampaign, SimError> {
    if truth.tools.is_empty() {
        return Err(SimError::setting(
            "sphere_tools",
            "an arm whose file lists styli as [[tool]] (with their ball_diameter_mm)",
        ));
    }
    let articulated = spheres.articulation(0).map(|_| 1);
    let base = super::seeds::of(settings.seed, super::seeds::SPHERE_TOOLS);
    let mut centres = Vec::new();
    for (k, tool) in truth.tools.iter().enumerate() {
        let seen = crate::domain::arm_with_tool(truth, &tool.name)
            .map_err(|e| SimError::Model(e.to_string()))?;
        let own = SphereSettings {
            ball_diameter_mm: tool.ball_diameter_mm.unwrap_or(settings.ball_diameter_mm),
            seed: base.wrapping_add((k as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15)),
            ..settings.clone()
        };
        let drawn = simulate_spheres(&seen, &own)?;
        let rows = &drawn.spheres;
        for i in 0..rows.len() {
            let name = format!("{}.{}", rows.spheres()[rows.sphere(i)], tool.name);
            let line = spheres.len() + 2;
            spheres.push(&name, rows.reading(i), line, articulated);
            spheres.set_tool(tool);
        }
        centres.extend((drawn.centres.into_iter()).map(|(n, c)| (format!("{n}.{}", tool.name), c)));
    }
    Ok(SphereCampaign { spheres, centres })
}

/// Draws of a placement before the campaign is given up.
const DRAWS_PER_PLACEMENT: usize = 50;

/// One placement whose every point the arm reaches: its centre and the
/// readings of its points (a placement with a point out of reach, near the
/// edge of the volume, is drawn again).
fn place(
    kernel: &ArmKernel,
    limits: &[Option<[f64; 2]>],
    (offset, pattern): (f64, &[[f64; 3]]),
    settings: &SphereSettings,
    rng: &mut ChaCha8Rng,
) -> Result<([f64; 3], Vec<Vec<f64>>), SimError> {
    let shape = kernel.shape();
    'draw: for _ in 0..DRAWS_PER_PLACEMENT {
        let q0 = random_configuration(limits, rng);
        let tilt = [0.6 * normal(rng), 0.6 * normal(rng), 1.0];
        let norm = (tilt[0] * tilt[0] + tilt[1] * tilt[1] + 1.0).sqrt();
        let pole = tilt.map(|v| v / norm);
        let top = kernel.position(&q0)?;
        let c = std::array::from_fn(|k| top[k] - offset * pole[k]);
        let mut rows = Vec::with_capacity(pattern.len());
        for d in turned(pattern, pole) {
            let target: [f64; 3] =
                std::array::from_fn(|k| c[k] + offset * d[k] + settings.probe_mm * normal(rng));
            let Some(q) = reach(kernel, target, &q0, rng)? else {
                continue 'draw;
            };
            rows.push(
                (q.iter().enumerate())
                    .map(|(j, v)| match shape.is_prismatic(j) {
                        true => *v,
                        false => v + settings.encoder_rad * normal(rng),
                    })
                    .collect(),
            );
        }
        return Ok((c, rows));
    }
    Err(SimError::Model(format!(
        "no placement of a {} mm sphere whose 25 points the arm reaches in {DRAWS_PER_PLACEMENT} \
         draws",
        settings.diameter_mm
    )))
}

/// The readings that put `kernel`'s probe centre at `target`, from `q0`
/// turned by about 0.3 rad per revolute joint (another draw while the
/// inverse kinematics does not converge); `None` when none does.
fn reach(
    kernel: &ArmKernel,
    target: [f64; 3],
    q0: &[f64],
    rng: &mut ChaCha8Rng,
) -> Result<Option<Vec<f64>>, SimError> {
    let shape = kernel.shape();
    for _ in 0..STARTS_PER_POINT {
        let start: Vec<f64> = (q0.iter().enumerate())
            .map(|(j, v)| match shape.is_prismatic(j) {
                true => *v,
                false => v + SPREAD_RAD * normal(rng),
            })
            .collect();
        let found = solve_point(kernel, target, &start)?;
        if found.converged() {
            return Ok(Some(found.q));
        }
    }
    Ok(None)
}

/// A true arm drawn from `errors` about `nominal` (seeded by
/// `settings.seed`, as [`super::simulate_tracker`] draws it) and its sphere
/// campaign (seeded by [`super::seeds::SPHERES`]): what `aacmm simulate
/// --spheres` writes without sockets or positions.
///
/// # Errors
///
/// As [`super::true_arm`] and [`simulate_spheres`].
pub fn simulate_sphere_campaign(
    nominal: &Arm,
    errors: &super::ErrorModel,
    settings: &SphereSettings,
) -> Result<(Arm, SphereCampaign), SimError> {
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    let truth = super::true_arm(nominal, errors, &mut rng)?;
    let campaign = simulate_spheres(&truth, &settings.for_campaign())?;
    Ok((truth, campaign))
}

impl SphereSettings {
    /// The settings of the points' own stream ([`super::seeds::SPHERES`]),
    /// so that adding spheres to a campaign changes nothing else of it, and
    /// no draw of theirs is one of another part's.
    pub fn for_campaign(&self) -> SphereSettings {
        SphereSettings {
            seed: super::seeds::of(self.seed, super::seeds::SPHERES),
            ..self.clone()
        }
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn simulate_spheres_iso_sphere_pattern() {
        let d = crate::simulate::iso_sphere_pattern();
        assert_eq!(d.len(), 25);
        assert_eq!(d[0], [0.0, 0.0, 1.0]);
        assert!(d[24][2].abs() < 1e-12); // the last on the equator
    }
}
