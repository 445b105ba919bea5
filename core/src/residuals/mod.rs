//! The open least-squares problem: residual terms on parameter blocks.
//!
//! A calibration's unknowns are columns of parameter blocks ([`blocks`]):
//! the arm's geometry first (per joint its D-H or Hayati parameters, then
//! the probe), then any auxiliary block a measurement needs (a rigid frame
//! per instrument station, a scalar, a per-joint vector), each with its own
//! names, units, local update, plausibility limits and tolerances. The
//! evidence is a list of residual terms behind one trait, [`Term`]: each
//! knows its whitened rows, its normal-equation contribution over the free
//! columns, its cost, how its weights follow the arm, what the structural
//! identifiability rules may assume of it, and (where it has them) its
//! observations' standardised residuals. The built-in ones:
//!
//! - `TouchTerm` — same-point touches, the point centres eliminated
//!   (variable projection: the normal matrix stays the size of the free
//!   columns whatever the number of points);
//! - `LengthTerm` — reference lengths between those centres;
//! - `PriorTerm` — stated tolerances as pseudo-observations.
//! - `HoldTerm` — weak directions no tolerance covers, held at nominal.
//!
//! A new kind of measurement is one new implementation of [`Term`] (and
//! its reader); the fits, the covariance, the degrees of freedom and the
//! identifiability analysis take it as they take these.
//!
//! **Touch** `i` of point `k`: `r_i = L_iᵀ (p(q_i; x) − c_k)` (3 rows),
//! whitened by its covariance `Σ_i = σ_probe² I + σ_enc² J_q J_qᵀ`
//! (`L_i L_iᵀ = A_i = Σ_i⁻¹`) — probe seating plus encoder noise carried
//! through the joint Jacobian `J_q` at the arm the fit starts from (fixed
//! during the fit, so the cost is one function). Encoder noise moves the
//! probe mostly across the arm, so the 3 × 3 weight matters; without stated
//! noise, `A_i = I/σ²`.
//!
//! **Reference length** between points `a`, `b`: `r = w_L (|c_a − c_b| −
//! L)` with `σ_L² = u_L² + uᵀ(C_a + C_b)u`, the stated uncertainty plus the
//! variance of both centroids along the unit vector `u` between them
//! (`C_k = (Σ_{i∈k} A_i)⁻¹`), or `w_L = 1/σ` from `--length-weight`.
//!
//! For fixed `x` the touch cost `Σ_i (p_i − c)ᵀA_i(p_i − c)` is least at the
//! weighted centroid `c_k = (Σ A_i)⁻¹ Σ A_i p_i`, so the centres are replaced
//! by centroids: each touch costs only its own Jacobian, and the reduced
//! matrix is exactly the Schur complement one gets by carrying the centres
//! as parameters. Per point, with `J_i` the free columns of `∂p/∂x` and
//! `S = Σ A_i`, `G = Σ A_i J_i`:
//!
//! ```text
//! JᵀJ  += Σ J_iᵀA_iJ_i − Gᵀ S⁻¹ G
//! Jᵀr  += Σ J_iᵀA_i p_i − Gᵀ c_k
//! ```
//!
//! and a length adds `w_L² gᵀg`, `g = uᵀ (J̄_a − J̄_b)`, `J̄_k = S⁻¹G`. The
//! lengths use the touch centroids (their uncertainty folded into `σ_L`)
//! rather than pulling the centres: a reference length is one scalar
//! against 3·n touch rows per point. The centres are the one block the
//! terms share: the touch term leaves them in [`Shared`] for the terms
//! after it. Degrees of freedom: `m − p` with `m` the rows of every term and
//! `p` the free columns plus every term's eliminated unknowns.

mod beyond;
pub mod blocks;
mod folds;
mod hold;
mod inverse;
mod lengths;
mod orientations;
pub mod positions;
mod prior;
mod rank3;
mod schur;
pub mod spheres;
mod sym3;
#[cfg(test)]
mod tests;
pub mod tools;
mod touches;

use serde::{Deserialize, Serialize};

use crate::error::{OptionError, check_nonnegative};
use crate::kernel::{ArmKernel, KernelError};
use crate::params::DhParams;
use crate::setting::Setting;

