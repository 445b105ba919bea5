//! What a calibration predicts for each acceptance test: the expected value
//! and spread of every figure at the placements measured, by Monte Carlo
//! through the calibrated geometry's covariance and the readings' noise.
//!
//! **The model.** The true arm is the calibrated one plus `δ`, `δ ~ N(0,
//! Σ)` over the calibration's free parameters (`Σ` its covariance); each
//! reading carries the noise the calibration stated. One draw:
//!
//! 1. *Ideal points.* Every placement's probe-ball centres truly lie on a
//!    sphere of radius `(D_cal + d_ball)/2` about its true centre. The
//!    centre is the placement's free least-squares centre (the one
//!    `compute` fits), the centres of placements named by reference
//!    lengths moved (least change, [`lengths_held`]) until every length
//!    is its calibrated value; each measured point is projected radially
//!    onto that sphere, `s_i`. The ideal points keep the measured points'
//!    places on the sphere, so the draw probes the pattern the user probed.
//! 2. *The arm's error.* `e_i = FK(cal, q_i) − FK(cal + δ, q_i)`, exactly
//!    (two forward kinematics): a touch the true arm put at `s_i` is seen
//!    by the calibrated arm at `s_i + e_i`.
//! 3. *Noise.* The encoders: `J_q(q_i) ε`, `ε ~ N(0, σ_e² I)` per joint,
//!    first order (`J_q` the joint Jacobian at the calibrated arm: the
//!    second-order term, about `reach · σ_e²`, is below 1e-6 mm at σ_e =
//!    0.01°); the probe's seating: `N(0, σ_p² I)` per point.
//! 4. The draw's points `s_i + e_i + J_q ε + n_i` go through
//!    [`super::verify`] — the very computation of the measured figures —
//!    and every figure is kept.
//!
//! The prediction is each figure's mean and standard deviation over the
//! draws, and whether the measured value lies within two spreads of it.
//!
//! **What it leaves out.** The sphere's own form and diameter error (its
//! certificate's `u_D` is in the guard band `U`, not in the draws); the
//! reference lengths' calibration uncertainty; errors the calibration did
//! not fit (fixed parameters, corrections beyond the geometry: their error
//! is taken as zero, so a calibration that fixed a parameter which is
//! really wrong predicts too narrow a spread); the SPAT (its cones are not
//! drawn: its row has no prediction). `Σ` is the calibration's own
//! statement: a calibration that understates it predicts too narrow a
//! spread, which is what the comparison shows the user.
//!
//! **Cost.** Per draw one kernel for `cal + δ`, one forward kinematics per
//! point and one [`super::verify`] (a few sphere fits per placement): a
//! draw costs about one verification. For 10 placements of 25 points and
//! 20 ball-bar positions (`benches/acceptance.rs`) 200 draws took 209 ms
//! on one thread (one verification 0.91 ms), on a loaded 2-core machine.
//! Draws run in fixed chunks on up to `threads` threads; each draw has its
//! own generator, seeded from the seed's stream in draw order, so the
//! bytes do not depend on the thread count.
//!
//! `Σ` is factored by its symmetric eigen-decomposition, eigenvalues
//! clamped to zero from below when they are negative by rounding only
//! (within [`PSD_TOLERANCE`] of the largest); a clearly negative one, or a
//! covariance that is not finite or not symmetric, is refused
//! ([`PredictError::NotPositiveSemidefinite`]).

