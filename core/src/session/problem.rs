//! The calibration problem: the arm, the data and the settings, checked
//! once when it is made, and what a caller adds to it.

use crate::calibrate::validate::{check_folds, split_terms};
use crate::calibrate::{CalibrationError, Context, FitInputs, ModelOptions, SolverSettings};
use crate::dataset::DataSet;
use crate::domain::Arm;
use crate::error::OptionError;
use crate::params::DhParams;
use crate::residuals::spheres::SphereTerm;
use crate::residuals::{Block, BlockId, Layout, Term};

use super::checks::{check_held_out_frames, check_positions, of_arm_shape, of_arm_tools};
use super::{CalibrationReport, check_units, run};

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
    pub(super) arm: Arm,
    pub(super) data: DataSet,
    pub(super) model: ModelOptions,
    /// The columns: the arm's geometry, then the blocks added.
    pub(super) layout: Layout,
    /// Residual terms beyond the data's.
    pub(super) terms: Vec<Box<dyn Term>>,
    pub(super) held_out: Option<HeldOutData>,
    pub(super) cross_validate: Option<usize>,
    pub(super) sources: Sources,
    pub(super) truth: Option<DhParams>,
    /// Held-out positions in a frame the fit does not have may be
    /// registered on themselves ([`Problem::registering_held_out_frames`]).
    pub(super) register_held_out: bool,
    /// Points probed on reference spheres, when given
    /// ([`Problem::with_spheres`]): a term among `terms`, kept here too
    /// for its report.
    pub(super) spheres: Option<SphereTerm>,
    /// Points on reference spheres held out, to validate on
    /// ([`Problem::with_held_out_spheres`]).
    pub(super) held_out_spheres: Option<SphereTerm>,
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
    ///     Err(CalibrationError::Option(e)) => assert_eq!(e.field(), "noise.probe_mm"),
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
    ///
    /// [`HeldOut::registered_on_itself`]: super::HeldOut::registered_on_itself
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
    /// [`spheres::HeldOutSpheres`]: super::spheres::HeldOutSpheres
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
    pub(crate) fn truth(&self) -> Option<&DhParams> {
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
    pub(crate) fn held_out(&self) -> Option<&HeldOutData> {
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
