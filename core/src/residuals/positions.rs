//! Reference positions: where an instrument saw the probe, in the
//! instrument's own frame — a laser tracker's station, an artefact's
//! placement. Row `i` in frame `f`: `r_i = w_i (R_f p(q_i; x) + t_f − y_i)`
//! (3 rows), with `(R_f, t_f)` the frame's registration (a [`Frame`] block,
//! fitted with the arm) and `w_i = 1/σ_i`: the row's stated uncertainty, or
//! the noise model `σ = A + B·|y|` (a tracker's error grows with the
//! distance from it, and `y` is in its frame, so `|y|` is that distance), or
//! a σ the fit estimates when nothing is stated. The weights do not depend
//! on the arm.
//!
//! Because `R_f` is a rotation, the geometry's block of the normal
//! equations is `Σ w² J_pᵀJ_p` whatever the frame; the frame's columns
//! couple to it through `R_f J_p`. Each frame absorbs a rigid motion of
//! everything it sees: a turn about, or a slide along, the base axis
//! (`theta1`, `d1`) moves every position rigidly, so those two become
//! redundant with the frame — the identifiability analysis finds it from
//! the normal equations with the frames eliminated.

use nalgebra::{Matrix3, Rotation3, Vector3};

use super::CorrectionBlock;
use super::blocks::Frame;
use super::rank3::Rank3;
use super::tools::{ToolGroup, tool_columns, with_tool};
use super::{
    At, BlockId, Layout, LayoutError, Noise, Normal, Origin, Sees, Shared, Standardised, Term,
    TermError,
};
use crate::corrections::{Beyond, Effects, Physics};
use crate::dataset::{DataSet, PositionData};
use crate::kernel::{Batch, KernelError, LANES, LaneOp};
use crate::parallel::parallel_map;
use crate::params::DhParams;

/// Rows per work item: fixed, so sums are added in the same order whatever
/// the thread count.
const ROWS_PER_CHUNK: usize = 256;

/// A frame's best rigid registration of an arm's positions onto the
/// instrument's, in closed form, and how well it fits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Registration {
    /// `[rx, ry, rz, tx, ty, tz]`: `y ≈ R p + t` (rad, mm).
    pub x: [f64; 6],
    /// RMS of `|R p + t − y|` over the frame's rows, mm.
    pub rms_mm: f64,
    /// The same with a mirror image allowed (`det R = −1`): far below
    /// [`Registration::rms_mm`] when two axes were swapped.
    pub(crate) mirrored_rms_mm: f64,
    /// RMS distance of the instrument's positions from their centroid, mm.
    pub(crate) spread_mm: f64,
    /// The same of the arm's positions.
    pub(crate) arm_spread_mm: f64,
}

/// The rigid transform `y ≈ R p + t` of least squares
/// ([`crate::geometry::best_rigid_motion`]) of `p` onto `y`, proper
/// (`det R = +1`) or mirrored, and the RMS of its residuals.
fn kabsch(p: &[[f64; 3]], y: &[[f64; 3]], mirrored: bool) -> (Matrix3<f64>, Vector3<f64>, f64) {
    let n = p.len().max(1) as f64;
    let v = |a: &[f64; 3]| Vector3::new(a[0], a[1], a[2]);
    let (r, t) = crate::geometry::best_rigid_motion(p, y, mirrored)
        .map_or((Matrix3::identity(), Vector3::zeros()), |m| {
            (m.rotation, m.translation())
        });
    let ss: f64 = p
        .iter()
        .zip(y)
        .map(|(a, b)| (r * v(a) + t - v(b)).norm_squared())
        .sum();
    (r, t, (ss / n).sqrt())
}

/// The rotation vector of `R`, a proper rotation.
fn rotation_vector_of(r: &Matrix3<f64>) -> [f64; 3] {
    super::blocks::rotation_vector(&Rotation3::from_matrix_unchecked(*r))
}

