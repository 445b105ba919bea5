//! What the figures draw, computed from the positions with the metrics:
//! one [`Evaluated`] per data set and arm, eq. 19 per pair (streamed), the
//! per-touch residual lengths.

use plotters::style::RGBColor;

use super::svg::{BLUE, GREY, Marker, Shape, VERMILLION};
use super::{Arms, MAX_PAIR_MARKERS, Measured, ReportError};
use crate::dataset::DataSet;
use crate::geometry::distance;
use crate::metrics::{
    DEFAULT_THREADS, Evaluation, PairSet, add_pairs, evaluate_without_pairs, pair_set,
};

/// Which arm gave the positions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Stage {
    /// Before calibration (grey).
    Before,
    /// After calibration, or the one arm evaluated (colour).
    After,
}

/// One data set measured by one arm, with its metrics.
#[derive(Clone, Debug)]
pub(crate) struct Evaluated<'a> {
    /// Index of the data set among the `Measured`.
    pub(crate) set: usize,
    /// Its name (`fitted`, `held out`, `held out 2`, or `measured`).
    pub(crate) set_name: String,
    /// The data set.
    pub(crate) data: &'a DataSet,
    /// Held out from the fit.
    pub(crate) held_out: bool,
    /// Which arm.
    pub(crate) stage: Stage,
    /// Probe positions, touch order, mm.
    pub(crate) xyz: &'a [[f64; 3]],
    /// The metrics.
    pub(crate) ev: Evaluation,
    /// Eq. 19 for the figure, from the same pass as the metrics' summaries.
    pub(crate) pairs: Pairs,
    /// [`Evaluated::median_delta`], once found (a figure and a table show
    /// it).
    pub(crate) median: std::sync::OnceLock<Option<f64>>,
}

impl Evaluated<'_> {
    /// The median δ of the touches ([`median_delta`]), found once.
    pub(crate) fn median_delta(&self) -> Option<f64> {
        *self.median.get_or_init(|| median_delta(self))
    }

    /// The series' name: the arm and the data (`nominal, fitted`).
    pub(crate) fn name(&self, arms: &Arms) -> String {
        let arm = match self.stage {
            Stage::Before => &arms.before,
            Stage::After => &arms.after,
        };
        format!("{arm}, {}", self.set_name)
    }

    /// Grey before; blue (fitted) or vermillion (held out) after.
    pub(crate) fn color(&self) -> RGBColor {
        match (self.stage, self.held_out) {
            (Stage::Before, _) => GREY,
            (Stage::After, false) => BLUE,
            (Stage::After, true) => VERMILLION,
        }
    }

    /// Dots for fitted points, triangles for held-out ones.
    pub(crate) fn marker(&self) -> Marker {
        let shape = if self.held_out {
            Shape::Triangle
        } else {
            Shape::Dot
        };
        Marker::new(shape, self.color())
    }
}

/// Evaluates every data set with every arm: for each data set, before (if
/// given) then after; pairs of points sampled (above the metrics' budget)
/// with `seed`, the same pairs for both arms.
pub(crate) fn evaluate_all<'a>(
    measured: &[Measured<'a>],
    seed: u64,
) -> Result<Vec<Evaluated<'a>>, ReportError> {
    let held_total = measured.iter().filter(|m| m.held_out).count();
    let mut held_seen = 0;
    let mut out = Vec::new();
    for (set, m) in measured.iter().enumerate() {
        if m.data.is_empty() {
            // Reference positions only: no touch to evaluate (their errors
            // are in the validation's figures).
            continue;
        }
        let set_name = if m.held_out {
            held_seen += 1;
            if held_total > 1 {
                format!("held out {held_seen}")
            } else {
                "held out".to_string()
            }
        } else if m.before.is_some() {
            "fitted".to_string()
        } else {
            "measured".to_string()
        };
        let stages = [(Stage::Before, m.before), (Stage::After, Some(m.after))];
        for (stage, xyz) in stages {
            let Some(xyz) = xyz else { continue };
            if xyz.len() != m.data.len() {
                return Err(ReportError::Positions {
                    what: format!(
                        "{set_name}, {}",
                        if stage == Stage::Before {
                            "before"
                        } else {
                            "after"
                        }
                    ),
                    expected: m.data.len(),
                    got: xyz.len(),
                });
            }
            let (ev, pairs) = evaluate_with_pairs(m.data, xyz, seed)?;
            out.push(Evaluated {
                set,
                set_name: set_name.clone(),
                data: m.data,
                held_out: m.held_out,
                stage,
                xyz,
                ev,
                pairs,
                median: std::sync::OnceLock::new(),
            });
        }
    }
    Ok(out)
}

