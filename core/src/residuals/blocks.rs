//! Parameter blocks: the unknowns of a calibration, in columns.
//!
//! The arm's geometry comes first, in the paper's fixed order (`a1..an,
//! d1..dn, α1..αn, θ1..θn, Bx, By, Bz`; a Hayati joint's second slot is
//! its `β`, named `hbeta…` — [`crate::params::DhParams::param_id`]), then
//! any auxiliary [`Block`]: a rigid [`Frame`] (an instrument station, an
//! artefact placement), a [`Scalar`], a [`Vector`] (one value per joint).
//! Each knows its columns' names and units, its start values, how a step
//! updates it (its manifold: a frame composes rotations rather than adding
//! angles), its stated tolerances and what makes a result implausible.

use std::ops::Range;

use nalgebra::{Matrix3, Rotation3, Vector3};

use crate::params::DhParams;

/// The unit of a column.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Unit {
    /// mm inside and in reports.
    Length,
    /// rad inside, deg in reports.
    Angle,
    /// Any other unit, as it is (its name, e.g. `rad/(N·m)`).
    Other(String),
}

impl Unit {
    /// The unit users see: `mm`, `deg`, or the other unit's name.
    pub fn name(&self) -> &str {
        match self {
            Unit::Length => "mm",
            Unit::Angle => "deg",
            Unit::Other(name) => name,
        }
    }

    /// A value (mm, rad, or as it is) in the unit users see.
    ///
    /// ```
    /// use aacmm_core::residuals::Unit;
    /// assert_eq!(Unit::Angle.to_user(std::f64::consts::PI), 180.0);
    /// assert_eq!(Unit::Length.to_user(2.5), 2.5);
    /// ```
    pub fn to_user(&self, v: f64) -> f64 {
        match self {
            Unit::Angle => v.to_degrees(),
            _ => v,
        }
    }

    /// Whether the column is an angle (the identifiability analysis scales
    /// it by the arm's reach, as it does the geometry's angles).
    pub(crate) fn is_angle(&self) -> bool {
        matches!(self, Unit::Angle)
    }
}

/// One column of a block: its name and unit.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Parameter {
    /// Its name in reports (`frame.tracker.tx`).
    pub name: String,
    /// Its unit.
    pub unit: Unit,
}

/// An auxiliary block of unknowns.
pub trait Block: dyn_clone::DynClone + Send + Sync + std::fmt::Debug {
    /// The block's name (`tracker`, `plane`).
    fn name(&self) -> &str;

    /// Its columns, in order.
    fn parameters(&self) -> Vec<Parameter>;

    /// Its start values (mm, rad, or as its units say).
    fn start(&self) -> Vec<f64>;

    /// Columns (the local update's dimension, equal to the values'). The
    /// built-in blocks say it without naming their columns: a layout asks
    /// for it whenever it finds a block's columns, in every cost (a
    /// frame's names were formatted for it, 2 % of a tracker fit).
    fn len(&self) -> usize {
        self.parameters().len()
    }

    /// Values the block stores ([`Block::start`]'s length): its ambient
    /// size. A layout keeps one column per value, so it refuses a block
    /// whose ambient and tangent sizes differ ([`LayoutError::Sizes`]); a
    /// frame stores its rotation as a rotation vector for that reason.
    fn ambient_len(&self) -> usize {
        self.len()
    }

    /// The local update's dimension ([`Block::plus`]'s `delta`,
    /// [`Block::minus`]'s result): its tangent size, the columns a fit
    /// steps (6 for a frame).
    fn tangent_len(&self) -> usize {
        self.len()
    }

    /// Whether the block has no column.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// `x ⊞ delta` into `out`: the block's local update. The default adds.
    fn plus(&self, x: &[f64], delta: &[f64], out: &mut [f64]) {
        for ((o, v), d) in out.iter_mut().zip(x).zip(delta) {
            *o = v + d;
        }
    }

    /// `y ⊟ x` into `out`: the step that takes `x` to `y`, the inverse of
    /// [`Block::plus`] (`x ⊞ (y ⊟ x) = y`, `(x ⊞ δ) ⊟ x = δ` for a small
    /// enough `δ`). The default subtracts.
    fn minus(&self, y: &[f64], x: &[f64], out: &mut [f64]) {
        for ((o, a), b) in out.iter_mut().zip(y).zip(x) {
            *o = a - b;
        }
    }

    /// Column `i`'s bounds `(low, high)`, if it has any (mm, rad, or its
    /// unit): a value no real instrument can take (a negative mass, a
    /// compliance below zero). After every step the layout **clamps** a
    /// value beyond a bound onto it ([`Layout::plus`]), rather than
    /// refusing the step: a solver's trial step that overshoots is then
    /// still a point it can evaluate, and the fit ends on the bound if the
    /// data pull it there — [`Layout::on_bounds`] names such columns, so
    /// that a result on its bound is said to be one.
    fn bounds(&self, i: usize) -> Option<(f64, f64)> {
        let _ = i;
        None
    }

    /// The stated tolerance (1σ) of column `i`, if any: a prior row.
    fn tolerance(&self, i: usize) -> Option<f64> {
        let _ = i;
        None
    }

    /// Why the values `x` are implausible against the start values (a
    /// result no real instrument could have), if they are: a sentence that
    /// names the block or its column.
    fn implausible(&self, start: &[f64], x: &[f64]) -> Option<String> {
        let _ = (start, x);
        None
    }