fn rms_spread(points: &[[f64; 3]]) -> f64 {
    let c = crate::geometry::centroid(points);
    let ss: f64 = points
        .iter()
        .map(|p| (0..3).map(|k| (p[k] - c[k]).powi(2)).sum::<f64>())
        .sum();
    (ss / points.len().max(1) as f64).sqrt()
}

/// Each frame's closed-form registration of `params`' positions onto the
/// data's (in the order of [`crate::domain::Positions::frames`]), each row's
/// tool at its nominal offset ([`crate::io::tools`]).
///
/// # Errors
///
/// The kernel's.
pub fn register(params: &DhParams, data: &PositionData) -> Result<Vec<Registration>, KernelError> {
    let p = super::tools::nominal_positions(params, data)?;
    let rows = data.rows();
    Ok((0..rows.frames().len())
        .map(|f| {
            let idx: Vec<usize> = (0..rows.len()).filter(|&i| rows.frame(i) == f).collect();
            let pf: Vec<[f64; 3]> = idx.iter().map(|&i| p[i]).collect();
            let yf: Vec<[f64; 3]> = idx.iter().map(|&i| rows.position(i)).collect();
            let (r, t, rms) = kabsch(&pf, &yf, false);
            let (_, _, mirrored) = kabsch(&pf, &yf, true);
            let w = rotation_vector_of(&r);
            Registration {
                x: [w[0], w[1], w[2], t[0], t[1], t[2]],
                rms_mm: rms,
                mirrored_rms_mm: mirrored,
                spread_mm: rms_spread(&yf),
                arm_spread_mm: rms_spread(&pf),
            }
        })
        .collect())
}

/// The columns of `params` and one [`Frame`] per frame of `data`'s
/// positions, each starting at its closed-form registration of `params`:
/// the layout every fit of these data uses.
///
/// # Errors
///
/// The kernel's.
pub fn layout_for(params: &DhParams, data: &DataSet) -> Result<Layout, TermError> {
    layout_with(params, data, &Physics::default(), &Beyond::default())
}

/// [`layout_for`] of an arm with `physics` whose fit estimates the models
/// `fit` beyond geometry: their [`CorrectionBlock`] first (when anything is
/// fitted or stated), the frames registered with the stated corrections
/// applied.
///
/// # Errors
///
/// The kernel's; a frame named as the corrections' block
/// (`super::beyond::BLOCK_NAME`) beside them. A stated correction whose
/// conditions `data` lack (an expansion without temperatures) is left out
/// of the frames' start; the session refuses such data first.
pub fn layout_with(
    params: &DhParams,
    data: &DataSet,
    physics: &Physics,
    fit: &Beyond,
) -> Result<Layout, TermError> {
    let mut layout = Layout::new(params.clone());
    // Masses alone change no position: no block (and no cost) without a
    // model fitted or a correction stated.
    if !fit.is_empty() || physics.corrects() {
        layout.add_corrections(CorrectionBlock {
            fit: fit.clone(),
            physics: physics.clone(),
            joints: params.joint_count(),
            prismatic: params.shape().map_or(0, |s| s.prismatic_mask()),
        })?;
    }
    // The frames' start through the stated corrections (a copy of the data
    // only when there are any).
    let corrected;
    let data = match physics.corrects().then(|| data.corrected(params, physics)) {
        Some(Ok(d)) => {
            corrected = d;
            &corrected
        }
        _ => data,
    };
    if let Some(positions) = data.positions() {
        let names = positions.rows().frames();
        let starts: Vec<[f64; 6]> = (register(params, positions)?.iter()).map(|r| r.x).collect();
        for (name, &start) in names.iter().zip(&starts) {
            layout.add(Box::new(Frame {
                name: name.clone(),
                start,
            }))?;
        }
        if let Some(start) = super::orientations::mount_start(params, positions, &starts)? {
            add_mount(&mut layout, start)?;
        }
        super::tools::add_tool_blocks(&mut layout, positions)?;
    }
    super::tools::add_touch_tool_blocks(&mut layout, data)?;
    Ok(layout)
}