/// Eq. 19 of one series: `(centroid distance, |d|_error)` per pair, or the
/// mean `|d|_error` per distance bin when there are more than
/// [`MAX_PAIR_MARKERS`] pairs.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Pairs {
    /// Every pair, in the data set's order.
    Each(Vec<(f64, f64)>),
    /// `(bin centre, mean |d|_error, pairs)` per non-empty bin, of `count`
    /// pairs in all.
    Binned {
        /// The bins.
        bins: Vec<(f64, f64, usize)>,
        /// Pairs in all.
        count: usize,
    },
}

/// Distance bins of [`Pairs::Binned`].
const PAIR_BINS: usize = 40;

/// The metrics of `data` at `xyz` with eq. 19 for the figure, in one pass
/// over the pairs of points on [`DEFAULT_THREADS`] (the pairs grow as the
/// square of the points: 1000 points of 1000 touches are 5·10⁸ touch
/// distances, so above the metrics' budget they are a sample drawn with
/// `seed`, which the figure states): every pair computed when there are
/// at most [`MAX_PAIR_MARKERS`], else the mean `|d|_error` per distance
/// bin. Memory does not grow with the pairs beyond the markers. The bins'
/// sums are per chunk of rows, merged in row order: the same bits whatever
/// the threads.
fn evaluate_with_pairs(
    data: &DataSet,
    xyz: &[[f64; 3]],
    seed: u64,
) -> Result<(Evaluation, Pairs), ReportError> {
    let mut ev = evaluate_without_pairs(data, xyz)?;
    let set = pair_set(data.points(), seed, DEFAULT_THREADS);
    let n = ev.points.len();
    let count = match &set {
        PairSet::All => n * n.saturating_sub(1) / 2,
        PairSet::Sampled { pairs, .. } => pairs.len(),
    };
    let threads = (DEFAULT_THREADS, &set);
    if count <= MAX_PAIR_MARKERS {
        let each = add_pairs(&mut ev, data, xyz, threads, Vec::new, |v, d, abs| {
            v.push((d, abs))
        })?;
        return Ok((ev, Pairs::Each(each.concat())));
    }
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut extend = |i: usize, j: usize| {
        let d = distance(&ev.points[i].centroid, &ev.points[j].centroid);
        lo = lo.min(d);
        hi = hi.max(d);
    };
    // The distance range of the pairs summarised: a sample's own, so that
    // this costs no more than the sample.
    match &set {
        PairSet::All => (0..n).for_each(|i| (i + 1..n).for_each(|j| extend(i, j))),
        PairSet::Sampled { pairs, .. } => {
            (pairs.iter()).for_each(|&(i, j)| extend(i as usize, j as usize));
        }
    }
    let width = ((hi - lo) / PAIR_BINS as f64).max(f64::MIN_POSITIVE);
    let parts = add_pairs(
        &mut ev,
        data,
        xyz,
        threads,
        || vec![(0.0f64, 0usize); PAIR_BINS],
        |sums, d, abs| {
            let k = (((d - lo) / width) as usize).min(PAIR_BINS - 1);
            sums[k].0 += abs;
            sums[k].1 += 1;
        },
    )?;
    let mut sums = vec![(0.0f64, 0usize); PAIR_BINS];
    for part in &parts {
        for (s, p) in sums.iter_mut().zip(part) {
            s.0 += p.0;
            s.1 += p.1;
        }
    }
    let bins = sums
        .iter()
        .enumerate()
        .filter(|(_, (_, c))| *c > 0)
        .map(|(k, (s, c))| (lo + (k as f64 + 0.5) * width, s / *c as f64, *c))
        .collect();
    Ok((ev, Pairs::Binned { bins, count }))
}