    /// What column `i`'s standard uncertainty is of, when not of its value:
    /// the fit's covariance is that of the local update ([`Block::plus`]),
    /// which the default update (adding) makes the values'. A frame's
    /// rotation columns are a rotation vector and their update a small
    /// rotation about the frame's axes ([`Frame`]).
    fn sigma_of(&self, i: usize) -> Option<String> {
        let _ = i;
        None
    }
}

dyn_clone::clone_trait_object!(Block);

/// Which auxiliary block: its place in the layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BlockId(usize);

/// Why a block cannot join a layout.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum LayoutError {
    /// The corrections beyond geometry come right after the geometry (a
    /// pose's Jacobian over the arm is the chain's columns, then theirs),
    /// once.
    #[error(
        "block `{block}`: the corrections beyond geometry must be the layout's first block, \
         and only one"
    )]
    CorrectionsNotFirst {
        /// The block refused.
        block: String,
    },
    /// Two blocks of one name: the name finds a block.
    #[error("block `{block}`: the layout already has a block of that name")]
    Duplicate {
        /// The block refused.
        block: String,
    },
    /// A block whose values, columns and steps are not of one size.
    #[error(
        "block `{block}`: {values} start values, {ambient} stored and {tangent} step columns, \
         {names} names: the layout keeps one column per value"
    )]
    Sizes {
        /// The block refused.
        block: String,
        /// Its start values.
        values: usize,
        /// Its ambient size.
        ambient: usize,
        /// Its tangent size.
        tangent: usize,
        /// Its columns' names.
        names: usize,
    },
    /// A bound that is not an interval of numbers, or a start outside it.
    #[error("block `{block}`, column {column}: {why}")]
    Bounds {
        /// The block refused.
        block: String,
        /// The column's name.
        column: String,
        /// What is wrong.
        why: String,
    },
}

/// Where every column is: the geometry's, then each auxiliary block's.
#[derive(Clone, Debug)]
pub struct Layout {
    geometry: DhParams,
    blocks: Vec<Box<dyn Block>>,
    /// First column of each block.
    starts: Vec<usize>,
    /// The corrections beyond geometry, when the first block is them.
    corrections: Option<super::CorrectionBlock>,
    /// Blocks held at their start values (no column of theirs is fitted).
    held: Vec<BlockId>,
}

impl Layout {
    /// The columns of the arm `geometry` (its joints' models decide the
    /// names) and no auxiliary block.
    pub fn new(geometry: DhParams) -> Layout {
        Layout {
            geometry,
            blocks: Vec::new(),
            starts: Vec::new(),
            corrections: None,
            held: Vec::new(),
        }
    }

    /// Appends `block`'s columns; returns where they are.
    ///
    /// ```
    /// use aacmm_core::residuals::{Frame, Layout, LayoutError};
    /// let mut layout = Layout::new(aacmm_core::DhParams::paper_nominal());
    /// layout.add(Box::new(Frame::identity("tracker"))).unwrap();
    /// let twice = layout.add(Box::new(Frame::identity("tracker")));
    /// assert!(matches!(twice, Err(LayoutError::Duplicate { .. })));
    /// ```
    ///
    /// # Errors
    ///
    /// A name already in the layout, sizes that disagree (start values,
    /// names, ambient and tangent sizes), bounds that are not an interval
    /// or do not hold the start.
    pub fn add(&mut self, block: Box<dyn Block>) -> Result<BlockId, LayoutError> {
        check_block(&*block)?;
        if self.block_named(block.name()).is_some() {
            return Err(LayoutError::Duplicate {
                block: block.name().to_string(),
            });
        }
        self.starts.push(self.len());
        self.blocks.push(block);
        Ok(BlockId(self.blocks.len() - 1))
    }

    /// Adds the corrections beyond geometry: the layout's first block, read
    /// by every term that moves the tool ([`super::At::effects`]).
    ///
    /// # Errors
    ///
    /// Another block already in the layout (the corrections' columns come
    /// right after the geometry's), and [`Layout::add`]'s.
    pub(crate) fn add_corrections(
        &mut self,
        block: super::CorrectionBlock,
    ) -> Result<BlockId, LayoutError> {
        if !self.blocks.is_empty() {
            return Err(LayoutError::CorrectionsNotFirst {
                block: block.name().to_string(),
            });
        }
        let id = self.add(Box::new(block.clone()))?;
        self.corrections = Some(block);
        Ok(id)
    }

    /// Holds block `id` at its start values: none of its columns is fitted
    /// (the fit's free columns leave them out, and the report says they
    /// were held and why). A known instrument pose, a plane whose offset
    /// was measured elsewhere.
    pub(crate) fn hold(&mut self, id: BlockId) {
        if !self.held.contains(&id) {
            self.held.push(id);
        }
    }

    /// The columns of the blocks held at their start ([`Layout::hold`]),
    /// in order.
    pub(crate) fn held_columns(&self) -> Vec<usize> {
        let mut cols: Vec<usize> = self.held.iter().flat_map(|&id| self.columns(id)).collect();
        cols.sort_unstable();
        cols
    }