use nalgebra::{DMatrix, DVector, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use super::{Acceptance, AcceptanceError, Predicted, Settings, SpherePoints};
use crate::domain::ReferenceLength;
use crate::error::{InputError, OptionError, quoted};
use crate::kernel::{ArmKernel, KernelError, PreparedPoses};
use crate::params::DhParams;

/// Draws when none is asked for.
pub const DEFAULT_DRAWS: usize = 200;
/// Most draws one prediction makes (bounded work: some minutes at most).
pub(crate) const MAX_DRAWS: usize = 100_000;
/// Draws per work item handed to a thread.
const CHUNK: usize = 8;
/// A negative eigenvalue of `Σ` within this fraction of the largest is
/// rounding, clamped to zero; beyond it `Σ` is refused.
pub(crate) const PSD_TOLERANCE: f64 = 1e-9;

/// The noise of each reading, internal units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReadingNoise {
    /// σ of each encoder reading, rad.
    pub encoder_rad: f64,
    /// σ of the probe's seating per axis, mm.
    pub probe_mm: f64,
    /// Whether the calibration stated it, or the σ is the touch σ its fit
    /// estimated (then all of it is the probe's, isotropic).
    pub stated: bool,
}

impl ReadingNoise {
    /// The noise a calibration used: the stated encoder and probe σ (an
    /// unstated one of the two 0) when it stated any; otherwise the touch σ
    /// its fit estimated (`touch_sigma_mm`), taken as isotropic probe
    /// noise with no encoder part — the only figure of the readings' noise
    /// such a calibration holds.
    pub fn of_calibration(noise: &crate::residuals::Noise, touch_sigma_mm: f64) -> ReadingNoise {
        if noise.stated() {
            ReadingNoise {
                encoder_rad: noise.encoder_rad.unwrap_or(0.0),
                probe_mm: noise.probe_mm.unwrap_or(0.0),
                stated: true,
            }
        } else {
            ReadingNoise {
                encoder_rad: 0.0,
                probe_mm: touch_sigma_mm,
                stated: false,
            }
        }
    }
}

/// The calibration a prediction draws from.
#[derive(Clone, Copy, Debug)]
pub struct Calibrated<'a> {
    /// The calibrated geometry (mm, rad), the one the figures were
    /// measured with.
    pub params: &'a DhParams,
    /// The free parameters' columns (of the `4n + 3`).
    pub free: &'a [usize],
    /// Their covariance, mm and rad.
    pub covariance: &'a DMatrix<f64>,
    /// The readings' noise.
    pub noise: ReadingNoise,
}

/// How many draws, from which seed, on how many threads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Draws {
    /// Draws (2 to `MAX_DRAWS`).
    pub count: usize,
    /// The seed.
    pub seed: u64,
    /// Threads at most (the result does not depend on them).
    pub threads: usize,
}

/// What a prediction was made from, as the outputs say it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PredictionInfo {
    /// Where the calibration came from (its file).
    pub calibration: String,
    /// Draws.
    pub draws: usize,
    /// The seed.
    pub seed: u64,
    /// Free parameters drawn.
    pub(crate) free_parameters: usize,
    /// The readings' noise drawn.
    pub noise: ReadingNoise,
}

