//! The calibration session every front end runs: a [`Problem`] (arm, data,
//! settings, optional held-out data and cross-validation, where the inputs
//! came from) checked once when it is made; [`run`] calibrates, validates
//! and cross-validates it and returns one [`CalibrationReport`] — the schema
//! of `calibration.json`, the input of the HTML report, what the C API's
//! report function returns. The command line, the C API and the examples
//! are shells around this module.
//!
//! ```
//! use aacmm_core::{Arm, ModelOptions, Problem, SolverSettings, params::DhParams, simulate::*};
//! let nominal = Arm::without_limits("nominal", DhParams::paper_nominal());
//! let mut settings = CampaignSettings::new(1, ErrorModel::Paper, 8, 10);
//! settings.reference_lengths = 3;
//! let data = simulate(&nominal, &settings).unwrap().data_set().unwrap();
//! let problem = Problem::new(nominal, data, ModelOptions::default()).unwrap();
//! let report = problem.run(&SolverSettings::default()).unwrap();
//! assert!(report.is_usable());
//! assert!(report.validation.fitted.after.e_mean < report.validation.fitted.before.e_mean);
//! ```

pub(crate) mod evaluation;
pub(crate) mod identification;
mod map;
mod position_evaluation;
pub mod probe;
pub mod request;
pub mod spheres;
pub mod tools;
mod verdict;

pub use map::MAP_POSES;

pub use evaluation::EvaluationReport;
pub use identification::IdentifyReport;
pub use position_evaluation::{FrameEvaluation, MountEvaluation, PositionEvaluation};
pub use request::{Request, user_noise};
pub use verdict::{Note, Reason, Setting, Spelling, StatedNoise, UnconfirmedSearch, Verdict};
use verdict::{verdict_line, verdict_of};

use serde::{Deserialize, Serialize};

use crate::calibrate::validate::{
    ArmView, BeforeAfter, Figures, Fold, before_after_of, check_folds, cross_validate_cancellable,
    registered_frames, seen_by, split_terms,
};
use crate::calibrate::{
    Calibration, CalibrationError, Context, FitInputs, ModelOptions, Solver, SolverSettings,
    calibrate_with,
};
use crate::corrections::Physics;
use crate::dataset::DataSet;
use crate::error::OptionError;
use crate::io::{AngleUnit, Arm, LengthUnit, arm_to_toml};
use crate::params::DhParams;
use crate::residuals::spheres::SphereTerm;
use crate::residuals::{Block, BlockId, Layout, Noise, Term};

/// The calibrated arm, in the arm-file schema.
pub const CALIBRATED_FILE: &str = "calibrated.toml";
/// Everything the calibration found, as JSON ([`CalibrationReport`]).
pub const REPORT_FILE: &str = "calibration.json";
/// Wall times per phase (apart from [`REPORT_FILE`], which is the same
/// bytes for the same seed).
pub const TIMING_FILE: &str = "timing.json";

/// Where the inputs came from, for the report: names as users gave them
/// (paths, `<stdin>`, `<arrays>`), and the readers' warnings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sources {
    /// The arm file.
    pub arm_file: String,
    /// The poses file.
    pub data_file: String,
    /// The reference-lengths file, if any.
    pub lengths_file: Option<String>,
    /// Warnings of the readers, kept in the report.
    pub warnings: Vec<String>,
}

/// Data held out from the fit, to validate on.
#[derive(Clone, Debug)]
pub struct HeldOutData {
    /// The touches (and lengths).
    pub data: DataSet,
    /// Its poses file.
    pub data_file: String,
    /// Its lengths file, if any.
    pub lengths_file: Option<String>,
}

/// A calibration problem: the start (nominal) arm, the data, the model —
/// all checked when it is made —, what a caller adds to the least squares
/// (auxiliary parameter blocks, residual terms of its own), and what to
/// validate on.
#[derive(Clone, Debug)]
pub struct Problem {
    arm: Arm,
    data: DataSet,
    model: ModelOptions,
    /// The columns: the arm's geometry, then the blocks added.
    layout: Layout,
    /// Residual terms beyond the data's.
    terms: Vec<Box<dyn Term>>,
    held_out: Option<HeldOutData>,
    cross_validate: Option<usize>,
    sources: Sources,
    truth: Option<DhParams>,
    /// Held-out positions in a frame the fit does not have may be
    /// registered on themselves ([`Problem::registering_held_out_frames`]).
    register_held_out: bool,
    /// Points probed on reference spheres, when given
    /// ([`Problem::with_spheres`]): a term among `terms`, kept here too
    /// for its report.
    spheres: Option<SphereTerm>,
    /// Points on reference spheres held out, to validate on
    /// ([`Problem::with_held_out_spheres`]).
    held_out_spheres: Option<SphereTerm>,
}

impl Problem {
    /// Checks every setting against the arm and the data.
    ///
    /// # Errors
    ///
    /// [`CalibrationError::Option`] naming the setting out of range;
    /// [`CalibrationError::Joints`] when the data have another joint count.
    ///
    /// ```
    /// use aacmm_core::{Arm, ModelOptions, Problem, params::DhParams, simulate::*};
    /// use aacmm_core::calibrate::CalibrationError;
    /// let nominal = Arm::without_limits("n", DhParams::paper_nominal());
    /// let data = simulate(&nominal, &CampaignSettings::new(1, ErrorModel::Paper, 4, 6))
    ///     .unwrap().data_set().unwrap();
    /// let mut model = ModelOptions::default();
    /// model.noise.probe_mm = Some(-1.0);
    /// match Problem::new(nominal, data, model) {
    ///     Err(CalibrationError::Option(e)) => assert_eq!(e.field, "noise.probe_mm"),
    ///     _ => panic!("negative noise accepted"),
    /// }
    /// ```
    pub fn new(arm: Arm, data: DataSet, model: ModelOptions) -> Result<Problem, CalibrationError> {
        let joints = arm.params.joint_count();
        if data.joints() != joints {
            return Err(CalibrationError::Joints {
                arm: joints,
                data: data.joints(),
            });
        }
        let data = of_arm_tools(&arm, of_arm_shape(&arm, data)?)?;
        model.check_for(&arm.params)?;
        model
            .beyond
            .check_inputs(&arm.physics, &data.condition_sets())?;
        // The arm's file is named by the request, which knows it.
        check_units(&arm.params, &data, "")?;
        let layout = crate::residuals::positions::layout_with(
            &arm.params,
            &data,
            &arm.physics,
            &model.beyond,
        )?;
        check_positions(&data, &layout)?;
        Ok(Problem {
            layout,
            arm,
            data,
            model,
            terms: Vec::new(),
            held_out: None,
            cross_validate: None,
            sources: Sources::default(),
            truth: None,
            register_held_out: false,
            spheres: None,
            held_out_spheres: None,
        })
    }

    /// Validates on `held_out` too. Its reference positions are scored in
    /// the fitted frames of their names; a frame the fit does not have is
    /// refused, unless [`Problem::registering_held_out_frames`] was called
    /// first.
    ///
    /// # Errors
    ///
    /// [`CalibrationError::Joints`] when it has another joint count;
    /// [`CalibrationError::Positions`] naming the first line of a held-out
    /// frame the fit does not have, and the fitted frames.
    pub fn with_held_out(mut self, held_out: HeldOutData) -> Result<Problem, CalibrationError> {
        if held_out.data.joints() != self.data.joints() {
            return Err(CalibrationError::Joints {
                arm: self.arm.params.joint_count(),
                data: held_out.data.joints(),
            });
        }
        let held_out = HeldOutData {
            data: of_arm_tools(&self.arm, of_arm_shape(&self.arm, held_out.data)?)?,
            ..held_out
        };
        if !self.register_held_out {
            check_held_out_frames(&self.data, &held_out.data)?;
        }
        self.held_out = Some(held_out);
        Ok(self)
    }

    /// Lets held-out reference positions in a frame the fit does not have
    /// be registered on themselves (their own closed-form fit): their
    /// figures are then optimistic — the registration absorbs part of the
    /// arm's error —, and every output says which frames were so
    /// registered ([`HeldOut::registered_on_itself`]). Call it before
    /// [`Problem::with_held_out`].
    pub fn registering_held_out_frames(mut self) -> Problem {
        self.register_held_out = true;
        self
    }

    /// Cross-validates over `k` folds of points (seeded by the solver
    /// seed), each added term's observations dealt as the term says
    /// ([`Term::split`]; add the terms first).
    ///
    /// # Errors
    ///
    /// An [`OptionError`] on `cross_validate` unless `2 ≤ k ≤` the groups
    /// of points joined by reference lengths; naming an added term that
    /// cannot be split, or not into `k`.
    pub fn with_cross_validation(mut self, k: usize) -> Result<Problem, OptionError> {
        check_folds(&self.data, k)?;
        // The counts do not depend on the seed, which orders the deal (the
        // run deals again with its own, and checks that deal's shares).
        split_terms(&self.layout, &self.terms, k, 0)?;
        self.cross_validate = Some(k);
        Ok(self)
    }