/// Adds the tool mount's block ([`super::Mount`]) starting at `start`; a
/// frame already named as it is refused by name (rename the frame).
fn add_mount(layout: &mut Layout, start: [f64; 3]) -> Result<(), TermError> {
    match layout.add(Box::new(super::Mount { start })) {
        Ok(_) => Ok(()),
        Err(LayoutError::Duplicate { block }) => Err(TermError::invalid(
            "positions",
            format!(
                "frame {}: the name of the tool mount's block, fitted when the positions give \
                 the tool's orientation: rename the frame",
                crate::error::quoted(&block)
            ),
        )),
        Err(e) => Err(e.into()),
    }
}

/// σ of row `i`: its own, or the noise model's (`A + B·|y|`, `B` per metre).
fn row_sigma(data: &PositionData, noise: &Noise, i: usize) -> Option<f64> {
    let rows = data.rows();
    rows.uncertainty(i).or_else(|| {
        let a = noise.position_mm?;
        let y = rows.position(i);
        let metres = (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt() / 1000.0;
        Some(a + noise.position_mm_per_m.unwrap_or(0.0) * metres)
    })
}

/// Per frame of `data`'s positions, its block in `layout` (one named as
/// the frame); a frame without one is refused by the term `term`.
pub(super) fn frame_blocks(
    data: &PositionData,
    layout: &Layout,
    term: &str,
) -> Result<Vec<BlockId>, TermError> {
    (data.rows().frames().iter())
        .map(|name| {
            layout.block_named(name).ok_or_else(|| {
                TermError::invalid(
                    term,
                    format!(
                        "frame {} has no block among the columns (a bug, not input)",
                        crate::error::quoted(name)
                    ),
                )
            })
        })
        .collect()
}

/// The reference positions of a data set on its frames' blocks.
#[derive(Clone)]
pub(crate) struct PositionTerm<'d> {
    data: &'d PositionData,
    /// Per frame, its block.
    frames: Vec<BlockId>,
    /// Per row, its stated σ (mm), or `None` for every row (unit weights).
    sigma: Option<Vec<f64>>,
    /// Per row, a robust fit's weight (1 without one).
    robust: Vec<f64>,
    /// Per row, `w_i` (1/mm); empty until weighed.
    weights: Vec<f64>,
    /// Rows per frame (each frame's leverage).
    per_frame: Vec<usize>,
    /// The rows by tool ([`super::tools`]): one group of every row when
    /// no row names a tool.
    groups: Vec<ToolGroup>,
}

impl std::fmt::Debug for PositionTerm<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PositionTerm")
            .field("positions", &self.data.len())
            .field("frames", &self.frames.len())
            .field("stated", &self.sigma.is_some())
            .finish()
    }
}

