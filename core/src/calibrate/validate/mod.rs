//! Validation: the figures of an arm before and after calibration, on the
//! data it was fitted to and on data held out from the fit — held-out
//! points by cross-validation here, held-out placements of a touch tool in
//! [`placements`].

pub mod placements;

use serde::{Deserialize, Serialize};

use super::{
    CalibrationError, Context, FitInputs, OptionError, Solver, SolverSettings, calibrate_with,
};
use crate::corrections::Physics;
use crate::dataset::DataSet;
use crate::kernel::ArmKernel;
use crate::metrics::evaluate_without_pairs;
use crate::params::DhParams;
use crate::setting::Setting;

/// The figures a calibration is judged by, mm.
///
/// In JSON, figures of reference positions alone (no touch, no length)
/// leave the touch fields out: a section per kind of evidence present and
/// none for a kind absent. Read back, the missing fields are 0 / `None`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(into = "FiguresJson", from = "FiguresJson")]
#[non_exhaustive]
pub struct Figures {
    /// Points evaluated (0 without touches: the touch figures are then 0).
    pub points: usize,
    /// Mean over points of the paper's `e` (single-point repeatability).
    pub e_mean: f64,
    /// Largest `e`.
    pub e_max: f64,
    /// Mean over points of the SPAT `2s`.
    pub two_s_mean: f64,
    /// Largest `δ_max` over points (SPAT).
    pub delta_max: f64,
    /// Reference lengths evaluated.
    pub lengths: usize,
    /// RMS of the reference-length errors; `None` without lengths.
    pub length_rms: Option<f64>,
    /// Largest `|error|`; `None` without lengths.
    pub length_max: Option<f64>,
    /// The 3-D errors at the reference positions; absent without them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub positions: Option<PositionErrors>,
    /// The orientation errors at the reference positions that give the
    /// tool's orientation, **degrees** ([`orientation_errors`]); absent
    /// without them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientations: Option<PositionErrors>,
}

/// [`Figures`] as `calibration.json` holds them: the touch fields are
/// `None` (left out) when the figures are of reference positions alone.
#[derive(Serialize, Deserialize)]
struct FiguresJson {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    points: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    e_mean: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    e_max: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    two_s_mean: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    delta_max: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    lengths: Option<usize>,
    // Present (possibly `null`) whenever the touch fields are.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    length_rms: Option<Option<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    length_max: Option<Option<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    positions: Option<PositionErrors>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    orientations: Option<PositionErrors>,
}

impl From<Figures> for FiguresJson {
    fn from(f: Figures) -> FiguresJson {
        // Touch figures of no touch are zeros that mean nothing: left out.
        let touches = !(f.points == 0 && f.lengths == 0 && f.positions.is_some());
        FiguresJson {
            points: touches.then_some(f.points),
            e_mean: touches.then_some(f.e_mean),
            e_max: touches.then_some(f.e_max),
            two_s_mean: touches.then_some(f.two_s_mean),
            delta_max: touches.then_some(f.delta_max),
            lengths: touches.then_some(f.lengths),
            length_rms: touches.then_some(f.length_rms),
            length_max: touches.then_some(f.length_max),
            positions: f.positions,
            orientations: f.orientations,
        }
    }
}

impl From<FiguresJson> for Figures {
    fn from(j: FiguresJson) -> Figures {
        Figures {
            points: j.points.unwrap_or(0),
            e_mean: j.e_mean.unwrap_or(0.0),
            e_max: j.e_max.unwrap_or(0.0),
            two_s_mean: j.two_s_mean.unwrap_or(0.0),
            delta_max: j.delta_max.unwrap_or(0.0),
            lengths: j.lengths.unwrap_or(0),
            length_rms: j.length_rms.flatten(),
            length_max: j.length_max.flatten(),
            positions: j.positions,
            orientations: j.orientations,
        }
    }
}