    /// Adds an auxiliary parameter block (a frame, a scalar) after the
    /// geometry and the blocks added before; returns where its columns are,
    /// for the terms that use it. Every column of it is fitted unless the
    /// block is held ([`Problem::hold_block`]).
    ///
    /// # Errors
    ///
    /// As [`crate::residuals::Layout::add`]: a name already taken (a
    /// frame of the positions file's), sizes or bounds that disagree.
    pub fn add_block(
        &mut self,
        block: impl Block + 'static,
    ) -> Result<BlockId, crate::residuals::LayoutError> {
        self.layout.add(Box::new(block))
    }

    /// [`Problem::add_block`] of a block already boxed (what
    /// [`crate::residuals::spheres::SphereTerm::new`] hands over).
    ///
    /// # Errors
    ///
    /// As [`Problem::add_block`].
    pub fn add_boxed_block(
        &mut self,
        block: Box<dyn Block>,
    ) -> Result<BlockId, crate::residuals::LayoutError> {
        self.layout.add(block)
    }

    /// Holds block `id` at its start values: its columns are not fitted,
    /// and the report says so (a frame measured elsewhere, a plane whose
    /// offset is known).
    pub fn hold_block(&mut self, id: BlockId) {
        self.layout.hold(id);
    }

    /// Adds a residual term of the caller's (a new kind of measurement),
    /// evaluated after the data's touches and lengths and before the
    /// prior.
    pub fn with_term(mut self, term: impl Term + 'static) -> Problem {
        self.terms.push(Box::new(term));
        self
    }

    /// What the calibration fits: the layout, the data, the model and the
    /// added terms.
    pub fn inputs(&self) -> FitInputs<'_> {
        FitInputs {
            layout: &self.layout,
            data: &self.data,
            model: &self.model,
            terms: &self.terms,
        }
    }

    /// Adds points probed on reference spheres (their blocks added with
    /// [`SphereTerm::new`] through [`Problem::add_boxed_block`]): a term
    /// like any added one, and a section of the report.
    pub fn with_spheres(mut self, term: SphereTerm) -> Problem {
        self.terms.push(Box::new(term.clone()));
        self.spheres = Some(term);
        self
    }

    /// Validates on points probed on reference spheres too: `term`'s own
    /// blocks are not fitted (make it on a layout of its own); each of its
    /// spheres is refitted on its points with each arm held fixed, and the
    /// points are scored by their radial error
    /// ([`spheres::HeldOutSpheres`]).
    ///
    /// # Errors
    ///
    /// [`CalibrationError::Joints`] when its readings have another joint
    /// count than the arm.
    pub fn with_held_out_spheres(mut self, term: SphereTerm) -> Result<Problem, CalibrationError> {
        let joints = term.spheres().joints();
        if joints != self.data.joints() {
            return Err(CalibrationError::Joints {
                arm: self.arm.params.joint_count(),
                data: joints,
            });
        }
        self.held_out_spheres = Some(term);
        Ok(self)
    }

    /// The sphere term, if any.
    pub fn spheres(&self) -> Option<&SphereTerm> {
        self.spheres.as_ref()
    }

    /// Names the inputs in the report.
    pub fn with_sources(mut self, sources: Sources) -> Problem {
        self.sources = sources;
        self
    }

    /// The true arm, when known (a simulation): the report draws its
    /// errors beside the corrections.
    pub fn with_truth(mut self, truth: DhParams) -> Problem {
        self.truth = Some(truth);
        self
    }

    /// The true arm, if known.
    pub fn truth(&self) -> Option<&DhParams> {
        self.truth.as_ref()
    }

    /// The start arm.
    pub fn arm(&self) -> &Arm {
        &self.arm
    }

    /// The data fitted.
    pub fn data(&self) -> &DataSet {
        &self.data
    }

    /// The settings.
    pub fn model(&self) -> &ModelOptions {
        &self.model
    }

    /// The held-out data, if any.
    pub fn held_out(&self) -> Option<&HeldOutData> {
        self.held_out.as_ref()
    }

    /// The inputs' names.
    pub fn sources(&self) -> &Sources {
        &self.sources
    }

    /// [`run`] with the method of `settings`.
    ///
    /// # Errors
    ///
    /// As [`run`].
    pub fn run(&self, settings: &SolverSettings) -> Result<CalibrationReport, CalibrationError> {
        run(
            self,
            settings,
            &*settings.method.solver(),
            &mut Context::new(),
        )
    }
}

/// Checks, before any work, that the memory a calibration of `data` (with
/// `held_out` data; cross-validated when `folds`) allocates beyond its data
/// sets can be had: its solver, statistics and report allocate as they go,
/// where a failure would abort the host process (see [`crate::memory`]).
/// Cross-validation copies the data set into its folds, one at a time; a
/// caller that copies the data sets into its request first (`copied`:
/// Python, which keeps its own) counts those copies too.
///
/// # Errors
///
/// [`crate::memory::OutOfMemory`] when the memory cannot be had.
pub fn room_to_calibrate(
    data: &DataSet,
    held_out: Option<&DataSet>,
    folds: bool,
    copied: bool,
) -> Result<(), crate::memory::OutOfMemory> {
    use crate::memory::data_set_bytes_per_touch as data_set_bytes;
    let all: Vec<&DataSet> = std::iter::once(data).chain(held_out).collect();
    let (touches, lengths) = observations(&all);
    let joints = data.joints();
    let folds = if folds {
        data.len().saturating_mul(data_set_bytes(joints, 2))
    } else {
        0
    };
    let copies = if copied {
        touches.saturating_mul(data_set_bytes(joints, 0))
    } else {
        0
    };
    let per_touch = crate::memory::WORK_BYTES_PER_TOUCH;
    let extra = folds.saturating_add(copies);
    crate::memory::room_for_work("calibrating", touches, lengths, per_touch, extra)
}

/// The touches and positions, and the reference lengths, of `data`.
pub(crate) fn observations(data: &[&DataSet]) -> (usize, usize) {
    let (mut touches, mut lengths) = (0usize, 0usize);
    for d in data {
        touches = touches.saturating_add(d.observation_count());
        lengths = lengths.saturating_add(d.references().len());
    }
    (touches, lengths)
}

/// Stated lengths this many times the nominal arm's distances (or their
/// inverse) are in another unit: a calibration moves the arm by per cent,
/// not by orders of magnitude — but the nominal arm of a newly assembled
/// one, its zeros anywhere, can put two sockets several times nearer or
/// farther than they are, so the bound is two orders of magnitude (metres
/// for millimetres is three).
const LENGTH_UNIT_RATIO: f64 = 100.0;

/// The reaches, mm, of arms that exist: a nominal arm outside them is in
/// another unit than its file declares (the arm reader warns from
/// `PLAUSIBLE_METRES` in metres on).
const PLAUSIBLE_REACH_MM: std::ops::RangeInclusive<f64> =
    10.0..=crate::io::arm::PLAUSIBLE_METRES * 1000.0;

/// `data` (of the arm's joint count) prepared for the arm's chain: a
/// prismatic joint's readings (mm) are used as lengths however the data
/// were made (a reader given only a joint count, arrays).
fn of_arm_shape(arm: &Arm, data: DataSet) -> Result<DataSet, CalibrationError> {
    let Ok(shape) = arm.params.shape() else {
        return Ok(data);
    };
    let joints = (shape.joints(), data.joints());
    data.for_shape(shape).map_err(|_| CalibrationError::Joints {
        arm: joints.0,
        data: joints.1,
    })
}

/// `data` with each tool its positions name given the arm's nominal
/// offset; a tool the arm does not list is refused by file, line and field.
pub(super) fn of_arm_tools(arm: &Arm, data: DataSet) -> Result<DataSet, CalibrationError> {
    data.with_tools(&crate::io::ToolNames::of(&arm.tools))
        .map_err(|e| match e {
            crate::error::InputError::Field {
                file,
                line,
                field,
                message,
            } => CalibrationError::Positions {
                file,
                line,
                field,
                message,
            },
            e => CalibrationError::Positions {
                file: String::new(),
                line: 0,
                field: "tool".into(),
                message: e.to_string(),
            },
        })
}