    /// The columns of `x` that sit on one of their bounds
    /// ([`Block::bounds`]): name and value.
    pub fn on_bounds(&self, x: &[f64]) -> Vec<(String, f64)> {
        let mut out = Vec::new();
        for (b, block) in self.blocks.iter().enumerate() {
            for (i, p) in block.parameters().into_iter().enumerate() {
                let c = self.starts[b] + i;
                if let (Some((lo, hi)), Some(&v)) = (block.bounds(i), x.get(c))
                    && (v <= lo || v >= hi)
                {
                    out.push((p.name, v));
                }
            }
        }
        out
    }

    /// The start arm: the geometry's models and start values.
    pub fn geometry(&self) -> &DhParams {
        &self.geometry
    }

    /// The geometry's columns (`4n + 3`).
    pub fn geometry_columns(&self) -> usize {
        self.geometry.param_count()
    }

    /// Every column.
    pub fn len(&self) -> usize {
        self.geometry_columns() + self.blocks.iter().map(|b| b.len()).sum::<usize>()
    }

    /// Whether there is no column (never: an arm has its geometry).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The corrections beyond geometry and their columns, if the layout
    /// has them (always its first block: right after the geometry, so that
    /// a pose's Jacobian over the arm is the chain's columns and then
    /// theirs).
    pub fn corrections(&self) -> Option<(&super::CorrectionBlock, Range<usize>)> {
        let block = self.corrections.as_ref()?;
        Some((block, self.columns(BlockId(0))))
    }

    /// Columns that move the arm's positions: the geometry's and the
    /// corrections'.
    pub fn arm_columns(&self) -> usize {
        self.geometry_columns() + self.corrections().map_or(0, |(_, c)| c.len())
    }

    /// The auxiliary blocks, in order.
    pub fn blocks(&self) -> impl Iterator<Item = &dyn Block> {
        self.blocks.iter().map(|b| &**b)
    }

    /// The auxiliary block named `name`, if any.
    pub(crate) fn block_named(&self, name: &str) -> Option<BlockId> {
        self.blocks
            .iter()
            .position(|b| b.name() == name)
            .map(BlockId)
    }

    /// The columns of block `id`.
    pub fn columns(&self, id: BlockId) -> Range<usize> {
        let start = self.starts[id.0];
        start..start + self.blocks[id.0].len()
    }

    /// The block and its index of column `c` beyond the geometry.
    fn block_of(&self, c: usize) -> Option<(usize, usize)> {
        let b = self.starts.partition_point(|&s| s <= c).checked_sub(1)?;
        let i = c - self.starts[b];
        (i < self.blocks[b].len()).then_some((b, i))
    }

    /// Every column's start value: the geometry's, then each block's.
    pub fn start(&self) -> Vec<f64> {
        let mut x = self.geometry.to_vec();
        for b in &self.blocks {
            x.extend(b.start());
        }
        x
    }

    /// The arm of `x`'s geometry columns.
    pub fn arm(&self, x: &[f64]) -> Option<DhParams> {
        self.geometry.with_values(x.get(..self.geometry_columns())?)
    }

    /// Column `c`'s name and unit.
    pub fn parameter(&self, c: usize) -> Option<Parameter> {
        if c < self.geometry_columns() {
            let id = self.geometry.param_id(c)?;
            let unit = if id.kind.is_length() {
                Unit::Length
            } else {
                Unit::Angle
            };
            return Some(Parameter {
                name: id.to_string(),
                unit,
            });
        }
        let (b, i) = self.block_of(c)?;
        self.blocks[b].parameters().into_iter().nth(i)
    }

    /// What column `c`'s standard uncertainty is of, when not of its value
    /// ([`Block::sigma_of`]).
    pub(crate) fn sigma_of(&self, c: usize) -> Option<String> {
        if c < self.geometry_columns() {
            return None;
        }
        let (b, i) = self.block_of(c)?;
        self.blocks[b].sigma_of(i)
    }

    /// `x` moved by `delta` over the columns `free` (`delta[k]` for column
    /// `free[k]`): the geometry's columns add, each auxiliary block takes
    /// its own local update (its fixed columns a zero step), and a value
    /// beyond its column's bounds is clamped onto them ([`Block::bounds`]).
    pub fn plus(&self, x: &[f64], free: &[usize], delta: &[f64]) -> Vec<f64> {
        let mut out = x.to_vec();
        let geometry = self.geometry_columns();
        let mut aux = false;
        for (&c, &d) in free.iter().zip(delta) {
            if c < geometry {
                out[c] += d;
            } else {
                aux = true;
            }
        }
        if !aux {
            return out;
        }
        for (b, block) in self.blocks.iter().enumerate() {
            let cols = self.starts[b]..self.starts[b] + block.len();
            let mut step = vec![0.0; block.len()];
            let mut moved = false;
            for (&c, &d) in free.iter().zip(delta) {
                if cols.contains(&c) {
                    step[c - cols.start] = d;
                    moved = true;
                }
            }
            if moved {
                block.plus(&x[cols.clone()], &step, &mut out[cols.clone()]);
                for (i, v) in out[cols].iter_mut().enumerate() {
                    if let Some((lo, hi)) = block.bounds(i) {
                        *v = v.clamp(lo, hi);
                    }
                }
            }
        }
        out
    }
}

