//! Same-point touches: every touch of a point against the point's weighted
//! centroid, the centres eliminated (see the module docs of
//! [`crate::residuals`]). The work runs in chunks of whole points on the
//! kernel's SIMD lanes, in a fixed order, so the sums are the same bits on
//! any thread count.

use std::ops::Range;

use super::rank3::Rank3;
use super::sym3::{Sym3, centroid_cov, sym_inv, sym_mul};
use super::{
    At, Centres, Noise, Normal, Origin, ParameterLeverage, Sees, Shared, Standardised, Term,
    TermError,
};
use crate::corrections::Effects;
use crate::dataset::DataSet;
use crate::error::short;
use crate::kernel::{ArmKernel, Batch, KernelError, LANES, LaneOp, NoiseOf, run_lanes};
use crate::parallel::parallel_map;

use super::tools::{TouchViews, tool_columns};

/// Touches per work item of the weights (about 0.1 ms of work: enough to pay
/// for handing it out).
pub(super) const TOUCHES_PER_CHUNK: usize = 1024;

/// Points per work item of the normal equations: fixed, so the sums are
/// added in the same order whatever the number of threads (same bytes on
/// any machine).
pub(super) const POINTS_PER_CHUNK: usize = 64;

/// The touches whose positions a cost pass computes at a time (whole
/// points, or one point of more): enough for the kernel's lanes, and a
/// batch's positions (24 KiB) stay in the core's cache — a chunk of 64
/// points of 1000 touches was 1.5 MB a thread.
const TOUCH_BATCH: usize = 1024;

/// How many chunks of work the normal equations of `points` points split
/// into: chunks of a fixed number of points, shared between threads from
/// `MIN_ITEMS_PER_THREAD` chunks
/// a thread up ([`threads_for`](crate::parallel::threads_for); below that,
/// on the calling thread whatever the thread count). What a test of
/// thread-independence asks, to know that the work really splits.
///
/// ```
/// use aacmm_core::parallel::threads_for;
/// use aacmm_core::residuals::point_chunks;
/// assert_eq!(point_chunks(64), 1);
/// assert_eq!(point_chunks(65), 2);
/// assert_eq!(threads_for(point_chunks(300), 2), 1, "300 points: one thread");
/// assert_eq!(threads_for(point_chunks(500), 2), 2, "500 points: two");
/// ```
pub fn point_chunks(points: usize) -> usize {
    points.div_ceil(POINTS_PER_CHUNK)
}

/// The touches of a data set, each weighed by the inverse of its position's
/// covariance: stated probe and encoder noise carried through the arm, or
/// `I/σ²` with `σ` estimated from the fit when no noise is stated.
#[derive(Clone)]
pub(crate) struct TouchTerm<'d> {
    data: &'d DataSet,
    noise: Noise,
    /// The σ of an unweighted touch (noise not stated), mm.
    unit_sigma: f64,
    /// Per touch (data-set order), `A_i = Σ_i⁻¹`, 1/mm²; empty until weighed.
    weights: Vec<Sym3>,
    /// The touches' corrected readings at the last points evaluated.
    seen: crate::corrections::SeenCache,
}

impl std::fmt::Debug for TouchTerm<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TouchTerm")
            .field("touches", &self.data.len())
            .field("points", &self.data.points().len())
            .field("noise", &self.noise)
            .field("unit_sigma", &self.unit_sigma)
            .field("weighed", &!self.weights.is_empty())
            .finish()
    }
}

impl<'d> TouchTerm<'d> {
    /// [`Term::standardised`] of the points `points`, their touches' values
    /// in order into `out`, with `(cols, m)` the free arm columns and their
    /// block of `N⁻¹` (empty: the centres' leverage only).
    fn standardised_points(
        &self,
        at: &At<'_>,
        effects: Option<&Effects>,
        (cols, m): (&[usize], &[f64]),
        points: &Range<usize>,
        out: &mut [f64],
    ) -> Result<(), KernelError> {
        let (data, q) = (self.data, cols.len());
        let all = &data.points()[points.clone()];
        let most = all.iter().map(|p| p.touches.len()).max().unwrap_or(0);
        let mut scratch = PointScratch::new(most, q);
        let poses = effects.map_or(data.poses(), |e| &e.poses);
        // `out` holds these points' touches, from the first one's.
        let offset = all.first().map_or(0, |p| p.touches.start);
        let mut ext = Vec::new();
        for point in all {
            let first = point.touches.start;
            if q == 0 {
                let xyz = &mut scratch.xyz[..point.touches.len()];
                at.kernel.positions(poses, point.touches.clone(), xyz)?;
            } else {
                let (xyz, jac) = (&mut scratch.xyz, &mut scratch.jac);
                at.kernel
                    .for_each_jacobian(poses, point.touches.clone(), |i, pos, j| {
                        let j = match effects {
                            Some(e) => {
                                e.extend(i, pos, j, &mut ext);
                                &ext[..]
                            }
                            None => j,
                        };
                        xyz[i - first] = *pos;
                        // A row's slice once: indexing `jac` per column
                        // reloaded and checked it each time.
                        let row = &mut jac[(i - first) * q..][..q];
                        for (dst, &c) in row.iter_mut().zip(cols) {
                            *dst = j[c];
                        }
                    })?;
            }
            // On the kernel's lanes (AVX where the CPU has it; the same
            // bits): the parameter share's sums are most of a point's work.
            let weights = &self.weights[point.touches.clone()];
            run_lanes(OnePoint {
                scratch: &mut scratch,
                a: weights,
                m,
                out: &mut *out,
                at: point.touches.start - offset,
            });
        }
        run_lanes(Flush {
            group: &mut scratch.group,
            m,
            out,
        });
        Ok(())
    }