/// Refuses reference lengths whose median ratio to the nominal arm's
/// distances between the same points is beyond 100 or below 1/100
/// (lengths in metres for an arm in mm, say), naming the input at fault:
/// the poses file when the readings look like radians read as degrees
/// (the reader's warning; every joint within ±6.3° puts the sockets almost
/// on top of each other, [`CalibrationError::AngleUnits`]); the arm file
/// (`arm_file`) when its reach is no arm's — its numbers in another unit
/// than it declares ([`CalibrationError::ArmUnits`]); else the lengths
/// file ([`CalibrationError::LengthUnits`]). Every command that reads a
/// lengths file makes this check, in every front end: calibrate and
/// identify (the [`Request`]), evaluate (the command line and Python call
/// it before evaluating).
///
/// # Errors
///
/// As above; a kernel that refuses the arm.
///
/// ```
/// use aacmm_core::{calibrate::CalibrationError, io::Arm, params::DhParams, simulate::*};
/// use aacmm_core::session::check_units;
/// let nominal = Arm::without_limits("n", DhParams::paper_nominal());
/// let mut settings = CampaignSettings::new(1, ErrorModel::Paper, 4, 6);
/// settings.reference_lengths = 3;
/// let campaign = simulate(&nominal, &settings).unwrap();
/// let data = campaign.data_set().unwrap();
/// assert!(check_units(&nominal.params, &data, "arm.toml").is_ok());
/// // The arm's millimetres declared as metres: the arm is 1240 m long.
/// let mut metres = nominal.params.clone();
/// for j in &mut metres.joints {
///     (j.a, j.d) = (1000.0 * j.a, 1000.0 * j.d);
/// }
/// metres.probe = metres.probe.map(|v| 1000.0 * v);
/// let e = check_units(&metres, &data, "arm.toml").unwrap_err();
/// assert!(matches!(e, CalibrationError::ArmUnits { .. }), "{e}");
/// assert!(e.to_string().starts_with("arm.toml: "), "{e}");
/// ```
pub fn check_units(
    params: &DhParams,
    data: &DataSet,
    arm_file: &str,
) -> Result<(), CalibrationError> {
    let Some(ratio) = median_length_ratio(params, data, data.poses())? else {
        return Ok(());
    };
    let in_range = |r: f64| (1.0 / LENGTH_UNIT_RATIO..=LENGTH_UNIT_RATIO).contains(&r);
    if in_range(ratio) {
        return Ok(());
    }
    let to_deg = 1f64.to_degrees();
    let shape = (data.joints(), data.poses().prismatic_mask());
    if crate::io::poses::look_like_radians(data.readings(), data.len(), shape, to_deg) {
        // The numbers as typed, taken as radians: what `--angle-unit rad`
        // would have read (a prismatic joint's reading, mm, as it is).
        let mask = data.poses().prismatic_mask();
        let slides = |j: usize| j < 16 && mask & (1 << j) != 0;
        let typed: Vec<f64> = (data.readings().iter().enumerate())
            .map(|(i, x)| {
                if slides(i % data.joints()) {
                    *x
                } else {
                    x * to_deg
                }
            })
            .collect();
        let as_rad =
            crate::kernel::PreparedPoses::from_flat_with(data.joints(), mask, data.len(), &typed);
        let ratio_as_rad = median_length_ratio(params, data, &as_rad)?.unwrap_or(f64::NAN);
        return Err(CalibrationError::AngleUnits {
            file: data.source().poses_file().to_string(),
            ratio,
            ratio_as_rad,
            lengths_agree: in_range(ratio_as_rad),
        });
    }
    let reach = params.reach();
    if !PLAUSIBLE_REACH_MM.contains(&reach) {
        return Err(CalibrationError::ArmUnits {
            file: arm_file.to_string(),
            reach_mm: reach,
            ratio,
        });
    }
    Err(CalibrationError::LengthUnits {
        file: data.source().reference(0).file.to_string(),
        ratio,
    })
}

/// The median over the reference lengths of stated length / the nominal
/// arm's distance between the centroids of the same points, with the
/// touches at `poses`; `None` without a finite ratio (no lengths).
fn median_length_ratio(
    params: &DhParams,
    data: &DataSet,
    poses: &crate::kernel::PreparedPoses,
) -> Result<Option<f64>, CalibrationError> {
    if data.references().is_empty() {
        return Ok(None);
    }
    let kernel = crate::kernel::ArmKernel::new(params)?;
    let mut xyz = vec![[0.0; 3]; data.len()];
    kernel.positions(poses, 0..data.len(), &mut xyz)?;
    let centroids: Vec<[f64; 3]> = data
        .points()
        .iter()
        .map(|p| crate::geometry::centroid(&xyz[p.touches.clone()]))
        .collect();
    let mut ratios: Vec<f64> = data
        .references()
        .iter()
        .map(|r| r.distance / crate::geometry::distance(&centroids[r.a], &centroids[r.b]))
        .filter(|v| v.is_finite())
        .collect();
    if ratios.is_empty() {
        return Ok(None);
    }
    ratios.sort_by(f64::total_cmp);
    Ok(Some(ratios[ratios.len() / 2]))
}

/// The ratio of the spreads of an instrument's positions and the nominal
/// arm's beyond which they are in another unit (metres: 1/1000, inches:
/// 1/25.4) or of another arm.
const POSITION_SPREAD_RATIO: f64 = 5.0;

/// The share of its spread by which the nominal arm, best registered, may
/// miss a frame's positions: more is another arm, readings in another
/// joint order or unit, or a different tool (a nominal arm misses by per
/// cent of its reach, not by a fifth).
const POSITION_MISS_SHARE: f64 = 0.2;

/// Refuses reference positions the nominal arm cannot be registered to,
/// frame by frame: positions in another unit (their spread against the
/// arm's), a mirror image (swapped axes: a mirrored registration fits much
/// better than any rotation), or positions of another arm (the best
/// registration misses by a large share of their spread). When every
/// reading, read as degrees, is within ±2π — radians read as degrees, as
/// the touch readers ask ([`crate::io::poses::look_like_radians`]) — the
/// refusal names the angle unit instead, and whether the numbers read as
/// radians fit.
fn check_positions(data: &DataSet, layout: &Layout) -> Result<(), CalibrationError> {
    let Some(positions) = data.positions() else {
        return Ok(());
    };
    let Some(refusal) = position_refusal(positions, layout.geometry())? else {
        return Ok(());
    };
    let rows = positions.rows();
    let to_deg = 1f64.to_degrees();
    let shape = (rows.joints(), rows.prismatic_mask());
    if !crate::io::poses::look_like_radians(rows.readings(), rows.len(), shape, to_deg) {
        return Err(refusal);
    }
    let as_rad =
        DataSet::from_positions(rows.revolute_scaled(to_deg), positions.file()).map_err(|e| {
            CalibrationError::Term {
                term: "positions".into(),
                message: e.to_string(),
            }
        })?;
    let fits = match as_rad.positions() {
        Some(p) => position_refusal(p, layout.geometry())?.is_none(),
        None => false,
    };
    // What reading them as degrees did, in numbers rather than the
    // refusal's guesses (another unit, another arm).
    let reg = &crate::residuals::positions::register(layout.geometry(), positions)?[0];
    Err(CalibrationError::Positions {
        file: positions.file().to_string(),
        line: rows.line(0),
        field: "q1".to_string(),
        message: format!(
            "every joint reading, read as degrees, is within ±6.28° in all {} rows: these angles \
             look like radians read as degrees, not positions in another unit — read so, the \
             nominal arm's probe spreads {:.4} mm about its centroid where the instrument saw \
             {:.4} mm; {}{}",
            rows.len(),
            reg.arm_spread_mm,
            reg.spread_mm,
            crate::calibrate::ANGLE_UNITS_REMEDY,
            if fits {
                ": read so, the nominal arm fits these positions"
            } else {
                "; read so, the nominal arm still does not fit them: check the readings' order \
                 and the positions' unit (mm) too"
            }
        ),
    })
}