/// A block's sizes agree, and its bounds are intervals holding its start.
fn check_block(block: &dyn Block) -> Result<(), LayoutError> {
    let start = block.start();
    let names = block.parameters();
    let (ambient, tangent) = (block.ambient_len(), block.tangent_len());
    if [start.len(), names.len(), ambient, tangent]
        .iter()
        .any(|&n| n != block.len())
    {
        return Err(LayoutError::Sizes {
            block: block.name().to_string(),
            values: start.len(),
            ambient,
            tangent,
            names: names.len(),
        });
    }
    for (i, (p, &v)) in names.iter().zip(&start).enumerate() {
        let Some((lo, hi)) = block.bounds(i) else {
            continue;
        };
        let why = if lo.is_nan() || hi.is_nan() || lo >= hi {
            format!("bounds {lo}..{hi} are not an interval")
        } else if !(lo..=hi).contains(&v) {
            format!("starts at {v}, outside its bounds {lo}..{hi}")
        } else {
            continue;
        };
        return Err(LayoutError::Bounds {
            block: block.name().to_string(),
            column: p.name.clone(),
            why,
        });
    }
    Ok(())
}

/// One unknown number: a plane's offset, a scale, a compliance.
#[derive(Clone, Debug, PartialEq)]
pub struct Scalar {
    /// Its name.
    pub name: String,
    /// Its unit.
    pub unit: Unit,
    /// Its start value.
    pub start: f64,
    /// Its stated tolerance (1σ), if any.
    pub tolerance: Option<f64>,
    /// The largest move from the start a real instrument could make, if
    /// any: a result beyond it is implausible (a unit mistake, a wrong
    /// minimum), whatever its residuals.
    pub limit: Option<f64>,
}

impl Block for Scalar {
    fn name(&self) -> &str {
        &self.name
    }

    fn parameters(&self) -> Vec<Parameter> {
        vec![Parameter {
            name: self.name.clone(),
            unit: self.unit.clone(),
        }]
    }

    fn len(&self) -> usize {
        1
    }

    fn start(&self) -> Vec<f64> {
        vec![self.start]
    }

    fn tolerance(&self, _i: usize) -> Option<f64> {
        self.tolerance
    }

    fn implausible(&self, start: &[f64], x: &[f64]) -> Option<String> {
        let limit = self.limit?;
        let moved = x[0] - start[0];
        (moved.abs() > limit).then(|| {
            let u = |v: f64| self.unit.to_user(v);
            format!(
                "{} moved by {:.4} {} (more than ±{})",
                self.name,
                u(moved),
                self.unit.name(),
                u(limit)
            )
        })
    }
}

/// Named numbers of one unit: one per joint (encoder harmonics, joint
/// compliances), or any fixed count.
#[derive(Clone, Debug, PartialEq)]
pub struct Vector {
    /// The block's name.
    pub name: String,
    /// Per column, its name.
    pub names: Vec<String>,
    /// Their unit.
    pub unit: Unit,
    /// Per column, its start value.
    pub start: Vec<f64>,
    /// Per column, its stated tolerance, if any.
    pub tolerances: Vec<Option<f64>>,
}

impl Block for Vector {
    fn name(&self) -> &str {
        &self.name
    }

    fn parameters(&self) -> Vec<Parameter> {
        self.names
            .iter()
            .map(|name| Parameter {
                name: name.clone(),
                unit: self.unit.clone(),
            })
            .collect()
    }

    fn len(&self) -> usize {
        self.names.len()
    }

    fn start(&self) -> Vec<f64> {
        self.start.clone()
    }

    fn tolerance(&self, i: usize) -> Option<f64> {
        self.tolerances.get(i).copied().flatten()
    }
}

/// A rigid transform `p ↦ R p + t` (an instrument's frame in the arm's base
/// frame, an artefact's placement): values `[rx, ry, rz, tx, ty, tz]`, the
/// rotation vector (rad) of `R` and the translation (mm). A step `δ` turns
/// the frame by `exp(δω)` on the left and moves it by `δt`, so the
/// Jacobian of [`Frame::jacobian`] is with respect to that local step and
/// no angle of the chart ever wraps.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// The frame's name (`tracker`, `placement 2`).
    pub name: String,
    /// Start values `[rx, ry, rz, tx, ty, tz]` (rad, mm).
    pub start: [f64; 6],
}

/// `R = exp([ω]×)` (Rodrigues).
///
/// nalgebra's rotations carry it (products, points turned, inverses), but
/// the map itself is written here: `Rotation3::new` evaluates
/// `cos θ + (1 − cos θ) u²` on the unit axis where this evaluates
/// `1 − b θ²(1 − u²)`, and 80 % of random rotations then differ in their
/// last bit — every frame fitted to reference positions would change its
/// last digits, and with it every figure of such a calibration.
pub(crate) fn rotation(w: [f64; 3]) -> Rotation3<f64> {
    let th = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
    // sin θ/θ and (1 − cos θ)/θ² by their series near 0.
    let (a, b) = if th < 1e-6 {
        (1.0 - th * th / 6.0, 0.5 - th * th / 24.0)
    } else {
        (th.sin() / th, (1.0 - th.cos()) / (th * th))
    };
    let [x, y, z] = w;
    Rotation3::from_matrix_unchecked(Matrix3::new(
        1.0 - b * (y * y + z * z),
        -a * z + b * x * y,
        a * y + b * x * z,
        a * z + b * x * y,
        1.0 - b * (x * x + z * z),
        -a * x + b * y * z,
        -a * y + b * x * z,
        a * x + b * y * z,
        1.0 - b * (x * x + y * y),
    ))
}

