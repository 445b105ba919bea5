//! Simulated placements for the acceptance tests beyond the probing
//! spheres (`simulate --spheres N --articulated A --ball-bar B`):
//!
//! - **`L_Dia`** placements `L1`, `L2`, …: a sphere probed in five
//!   articulations, five points each (the pole and four at 45° from it,
//!   the four turned 18° from one articulation to the next). Each
//!   articulation starts from the placement's configuration turned by about
//!   1 rad per revolute joint (elbow and wrist in another posture); its five
//!   points are reached from its first one's readings turned by about 0.02
//!   rad, so that the probe points about the same way within it.
//! - **Ball-bar** placements `B1a`/`B1b`, `B2a`/`B2b`, …: the two spheres of
//!   a bar of the stated length, in a random position and orientation
//!   (within about 17° of horizontal) where the arm reaches both, each probed at
//!   ISO 10360-5's 25 points; the lengths file names each pair with the
//!   true distance between the centres (the bar's length: a calibrated
//!   artefact's).
//!
//! Their draws are their own stream ([`super::seeds::ACCEPTANCE`]): the
//! probing placements of `--spheres N` are the same bytes with or without
//! them.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::SimError;
use super::ik::solve_point;
use super::sockets::random_configuration;
use super::spheres::{SphereCampaign, SphereSettings, iso_sphere_pattern, turned};
use super::truth::normal;
use crate::domain::{Arm, ReferenceLength, Spheres};
use crate::kernel::ArmKernel;

/// The lengths file of a simulated ball bar.
pub const BAR_LENGTHS_FILE: &str = "bar_lengths.csv";

/// The ball bar's length `simulate` uses unless told, mm.
pub const DEFAULT_BAR_LENGTH_MM: f64 = 500.0;

/// What the acceptance placements add.
#[derive(Clone, Debug, PartialEq)]
pub struct AcceptanceSettings {
    /// `L_Dia` placements.
    pub articulated: usize,
    /// Ball-bar positions.
    pub bar_positions: usize,
    /// The bar's length (centre to centre), mm.
    pub bar_length_mm: f64,
}

/// The campaign with the acceptance placements: every row, the lengths of
/// the ball bar, each placement's true centre.
#[derive(Clone, Debug, PartialEq)]
pub struct AcceptanceCampaign {
    /// The rows: the probing placements first (articulation 1 when the file
    /// has the column), then `L…`, then `B…`.
    pub spheres: Spheres,
    /// The ball bar's lengths (true centre distances), lines from 2.
    pub lengths: Vec<ReferenceLength>,
    /// Per placement, its label and true centre, mm.
    pub centres: Vec<(String, [f64; 3])>,
}

/// Tries of a group's or a bar's placement before the campaign is given
/// up.
const DRAWS: usize = 50;

/// `base` (the probing placements of `settings`, by `truth`) with the
/// placements of `more`, drawn from the stream of `settings.seed` +
/// [`super::seeds::ACCEPTANCE`] (the user's seed, as `base`'s own stream is
/// derived from it).
///
/// # Errors
///
/// A bar length not positive; the kernel's; a placement the arm cannot
/// reach in 50 draws.
pub fn with_acceptance(
    truth: &Arm,
    base: SphereCampaign,
    settings: &SphereSettings,
    more: &AcceptanceSettings,
) -> Result<AcceptanceCampaign, SimError> {
    if !(more.bar_length_mm > 0.0 && more.bar_length_mm.is_finite()) {
        return Err(SimError::setting("bar_length", "a positive length, mm"));
    }
    let kernel = ArmKernel::new(&truth.params)?;
    let mut limits = truth.limits.clone();
    limits.resize(truth.params.joint_count(), None);
    let seed = super::seeds::of(settings.seed, super::seeds::ACCEPTANCE);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let articulated = more.articulated > 0;
    let rows = &base.spheres;
    let mut spheres = Spheres::new(rows.joints(), rows.prismatic_mask());
    for i in 0..rows.len() {
        let a = articulated.then_some(1);
        spheres.push(
            &rows.spheres()[rows.sphere(i)],
            rows.reading(i),
            rows.line(i),
            a,
        );
    }
    let mut out = AcceptanceCampaign {
        spheres,
        lengths: Vec::new(),
        centres: base.centres,
    };
    let draw = Draw {
        kernel: &kernel,
        limits: &limits,
        settings,
        offset: (settings.diameter_mm + settings.ball_diameter_mm) / 2.0,
    };
    for l in 0..more.articulated {
        let name = format!("L{}", l + 1);
        let (c, groups) = draw.articulated(&mut rng)?;
        for (g, rows) in groups.iter().enumerate() {
            for q in rows {
                out.push(&name, q, Some(g as u32 + 1));
            }
        }
        out.centres.push((name, c));
    }
    let pattern = iso_sphere_pattern();
    for b in 0..more.bar_positions {
        let ends = draw.bar(more.bar_length_mm, &pattern, &mut rng)?;
        let names = [format!("B{}a", b + 1), format!("B{}b", b + 1)];
        for ((c, rows), name) in ends.iter().zip(&names) {
            for q in rows {
                out.push(name, q, articulated.then_some(1));
            }
            out.centres.push((name.clone(), *c));
        }
        out.lengths.push(ReferenceLength {
            a: names[0].clone(),
            b: names[1].clone(),
            distance: crate::geometry::distance(&ends[0].0, &ends[1].0),
            uncertainty: None,
            line: b + 2,
        });
    }
    Ok(out)
}

impl AcceptanceCampaign {
    /// A row at the next line.
    fn push(&mut self, name: &str, q: &[f64], articulation: Option<u32>) {
        let line = 2 + self.spheres.len();
        self.spheres.push(name, q, line, articulation);
    }
}