/// The first frame of `positions` that the nominal arm `params` cannot be
/// registered to, as the refusal ([`check_positions`]); `None` when every
/// frame can.
fn position_refusal(
    positions: &crate::dataset::PositionData,
    params: &DhParams,
) -> Result<Option<CalibrationError>, CalibrationError> {
    let registrations = crate::residuals::positions::register(params, positions)?;
    let rows = positions.rows();
    for (f, (name, reg)) in rows.frames().iter().zip(registrations).enumerate() {
        let first = (0..rows.len()).find(|&i| rows.frame(i) == f).unwrap_or(0);
        let refuse = |field: &str, message: String| CalibrationError::Positions {
            file: positions.file().to_string(),
            line: rows.line(first),
            field: field.to_string(),
            message: format!("frame `{name}`: {message}"),
        };
        let ratio = reg.spread_mm / reg.arm_spread_mm;
        if !(1.0 / POSITION_SPREAD_RATIO..=POSITION_SPREAD_RATIO).contains(&ratio) {
            return Ok(Some(refuse(
                "x",
                format!(
                    "the positions spread {:.4} mm about their centroid, the nominal arm's \
                     {:.4} mm ({ratio:.3e} times): positions in another unit (they must be \
                     mm; metres give 1e-3) or of another arm?",
                    reg.spread_mm, reg.arm_spread_mm
                ),
            )));
        }
        if reg.mirrored_rms_mm < 0.5 * reg.rms_mm && reg.rms_mm > 0.01 * reg.spread_mm {
            return Ok(Some(refuse(
                "y",
                format!(
                    "a mirror image fits the nominal arm (RMS {:.4} mm) far better than any \
                     rotation (RMS {:.4} mm): two axes swapped, or one reversed — give x, y, z \
                     of a right-handed frame",
                    reg.mirrored_rms_mm, reg.rms_mm
                ),
            )));
        }
        if reg.rms_mm > POSITION_MISS_SHARE * reg.spread_mm {
            return Ok(Some(refuse(
                "point",
                format!(
                    "the nominal arm, best registered, misses these positions by RMS {:.4} mm \
                     over a spread of {:.4} mm: positions of another arm, joint readings in \
                     another order or unit, or another tool?",
                    reg.rms_mm, reg.spread_mm
                ),
            )));
        }
    }
    Ok(None)
}

/// Units of the values in a [`CalibrationReport`] meant for people.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Units {
    /// `mm`.
    pub lengths: String,
    /// `deg`.
    pub angles: String,
}

/// Held-out validation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HeldOut {
    /// Its poses file.
    pub data_file: String,
    /// Its lengths file.
    pub lengths_file: Option<String>,
    /// Before and after there.
    pub figures: BeforeAfter,
    /// Its frames the fit does not have, each registered on its own
    /// positions (closed form, for each arm) because the user asked
    /// (`--register-held-out`): their figures are optimistic.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub registered_on_itself: Vec<String>,
}

/// The frames of `data`'s reference positions (none without them).
fn frame_names(data: &DataSet) -> &[String] {
    data.positions().map_or(&[], |p| p.rows().frames())
}

/// The frames of held-out positions that `fitted` has none of, in order.
fn unfitted_frames<'a>(fitted: &DataSet, held: &'a DataSet) -> Vec<&'a String> {
    let have = frame_names(fitted);
    (frame_names(held).iter())
        .filter(|f| !have.contains(f))
        .collect()
}

/// Held-out positions are scored in the fitted frames of their names: a
/// frame the fit does not have would be registered on its own positions,
/// which absorbs part of the arm's error (an optimistic score), so it is
/// refused by its first line, with the fitted frames.
fn check_held_out_frames(fitted: &DataSet, held: &DataSet) -> Result<(), CalibrationError> {
    let Some(p) = held.positions() else {
        return Ok(());
    };
    let Some(frame) = unfitted_frames(fitted, held).into_iter().next() else {
        return Ok(());
    };
    let rows = p.rows();
    let first = (0..rows.len())
        .find(|&i| &rows.frames()[rows.frame(i)] == frame)
        .expect("a frame has a row");
    let have = frame_names(fitted);
    let fitted = if have.is_empty() {
        "the fit has no reference positions, so no frame".to_string()
    } else {
        format!(
            "the fitted frame{} {}",
            if have.len() == 1 { " is" } else { "s are" },
            have.iter()
                .map(|f| format!("`{f}`"))
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    Err(CalibrationError::Positions {
        file: p.file().to_string(),
        line: rows.line(first),
        field: "frame".to_string(),
        message: format!(
            "held-out frame `{frame}` was not fitted ({fitted}): its positions could only be \
             registered on themselves, which hides part of the arm's error. Name the fitted \
             frame they were measured in, fit this frame too (in --positions), or let it be \
             registered on its own positions with --register-held-out (then every output says \
             so)"
        ),
    })
}

/// Cross-validation over points.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CrossValidation {
    /// One entry per fold.
    pub folds: Vec<Fold>,
    /// Seed of the fold assignment.
    pub seed: u64,
}

/// The figures of the start and calibrated arms on the data.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Validation {
    /// On the fitted data.
    pub fitted: BeforeAfter,
    /// On held-out data.
    pub held_out: Option<HeldOut>,
    /// Cross-validation folds.
    pub cross_validation: Option<CrossValidation>,
    /// Points on reference spheres held out (`--validate-spheres`); absent
    /// without them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub held_out_spheres: Option<spheres::HeldOutSpheres>,
}

/// Everything a calibration session found: the schema of
/// `calibration.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CalibrationReport {
    /// The start arm's name.
    pub arm: String,
    /// Its file.
    pub arm_file: String,
    /// The poses file.
    pub data_file: String,
    /// The lengths file.
    pub lengths_file: Option<String>,
    /// The fixed set: `auto` or the names fixed.
    pub fix: String,
    /// The noise (internal units: rad, mm).
    pub noise: Noise,
    /// Seed of every random draw.
    pub seed: u64,
    /// Units of the parameter tables.
    pub units: Units,
    /// Touches fitted.
    pub touches: usize,
    /// Points fitted.
    pub points: usize,
    /// Reference lengths fitted.
    pub reference_lengths: usize,
    /// The reference-positions file, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub positions_file: Option<String>,
    /// Reference positions fitted.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub positions: usize,
    /// The calibration.
    pub calibration: Calibration,
    /// Before and after.
    pub validation: Validation,
    /// The readers' warnings.
    pub warnings: Vec<String>,
    /// Whether the calibration may be used, and if not, why.
    pub verdict: Verdict,
    /// The predicted position uncertainty over a sampled workspace
    /// ([`crate::plan::map`]); absent when the covariance is not finite.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uncertainty_map: Option<crate::plan::UncertaintyMap>,
    /// Points probed on reference spheres, when given: per sphere its
    /// centre, diameter and radial residuals.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spheres: Option<spheres::SphereReport>,
    /// Several tool points, when rows name them: per tool its offset ± σ
    /// and its rows' 3-D errors.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tools: Option<tools::ToolReport>,
    /// The same poses as each fitted frame's instrument sees the probe,
    /// that frame's registration included
    /// ([`crate::plan::uncertainty_map_in_frame`]); absent without frames.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub uncertainty_maps_in_frames: Vec<crate::plan::UncertaintyMap>,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

impl CalibrationReport {
    /// Whether the calibration is usable: the solver reached a confirmed
    /// minimum, the arm is the nominal arm's kind of geometry, and (unless
    /// a poor fit was accepted) the χ² test and the fitted data agree.
    pub fn is_usable(&self) -> bool {
        self.verdict.usable
    }