    /// The touches of `data` under `noise` (its touch part), not weighed
    /// yet ([`Term::weigh`]).
    pub(crate) fn new(data: &'d DataSet, noise: Noise) -> TouchTerm<'d> {
        TouchTerm {
            data,
            noise,
            unit_sigma: 1.0,
            weights: Vec::new(),
            seen: Default::default(),
        }
    }

    /// Per touch (data-set order), its weight `A_i`, `[xx, yy, zz, xy,
    /// xz, yz]`, 1/mm².
    #[cfg(test)]
    pub(crate) fn weights(&self) -> &[[f64; 6]] {
        &self.weights
    }

    /// These weights less the last touch's: weights of another shape.
    #[cfg(test)]
    pub(super) fn without_last_weight(mut self) -> Self {
        self.weights.pop();
        self
    }

    /// The weights of touches `range` at `kernel`, in order, to `f(i, A_i)`.
    fn each_weight(
        &self,
        kernel: &ArmKernel,
        range: Range<usize>,
        unit_sigma: f64,
        f: impl FnMut(usize, Sym3) -> Result<(), KernelError>,
    ) -> Result<(), KernelError> {
        TouchWeight::new(kernel, self.data, &self.noise, unit_sigma).each(range, f)
    }

    /// Every touch's weight as its tool sees it (`views` at `at`), the
    /// joint Jacobians on up to `at.threads` threads in chunks of fixed
    /// size within each run of one tool: each touch's weight is its own, so
    /// the result is the same bits whatever the thread count.
    fn weights_at(
        &self,
        at: &At<'_>,
        views: &TouchViews,
        unit_sigma: f64,
    ) -> Result<Vec<Sym3>, KernelError> {
        if !self.noise.stated() {
            let w = 1.0 / (unit_sigma * unit_sigma);
            return Ok(vec![[w, w, w, 0.0, 0.0, 0.0]; self.data.len()]);
        }
        let mut touch = vec![[0.0; 6]; self.data.len()];
        let mut parts = Vec::new();
        let mut rest = touch.as_mut_slice();
        for (k, run) in &views.runs {
            let touches = self.touches_of(run);
            let (mine, tail) = std::mem::take(&mut rest).split_at_mut(touches.len());
            rest = tail;
            for (c, out) in mine.chunks_mut(TOUCHES_PER_CHUNK).enumerate() {
                let start = touches.start + c * TOUCHES_PER_CHUNK;
                parts.push((*k, start, out));
            }
        }
        let results = crate::parallel::parallel_map_mut(&mut parts, at.threads, |part| {
            let (k, start, out) = part;
            let (k, start) = (*k, *start);
            let kernel = views.kernel(at, k);
            self.each_weight(kernel, start..start + out.len(), unit_sigma, |i, w| {
                out[i - start] = w;
                Ok(())
            })
        });
        drop(parts);
        results.into_iter().collect::<Result<(), KernelError>>()?;
        Ok(touch)
    }

    /// The chunks of points of one tool each (the run's index, its points),
    /// in point order: the work items of the passes over touches, each
    /// point's values depending on that point alone (the same bits on any
    /// number of threads). Counted by [`point_chunks`], so that what it
    /// tells the tests holds here.
    fn chunks_of(&self, views: &TouchViews) -> Vec<(usize, Range<usize>)> {
        (views.runs.iter().enumerate())
            .flat_map(|(r, (_, run))| {
                (0..point_chunks(run.len())).map(move |c| {
                    let first = run.start + c * POINTS_PER_CHUNK;
                    (r, first..(first + POINTS_PER_CHUNK).min(run.end))
                })
            })
            .collect()
    }

    /// Each of `points`' cost `Σ dᵀA d − cᵀ(Σ A d)` (its touches' offsets
    /// `d` from the first, at the weighted centroid `c` of the offsets) and
    /// centroid, from the positions `xyz` of the touches from `first` on,
    /// handed to `each` point by point.
    fn point_costs(
        &self,
        points: &[crate::dataset::Point],
        xyz: &[[f64; 3]],
        first: usize,
        mut each: impl FnMut(f64, [f64; 3]),
    ) {
        for point in points {
            let origin = xyz[point.touches.start - first];
            let (mut ap, mut pap, mut sum) = ([0.0; 3], 0.0, [0.0; 6]);
            for i in point.touches.clone() {
                let a = &self.weights[i];
                let d: [f64; 3] = std::array::from_fn(|k| xyz[i - first][k] - origin[k]);
                let ad = sym_mul(a, &d);
                for (s, v) in ap.iter_mut().zip(&ad) {
                    *s += v;
                }
                pap += d[0] * ad[0] + d[1] * ad[1] + d[2] * ad[2];
                for (s, v) in sum.iter_mut().zip(a) {
                    *s += v;
                }
            }
            let c = sym_mul(&sym_inv(&sum), &ap);
            let cost = pap - (c[0] * ap[0] + c[1] * ap[1] + c[2] * ap[2]);
            each(cost, std::array::from_fn(|k| c[k] + origin[k]));
        }
    }

    /// [`TouchTerm::point_costs`] of the points `points` seen by
    /// `(at, poses)`, their positions computed a batch of whole points of
    /// at most [`TOUCH_BATCH`] touches at a time (or one larger point) into
    /// `xyz`, which holds such a batch.
    fn chunk_costs(
        &self,
        (at, poses): (&At<'_>, &crate::kernel::PreparedPoses),
        points: Range<usize>,
        xyz: &mut [[f64; 3]],
        each: &mut dyn FnMut(f64, [f64; 3]),
    ) -> Result<(), KernelError> {
        let all = self.data.points();
        let mut p = points.start;
        while p < points.end {
            let first = all[p].touches.start;
            let mut end = p + 1;
            while end < points.end && all[end].touches.end - first <= TOUCH_BATCH {
                end += 1;
            }
            let touches = first..all[end - 1].touches.end;
            at.kernel
                .positions(poses, touches.clone(), &mut xyz[..touches.len()])?;
            self.point_costs(&all[p..end], xyz, first, &mut *each);
            p = end;
        }
        Ok(())
    }

    /// The touches of the points `run` (contiguous).
    fn touches_of(&self, run: &Range<usize>) -> Range<usize> {
        let points = &self.data.points()[run.clone()];
        match (points.first(), points.last()) {
            (Some(a), Some(b)) => a.touches.start..b.touches.end,
            _ => 0..0,
        }
    }

    /// Refuses weights that are not finite numbers, naming the noise that
    /// made them: a σ whose square overflows (the weight is 0/0), or one
    /// that vanishes (the weight is 1/0). Positions are finite here, so the
    /// noise is the only cause.
    fn check(&self, weights: &[Sym3], unit_sigma: f64) -> Result<(), KernelError> {
        let Some(i) = weights.iter().position(refused) else {
            return Ok(());
        };
        let noise = &self.noise;
        let stated = match (noise.encoder_rad, noise.probe_mm) {
            (None, None) => format!("an assumed touch σ of {} mm", short(unit_sigma)),
            (e, p) => [
                e.map(|e| {
                    format!(
                        "encoder noise σ = {}° ({} rad)",
                        short(e.to_degrees()),
                        short(e)
                    )
                }),
                p.map(|p| format!("probe noise σ = {} mm", short(p))),
            ]
            .into_iter()
            .flatten()
            .collect::<Vec<_>>()
            .join(" and "),
        };
        Err(KernelError::Noise {
            of: NoiseOf::Touches,
            message: format!(
                "the touch weights are not finite positive numbers with {stated} (first at {}); \
                 {OVERFLOW}; state the instrument's noise (typically 0.001–0.1° per encoder and \
                 0.001–0.1 mm for the probe)",
                self.data.source().touch(i)
            ),
        })
    }

    /// Per point, the covariance of its centre under `weights`.
    fn centre_covariances(&self, weights: &[Sym3]) -> Vec<Sym3> {
        self.data
            .points()
            .iter()
            .map(|p| centroid_cov(&weights[p.touches.clone()]))
            .collect()
    }

    /// The largest relative change of any touch's weight at `kernel`, and
    /// every point's centre covariance under the new weights, made a chunk
    /// of whole points at a time and compared at once: at 10⁶ touches a
    /// second set of weights would be 48 MB.
    fn streamed_change(
        &self,
        at: &At<'_>,
        views: &TouchViews,
        unit_sigma: f64,
    ) -> Result<(f64, Vec<Sym3>), KernelError> {
        let data = self.data;
        // Chunks of whole points of one tool, so that each chunk's centroid
        // covariances are its own.
        let mut chunks = Vec::new();
        for (tool, run) in &views.runs {
            let mut first = run.start;
            for k in run.clone() {
                let p = &data.points()[k];
                if p.touches.end - data.points()[first].touches.start >= TOUCHES_PER_CHUNK
                    || k + 1 == run.end
                {
                    chunks.push((*tool, first..k + 1));
                    first = k + 1;
                }
            }
        }
        let results = parallel_map(&chunks, at.threads, |(tool, points)| {
            let kernel = views.kernel(at, *tool);
            let all = &data.points()[points.clone()];
            let mut change = 0.0_f64;
            let mut covs = Vec::with_capacity(points.len());
            let mut buffer = Vec::new();
            let mut point = all.iter().map(|p| p.touches.end).peekable();
            let touches = all[0].touches.start..all[all.len() - 1].touches.end;
            self.each_weight(kernel, touches, unit_sigma, |i, a| {
                change = change.max(touch_change(&a, &self.weights[i]));
                buffer.push(a);
                if point.next_if_eq(&(i + 1)).is_some() {
                    covs.push(centroid_cov(&buffer));
                    buffer.clear();
                }
                Ok(())
            })?;
            Ok::<_, KernelError>((change, covs))
        });
        let mut change = 0.0_f64;
        let mut covs = Vec::with_capacity(data.points().len());
        for r in results {
            let (c, v) = r?;
            change = change.max(c);
            covs.extend(v);
        }
        Ok((change, covs))
    }

    /// The point a touch belongs to (its index): the points' touches are
    /// contiguous and in order.
    fn point_of(&self, touch: usize) -> usize {
        self.data
            .points()
            .partition_point(|p| p.touches.end <= touch)
    }
}

/// Why a σ gives no weight.
const OVERFLOW: &str = "a σ this large overflows and one this small vanishes in double precision";

/// Whether a weight matrix is refused: it must be finite with a positive
/// diagonal (an overflowing covariance can also invert to exact zeros).
fn refused(a: &Sym3) -> bool {
    !a.iter().all(|v| v.is_finite()) || !a[..3].iter().all(|&v| v > 0.0)
}

/// One touch's weight at an arm: `A_i = (p²I + e² J_q J_qᵀ)⁻¹` with stated
/// noise, `I/σ²` without.
struct TouchWeight<'a> {
    kernel: &'a ArmKernel,
    data: &'a DataSet,
    stated: bool,
    e2: f64,
    p2: f64,
    unit: f64,
}

impl<'a> TouchWeight<'a> {
    fn new(kernel: &'a ArmKernel, data: &'a DataSet, noise: &Noise, touch_sigma_mm: f64) -> Self {
        TouchWeight {
            kernel,
            data,
            stated: noise.stated(),
            e2: noise.encoder_rad.unwrap_or(0.0).powi(2),
            p2: noise.probe_mm.unwrap_or(0.0).powi(2),
            unit: 1.0 / (touch_sigma_mm * touch_sigma_mm),
        }
    }