/// What every draw needs.
struct Draw<'a> {
    kernel: &'a ArmKernel,
    limits: &'a [Option<[f64; 2]>],
    settings: &'a SphereSettings,
    /// The probe centre's distance from the sphere's centre, mm.
    offset: f64,
}

/// A sphere's readings at its points: per point, readings.
type Rows = Vec<Vec<f64>>;

/// A placement's start: the configuration, the sphere's centre, its pole.
type Placed = (Vec<f64>, [f64; 3], [f64; 3]);

/// A touch: the exact readings, and as read (with the encoders' noise).
type Touched = (Vec<f64>, Vec<f64>);

impl Draw<'_> {
    /// A random sphere centre below the probe of a random configuration,
    /// its pole within about 35° of up: `(q0, centre, pole)`.
    fn centre(&self, rng: &mut ChaCha8Rng) -> Result<Placed, SimError> {
        let q0 = random_configuration(self.limits, rng);
        let tilt = [0.6 * normal(rng), 0.6 * normal(rng), 1.0];
        let norm = (tilt[0] * tilt[0] + tilt[1] * tilt[1] + 1.0).sqrt();
        let pole = tilt.map(|v| v / norm);
        let top = self.kernel.position(&q0)?;
        let c = std::array::from_fn(|k| top[k] - self.offset * pole[k]);
        Ok((q0, c, pole))
    }

    /// The true arm's noisy readings at the point of direction `d` on the
    /// sphere about `c`, from `start` turned by `spread` rad per revolute
    /// joint (20 tries); `None` when out of reach.
    fn touch(
        &self,
        (c, d): ([f64; 3], [f64; 3]),
        start: &[f64],
        spread: f64,
        rng: &mut ChaCha8Rng,
    ) -> Result<Option<Touched>, SimError> {
        let s = self.settings;
        let shape = self.kernel.shape();
        let target: [f64; 3] =
            std::array::from_fn(|k| c[k] + self.offset * d[k] + s.probe_mm * normal(rng));
        for _ in 0..20 {
            let from: Vec<f64> = (start.iter().enumerate())
                .map(|(j, v)| {
                    if shape.is_prismatic(j) {
                        *v
                    } else {
                        v + spread * normal(rng)
                    }
                })
                .collect();
            let found = solve_point(self.kernel, target, &from)?;
            if found.converged() {
                let read = (found.q.iter().enumerate())
                    .map(|(j, v)| {
                        if shape.is_prismatic(j) {
                            *v
                        } else {
                            v + s.encoder_rad * normal(rng)
                        }
                    })
                    .collect();
                return Ok(Some((found.q, read)));
            }
        }
        Ok(None)
    }

    /// An `L_Dia` placement: its centre and five articulations' readings.
    fn articulated(&self, rng: &mut ChaCha8Rng) -> Result<([f64; 3], Vec<Rows>), SimError> {
        let five = |g: usize| {
            let turn = (18.0 * g as f64).to_radians();
            let mut p = vec![[0.0, 0.0, 1.0]];
            p.extend((0..4).map(|j| {
                let a = turn + j as f64 * std::f64::consts::FRAC_PI_2;
                let s = std::f64::consts::FRAC_1_SQRT_2;
                [s * a.cos(), s * a.sin(), s]
            }));
            p
        };
        'draw: for _ in 0..DRAWS {
            let (q0, c, pole) = self.centre(rng)?;
            let mut groups = Vec::with_capacity(5);
            for g in 0..5 {
                let mut start = q0.clone();
                let mut rows = Vec::with_capacity(5);
                for (k, d) in turned(&five(g), pole).into_iter().enumerate() {
                    let spread = if k == 0 { 1.0 } else { 0.02 };
                    let Some((q, read)) = self.touch((c, d), &start, spread, rng)? else {
                        continue 'draw;
                    };
                    if k == 0 {
                        start = q;
                    }
                    rows.push(read);
                }
                groups.push(rows);
            }
            return Ok((c, groups));
        }
        Err(SimError::Model(format!(
            "no L_Dia placement the arm reaches in {DRAWS} draws"
        )))
    }

    /// A ball bar of `length`: each end's centre and readings.
    fn bar(
        &self,
        length: f64,
        pattern: &[[f64; 3]],
        rng: &mut ChaCha8Rng,
    ) -> Result<[([f64; 3], Rows); 2], SimError> {
        'draw: for _ in 0..DRAWS {
            let (q0, c, pole) = self.centre(rng)?;
            let azimuth: f64 = std::f64::consts::TAU * rng.random_range(0.0..1.0);
            let elevation: f64 = 0.6 * (rng.random_range(0.0..1.0) - 0.5);
            let dir = [
                elevation.cos() * azimuth.cos(),
                elevation.cos() * azimuth.sin(),
                elevation.sin(),
            ];
            let other: [f64; 3] = std::array::from_fn(|k| c[k] + length * dir[k]);
            let mut ends: Vec<([f64; 3], Rows)> = Vec::with_capacity(2);
            for centre in [c, other] {
                let mut rows = Vec::with_capacity(pattern.len());
                let mut start = q0.clone();
                for d in turned(pattern, pole) {
                    let Some((q, read)) = self.touch((centre, d), &start, 1.0, rng)? else {
                        continue 'draw;
                    };
                    start = q;
                    rows.push(read);
                }
                ends.push((centre, rows));
            }
            let b = ends.pop().expect("two ends");
            let a = ends.pop().expect("two ends");
            return Ok([a, b]);
        }
        Err(SimError::Model(format!(
            "no position of a {length} mm ball bar whose both spheres the arm reaches in {DRAWS} \
             draws"
        )))
    }
}