    /// `calibration.json`: pretty JSON and a final newline, the same bytes
    /// for the same inputs and seed.
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self)
            .expect("the report holds only strings, numbers, arrays and maps");
        s.push('\n');
        s
    }

    /// Reads a report back (the calibrated parameters are rebuilt from the
    /// estimates).
    ///
    /// # Errors
    ///
    /// The JSON error when `text` is not a report.
    pub fn from_json(text: &str) -> Result<CalibrationReport, serde_json::Error> {
        let mut r: CalibrationReport = serde_json::from_str(text)?;
        r.calibration.restore_params();
        Ok(r)
    }

    /// The calibrated arm: named `<start>-calibrated`, with the start arm's
    /// joint limits and no tolerances (those were the nominal's; the
    /// calibration's σ are in the report).
    pub fn calibrated_arm(&self, start: &Arm) -> Arm {
        Arm {
            name: format!("{}-calibrated", start.name),
            params: self.calibration.params.clone(),
            limits: start.limits.clone(),
            prior: None,
            // Drift belongs to the session, not to the arm.
            physics: match &self.calibration.physics {
                Some(p) => Box::new(Physics {
                    drift_mm_per_h: None,
                    ..p.clone()
                }),
                None => start.physics.clone(),
            },
            ball_diameter_mm: start.ball_diameter_mm,
            tools: self.calibrated_tools(start),
        }
    }

    /// The start arm's tools, each fitted one at its fitted offset (a tool
    /// no row named keeps its own).
    fn calibrated_tools(&self, start: &Arm) -> Vec<crate::io::Tool> {
        let fitted = self.calibration.tool_offsets();
        (start.tools.iter())
            .map(|t| crate::io::Tool {
                name: t.name.clone(),
                offset: (fitted.iter().find(|(n, _)| *n == t.name)).map_or(t.offset, |(_, x)| *x),
                ball_diameter_mm: t.ball_diameter_mm,
            })
            .collect()
    }

    /// The summary every front end prints: the solver, the dof, every
    /// parameter with σ, the correlations and the validation table.
    pub fn summary(&self) -> String {
        let c = &self.calibration;
        let mut t = self.summary_header();
        t += &dof_lines(c);
        t += &fit_quality_lines(c);
        let maps = self
            .uncertainty_map
            .iter()
            .chain(&self.uncertainty_maps_in_frames);
        for m in maps {
            t += &format!("Uncertainty map: {}\n", m.describe());
        }
        t += &outliers_line(c);
        t += &verdict_line(&self.verdict);
        t += &joints_line(c);
        t += &parameter_table(c);
        t += &correlations_line(c);
        t += &validation_table(&self.validation);
        if let Some(s) = &self.spheres {
            t += &s.summary();
        }
        if let Some(h) = &self.validation.held_out_spheres {
            t += &h.summary();
        }
        if let Some(s) = &self.tools {
            t += &s.summary();
        }
        t
    }

    /// The orientation noise the tool orientations were weighed with, in
    /// words; `None` without reference positions or a stated σ (only a file
    /// with orientations is weighed by it: without one the fit refuses
    /// them).
    pub fn orientation_noise(&self) -> Option<String> {
        let o = self.noise.orientation_rad?;
        self.positions_file.as_ref()?;
        Some(format!(
            "stated: σ = {}° per axis (the rows giving the tool's orientation)",
            // Rounded: the degrees given, not their trip through rad.
            (o.to_degrees() * 1e9).round() / 1e9
        ))
    }

    /// The reference positions' noise, `None` without them: the σ stated
    /// (`--position-noise`, or each row's own), or that it was estimated,
    /// with the σ the fit used; and an encoder noise stated without
    /// touches, which weighs nothing.
    pub fn position_noise(&self) -> Option<String> {
        let r = self;
        r.positions_file.as_ref()?;
        let n = r.noise;
        let d = &r.calibration.dof;
        let mut s = match (n.position_mm, n.position_mm_per_m) {
            (Some(a), Some(b)) if b > 0.0 => format!(
                "stated: σ = {a} mm + {b} mm per metre from the instrument, per coordinate (where \
                 a row states no uncertainty of its own)"
            ),
            (Some(a), _) => format!(
                "stated: σ = {a} mm per coordinate (where a row states no uncertainty of its own)"
            ),
            // Alone, positions are weighed as stated only by their own column.
            (None, _) if r.touches == 0 && !d.touch_sigma_estimated => {
                "stated: each row's own uncertainty (the file's `uncertainty` column)".to_string()
            }
            // The σ's source follows ("estimated from the fit").
            (None, _) if r.touches == 0 => "not stated".to_string(),
            (None, _) => "no --position-noise: each row's own uncertainty where the file states \
                          one, else a σ estimated from the fit"
                .to_string(),
        };
        let noun = if r.touches > 0 {
            "observation"
        } else {
            "position"
        };
        s += &format!(
            "; the fit's {noun} σ {:.4} mm ({})",
            d.touch_sigma_mm,
            if d.touch_sigma_estimated {
                "estimated from the fit"
            } else {
                "from the stated noise"
            }
        );
        if let (Some(e), 0) = (n.encoder_rad, r.touches) {
            s += &format!(
                "; encoders {} deg stated, weighing no row: a position's σ is the instrument's",
                e.to_degrees()
            );
        }
        Some(s)
    }

    /// The summary's head: what was calibrated on what, and how the solver
    /// went.
    fn summary_header(&self) -> String {
        let r = self;
        let s = &r.calibration.solver;
        let mut t = if r.touches == 0 {
            String::new()
        } else {
            format!(
                "calibrated `{}` ({}) on {}: {} touches of {} points, {} reference lengths\n",
                r.arm, r.arm_file, r.data_file, r.touches, r.points, r.reference_lengths
            )
        };
        if let Some(file) = &r.positions_file {
            let frames = r.calibration.frames().len();
            t += &format!(
                "calibrated `{}` ({}) on {file}: {} reference positions in {frames} frame{}\n",
                r.arm,
                r.arm_file,
                r.positions,
                if frames == 1 { "" } else { "s" }
            );
        }
        if let Some(noise) = r.position_noise() {
            t += &format!("Position noise: {noise}\n");
        }
        if let Some(noise) = r.orientation_noise() {
            t += &format!("Orientation noise: {noise}\n");
        }
        t += "\n";
        t += &method_lines(s);
        t += &format!(
            "Solver: {} — {} after {} iterations ({} cost and {} Jacobian evaluations); \
             cost {:.6e} -> {:.6e}\n",
            s.method.name(),
            s.stop.describe(),
            s.iterations,
            s.cost_evaluations,
            s.jacobian_evaluations,
            s.initial_cost,
            s.final_cost
        );
        t
    }

    /// `timing.json`: the wall time of every phase, ms.
    pub fn timing_json(&self, total_seconds: f64) -> String {
        #[derive(Serialize)]
        struct PhaseTime<'a> {
            name: &'a str,
            ms: f64,
        }
        #[derive(Serialize)]
        struct Timing<'a> {
            fit_ms: f64,
            total_ms: f64,
            phases: Vec<PhaseTime<'a>>,
        }
        let phases = &self.calibration.solver.phases;
        let timing = Timing {
            fit_ms: phases.iter().map(|p| p.seconds).sum::<f64>() * 1e3,
            total_ms: total_seconds * 1e3,
            phases: phases
                .iter()
                .map(|p| PhaseTime {
                    name: &p.name,
                    ms: p.seconds * 1e3,
                })
                .collect(),
        };
        let mut s = serde_json::to_string_pretty(&timing).expect("numbers and strings");
        s.push('\n');
        s
    }

    /// `calibrated.toml`: the calibrated arm, its frames, and the verdict
    /// (`[verdict]`; a refused calibration's file also opens with a comment
    /// saying so), which every reader of arm files checks
    /// ([`crate::io::verdict`]).
    pub fn calibrated_toml(&self, problem: &Problem) -> String {
        let calibrated = self.calibrated_arm(problem.arm());
        let verdict = &self.verdict;
        let header = if verdict.usable {
            ""
        } else {
            crate::io::verdict::rejected_header()
        };
        let mount = (self.calibration.mount_record().as_ref())
            .map_or_else(String::new, crate::io::frames::mount_to_toml);
        format!(
            "{header}{}{}{mount}{}",
            arm_to_toml(&calibrated, LengthUnit::Mm, AngleUnit::Deg),
            crate::io::frames::frames_to_toml(&self.calibration.frame_records()),
            crate::io::verdict::verdict_to_toml(&verdict.words(Spelling::Cli))
        )
    }
}

/// Calibrates `problem` with `solver` under `settings` (threads, seed, the
/// solvers' tolerances), validates the result on the fitted and held-out
/// data, and cross-validates when asked (each fold with the same solver's
/// method).
///
/// # Errors
///
/// The calibration's, when it cannot run (the data cannot determine the
/// free parameters, the kernel refuses the arm).
pub fn run(
    problem: &Problem,
    settings: &SolverSettings,
    solver: &dyn Solver,
    ctx: &mut Context,
) -> Result<CalibrationReport, CalibrationError> {
    let start = &problem.arm.params;
    let data = &problem.data;
    let model = &problem.model;
    let held_out = problem.held_out.as_ref().map(|h| &h.data);
    room_to_calibrate(data, held_out, problem.cross_validate.is_some(), false)?;
    let calibration = calibrate_with(problem.inputs(), settings, solver, ctx)?;
    // Each arm's frames: the start's registered to the fitted data, the
    // calibrated arm's fitted with it; held-out positions seen from the
    // same stations are scored in those frames.
    let stated = &problem.arm.physics;
    let start_frames = registered_frames(start, &*seen_by(start, stated, data)?)?;
    let frames = calibration.frames_with_mount();
    let before = ArmView {
        params: start,
        physics: stated,
        frames: &start_frames,
    };
    let after = ArmView {
        params: &calibration.params,
        physics: calibration.physics.as_ref().unwrap_or(stated),
        frames: &frames,
    };
    let fitted = before_after_of(before, after, data)?;
    let Evidence {
        spheres,
        held_out_spheres,
        tools,
    } = evidence_reports(problem, &calibration, (before, after))?;
    let held_out = match &problem.held_out {
        Some(h) => Some(HeldOut {
            data_file: h.data_file.clone(),
            lengths_file: h.lengths_file.clone(),
            figures: before_after_of(before, after, &h.data)?,
            registered_on_itself: (unfitted_frames(&problem.data, &h.data).into_iter())
                .cloned()
                .collect(),
        }),
        None => None,
    };
    // The folds are calibrations of their own: not started once cancelled,
    // and each stops with the run.
    ctx.check()?;
    let cross_validation = match problem.cross_validate {
        Some(k) => Some(CrossValidation {
            folds: cross_validate_cancellable(
                problem.inputs(),
                settings,
                solver,
                k,
                ctx.cancel_token(),
            )?,
            seed: settings.seed,
        }),
        None => None,
    };
    let s = &problem.sources;
    let verdict = verdict_of(problem, &calibration, &fitted);
    let (uncertainty_map, uncertainty_maps_in_frames) =
        map::workspace_maps(&problem.arm, data, &calibration, settings.seed);
    Ok(CalibrationReport {
        arm: problem.arm.name.clone(),
        arm_file: s.arm_file.clone(),
        data_file: s.data_file.clone(),
        lengths_file: s.lengths_file.clone(),
        fix: model.fix.describe_for(start),
        noise: model.noise,
        seed: settings.seed,
        units: Units {
            lengths: "mm".to_string(),
            angles: "deg".to_string(),
        },
        touches: data.len(),
        points: data.points().len(),
        reference_lengths: data.references().len(),
        positions_file: data.positions().map(|p| p.file().to_string()),
        positions: data.positions().map_or(0, |p| p.len()),
        calibration,
        validation: Validation {
            fitted,
            held_out,
            cross_validation,
            held_out_spheres,
        },
        warnings: s.warnings.clone(),
        verdict,
        uncertainty_map,
        spheres,
        tools,
        uncertainty_maps_in_frames,
    })
}