/// The 3-D distances between where an arm puts the probe, registered to
/// each frame, and where the instrument saw it, mm.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct PositionErrors {
    /// Positions evaluated.
    pub count: usize,
    /// Mean distance.
    pub mean: f64,
    /// RMS distance.
    pub rms: f64,
    /// The 95th percentile of the distances (`percentile_95`); 0 in a
    /// file written before it was recorded.
    #[serde(default)]
    pub p95: f64,
    /// Largest distance.
    pub max: f64,
}

impl PositionErrors {
    /// The figures of the distances `d` (mm); all 0 for none.
    pub(crate) fn of(d: &[f64]) -> PositionErrors {
        let n = d.len().max(1) as f64;
        PositionErrors {
            count: d.len(),
            mean: d.iter().sum::<f64>() / n,
            rms: (d.iter().map(|v| v * v).sum::<f64>() / n).sqrt(),
            p95: percentile_95(d),
            max: d.iter().copied().fold(0.0, f64::max),
        }
    }
}

/// The 95th percentile of `d` by nearest rank: the smallest value with at
/// least 95 % of the values at or below it (0 for none; NaN sorts last).
pub(crate) fn percentile_95(d: &[f64]) -> f64 {
    if d.is_empty() {
        return 0.0;
    }
    let mut sorted = d.to_vec();
    sorted.sort_by(f64::total_cmp);
    // Nearest rank: ⌈0.95 n⌉, 1-based, computed in integers (no rounding).
    let rank = (95 * d.len()).div_ceil(100);
    sorted[rank.max(1) - 1]
}

impl Figures {
    /// The figures of data without touches: the touch figures 0 (and
    /// left out of the JSON when there are `positions`).
    pub(crate) fn without_touches(positions: Option<PositionErrors>) -> Figures {
        Figures {
            points: 0,
            e_mean: 0.0,
            e_max: 0.0,
            two_s_mean: 0.0,
            delta_max: 0.0,
            lengths: 0,
            length_rms: None,
            length_max: None,
            positions,
            orientations: None,
        }
    }

    /// The figure a calibration must not make worse on its own data: the
    /// mean `e` of the touches, or without touches the mean 3-D error at
    /// the reference positions.
    pub(crate) fn headline(&self) -> f64 {
        match (self.points, self.positions) {
            (0, Some(p)) => p.mean,
            _ => self.e_mean,
        }
    }

    /// What [`Figures::headline`] is, in words.
    pub(crate) fn headline_name(&self) -> &'static str {
        match (self.points, self.positions) {
            (0, Some(_)) => "mean 3-D position error",
            _ => "mean e",
        }
    }
}

/// A frame's registration by name: `[rx, ry, rz, tx, ty, tz]` (rad, mm).
/// A list of them may also carry the tool mount of orientations
/// (`crate::residuals::Mount`) under the mount's block name
/// ([`crate::residuals::MOUNT_BLOCK`]), `[rx, ry, rz, 0, 0, 0]`
/// ([`crate::Calibration::frames_with_mount`]); a frame cannot have that
/// name where orientations are fitted.
pub type FrameValues = (String, [f64; 6]);

/// The 3-D errors of `params` at `data`'s positions, each frame registered
/// as `frames` say, or (a frame not among them) by its closed-form
/// registration of `params`.
///
/// # Errors
///
/// The kernel's.
pub fn position_errors(
    params: &DhParams,
    data: &crate::dataset::PositionData,
    frames: &[FrameValues],
) -> Result<PositionErrors, CalibrationError> {
    let (_, d) = pose_errors(params, data, frames)?;
    Ok(PositionErrors::of(&d))
}

/// Per row of `data`, where `params` puts the probe (the arm's base frame,
/// mm) and its 3-D error `|R p + t − y|` (mm), each frame registered as
/// `frames` say or by its closed form.
///
/// # Errors
///
/// The kernel's.
pub(crate) fn pose_errors(
    params: &DhParams,
    data: &crate::dataset::PositionData,
    frames: &[FrameValues],
) -> Result<(Vec<[f64; 3]>, Vec<f64>), crate::kernel::KernelError> {
    let rows = data.rows();
    let x = frame_values(params, data, frames)?;
    // Each row's tool point at its fitted offset when `frames` carry it.
    let p = crate::residuals::tools::positions_at(params, data, frames)?;
    let d = (0..data.len())
        .map(|i| {
            let seen = crate::residuals::Frame::apply(&x[rows.frame(i)], p[i]);
            crate::geometry::distance(&seen, &rows.position(i))
        })
        .collect();
    Ok((p, d))
}