    /// The weights of touches `range`, in order, to `f(i, A_i)`; the joint
    /// Jacobians a batch of lanes at a time.
    fn each(
        &self,
        mut range: Range<usize>,
        mut f: impl FnMut(usize, Sym3) -> Result<(), KernelError>,
    ) -> Result<(), KernelError> {
        if !self.stated {
            let w = self.unit;
            return range.try_for_each(|i| f(i, [w, w, w, 0.0, 0.0, 0.0]));
        }
        let (e2, p2) = (self.e2, self.p2);
        let mut result = Ok(());
        self.kernel
            .for_each_joint_jacobian(self.data.poses(), range, |i, jq| {
                if result.is_ok() {
                    result = f(i, touch_weight(jq, e2, p2));
                }
            })?;
        result
    }
}

/// `(p²I + e² J_q J_qᵀ)⁻¹` of one touch's joint Jacobian.
#[inline(always)]
fn touch_weight(jq: &[[f64; 3]], e2: f64, p2: f64) -> Sym3 {
    let s = |a: usize, b: usize| jq.iter().map(|c| c[a] * c[b]).sum::<f64>() * e2;
    let cov = [
        p2 + s(0, 0),
        p2 + s(1, 1),
        p2 + s(2, 2),
        s(0, 1),
        s(0, 2),
        s(1, 2),
    ];
    sym_inv(&cov)
}

/// `‖a − b‖/‖b‖` in the Frobenius norm (off-diagonal entries count twice).
/// A touch weight the term would refuse counts as an infinite change.
fn touch_change(a: &Sym3, b: &Sym3) -> f64 {
    if refused(a) {
        return f64::INFINITY;
    }
    let norm = |a: &Sym3| {
        (a[..3].iter().map(|v| v * v).sum::<f64>()
            + 2.0 * a[3..].iter().map(|v| v * v).sum::<f64>())
        .sqrt()
    };
    let d: Sym3 = std::array::from_fn(|k| a[k] - b[k]);
    norm(&d) / norm(b)
}

impl Term for TouchTerm<'_> {
    fn name(&self) -> &str {
        "touches"
    }

    fn role(&self) -> super::Role {
        super::Role::Touches
    }

    fn rows(&self, _free: &[usize]) -> usize {
        3 * self.data.len()
    }

    fn eliminated(&self) -> usize {
        3 * self.data.points().len()
    }

    fn unit_weighted(&self) -> bool {
        !self.noise.stated()
    }

    /// Touches are relative (compared with their point's centroid): they
    /// see neither base motion. They fix the arm's size when a prismatic
    /// joint moves among the touches of a point: its reading is a length
    /// (mm), which scaling the arm's lengths does not scale.
    fn sees(&self) -> Sees {
        Sees {
            scale: slide_moves(self.data),
            ..Sees::default()
        }
    }

    /// The old weights are freed before the new ones are made: one set
    /// alive at a time (48 MB at 10⁶ touches).
    fn weigh(
        &mut self,
        at: &At<'_>,
        shared: &mut Shared,
        unit_sigma: f64,
    ) -> Result<(), TermError> {
        self.weights = Vec::new();
        let views = TouchViews::of(self.data, at)?;
        let weights = self.weights_at(at, &views, unit_sigma)?;
        self.check(&weights, unit_sigma)?;
        shared.centre_covariances = Some(self.centre_covariances(&weights));
        self.weights = weights;
        self.unit_sigma = unit_sigma;
        Ok(())
    }

    fn weight_change(
        &self,
        at: &At<'_>,
        shared: &mut Shared,
        unit_sigma: f64,
    ) -> Result<f64, TermError> {
        if self.weights.len() != self.data.len() {
            shared.centre_covariances = None;
            return Ok(f64::INFINITY);
        }
        let views = TouchViews::of(self.data, at)?;
        let (change, covs) = self.streamed_change(at, &views, unit_sigma)?;
        shared.centre_covariances = Some(covs);
        Ok(change)
    }

    fn accumulate(
        &self,
        at: &At<'_>,
        shared: &mut Shared,
        normal: &mut Normal,
    ) -> Result<f64, TermError> {
        let views = TouchViews::of(self.data, at)?;
        accumulate(self, at, &views, shared, normal)
    }

    fn add_cost(
        &self,
        at: &At<'_>,
        _free: &[usize],
        shared: &mut Shared,
        scratch: &mut Vec<[f64; 3]>,
        total: &mut f64,
    ) -> Result<(), TermError> {
        let data = self.data;
        let views = TouchViews::of(data, at)?;
        // Per run of one tool: its arm and corrected poses.
        let mut runs = Vec::with_capacity(views.runs.len());
        for (k, _) in &views.runs {
            let seen = views.at(at, *k);
            let effects = seen.corrected_poses_in(data.poses(), data.conditions(), &self.seen)?;
            runs.push((seen, effects));
        }
        let chunks = self.chunks_of(&views);
        // The positions a batch of touches at a time ([`TOUCH_BATCH`]), into
        // one slot of the scratch per thread: memory a few batches'
        // positions, not every touch's (24 MB at 10⁶ touches), and the
        // chunks on every thread.
        let largest = (data.points().iter()).map(|p| p.touches.len()).max();
        let widest = (chunks.iter()).map(|(_, c)| self.touches_of(c).len()).max();
        let most = TOUCH_BATCH
            .min(widest.unwrap_or(0))
            .max(largest.unwrap_or(0))
            .max(1);
        let slots = crate::parallel::threads_for(chunks.len(), at.threads);
        scratch.resize(slots * most, [0.0; 3]);
        let mut centroids = Vec::with_capacity(data.points().len());
        // Point by point in order, as one loop over the points adds.
        let mut add = |cost: f64, centroid| {
            *total += cost;
            centroids.push(centroid);
        };
        let chunk = |(r, c): &(usize, Range<usize>),
                     xyz: &mut [[f64; 3]],
                     each: &mut dyn FnMut(f64, [f64; 3])| {
            let (seen, effects) = &runs[*r];
            let poses = effects.as_ref().map_or(data.poses(), |e| &e.poses);
            self.chunk_costs((seen, poses), c.clone(), xyz, each)
        };
        if slots == 1 {
            // One thread (a small problem): each chunk's points summed as
            // they are costed, nothing allocated per pass.
            for c in &chunks {
                chunk(c, &mut scratch[..most], &mut add)?;
            }
        } else {
            let slots: Vec<std::sync::Mutex<&mut [[f64; 3]]>> = scratch
                .chunks_mut(most)
                .map(std::sync::Mutex::new)
                .collect();
            let run = |c: &(usize, Range<usize>)| {
                // As many slots as threads take chunks: one is free.
                let mut own = Vec::new();
                let mut slot = slots.iter().find_map(|s| s.try_lock().ok());
                let xyz = match &mut slot {
                    Some(slot) => &mut slot[..],
                    None => {
                        own.resize(most, [0.0; 3]);
                        &mut own[..]
                    }
                };
                let mut part = Vec::with_capacity(c.1.len());
                chunk(c, xyz, &mut |cost, centroid| part.push((cost, centroid)))?;
                Ok::<_, KernelError>(part)
            };
            for part in parallel_map(&chunks, at.threads, run) {
                for (cost, centroid) in part? {
                    add(cost, centroid);
                }
            }
        }
        shared.centres = Some(Centres {
            points: centroids,
            jacobians: Vec::new(),
        });
        Ok(())
    }