/// The sections of the evidence beyond touches and positions that a
/// session's problem holds, each when given.
struct Evidence {
    /// The fitted spheres'.
    spheres: Option<spheres::SphereReport>,
    /// The held-out sphere file's figures.
    held_out_spheres: Option<spheres::HeldOutSpheres>,
    /// The tool points'.
    tools: Option<tools::ToolReport>,
}

/// The sections of the evidence beyond touches and positions that
/// `problem` holds, after `calibration`: its spheres' (fitted and held
/// out) and its tool points' (each arm seeing the data as `views` say).
///
/// # Errors
///
/// The kernel's; a correction whose conditions the data lack.
fn evidence_reports(
    problem: &Problem,
    calibration: &Calibration,
    (before, after): (ArmView<'_>, ArmView<'_>),
) -> Result<Evidence, CalibrationError> {
    let layout = &problem.layout;
    let spheres = (problem.spheres.as_ref())
        .map(|t| spheres::sphere_report(t, layout, calibration))
        .transpose()?;
    let held_out_spheres = (problem.held_out_spheres.as_ref())
        .map(|t| spheres::held_out_spheres(t, layout, calibration))
        .transpose()?;
    let start = (&problem.arm.params, before, after);
    let tools = tools::tool_report(&problem.data, calibration, start)?;
    Ok(Evidence {
        spheres,
        held_out_spheres,
        tools,
    })
}

/// The summary's degrees of freedom and the σ behind the weights.
fn dof_lines(c: &Calibration) -> String {
    let d = &c.dof;
    let mut t = if d.touch_rows == 0 && d.length_rows == 0 {
        let included = match (d.rows_of("positions") > 0, d.rows_of("spheres") > 0) {
            (false, true) => "the spheres' included",
            (true, true) => "the frames' and the spheres' included",
            _ => "the frames' included",
        };
        format!(
            "Residuals: {} rows; unknowns: {} parameters ({included}); {} degrees of freedom\n",
            d.other_rows.iter().map(|r| r.rows).sum::<usize>(),
            d.free_parameters,
            d.degrees_of_freedom
        )
    } else {
        format!(
            "Residuals: {} touch rows + {} length rows; unknowns: {} parameters + {} centre \
             coordinates; {} degrees of freedom\n",
            d.touch_rows,
            d.length_rows,
            d.free_parameters,
            d.centre_coordinates,
            d.degrees_of_freedom
        )
    };
    t += &format!(
        "sigma0 = {} = {:.4} (1 when the weights are right); {} sigma {:.4} mm{}\n",
        if c.robust.is_some() {
            "robust scale (median of the standardised residuals)"
        } else {
            "sqrt(cost/dof)"
        },
        d.sigma0,
        noun(c),
        d.touch_sigma_mm,
        if d.touch_sigma_estimated {
            " (estimated from the fit)"
        } else {
            " (from the stated noise)"
        }
    );
    if !d.other_rows.is_empty() {
        let terms: Vec<String> = (d.other_rows.iter())
            .map(|r| format!("{} {} rows ({} eliminated)", r.term, r.rows, r.eliminated))
            .collect();
        t += &format!("Other residual terms (in the dof): {}\n", terms.join(", "));
    }
    t
}

/// The summary's account of the fit against the noise: the prior, the χ²
/// test, the robust fit and what the experiment can determine.
fn fit_quality_lines(c: &Calibration) -> String {
    let mut t = String::new();
    if let Some(p) = &c.prior {
        t += &format!(
            "Prior: {}; {} pseudo-observation rows (counted in the dof), prior cost {:.3}{}\n",
            p.tolerances,
            p.rows,
            p.cost,
            p.conflict().unwrap_or_default()
        );
        if !p.carried.is_empty() {
            let what: Vec<String> = p.carried.iter().map(|c| c.describe()).collect();
            t += &format!(
                "Tolerances carried onto the free partners of redundant fixed parameters (the data \
                 see only their sums; in quadrature): {}\n",
                what.join("; ")
            );
        }
    }
    if let Some(chi) = &c.checks.chi_square {
        t += &format!("Fit quality: {}\n", chi.describe());
    }
    if let Some(r) = &c.robust {
        if let Some(d) = r.describe_scale() {
            t += &format!("Fit quality: {d}\n");
        }
        t += &robust_line(r, noun(c));
    }
    if let Some(u) = &c.checks.position_uncertainty {
        t += &format!("Experiment: {}\n", u.describe());
    }
    if let Some(s) = Note::scale(c) {
        t += &format!("Scale: {}\n", s.describe(Spelling::Cli));
    }
    t
}

/// `noun`, counted: `touch(es)`, `position(s)`.
fn plural(noun: &str) -> String {
    match noun {
        "touch" => "touch(es)".to_string(),
        _ => format!("{noun}(s)"),
    }
}

/// What the observations are: touches, reference positions, points on
/// spheres, or several of them.
fn noun(c: &Calibration) -> &'static str {
    let has = |term: &str| c.dof.rows_of(term) > 0;
    match (c.dof.touch_rows > 0, has("positions"), has("spheres")) {
        (false, true, false) => "position",
        (false, false, true) => "sphere point",
        (true, false, false) | (false, false, false) => "touch",
        _ => "observation",
    }
}

/// [`noun`], or `observation` when orientations are observed too.
fn any_noun(c: &Calibration) -> &'static str {
    match c.dof.rows_of("orientations") > 0 {
        true => "observation",
        false => noun(c),
    }
}

/// What the outliers `o` are: their one kind
/// ([`crate::calibrate::checks::Outlier::noun`], `noun` for touches and
/// positions), or `observation` when they are of several.
fn outliers_noun<'a>(o: &'a [crate::calibrate::checks::Outlier], noun: &'a str) -> &'a str {
    let first = o.first().map_or(noun, |x| x.noun(noun));
    if o.iter().all(|x| x.noun(noun) == first) {
        first
    } else {
        "observation"
    }
}

/// The summary's outliers: the first 20 by `file:line`; after a screen by
/// a robust refit, that the list keeps to the touches it weighs down, and
/// how many the plain fit had beyond the threshold.
fn outliers_line(c: &Calibration) -> String {
    let o = &c.checks.outliers;
    let noun = any_noun(c);
    let threshold = c.checks.outlier_threshold;
    let screen = c.checks.outlier_screen;
    let below = crate::calibrate::robust::DOWNWEIGHTED;
    if o.is_empty() {
        return match screen {
            Some(s) => format!(
                "Outliers: none singled out: {} {} beyond {threshold:.2} sigma, none of which a \
                 robust {} refit weighs below {below} — the residuals are large overall, not a \
                 few {}\n",
                s.flagged,
                plural(noun),
                s.loss.name(),
                plural(noun)
            ),
            None => format!("Outliers: none (no {noun} beyond {threshold:.2} sigma)\n"),
        };
    }
    let shown: Vec<String> = o
        .iter()
        .take(20)
        .map(|x| {
            let kind = x.kind.as_ref().map_or(String::new(), |k| format!("{k}, "));
            format!(
                "{} (point {}, {kind}{:.1} sigma)",
                x.at, x.point, x.standardised
            )
        })
        .collect();
    let screened = screen.map_or(String::new(), |s| {
        // What the screen says of the rest: pulled by the named touches,
        // or (far outside the stated noise all the same) a wrong minimum
        // or model; else nothing.
        let far = (c.checks.chi_square.as_ref()).is_some_and(|chi| chi.far_outside());
        let why = if s.explains(c.dof.sigma0) {
            ", pulled by them"
        } else if far {
            ", and the rest stay large without them: a wrong minimum or model"
        } else {
            ""
        };
        format!(
            " that a robust {} refit weighs below {below} (of {} beyond it in this fit{why})",
            s.loss.name(),
            s.flagged
        )
    });
    format!(
        "Outliers: {} {} beyond {threshold:.2} sigma{screened} — check them (remeasure, or \
         fix the label): {}{}\n",
        o.len(),
        plural(outliers_noun(o, self::noun(c))),
        shown.join(", "),
        if o.len() > shown.len() { ", …" } else { "" }
    )
}