/// Why there is no prediction.
#[derive(Debug, thiserror::Error)]
pub enum PredictError {
    /// The covariance is not a covariance.
    #[error(
        "the calibration's covariance is not positive semi-definite ({why}): its draws would be \
         no distribution"
    )]
    NotPositiveSemidefinite {
        /// What is wrong, in words.
        why: String,
    },
    /// A setting's fault (the draws).
    #[error(transparent)]
    Option(#[from] OptionError),
    /// The lengths cannot all hold at once, by file and line.
    #[error(transparent)]
    Input(#[from] InputError),
    /// The kernel's.
    #[error(transparent)]
    Kernel(#[from] KernelError),
    /// A draw's points fix no figure.
    #[error("draw {draw} of the prediction: {source}")]
    Draw {
        /// The draw (0-based).
        draw: usize,
        /// Why.
        source: AcceptanceError,
    },
}

/// The readings the figures were measured from.
#[derive(Clone, Copy, Debug)]
pub struct Measured<'a> {
    /// The sphere points (as [`super::verify`] took them).
    pub points: SpherePoints<'a>,
    /// Their readings, prepared as the arm saw them.
    pub poses: &'a PreparedPoses,
    /// The reference lengths and their file, if any.
    pub lengths: Option<(&'a [ReferenceLength], &'a str)>,
}

/// Fills `acceptance` (the figures [`super::verify`] computed from
/// `measured` under `settings`) with each test's prediction from `cal`:
/// see the module's documentation. `source` names the calibration in the
/// outputs.
///
/// # Errors
///
/// Draws out of range; a covariance of another size than the free
/// parameters, or not positive semi-definite; lengths that cannot hold at
/// once; a draw whose points fix no figure.
pub fn predict(
    acceptance: &mut Acceptance,
    settings: &Settings,
    measured: Measured<'_>,
    cal: Calibrated<'_>,
    draws: Draws,
    source: &str,
) -> Result<(), PredictError> {
    check_draws(draws.count)?;
    let root = covariance_root(cal.covariance, cal.free.len())?;
    let ideal = ideal_points(acceptance, settings, measured)?;
    let arm = CalibratedArm::new(cal, measured.poses)?;
    let seeds: Vec<u64> = {
        let mut r = crate::random::rng(draws.seed, crate::random::streams::PREDICTION);
        (0..draws.count).map(|_| r.random()).collect()
    };
    let chunks: Vec<std::ops::Range<usize>> = (0..draws.count)
        .step_by(CHUNK)
        .map(|s| s..(s + CHUNK).min(draws.count))
        .collect();
    let one = |d: usize| {
        let mut rng = ChaCha8Rng::seed_from_u64(seeds[d]);
        let xyz = arm.draw(&ideal, &root, cal.noise, &mut rng)?;
        let points = SpherePoints {
            centres: &xyz,
            ..measured.points
        };
        super::verify(settings, points, measured.lengths, None)
            .map(|a| figures(&a))
            .map_err(|source| PredictError::Draw { draw: d, source })
    };
    let done = crate::parallel::parallel_map(&chunks, draws.threads, |c| {
        c.clone().map(one).collect::<Result<Vec<_>, _>>()
    });
    let mut all = Vec::with_capacity(draws.count);
    for chunk in done {
        all.extend(chunk?);
    }
    fill(acceptance, &all);
    acceptance.prediction = Some(PredictionInfo {
        calibration: source.to_string(),
        draws: draws.count,
        seed: draws.seed,
        free_parameters: cal.free.len(),
        noise: cal.noise,
    });
    Ok(())
}

/// The draws checked: at least 2 (one has no spread), at most
/// [`MAX_DRAWS`].
fn check_draws(n: usize) -> Result<(), OptionError> {
    if (2..=MAX_DRAWS).contains(&n) {
        return Ok(());
    }
    Err(OptionError::new(
        crate::setting::Setting::PredictionDraws,
        n,
        format!("the prediction's draws are 2 to {MAX_DRAWS} (a spread needs two)"),
    ))
}

/// One draw's figures: the tests' values, then each placement's own.
type Figures = (Vec<f64>, Vec<Vec<f64>>);

fn figures(a: &Acceptance) -> Figures {
    (
        a.tests.iter().map(|t| t.value).collect(),
        (a.placements.iter())
            .map(|p| p.tests.iter().map(|t| t.value).collect())
            .collect(),
    )
}

/// Each test's (and each placement's test's) mean and spread over `all`,
/// and whether its measured value lies within two spreads. The SPAT is not
/// drawn (its cones are not part of the draws): no prediction.
fn fill(a: &mut Acceptance, all: &[Figures]) {
    let stat = |values: &mut dyn Iterator<Item = f64>, measured: f64| {
        let v: Vec<f64> = values.collect();
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let spread = var.max(0.0).sqrt();
        Predicted {
            value: mean,
            spread,
            agrees: (measured - mean).abs() <= 2.0 * spread,
        }
    };
    for (k, t) in a.tests.iter_mut().enumerate() {
        if t.test == super::TestKind::Spat {
            continue;
        }
        t.predicted = Some(stat(&mut all.iter().map(|f| f.0[k]), t.value));
    }
    for (s, p) in a.placements.iter_mut().enumerate() {
        for (k, t) in p.tests.iter_mut().enumerate() {
            t.predicted = Some(stat(&mut all.iter().map(|f| f.1[s][k]), t.value));
        }
    }
}

/// `L` with `L Lᵀ = Σ` (`q × q`), from the symmetric eigen-decomposition,
/// rounding's negative eigenvalues clamped to zero.
fn covariance_root(cov: &DMatrix<f64>, q: usize) -> Result<DMatrix<f64>, PredictError> {
    let refuse = |why: String| PredictError::NotPositiveSemidefinite { why };
    if cov.shape() != (q, q) {
        return Err(refuse(format!(
            "{} × {} for {q} free parameters",
            cov.nrows(),
            cov.ncols()
        )));
    }
    if !cov.iter().all(|v| v.is_finite()) {
        return Err(refuse("an entry is not a finite number".into()));
    }
    let scale = cov.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let asym = (0..q)
        .flat_map(|i| (0..q).map(move |j| (i, j)))
        .fold(0.0f64, |m, (i, j)| m.max((cov[(i, j)] - cov[(j, i)]).abs()));
    if asym > PSD_TOLERANCE * scale.max(f64::MIN_POSITIVE) {
        return Err(refuse(format!("not symmetric: entries differ by {asym:e}")));
    }
    let eig = nalgebra::SymmetricEigen::new(cov.clone());
    let largest = eig.eigenvalues.iter().fold(0.0f64, |m, v| m.max(*v));
    let smallest = eig.eigenvalues.iter().fold(f64::INFINITY, |m, v| m.min(*v));
    if smallest < -PSD_TOLERANCE * largest.max(f64::MIN_POSITIVE) {
        return Err(refuse(format!(
            "an eigenvalue {smallest:e} against a largest {largest:e}"
        )));
    }
    let mut root = eig.eigenvectors;
    for (j, l) in eig.eigenvalues.iter().enumerate() {
        let s = l.max(0.0).sqrt();
        root.column_mut(j).scale_mut(s);
    }
    Ok(root)
}

/// Every point projected onto its placement's ideal sphere: radius
/// `(D_cal + d_ball)/2` about the placement's centre, the centres named by
/// lengths moved until the lengths hold.
fn ideal_points(
    a: &Acceptance,
    settings: &Settings,
    measured: Measured<'_>,
) -> Result<Vec<[f64; 3]>, PredictError> {
    let mut centres: Vec<Vector3<f64>> = (a.placements.iter())
        .map(|p| Vector3::from(p.fit.centre))
        .collect();
    if let Some((lengths, file)) = measured.lengths {
        let names = measured.points.rows.spheres();
        lengths_held(&mut centres, names, lengths, file)?;
    }
    let radius = (settings.sphere_diameter + settings.ball_diameter) / 2.0;
    let rows = measured.points.rows;
    Ok((0..rows.len())
        .map(|i| {
            let c = centres[rows.sphere(i)];
            let v = Vector3::from(measured.points.centres[i]) - c;
            let n = v.norm();
            // A point at the centre itself has no direction: it stays (a
            // fit that put a centre on a point is already refused).
            let p = if n > 0.0 { c + v * (radius / n) } else { c };
            [p[0], p[1], p[2]]
        })
        .collect())
}

/// Sweeps of [`lengths_held`] before it gives up.
const LENGTH_SWEEPS: usize = 1000;

/// The placements' `centres` moved the least (each length's two ends
/// moved alike along it, sweep after sweep: SHAKE's iteration) until
/// every reference length is its calibrated value to 1e-12 relative.
///
/// # Errors
///
/// A length between two placements at one centre, or lengths that cannot
/// all hold at once (no convergence in [`LENGTH_SWEEPS`] sweeps): by file
/// and line of the length furthest from its value.
pub(crate) fn lengths_held(
    centres: &mut [Vector3<f64>],
    names: &[String],
    lengths: &[ReferenceLength],
    file: &str,
) -> Result<(), InputError> {
    let index = |n: &str| {
        names
            .iter()
            .position(|x| x == n)
            .expect("checked by verify")
    };
    let ends: Vec<(usize, usize)> = lengths.iter().map(|l| (index(&l.a), index(&l.b))).collect();
    let off = |centres: &[Vector3<f64>], k: usize| {
        let (a, b) = ends[k];
        (centres[a] - centres[b]).norm() - lengths[k].distance
    };
    for _ in 0..LENGTH_SWEEPS {
        let worst = (0..lengths.len())
            .map(|k| (k, off(centres, k).abs() / (1.0 + lengths[k].distance)))
            .fold((0, 0.0), |m, x| if x.1 > m.1 { x } else { m });
        if worst.1 <= 1e-12 {
            return Ok(());
        }
        for (k, &(a, b)) in ends.iter().enumerate() {
            let d = centres[a] - centres[b];
            let n = d.norm();
            if a == b || n == 0.0 {
                let message = format!(
                    "{} and {} are one centre: the length between them has no direction",
                    quoted(&lengths[k].a),
                    quoted(&lengths[k].b)
                );
                return Err(InputError::field(file, lengths[k].line, "point_b", message));
            }
            let step = d * ((lengths[k].distance - n) / (2.0 * n));
            centres[a] += step;
            centres[b] -= step;
        }
    }
    let k = (0..lengths.len())
        .max_by(|&i, &j| off(centres, i).abs().total_cmp(&off(centres, j).abs()))
        .unwrap_or(0);
    let message = format!(
        "the reference lengths cannot all hold at once (this one stays {:.3e} mm off after \
         {LENGTH_SWEEPS} sweeps): the prediction places the spheres where every calibrated \
         length holds",
        off(centres, k)
    );
    Err(InputError::field(
        file,
        lengths[k].line,
        "distance",
        message,
    ))
}

/// The calibrated arm at the measured poses: its positions, each pose's
/// joint Jacobian, and what a draw perturbs.
struct CalibratedArm<'a> {
    cal: Calibrated<'a>,
    poses: &'a PreparedPoses,
    values: Vec<f64>,
    at: Vec<[f64; 3]>,
    /// Per pose, `∂p/∂q_j` for each joint `j`.
    joint: Vec<Vec<[f64; 3]>>,
}