/// Per frame of `data`'s positions (their order), its registration: as
/// `frames` say, or (a frame not among them) its closed form of `params`.
fn frame_values(
    params: &DhParams,
    data: &crate::dataset::PositionData,
    frames: &[FrameValues],
) -> Result<Vec<[f64; 6]>, crate::kernel::KernelError> {
    let rows = data.rows();
    let given = |name: &String| frames.iter().find(|(n, _)| n == name).map(|(_, v)| *v);
    // The closed form only where a frame is not given (a fit's frames
    // usually all are).
    let closed = if rows.frames().iter().all(|n| given(n).is_some()) {
        Vec::new()
    } else {
        crate::residuals::positions::register(params, data)?
    };
    Ok((rows.frames().iter().enumerate())
        .map(|(f, name)| given(name).unwrap_or_else(|| closed[f].x))
        .collect())
}

/// The orientation errors of `params` at the rows of `data` that give the
/// tool's orientation, degrees: per row the angle of the small rotation
/// from where the arm turns the target (its last frame turned by the
/// mount, then into the row's frame, registered as in [`position_errors`])
/// to the orientation seen. The mount is the one `frames` carry
/// ([`FrameValues`]), or its closed form on these rows. `None` when no row
/// gives an orientation. (The figures' fields are in degrees here.)
///
/// # Errors
///
/// The kernel's.
pub fn orientation_errors(
    params: &DhParams,
    data: &crate::dataset::PositionData,
    frames: &[FrameValues],
) -> Result<Option<PositionErrors>, CalibrationError> {
    let d: Vec<f64> = orientation_errors_per_row(params, data, frames)?
        .into_iter()
        .flatten()
        .collect();
    Ok((!d.is_empty()).then(|| PositionErrors::of(&d)))
}

/// Per row of `data`, its orientation error as [`orientation_errors`]
/// takes it, degrees; `None` for a row without an orientation (every row
/// when none gives one).
///
/// # Errors
///
/// The kernel's.
pub(crate) fn orientation_errors_per_row(
    params: &DhParams,
    data: &crate::dataset::PositionData,
    frames: &[FrameValues],
) -> Result<Vec<Option<f64>>, crate::kernel::KernelError> {
    let rows = data.rows();
    if rows.oriented_rows() == 0 {
        return Ok(vec![None; data.len()]);
    }
    let x = frame_values(params, data, frames)?;
    let given = (frames.iter()).find(|(n, _)| n == crate::residuals::MOUNT_BLOCK);
    let mount = match given {
        Some((_, m)) => [m[0], m[1], m[2]],
        None => crate::residuals::mount_start(params, data, &x)?.unwrap_or_default(),
    };
    let mount = crate::residuals::Frame::rotation(&mount);
    let k = ArmKernel::new(params)?;
    let mut tools = vec![crate::kernel::Pose::default(); data.len()];
    k.poses(data.poses(), 0..data.len(), &mut tools)?;
    Ok((0..data.len())
        .map(|i| {
            let q = rows.orientation(i)?;
            let seen = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                q[0], q[1], q[2], q[3],
            ));
            let predicted = crate::residuals::Frame::apply_pose(&x[rows.frame(i)], &tools[i]);
            let r = nalgebra::Matrix3::from_fn(|a, b| predicted.rotation[a][b]) * mount.matrix();
            let turn = seen.to_rotation_matrix().matrix() * r.transpose();
            // The angle from the trace, its sine from the antisymmetric
            // part: exact near 0, where a calibrated arm's errors are.
            let s = nalgebra::Vector3::new(
                turn[(2, 1)] - turn[(1, 2)],
                turn[(0, 2)] - turn[(2, 0)],
                turn[(1, 0)] - turn[(0, 1)],
            )
            .norm()
                / 2.0;
            let c = (turn.trace() - 1.0) / 2.0;
            Some(s.atan2(c).to_degrees())
        })
        .collect())
}