    /// `rᵀ A r / (1 − h)` per touch: `r` the touch's offset from its point's
    /// weighted centroid, `A` its weight, `h` its leverage — the trace over 3
    /// of its hat-matrix block: `tr(A (Σ A)⁻¹)`, the centroid's share, plus
    /// with `leverage` `tr(A J̃ N⁻¹ J̃ᵀ)`, the free parameters' (`J̃ = J −
    /// (Σ A)⁻¹ Σ A J` its Jacobian with the centroid profiled out, as the
    /// normal equations have it). Summed over touches the two are `3k` and
    /// `p`: the residuals' missing degrees of freedom, so each corrected
    /// residual is about `χ²₃` without a global dof factor, and a touch of
    /// high leverage is not flagged for it. One point at a time: memory
    /// stays the output's and a point's Jacobians; linear in the touches.
    fn standardised(
        &self,
        at: &At<'_>,
        leverage: Option<&ParameterLeverage>,
    ) -> Result<Option<Standardised>, TermError> {
        let data = self.data;
        let views = TouchViews::of(data, at)?;
        let arm = at.layout.arm_columns();
        // Per run of one tool: its arm, corrected poses, leverage columns.
        let mut runs = Vec::with_capacity(views.runs.len());
        for (k, _) in &views.runs {
            let seen = views.at(at, *k);
            let (cols, m) = leverage.map_or((Vec::new(), Vec::new()), |l| {
                let geo: Vec<(usize, usize)> = (l.free().iter().enumerate())
                    .filter(|(_, c)| **c < arm)
                    .map(|(a, &c)| (a, c))
                    .collect();
                l.restricted_to(&tool_columns(&geo, l.free(), at.layout, views.block(*k)))
            });
            // The corrections' Jacobian factors too when the leverage needs
            // their columns (as the normal equations have them).
            let effects = if cols.is_empty() {
                seen.corrected_poses_in(data.poses(), data.conditions(), &self.seen)?
            } else {
                seen.effects_in(data.poses(), data.conditions(), &self.seen)?
            };
            runs.push((seen, effects, cols, m));
        }
        // Chunks of points of one tool, on up to `at.threads` threads: each
        // point's values depend on that point alone, so the same bits on
        // any count.
        let chunks = self.chunks_of(&views);
        // Each chunk writes its own touches' slice of the output (a point's
        // touches are contiguous, in point order): no second copy of the
        // values, which at 10⁶ touches would be 8 MB more at the peak.
        let mut values = vec![0.0; data.len()];
        let mut slots = Vec::new();
        let mut rest = values.as_mut_slice();
        for (r, c) in chunks {
            let touches = self.touches_of(&c).len();
            let (slot, tail) = std::mem::take(&mut rest).split_at_mut(touches);
            rest = tail;
            slots.push((r, c, slot));
        }
        let run = |(r, c, slot): &mut (usize, Range<usize>, &mut [f64])| {
            let (seen, effects, cols, m) = &runs[*r];
            self.standardised_points(seen, effects.as_ref(), (cols, m), c, slot)
        };
        let done = crate::parallel::parallel_map_mut(&mut slots, at.threads, run);
        done.into_iter().collect::<Result<(), KernelError>>()?;
        drop(slots);
        Ok(Some(Standardised { rows: 3, values }))
    }

    fn observations(&self) -> usize {
        self.data.len()
    }

    /// The touch's file:line; its group the point's label, and the tool's
    /// name when another tool than the probe touched it (a label touched
    /// by two tools is two points).
    fn origin(&self, i: usize) -> Origin {
        let p = self.point_of(i);
        let point = &self.data.points()[p];
        let group = match self.data.touch_tools() {
            Some(t) if t.of_point(p) != 0 => {
                format!("{} ({})", point.label, t.names()[t.of_point(p)])
            }
            _ => point.label.clone(),
        };
        Origin {
            at: self.data.source().touch(i).to_string(),
            group,
        }
    }

    /// Touch `i`'s matrix `A_i` multiplied by `w[i]`.
    fn weigh_observations(&mut self, w: &[f64]) -> bool {
        for (a, &w) in self.weights.iter_mut().zip(w) {
            *a = a.map(|v| v * w);
        }
        true
    }

    /// The median over touches of `sqrt(trace(Σ_i)/3)`.
    fn typical_sigma(&self) -> Option<f64> {
        let mut s: Vec<f64> = self
            .weights
            .iter()
            .map(|a| (sym_inv(a)[..3].iter().sum::<f64>() / 3.0).sqrt())
            .collect();
        let m = s.len() / 2;
        Some(crate::stats::kth_smallest(&mut s, m).unwrap_or(f64::NAN))
    }
}

/// [`TouchTerm::standardised`]'s buffers for a chunk of points: one
/// point's positions, the free columns of its touches' Jacobians (`q` per
/// touch) and `J̄`; and the touches waiting for their parameter shares.
struct PointScratch {
    xyz: Vec<[f64; 3]>,
    jac: Vec<[f64; 3]>,
    mean: Vec<[f64; 3]>,
    group: ShareGroup,
}

impl PointScratch {
    fn new(touches: usize, q: usize) -> PointScratch {
        PointScratch {
            xyz: vec![[0.0; 3]; touches],
            jac: vec![[0.0; 3]; touches * q],
            mean: vec![[0.0; 3]; q],
            group: ShareGroup::new(q),
        }
    }