pub use beyond::CorrectionBlock;
pub(crate) use blocks::Mount;
pub use blocks::{
    Block, BlockId, Frame, Layout, LayoutError, MOUNT_BLOCK, Parameter, Scalar, Unit, Vector,
};
pub use folds::{HeldOutScorer, TermFold};
pub use hold::{HeldDirection, WEAK_RATIO};
pub(crate) use hold::{Hold, HoldTerm};
pub(crate) use inverse::{cholesky, cholesky_inverse, cholesky_solve};
pub(crate) use lengths::LengthTerm;
pub(crate) use orientations::{OrientationTerm, mount_start};
pub(crate) use positions::PositionTerm;
pub(crate) use prior::PriorTerm;
pub(crate) use schur::Elimination;
pub(crate) use sym3::Sym3;
pub(crate) use touches::TouchTerm;
pub use touches::point_chunks;

/// σ of a reference length whose file states none, mm.
pub const DEFAULT_LENGTH_SIGMA_MM: f64 = 0.001;

/// What is known of the measurement noise; `None` = not stated. The
/// default states no touch noise and [`DEFAULT_LENGTH_SIGMA_MM`] for
/// lengths without their own uncertainty.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Noise {
    /// σ of each encoder reading, rad.
    pub encoder_rad: Option<f64>,
    /// σ of the probe seating per axis, mm.
    pub probe_mm: Option<f64>,
    /// σ of a reference length when its file states none, mm.
    pub length_default_mm: f64,
    /// Overrides every length's weight (1/mm).
    pub length_weight: Option<f64>,
    /// σ of a reference position per coordinate where its file states none,
    /// mm: the constant part `A` of an instrument's `A + B·distance`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position_mm: Option<f64>,
    /// The part of that σ that grows with the distance from the
    /// instrument, `B`, mm per metre (a tracker's 0.006).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position_mm_per_m: Option<f64>,
    /// σ of a tool orientation seen (a positions file's `qw,qx,qy,qz`)
    /// about each axis, rad.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientation_rad: Option<f64>,
}

/// Largest σ of an encoder reading, degrees (in identification,
/// calibration and simulation alike): beyond half a turn the σ of an angle
/// means nothing, and the weights it gives vanish.
pub(crate) const MAX_ENCODER_SIGMA_DEG: f64 = 180.0;
/// [`MAX_ENCODER_SIGMA_DEG`] in rad.
pub(crate) const MAX_ENCODER_SIGMA_RAD: f64 = std::f64::consts::PI;

impl Default for Noise {
    fn default() -> Self {
        Noise {
            encoder_rad: None,
            probe_mm: None,
            length_default_mm: DEFAULT_LENGTH_SIGMA_MM,
            length_weight: None,
            position_mm: None,
            position_mm_per_m: None,
            orientation_rad: None,
        }
    }
}

impl Noise {
    /// Whether any touch noise was stated.
    pub fn stated(&self) -> bool {
        self.encoder_rad.is_some() || self.probe_mm.is_some()
    }

    /// Checks the values: each finite and `≥ 0` (a length weight `> 0`),
    /// and stated touch noise not zero on both counts.
    ///
    /// ```
    /// use aacmm_core::residuals::Noise;
    /// assert!(Noise::default().check().is_ok());
    /// let zero = Noise { encoder_rad: Some(0.0), probe_mm: Some(0.0), ..Noise::default() };
    /// assert_eq!(zero.check().unwrap_err().field(), "noise.probe_mm");
    /// let negative = Noise { probe_mm: Some(-0.01), ..Noise::default() };
    /// assert_eq!(negative.check().unwrap_err().field(), "noise.probe_mm");
    /// ```
    pub fn check(&self) -> Result<(), OptionError> {
        for (field, v) in [
            (Setting::EncoderNoise, self.encoder_rad),
            (Setting::ProbeNoise, self.probe_mm),
        ] {
            if let Some(v) = v {
                check_nonnegative(field, v, true)?;
            }
        }
        check_nonnegative(Setting::LengthUncertainty, self.length_default_mm, true)?;
        if let Some(a) = self.position_mm {
            check_nonnegative(Setting::PositionNoise, a, false)?;
        }
        if let Some(b) = self.position_mm_per_m {
            check_nonnegative(Setting::PositionNoisePerMetre, b, true)?;
            if self.position_mm.is_none() {
                return Err(OptionError::new(
                    Setting::PositionNoisePerMetre,
                    b,
                    "a distance-dependent position σ needs its constant part too (A+B/m)",
                ));
            }
        }
        if let Some(w) = self.length_weight {
            check_nonnegative(Setting::LengthWeight, w, false)?;
        }
        if let Some(o) = self.orientation_rad {
            check_nonnegative(Setting::OrientationNoise, o, false)?;
            if o > MAX_ENCODER_SIGMA_RAD {
                return Err(OptionError::new(
                    Setting::OrientationNoise,
                    crate::error::short(o),
                    format!(
                        "σ = {}° is more than {}°: beyond half a turn an orientation's σ means \
                         nothing (a tracker's 6-D target is about 0.01°)",
                        crate::error::short(o.to_degrees()),
                        MAX_ENCODER_SIGMA_DEG
                    ),
                ));
            }
        }
        if let Some(v) = self.encoder_rad
            && v > MAX_ENCODER_SIGMA_RAD
        {
            return Err(OptionError::new(
                Setting::EncoderNoise,
                crate::error::short(v),
                format!(
                    "σ = {}° is more than {}°: beyond half a turn an angle's σ means nothing \
                     (a real encoder's is 0.001–0.01°)",
                    crate::error::short(v.to_degrees()),
                    MAX_ENCODER_SIGMA_DEG
                ),
            ));
        }
        let zero = |v: Option<f64>| v.unwrap_or(0.0) == 0.0;
        if self.stated() && zero(self.encoder_rad) && zero(self.probe_mm) {
            // Named by the setting given (the probe's when both were).
            let field = if self.probe_mm.is_some() {
                Setting::ProbeNoise
            } else {
                Setting::EncoderNoise
            };
            return Err(OptionError::new(
                field,
                0,
                "encoder and probe noise both 0: a touch needs some uncertainty",
            ));
        }
        Ok(())
    }
}

