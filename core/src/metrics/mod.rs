//! Evaluation metrics: the paper's figures (method.md §3, §7) and the arm
//! standards' figures (standards.md), as pure functions with a typed,
//! serialisable report.
//!
//! Input is a list of measured probe centres in row order, each labelled with
//! the physical point (cone socket) it touches, plus optional reference
//! lengths between points. All lengths are mm. Rows are grouped by label in the
//! order labels first appear, so every list in the report has a deterministic
//! order; "touch k" of a point is its k-th row in input order.
//!
//! # Per point (socket) — `point_stats`
//!
//! With touches `x_1..x_n` (n ≥ [`MIN_TOUCHES`]), centroid `x̄ = (1/n) Σ x_i`
//! and `δ_i = |x_i − x̄|`:
//!
//! | figure | formula | source |
//! |---|---|---|
//! | `e` | `(1/n) Σ δ_i` | paper eq. 9–10 |
//! | `σ` | `sqrt((1/n) Σ (δ_i − e)²)` (population) | paper eq. 11 |
//! | `OA` | `e + 3σ` | paper eq. 12 (the calibration objective) |
//! | `δ_max` | `max δ_i` | ASME B89.4.22 single-point articulation test (SPAT) |
//! | `2s` | `2·sqrt(Σ δ_i² / (n − 1))` | SPAT (makers quote either `δ_max` or `2s`; [`crate::acceptance`] decides on `δ_max`) |
//! | half-range | `(max − min)/2` of X, Y and Z separately | FARO's SPAT routine |
//!
//! Across points, [`Summary`] gives min, mean, max and population standard
//! deviation of `e` (the paper's Fig. 6 numbers, §7), of `δ_max` and of `2s`.
//!
//! # Per pair of points — [`pair_length_error`]
//!
//! The paper's length error (eq. 19) for points `i < j` (first-appearance
//! order), over the common touch count `n = min(n_i, n_j)`:
//!
//! ```text
//! d_error = (1/n) Σ_{k=1..n} ( |x_ik − x_jk| − |x̄_i − x̄_j| )
//! ```
//!
//! where the centroids use all touches of each point; `d_error_abs` is the
//! same with absolute values inside the sum — our reading of the paper's
//! reported figures, since the printed formula is of second order in the
//! scatter (see [`pair_length_error`]). **Eq. 19 uses no
//! reference length** (method.md §8.4): it compares touch-by-touch distances
//! with the distance between centroids, so it measures repeatability again,
//! not scale. A uniformly shrunk arm scores as well as a correct one. With
//! equal touch counts it is never negative (the mean of distances is at least
//! the distance of the means); with unequal counts it can be. Summary over all
//! pairs: the paper's Fig. 7 numbers.
//!
//! # Per reference length — [`ReferenceError`]
//!
//! For a calibrated distance `L` between points `a` and `b` (ball bar, cone
//! plate, step gauge): `error = |x̄_a − x̄_b| − L`, as in ISO 10360-12 `E_Uni`
//! (`E = L_meas − L_cal`). Summary ([`ReferenceSummary`]): min, mean, max,
//! population std, `max |error|`, `RMS = sqrt((1/m) Σ error²)` and `2·RMS` —
//! the ASME B89.4.22 volumetric-test figures (unverified which the standard
//! quotes). This is the only figure here that measures scale.
//!
//! # Example
//!
//! ```
//! use aacmm_core::{dataset::DataSet, io::parse_lengths, metrics::evaluate};
//!
//! // Socket "p" touched at the four corners of a square of side 2 around
//! // (0, 0, 0); socket "q" four times at exactly (100.01, 0, 0).
//! let labels = ["p", "p", "p", "p", "q", "q", "q", "q"];
//! let points = [
//!     [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0], [-1.0, -1.0, 0.0], [1.0, -1.0, 0.0],
//!     [100.01, 0.0, 0.0], [100.01, 0.0, 0.0], [100.01, 0.0, 0.0], [100.01, 0.0, 0.0],
//! ];
//! let bar = parse_lengths("point_a,point_b,distance\np,q,100\n", "l.csv").unwrap();
//! let data = DataSet::from_labels(&labels, "m.csv").unwrap().with_lengths(&bar, "l.csv").unwrap();
//! let ev = evaluate(&data, &data.to_touch_order(&points)).unwrap();
//!
//! assert_eq!(ev.points[0].label, "p");
//! assert!((ev.points[0].e - 2f64.sqrt()).abs() < 1e-12); // δ = √2 for every corner
//! assert_eq!(ev.points[1].e, 0.0);
//! assert!((ev.single_point_e.mean - 2f64.sqrt() / 2.0).abs() < 1e-12);
//! assert!((ev.reference[0].error - 0.01).abs() < 1e-9);
//! println!("{}", ev.to_table());
//! ```

mod length;
mod pairs;
mod point;
pub(crate) mod table;

pub(crate) use length::pair_length_errors;
pub use length::{PairLengthError, ReferenceError, ReferenceSummary, pair_length_error};
pub use pairs::PairSample;
pub(crate) use pairs::{DEFAULT_PAIR_SEED, PAIR_TOUCH_BUDGET, PairSet, pair_set};
pub use point::PointStats;
pub(crate) use point::point_stats;
pub(crate) use table::write_pair_table;

use crate::dataset::DataSet;
pub(crate) use crate::dataset::MIN_TOUCHES;
pub(crate) use crate::geometry::{centroid, distance};
use serde::{Deserialize, Serialize};