    /// The standardised residuals of the point's touches, from their
    /// positions (and Jacobians, when `m`, the `q × q` block of `N⁻¹`
    /// row-major, is not empty) under their weights `a`, into `out` from
    /// `at` on: at once without `m`; with it, as their parameter shares are
    /// computed, [`LANES`] touches at a time on lanes `L` (a last group
    /// waits for the next point's touches, or for [`ShareGroup::flush`]).
    #[inline(always)]
    fn point<L: Batch>(&mut self, a: &[Sym3], m: &[f64], out: &mut [f64], at: usize) {
        let q = self.mean.len();
        let (mut sum_a, mut sum_ap) = ([0.0; 6], [0.0; 3]);
        self.mean.fill([0.0; 3]);
        for (t, a) in a.iter().enumerate() {
            let ap = sym_mul(a, &self.xyz[t]);
            for k in 0..6 {
                sum_a[k] += a[k];
            }
            for k in 0..3 {
                sum_ap[k] += ap[k];
            }
            for (g, j) in self.mean.iter_mut().zip(&self.jac[t * q..(t + 1) * q]) {
                let aj = sym_mul(a, j);
                (0..3).for_each(|k| g[k] += aj[k]);
            }
        }
        let inv = sym_inv(&sum_a);
        let c = sym_mul(&inv, &sum_ap);
        for g in &mut self.mean {
            *g = sym_mul(&inv, g);
        }
        for (t, a) in a.iter().enumerate() {
            let r: [f64; 3] = std::array::from_fn(|k| self.xyz[t][k] - c[k]);
            let ar = sym_mul(a, &r);
            let quad = r[0] * ar[0] + r[1] * ar[1] + r[2] * ar[2];
            // tr(A·inv) for symmetric A and inv: the centroid's share.
            let tr = a[0] * inv[0]
                + a[1] * inv[1]
                + a[2] * inv[2]
                + 2.0 * (a[3] * inv[3] + a[4] * inv[4] + a[5] * inv[5]);
            if q == 0 {
                out[at + t] = standardised(quad, tr);
                continue;
            }
            let jac = &self.jac[t * q..(t + 1) * q];
            if self.group.push(at + t, quad, tr, a, jac, &self.mean) {
                self.group.flush::<L>(m, out);
            }
        }
    }
}

/// `rᵀ A r / (1 − h)`, `h` the leverage from `tr`, the trace of the
/// touch's hat-matrix block (its centroid's and its parameters' shares).
#[inline(always)]
fn standardised(quad: f64, tr: f64) -> f64 {
    let h = (tr / 3.0).clamp(0.0, 0.999);
    quad / (1.0 - h)
}

/// Up to [`LANES`] touches, of one point or several, waiting for their
/// parameter shares `tr(A J̃ M J̃ᵀ)`, `J̃ = J − J̄` (`3q²` operations a
/// touch): their `J̃` and weights `A` as lanes (a touch a lane; `A J̃` is
/// made from them on the lanes when the group is full), and per lane
/// where its value goes, its `rᵀ A r` and its centroid's share.
///
/// Each lane does what one touch alone would, in its order — `y = M (A
/// J̃)ᵀ` a row at a time, each entry summed over the columns in order, then
/// the rows' terms `J̃_r · y_r` added in row order — so the same bits as
/// one touch at a time. Before, the lanes held eight rows of `M` for one
/// touch: each row's `J̃_r · y_r` was then a scalar tail as long as the
/// sums it closed. Touches of consecutive points share a group: a point
/// has few touches, and padding each point's last group wasted a fifth of
/// the lanes.
struct ShareGroup {
    d: Vec<[[f64; LANES]; 3]>,
    aj: Vec<[[f64; LANES]; 3]>,
    a: [[f64; LANES]; 6],
    waiting: [(usize, f64, f64); LANES],
    len: usize,
}

impl ShareGroup {
    fn new(q: usize) -> ShareGroup {
        ShareGroup {
            d: vec![[[0.0; LANES]; 3]; q],
            aj: vec![[[0.0; LANES]; 3]; q],
            a: [[0.0; LANES]; 6],
            waiting: [(0, 0.0, 0.0); LANES],
            len: 0,
        }
    }

    /// Touch `index` (of the output) into the next lane: its `rᵀ A r`
    /// `quad`, centroid share `tr`, weight `a`, Jacobian's free columns
    /// `jac` and its point's `J̄` `mean`. True when the group is full.
    #[inline(always)]
    fn push(
        &mut self,
        index: usize,
        quad: f64,
        tr: f64,
        a: &Sym3,
        jac: &[[f64; 3]],
        mean: &[[f64; 3]],
    ) -> bool {
        let l = self.len;
        for (d, (j, mean)) in self.d.iter_mut().zip(jac.iter().zip(mean)) {
            for k in 0..3 {
                d[k][l] = j[k] - mean[k];
            }
        }
        for (lanes, a) in self.a.iter_mut().zip(a) {
            lanes[l] = *a;
        }
        self.waiting[l] = (index, quad, tr);
        self.len += 1;
        self.len == LANES
    }

    /// The waiting touches' values into `out`, `m` the `q × q` block of
    /// `N⁻¹` row-major; the group empty after. Lanes past the waiting ones
    /// hold an earlier group's touches: computed, not read.
    #[inline(always)]
    fn flush<L: Batch>(&mut self, m: &[f64], out: &mut [f64]) {
        if self.len == 0 {
            return;
        }
        let shares = self.shares::<L>(m);
        for (&(index, quad, tr), share) in self.waiting[..self.len].iter().zip(shares) {
            out[index] = standardised(quad, tr + share);
        }
        self.len = 0;
    }

    /// Every lane's parameter share, `m` the `q × q` block of `N⁻¹`
    /// row-major.
    #[inline(always)]
    fn shares<L: Batch>(&mut self, m: &[f64]) -> [f64; LANES] {
        // `A J̃` on the lanes: what `sym_mul` does for each touch. Written
        // out, not `sym_mul` made generic over lanes: that cost the normal
        // pass's f64 calls 1–2 % more instructions (callgrind), though the
        // same bits.
        let a = self.a.map(|v| L::load(&v));
        for (aj, d) in self.aj.iter_mut().zip(&self.d) {
            let d = [L::load(&d[0]), L::load(&d[1]), L::load(&d[2])];
            let y = [
                a[0] * d[0] + a[3] * d[1] + a[4] * d[2],
                a[3] * d[0] + a[1] * d[1] + a[5] * d[2],
                a[4] * d[0] + a[5] * d[1] + a[2] * d[2],
            ];
            (0..3).for_each(|k| y[k].store(&mut aj[k]));
        }
        group_shares::<L>(m, &self.d, &self.aj)
    }
}

/// What [`TouchTerm::standardised_points`] runs on the lanes for one point.
struct OnePoint<'s> {
    scratch: &'s mut PointScratch,
    a: &'s [Sym3],
    m: &'s [f64],
    out: &'s mut [f64],
    at: usize,
}

impl LaneOp for OnePoint<'_> {
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        self.scratch.point::<L>(self.a, self.m, self.out, self.at)
    }
}

/// What [`TouchTerm::standardised_points`] runs on the lanes after a
/// chunk's last point: its last touches' values.
struct Flush<'s> {
    group: &'s mut ShareGroup,
    m: &'s [f64],
    out: &'s mut [f64],
}

impl LaneOp for Flush<'_> {
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        self.group.flush::<L>(self.m, self.out)
    }
}

/// Rows of `M` that [`group_shares`] runs together: their `3 · SHARE_ROWS`
/// chains of additions hide each other's latency.
const SHARE_ROWS: usize = 3;

/// A group of touches' parameter shares `Σ_r J̃_r · (M (A J̃)ᵀ)_r` (see
/// [`ShareGroup`]), `d` their `J̃` and `aj` their
/// `A J̃` as lanes, `m` row-major `q × q`.
#[inline(always)]
fn group_shares<L: Batch>(
    m: &[f64],
    d: &[[[f64; LANES]; 3]],
    aj: &[[[f64; LANES]; 3]],
) -> [f64; LANES] {
    let q = d.len();
    let mut share = L::from(0.0);
    let whole = q - q % SHARE_ROWS;
    for first in (0..whole).step_by(SHARE_ROWS) {
        let y = rows_times::<L, SHARE_ROWS>(m, first, aj);
        for (d, y) in d[first..].iter().zip(&y) {
            share = share + row_term(d, y);
        }
    }
    for (r, d) in d.iter().enumerate().skip(whole) {
        let [y] = rows_times::<L, 1>(m, r, aj);
        share = share + row_term(d, &y);
    }
    share.to_array()
}