/// The figures of `params` on `data`, each frame of its positions at its
/// closed-form registration of `params`.
///
/// # Errors
///
/// The kernel's and the metrics'.
pub fn figures(params: &DhParams, data: &DataSet) -> Result<Figures, CalibrationError> {
    figures_in(params, data, &[])
}

/// [`figures`] with the frames registered as `frames` say (a fit's).
///
/// # Errors
///
/// As [`figures`].
pub(crate) fn figures_in(
    params: &DhParams,
    data: &DataSet,
    frames: &[FrameValues],
) -> Result<Figures, CalibrationError> {
    let positions = data
        .positions()
        .map(|p| position_errors(params, p, frames))
        .transpose()?;
    let orientations = match data.positions() {
        Some(p) => orientation_errors(params, p, frames)?,
        None => None,
    };
    if data.is_empty() {
        return Ok(Figures {
            orientations,
            ..Figures::without_touches(positions)
        });
    }
    // Each touch through its tool (the probe's when no touch names one).
    let xyz = crate::residuals::tools::touch_positions_at(params, data, frames)?;
    // The figures use no pair of points (eq. 19): not computed.
    let ev = evaluate_without_pairs(data, &xyz)?;
    Ok(Figures {
        points: ev.points.len(),
        e_mean: ev.single_point_e.mean,
        e_max: ev.single_point_e.max,
        two_s_mean: ev.single_point_two_s.mean,
        delta_max: ev.single_point_delta_max.max,
        lengths: ev.reference.len(),
        length_rms: ev.reference_summary.map(|s| s.rms),
        length_max: ev.reference_summary.map(|s| s.max_abs),
        positions,
        orientations,
    })
}

/// Before and after on one data set.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct BeforeAfter {
    /// With the start (nominal) arm.
    pub before: Figures,
    /// With the calibrated arm.
    pub after: Figures,
}

/// Before and after of `start` → `calibrated` on `data` (the report's
/// tests compare with it).
///
/// # Errors
///
/// As [`figures`].
#[cfg(test)]
pub(crate) fn before_after(
    start: &DhParams,
    calibrated: &DhParams,
    data: &DataSet,
) -> Result<BeforeAfter, CalibrationError> {
    before_after_in(start, &[], calibrated, &[], data)
}

/// [`before_after`], the frames of each arm registered as given (the
/// start arm's closed form on the fitted data, the fit's own), a frame not
/// given by its closed form on `data`.
///
/// # Errors
///
/// As [`figures`].
#[cfg(test)]
pub(crate) fn before_after_in(
    start: &DhParams,
    start_frames: &[FrameValues],
    calibrated: &DhParams,
    frames: &[FrameValues],
    data: &DataSet,
) -> Result<BeforeAfter, CalibrationError> {
    Ok(BeforeAfter {
        before: figures_in(start, data, start_frames)?,
        after: figures_in(calibrated, data, frames)?,
    })
}

/// An arm as it sees data: its geometry, its physics (the corrections
/// beyond geometry it applies, [`crate::corrections`]) and its frames.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ArmView<'a> {
    /// The geometry.
    pub params: &'a DhParams,
    /// The corrections it applies.
    pub(crate) physics: &'a Physics,
    /// Its frames (a frame not given: its closed form on the data).
    pub frames: &'a [FrameValues],
}

/// `data` as an arm `params` with `physics` sees it: unchanged when the
/// physics corrects nothing ([`DataSet::corrected`]).
///
/// # Errors
///
/// A correction whose conditions the data lack.
pub(crate) fn seen_by<'d>(
    params: &DhParams,
    physics: &Physics,
    data: &'d DataSet,
) -> Result<std::borrow::Cow<'d, DataSet>, CalibrationError> {
    if !physics.corrects() {
        return Ok(std::borrow::Cow::Borrowed(data));
    }
    data.corrected(params, physics)
        .map(std::borrow::Cow::Owned)
        .map_err(|message| CalibrationError::Term {
            term: "beyond".into(),
            message,
        })
}