/// The rotation vector of `R` (angle in [0, π]).
///
/// Not nalgebra's `scaled_axis`: it takes the angle from the arccosine of
/// the trace, which loses half the digits near the identity (a rotation of
/// 1e-5 rad comes back 4e-8 off relative, one of 1e-7 rad 1 % off), where
/// a fitted frame's step always is. This takes the angle's sine from the
/// antisymmetric part, exact to rounding at every angle.
pub(crate) fn rotation_vector(r: &Rotation3<f64>) -> [f64; 3] {
    let r = r.matrix();
    let trace = r[(0, 0)] + r[(1, 1)] + r[(2, 2)];
    let c = ((trace - 1.0) / 2.0).clamp(-1.0, 1.0);
    let th = c.acos();
    let v = [
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    ];
    if th < 1e-6 {
        // sin θ ≈ θ: v = 2 sin θ · axis.
        return v.map(|x| x / 2.0);
    }
    if th < std::f64::consts::PI - 1e-6 {
        let k = th / (2.0 * th.sin());
        return v.map(|x| x * k);
    }
    // θ ≈ π: the axis from the diagonal of R = 2 a aᵀ − I.
    let d = [r[(0, 0)], r[(1, 1)], r[(2, 2)]];
    let i = (0..3).max_by(|&a, &b| d[a].total_cmp(&d[b])).unwrap_or(0);
    let mut a = [0.0; 3];
    a[i] = ((d[i] + 1.0) / 2.0).max(0.0).sqrt();
    for j in (0..3).filter(|&j| j != i) {
        a[j] = (r[(i, j)] + r[(j, i)]) / (4.0 * a[i]);
    }
    a.map(|x| x * th)
}

impl Frame {
    /// A frame named `name` starting at the identity.
    pub fn identity(name: impl Into<String>) -> Frame {
        Frame {
            name: name.into(),
            start: [0.0; 6],
        }
    }

    /// `R p + t` for the values `x`.
    ///
    /// ```
    /// use aacmm_core::residuals::Frame;
    /// let quarter = [0.0, 0.0, std::f64::consts::FRAC_PI_2, 10.0, 0.0, 0.0];
    /// let p = Frame::apply(&quarter, [1.0, 0.0, 0.0]);
    /// assert!((p[0] - 10.0).abs() < 1e-12 && (p[1] - 1.0).abs() < 1e-12);
    /// ```
    pub fn apply(x: &[f64], p: [f64; 3]) -> [f64; 3] {
        let y = Frame::rotation(x) * Vector3::from(p) + Vector3::new(x[3], x[4], x[5]);
        y.into()
    }

    /// `R` of the values `x` (`[rx, ry, rz, …]`, rad).
    ///
    /// ```
    /// use aacmm_core::residuals::Frame;
    /// let r = Frame::rotation(&[0.0, 0.0, std::f64::consts::FRAC_PI_2]);
    /// assert!((r * nalgebra::Vector3::x() - nalgebra::Vector3::y()).norm() < 1e-15);
    /// ```
    pub fn rotation(x: &[f64]) -> Rotation3<f64> {
        rotation([x[0], x[1], x[2]])
    }

    /// A tool pose seen in the frame of values `x`: its orientation turned
    /// by `R`, its position `R p + t`.
    ///
    /// ```
    /// use aacmm_core::{kernel::Pose, residuals::Frame};
    /// let quarter = [0.0, 0.0, std::f64::consts::FRAC_PI_2, 10.0, 0.0, 0.0];
    /// let tool = Pose { rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], position: [1.0, 0.0, 0.0] };
    /// let seen = Frame::apply_pose(&quarter, &tool);
    /// assert!((seen.rotation[1][0] - 1.0).abs() < 1e-12); // its x axis along the frame's y
    /// assert_eq!(seen.position, Frame::apply(&quarter, tool.position));
    /// ```
    pub fn apply_pose(x: &[f64], pose: &crate::kernel::Pose) -> crate::kernel::Pose {
        let r = rotation([x[0], x[1], x[2]]);
        let m = pose.rotation;
        // Row i of R·M: rows of the kernel's matrix are `rotation[row][col]`.
        let rotation = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).map(|k| r[(i, k)] * m[k][j]).sum())
        });
        crate::kernel::Pose {
            rotation,
            position: Frame::apply(x, pose.position),
        }
    }

    /// `∂(R p + t)/∂δ` for the local step `δ = [δω, δt]` at `x`: row `i` is
    /// the derivative of coordinate `i`, `[−[Rp]× | I]`.
    pub fn jacobian(x: &[f64], p: [f64; 3]) -> [[f64; 6]; 3] {
        let q = Frame::rotation(x) * Vector3::from(p);
        // δω × q = −[q]× δω.
        [
            [0.0, q[2], -q[1], 1.0, 0.0, 0.0],
            [-q[2], 0.0, q[0], 0.0, 1.0, 0.0],
            [q[1], -q[0], 0.0, 0.0, 0.0, 1.0],
        ]
    }
}