/// Why a term could not be evaluated.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TermError {
    /// The kernel refused the arm or the data, or the noise gives weights
    /// that are not finite numbers.
    #[error(transparent)]
    Kernel(#[from] KernelError),
    /// A parameter block the layout cannot take.
    #[error(transparent)]
    Layout(#[from] LayoutError),
    /// The term's own inputs cannot be used as they are.
    #[error("{term}: {message}")]
    Invalid {
        /// The term's name.
        term: String,
        /// What is wrong.
        message: String,
    },
}

impl TermError {
    /// A refusal by the term `term`.
    pub(crate) fn invalid(term: &str, message: impl Into<String>) -> TermError {
        TermError::Invalid {
            term: term.to_string(),
            message: message.into(),
        }
    }
}

/// Where the terms are evaluated: every column's value and what follows
/// from it once (the arm of the geometry columns and its kernel).
pub struct At<'a> {
    /// Every column, the geometry's first (mm, rad; the layout's order).
    pub x: &'a [f64],
    /// The arm of the geometry columns.
    pub arm: &'a DhParams,
    /// Its kernel.
    pub kernel: &'a ArmKernel,
    /// Where each block's columns are.
    pub layout: &'a Layout,
    /// Worker threads a term may use (results never depend on them).
    pub threads: usize,
}