/// Before and after of two arms, each with its physics: each sees the
/// data through its own corrections.
///
/// # Errors
///
/// As [`figures`], and [`seen_by`]'s.
pub(crate) fn before_after_of(
    before: ArmView<'_>,
    after: ArmView<'_>,
    data: &DataSet,
) -> Result<BeforeAfter, CalibrationError> {
    let of = |arm: ArmView<'_>| -> Result<Figures, CalibrationError> {
        figures_in(
            arm.params,
            &*seen_by(arm.params, arm.physics, data)?,
            arm.frames,
        )
    };
    Ok(BeforeAfter {
        before: of(before)?,
        after: of(after)?,
    })
}

/// Each frame of `data`'s positions, registered to `params` in closed
/// form, by name (none without positions); then, when rows give the tool's
/// orientation, the mount's closed form in those frames
/// ([`FrameValues`]).
///
/// # Errors
///
/// The kernel's.
pub(crate) fn registered_frames(
    params: &DhParams,
    data: &DataSet,
) -> Result<Vec<FrameValues>, crate::kernel::KernelError> {
    let Some(p) = data.positions() else {
        return Ok(Vec::new());
    };
    let x: Vec<[f64; 6]> = (crate::residuals::positions::register(params, p)?.iter())
        .map(|r| r.x)
        .collect();
    let mut frames: Vec<FrameValues> = p.rows().frames().iter().cloned().zip(x.clone()).collect();
    if let Some(m) = crate::residuals::mount_start(params, p, &x)? {
        let name = crate::residuals::MOUNT_BLOCK.to_string();
        frames.push((name, [m[0], m[1], m[2], 0.0, 0.0, 0.0]));
    }
    Ok(frames)
}

/// One cross-validation fold: the points held out, and the figures there of
/// the arm fitted without them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct Fold {
    /// Labels of the held-out points.
    pub held_out: Vec<String>,
    /// Before and after on the held-out points.
    pub figures: BeforeAfter,
    /// Whether the fold's fit converged.
    pub successful: bool,
    /// The observations of the added terms the fold held out (points on
    /// spheres), scored per term; absent when there is none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub terms: Vec<TermHeldOut>,
}

/// A term's observations one fold held out, scored
/// ([`crate::residuals::HeldOutScorer`]): the distribution of `|error|`
/// (mm; a point on a sphere's radial error) before and after.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct TermHeldOut {
    /// The term's name (`spheres`).
    pub term: String,
    /// What the figures are ([`crate::residuals::HeldOutScorer::what`]).
    pub(crate) what: String,
    /// Where each held-out observation came from (`file:line`).
    pub held_out: Vec<String>,
    /// The start arm, the term's own unknowns (a sphere's centre and
    /// size) refitted with it on the fold's training observations.
    pub before: PositionErrors,
    /// The fold's fit, its own unknowns as it fitted them.
    pub after: PositionErrors,
}

/// Per added term (`terms`, in order), its folds: `None` for prior
/// knowledge, passed whole to every fold.
type TermFolds = Vec<Option<Vec<crate::residuals::TermFold>>>;

/// Each added term's observations dealt to `k` folds
/// ([`crate::residuals::Term::split`]) at the start of `layout`.
///
/// # Errors
///
/// An [`OptionError`] on `cross_validate` naming a data term that cannot be
/// split, or whose split refuses `k` (saying why).
pub(crate) fn split_terms(
    layout: &crate::residuals::Layout,
    terms: &[Box<dyn crate::residuals::Term>],
    k: usize,
    seed: u64,
) -> Result<TermFolds, OptionError> {
    let refused = |why: String| OptionError::new(Setting::CrossValidate, k, why);
    let x = layout.start();
    (terms.iter())
        .map(|t| {
            if t.is_prior() {
                return Ok(None);
            }
            let split = crate::residuals::At::with(layout, &x, |at| t.split(at, k, seed))
                .map_err(|e| refused(e.to_string()))?;
            match split {
                Some(folds) if folds.len() == k => Ok(Some(folds)),
                _ => Err(refused(format!(
                    "the term `{}` does not say how its observations split into folds (each fold \
                     would fit them all and score none): calibrate without cross-validation",
                    t.name()
                ))),
            }
        })
        .collect()
}