impl Frame {
    /// The local step `δ = [δω, δt]` that takes the frame `a` to `b`
    /// (`b = a ⊞ δ`): `δω = log(R_b R_aᵀ)`, `δt = t_b − t_a` — the
    /// coordinates a fitted frame's covariance is in.
    ///
    /// ```
    /// use aacmm_core::residuals::Frame;
    /// let a = [0.3, -0.2, 1.0, 5.0, 0.0, 0.0];
    /// let d = Frame::difference(&a, &a);
    /// assert!(d.iter().all(|v| v.abs() < 1e-12));
    /// ```
    pub fn difference(a: &[f64], b: &[f64]) -> [f64; 6] {
        let w = rotation_vector(&(Frame::rotation(b) * Frame::rotation(a).inverse()));
        [w[0], w[1], w[2], b[3] - a[3], b[4] - a[4], b[5] - a[5]]
    }
}

impl Block for Frame {
    fn name(&self) -> &str {
        &self.name
    }

    fn parameters(&self) -> Vec<Parameter> {
        ["rx", "ry", "rz", "tx", "ty", "tz"]
            .iter()
            .enumerate()
            .map(|(i, c)| Parameter {
                name: format!("{}.{c}", self.name),
                unit: if i < 3 { Unit::Angle } else { Unit::Length },
            })
            .collect()
    }

    fn len(&self) -> usize {
        6
    }

    fn start(&self) -> Vec<f64> {
        self.start.to_vec()
    }

    /// The rotation's columns hold the rotation vector, but the fit steps
    /// (and its covariance is of) a small rotation `δω` about the frame's
    /// own axes, `R ← exp(δω) R`: not the same thing as a change of the
    /// vector's components (the two agree only at the identity).
    fn sigma_of(&self, i: usize) -> Option<String> {
        let axis = ["x", "y", "z"].get(i)?;
        Some(format!(
            "a small rotation about {}'s {axis} axis",
            self.name
        ))
    }

    /// `δω = log(R_y R_xᵀ)`, `δt = t_y − t_x` ([`Frame::difference`]).
    fn minus(&self, y: &[f64], x: &[f64], out: &mut [f64]) {
        out[..6].copy_from_slice(&Frame::difference(x, y));
    }

    /// `R ← exp(δω) R`, `t ← t + δt`.
    fn plus(&self, x: &[f64], delta: &[f64], out: &mut [f64]) {
        turn_left(x, delta, out);
        for i in 3..6 {
            out[i] = x[i] + delta[i];
        }
    }
}

/// The name of the tool mount's block (`Mount`).
pub const MOUNT_BLOCK: &str = "mount";

/// How a 6-D target (a tracker's, a motion-capture rigid body) is mounted
/// on the arm: the rotation `R_m` from the target's frame to the arm's last
/// frame, so that the target is seen turned by `R_f R_last R_m`. Its
/// columns `mount.rx … mount.rz` hold the rotation vector (rad; deg in
/// reports); a step `δ` turns it by `exp(δ)` on the left, `R_m ← exp(δ)
/// R_m` — a small rotation about the arm's last frame's axes, which is what
/// its σ is of. Added to a layout only when some position gives the tool's
/// orientation ([`crate::residuals::positions::layout_with`]).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Mount {
    /// Start values `[rx, ry, rz]` (rad).
    pub start: [f64; 3],
}

impl Block for Mount {
    fn name(&self) -> &str {
        MOUNT_BLOCK
    }

    fn parameters(&self) -> Vec<Parameter> {
        ["rx", "ry", "rz"]
            .iter()
            .map(|c| Parameter {
                name: format!("{MOUNT_BLOCK}.{c}"),
                unit: Unit::Angle,
            })
            .collect()
    }

    fn len(&self) -> usize {
        3
    }

    fn start(&self) -> Vec<f64> {
        self.start.to_vec()
    }

    /// As a frame's rotation: the step is a small rotation, about the arm's
    /// last frame's axes.
    fn sigma_of(&self, i: usize) -> Option<String> {
        let axis = ["x", "y", "z"].get(i)?;
        Some(format!(
            "a small rotation about the arm's last frame's {axis} axis"
        ))
    }

    /// `δ = log(R_y R_xᵀ)`.
    fn minus(&self, y: &[f64], x: &[f64], out: &mut [f64]) {
        let d = rotation_vector(&(Frame::rotation(y) * Frame::rotation(x).inverse()));
        out[..3].copy_from_slice(&d);
    }

    /// `R ← exp(δ) R`.
    fn plus(&self, x: &[f64], delta: &[f64], out: &mut [f64]) {
        turn_left(x, delta, out);
    }
}