impl<'d> PositionTerm<'d> {
    /// The positions of `data` on the frame blocks of `layout` (one named as
    /// each frame), under `noise`.
    ///
    /// # Errors
    ///
    /// A frame without its block in the layout, and a file in which some
    /// rows state an uncertainty and others have none to fall back on.
    pub(crate) fn new(
        data: &'d PositionData,
        layout: &Layout,
        noise: &Noise,
    ) -> Result<PositionTerm<'d>, TermError> {
        let rows = data.rows();
        let frames = frame_blocks(data, layout, "positions")?;
        let sigmas: Vec<Option<f64>> = (0..rows.len()).map(|i| row_sigma(data, noise, i)).collect();
        let sigma = match sigmas.iter().position(Option::is_none) {
            None => Some(sigmas.into_iter().flatten().collect()),
            Some(_) if sigmas.iter().all(Option::is_none) => None,
            Some(i) => {
                return Err(TermError::invalid(
                    "positions",
                    format!(
                        "{}: field `uncertainty`: empty while other rows state one, and no \
                         position noise is given for it (--position-noise)",
                        data.at(i)
                    ),
                ));
            }
        };
        let mut per_frame = vec![0; frames.len()];
        for i in 0..rows.len() {
            per_frame[rows.frame(i)] += 1;
        }
        Ok(PositionTerm {
            data,
            frames,
            sigma,
            robust: vec![1.0; rows.len()],
            weights: Vec::new(),
            per_frame,
            groups: super::tools::groups(data, layout, "positions")?,
        })
    }

    /// Every row's position at `at` (its tool's, the corrections applied).
    fn positions_at(&self, at: &At<'_>) -> Result<Vec<[f64; 3]>, TermError> {
        let mut p = vec![[0.0; 3]; self.data.len()];
        for g in &self.groups {
            with_tool(at, g.block, |at| {
                let data = g.data(self.data);
                let n = data.len();
                let mut q = vec![[0.0; 3]; n];
                let effects = at.corrected_poses(data.poses(), data.conditions())?;
                let poses = effects.as_ref().map_or(data.poses(), |e| &e.poses);
                at.kernel.positions(poses, 0..n, &mut q)?;
                for (i, v) in q.into_iter().enumerate() {
                    p[g.row(i)] = v;
                }
                Ok(())
            })?;
        }
        Ok(p)
    }

    /// Per frame, `R` and `t` at `at`.
    fn frames_at(&self, at: &At<'_>) -> Vec<(Rotation3<f64>, [f64; 3])> {
        self.frames
            .iter()
            .map(|&id| {
                let x = at.block(id);
                (Frame::rotation(x), [x[3], x[4], x[5]])
            })
            .collect()
    }

    /// Row `i`'s whitened residual for the arm's position `p`. Inlined: a
    /// call returned the three values through memory, which the caller read
    /// back as a pair while the stores were still in flight (a stall per
    /// position in every cost pass).
    #[inline(always)]
    fn residual(&self, frames: &[(Rotation3<f64>, [f64; 3])], i: usize, p: &[f64; 3]) -> [f64; 3] {
        let rows = self.data.rows();
        let (r, t) = &frames[rows.frame(i)];
        let y = rows.position(i);
        let w = self.weights[i];
        let q = r * Vector3::from(*p);
        std::array::from_fn(|k| w * (q[k] + t[k] - y[k]))
    }
}

/// `total` plus every row's `|r|²`, added in row order (the cost pass): four
/// rows of one frame at a time on lanes, each row's operations those of
/// [`PositionTerm::residual`] and its squares summed as there, so the same
/// bits as one row at a time (a tracker fit's grid costs spent 12 % here).
struct SquaredResiduals<'a, 't> {
    term: &'a PositionTerm<'t>,
    frames: &'a [(Rotation3<f64>, [f64; 3])],
    positions: &'a [[f64; 3]],
    total: f64,
}

impl LaneOp for SquaredResiduals<'_, '_> {
    type Output = f64;
    #[inline(always)]
    fn run<L: Batch>(self) -> f64 {
        let (term, frames, positions) = (self.term, self.frames, self.positions);
        let rows = term.data.rows();
        let mut sum = self.total;
        let one = |i: usize| {
            let r = term.residual(frames, i, &positions[i]);
            r[0] * r[0] + r[1] * r[1] + r[2] * r[2]
        };
        let whole = positions.len() / LANES * LANES;
        for i in (0..whole).step_by(LANES) {
            let frame = rows.frame(i);
            if (i + 1..i + LANES).any(|l| rows.frame(l) != frame) {
                for l in i..i + LANES {
                    sum += one(l);
                }
                continue;
            }
            let (r, t) = &frames[frame];
            let seen: [[f64; 3]; LANES] = std::array::from_fn(|l| rows.position(i + l));
            let w: &[f64; LANES] = term.weights[i..i + LANES].try_into().expect("four rows");
            let at: &[[f64; 3]; LANES] = positions[i..i + LANES].try_into().expect("four rows");
            for v in squared_norms::<L>(r.matrix(), t, at, &seen, w) {
                sum += v;
            }
        }
        for i in whole..positions.len() {
            sum += one(i);
        }
        sum
    }
}