/// Fold `f`'s share of each added term: its training term, or the term
/// whole (prior knowledge).
fn fold_terms(
    terms: &[Box<dyn crate::residuals::Term>],
    split: &TermFolds,
    f: usize,
) -> Vec<Box<dyn crate::residuals::Term>> {
    (terms.iter().zip(split))
        .map(|(t, s)| match s {
            Some(folds) => folds[f].training.clone(),
            None => t.clone(),
        })
        .collect()
}

/// Fold `f`'s held-out observations of each split term, scored: before at
/// the start of `layout` (the term's unknowns refitted), after at the
/// fold's fit `fit`.
///
/// # Errors
///
/// A scorer's.
fn score_terms(
    layout: &crate::residuals::Layout,
    terms: &[Box<dyn crate::residuals::Term>],
    split: &TermFolds,
    f: usize,
    fit: &super::Calibration,
) -> Result<Vec<TermHeldOut>, CalibrationError> {
    let (x0, x1) = (layout.start(), fit.point_in(layout));
    let of = |e: Vec<f64>| PositionErrors::of(&e.iter().map(|v| v.abs()).collect::<Vec<_>>());
    let mut out = Vec::new();
    for (t, s) in terms.iter().zip(split) {
        let Some(folds) = s else { continue };
        let scorer = &folds[f].held_out;
        out.push(TermHeldOut {
            term: t.name().to_string(),
            what: scorer.what(),
            held_out: scorer.labels(),
            before: of(crate::residuals::At::with(layout, &x0, |at| {
                scorer.refitted(at)
            })?),
            after: of(crate::residuals::At::with(layout, &x1, |at| {
                scorer.fitted(at)
            })?),
        });
    }
    Ok(out)
}

/// `k`-fold cross-validation over points and reference positions: points
/// joined by a reference length stay in one fold (so every fold is also
/// scored on lengths where it has them), and each frame's positions are
/// dealt to the folds one by one (every fold's training keeps every frame);
/// groups and positions are dealt in an order shuffled by the settings'
/// seed, and each fold is calibrated as `inputs` say (their data are the
/// fold's training points and positions) by `solver`. Held-out positions
/// are scored in the frames the fold fitted (the start arm in its closed-
/// form registration on the fold's training positions). Each added term
/// deals its own observations ([`crate::residuals::Term::split`]) and
/// scores the held-out ones ([`Fold::terms`]); prior knowledge is passed
/// whole.
///
/// # Errors
///
/// A fold count the data cannot split into; an added data term that cannot
/// be split, or not into `k`; a fold's calibration's.
pub fn cross_validate(
    inputs: FitInputs<'_>,
    settings: &SolverSettings,
    solver: &dyn Solver,
    k: usize,
) -> Result<Vec<Fold>, CalibrationError> {
    cross_validate_cancellable(inputs, settings, solver, k, None)
}