impl At<'_> {
    /// Calls `f` at the point `x` of `layout` (its arm and kernel made
    /// here, one thread): what a caller that holds only a point evaluates
    /// a term with.
    ///
    /// # Errors
    ///
    /// `f`'s; a point of another length than the layout's; the kernel's
    /// refusal of its arm.
    pub fn with<R>(
        layout: &Layout,
        x: &[f64],
        f: impl FnOnce(&At<'_>) -> Result<R, TermError>,
    ) -> Result<R, TermError> {
        let arm = (layout.arm(x))
            .filter(|_| x.len() == layout.len())
            .ok_or_else(|| {
                TermError::invalid(
                    "layout",
                    format!("a point of {} columns for {}", x.len(), layout.len()),
                )
            })?;
        let kernel = ArmKernel::new(&arm)?;
        f(&At {
            x,
            arm: &arm,
            kernel: &kernel,
            layout,
            threads: 1,
        })
    }

    /// The values of block `id`'s columns.
    pub fn block(&self, id: BlockId) -> &[f64] {
        &self.x[self.layout.columns(id)]
    }

    /// The poses `raw` (a data set's prepared readings) under `conditions`
    /// as the chain sees them with the layout's corrections at this point,
    /// and the corrections' Jacobian factors; `None` when the layout
    /// corrects nothing (the poses are the readings).
    ///
    /// # Errors
    ///
    /// A correction whose conditions were not recorded (an expansion
    /// without temperatures).
    pub(crate) fn effects(
        &self,
        raw: &crate::kernel::PreparedPoses,
        conditions: crate::corrections::Conditions<'_>,
    ) -> Result<Option<crate::corrections::Effects>, TermError> {
        self.corrected(raw, conditions, true, None)
    }

    /// [`At::effects`] of a term's own poses, their corrected readings
    /// kept in the term's `cache` between evaluations at the same point.
    ///
    /// # Errors
    ///
    /// As [`At::effects`].
    pub(crate) fn effects_in(
        &self,
        raw: &crate::kernel::PreparedPoses,
        conditions: crate::corrections::Conditions<'_>,
        cache: &crate::corrections::SeenCache,
    ) -> Result<Option<crate::corrections::Effects>, TermError> {
        self.corrected(raw, conditions, true, Some(cache))
    }

    /// [`At::corrected_poses`] with a term's `cache` ([`At::effects_in`]).
    ///
    /// # Errors
    ///
    /// As [`At::effects`].
    pub(crate) fn corrected_poses_in(
        &self,
        raw: &crate::kernel::PreparedPoses,
        conditions: crate::corrections::Conditions<'_>,
        cache: &crate::corrections::SeenCache,
    ) -> Result<Option<crate::corrections::Effects>, TermError> {
        self.corrected(raw, conditions, false, Some(cache))
    }

    /// [`At::effects`] without the Jacobian factors: what a cost needs.
    ///
    /// # Errors
    ///
    /// As [`At::effects`].
    pub(crate) fn corrected_poses(
        &self,
        raw: &crate::kernel::PreparedPoses,
        conditions: crate::corrections::Conditions<'_>,
    ) -> Result<Option<crate::corrections::Effects>, TermError> {
        self.corrected(raw, conditions, false, None)
    }

    /// The tool's position at every pose of `poses` (a term's readings;
    /// `conditions`, what was recorded with them) as this point's arm puts
    /// it, **with the layout's corrections beyond geometry applied**
    /// (compliance, harmonics, backlash, expansion, drift: as the built-in
    /// terms see the arm), into `out`, one per pose.
    ///
    /// # Errors
    ///
    /// The kernel's; a correction whose conditions were not recorded (an
    /// expansion without temperatures).
    pub fn tool_positions(
        &self,
        poses: &crate::kernel::PreparedPoses,
        conditions: crate::corrections::Conditions<'_>,
        out: &mut [[f64; 3]],
    ) -> Result<(), TermError> {
        let effects = self.corrected_poses(poses, conditions)?;
        let seen = effects.as_ref().map_or(poses, |e| &e.poses);
        self.kernel.positions(seen, 0..seen.len(), out)?;
        Ok(())
    }

    /// Calls `f(i, position, jacobian)` for every pose `i` of `range`, in
    /// order: the tool's position with the corrections applied
    /// ([`At::tool_positions`]) and its Jacobian over the arm's columns —
    /// `jacobian[c] = ∂p/∂x_c` for every column `c` below
    /// [`Layout::arm_columns`], the geometry's and then the corrections'.
    /// A term that reads the tool through this cannot forget the
    /// corrections.
    ///
    /// # Errors
    ///
    /// As [`At::tool_positions`].
    pub fn for_each_tool(
        &self,
        poses: &crate::kernel::PreparedPoses,
        conditions: crate::corrections::Conditions<'_>,
        range: std::ops::Range<usize>,
        mut f: impl FnMut(usize, &[f64; 3], &[[f64; 3]]),
    ) -> Result<(), TermError> {
        let effects = self.effects(poses, conditions)?;
        let seen = effects.as_ref().map_or(poses, |e| &e.poses);
        let mut ext = Vec::new();
        self.kernel
            .for_each_jacobian(seen, range, |i, p, jac| match &effects {
                Some(e) => {
                    e.extend(i, p, jac, &mut ext);
                    f(i, p, &ext);
                }
                None => f(i, p, jac),
            })?;
        Ok(())
    }

    /// [`At::for_each_tool`] of the tool's whole pose (its frame: position
    /// and orientation, [`crate::kernel::Pose`]) and its `6`-row Jacobian
    /// (position rows, then rotation rows) over the arm's columns, the
    /// corrections applied: what a term of 6-D targets reads.
    ///
    /// # Errors
    ///
    /// As [`At::tool_positions`].
    pub fn for_each_tool_pose(
        &self,
        poses: &crate::kernel::PreparedPoses,
        conditions: crate::corrections::Conditions<'_>,
        range: std::ops::Range<usize>,
        mut f: impl FnMut(usize, &crate::kernel::Pose, &[[f64; 6]]),
    ) -> Result<(), TermError> {
        let effects = self.effects(poses, conditions)?;
        let seen = effects.as_ref().map_or(poses, |e| &e.poses);
        let mut ext = Vec::new();
        self.kernel
            .for_each_pose_jacobian(seen, range, |i, t, jac| match &effects {
                Some(e) => {
                    e.extend_pose(i, &t.position, jac, &mut ext);
                    f(i, t, &ext);
                }
                None => f(i, t, jac),
            })?;
        Ok(())
    }

    /// [`At::effects`], with the factors of the fitted columns when
    /// `columns`, the corrected readings from `cache` when given.
    fn corrected(
        &self,
        raw: &crate::kernel::PreparedPoses,
        conditions: crate::corrections::Conditions<'_>,
        columns: bool,
        cache: Option<&crate::corrections::SeenCache>,
    ) -> Result<Option<crate::corrections::Effects>, TermError> {
        let Some((block, cols)) = self.layout.corrections() else {
            return Ok(None);
        };
        let physics = block.physics_at(&self.x[cols]);
        let none = crate::corrections::Beyond::default();
        let fit = if columns { &block.fit } else { &none };
        if fit.is_empty() && !physics.corrects() {
            return Ok(None);
        }
        crate::corrections::Effects::new_cached(self.arm, &physics, fit, raw, conditions, cache)
            .map(Some)
            .map_err(|e| TermError::invalid("beyond", e))
    }
}

