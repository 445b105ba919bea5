//! Which pairs of points eq. 19 is summarised over. All pairs cost
//! `Σ_{i<j} min(n_i, n_j)` touch distances — quadratic in the points: at
//! 1000 sockets of 1000 touches 5·10⁸ per arm, most of a 10⁶-touch
//! calibration's time. Above [`PAIR_TOUCH_BUDGET`] a seeded sample of the
//! pairs is taken instead (each pair with the same probability, so the
//! summaries are unbiased estimates of the all-pairs ones), and every
//! output that shows them says so ([`PairSample::describe`]).

use rand::RngExt;
use serde::{Deserialize, Serialize};

use crate::dataset::Point;

/// Touch distances eq. 19 may compute over all pairs of points before the
/// pairs are sampled: 10⁷, a few hundredths of a second (≈ 4 ns each on one
/// thread). Every campaign of up to ~1400 points of 10 touches, or 140 of
/// 1000, is summarised over every pair; above, the sampled pairs cost about
/// this much, whatever the points, so the cost grows no faster than the
/// touches (which the per-point figures visit once).
pub(crate) const PAIR_TOUCH_BUDGET: u64 = 10_000_000;

/// The seed of the pair sample where no session gives one (`aacmm
/// evaluate`, [`super::evaluate`]).
pub(crate) const DEFAULT_PAIR_SEED: u64 = 0;

/// The pairs of points eq. 19 was summarised over, when not all: a seeded
/// sample, each pair kept with the same probability.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct PairSample {
    /// Pairs summarised.
    pub sampled: u64,
    /// Pairs of points in all.
    pub pairs: u64,
    /// The seed of the sample.
    pub seed: u64,
}

impl PairSample {
    /// `N of M pairs, sampled (seed S)`.
    ///
    /// ```
    /// let s = aacmm_core::metrics::PairSample { sampled: 9_950, pairs: 499_500, seed: 3 };
    /// assert_eq!(s.describe(), "9950 of 499500 pairs, sampled (seed 3)");
    /// ```
    pub fn describe(&self) -> String {
        format!(
            "{} of {} pairs, sampled (seed {})",
            self.sampled, self.pairs, self.seed
        )
    }
}

/// Every pair `i < j` of points, or a sample of them in row order.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum PairSet {
    /// Every pair.
    All,
    /// The pairs `(i, j)` drawn, `i < j`, in row-major order.
    Sampled {
        /// The pairs.
        pairs: Vec<(u32, u32)>,
        /// What was drawn, for the outputs.
        sample: PairSample,
    },
}

impl PairSet {
    /// What was drawn, when sampled.
    pub(crate) fn sample(&self) -> Option<PairSample> {
        match self {
            PairSet::All => None,
            PairSet::Sampled { sample, .. } => Some(*sample),
        }
    }
}

/// `Σ_{i<j} min(n_i, n_j)` over the points' touch counts: with the counts
/// sorted ascending, the k-th is the minimum of its pairs with every later
/// one. `n log n` in the points, where summing the pairs is quadratic.
fn pair_work(points: &[Point]) -> u64 {
    let mut counts: Vec<u64> = points.iter().map(|p| p.touches.len() as u64).collect();
    counts.sort_unstable();
    let n = counts.len() as u64;
    (counts.iter().enumerate())
        .map(|(k, &c)| c.saturating_mul(n - 1 - k as u64))
        .fold(0u64, u64::saturating_add)
}

/// The pairs to summarise: all when they cost at most
/// [`PAIR_TOUCH_BUDGET`] touch distances, else each pair kept with
/// probability budget / cost (seeded by `seed`), drawn in row order by
/// geometric gaps — time and memory in the pairs kept, not in all pairs.
pub(crate) fn pair_set(points: &[Point], seed: u64) -> PairSet {
    let work = pair_work(points);
    if work <= PAIR_TOUCH_BUDGET {
        return PairSet::All;
    }
    let n = points.len() as u64;
    let total = n * (n - 1) / 2;
    let p = PAIR_TOUCH_BUDGET as f64 / work as f64;
    let ln_miss = (-p).ln_1p();
    let mut rng = crate::random::rng(seed, crate::random::streams::PAIRS);
    let mut pairs = Vec::with_capacity((p * total as f64 * 1.1) as usize + 16);
    let (mut k, mut row, mut row_start) = (0u64, 0u64, 0u64);
    loop {
        // The pairs skipped before the next kept one: Geometric(p).
        let u: f64 = rng.random();
        let gap = ((-u).ln_1p() / ln_miss).floor();
        // `gap` is finite or +∞ (u near 1), never NaN: 0 < p < 1.
        if gap >= (total - k) as f64 {
            break;
        }
        k += gap as u64;
        while k >= row_start + (n - 1 - row) {
            row_start += n - 1 - row;
            row += 1;
        }
        let col = row + 1 + (k - row_start);
        // Points are fewer than 2³² (the data set's indices are u32).
        pairs.push((row as u32, col as u32));
        k += 1;
        if k >= total {
            break;
        }
    }
    let sample = PairSample {
        sampled: pairs.len() as u64,
        pairs: total,
        seed,
    };
    PairSet::Sampled { pairs, sample }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(counts: &[usize]) -> Vec<Point> {
        let mut start = 0;
        (counts.iter().enumerate())
            .map(|(i, &c)| {
                start += c;
                Point {
                    label: format!("p{i}"),
                    touches: start - c..start,
                }
            })
            .collect()
    }

    #[test]
    fn work_is_the_sum_of_pairwise_minima() {
        let counts = [3, 7, 5, 5, 1000];
        let mut brute = 0;
        for i in 0..counts.len() {
            for j in i + 1..counts.len() {
                brute += counts[i].min(counts[j]) as u64;
            }
        }
        assert_eq!(pair_work(&points(&counts)), brute);
    }

    /// Below the budget every pair; above, a sample of distinct pairs in
    /// row order whose cost is near the budget, the same for the same seed
    /// and another for another seed.
    #[test]
    fn large_campaigns_sample_their_pairs() {
        assert_eq!(pair_set(&points(&[10; 1000]), 1), PairSet::All);
        let big = points(&[1000; 1000]);
        let PairSet::Sampled { pairs, sample } = pair_set(&big, 1) else {
            panic!("10⁶ touches summarised over every pair");
        };
        assert_eq!(sample.pairs, 499_500);
        assert_eq!(sample.sampled, pairs.len() as u64);
        // Expected 10⁷ / 1000 = 10⁴ pairs; binomial σ ≈ 99.
        assert!((9_500..10_500).contains(&pairs.len()), "{}", pairs.len());
        assert!(pairs.windows(2).all(|w| w[0] < w[1]), "not in row order");
        assert!(pairs.iter().all(|&(i, j)| i < j && j < 1000));
        // Rows are covered evenly: the first and last hundred rows hold
        // the shares of the pairs they own (±5 σ).
        let early = pairs.iter().filter(|(i, _)| *i < 100).count() as f64;
        let share = (999.0 + 900.0) / 2.0 * 100.0 / 499_500.0;
        let sd = (pairs.len() as f64 * share * (1.0 - share)).sqrt();
        assert!(
            (early - share * pairs.len() as f64).abs() < 5.0 * sd,
            "{early}"
        );
        assert_eq!(
            pair_set(&big, 1),
            PairSet::Sampled {
                pairs: pairs.clone(),
                sample
            }
        );
        assert_ne!(pair_set(&big, 2), PairSet::Sampled { pairs, sample });
    }
}