/// `δ_i = |x_i − x̄|` of every touch of `e`, touch order, mm.
#[cfg(test)]
pub(crate) fn deltas(e: &Evaluated) -> Vec<f64> {
    let mut out = Vec::with_capacity(e.xyz.len());
    for_each_delta(e, |d| out.push(d));
    out
}

/// [`median`] of the δ of `e` ([`for_each_delta`]), without holding them
/// all (10⁶ touches' are 8 MB, at the peak of a large calibration's
/// report): a first visit counts them by the top 16 bits of their order
/// key, a second keeps only those of the one or two groups that hold the
/// middle ranks, and the same selection picks the same values there.
pub(crate) fn median_delta(e: &Evaluated) -> Option<f64> {
    // `f64::total_cmp`'s order as an unsigned key.
    let key = |v: f64| {
        let b = v.to_bits();
        if b >> 63 == 1 { !b } else { b | 1 << 63 }
    };
    let group = |v: f64| (key(v) >> 48) as usize;
    let mut counts = vec![0u64; 1 << 16];
    for_each_delta(e, |v| {
        if v.is_finite() {
            counts[group(v)] += 1;
        }
    });
    let n: u64 = counts.iter().sum();
    let m = n / 2;
    // The middle ranks: the m-th smallest, and the (m − 1)-th for an even
    // count.
    let first_rank = if n.is_multiple_of(2) {
        m.checked_sub(1)?
    } else {
        m
    };
    let (mut below, mut lo) = (0u64, None);
    let mut hi = 0;
    for (g, &c) in counts.iter().enumerate() {
        if lo.is_none() && below + c > first_rank {
            lo = Some((g, below));
        }
        if below + c > m {
            hi = g;
            break;
        }
        below += c;
    }
    let (lo, before) = lo?;
    let mut middle = Vec::new();
    for_each_delta(e, |v| {
        if v.is_finite() && (lo..=hi).contains(&group(v)) {
            middle.push(v);
        }
    });
    // Ranks within `middle`: it starts at rank `before`.
    let at = usize::try_from(m - before).ok()?;
    middle_value(&mut middle, at, n % 2 == 1)
}

/// The median whose upper middle value has rank `at` in `v` (a count
/// `odd` or not): that value, or its mean with the value below it.
fn middle_value(v: &mut [f64], at: usize, odd: bool) -> Option<f64> {
    let upper = crate::stats::kth_smallest(v, at)?;
    Some(if odd {
        upper
    } else {
        // After the selection the values below rank `at` are `v[..at]`:
        // their largest is the lower middle value.
        let lower = v[..at]
            .iter()
            .copied()
            .max_by(f64::total_cmp)
            .unwrap_or(upper);
        (lower + upper) / 2.0
    })
}

/// Hands every touch's δ to `f` one by one, touch order: for figures and
/// tables that need no list (10⁶ touches' δ are 8 MB per series).
pub(crate) fn for_each_delta(e: &Evaluated, mut f: impl FnMut(f64)) {
    for (point, stats) in e.data.points().iter().zip(&e.ev.points) {
        (e.xyz[point.touches.clone()].iter()).for_each(|x| f(distance(x, &stats.centroid)));
    }
}