/// `J̃_r · y_r` on the lanes, summed in coordinate order.
#[inline(always)]
fn row_term<L: Batch>(d: &[[f64; LANES]; 3], y: &[L; 3]) -> L {
    (L::load(&d[0]) * y[0] + L::load(&d[1]) * y[1]) + L::load(&d[2]) * y[2]
}

/// `y[i][k] = Σ_b M[first + i][b] · aj[b][k]` for `R` rows of `M`
/// (row-major, `q × q`), each summed over `b` in order, on the lanes.
#[inline(always)]
fn rows_times<L: Batch, const R: usize>(
    m: &[f64],
    first: usize,
    aj: &[[[f64; LANES]; 3]],
) -> [[L; 3]; R] {
    let q = aj.len();
    let rows: [&[f64]; R] = std::array::from_fn(|i| &m[(first + i) * q..][..q]);
    let zero = L::from(0.0);
    let mut y = [[zero; 3]; R];
    for (b, ajb) in aj.iter().enumerate() {
        let v = [L::load(&ajb[0]), L::load(&ajb[1]), L::load(&ajb[2])];
        for (y, row) in y.iter_mut().zip(&rows) {
            let mb = L::from(row[b]);
            for k in 0..3 {
                y[k] = y[k] + mb * v[k];
            }
        }
    }
    y
}

/// The touches' contribution at `at` over `normal.free()`: chunks of points
/// on up to `at.threads` threads (the result does not depend on it), added
/// in chunk order; the centroids (and, when a later term needs them, their
/// Jacobians) left in `shared`.
fn accumulate(
    term: &TouchTerm<'_>,
    at: &At<'_>,
    views: &TouchViews,
    shared: &mut Shared,
    normal: &mut Normal,
) -> Result<f64, TermError> {
    let data = term.data;
    let np = data.points().len();
    let need_mean = shared.want_centre_jacobians;
    // Touches move with the arm only: their sums run over the free
    // geometry and correction columns, placed at those columns' rows of
    // `normal` (the identity when no other column is free); a tool's
    // touches over its offset block's columns instead of the probe's.
    let arm = at.layout.arm_columns();
    let geo: Vec<(usize, usize)> = (normal.free.iter().enumerate())
        .filter(|(_, c)| **c < arm)
        .map(|(a, &c)| (a, c))
        .collect();
    let mut runs = Vec::with_capacity(views.runs.len());
    for (k, _) in &views.runs {
        let pairs = tool_columns(&geo, &normal.free, at.layout, views.block(*k));
        let (at_free, free): (Vec<usize>, Vec<usize>) = pairs.into_iter().unzip();
        let effects = (views.at(at, *k)).effects_in(data.poses(), data.conditions(), &term.seen)?;
        runs.push((views.kernel(at, *k), effects, at_free, free));
    }
    let chunks = term.chunks_of(views);
    let p = normal.free.len();
    let run = |(r, c): &(usize, Range<usize>)| {
        let (kernel, effects, _, free) = &runs[*r];
        let part = chunk(kernel, term, effects.as_ref(), free, c.clone(), need_mean);
        (*r, part)
    };
    let partials = parallel_map(&chunks, at.threads, run);
    let mut cost = 0.0;
    let mut centres = Centres {
        points: Vec::with_capacity(np),
        jacobians: Vec::with_capacity(if need_mean { np } else { 0 }),
    };
    for (r, part) in partials {
        let part = part?;
        let at_free = &runs[r].2;
        let q = at_free.len();
        if at_free.iter().enumerate().all(|(i, &a)| i == a) && q == p {
            for (o, v) in normal.jtj.iter_mut().zip(&part.jtj) {
                *o += v;
            }
            for (o, v) in normal.jtr.iter_mut().zip(&part.jtr) {
                *o += v;
            }
            centres.jacobians.extend(part.mean_j);
        } else {
            for (a, &ra) in at_free.iter().enumerate() {
                normal.jtr[ra] += part.jtr[a];
                for (b, &rb) in at_free.iter().enumerate() {
                    normal.jtj[ra * p + rb] += part.jtj[a * q + b];
                }
            }
            centres.jacobians.extend(part.mean_j.into_iter().map(|m| {
                let mut full = vec![[0.0; 3]; p];
                for (&ra, v) in at_free.iter().zip(m) {
                    full[ra] = v;
                }
                full
            }));
        }
        cost += part.cost;
        centres.points.extend(part.centroids);
    }
    shared.centres = Some(centres);
    Ok(cost)
}

/// Per-point sums: `G = Σ A J` (3 × p), `Σ Jᵀ A p̃`, `Σ A p̃`, `Σ p̃ᵀA p̃`,
/// `S = Σ A`, with `p̃` the position relative to the point's first touch (no
/// cancellation of metre-sized coordinates).
///
/// The per-column sums are held by coordinate (`g[k]` is row `k` of `G`),
/// each padded to the [`Rank3::stride`], so that a touch's columns are
/// updated a whole lane at a time: every entry still gets the same
/// operations in the same order as one column at a time.
struct PointSums {
    g: [Vec<f64>; 3],
    jap: Vec<f64>,
    ap: [f64; 3],
    pap: f64,
    s: Sym3,
    started: bool,
    origin: [f64; 3],
    /// Up to [`super::rank3::BLOCK`] touches of one point not yet in `JᵀAJ`.
    rank3: Rank3,
    /// Scratch: the point's `J̄ = S⁻¹ G`, by coordinate like `g`.
    mean: [Vec<f64>; 3],
}

/// What one chunk of points contributes.
struct Partial {
    jtj: Vec<f64>,
    jtr: Vec<f64>,
    cost: f64,
    /// Per point of the chunk: centroid, and `J̄` (3 × p) if lengths need it.
    centroids: Vec<[f64; 3]>,
    mean_j: Vec<Vec<[f64; 3]>>,
}

impl PointSums {
    fn new(p: usize) -> PointSums {
        let rank3 = Rank3::new(p);
        let w = rank3.stride();
        PointSums {
            g: std::array::from_fn(|_| vec![0.0; w]),
            jap: vec![0.0; w],
            ap: [0.0; 3],
            pap: 0.0,
            s: [0.0; 6],
            started: false,
            origin: [0.0; 3],
            rank3,
            mean: std::array::from_fn(|_| vec![0.0; w]),
        }
    }

    /// Ready for the next point, keeping the buffers.
    fn reset(&mut self) {
        for g in &mut self.g {
            g.fill(0.0);
        }
        self.jap.fill(0.0);
        self.ap = [0.0; 3];
        self.pap = 0.0;
        self.s = [0.0; 6];
        self.started = false;
    }