/// The point centres of the same-point touches: the unknowns the touch term
/// eliminates, which later terms measure between (a reference length, an
/// artefact's certified distance).
#[derive(Clone, Debug, Default)]
pub struct Centres {
    /// Per point (data-set order), its weighted centroid, mm.
    pub points: Vec<[f64; 3]>,
    /// Per point, `∂c/∂x` over the free columns (`J̄ = S⁻¹G`), when a later
    /// term asked for it ([`Term::needs_centre_jacobians`]).
    pub jacobians: Vec<Vec<[f64; 3]>>,
}

/// What a term evaluated earlier leaves for the terms after it, in the
/// objective's order.
#[derive(Clone, Debug, Default)]
pub struct Shared {
    /// The point centres, once the touch term has run.
    pub centres: Option<Centres>,
    /// Per point, the covariance `(Σ A_i)⁻¹` of its centre under the touch
    /// weights, once the touch term has been weighed.
    pub(crate) centre_covariances: Option<Vec<Sym3>>,
    /// Whether a later term needs `∂c/∂x` of the centres.
    pub(crate) want_centre_jacobians: bool,
}

/// What the structural identifiability rules may assume of a term's data
/// ([`crate::identify`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Sees {
    /// The data change when the whole arm turns about its base axis
    /// (`theta1`): positions in a frame tied to the base do, unless they
    /// lie on a surface of revolution about that axis (a horizontal plane
    /// does not see it). Touches compared with their own centroid and
    /// distances between centroids are relative: they never see it.
    pub base_rotation: bool,
    /// The data change when the whole arm slides along its base axis
    /// (`d1`): positions along that axis do (a horizontal plane does).
    pub base_slide: bool,
    /// The data fix the arm's size (a reference length, a known plane or
    /// position): without any such term, scaling every length scales
    /// every residual.
    pub scale: bool,
}

/// The reduced normal equations at one point: `JᵀJ` and `Jᵀr` over the
/// free columns, and each term's cost `Σ r²` in the objective's order.
#[derive(Clone, Debug, PartialEq)]
pub struct Normal {
    /// Free columns, in order (indices into the full parameter vector).
    pub(crate) free: Vec<usize>,
    /// `JᵀJ`, row-major `p × p`.
    pub(crate) jtj: Vec<f64>,
    /// `Jᵀr`.
    pub(crate) jtr: Vec<f64>,
    /// `Σ r²` per term, in the objective's order.
    pub(crate) costs: Vec<f64>,
}

impl Normal {
    /// Empty normal equations over the columns `free`.
    pub fn new(free: &[usize]) -> Normal {
        let p = free.len();
        Normal {
            free: free.to_vec(),
            jtj: vec![0.0; p * p],
            jtr: vec![0.0; p],
            costs: Vec::new(),
        }
    }

    /// The free columns, in order: a term's contribution is over these.
    pub fn free(&self) -> &[usize] {
        &self.free
    }