/// The summary's parameter table (user units), and the prior's if any.
/// The chain's joints with their types and reading units, when some joint
/// slides (a revolute arm's summary is what it always was).
///
/// ```text
/// Joints: 1 prismatic (reading mm), 2 revolute (reading deg), …
/// ```
fn joints_line(c: &Calibration) -> String {
    use crate::params::JointKind;
    if !c.joint_types.contains(&JointKind::Prismatic) {
        return String::new();
    }
    let joints: Vec<String> = (c.joint_types.iter().enumerate())
        .map(|(j, k)| format!("{} {} (reading {})", j + 1, k.name(), k.reading_unit()))
        .collect();
    format!("Joints: {}\n", joints.join(", "))
}

fn parameter_table(c: &Calibration) -> String {
    let mut t = String::from("Parameters (mm, deg; sigma = standard uncertainty, k = 1):\n");
    t += &format!(
        "  {:<8} {:<4} {:>14} {:>14} {:>12} {:>10}  {}\n",
        "name", "unit", "nominal", "calibrated", "correction", "sigma", "fixed because"
    );
    for p in c.parameters.iter().map(|p| p.user()) {
        t += &format!(
            "  {:<8} {:<4} {:>14.6} {:>14.6} {:>12.6} {:>10}  {}\n",
            p.name,
            p.unit,
            p.nominal,
            p.calibrated,
            p.correction,
            p.sigma.map_or("-".to_string(), |s| format!("{s:.6}")),
            p.fixed.as_deref().unwrap_or("")
        );
    }
    if let Some(p) = &c.prior {
        t += &prior_table(p);
    }
    if !c.auxiliary.is_empty() {
        t += if c.auxiliary.iter().any(|e| e.fixed.is_some()) {
            "Auxiliary blocks (sigma k = 1; a correction the data cannot separate is held):\n"
        } else {
            "Auxiliary blocks (every column free; sigma k = 1):\n"
        };
        // The unit column as wide as its widest unit (`µrad/(N·m)`).
        let w = (c.auxiliary.iter())
            .map(|e| e.unit.chars().count())
            .fold(4, usize::max);
        t += &format!(
            "  {:<16} {:<w$} {:>14} {:>14} {:>10}\n",
            "name", "unit", "start", "calibrated", "sigma"
        );
        for e in &c.auxiliary {
            // Why a column was held, or what its σ is of when not its
            // value (a frame's rotation: a small rotation about an axis).
            let note = match (&e.fixed, &e.sigma_of) {
                (Some(why), _) => why.clone(),
                (None, Some(of)) if e.sigma.is_some() => format!("sigma of {of}"),
                _ => String::new(),
            };
            let line = format!(
                "  {:<16} {:<w$} {:>14.6} {:>14.6} {:>10}  {note}",
                e.name,
                e.unit,
                e.start,
                e.calibrated,
                e.sigma.map_or("-".to_string(), |s| format!("{s:.6}")),
            );
            t += line.trim_end();
            t += "\n";
        }
    }
    t
}

fn correlations_line(c: &Calibration) -> String {
    if c.correlations.is_empty() {
        return "No pair of free parameters correlates with |rho| > 0.9.\n".to_string();
    }
    let mut t = String::from("Correlations |rho| > 0.9:");
    for x in &c.correlations {
        t += &format!("  {}/{} {:+.3}", x.a, x.b, x.rho);
    }
    t += "\n";
    t += &held_lines(c);
    t
}

/// The weak directions held at nominal, one line each, with the remedy.
fn held_lines(c: &Calibration) -> String {
    if c.held.is_empty() {
        return String::new();
    }
    let mut t = format!(
        "Held at nominal: {} direction(s) the data determine more than {:.0} times worse than the \
         best one (fitted, they would follow noise and model error; state tolerances for their \
         parameters — `[prior]` or --prior — to fit them):\n",
        c.held.len(),
        1.0 / crate::residuals::WEAK_RATIO
    );
    for h in &c.held {
        t += &format!("  {}\n", h.describe());
    }
    t
}

/// The summary's validation table: before and after, on the fitted data,
/// the held-out data and each cross-validation fold.
fn validation_table(v: &Validation) -> String {
    if v.fitted.before.points == 0
        && v.held_out
            .as_ref()
            .is_none_or(|h| h.figures.before.points == 0)
    {
        return position_table(v) + "\n";
    }
    let mut t = String::from(
        "\nValidation (mm): e = mean single-point error, 2s and delta_max (SPAT), length RMS/max\n",
    );
    t += &format!(
        "  {:<28} {:>8} {:>8} {:>9} {:>10} {:>10}\n",
        "data", "e", "2s", "delta_max", "len RMS", "len max"
    );
    let mut row = |name: &str, f: &Figures| {
        let opt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4}"));
        t += &format!(
            "  {:<28} {:>8.4} {:>8.4} {:>9.4} {:>10} {:>10}\n",
            name,
            f.e_mean,
            f.two_s_mean,
            f.delta_max,
            opt(f.length_rms),
            opt(f.length_max)
        );
    };
    row("fitted, before", &v.fitted.before);
    row("fitted, after", &v.fitted.after);
    if let Some(h) = &v.held_out {
        row("held out, before", &h.figures.before);
        row("held out, after", &h.figures.after);
    }
    if let Some(cv) = &v.cross_validation {
        for (i, f) in cv.folds.iter().enumerate() {
            row(
                &format!("fold {} ({} pts), before", i + 1, f.held_out.len()),
                &f.figures.before,
            );
            row(
                &format!("fold {} ({} pts), after", i + 1, f.held_out.len()),
                &f.figures.after,
            );
        }
    }
    t += &position_table(v);
    t += "\n";
    t
}