/// Why the metrics could not be computed. Every variant says where the
/// offending value came from.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MetricsError {
    /// The evaluation needs more memory than the process can allocate,
    /// found before any work (see [`crate::memory`]).
    #[error(transparent)]
    Memory(#[from] crate::memory::OutOfMemory),
    /// The positions do not match the data set, one per touch.
    #[error("{got} positions for {expected} touches")]
    LengthMismatch {
        /// Touches in the data set.
        expected: usize,
        /// Positions given.
        got: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error(
        "{at}: point {}: computed position is not a finite number",
        crate::error::quoted(label)
    )]
    NonFinite {
        /// Label of the offending touch.
        label: String,
        /// Where the touch came from (`file:line`), or its index among the
        /// touches passed to `point_stats`.
        at: String,
    },
    /// A point has fewer than [`MIN_TOUCHES`] touches.
    #[error(
        "point {} has {touches} touch(es); at least {MIN_TOUCHES} are needed",
        crate::error::quoted(label)
    )]
    TooFewTouches {
        /// The point's label.
        label: String,
        /// How many touches it has.
        touches: usize,
    },
    /// The data set has no touches (reference positions only): the
    /// touch metrics have nothing to evaluate.
    #[error(
        "no touches: the single-point and length metrics evaluate touches of points; reference \
         positions are scored by a calibration's validation"
    )]
    NoTouches,
    /// A figure overflowed (positions far too large to compare).
    #[error(
        "the figure `{figure}` overflows (not a finite number): the probe positions are too \
         large for the statistics; check the arm's lengths and units"
    )]
    Overflow {
        /// The figure that overflowed.
        figure: String,
    },
}

/// Min, mean, max and population standard deviation of a list of values
/// (`std = sqrt((1/m) Σ (v − mean)²)`). The one summary used everywhere in
/// this module, including for the per-point `e`, `σ` and `δ_max`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Number of values summarised.
    pub count: usize,
    /// Smallest value.
    pub min: f64,
    /// Arithmetic mean.
    pub mean: f64,
    /// Largest value.
    pub max: f64,
    /// Population standard deviation (divides by the count, not count − 1).
    pub std: f64,
}

impl Summary {
    /// Summarises `values`; `None` when there are none.
    ///
    /// ```
    /// use aacmm_core::metrics::Summary;
    /// // mean 2.5; squared deviations 2.25 + 0.25 + 0.25 + 2.25 = 5; 5/4 = 1.25
    /// let s = Summary::of(&[1.0, 2.0, 3.0, 4.0]).unwrap();
    /// assert_eq!((s.count, s.min, s.mean, s.max), (4, 1.0, 2.5, 4.0));
    /// assert!((s.std - 1.25f64.sqrt()).abs() < 1e-15);
    /// assert_eq!(Summary::of(&[]), None);
    /// ```
    pub fn of(values: &[f64]) -> Option<Summary> {
        let count = values.len();
        if count == 0 {
            return None;
        }
        let mean = values.iter().sum::<f64>() / count as f64;
        let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / count as f64;
        Some(Summary {
            count,
            min: values.iter().copied().fold(f64::INFINITY, f64::min),
            mean,
            max: values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            std: variance.sqrt(),
        })
    }

    fn is_finite(&self) -> bool {
        [self.min, self.mean, self.max, self.std]
            .iter()
            .all(|v| v.is_finite())
    }
}

/// Sums of values shifted by the first one: no division per value, so the
/// hot loop over all pairs is not bound by a dependent division (Welford's
/// update is); turned into a [`Running`] per chunk.
#[derive(Clone, Copy, Debug, Default)]
struct Shifted {
    count: usize,
    shift: f64,
    sum: f64,
    sum_sq: f64,
    min: f64,
    max: f64,
}

impl Shifted {
    #[inline(always)]
    fn push(&mut self, v: f64) {
        if self.count == 0 {
            (self.shift, self.min, self.max) = (v, v, v);
        }
        self.count += 1;
        let d = v - self.shift;
        self.sum += d;
        self.sum_sq += d * d;
        self.min = self.min.min(v);
        self.max = self.max.max(v);
    }

    fn running(&self) -> Running {
        if self.count == 0 {
            return Running::default();
        }
        let n = self.count as f64;
        let mean_d = self.sum / n;
        Running {
            count: self.count,
            min: self.min,
            max: self.max,
            mean: self.shift + mean_d,
            m2: (self.sum_sq - self.sum * mean_d).max(0.0),
        }
    }
}

/// A [`Summary`] of a list too long to hold (eq. 19 over all pairs), as
/// count, extremes, mean and the sum of squared deviations, so that the
/// summaries of parts merge exactly.
#[derive(Clone, Copy, Debug, Default)]
struct Running {
    count: usize,
    min: f64,
    max: f64,
    mean: f64,
    m2: f64,
}

impl Running {
    /// The summary of both lists together (Chan et al.'s pairwise update).
    fn merge(&self, o: &Running) -> Running {
        if o.count == 0 {
            return *self;
        }
        if self.count == 0 {
            return *o;
        }
        let n = (self.count + o.count) as f64;
        let d = o.mean - self.mean;
        Running {
            count: self.count + o.count,
            min: self.min.min(o.min),
            max: self.max.max(o.max),
            mean: self.mean + d * o.count as f64 / n,
            m2: self.m2 + o.m2 + d * d * self.count as f64 * o.count as f64 / n,
        }
    }