/// `|w (R p + t − y)|²` of four rows of one frame, each as
/// [`PositionTerm::residual`] and the cost pass compute it: `R p` as
/// nalgebra's product sums its columns, `(q + t − y) w`, and the squares
/// added in order.
#[inline(always)]
fn squared_norms<L: Batch>(
    m: &Matrix3<f64>,
    t: &[f64; 3],
    p: &[[f64; 3]; LANES],
    y: &[[f64; 3]; LANES],
    w: &[f64; LANES],
) -> [f64; LANES] {
    let lanes = |v: &[[f64; 3]; LANES], k: usize| L::load(&v.map(|v| v[k]));
    let p = [0, 1, 2].map(|k| lanes(p, k));
    let w = L::load(w);
    let r = [0, 1, 2].map(|k| {
        let q = L::from(m[(k, 0)]) * p[0] + L::from(m[(k, 1)]) * p[1] + L::from(m[(k, 2)]) * p[2];
        w * (q + L::from(t[k]) - lanes(y, k))
    });
    (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).to_array()
}

/// A chunk's share of the normal equations: `JᵀJ` (upper triangle filled),
/// `Jᵀr`, cost.
struct Part {
    jtj: Vec<f64>,
    jtr: Vec<f64>,
    cost: f64,
}

impl Term for PositionTerm<'_> {
    fn name(&self) -> &str {
        "positions"
    }

    fn role(&self) -> super::Role {
        super::Role::Positions
    }

    fn rows(&self, _free: &[usize]) -> usize {
        3 * self.data.len()
    }

    /// Positions fix the scale (they are absolute); a turn about, or a
    /// slide along, the base axis moves every position of a frame rigidly,
    /// which the frame's fitted registration absorbs: not seen. (The
    /// normal equations with the frames eliminated say so too, but only to
    /// the precision the elimination leaves: the rule is exact.)
    fn sees(&self) -> Sees {
        Sees {
            base_rotation: false,
            base_slide: false,
            scale: true,
        }
    }

    fn unit_weighted(&self) -> bool {
        self.sigma.is_none()
    }

    fn weigh(
        &mut self,
        _at: &At<'_>,
        _shared: &mut Shared,
        unit_sigma: f64,
    ) -> Result<(), TermError> {
        let n = self.data.len();
        self.weights = (0..n)
            .map(|i| {
                let s = self.sigma.as_ref().map_or(unit_sigma, |s| s[i]);
                self.robust[i].sqrt() / s
            })
            .collect();
        if let Some(i) = self
            .weights
            .iter()
            .position(|w| !(w.is_finite() && *w > 0.0))
        {
            return Err(TermError::invalid(
                "positions",
                format!(
                    "{}: the weight of this position is not a finite positive number: give \
                     its uncertainty in mm (a tracker's is 0.005–0.05 mm)",
                    self.data.at(i)
                ),
            ));
        }
        Ok(())
    }

    fn weight_change(
        &self,
        _at: &At<'_>,
        _shared: &mut Shared,
        unit_sigma: f64,
    ) -> Result<f64, TermError> {
        if self.weights.len() != self.data.len() {
            return Ok(f64::INFINITY);
        }
        // Only an estimated σ moves them.
        Ok(match (&self.sigma, self.weights.first()) {
            (None, Some(&w)) => ((1.0 / unit_sigma) * self.robust[0].sqrt() / w - 1.0).abs(),
            _ => 0.0,
        })
    }

    fn accumulate(
        &self,
        at: &At<'_>,
        _shared: &mut Shared,
        normal: &mut Normal,
    ) -> Result<f64, TermError> {
        let frames = self.frames_at(at);
        let free = normal.free.clone();
        let arm = at.layout.arm_columns();
        // Per free column: the arm's column (geometry or correction), or
        // (frame, its column 0..6).
        let geo: Vec<(usize, usize)> = free
            .iter()
            .enumerate()
            .filter(|(_, c)| **c < arm)
            .map(|(a, &c)| (a, c))
            .collect();
        let frame_cols: Vec<Vec<(usize, usize)>> = self
            .frames
            .iter()
            .map(|&id| {
                let cols = at.layout.columns(id);
                free.iter()
                    .enumerate()
                    .filter(|(_, c)| cols.contains(c))
                    .map(|(a, &c)| (a, c - cols.start))
                    .collect()
            })
            .collect();
        let p = free.len();
        let mut cost = 0.0;
        for g in &self.groups {
            let geo = tool_columns(&geo, &free, at.layout, g.block);
            let parts = with_tool(at, g.block, |at| {
                let data = g.data(self.data);
                let effects = at.effects(data.poses(), data.conditions())?;
                let n = data.len();
                let chunks: Vec<std::ops::Range<usize>> = (0..n.div_ceil(ROWS_PER_CHUNK))
                    .map(|k| k * ROWS_PER_CHUNK..((k + 1) * ROWS_PER_CHUNK).min(n))
                    .collect();
                Ok(parallel_map(&chunks, at.threads, |range| {
                    let cols = Columns {
                        p,
                        geo: &geo,
                        frame_cols: &frame_cols,
                    };
                    self.part(at, (g, effects.as_ref()), &frames, range.clone(), cols)
                }))
            })?;
            for part in parts {
                let part = part?;
                cost += part.cost;
                for a in 0..p {
                    normal.jtr[a] += part.jtr[a];
                    for b in a..p {
                        let v = part.jtj[a * p + b];
                        normal.jtj[a * p + b] += v;
                        if b != a {
                            normal.jtj[b * p + a] += v;
                        }
                    }
                }
            }
        }
        Ok(cost)
    }

    fn add_cost(
        &self,
        at: &At<'_>,
        _free: &[usize],
        _shared: &mut Shared,
        scratch: &mut Vec<[f64; 3]>,
        total: &mut f64,
    ) -> Result<(), TermError> {
        let frames = self.frames_at(at);
        let n = self.data.len();
        scratch.resize(n, [0.0; 3]);
        if self.groups.len() == 1 && self.groups[0].subset.is_none() {
            let effects = at.corrected_poses(self.data.poses(), self.data.conditions())?;
            let poses = effects.as_ref().map_or(self.data.poses(), |e| &e.poses);
            at.kernel.positions(poses, 0..n, &mut scratch[..n])?;
        } else {
            scratch[..n].copy_from_slice(&self.positions_at(at)?);
        }
        *total = crate::kernel::run_lanes(SquaredResiduals {
            term: self,
            frames: &frames,
            positions: &scratch[..n],
            total: *total,
        });
        Ok(())
    }

    /// `|r|²/(1 − h)` per row, `h = 2/n_f`: the average leverage of its
    /// frame's six unknowns over the frame's `3 n_f` rows.
    fn standardised(
        &self,
        at: &At<'_>,
        _leverage: Option<&super::ParameterLeverage>,
    ) -> Result<Option<Standardised>, TermError> {
        let frames = self.frames_at(at);
        let n = self.data.len();
        let p = self.positions_at(at)?;
        let rows = self.data.rows();
        let values = (0..n)
            .map(|i| {
                let r = self.residual(&frames, i, &p[i]);
                let h = (2.0 / self.per_frame[rows.frame(i)] as f64).min(0.999);
                // At the weights in force, a robust fit's included (its
                // residual carries `√w`), as a touch's `rᵀAr`: the robust
                // fit divides by the weight once.
                (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]) / (1.0 - h)
            })
            .collect();
        Ok(Some(Standardised { rows: 3, values }))
    }

    fn observations(&self) -> usize {
        self.data.len()
    }

    fn origin(&self, i: usize) -> Origin {
        Origin {
            at: self.data.at(i).to_string(),
            group: self.data.rows().label(i).to_string(),
        }
    }

    fn weigh_observations(&mut self, w: &[f64]) -> bool {
        for (r, &v) in self.robust.iter_mut().zip(w) {
            *r *= v;
        }
        for (x, &v) in self.weights.iter_mut().zip(w) {
            *x *= v.sqrt();
        }
        true
    }

    fn typical_sigma(&self) -> Option<f64> {
        let mut s = self.sigma.clone()?;
        s.sort_by(f64::total_cmp);
        s.get(s.len() / 2).copied()
    }
}