impl<'a> CalibratedArm<'a> {
    fn new(
        cal: Calibrated<'a>,
        poses: &'a PreparedPoses,
    ) -> Result<CalibratedArm<'a>, KernelError> {
        let kernel = ArmKernel::new(cal.params)?;
        let n = poses.len();
        let mut at = vec![[0.0; 3]; n];
        kernel.positions(poses, 0..n, &mut at)?;
        let mut joint = vec![Vec::new(); n];
        kernel.for_each_joint_jacobian(poses, 0..n, |i, jq| joint[i] = jq.to_vec())?;
        Ok(CalibratedArm {
            cal,
            poses,
            values: cal.params.to_vec(),
            at,
            joint,
        })
    }

    /// One draw's points: `ideal + e + J_q ε + n` (module documentation).
    fn draw(
        &self,
        ideal: &[[f64; 3]],
        root: &DMatrix<f64>,
        noise: ReadingNoise,
        rng: &mut ChaCha8Rng,
    ) -> Result<Vec<[f64; 3]>, PredictError> {
        let mut normal = || -> f64 { StandardNormal.sample(&mut *rng) };
        let z = DVector::from_fn(root.ncols(), |_, _| normal());
        let delta = root * z;
        let mut v = self.values.clone();
        for (k, &c) in self.cal.free.iter().enumerate() {
            v[c] += delta[k];
        }
        let truth = (self.cal.params.with_values(&v)).expect("the free columns are the arm's own");
        let kernel = ArmKernel::new(&truth)?;
        let mut seen = vec![[0.0; 3]; self.poses.len()];
        kernel.positions(self.poses, 0..self.poses.len(), &mut seen)?;
        Ok((0..ideal.len())
            .map(|i| {
                let mut p =
                    Vector3::from(ideal[i]) + Vector3::from(self.at[i]) - Vector3::from(seen[i]);
                for col in &self.joint[i] {
                    p += Vector3::from(*col) * (noise.encoder_rad * normal());
                }
                p += Vector3::from_fn(|_, _| noise.probe_mm * normal());
                [p[0], p[1], p[2]]
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{DMatrix, Matrix4, Vector3, Vector4};

    use super::*;
    use crate::acceptance::{LDiaRadius, Mpe, TestKind, verify};
    use crate::domain::Arm;
    use crate::simulate::{AcceptanceSettings, SphereSettings, simulate_spheres, with_acceptance};

    const D: f64 = 25.4;
    const BALL: f64 = 6.0;

    fn settings() -> Settings {
        Settings {
            sphere_diameter: D,
            sphere_uncertainty: 0.0,
            ball_diameter: BALL,
            l_dia_radius: LDiaRadius::Held,
            mpe: Mpe::default(),
        }
    }

    /// A noise-free campaign of the paper arm: one probing placement and
    /// one ball-bar position (two placements, one length).
    fn campaign() -> (Arm, crate::simulate::AcceptanceCampaign) {
        let arm = Arm {
            ball_diameter_mm: Some(BALL),
            ..Arm::without_limits("paper", DhParams::paper_nominal())
        };
        let s = SphereSettings {
            placements: 1,
            diameter_mm: D,
            ball_diameter_mm: BALL,
            encoder_rad: 0.0,
            probe_mm: 0.0,
            seed: 5,
        };
        let base = simulate_spheres(&arm, &s.for_campaign()).unwrap();
        let more = AcceptanceSettings {
            articulated: 0,
            bar_positions: 1,
            bar_length_mm: 400.0,
        };
        let c = with_acceptance(&arm, base, &s, &more).unwrap();
        (arm, c)
    }

    /// A covariance of `free` with correlations: `B Bᵀ`, `B` fixed numbers
    /// of about `scale`.
    fn covariance(q: usize, scale: f64) -> DMatrix<f64> {
        let b = DMatrix::from_fn(q, q, |i, j| {
            scale * (((i * 7 + j * 3) % 5) as f64 - 2.0) / 2.0 + if i == j { scale } else { 0.0 }
        });
        &b * b.transpose()
    }

    /// The prediction of the campaign's tests at `cov` and `noise`.
    fn predicted(
        cov: &DMatrix<f64>,
        free: &[usize],
        noise: ReadingNoise,
        count: usize,
        threads: usize,
    ) -> (Acceptance, PreparedPoses) {
        let (arm, c) = campaign();
        let rows: Vec<&[f64]> = (0..c.spheres.len()).map(|i| c.spheres.reading(i)).collect();
        let poses = PreparedPoses::new(6, &rows).unwrap();
        let kernel = ArmKernel::new(&arm.params).unwrap();
        let mut xyz = vec![[0.0; 3]; rows.len()];
        kernel.positions(&poses, 0..rows.len(), &mut xyz).unwrap();
        let measured = Measured {
            points: SpherePoints {
                rows: &c.spheres,
                file: "s.csv",
                centres: &xyz,
            },
            poses: &poses,
            lengths: Some((&c.lengths, "l.csv")),
        };
        let mut a = verify(&settings(), measured.points, measured.lengths, None).unwrap();
        let cal = Calibrated {
            params: &arm.params,
            free,
            covariance: cov,
            noise,
        };
        let draws = Draws {
            count,
            seed: 11,
            threads,
        };
        predict(&mut a, &settings(), measured, cal, draws, "cal.json").unwrap();
        (a, poses)
    }

    /// `E_Uni`'s first-order variance: `dE = Σ_i h_iᵀ dp_i` through the two
    /// free sphere fits (`dc = −[(JᵀJ)⁻¹Jᵀ]_c (n̂_iᵀ dp_i)`), with
    /// `dp_i = −A_i δ + J_q,i ε + n_i`, is
    /// `uᵀΣu + σ_e² Σ|J_q,iᵀh_i|² + σ_p² Σ|h_i|²`, `u = Σ A_iᵀ h_i`.
    fn e_uni_variance(
        a: &Acceptance,
        poses: &PreparedPoses,
        free: &[usize],
        cov: &DMatrix<f64>,
        noise: ReadingNoise,
    ) -> f64 {
        let (arm, c) = campaign();
        let rows = &c.spheres;
        let kernel = ArmKernel::new(&arm.params).unwrap();
        let mut p = vec![[0.0; 3]; rows.len()];
        kernel.positions(poses, 0..rows.len(), &mut p).unwrap();
        let centre = |name: &str| {
            let s = a.placements.iter().find(|s| s.name == name).unwrap();
            Vector3::from(s.fit.centre)
        };
        let (ca, cb) = (centre("B1a"), centre("B1b"));
        let g = (ca - cb).normalize();
        let mut h = vec![Vector3::zeros(); rows.len()];
        for (name, c, sign) in [("B1a", ca, 1.0), ("B1b", cb, -1.0)] {
            let of: Vec<usize> = (0..rows.len())
                .filter(|&i| rows.spheres()[rows.sphere(i)] == name)
                .collect();
            let n: Vec<Vector3<f64>> = (of.iter())
                .map(|&i| (Vector3::from(p[i]) - c).normalize())
                .collect();
            let jtj: Matrix4<f64> = n
                .iter()
                .map(|n| {
                    let r = Vector4::new(-n[0], -n[1], -n[2], -1.0);
                    r * r.transpose()
                })
                .sum();
            let m = jtj.try_inverse().unwrap();
            for (k, &i) in of.iter().enumerate() {
                let r = Vector4::new(-n[k][0], -n[k][1], -n[k][2], -1.0);
                let dc = -(m * r);
                let w = g.dot(&Vector3::new(dc[0], dc[1], dc[2]));
                h[i] = n[k] * (sign * w);
            }
        }
        let mut u = DVector::zeros(free.len());
        let mut enc = 0.0;
        kernel
            .for_each_jacobian(poses, 0..rows.len(), |i, _, jac| {
                for (k, &col) in free.iter().enumerate() {
                    u[k] += Vector3::from(jac[col]).dot(&h[i]);
                }
            })
            .unwrap();
        kernel
            .for_each_joint_jacobian(poses, 0..rows.len(), |i, jq| {
                enc += jq
                    .iter()
                    .map(|c| Vector3::from(*c).dot(&h[i]).powi(2))
                    .sum::<f64>();
            })
            .unwrap();
        let probe: f64 = h.iter().map(|v| v.norm_squared()).sum();
        (u.transpose() * cov * &u)[(0, 0)]
            + noise.encoder_rad.powi(2) * enc
            + noise.probe_mm.powi(2) * probe
    }

    #[test]
    fn e_uni_spread_is_the_first_order_closed_form_within_monte_carlo_error() {
        // a2, d3, α2, θ4 and the probe's x: lengths in mm, angles in rad.
        let free = [1, 8, 13, 21, 24];
        let mut cov = covariance(free.len(), 0.004);
        for (k, &c) in free.iter().enumerate() {
            if !crate::params::ParamId::from_column(6, c)
                .unwrap()
                .kind
                .is_length()
            {
                // An angle: 0.004 mm over a 500 mm lever.
                for j in 0..free.len() {
                    cov[(k, j)] /= 500.0;
                    cov[(j, k)] /= 500.0;
                }
            }
        }
        let noise = ReadingNoise {
            encoder_rad: 0.0005f64.to_radians(),
            probe_mm: 0.003,
            stated: true,
        };
        let n = 2000;
        let (a, poses) = predicted(&cov, &free, noise, n, 2);
        let e = a.tests.iter().find(|t| t.test == TestKind::EUni).unwrap();
        let p = e.predicted.unwrap();
        let var = e_uni_variance(&a, &poses, &free, &cov, noise);
        // The sample variance's relative σ is sqrt(2/(n − 1)), 3.2 %: 4 of
        // them.
        let bound = 4.0 * (2.0 / (n as f64 - 1.0)).sqrt();
        let ratio = p.spread.powi(2) / var;
        let quiet = ReadingNoise {
            encoder_rad: 0.0,
            probe_mm: 0.0,
            stated: true,
        };
        let share = e_uni_variance(&a, &poses, &free, &cov, quiet) / var;
        eprintln!(
            "E_Uni spread² / closed form {ratio}, σ {} mm, the geometry's share {share}",
            var.sqrt()
        );
        // Both parts tested: neither the geometry's nor the noise's vanishes.
        assert!((0.1..0.9).contains(&share), "{share}");
        assert!((ratio - 1.0).abs() < bound, "{ratio} (σ {} mm)", var.sqrt());
        // The lengths hold on the ideal centres: the mean is 0 within 4 σ
        // of a mean.
        assert!(p.value.abs() < 4.0 * p.spread / (n as f64).sqrt(), "{p:?}");
        // Every probing figure has a prediction; P_Size is centred near 0.
        let size = a.tests.iter().find(|t| t.test == TestKind::PSize).unwrap();
        assert!(size.predicted.unwrap().value.abs() < 4.0 * size.predicted.unwrap().spread);
        assert!(a.placements[0].tests.iter().all(|t| t.predicted.is_some()));
        assert_eq!(a.prediction.as_ref().unwrap().draws, n);
    }

    #[test]
    fn the_same_seed_gives_the_same_bytes_on_any_thread_count() {
        let free = [1, 8];
        let cov = covariance(2, 0.01);
        let noise = ReadingNoise {
            encoder_rad: 1e-5,
            probe_mm: 0.002,
            stated: true,
        };
        let (one, _) = predicted(&cov, &free, noise, 40, 1);
        let (four, _) = predicted(&cov, &free, noise, 40, 4);
        assert_eq!(
            serde_json::to_string(&one).unwrap(),
            serde_json::to_string(&four).unwrap()
        );
        assert!(one.tests[0].predicted.unwrap().spread > 0.0);
    }

    #[test]
    fn a_covariance_that_is_no_covariance_is_refused() {
        let bad = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        let e = covariance_root(&bad, 2).unwrap_err();
        assert!(e.to_string().contains("positive semi-definite"), "{e}");
        let nan = DMatrix::from_row_slice(1, 1, &[f64::NAN]);
        assert!(covariance_root(&nan, 1).is_err());
        assert!(covariance_root(&DMatrix::identity(2, 2), 3).is_err());
        // Rounding below zero is clamped: L Lᵀ = Σ.
        let near = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0 - 1e-14]);
        let l = covariance_root(&near, 2).unwrap();
        assert!((&l * l.transpose() - &near).amax() < 1e-12);
        let e = check_draws(1).unwrap_err();
        assert_eq!(e.field(), "prediction.draws");
    }

    #[test]
    fn lengths_that_cannot_hold_at_once_are_named() {
        let names: Vec<String> = ["A", "B", "C"].map(String::from).to_vec();
        let l = |a: &str, b: &str, d: f64, line| ReferenceLength {
            a: a.into(),
            b: b.into(),
            distance: d,
            uncertainty: None,
            line,
        };
        let mut c = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(100.0, 0.0, 0.0),
            Vector3::new(0.0, 100.0, 0.0),
        ];
        let fine = [l("A", "B", 100.01, 2), l("B", "C", 141.4, 3)];
        lengths_held(&mut c, &names, &fine, "l.csv").unwrap();
        assert!(((c[0] - c[1]).norm() - 100.01).abs() < 1e-9);
        assert!(((c[1] - c[2]).norm() - 141.4).abs() < 1e-9);
        let triangle = [
            l("A", "B", 100.0, 2),
            l("B", "C", 100.0, 3),
            l("A", "C", 500.0, 4),
        ];
        let e = lengths_held(&mut c, &names, &triangle, "l.csv").unwrap_err();
        assert!(e.to_string().starts_with("l.csv:"), "{e}");
        assert!(e.to_string().contains("cannot all hold"), "{e}");
    }
}