/// [`cross_validate`], each fold's calibration stopped by `cancel` when it
/// is set ([`CalibrationError::Cancelled`]): a run's folds stop with it.
///
/// # Errors
///
/// As [`cross_validate`]; [`CalibrationError::Cancelled`].
pub fn cross_validate_cancellable(
    inputs: FitInputs<'_>,
    settings: &SolverSettings,
    solver: &dyn Solver,
    k: usize,
    cancel: Option<&super::Cancel>,
) -> Result<Vec<Fold>, CalibrationError> {
    let (start, data) = (inputs.layout.geometry(), inputs.data);
    let stated =
        (inputs.layout.corrections()).map_or_else(Physics::default, |(b, _)| b.physics.clone());
    check_folds(data, k)?;
    let split = split_terms(inputs.layout, inputs.terms, k, settings.seed)?;
    let point_folds = point_folds(data, k, settings.seed);
    let row_folds = position_folds(data, k, settings.seed);
    (0..k)
        .map(|f| {
            let (train_data, test_data) = fold_data(data, &point_folds[f], &row_folds[f]);
            let terms = fold_terms(inputs.terms, &split, f);
            let fold = FitInputs {
                data: &train_data,
                terms: &terms,
                ..inputs
            };
            let mut ctx = Context::new();
            if let Some(token) = cancel {
                ctx = ctx.cancelled_by(token.clone());
            }
            let fit = calibrate_with(fold, settings, solver, &mut ctx)?;
            let scored = score_terms(inputs.layout, inputs.terms, &split, f, &fit)?;
            let start_frames = registered_frames(start, &*seen_by(start, &stated, &train_data)?)?;
            let fit_frames = fit.frames_with_mount();
            let mut held_out: Vec<String> = (point_folds[f].iter())
                .map(|&p| data.points()[p].label.clone())
                .collect();
            if let Some(p) = data.positions() {
                held_out.extend(row_folds[f].iter().map(|&i| p.rows().label(i).to_string()));
            }
            Ok(Fold {
                held_out,
                figures: before_after_of(
                    ArmView {
                        params: start,
                        physics: &stated,
                        frames: &start_frames,
                    },
                    ArmView {
                        params: &fit.params,
                        physics: fit.physics.as_ref().unwrap_or(&stated),
                        frames: &fit_frames,
                    },
                    &test_data,
                )?,
                successful: fit.solver.successful,
                terms: scored,
            })
        })
        .collect()
}

/// Per fold, the points it holds out (sorted): groups joined by reference
/// lengths dealt in a seeded order.
fn point_folds(data: &DataSet, k: usize, seed: u64) -> Vec<Vec<usize>> {
    let groups = length_groups(data);
    let mut order: Vec<usize> = (0..groups.len()).collect();
    {
        use rand::seq::SliceRandom;
        order.shuffle(&mut crate::random::rng(seed, crate::random::streams::FOLDS));
    }
    let mut folds: Vec<Vec<usize>> = vec![Vec::new(); k];
    for (i, &g) in order.iter().enumerate() {
        folds[i % k].extend(&groups[g]);
    }
    folds.iter_mut().for_each(|f| f.sort_unstable());
    folds
}

/// Per fold, the position rows it holds out (sorted): each frame's rows in
/// a seeded order, dealt one by one.
fn position_folds(data: &DataSet, k: usize, seed: u64) -> Vec<Vec<usize>> {
    let mut folds: Vec<Vec<usize>> = vec![Vec::new(); k];
    let Some(p) = data.positions() else {
        return folds;
    };
    let rows = p.rows();
    let mut rng = crate::random::rng(seed, crate::random::streams::POSITION_FOLDS);
    for f in 0..rows.frames().len() {
        let mut of: Vec<usize> = (0..rows.len()).filter(|&i| rows.frame(i) == f).collect();
        {
            use rand::seq::SliceRandom;
            of.shuffle(&mut rng);
        }
        for (i, row) in of.into_iter().enumerate() {
            folds[i % k].push(row);
        }
    }
    folds.iter_mut().for_each(|f| f.sort_unstable());
    folds
}

/// A fold's training and test data: without the `points` and position
/// `rows` held out, and of them only.
fn fold_data(data: &DataSet, points: &[usize], rows: &[usize]) -> (DataSet, DataSet) {
    let train: Vec<usize> = (0..data.points().len())
        .filter(|p| points.binary_search(p).is_err())
        .collect();
    let (mut train_data, mut test_data) = (data.subset(&train), data.subset(points));
    if let Some(p) = data.positions() {
        let kept: Vec<usize> = (0..p.len())
            .filter(|i| rows.binary_search(i).is_err())
            .collect();
        train_data = train_data.with_position_data(Some(p.subset(&kept)));
        test_data = test_data.with_position_data((!rows.is_empty()).then(|| p.subset(rows)));
    }
    (train_data, test_data)
}