    fn summary(&self) -> Option<Summary> {
        (self.count > 0).then(|| Summary {
            count: self.count,
            min: self.min,
            mean: self.mean,
            max: self.max,
            std: (self.m2.max(0.0) / self.count as f64).sqrt(),
        })
    }
}

/// Everything [`evaluate`] computes; lists are in the data set's point order
/// (references in file order). Per-pair eq. 19 rows, which grow as the
/// square of the points, are not kept: `pair_length_errors` streams them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Evaluation {
    /// Per-point figures (paper eq. 9–12, SPAT).
    pub points: Vec<PointStats>,
    /// `e` across points: the paper's single-point repeatability (Fig. 6).
    pub single_point_e: Summary,
    /// `δ_max` across points (SPAT).
    pub single_point_delta_max: Summary,
    /// `2s` across points (SPAT; makers quote it or `δ_max`).
    pub single_point_two_s: Summary,
    /// `d_error` (eq. 19) across all pairs of points (Fig. 7), or across
    /// [`Evaluation::pair_sample`]; `None` with a single point.
    pub pair_length_summary: Option<Summary>,
    /// `d_error_abs` across pairs; `None` with a single point.
    pub pair_length_abs_summary: Option<Summary>,
    /// The pairs the two summaries are over when not all of them: a seeded
    /// sample above `PAIR_TOUCH_BUDGET` touch distances (`None`: every
    /// pair, or none computed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pair_sample: Option<PairSample>,
    /// Error against every reference length of the data set.
    pub reference: Vec<ReferenceError>,
    /// Summary of the reference errors; `None` when none were given.
    pub reference_summary: Option<ReferenceSummary>,
}

/// Computes every metric of the module for the probe positions `xyz` of the
/// data set's touches (in its touch order; see the module documentation for
/// the formulas). Memory is linear in the touches: pairs are summarised as
/// they are computed, on up to two threads;
/// [`evaluate_threads`] takes the count. Above `PAIR_TOUCH_BUDGET` touch
/// distances the pairs are a sample (seed `DEFAULT_PAIR_SEED`;
/// [`evaluate_seeded`] takes one), stated in [`Evaluation::pair_sample`].
///
/// # Errors
///
/// [`MetricsError::LengthMismatch`]; [`MetricsError::NonFinite`] naming the
/// file and line of the first non-finite position;
/// [`MetricsError::Overflow`] when a figure is not finite.
///
/// ```
/// use aacmm_core::{dataset::DataSet, metrics::evaluate};
/// // Socket "a" at x = 0, 0, 0, 4 (centroid 1, δ = 1, 1, 1, 3);
/// // socket "b" three times at (10, 0, 0).
/// let labels = ["a", "b", "a", "b", "a", "b", "a"];
/// let x = |v: f64| [v, 0.0, 0.0];
/// let points = [x(0.0), x(10.0), x(0.0), x(10.0), x(0.0), x(10.0), x(4.0)];
/// let data = DataSet::from_labels(&labels, "m.csv").unwrap();
/// let ev = evaluate(&data, &data.to_touch_order(&points)).unwrap();
/// assert_eq!(ev.points[0].e, 1.5); // (1 + 1 + 1 + 3) / 4
/// assert_eq!(ev.points[0].delta_max, 3.0);
/// assert_eq!(ev.points[0].two_s, 4.0); // 2·sqrt((1 + 1 + 1 + 9) / 3)
/// // eq. 19 pairs the first three touches: distances 10, 10, 10 vs 9 between centroids.
/// assert_eq!(ev.pair_length_summary.unwrap().mean, 1.0);
/// assert_eq!(ev.reference_summary, None);
/// ```
pub fn evaluate(data: &DataSet, xyz: &[[f64; 3]]) -> Result<Evaluation, MetricsError> {
    evaluate_threads(data, xyz, DEFAULT_THREADS)
}

/// Checks, before any work, that an evaluation of `data` can have the
/// memory it needs beyond the data set, the positions its caller computes
/// first included (`crate::memory::EVALUATE_BYTES_PER_TOUCH`): callers
/// check before they compute them, [`evaluate_threads`] again.
///
/// # Errors
///
/// [`crate::memory::OutOfMemory`] when the memory cannot be had.
pub fn room_to_evaluate(data: &DataSet) -> Result<(), crate::memory::OutOfMemory> {
    let per_touch = crate::memory::EVALUATE_BYTES_PER_TOUCH;
    let lengths = data.references().len();
    crate::memory::room_for_work("evaluating", data.len(), lengths, per_touch, 0)
}

/// The threads [`evaluate`] uses for the pairs of points.
pub(crate) const DEFAULT_THREADS: usize = 2;

/// [`evaluate`] with the pairs of points (eq. 19, quadratic in the points:
/// the only part that costs) on up to `threads` threads; 0 counts as 1. The
/// rows of pairs are cut into chunks of a fixed size whose summaries are
/// merged in row order, so the result is the same bits whatever `threads`.
///
/// # Errors
///
/// As [`evaluate`].
pub fn evaluate_threads(
    data: &DataSet,
    xyz: &[[f64; 3]],
    threads: usize,
) -> Result<Evaluation, MetricsError> {
    room_to_evaluate(data)?;
    evaluate_with(data, xyz, Some((threads, DEFAULT_PAIR_SEED)))
}