/// The free columns a chunk of rows adds to: `p` in all, `geo` the arm's
/// (index into the free list, column), `frame_cols` each frame's (index
/// into the free list, column of the frame).
#[derive(Clone, Copy)]
struct Columns<'a> {
    p: usize,
    geo: &'a [(usize, usize)],
    frame_cols: &'a [Vec<(usize, usize)>],
}

impl PositionTerm<'_> {
    /// Rows `range`'s share of the normal equations over `p` free columns:
    /// `geo` the free geometry columns, `frame_cols` each frame's free
    /// columns (index into the free list, column of the frame).
    ///
    /// The sums run over compact columns — the geometry's, then each
    /// frame's — in blocks of rows ([`Rank3`]); each entry's terms are added
    /// row by row in row order, as one row at a time into the free columns
    /// would (the same bits). A row fills its frame's columns and zeros in
    /// the other frames'.
    fn part(
        &self,
        at: &At<'_>,
        (group, effects): (&ToolGroup, Option<&Effects>),
        frames: &[(Rotation3<f64>, [f64; 3])],
        range: std::ops::Range<usize>,
        cols: Columns<'_>,
    ) -> Result<Part, TermError> {
        let Columns { p, geo, frame_cols } = cols;
        let g = geo.len();
        // Per frame, where its compact columns start.
        let offsets: Vec<usize> = (frame_cols.iter())
            .scan(g, |next, f| {
                let at = *next;
                *next += f.len();
                Some(at)
            })
            .collect();
        let m = g + frame_cols.iter().map(Vec::len).sum::<usize>();
        let mut rank3 = Rank3::new(m);
        let mut jtj = rank3.matrix();
        let mut jtr = vec![0.0; m];
        let mut cost = 0.0;
        let rows = self.data.rows();
        let poses = effects.map_or(group.data(self.data).poses(), |e| &e.poses);
        let mut ext = Vec::new();
        // Inlined into the kernel's loop, so that the accumulation is
        // compiled with the same target features (AVX2 where the CPU has it).
        at.kernel.for_each_jacobian(
            poses,
            range,
            #[inline(always)]
            |k, pos, jac| {
                let jac = match effects {
                    Some(e) => {
                        e.extend(k, pos, jac, &mut ext);
                        &ext[..]
                    }
                    None => jac,
                };
                let i = group.row(k);
                let f = rows.frame(i);
                let (rot, _) = &frames[f];
                let w = self.weights[i];
                let r = self.residual(frames, i, pos);
                cost += r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
                let mut slot = rank3.slot();
                let (start, kf) = (offsets[f], frame_cols[f].len());
                if g + kf < m {
                    slot.clear();
                }
                // `J` and `A·J` alike: the rows are whitened (`A = I`).
                for (u, &(_, c)) in geo.iter().enumerate() {
                    let d: [f64; 3] = (rot * Vector3::from(jac[c]) * w).into();
                    slot.set_both(u, d);
                    jtr[u] += d[0] * r[0] + d[1] * r[1] + d[2] * r[2];
                }
                if kf > 0 {
                    // Frame::jacobian with R already at hand: [−[Rp]× | I].
                    let q = rot * Vector3::from(*pos);
                    let jf = [
                        [0.0, q[2], -q[1], 1.0, 0.0, 0.0],
                        [-q[2], 0.0, q[0], 0.0, 1.0, 0.0],
                        [q[1], -q[0], 0.0, 0.0, 0.0, 1.0],
                    ];
                    for (u, &(_, c)) in frame_cols[f].iter().enumerate() {
                        let d: [f64; 3] = std::array::from_fn(|row| w * jf[row][c]);
                        slot.set_both(start + u, d);
                        jtr[start + u] += d[0] * r[0] + d[1] * r[1] + d[2] * r[2];
                    }
                }
                rank3.add(&mut jtj);
            },
        )?;
        rank3.flush(&mut jtj);
        // Back to the free columns, upper triangle.
        let index: Vec<usize> = (geo.iter().chain(frame_cols.iter().flatten()))
            .map(|&(a, _)| a)
            .collect();
        let mut part = Part {
            jtj: vec![0.0; p * p],
            jtr: vec![0.0; p],
            cost,
        };
        for (u, &a) in index.iter().enumerate() {
            part.jtr[a] = jtr[u];
            for (v, &b) in index.iter().enumerate().take(u + 1) {
                let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
                part.jtj[lo * p + hi] = rank3.entry(&jtj, u, v);
            }
        }
        Ok(part)
    }
}