/// The rotation vector of `exp(δ) R` into `out[..3]`, for the rotation
/// vectors `x[..3]` of `R` and `delta[..3]` of `δ`: a frame's and a
/// mount's step.
fn turn_left(x: &[f64], delta: &[f64], out: &mut [f64]) {
    let r = Frame::rotation(delta) * Frame::rotation(x);
    out[..3].copy_from_slice(&rotation_vector(&r));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The built-in blocks' column counts, said without naming the
    /// columns, are their names' and their start values' counts.
    #[test]
    fn the_blocks_count_their_columns_as_they_name_them() {
        let scalar = Scalar {
            name: "scale".into(),
            unit: Unit::Length,
            start: 1.0,
            tolerance: None,
            limit: None,
        };
        let vector = Vector {
            name: "c".into(),
            names: vec!["c1".into(), "c2".into(), "c3".into()],
            unit: Unit::Angle,
            start: vec![0.0; 3],
            tolerances: vec![None; 3],
        };
        let blocks: [&dyn Block; 4] = [
            &scalar,
            &vector,
            &Frame::identity("tracker"),
            &Mount { start: [0.0; 3] },
        ];
        for block in blocks {
            assert_eq!(block.len(), block.parameters().len(), "{}", block.name());
            assert_eq!(block.len(), block.start().len(), "{}", block.name());
        }
    }

    /// The frame's Jacobian is the derivative of `apply` along its own
    /// local update, at frames near the identity and turned by more than a
    /// right angle.
    #[test]
    fn the_frame_jacobian_follows_its_local_update() {
        let frame = Frame::identity("f");
        let p = [120.0, -40.0, 300.0];
        for x in [
            [0.0; 6],
            [0.3, -0.2, 0.1, 5.0, -7.0, 2.0],
            [1.9, 0.4, -1.2, 100.0, 0.0, -50.0],
        ] {
            let j = Frame::jacobian(&x, p);
            for k in 0..6 {
                let h = 1e-6;
                let (mut up, mut down) = ([0.0; 6], [0.0; 6]);
                let (mut d_up, mut d_down) = ([0.0; 6], [0.0; 6]);
                d_up[k] = h;
                d_down[k] = -h;
                frame.plus(&x, &d_up, &mut up);
                frame.plus(&x, &d_down, &mut down);
                let (a, b) = (Frame::apply(&up, p), Frame::apply(&down, p));
                for i in 0..3 {
                    let numeric = (a[i] - b[i]) / (2.0 * h);
                    assert!(
                        (numeric - j[i][k]).abs() < 1e-5 * (1.0 + j[i][k].abs()),
                        "x {x:?}, column {k}, row {i}: {numeric} vs {}",
                        j[i][k]
                    );
                }
            }
        }
    }

    /// The rotation vector of `exp(ω)` is `ω` for every angle up to π.
    #[test]
    fn rotation_vectors_round_trip() {
        for w in [
            [0.0, 0.0, 0.0],
            [1e-9, -2e-9, 0.0],
            [0.5, -0.3, 0.2],
            [0.0, 3.0, 0.0],
            [std::f64::consts::PI - 1e-9, 0.0, 0.0],
        ] {
            let back = rotation_vector(&rotation(w));
            for k in 0..3 {
                assert!((back[k] - w[k]).abs() < 1e-7, "{w:?} -> {back:?}");
            }
        }
    }

    /// Near the identity, where a fitted frame's step is, the rotation
    /// vector comes back to rounding (nalgebra's `scaled_axis`, from the
    /// arccosine of the trace, is 4e-8 off at 1e-5 rad and 1 % at 1e-7).
    #[test]
    fn small_rotation_vectors_come_back_to_rounding() {
        for th in [1e-3, 1e-5, 1e-7, 1e-9] {
            let w = [0.6 * th, -0.8 * th, 0.0];
            let back = rotation_vector(&rotation(w));
            for k in 0..2 {
                assert!((back[k] / w[k] - 1.0).abs() < 1e-14, "{th}: {back:?}");
            }
        }
    }

    /// Columns are found by block; a step moves the geometry by addition
    /// and a frame by its own update, fixed columns not at all.
    #[test]
    fn the_layout_places_and_moves_blocks() {
        let mut layout = Layout::new(DhParams::paper_nominal());
        let s = layout
            .add(Box::new(Scalar {
                name: "offset".into(),
                unit: Unit::Length,
                start: 3.0,
                tolerance: None,
                limit: None,
            }))
            .unwrap();
        let f = layout.add(Box::new(Frame::identity("tracker"))).unwrap();
        assert_eq!(layout.columns(s), 27..28);
        assert_eq!(layout.columns(f), 28..34);
        assert_eq!(layout.len(), 34);
        assert_eq!(layout.parameter(30).unwrap().name, "tracker.rz");
        assert_eq!(layout.parameter(26).unwrap().name, "Bz");
        let x = layout.start();
        let moved = layout.plus(&x, &[0, 27, 30, 33], &[1.0, 0.5, 0.1, -2.0]);
        assert_eq!(moved[0], x[0] + 1.0);
        assert_eq!(moved[27], 3.5);
        assert!((moved[30] - 0.1).abs() < 1e-15 && moved[28] == 0.0);
        assert_eq!(moved[33], -2.0);
        assert_eq!(moved[1..27], x[1..27]);
    }

    /// `minus` undoes `plus`: `(x ⊞ δ) ⊟ x = δ` and `x ⊞ (y ⊟ x) = y`, to
    /// 1e-12, for frames near the identity and turned by more than a right
    /// angle, with steps small and large.
    #[test]
    fn a_frames_minus_undoes_its_plus() {
        let frame = Frame::identity("f");
        for x in [
            [0.0; 6],
            [0.3, -0.2, 0.1, 5.0, -7.0, 2.0],
            [1.9, 0.4, -1.2, 100.0, 0.0, -50.0],
        ] {
            for d in [
                [1e-9, 0.0, -2e-9, 1e-6, 0.0, 0.0],
                [0.01, -0.02, 0.03, 1.0, 2.0, -3.0],
                [0.7, 0.2, -0.5, -40.0, 10.0, 5.0],
            ] {
                let (mut y, mut back, mut again) = ([0.0; 6], [0.0; 6], [0.0; 6]);
                frame.plus(&x, &d, &mut y);
                frame.minus(&y, &x, &mut back);
                for k in 0..6 {
                    assert!((back[k] - d[k]).abs() < 1e-12, "{x:?} ⊞ {d:?}: {back:?}");
                }
                // The same frame, to the rounding of its storage: a
                // rotation vector of angle θ is read back from a matrix
                // through 1/sin θ, which near π (θ = 3.12 here) amplifies
                // the matrix's rounding fiftyfold.
                frame.plus(&x, &back, &mut again);
                let th = (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt();
                let storage = 1e-12 * (0.1 / th.sin().abs()).max(1.0);
                let apart = Frame::difference(&y, &again);
                assert!(
                    apart.iter().all(|v| v.abs() < storage),
                    "{again:?} vs {y:?}"
                );
            }
        }
        // A mount's rotation steps and comes back as a frame's does.
        let mount = Mount { start: [0.0; 3] };
        let (x, d) = ([0.3, -0.2, 0.1], [0.7, 0.2, -0.5]);
        let (mut y, mut back) = ([0.0; 3], [0.0; 3]);
        mount.plus(&x, &d, &mut y);
        mount.minus(&y, &x, &mut back);
        assert!((0..3).all(|k| (back[k] - d[k]).abs() < 1e-12), "{back:?}");
        let as_frame = Frame::rotation(&d) * Frame::rotation(&x);
        assert!((Frame::rotation(&y).matrix() - as_frame.matrix()).norm() < 1e-12);
        // The default (adding) update's minus subtracts.
        let s = Scalar {
            name: "s".into(),
            unit: Unit::Length,
            start: 0.0,
            tolerance: None,
            limit: None,
        };
        let mut out = [0.0];
        s.minus(&[5.5], &[2.0], &mut out);
        assert_eq!(out, [3.5]);
    }

    /// A mass: one column bounded below by 0 (and above by 100 kg).
    #[derive(Clone, Debug)]
    struct Mass {
        start: f64,
        names: usize,
    }

    impl Block for Mass {
        fn name(&self) -> &str {
            "mass"
        }
        fn parameters(&self) -> Vec<Parameter> {
            let p = Parameter {
                name: "mass.kg".into(),
                unit: Unit::Other("kg".into()),
            };
            vec![p; self.names]
        }
        fn start(&self) -> Vec<f64> {
            vec![self.start]
        }
        fn len(&self) -> usize {
            1
        }
        fn bounds(&self, _i: usize) -> Option<(f64, f64)> {
            Some((0.0, 100.0))
        }
    }

    /// The layout refuses, with a typed error naming the block, what it
    /// used to panic on or take silently; it clamps a bounded column onto
    /// its bound, says so, and holds a block's columns when asked.
    #[test]
    fn the_layout_refuses_by_name_and_clamps_to_bounds() {
        let nominal = DhParams::paper_nominal();
        let corrections = || super::super::CorrectionBlock {
            fit: crate::corrections::Beyond {
                harmonics: vec![(0, 1)],
                ..Default::default()
            },
            physics: crate::corrections::Physics::default(),
            joints: 6,
            prismatic: 0,
        };
        let mut layout = Layout::new(nominal.clone());
        let frame = layout.add(Box::new(Frame::identity("tracker"))).unwrap();
        assert_eq!(
            layout.add_corrections(corrections()),
            Err(LayoutError::CorrectionsNotFirst {
                block: "beyond".into()
            })
        );
        assert!(matches!(
            layout.add(Box::new(Frame::identity("tracker"))),
            Err(LayoutError::Duplicate { block }) if block == "tracker"
        ));
        let two_names = layout.add(Box::new(Mass {
            start: 1.0,
            names: 2,
        }));
        assert!(matches!(
            two_names,
            Err(LayoutError::Sizes { names: 2, .. })
        ));
        let outside = layout.add(Box::new(Mass {
            start: -1.0,
            names: 1,
        }));
        let e = outside.unwrap_err();
        assert!(e.to_string().contains("mass.kg: starts at -1"), "{e}");
        let mass = layout
            .add(Box::new(Mass {
                start: 1.0,
                names: 1,
            }))
            .unwrap();
        let c = layout.columns(mass).start;
        let x = layout.start();
        let below = layout.plus(&x, &[c], &[-3.0]);
        assert_eq!(below[c], 0.0);
        assert_eq!(layout.on_bounds(&below), [("mass.kg".to_string(), 0.0)]);
        assert!(layout.on_bounds(&layout.plus(&x, &[c], &[2.0])).is_empty());
        // The corrections first, found by position, not by downcast.
        let mut first = Layout::new(nominal);
        let id = first.add_corrections(corrections()).unwrap();
        let (block, cols) = first.corrections().unwrap();
        assert_eq!((block.joints, cols), (6, first.columns(id)));
        assert!(layout.corrections().is_none());
        // Holding a block: its columns are the held ones.
        assert!(layout.held_columns().is_empty());
        layout.hold(frame);
        layout.hold(frame);
        assert_eq!(layout.held_columns(), (27..33).collect::<Vec<_>>());
    }
}