/// [`evaluate_threads`] with the pairs, when sampled, drawn with `seed`
/// (a session's, so that its outputs agree).
///
/// # Errors
///
/// As [`evaluate`].
///
/// ```
/// use aacmm_core::{dataset::DataSet, metrics::evaluate_seeded};
/// // 1500 points of 10 touches: 1.1·10⁷ touch distances, above the budget.
/// let labels: Vec<String> = (0..15_000).map(|i| format!("s{}", i % 1500)).collect();
/// let xyz: Vec<[f64; 3]> = (0..15_000).map(|i| [(i as f64).sin() * 500.0, i as f64, 0.0]).collect();
/// let data = DataSet::from_labels(&labels, "m.csv").unwrap();
/// let xyz = data.to_touch_order(&xyz);
/// let ev = evaluate_seeded(&data, &xyz, 2, 7).unwrap();
/// let sample = ev.pair_sample.unwrap();
/// assert_eq!((sample.pairs, sample.seed), (1500 * 1499 / 2, 7));
/// assert_eq!(ev.pair_length_summary.unwrap().count as u64, sample.sampled);
/// assert!(sample.sampled < sample.pairs);
/// ```
pub fn evaluate_seeded(
    data: &DataSet,
    xyz: &[[f64; 3]],
    threads: usize,
    seed: u64,
) -> Result<Evaluation, MetricsError> {
    evaluate_with(data, xyz, Some((threads, seed)))
}

/// [`evaluate`] without the pairs of points (their summaries `None`): the
/// per-point and reference figures, which are linear in the touches, where
/// eq. 19 is quadratic in the points (10⁹ touch distances at 1000 points of
/// 1000 touches). For callers that do not use the pairs, such as the
/// before/after figures of a calibration.
pub(crate) fn evaluate_without_pairs(
    data: &DataSet,
    xyz: &[[f64; 3]],
) -> Result<Evaluation, MetricsError> {
    evaluate_with(data, xyz, None)
}

/// [`evaluate_threads`], with the pairs on `pairs.0` threads (sampled with
/// seed `pairs.1` above the budget) or, `None`, not computed.
fn evaluate_with(
    data: &DataSet,
    xyz: &[[f64; 3]],
    pairs: Option<(usize, u64)>,
) -> Result<Evaluation, MetricsError> {
    if xyz.len() != data.len() {
        return Err(MetricsError::LengthMismatch {
            expected: data.len(),
            got: xyz.len(),
        });
    }
    if data.points().is_empty() {
        return Err(MetricsError::NoTouches);
    }
    for point in data.points() {
        if let Some(i) = point.touches.clone().find(|&i| !is_finite(&xyz[i])) {
            return Err(MetricsError::NonFinite {
                label: point.label.clone(),
                at: data.source().touch(i).to_string(),
            });
        }
    }
    let stats = data
        .points()
        .iter()
        .map(|p| point_stats(&p.label, &xyz[p.touches.clone()]))
        .collect::<Result<Vec<_>, _>>()?;
    let (signed, abs, pair_sample) = match pairs {
        Some((threads, seed)) => {
            let set = pairs::pair_set(data.points(), seed, threads);
            let (signed, abs) = pair_summaries(data, xyz, &stats, threads, &set);
            (signed.summary(), abs.summary(), set.sample())
        }
        None => (None, None, None),
    };
    let reference: Vec<ReferenceError> = data
        .references()
        .iter()
        .map(|r| {
            let measured = distance(&stats[r.a].centroid, &stats[r.b].centroid);
            ReferenceError {
                a: stats[r.a].label.clone(),
                b: stats[r.b].label.clone(),
                reference: r.distance,
                measured,
                error: measured - r.distance,
            }
        })
        .collect();
    let across_points = |figure: fn(&PointStats) -> f64| {
        let values: Vec<f64> = stats.iter().map(figure).collect();
        // Invariant: refused above without a point, so `values` is not
        // empty.
        Summary::of(&values).expect("a data set has points")
    };
    let ev = Evaluation {
        single_point_e: across_points(|p| p.e),
        single_point_delta_max: across_points(|p| p.delta_max),
        single_point_two_s: across_points(|p| p.two_s),
        pair_length_summary: signed,
        pair_length_abs_summary: abs,
        pair_sample,
        reference_summary: ReferenceSummary::of(
            &reference.iter().map(|r| r.error).collect::<Vec<_>>(),
        ),
        points: stats,
        reference,
    };
    ev.check_finite()?;
    Ok(ev)
}

impl Evaluation {
    /// Every figure must be finite: positions near `f64::MAX` make sums
    /// overflow where each position alone is finite.
    fn check_finite(&self) -> Result<(), MetricsError> {
        let overflow = |figure: &str| {
            Err(MetricsError::Overflow {
                figure: figure.to_string(),
            })
        };
        for (i, p) in self.points.iter().enumerate() {
            let values = [p.e, p.sigma, p.oa, p.delta_max, p.two_s];
            if !(values.iter().chain(&p.centroid).chain(&p.half_range)).all(|v| v.is_finite()) {
                return overflow(&format!("points[{i}]"));
            }
        }
        let summaries = [
            ("single_point_e", Some(self.single_point_e)),
            ("single_point_delta_max", Some(self.single_point_delta_max)),
            ("single_point_two_s", Some(self.single_point_two_s)),
            ("pair_length_summary", self.pair_length_summary),
            ("pair_length_abs_summary", self.pair_length_abs_summary),
            ("reference_summary", self.reference_summary.map(|r| r.error)),
        ];
        if let Some((name, _)) = summaries
            .iter()
            .find(|(_, s)| s.is_some_and(|s| !s.is_finite()))
        {
            return overflow(name);
        }
        if let Some(i) = self.reference.iter().position(|r| !r.measured.is_finite()) {
            return overflow(&format!("reference[{i}]"));
        }
        Ok(())
    }
}