#[cfg(test)]
mod tests {
    use super::{Batch, LANES, LaneOp, Matrix3, ROWS_PER_CHUNK, Rotation3, Vector3, squared_norms};
    use crate::parallel::threads_for;

    /// Four rows' squared residuals on lanes (portable and the widest the
    /// CPU has) are the bits of one row at a time: `R p` through nalgebra,
    /// `w (q + t − y)`, the squares added in order.
    #[test]
    fn four_rows_on_lanes_are_the_bits_of_one_at_a_time() {
        struct Norms<'a> {
            m: &'a Matrix3<f64>,
            t: &'a [f64; 3],
            p: &'a [[f64; 3]; LANES],
            y: &'a [[f64; 3]; LANES],
            w: &'a [f64; LANES],
        }
        impl LaneOp for Norms<'_> {
            type Output = [f64; LANES];
            fn run<L: Batch>(self) -> [f64; LANES] {
                squared_norms::<L>(self.m, self.t, self.p, self.y, self.w)
            }
        }
        let mut rng = crate::random::rng(17, 0);
        let mut draw = |scale: f64| rand::RngExt::random_range(&mut rng, -1.0..1.0) * scale;
        for _ in 0..200 {
            let axis = Vector3::new(draw(1.0), draw(1.0), draw(1.0));
            let r = Rotation3::from_scaled_axis(axis * draw(3.0));
            let t = [draw(2e3), draw(2e3), draw(2e3)];
            let p: [[f64; 3]; LANES] = std::array::from_fn(|_| [draw(1e3), draw(1e3), draw(1e3)]);
            let y: [[f64; 3]; LANES] = std::array::from_fn(|_| [draw(2e3), draw(2e3), draw(2e3)]);
            let w: [f64; LANES] = std::array::from_fn(|_| draw(50.0).abs());
            let want = std::array::from_fn::<u64, LANES, _>(|l| {
                let q = r * Vector3::from(p[l]);
                let v: [f64; 3] = std::array::from_fn(|k| w[l] * (q[k] + t[k] - y[l][k]));
                (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).to_bits()
            });
            let op = || Norms {
                m: r.matrix(),
                t: &t,
                p: &p,
                y: &y,
                w: &w,
            };
            for got in [
                op().run::<crate::kernel::Lanes>(),
                crate::kernel::run_lanes(op()),
            ] {
                assert_eq!(got.map(f64::to_bits), want);
            }
        }
    }

    /// The UR5 tracker example's 1000 positions are a small problem: 4
    /// chunks, which run on the calling thread whatever the thread count,
    /// so that on a loaded machine the default threads cost no more than
    /// one (the `threads` bench measures it).
    #[test]
    fn the_ur5_trackers_positions_run_on_the_calling_thread() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../examples/ur5-tracker/positions-grid.csv"
        );
        let text = std::fs::read_to_string(path).unwrap();
        let rows = text.lines().skip(1).filter(|l| !l.trim().is_empty());
        let chunks = rows.count().div_ceil(ROWS_PER_CHUNK);
        assert_eq!(chunks, 4);
        for threads in [1, 2, 8, 1024] {
            assert_eq!(threads_for(chunks, threads), 1, "{threads} threads");
        }
        // Twice the poses are shared.
        assert_eq!(threads_for(2 * chunks, 2), 2);
    }
}