    /// Adds one touch: position, weight, and its free Jacobian columns
    /// compacted by coordinate, as [`ArmKernel::for_each_free_jacobian`]
    /// hands them over (their padding is zeros): read as the slot's rows
    /// are, and written into it in the same sweep, not copied first (a
    /// `memcpy` call per row). `jtj` is `p` rows of [`Rank3::stride`]
    /// (lower triangle meaningful).
    #[inline(always)]
    fn add(&mut self, pos: &[f64; 3], a: &Sym3, rows: [&[[f64; LANES]]; 3], jtj: &mut [f64]) {
        if !self.started {
            self.origin = *pos;
            self.started = true;
        }
        let d: [f64; 3] = std::array::from_fn(|k| pos[k] - self.origin[k]);
        let ad = sym_mul(a, &d);
        for (s, v) in self.ap.iter_mut().zip(&ad) {
            *s += v;
        }
        self.pap += d[0] * ad[0] + d[1] * ad[1] + d[2] * ad[2];
        for (s, v) in self.s.iter_mut().zip(a) {
            *s += v;
        }
        let slot = self.rank3.padded_slot();
        let [jx, jy, jz] = slot.j;
        // Whole lanes over the padded rows (the padding's `J` is zero, in
        // the slot and in `rows`): `A·J` as `sym_mul` forms it, then `G`
        // and `Jᵀ A p̃`. Lanes of arrays, each loaded into a local before
        // it is used, so the loop needs no check of whether the rows
        // overlap.
        let k = self.jap.len() / LANES;
        let [ax, ay, az] = slot.aj;
        let (jx, jy, jz) = (lanes_mut(jx, k), lanes_mut(jy, k), lanes_mut(jz, k));
        let [rx, ry, rz] = rows.map(|r| &r[..k]);
        let (ax, ay, az) = (lanes_mut(ax, k), lanes_mut(ay, k), lanes_mut(az, k));
        let [gx, gy, gz] = &mut self.g;
        let (gx, gy, gz) = (lanes_mut(gx, k), lanes_mut(gy, k), lanes_mut(gz, k));
        let jap = lanes_mut(&mut self.jap, k);
        for c in 0..k {
            let (x, y, z) = (rx[c], ry[c], rz[c]);
            (jx[c], jy[c], jz[c]) = (x, y, z);
            let (mut g, mut p) = ([gx[c], gy[c], gz[c]], jap[c]);
            let mut wa = [[0.0; LANES]; 3];
            for l in 0..LANES {
                let [wx, wy, wz] = sym_mul(a, &[x[l], y[l], z[l]]);
                (g[0][l], g[1][l], g[2][l]) = (g[0][l] + wx, g[1][l] + wy, g[2][l] + wz);
                p[l] += wx * d[0] + wy * d[1] + wz * d[2];
                (wa[0][l], wa[1][l], wa[2][l]) = (wx, wy, wz);
            }
            (gx[c], gy[c], gz[c], jap[c]) = (g[0], g[1], g[2], p);
            (ax[c], ay[c], az[c]) = (wa[0], wa[1], wa[2]);
        }
        self.rank3.add(jtj);
    }

    /// Closes the point: its Schur term into the lower triangle of `jtj`
    /// (rows of [`Rank3::stride`]), its gradient and cost; resets for the
    /// next point.
    #[inline(always)]
    fn finish(&mut self, part: &mut Partial, jtj: &mut [f64], need_mean: bool) {
        self.rank3.flush(jtj);
        let (p, w) = (self.rank3.columns(), self.jap.len());
        let cinv = sym_inv(&self.s);
        let c = sym_mul(&cinv, &self.ap);
        // Σ p̃ᵀAp̃ − cᵀ S c, with S c = Σ A p̃
        part.cost += self.pap - (c[0] * self.ap[0] + c[1] * self.ap[1] + c[2] * self.ap[2]);
        let k = w / LANES;
        let [gx, gy, gz] = &self.g;
        let (gx, gy, gz) = (lanes(gx, k), lanes(gy, k), lanes(gz, k));
        let [mx, my, mz] = &mut self.mean;
        let (mx, my, mz) = (lanes_mut(mx, k), lanes_mut(my, k), lanes_mut(mz, k));
        for q in 0..k {
            let (x, y, z) = (gx[q], gy[q], gz[q]);
            let mut m = [[0.0; LANES]; 3];
            for l in 0..LANES {
                [m[0][l], m[1][l], m[2][l]] = sym_mul(&cinv, &[x[l], y[l], z[l]]);
            }
            (mx[q], my[q], mz[q]) = (m[0], m[1], m[2]);
        }
        for i in 0..p {
            let gi = [self.g[0][i], self.g[1][i], self.g[2][i]];
            part.jtr[i] += self.jap[i] - (gi[0] * c[0] + gi[1] * c[1] + gi[2] * c[2]);
            // Columns `b ≤ i`, in whole lanes: the entries past the diagonal
            // in the last lane are the upper triangle's scratch.
            let end = i / LANES + 1;
            let row = lanes_mut(&mut jtj[i * w..(i + 1) * w], end);
            // Each lane loaded whole before it is stored: written into the
            // row in place, LLVM could not tell the row from `J̄` and ran
            // rows shorter than four lanes a value at a time.
            for (r, ((x, y), z)) in row.iter_mut().zip(mx.iter().zip(my.iter()).zip(mz.iter())) {
                let (x, y, z, mut v) = (*x, *y, *z, *r);
                for l in 0..LANES {
                    v[l] -= gi[0] * x[l] + gi[1] * y[l] + gi[2] * z[l];
                }
                *r = v;
            }
        }
        part.centroids
            .push(std::array::from_fn(|k| c[k] + self.origin[k]));
        if need_mean {
            let [mx, my, mz] = &self.mean;
            part.mean_j
                .push((0..p).map(|i| [mx[i], my[i], mz[i]]).collect());
        }
        self.reset();
    }
}

/// The first `k` lanes of `v` (whose length is a whole number of lanes).
#[inline(always)]
fn lanes(v: &[f64], k: usize) -> &[[f64; LANES]] {
    &v.as_chunks::<LANES>().0[..k]
}

/// [`lanes`], to write.
#[inline(always)]
fn lanes_mut(v: &mut [f64], k: usize) -> &mut [[f64; LANES]] {
    &mut v.as_chunks_mut::<LANES>().0[..k]
}

/// A chunk's buffers, kept by its thread from one normal pass to the next:
/// a fit makes a pass per step, and the point sums' dozen buffers were
/// allocated and zeroed afresh each time (a tenth of a 100-touch pass in
/// the allocator). Taken back only in the state a new one starts in.
struct ChunkScratch {
    sums: PointSums,
    /// The padded lower triangle (see [`Rank3::flush`]).
    jtj: Vec<f64>,
}

/// Buffers of different widths a thread keeps: a fit's start normal is of
/// every column, its steps' of the free ones.
const KEPT_WIDTHS: usize = 4;

thread_local! {
    static SCRATCH: std::cell::RefCell<Vec<ChunkScratch>> = const { std::cell::RefCell::new(Vec::new()) };
}

impl ChunkScratch {
    /// This thread's buffers for `p` columns, as new: the sums reset (every
    /// chunk ends with a point's [`PointSums::finish`]), the triangle
    /// zeroed.
    fn take(p: usize) -> ChunkScratch {
        let kept = SCRATCH.with_borrow_mut(|kept| {
            let at = kept.iter().position(|s| s.sums.rank3.columns() == p)?;
            Some(kept.swap_remove(at))
        });
        match kept {
            Some(mut s) => {
                s.jtj.fill(0.0);
                s
            }
            None => {
                let sums = PointSums::new(p);
                let jtj = sums.rank3.matrix();
                ChunkScratch { sums, jtj }
            }
        }
    }

    /// Keeps the buffers for the thread's next chunk of this width (another
    /// width makes room when [`KEPT_WIDTHS`] are kept).
    fn keep(self) {
        SCRATCH.with_borrow_mut(|kept| {
            if kept.len() == KEPT_WIDTHS {
                kept.remove(0);
            }
            kept.push(self);
        });
    }
}