/// The validation at the reference positions, if any: the 3-D distance
/// between where each arm (its frames registered) puts the probe and where
/// the instrument saw it.
fn position_table(v: &Validation) -> String {
    let mut rows: Vec<(String, &Figures)> = vec![
        ("fitted, before".into(), &v.fitted.before),
        ("fitted, after".into(), &v.fitted.after),
    ];
    if let Some(h) = &v.held_out {
        rows.push(("held out, before".into(), &h.figures.before));
        rows.push(("held out, after".into(), &h.figures.after));
    }
    for (i, fold) in v
        .cross_validation
        .iter()
        .flat_map(|cv| &cv.folds)
        .enumerate()
    {
        rows.push((format!("fold {}, before", i + 1), &fold.figures.before));
        rows.push((format!("fold {}, after", i + 1), &fold.figures.after));
    }
    let mut t = error_table(
        &rows,
        |f| f.positions,
        "\nReference positions (mm): 3-D error |R p + t - y| per pose\n",
    );
    if let Some(h) = v
        .held_out
        .as_ref()
        .filter(|h| !h.registered_on_itself.is_empty())
    {
        t += &format!(
            "  held out: {} not fitted, registered on its own positions as asked \
             (--register-held-out): these held-out figures are optimistic\n",
            h.registered_on_itself
                .iter()
                .map(|f| format!("frame `{f}`"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    t += &error_table(
        &rows,
        |f| f.orientations,
        "\nTool orientations (deg): angle of the turn from the arm's tool frame to the one \
         seen, per pose\n",
    );
    t += &term_tables(v);
    t
}

/// The rows of `rows` whose figures have the errors `of` picks, under
/// `title` and a header; empty when none has them.
fn error_table(
    rows: &[(String, &Figures)],
    of: impl Fn(&Figures) -> Option<crate::calibrate::validate::PositionErrors>,
    title: &str,
) -> String {
    let rows = (rows.iter()).filter_map(|(name, f)| of(f).map(|p| (name.clone(), p)));
    errors_table(rows, title, "poses")
}

/// The held-out observations of each added term the folds scored (points
/// on spheres): a table per term, its `|error|` before and after per fold;
/// empty without any.
fn term_tables(v: &Validation) -> String {
    let folds = v.cross_validation.iter().flat_map(|cv| &cv.folds);
    let mut names: Vec<&str> = Vec::new();
    for t in folds.clone().flat_map(|f| &f.terms) {
        if !names.contains(&t.term.as_str()) {
            names.push(&t.term);
        }
    }
    let mut out = String::new();
    for name in names {
        let mut rows = Vec::new();
        for (i, f) in folds.clone().enumerate() {
            for t in f.terms.iter().filter(|t| t.term == name) {
                rows.push((format!("fold {}, before", i + 1), t.before));
                rows.push((format!("fold {}, after", i + 1), t.after));
            }
        }
        let what = (folds.clone().flat_map(|f| &f.terms))
            .find(|t| t.term == name)
            .map_or("", |t| t.what.as_str());
        let title = format!("\nHeld-out {what} (mm)\n");
        out += &errors_table(rows.into_iter(), &title, "count");
    }
    out
}

/// A table of error distributions `rows` (name, figures) under `title`,
/// the count column headed `count`; empty without rows.
fn errors_table(
    rows: impl Iterator<Item = (String, crate::calibrate::validate::PositionErrors)>,
    title: &str,
    count: &str,
) -> String {
    let mut t = String::new();
    for (name, p) in rows {
        if t.is_empty() {
            t += title;
            t += &format!(
                "  {:<28} {:>8} {:>8} {:>8} {:>8} {:>8}\n",
                "data", count, "mean", "RMS", "p95", "max"
            );
        }
        t += &format!(
            "  {:<28} {:>8} {:>8.4} {:>8.4} {:>8.4} {:>8.4}\n",
            name, p.count, p.mean, p.rms, p.p95, p.max
        );
    }
    t
}

/// What the method did, before the final LM's line.
fn method_lines(s: &crate::calibrate::SolverSummary) -> String {
    let mut t = String::new();
    if let Some(a) = &s.anneal {
        let o = &a.options;
        t += &format!(
            "Annealing: T0 {} mm, alpha {}, L {}, T_min {} mm, epsilon {} mm, ranges {} mm / {} deg \
             (twists) / {} deg (zeros); {} temperatures, {} energy evaluations; energy {:.4} -> \
             {:.4} mm; stopped: {}\n",
            o.t0,
            o.cooling,
            o.chain,
            o.t_min,
            o.target,
            o.step_mm,
            o.twist_step_deg,
            o.zero_step_deg,
            a.temperatures.len(),
            a.evaluations,
            a.start_energy,
            a.best_energy,
            a.stop.describe()
        );
        if let (Some(rule), Some(last)) = (&a.switch_rule, a.temperatures.last()) {
            t += &format!(
                "Switch (s0 {}, epsilon1 {}): at T = {:.3e} mm, energy {:.4} mm, after {} \
                 evaluations\n",
                rule.window, rule.epsilon, last.temperature, last.best, a.evaluations
            );
        }
    }
    if let Some(g) = &s.global {
        let searched = if g.circles.is_empty() {
            "no zero offset is free, so the start arm's LM is the search".to_string()
        } else {
            let n = g.minima.len();
            let twins = match g.twin_restarts {
                0 => String::new(),
                r => format!(", {r} restart(s) from a mirror image's zeros"),
            };
            format!(
                "{n} {} (the start arm, {} grid cell(s), {} random start(s){twins}) on the circles \
                 of {}",
                if n == 1 { "minimum" } else { "minima" },
                g.grid_starts,
                g.random_starts,
                g.circles.join(", ")
            )
        };
        t += &format!(
            "Global: {searched}; lowest cost reached {} time(s){}; stopped: {}{}\n",
            g.best_hits,
            match g.noise_level_hits {
                0 => String::new(),
                k => format!(
                    " ({k} of them at the noise level: a cost within cost/dof of the lowest and \
                     an arm within its uncertainty)"
                ),
            },
            g.stop.describe(),
            if g.sign_changes.is_empty() {
                String::new()
            } else {
                format!(
                    "; signs put in the nominal convention: {}",
                    g.sign_changes.join(", ")
                )
            }
        );
    }
    let phases: Vec<String> = s
        .phases
        .iter()
        .map(|p| {
            format!(
                "{} ({} cost, {} Jacobian)",
                p.name, p.cost_evaluations, p.jacobian_evaluations
            )
        })
        .collect();
    t += &format!("Phases: {}\n", phases.join("; "));
    t
}

/// The summary's line on a robust fit: its settings and the touches it
/// downweighted, by `file:line`.
fn robust_line(r: &crate::calibrate::RobustFit, noun: &str) -> String {
    use crate::calibrate::robust::DOWNWEIGHTED;
    let low = r.downweighted();
    let head = format!(
        "Robust: {} (k = {}), {} refit(s){}, scale {:.4}",
        r.loss.name(),
        r.scale_k,
        r.passes,
        if r.converged {
            ""
        } else {
            " (weights not settled)"
        },
        r.scale
    );
    if low.is_empty() {
        return format!("{head}; no {noun} weighed below {DOWNWEIGHTED}\n");
    }
    let shown: Vec<String> = low
        .iter()
        .take(20)
        .map(|t| format!("{} (point {}, weight {:.3})", t.at, t.point, t.weight))
        .collect();
    format!(
        "{head}; {} {} weighed below {DOWNWEIGHTED}: {}{}\n",
        low.len(),
        plural(noun),
        shown.join(", "),
        if low.len() > shown.len() { ", …" } else { "" }
    )
}

/// The summary's prior table: per free parameter with a tolerance, how much
/// of its information came from the data.
fn prior_table(p: &crate::calibrate::PriorReport) -> String {
    let mut t = String::from(
        "Prior (data share = 1 - posterior variance / prior variance; shift = correction in \
         tolerances):\n",
    );
    t += &format!(
        "  {:<8} {:<4} {:>10} {:>12} {:>10} {:>8}\n",
        "name", "unit", "tolerance", "post. sigma", "data share", "shift"
    );
    for e in &p.parameters {
        t += &format!(
            "  {:<8} {:<4} {:>10.6} {:>12.6} {:>9.1} % {:>+8.2}\n",
            e.name,
            e.unit,
            e.tolerance,
            e.posterior_sigma,
            100.0 * e.data_share,
            e.shift
        );
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{AngleUnit, parse_poses, read_lengths, write_poses};

    /// The shipped campaign (degrees), its lengths, and the nominal arm.
    fn shipped() -> (crate::io::Poses, Vec<crate::io::ReferenceLength>, Arm) {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples");
        let (poses, _) =
            crate::io::read_poses(&root.join("paper-campaign/poses.csv"), AngleUnit::Deg, None)
                .unwrap();
        let lengths = read_lengths(&root.join("paper-campaign/lengths.csv")).unwrap();
        let arm = Arm::without_limits("nominal", DhParams::paper_nominal());
        (poses, lengths, arm)
    }

    /// Radians read as degrees: the library's refusal names the angle unit
    /// (every front end's setting) and finds the lengths right once the
    /// readings are taken as radians; the lengths-unit refusal stays for
    /// lengths that are wrong.
    #[test]
    fn radians_read_as_degrees_are_refused_for_the_angle_unit() {
        let (poses, lengths, arm) = shipped();
        let mut text = Vec::new();
        write_poses(&mut text, &poses, AngleUnit::Rad).unwrap();
        let text = String::from_utf8(text).unwrap();
        let (as_deg, warnings) = parse_poses(&text, "rad.csv", AngleUnit::Deg, None).unwrap();
        assert!(
            warnings[0].message.contains("look like radians"),
            "{warnings:?}"
        );
        let data = DataSet::from_poses(&as_deg, "rad.csv")
            .unwrap()
            .with_lengths(&lengths, "l.csv")
            .unwrap();
        let e = Problem::new(arm.clone(), data, ModelOptions::default()).unwrap_err();
        match &e {
            CalibrationError::AngleUnits {
                file,
                ratio,
                ratio_as_rad,
                lengths_agree,
            } => {
                assert_eq!(file, "rad.csv");
                assert!(*ratio > LENGTH_UNIT_RATIO, "{ratio}");
                // The nominal arm is within a few mm of the true one.
                assert!((ratio_as_rad - 1.0).abs() < 0.01, "{ratio_as_rad}");
                assert!(lengths_agree);
            }
            other => panic!("not the angle unit: {other}"),
        }
        let m = e.to_string();
        for want in [
            "`--angle-unit rad`",
            "angle_unit=\"rad\"",
            "AACMM_ANGLE_RAD",
        ] {
            assert!(m.contains(want), "{want}: {m}");
        }
        // Lengths in metres with readings in degrees: still the lengths.
        let metres: Vec<_> = (lengths.iter().cloned())
            .map(|mut l| {
                l.distance /= 1000.0;
                l
            })
            .collect();
        let data = DataSet::from_poses(&poses, "p.csv")
            .unwrap()
            .with_lengths(&metres, "m.csv")
            .unwrap();
        let e = Problem::new(arm, data, ModelOptions::default()).unwrap_err();
        assert!(matches!(e, CalibrationError::LengthUnits { .. }), "{e}");
    }
}