/// Eq. 19 summarised over the pairs `i < j` of `set`, in constant memory
/// beyond the set. Rows `i` (or the sampled pairs) are split into chunks of
/// fixed size that run on up to `threads` threads (one below three chunks:
/// too little work to pay for a thread); the chunks' summaries are merged
/// in row order, so the result does not depend on the threads.
fn pair_summaries(
    data: &DataSet,
    xyz: &[[f64; 3]],
    stats: &[PointStats],
    threads: usize,
    set: &pairs::PairSet,
) -> (Running, Running) {
    let (signed, abs, _) = pair_pass(data, xyz, stats, threads, set, || (), |_, _, _| {});
    (signed, abs)
}

/// [`pair_summaries`], also handing every pair's `(centroid distance,
/// d_error_abs)` to `visit` with an accumulator per chunk of rows (made by
/// `init`); the accumulators come back in row order, so a caller that merges
/// them in that order gets the same bits whatever `threads`.
fn pair_pass<A: Send>(
    data: &DataSet,
    xyz: &[[f64; 3]],
    stats: &[PointStats],
    threads: usize,
    set: &pairs::PairSet,
    init: impl Fn() -> A + Sync,
    visit: impl Fn(&mut A, f64, f64) + Sync,
) -> (Running, Running, Vec<A>) {
    const ROWS_PER_CHUNK: usize = 64;
    // Sampled pairs: about as many distances per chunk as 64 rows of a
    // campaign at the budget's edge.
    const PAIRS_PER_CHUNK: usize = 1024;
    let points = data.points();
    let chunk = |pairs: &mut dyn Iterator<Item = (usize, usize)>| {
        let (mut signed, mut abs) = (Shifted::default(), Shifted::default());
        let mut acc = init();
        for (i, j) in pairs {
            let (_, centroid_distance, d, d_abs) = length::eq19(
                &xyz[points[i].touches.clone()],
                &xyz[points[j].touches.clone()],
                &stats[i].centroid,
                &stats[j].centroid,
            );
            signed.push(d);
            abs.push(d_abs);
            visit(&mut acc, centroid_distance, d_abs);
        }
        (signed.running(), abs.running(), acc)
    };
    let all_rows = |r: &std::ops::Range<usize>| {
        let n = points.len();
        chunk(&mut r.clone().flat_map(|i| (i + 1..n).map(move |j| (i, j))))
    };
    let parts = match set {
        pairs::PairSet::All => {
            let chunks: Vec<std::ops::Range<usize>> = (0..points.len())
                .step_by(ROWS_PER_CHUNK)
                .map(|s| s..(s + ROWS_PER_CHUNK).min(points.len()))
                .collect();
            crate::parallel::parallel_map(&chunks, threads, all_rows)
        }
        pairs::PairSet::Sampled { pairs, .. } => {
            let chunks: Vec<&[(u32, u32)]> = pairs.chunks(PAIRS_PER_CHUNK).collect();
            crate::parallel::parallel_map(&chunks, threads, |c| {
                chunk(&mut c.iter().map(|&(i, j)| (i as usize, j as usize)))
            })
        }
    };
    let mut accs = Vec::with_capacity(parts.len());
    let (mut signed, mut abs) = (Running::default(), Running::default());
    for (ps, pa, acc) in parts {
        signed = signed.merge(&ps);
        abs = abs.merge(&pa);
        accs.push(acc);
    }
    (signed, abs, accs)
}

/// Adds the pairs of points to `ev`, an evaluation of `data` at `xyz`
/// without them ([`evaluate_without_pairs`]): the same summaries as
/// [`evaluate_threads`], in one pass over the pairs that also hands each
/// pair's `(centroid distance, d_error_abs)` to `visit` (see [`pair_pass`]),
/// so that a figure of the pairs costs no second pass. Returns the chunks'
/// accumulators in row order.
///
/// # Errors
///
/// [`MetricsError::Overflow`] when a pair summary is not finite.
pub(crate) fn add_pairs<A: Send>(
    ev: &mut Evaluation,
    data: &DataSet,
    xyz: &[[f64; 3]],
    (threads, set): (usize, &PairSet),
    init: impl Fn() -> A + Sync,
    visit: impl Fn(&mut A, f64, f64) + Sync,
) -> Result<Vec<A>, MetricsError> {
    let (signed, abs, accs) = pair_pass(data, xyz, &ev.points, threads, set, init, visit);
    ev.pair_length_summary = signed.summary();
    ev.pair_length_abs_summary = abs.summary();
    ev.pair_sample = set.sample();
    ev.check_finite()?;
    Ok(accs)
}

fn is_finite(p: &[f64; 3]) -> bool {
    p.iter().all(|c| c.is_finite())
}