/// One chunk of points' sums over the geometry columns `free`.
fn chunk(
    kernel: &ArmKernel,
    term: &TouchTerm<'_>,
    effects: Option<&Effects>,
    free: &[usize],
    points: Range<usize>,
    need_mean: bool,
) -> Result<Partial, KernelError> {
    let (data, weights) = (term.data, &term.weights);
    let p = free.len();
    let mut part = Partial {
        jtj: vec![0.0; p * p],
        jtr: vec![0.0; p],
        cost: 0.0,
        centroids: Vec::with_capacity(points.len()),
        mean_j: Vec::with_capacity(if need_mean { points.len() } else { 0 }),
    };
    let all = data.points();
    let touches = all[points.start].touches.start..all[points.end - 1].touches.end;
    // A chunk that fails part-way leaves its buffers mid-sum: they are
    // dropped, not kept (`?` returns before `keep`).
    let mut scratch = ChunkScratch::take(p);
    let ChunkScratch { sums, jtj } = &mut scratch;
    let mut point = points.start;
    let mut finite = true;
    // Inlined into the kernel's loop, so the accumulation is compiled with
    // the same target features (AVX2 where the CPU has it; a transform
    // after the chain or a chain not inlined takes the kernel's fallback).
    // (`identity`: an attribute on a closure is accepted as an argument.)
    let mut add = std::convert::identity(
        #[inline(always)]
        |i: usize, pos: &[f64; 3], rows: [&[[f64; LANES]]; 3]| {
            if i == all[point].touches.end {
                sums.finish(&mut part, jtj, need_mean);
                point += 1;
            }
            finite &= pos.iter().all(|v| v.is_finite());
            sums.add(pos, &weights[i], rows, jtj);
        },
    );
    match effects {
        // Two loops, not one asking per touch which it is: the question
        // cost the plain fit 0.4–0.8 % of its instructions (callgrind,
        // `lm-solve/100` and `/10000`).
        None => kernel.for_each_free_jacobian(
            data.poses(),
            touches,
            free,
            #[inline(always)]
            |i, pos, rows| add(i, pos, rows.each_ref().map(|r| &**r)),
        )?,
        // A model beyond geometry asks the kernel for the chain's columns
        // its corrections scale, and finishes them in place.
        Some(e) => {
            let plan = e.free_plan(free, kernel.param_count());
            kernel.for_each_free_jacobian(
                &e.poses,
                touches,
                &plan.chain,
                #[inline(always)]
                |i, pos, mut rows| {
                    e.finish_free(&plan, i, pos, rows.each_mut().map(|r| &mut **r));
                    add(i, pos, rows.each_ref().map(|r| &**r));
                },
            )?
        }
    }
    run_lanes(ChunkTail {
        sums,
        jtj,
        part: &mut part,
        need_mean,
    });
    scratch.keep();
    if !finite {
        part.cost = f64::INFINITY;
    }
    Ok(part)
}

/// A chunk's last point closed and its padded triangle copied out whole:
/// on the lanes, so that this tail compiles with the same target features
/// as the kernel's loop that ran the chunk's other points (the same
/// operations, so the same bits either way).
struct ChunkTail<'s> {
    sums: &'s mut PointSums,
    jtj: &'s mut [f64],
    part: &'s mut Partial,
    need_mean: bool,
}

impl LaneOp for ChunkTail<'_> {
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        let ChunkTail {
            sums,
            jtj,
            part,
            need_mean,
        } = self;
        sums.finish(part, jtj, need_mean);
        let p = sums.rank3.columns();
        for a in 0..p {
            for b in 0..=a {
                let v = sums.rank3.entry(jtj, a, b);
                part.jtj[a * p + b] = v;
                part.jtj[b * p + a] = v;
            }
        }
    }
}

/// Whether some prismatic joint's reading differs between two touches of
/// one point (beyond rounding): the touches then see the arm's size.
fn slide_moves(data: &DataSet) -> bool {
    let mask = data.poses().prismatic_mask();
    if mask == 0 {
        return false;
    }
    let slides: Vec<usize> = (0..data.joints()).filter(|j| mask >> j & 1 == 1).collect();
    data.points().iter().any(|point| {
        slides.iter().any(|&j| {
            let (lo, hi) = (point.touches.clone())
                .map(|i| data.reading(i)[j])
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), q| {
                    (lo.min(q), hi.max(q))
                });
            hi - lo > 1e-9 * hi.abs().max(lo.abs()).max(1.0)
        })
    })
}

#[cfg(test)]
mod share_tests {
    use super::*;

    /// A group's parameter shares on the lanes the CPU has.
    struct Shares<'a> {
        g: &'a mut ShareGroup,
        m: &'a [f64],
    }

    impl LaneOp for Shares<'_> {
        type Output = [f64; LANES];
        fn run<L: Batch>(self) -> [f64; LANES] {
            self.g.shares::<L>(self.m)
        }
    }

    /// The parameter shares with touches side by side (each with its own
    /// `J̄`, as touches of consecutive points), on the portable lanes and
    /// on the CPU's, are the same bits as one touch and one row at a time
    /// (three chains of sums per row, rows in order) — with every count of
    /// rows left over from [`SHARE_ROWS`] and of touches in a group; and a
    /// flushed group writes each touch's value where it belongs.
    #[test]
    fn the_parameter_shares_are_the_same_bits_as_row_by_row() {
        let mut rng = crate::random::rng(9, 0);
        let mut draw = || rand::RngExt::random_range(&mut rng, -1.0..1.0);
        for (q, n) in [
            (1, 1),
            (3, 4),
            (4, 2),
            (5, 3),
            (7, 4),
            (8, 2),
            (9, 1),
            (16, 3),
            (21, 4),
            (27, 3),
        ] {
            let jac: Vec<[f64; 3]> = (0..n * q).map(|_| [draw(), draw(), draw()]).collect();
            let mean: Vec<[f64; 3]> = (0..n * q).map(|_| [draw(), draw(), draw()]).collect();
            let m: Vec<f64> = (0..q * q).map(|_| draw()).collect();
            let a: Vec<Sym3> = (0..n)
                .map(|_| {
                    [
                        2.0 + draw(),
                        2.0 + draw(),
                        2.0 + draw(),
                        draw(),
                        draw(),
                        draw(),
                    ]
                })
                .collect();
            // One touch and one row at a time, as before.
            let want: Vec<f64> = (0..n)
                .map(|t| {
                    let (j, mean) = (&jac[t * q..(t + 1) * q], &mean[t * q..(t + 1) * q]);
                    let aj: Vec<[f64; 3]> = (j.iter().zip(mean))
                        .map(|(j, mean)| sym_mul(&a[t], &std::array::from_fn(|k| j[k] - mean[k])))
                        .collect();
                    let mut want = 0.0;
                    for (row, (j, mean)) in m.chunks_exact(q).zip(j.iter().zip(mean)) {
                        let mut y = [0.0; 3];
                        for (&mab, aj) in row.iter().zip(&aj) {
                            (0..3).for_each(|k| y[k] += mab * aj[k]);
                        }
                        want += (0..3).map(|k| (j[k] - mean[k]) * y[k]).sum::<f64>();
                    }
                    want
                })
                .collect();
            let mut g = ShareGroup::new(q);
            // Values written in reverse order, from the centroid shares 0.1 t.
            let tr = |t: usize| 0.1 * t as f64;
            for t in 0..n {
                let (j, mean) = (&jac[t * q..(t + 1) * q], &mean[t * q..(t + 1) * q]);
                assert_eq!(
                    g.push(n - 1 - t, 1.0 + t as f64, tr(t), &a[t], j, mean),
                    t + 1 == LANES
                );
            }
            let bits = |v: &[f64]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            let portable = g.shares::<crate::kernel::Lanes>(&m);
            assert_eq!(
                bits(&portable[..n]),
                bits(&want),
                "q {q}, {n} touches, portable lanes"
            );
            let cpu = run_lanes(Shares { g: &mut g, m: &m });
            assert_eq!(
                bits(&cpu[..n]),
                bits(&want),
                "q {q}, {n} touches, the CPU's lanes"
            );
            let mut out = vec![f64::NAN; n];
            g.flush::<crate::kernel::Lanes>(&m, &mut out);
            let values: Vec<f64> = (0..n)
                .map(|i| standardised(1.0 + (n - 1 - i) as f64, tr(n - 1 - i) + want[n - 1 - i]))
                .collect();
            assert_eq!(bits(&out), bits(&values), "q {q}, {n} touches, the values");
            assert_eq!(g.len, 0);
        }
    }
}