    /// Adds one whitened residual row: `r` and its derivatives `j` over
    /// the free columns (`j[a]` for column `free()[a]`), so `JᵀJ += jjᵀ`
    /// and `Jᵀr += j·r`. The caller adds `r²` to its cost.
    ///
    /// ```
    /// let mut n = aacmm_core::residuals::Normal::new(&[3, 7]);
    /// n.add_row(&[1.0, 2.0], 0.5);
    /// assert_eq!(n.jtj_entry(0, 1), 2.0);
    /// assert_eq!(n.gradient(1), 1.0);
    /// ```
    pub fn add_row(&mut self, j: &[f64], r: f64) {
        let p = self.free.len();
        for (a, &ja) in j.iter().enumerate().take(p) {
            self.jtr[a] += ja * r;
            for (b, &jb) in j.iter().enumerate().take(p) {
                self.jtj[a * p + b] += ja * jb;
            }
        }
    }

    /// Adds whitened rows `(j, r)` ([`Normal::add_row`] each, in order) and
    /// returns their cost `Σ r²`: what a term's `accumulate` ends with.
    ///
    /// ```
    /// let mut n = aacmm_core::residuals::Normal::new(&[0]);
    /// assert_eq!(n.add_rows([(vec![2.0], 1.0), (vec![1.0], 3.0)]), 10.0);
    /// assert_eq!(n.gradient(0), 5.0);
    /// ```
    pub fn add_rows(&mut self, rows: impl IntoIterator<Item = (Vec<f64>, f64)>) -> f64 {
        let mut cost = 0.0;
        for (j, r) in rows {
            self.add_row(&j, r);
            cost += r * r;
        }
        cost
    }

    /// `(JᵀJ)_ab` over the free columns.
    pub fn jtj_entry(&self, a: usize, b: usize) -> f64 {
        self.jtj[a * self.free.len() + b]
    }

    /// `(Jᵀr)_a` over the free columns.
    pub fn gradient(&self, a: usize) -> f64 {
        self.jtr[a]
    }

    /// The whole cost `Σ r²` (a χ² when the weights are right): the terms'
    /// costs added in order.
    pub fn cost(&self) -> f64 {
        self.costs.iter().sum()
    }

    /// The normal equations over `cols`, a subset of these columns: every
    /// term is bilinear in the columns (the centres' elimination too), so
    /// the reduced system of a subset is the principal submatrix. `None`
    /// when a column is not among these.
    pub(crate) fn restrict(&self, cols: &[usize]) -> Option<Normal> {
        let at: Vec<usize> = cols
            .iter()
            .map(|c| self.free.iter().position(|f| f == c))
            .collect::<Option<_>>()?;
        let p = self.free.len();
        Some(Normal {
            free: cols.to_vec(),
            jtj: at
                .iter()
                .flat_map(|&a| at.iter().map(move |&b| self.jtj[a * p + b]))
                .collect(),
            jtr: at.iter().map(|&a| self.jtr[a]).collect(),
            costs: self.costs.clone(),
        })
    }
}

/// The free parameters' share of an observation's leverage: `N⁻¹`, the
/// inverse of the normal matrix the fit solved (at the observations'
/// current weights), over its free columns. An observation's hat-matrix
/// block is then its eliminated unknowns' part plus `A^½ J̃ N⁻¹ J̃ᵀ A^½`,
/// `J̃` its rows' Jacobian over the free columns with the eliminated
/// unknowns profiled out ([`Term::standardised`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ParameterLeverage {
    /// The normal matrix's free columns, in order.
    pub(crate) free: Vec<usize>,
    /// `N⁻¹`, row-major `p × p`.
    pub(crate) n_inv: Vec<f64>,
}

impl ParameterLeverage {
    /// From `normal`, its matrix divided by `scale` (the factor the normal
    /// equations were rescaled by without the weights: 1 when they agree);
    /// `None` when it is not positive definite (then only the eliminated
    /// unknowns' leverage is corrected).
    pub fn of(normal: &Normal, scale: f64) -> Option<ParameterLeverage> {
        let p = normal.free.len();
        let n = nalgebra::DMatrix::from_row_slice(p, p, &normal.jtj) / scale;
        ParameterLeverage::from_inverse(normal, &cholesky_inverse(&cholesky(n)?))
    }

    /// From `normal` and `inv`, its matrix's inverse (made elsewhere, by
    /// the same Cholesky); `None` when `inv` is not finite.
    pub(crate) fn from_inverse(
        normal: &Normal,
        inv: &nalgebra::DMatrix<f64>,
    ) -> Option<ParameterLeverage> {
        let p = normal.free.len();
        let n_inv: Vec<f64> = (0..p * p).map(|i| inv[(i / p, i % p)]).collect();
        n_inv
            .iter()
            .all(|v| v.is_finite())
            .then(|| ParameterLeverage {
                free: normal.free.clone(),
                n_inv,
            })
    }