/// Checks what every per-point function needs: enough, finite touches.
fn check_touches(label: &str, touches: &[[f64; 3]]) -> Result<(), MetricsError> {
    if touches.len() < MIN_TOUCHES {
        return Err(MetricsError::TooFewTouches {
            label: label.to_owned(),
            touches: touches.len(),
        });
    }
    if let Some(row) = touches.iter().position(|p| !is_finite(p)) {
        return Err(MetricsError::NonFinite {
            label: label.to_owned(),
            at: format!("touch {row}"),
        });
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::domain::ReferenceLength;

    /// A point label echoed in an error is bounded and escaped (issue 29):
    /// CR/LF/NUL, or 10 000 characters, make a short single-line message;
    /// so does a parameter name that is not one.
    #[test]
    fn hostile_labels_give_bounded_messages() {
        for label in ["p\r\n\0".to_string(), "p".repeat(10_000)] {
            let errors = [
                MetricsError::TooFewTouches {
                    label: label.clone(),
                    touches: 1,
                }
                .to_string(),
                MetricsError::NonFinite {
                    label: label.clone(),
                    at: "p.csv:2".into(),
                }
                .to_string(),
                label.parse::<crate::params::ParamId>().unwrap_err(),
            ];
            for m in errors {
                assert!(m.chars().count() < 600, "{m:.700}");
                assert!(!m.contains(char::is_control), "{m:?}");
                assert!(
                    label.len() < 10_000 || m.contains("(10000 characters)"),
                    "{m}"
                );
            }
        }
    }

    /// `evaluate` on points given in row order with labels and references
    /// `(a, b, L)`.
    pub(crate) fn eval<S: AsRef<str>>(
        labels: &[S],
        points: &[[f64; 3]],
        refs: &[(&str, &str, f64)],
    ) -> Result<Evaluation, MetricsError> {
        let lengths: Vec<ReferenceLength> = refs
            .iter()
            .enumerate()
            .map(|(i, &(a, b, distance))| ReferenceLength {
                a: a.into(),
                b: b.into(),
                distance,
                uncertainty: None,
                line: i + 2,
            })
            .collect();
        let data = DataSet::from_labels(labels, "m.csv")
            .unwrap()
            .with_lengths(&lengths, "l.csv")
            .unwrap();
        assert_eq!(points.len(), labels.len(), "test points per label");
        evaluate(&data, &data.to_touch_order(points))
    }

    /// The eq. 19 rows of points in row order.
    pub(crate) fn pairs<S: AsRef<str>>(labels: &[S], points: &[[f64; 3]]) -> Vec<PairLengthError> {
        let data = DataSet::from_labels(labels, "m.csv").unwrap();
        let xyz = data.to_touch_order(points);
        let stats = evaluate(&data, &xyz).unwrap().points;
        pair_length_errors(&data, &xyz, &stats).collect()
    }

    fn x(v: f64) -> [f64; 3] {
        [v, 0.0, 0.0]
    }

    #[test]
    fn without_pairs_is_evaluate_without_the_pair_summaries() {
        let labels: Vec<String> = (0..90).map(|i| format!("s{}", i % 30)).collect();
        let xyz: Vec<[f64; 3]> = (0..90)
            .map(|i| [(i as f64).sin() * 500.0, i as f64, (i as f64 * 0.7).cos()])
            .collect();
        let data = DataSet::from_labels(&labels, "m.csv").unwrap();
        let xyz = data.to_touch_order(&xyz);
        let full = evaluate(&data, &xyz).unwrap();
        let mut part = evaluate_without_pairs(&data, &xyz).unwrap();
        assert_eq!(part.pair_length_summary, None);
        assert_eq!(part.pair_length_abs_summary, None);
        assert_ne!(full.pair_length_summary, None);
        let rows = add_pairs(
            &mut part,
            &data,
            &xyz,
            (2, &PairSet::All),
            Vec::new,
            |v, d, a| v.push((d, a)),
        )
        .unwrap();
        assert_eq!(part, full);
        let each: Vec<(f64, f64)> = pair_length_errors(&data, &xyz, &full.points)
            .map(|p| (p.centroid_distance, p.d_error_abs))
            .collect();
        assert_eq!(rows.concat(), each);
    }

    #[test]
    fn summary_of_one_value_has_zero_spread() {
        let s = Summary::of(&[-0.5]).unwrap();
        assert_eq!(
            (s.count, s.min, s.mean, s.max, s.std),
            (1, -0.5, -0.5, -0.5, 0.0)
        );
    }

    #[test]
    fn summary_of_signed_values() {
        // [-3, 1]: mean -1, deviations ∓2, variance (4 + 4)/2 = 4, std 2
        let s = Summary::of(&[-3.0, 1.0]).unwrap();
        assert_eq!((s.min, s.mean, s.max, s.std), (-3.0, -1.0, 1.0, 2.0));
    }

    #[test]
    fn groups_keep_first_appearance_order() {
        let labels = ["b", "a", "b", "c", "a", "b", "c", "a", "c"];
        let points: Vec<[f64; 3]> = (0..9).map(|r| x(r as f64)).collect();
        let ev = eval(&labels, &points, &[]).unwrap();
        let order: Vec<&str> = ev.points.iter().map(|p| p.label.as_str()).collect();
        assert_eq!(order, ["b", "a", "c"]);
        // b: rows 0, 2, 5 → centroid 7/3; a: rows 1, 4, 7 → centroid 4.
        assert!((ev.points[0].centroid[0] - 7.0 / 3.0).abs() < 1e-12);
        assert_eq!(ev.points[1].centroid[0], 4.0);
    }

    #[test]
    fn evaluation_order_is_deterministic() {
        let labels: Vec<String> = ["s3", "s1", "s2"]
            .iter()
            .cycle()
            .take(9)
            .map(|s| s.to_string())
            .collect();
        let points: Vec<[f64; 3]> = (0..9).map(|r| [r as f64, (r * r) as f64, 1.0]).collect();
        let first = eval(&labels, &points, &[]).unwrap();
        for _ in 0..5 {
            assert_eq!(eval(&labels, &points, &[]).unwrap(), first);
        }
        let names: Vec<&str> = first.points.iter().map(|p| p.label.as_str()).collect();
        assert_eq!(names, ["s3", "s1", "s2"]);
        let pairs: Vec<(String, String)> = pairs(&labels, &points)
            .into_iter()
            .map(|p| (p.a, p.b))
            .collect();
        let pairs: Vec<(&str, &str)> = pairs
            .iter()
            .map(|(a, b)| (a.as_str(), b.as_str()))
            .collect();
        assert_eq!(pairs, [("s3", "s1"), ("s3", "s2"), ("s1", "s2")]);
    }

    #[test]
    fn summaries_across_points() {
        // "p": x = 0, 0, 0, 4 → e 1.5, δ_max 3, 2s 4 (see point::tests)
        // "q": x = 10, 10, 10   → e 0,   δ_max 0, 2s 0
        let labels = ["p", "p", "p", "p", "q", "q", "q"];
        let points = [x(0.0), x(0.0), x(0.0), x(4.0), x(10.0), x(10.0), x(10.0)];
        let ev = eval(&labels, &points, &[]).unwrap();
        let e = ev.single_point_e;
        // e: [1.5, 0] → mean 0.75, std 0.75
        assert_eq!(
            (e.count, e.min, e.mean, e.max, e.std),
            (2, 0.0, 0.75, 1.5, 0.75)
        );
        assert_eq!(ev.single_point_delta_max.max, 3.0);
        assert_eq!(ev.single_point_two_s.mean, 2.0);
        // one pair: centroids 1 and 10 → 9; touch distances 10, 10, 10 → d_error 1
        let pair = ev.pair_length_summary.unwrap();
        assert_eq!((pair.count, pair.mean, pair.std), (1, 1.0, 0.0));
    }

    #[test]
    fn streamed_pair_summary_equals_the_summary_of_the_rows() {
        let labels: Vec<String> = (0..40).map(|r| format!("s{}", r % 8)).collect();
        let points: Vec<[f64; 3]> = (0..40)
            .map(|r| [(r as f64 * 0.7).sin() * 300.0, (r as f64).cos(), r as f64])
            .collect();
        let ev = eval(&labels, &points, &[]).unwrap();
        let rows = pairs(&labels, &points);
        assert_eq!(rows.len(), 28);
        let of = |f: fn(&PairLengthError) -> f64| {
            Summary::of(&rows.iter().map(f).collect::<Vec<_>>()).unwrap()
        };
        for (streamed, direct) in [
            (ev.pair_length_summary.unwrap(), of(|p| p.d_error)),
            (ev.pair_length_abs_summary.unwrap(), of(|p| p.d_error_abs)),
        ] {
            assert_eq!(
                (streamed.count, streamed.min, streamed.max),
                (direct.count, direct.min, direct.max)
            );
            assert!((streamed.mean - direct.mean).abs() < 1e-12);
            assert!((streamed.std - direct.std).abs() < 1e-12);
        }
    }

    #[test]
    fn pair_summary_of_many_chunks_equals_the_summary_of_the_rows() {
        // 200 points: four chunks of rows on two threads, merged.
        let labels: Vec<String> = (0..600).map(|r| format!("s{}", r % 200)).collect();
        let points: Vec<[f64; 3]> = (0..600)
            .map(|r| {
                [
                    (r as f64 * 0.37).sin() * 400.0,
                    (r as f64 * 0.11).cos() * 300.0,
                    r as f64,
                ]
            })
            .collect();
        let ev = eval(&labels, &points, &[]).unwrap();
        let rows = pairs(&labels, &points);
        assert_eq!(rows.len(), 200 * 199 / 2);
        let direct = Summary::of(&rows.iter().map(|p| p.d_error_abs).collect::<Vec<_>>()).unwrap();
        let streamed = ev.pair_length_abs_summary.unwrap();
        assert_eq!(
            (streamed.count, streamed.min, streamed.max),
            (direct.count, direct.min, direct.max)
        );
        assert!((streamed.mean - direct.mean).abs() < 1e-9 * direct.mean.abs());
        assert!((streamed.std - direct.std).abs() < 1e-9 * direct.std);
    }

    /// 1000 points (16 chunks of pair rows, so 2 and 4 threads really split
    /// the work) with reference lengths: the same JSON bytes on 1, 2 and 4
    /// threads.
    #[test]
    fn evaluation_is_the_same_bytes_on_any_thread_count() {
        let n = 1000;
        let labels: Vec<String> = (0..3 * n).map(|r| format!("s{}", r % n)).collect();
        let points: Vec<[f64; 3]> = (0..3 * n)
            .map(|r| {
                let (p, k) = ((r % n) as f64, (r / n) as f64);
                [
                    (p * 0.37).sin() * 400.0 + (k * 1.3 + p).sin() * 0.05,
                    (p * 0.11).cos() * 300.0 + (k * 0.7 - p).cos() * 0.05,
                    p + k * 0.01,
                ]
            })
            .collect();
        let refs: Vec<(String, String, f64)> = (0..20)
            .map(|i| (format!("s{i}"), format!("s{}", 999 - i), 500.0 + i as f64))
            .collect();
        let lengths: Vec<ReferenceLength> = refs
            .iter()
            .enumerate()
            .map(|(i, (a, b, distance))| ReferenceLength {
                a: a.clone(),
                b: b.clone(),
                distance: *distance,
                uncertainty: None,
                line: i + 2,
            })
            .collect();
        let data = DataSet::from_labels(&labels, "m.csv")
            .unwrap()
            .with_lengths(&lengths, "l.csv")
            .unwrap();
        assert_eq!(data.points().len(), n);
        let xyz = data.to_touch_order(&points);
        let json = |threads| {
            serde_json::to_string(&evaluate_threads(&data, &xyz, threads).unwrap()).unwrap()
        };
        let one = json(1);
        assert!(
            one.contains("\"pair_length_summary\":{\"count\":499500"),
            "{}",
            &one[..200]
        );
        assert_eq!(json(2), one);
        assert_eq!(json(4), one);
    }

    #[test]
    fn single_point_has_no_pairs_and_no_reference_summary() {
        let ev = eval(&["p"; 3], &[x(0.0), x(1.0), x(2.0)], &[]).unwrap();
        assert!(pairs(&["p"; 3], &[x(0.0), x(1.0), x(2.0)]).is_empty());
        assert_eq!(ev.pair_length_summary, None);
        assert_eq!(ev.reference_summary, None);
    }

    #[test]
    fn accepts_owned_labels() {
        let labels = vec!["p".to_string(); 3];
        assert!(eval(&labels, &[x(0.0); 3], &[]).is_ok());
    }

    #[test]
    fn mismatched_lengths_are_an_error() {
        let data = DataSet::from_labels(&["p"; 3], "m.csv").unwrap();
        assert_eq!(
            evaluate(&data, &[x(0.0); 2]),
            Err(MetricsError::LengthMismatch {
                expected: 3,
                got: 2
            })
        );
    }

    #[test]
    fn non_finite_coordinate_names_the_input_line() {
        let labels = ["p", "q", "p", "q", "p", "q"];
        let mut points = [x(0.0); 6];
        points[3][1] = f64::NAN;
        // Row 3 is line 5 of the file (header on line 1).
        assert_eq!(
            eval(&labels, &points, &[]),
            Err(MetricsError::NonFinite {
                label: "q".into(),
                at: "m.csv:5".into()
            })
        );
    }

    #[test]
    fn overflowing_figures_are_errors_not_nulls() {
        let big = f64::MAX / 2.0;
        let labels = ["p", "p", "p"];
        let points = [x(-big), x(big), x(big)];
        let e = eval(&labels, &points, &[]).unwrap_err();
        assert!(matches!(e, MetricsError::Overflow { .. }), "{e}");
        assert!(e.to_string().contains("`points[0]`"), "{e}");
    }

    #[test]
    fn report_round_trips_through_json() {
        // serde_json's default float parser may be off by one ulp, so compare
        // with a tolerance rather than exactly.
        let labels = ["p", "q", "p", "q", "p", "q"];
        let points = [x(0.0), x(10.0), x(0.1), x(10.0), x(0.2), x(10.1)];
        let ev = eval(&labels, &points, &[("q", "p", 9.9)]).unwrap();
        let back: Evaluation = serde_json::from_str(&serde_json::to_string(&ev).unwrap()).unwrap();
        let (ev, back) = (
            serde_json::to_value(&ev).unwrap(),
            serde_json::to_value(&back).unwrap(),
        );
        assert!(json_close(&ev, &back), "{ev}\n{back}");
    }

    fn json_close(a: &serde_json::Value, b: &serde_json::Value) -> bool {
        use serde_json::Value::{Array, Number, Object};
        match (a, b) {
            (Number(a), Number(b)) => (a.as_f64().unwrap() - b.as_f64().unwrap()).abs() < 1e-12,
            (Array(a), Array(b)) => {
                a.len() == b.len() && a.iter().zip(b).all(|(a, b)| json_close(a, b))
            }
            (Object(a), Object(b)) => {
                a.len() == b.len()
                    && a.iter()
                        .all(|(k, v)| b.get(k).is_some_and(|w| json_close(v, w)))
            }
            _ => a == b,
        }
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn metrics_evaluate_threads() {
        use crate::{
            dataset::DataSet,
            metrics::{evaluate, evaluate_threads},
        };
        let labels: Vec<String> = (0..600).map(|i| format!("s{}", i % 200)).collect();
        let xyz: Vec<[f64; 3]> = (0..600)
            .map(|i| [(i as f64).sin() * 500.0, i as f64, 0.0])
            .collect();
        let data = DataSet::from_labels(&labels, "m.csv").unwrap();
        let xyz = data.to_touch_order(&xyz);
        let one = evaluate_threads(&data, &xyz, 1).unwrap();
        assert_eq!(one, evaluate_threads(&data, &xyz, 3).unwrap());
        assert_eq!(one, evaluate(&data, &xyz).unwrap());
    }
}