/// Checks a fold count `k` for `data`: 2 to the number of groups of points
/// joined by reference lengths (with touches), and few enough that every
/// frame of the reference positions keeps three in each fold's training.
pub(crate) fn check_folds(data: &DataSet, k: usize) -> Result<(), OptionError> {
    let groups = length_groups(data).len();
    if k < 2 || (!data.is_empty() && k > groups) {
        return Err(OptionError::new(
            Setting::CrossValidate,
            k,
            format!(
                "needs 2 to {groups} folds ({groups} groups of points joined by reference \
                 lengths)"
            ),
        ));
    }
    if let Some(p) = data.positions() {
        let rows = p.rows();
        for (f, name) in rows.frames().iter().enumerate() {
            let n = (0..rows.len()).filter(|&i| rows.frame(i) == f).count();
            if n - n.div_ceil(k) < crate::domain::MIN_FRAME_POSITIONS {
                return Err(OptionError::new(
                    Setting::CrossValidate,
                    k,
                    format!(
                        "frame {} has {n} positions: {k} folds leave its registration \
                         fewer than {} in a fold's training",
                        crate::error::quoted(name),
                        crate::domain::MIN_FRAME_POSITIONS
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Points grouped so that each reference length joins points of one group;
/// groups in order of their first point.
fn length_groups(data: &DataSet) -> Vec<Vec<usize>> {
    let n = data.points().len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for r in data.references() {
        let (a, b) = (root(&mut parent, r.a), root(&mut parent, r.b));
        parent[a.max(b)] = a.min(b);
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut index = vec![usize::MAX; n];
    for p in 0..n {
        let r = root(&mut parent, p);
        if index[r] == usize::MAX {
            index[r] = groups.len();
            groups.push(Vec::new());
        }
        groups[index[r]].push(p);
    }
    groups
}

#[cfg(test)]
mod tests {
    use super::{Figures, PositionErrors};

    fn touches() -> Figures {
        Figures {
            points: 3,
            e_mean: 0.1,
            e_max: 0.2,
            two_s_mean: 0.3,
            delta_max: 0.4,
            lengths: 0,
            length_rms: None,
            length_max: None,
            positions: None,
            orientations: None,
        }
    }

    /// Touch figures keep every field (`null` lengths included), in the
    /// order `calibration.json` has always had them.
    #[test]
    fn touch_figures_are_written_as_before() {
        let json = serde_json::to_string(&touches()).unwrap();
        assert_eq!(
            json,
            "{\"points\":3,\"e_mean\":0.1,\"e_max\":0.2,\"two_s_mean\":0.3,\"delta_max\":0.4,\
             \"lengths\":0,\"length_rms\":null,\"length_max\":null}"
        );
        assert_eq!(serde_json::from_str::<Figures>(&json).unwrap(), touches());
    }

    /// Figures of reference positions alone hold the positions only, and
    /// read back as they were.
    #[test]
    fn figures_of_positions_alone_have_no_touch_field() {
        let positions = PositionErrors::of(&[1.0, 2.0, 4.0]);
        assert_eq!(positions.p95, 4.0);
        let f = Figures::without_touches(Some(positions));
        let json = serde_json::to_value(f).unwrap();
        let keys: Vec<&String> = json.as_object().unwrap().keys().collect();
        assert_eq!(keys, ["positions"]);
        assert_eq!(serde_json::from_value::<Figures>(json).unwrap(), f);
        // With touches as well, both.
        let both = Figures {
            positions: Some(positions),
            ..touches()
        };
        let json = serde_json::to_value(both).unwrap();
        assert_eq!(json.as_object().unwrap().len(), 9);
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn calibrate_validate_percentile_95() {
        use crate::calibrate::validate::percentile_95;
        let d: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(percentile_95(&d), 95.0);
        assert_eq!(percentile_95(&[3.0, 1.0]), 3.0);
        assert_eq!(percentile_95(&[]), 0.0);
    }
}