    /// The columns `pairs` (free index, the Jacobian column that holds its
    /// derivative — a tool's offset block held by the probe's columns,
    /// [`tools::tool_columns`]): those Jacobian columns and their block of
    /// `N⁻¹`, row-major.
    pub(crate) fn restricted_to(&self, pairs: &[(usize, usize)]) -> (Vec<usize>, Vec<f64>) {
        let p = self.free.len();
        let block = (pairs.iter())
            .flat_map(|&(a, _)| pairs.iter().map(move |&(b, _)| self.n_inv[a * p + b]))
            .collect();
        (pairs.iter().map(|&(_, c)| c).collect(), block)
    }

    /// The normal matrix's free columns, in order.
    pub(crate) fn free(&self) -> &[usize] {
        &self.free
    }
}

/// Standardised squared residuals of a term's observations: each about
/// `χ²_k` (`k` = [`Standardised::rows`]) when it fits the noise model.
#[derive(Clone, Debug, PartialEq)]
pub struct Standardised {
    /// Rows per observation (3 for a touch).
    pub rows: usize,
    /// Per observation, `rᵀ A r / (1 − h)` with `h` its leverage.
    pub values: Vec<f64>,
}

/// Where an observation came from, for a report: `file:line` and the group
/// it belongs to (a touch's point).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Origin {
    /// `file:line`.
    pub at: String,
    /// Its group (the point's label).
    pub group: String,
}

/// What a term is to the pipeline: the built-in kinds it reports and
/// treats by kind (the touches' and lengths' rows in the degrees of
/// freedom, the prior a tolerance study replaces), or another kind of
/// evidence. A term says its role; the pipeline never compares names, so a
/// term of any name is what its role says.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Role {
    /// Same-point touches (the built-in touch term).
    Touches,
    /// Reference lengths between the touches' points.
    Lengths,
    /// Reference positions in an instrument's frame.
    Positions,
    /// Tool orientations seen in an instrument's frame (the rows of a
    /// positions file that give one).
    Orientations,
    /// Points probed on the surface of reference spheres.
    Spheres,
    /// Stated tolerances as pseudo-observations: prior knowledge, not data.
    Prior,
    /// Weak directions held at nominal: prior knowledge, not data.
    Held,
    /// Any other evidence (a term written outside the library).
    Other,
}

impl Role {
    /// Whether a term of this role is prior knowledge rather than data.
    pub fn is_prior(self) -> bool {
        matches!(self, Role::Prior | Role::Held)
    }
}

/// One kind of evidence in the least squares: whitened residual rows on the
/// parameter blocks' columns.
///
/// Implement [`Term::rows`], [`Term::accumulate`] and [`Term::add_cost`] on
/// a type that is `Clone` (a term is copied when an objective is weighed
/// elsewhere); the rest has defaults for data whose weights do not
/// depend on the arm, that fix scale and base motion as
/// [`Term::sees`] says, and that a robust loss leaves alone. A term is
/// evaluated in the objective's order: one that needs the point centres
/// (its [`Shared::centres`]) comes after the touches.
pub trait Term: dyn_clone::DynClone + Send + Sync + std::fmt::Debug {
    /// Short name, for reports: `touches`, `lengths`, `prior`, `plane`.
    /// Only words: what the pipeline does with a term follows its
    /// [`Term::role`].
    fn name(&self) -> &str;

    /// What the term is to the pipeline; [`Role::Other`] unless it is one
    /// of the built-in kinds.
    fn role(&self) -> Role {
        Role::Other
    }

    /// Whether this is prior knowledge rather than data: left out of the
    /// data's cost (the start arm's cost, the grid of the global search)
    /// and, in the covariance, not rescaled by the fit's σ̂. By default,
    /// as its role says ([`Role::is_prior`]).
    fn is_prior(&self) -> bool {
        self.role().is_prior()
    }

    /// Whitened residual rows over the free columns `free` (a prior has a
    /// row per free column it holds; data have theirs whatever is free).
    fn rows(&self, free: &[usize]) -> usize;

    /// Unknowns fitted inside the term and eliminated from the normal
    /// equations (3 per point centre), counted in the degrees of freedom.
    fn eliminated(&self) -> usize {
        0
    }

    /// What the structural identifiability rules may assume of the data.
    fn sees(&self) -> Sees {
        Sees::default()
    }