/// The median of the finite `values` (none: `None`), by selection over the
/// whole list: what [`median_delta`] found before it stopped holding the
/// list, kept as the tests' reference for its grouping.
#[cfg(test)]
pub(crate) fn median(mut v: Vec<f64>) -> Option<f64> {
    v.retain(|x| x.is_finite());
    let (at, odd) = (v.len() / 2, v.len() % 2 == 1);
    middle_value(&mut v, at, odd)
}

/// The data sets of `evaluated`, in order, once each: (set index, name,
/// data, held out).
pub(crate) fn sets<'a, 'b>(
    evaluated: &'b [Evaluated<'a>],
) -> Vec<(usize, &'b str, &'a DataSet, bool)> {
    let mut out: Vec<(usize, &str, &DataSet, bool)> = Vec::new();
    for e in evaluated {
        if !out.iter().any(|(s, ..)| *s == e.set) {
            out.push((e.set, &e.set_name, e.data, e.held_out));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::{evaluate, pair_length_errors};

    /// The after-fit series `name` of `data` at `xyz`, the only data set.
    fn after<'a>(
        name: &str,
        data: &'a DataSet,
        xyz: &'a [[f64; 3]],
        (ev, pairs): (Evaluation, Pairs),
    ) -> Evaluated<'a> {
        Evaluated {
            set: 0,
            set_name: name.into(),
            data,
            held_out: false,
            stage: Stage::After,
            xyz,
            ev,
            pairs,
            median: std::sync::OnceLock::new(),
        }
    }

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(vec![4.0, f64::NAN, 1.0, 2.0, 3.0]), Some(2.5));
        assert_eq!(median(vec![]), None);
        assert_eq!(median(vec![f64::INFINITY]), None);
    }

    /// The median of δ visited twice is that of the list, to the bit: odd
    /// and even counts, repeated values, values spread over many groups of
    /// the key and crowded into one (the evaluation refuses a position that
    /// is not finite).
    #[test]
    fn the_median_delta_is_the_lists() {
        let mut rng = crate::random::rng(9, 0);
        for (touches, spread) in [
            (9usize, 1.0),
            (10, 1.0),
            (13, 0.0),
            (210, 1e-6),
            (211, 1e3),
            (1000, 1.0),
        ] {
            let labels: Vec<String> = (0..touches).map(|r| format!("p{}", r % 3)).collect();
            let data = DataSet::from_labels(&labels, "m.csv").unwrap();
            let rows: Vec<[f64; 3]> = (0..touches)
                .map(|r| {
                    let v: f64 = rand::RngExt::random_range(&mut rng, 0.0..1.0);
                    // A few values repeat exactly.
                    let v = if r % 5 == 0 { 0.25 } else { v };
                    [(r % 3) as f64 * 100.0 + spread * v, 0.0, 0.0]
                })
                .collect();
            let xyz = data.to_touch_order(&rows);
            let ev = evaluate(&data, &xyz).unwrap();
            let e = after("fitted", &data, &xyz, (ev, Pairs::Each(Vec::new())));
            let want = median(deltas(&e)).map(f64::to_bits);
            assert_eq!(
                median_delta(&e).map(f64::to_bits),
                want,
                "{touches} touches"
            );
        }
    }

    #[test]
    fn many_pairs_are_binned_with_every_pair_counted() {
        // 70 points: 2415 pairs, more than MAX_PAIR_MARKERS.
        let labels: Vec<String> = (0..210).map(|r| format!("p{}", r % 70)).collect();
        let data = DataSet::from_labels(&labels, "m.csv").unwrap();
        let rows: Vec<[f64; 3]> = (0..210)
            .map(|r| {
                let p = (r % 70) as f64;
                [
                    p * 10.0 + (r / 70) as f64 * 0.01,
                    (p * 0.3).sin() * 50.0,
                    0.0,
                ]
            })
            .collect();
        let xyz = data.to_touch_order(&rows);
        let (ev, pairs) = evaluate_with_pairs(&data, &xyz, 0).unwrap();
        assert_eq!(ev, evaluate(&data, &xyz).unwrap());
        let mut expected = vec![(0.0, 0usize); PAIR_BINS];
        let d: Vec<f64> = pair_length_errors(&data, &xyz, &ev.points)
            .map(|p| p.centroid_distance)
            .collect();
        let lo = d.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = d.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let width = (hi - lo) / PAIR_BINS as f64;
        for p in pair_length_errors(&data, &xyz, &ev.points) {
            let k = (((p.centroid_distance - lo) / width) as usize).min(PAIR_BINS - 1);
            expected[k].0 += p.d_error_abs;
            expected[k].1 += 1;
        }
        let e = after("fitted", &data, &xyz, (ev, pairs));
        let Pairs::Binned { bins, count } = e.pairs.clone() else {
            panic!("expected bins")
        };
        for (b, (s, c)) in bins.iter().zip(expected.iter().filter(|x| x.1 > 0)) {
            assert_eq!(b.2, *c);
            assert!((b.1 - s / *c as f64).abs() < 1e-12, "{b:?} vs {s}/{c}");
        }
        assert_eq!(count, 70 * 69 / 2);
        assert_eq!(bins.iter().map(|b| b.2).sum::<usize>(), count);
        assert!(bins.len() <= PAIR_BINS);
        assert_eq!(deltas(&e).len(), 210);
    }

    /// Above the metrics' budget the figure's pairs are a seeded sample,
    /// stated on the figure, whose mean estimates the all-pairs mean
    /// without bias (within 5 σ of the sample mean's spread).
    #[test]
    fn pairs_above_the_budget_are_a_stated_unbiased_sample() {
        // 2000 points of 10 touches: 2·10⁷ touch distances, twice the budget.
        let labels: Vec<String> = (0..20_000).map(|r| format!("p{}", r % 2000)).collect();
        let data = DataSet::from_labels(&labels, "m.csv").unwrap();
        let rows: Vec<[f64; 3]> = (0..20_000)
            .map(|r| {
                let (p, k) = ((r % 2000) as f64, (r / 2000) as f64);
                [(p * 0.37).sin() * 400.0 + k * 0.03, p, (p * k).cos()]
            })
            .collect();
        let xyz = data.to_touch_order(&rows);
        let (ev, pairs) = evaluate_with_pairs(&data, &xyz, 5).unwrap();
        let sample = ev.pair_sample.expect("sampled");
        assert_eq!((sample.pairs, sample.seed), (2000 * 1999 / 2, 5));
        // Kept with probability 1/2: 999 500 ± 707 (σ).
        assert!(sample.sampled.abs_diff(999_500) < 5 * 707, "{sample:?}");
        let Pairs::Binned { count, .. } = &pairs else {
            panic!("expected bins")
        };
        assert_eq!(*count as u64, sample.sampled);
        let mut full = evaluate_without_pairs(&data, &xyz).unwrap();
        add_pairs(
            &mut full,
            &data,
            &xyz,
            (2, &PairSet::All),
            || (),
            |_, _, _| {},
        )
        .unwrap();
        let (s, f) = (
            ev.pair_length_abs_summary.unwrap(),
            full.pair_length_abs_summary.unwrap(),
        );
        let n = sample.sampled as f64;
        let spread = f.std * ((1.0 - n / sample.pairs as f64) / n).sqrt();
        assert!(
            (s.mean - f.mean).abs() < 5.0 * spread,
            "{} vs {}",
            s.mean,
            f.mean
        );
        let e = after("measured", &data, &xyz, (ev, pairs));
        let arms = Arms {
            before: String::new(),
            after: "arm".into(),
        };
        let figure = crate::report::figures::lengths::figure(&[e], &arms).unwrap();
        let said = format!("{} of 1999000 pairs, sampled (seed 5)", sample.sampled);
        assert!(figure.svg.contains(&said), "{said} not on the figure");
    }
}