    /// Whether the term needs `∂c/∂x` of the point centres
    /// ([`Centres::jacobians`]) when accumulating.
    fn needs_centre_jacobians(&self) -> bool {
        false
    }

    /// Whether its weights are in units of an estimated σ (touch noise not
    /// stated): the fit estimates that σ from these terms' residuals and
    /// weighs them with it ([`Term::weigh`]'s `unit_sigma`).
    fn unit_weighted(&self) -> bool {
        false
    }

    /// Weighs the rows at `at` (noise carried through the arm), a term with
    /// unit weights as `unit_sigma` mm. Terms whose weights do not depend
    /// on the arm keep them.
    ///
    /// # Errors
    ///
    /// The kernel's, or weights that are not finite numbers (naming the
    /// noise that made them).
    fn weigh(
        &mut self,
        at: &At<'_>,
        shared: &mut Shared,
        unit_sigma: f64,
    ) -> Result<(), TermError> {
        let _ = (at, shared, unit_sigma);
        Ok(())
    }

    /// The largest relative change [`Term::weigh`] would make to its
    /// weights (0 when they do not depend on the arm; `∞` where it would
    /// refuse them), without keeping a second set.
    ///
    /// # Errors
    ///
    /// The kernel's.
    fn weight_change(
        &self,
        at: &At<'_>,
        shared: &mut Shared,
        unit_sigma: f64,
    ) -> Result<f64, TermError> {
        let _ = (at, shared, unit_sigma);
        Ok(0.0)
    }

    /// Adds its contribution to `normal` (over [`Normal::free`]) at `at`
    /// and returns its cost `Σ r²`.
    ///
    /// # Errors
    ///
    /// The kernel's.
    fn accumulate(
        &self,
        at: &At<'_>,
        shared: &mut Shared,
        normal: &mut Normal,
    ) -> Result<f64, TermError>;

    /// Adds its cost `Σ r²` at `at` to `total`, positions only (what a trial
    /// step costs); `free` are the columns fitted, `scratch` a buffer the
    /// caller keeps between calls.
    ///
    /// # Errors
    ///
    /// The kernel's.
    fn add_cost(
        &self,
        at: &At<'_>,
        free: &[usize],
        shared: &mut Shared,
        scratch: &mut Vec<[f64; 3]>,
        total: &mut f64,
    ) -> Result<(), TermError>;

    /// Its observations' standardised squared residuals at `at`, if it has
    /// observations a robust loss may downweight and the outlier test may
    /// name; with `leverage`, the free parameters' share of each
    /// observation's leverage corrected too (a term may ignore it).
    ///
    /// # Errors
    ///
    /// The kernel's.
    fn standardised(
        &self,
        at: &At<'_>,
        leverage: Option<&ParameterLeverage>,
    ) -> Result<Option<Standardised>, TermError> {
        let _ = (at, leverage);
        Ok(None)
    }

    /// Observations a robust loss may downweight ([`Term::standardised`]).
    fn observations(&self) -> usize {
        0
    }

    /// Where observation `i` came from.
    fn origin(&self, i: usize) -> Origin {
        Origin {
            at: format!("{} #{}", self.name(), i + 1),
            group: String::new(),
        }
    }

    /// Multiplies observation `i`'s weight by `w[i]` (a robust fit's weight
    /// in (0, 1]); `false` for a term without observations.
    fn weigh_observations(&mut self, w: &[f64]) -> bool {
        let _ = w;
        false
    }

    /// A typical σ of one coordinate of an observation, mm, under its
    /// weights (the report's touch σ), if it has one.
    fn typical_sigma(&self) -> Option<f64> {
        None
    }

    /// Its observations dealt to `k` folds for cross-validation, `at` the
    /// point the fit starts from: per fold the term over the training
    /// share (the same blocks) and a scorer of the share held out
    /// ([`TermFold`]). `seed` is the run's; a term draws from a generator
    /// of its own seeded by it. `None` (the default) when the term cannot
    /// be split: cross-validation then refuses it by its name rather than
    /// fit it whole in every fold and score it nowhere (prior knowledge
    /// needs no split: it is passed whole).
    ///
    /// # Errors
    ///
    /// `k` folds that would leave a training share unable to fix the
    /// term's own unknowns (saying why).
    fn split(&self, at: &At<'_>, k: usize, seed: u64) -> Result<Option<Vec<TermFold>>, TermError> {
        let _ = (at, k, seed);
        Ok(None)
    }
}

dyn_clone::clone_trait_object!(Term);
