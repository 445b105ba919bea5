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
/// The gaps are drawn, and turned into pairs ([`pairs_from`]), on up to
/// `threads` threads ([`Gaps`]): the same pairs on any count.
pub(crate) fn pair_set(points: &[Point], seed: u64, threads: usize) -> PairSet {
    let work = pair_work(points);
    if work <= PAIR_TOUCH_BUDGET {
        return PairSet::All;
    }
    let n = points.len() as u64;
    let total = n * (n - 1) / 2;
    let p = PAIR_TOUCH_BUDGET as f64 / work as f64;
    let mut pairs = Vec::with_capacity((p * total as f64 * 1.1) as usize + 16);
    let mut draws = Gaps::new(seed, p);
    // The index, in row-major order, of the pair the next gap counts from.
    let mut k = 0u64;
    while k < total {
        // Draws for the pairs still to come, but in one case of about 10⁴
        // (the kept pairs are binomial: 4 σ past their mean), at most a
        // few chunks a thread at a time (their memory).
        let rest = p * (total - k) as f64;
        let wave =
            ((rest + 4.0 * rest.sqrt()) as u64 + 1).min(GAP_CHUNK * 8 * threads.max(1) as u64);
        let chunks = draws.next_wave(wave, threads);
        // Each chunk's gaps with where its first gap counts from: the
        // chunks before it span their gaps and a kept pair each.
        let mut work: Vec<(u64, &[u64])> = Vec::with_capacity(chunks.len());
        for chunk in &chunks {
            work.push((k, &chunk.gaps));
            k = k.saturating_add(chunk.span);
        }
        let kept = crate::parallel::parallel_map(&work, threads, |&(start, gaps)| {
            pairs_from(start, gaps, n, total)
        });
        for chunk in kept {
            pairs.extend_from_slice(&chunk);
        }
    }
    let sample = PairSample {
        sampled: pairs.len() as u64,
        pairs: total,
        seed,
    };
    PairSet::Sampled { pairs, sample }
}

/// Draws of a gap a work item.
const GAP_CHUNK: u64 = 1 << 14;

/// The pairs `gaps` keep, the first gap counted from pair `k` (row-major
/// index): pair `k + gap` is kept and the next gap counts from the pair
/// after it, until a gap reaches past the last pair. A chunk's pairs are
/// found from its start alone, so the chunks are turned into pairs side
/// by side — the same pairs as one loop over every gap.
fn pairs_from(mut k: u64, gaps: &[u64], n: u64, total: u64) -> Vec<(u32, u32)> {
    let mut pairs = Vec::with_capacity(gaps.len());
    if k >= total {
        return pairs;
    }
    let (mut row, mut row_start) = row_of(k, n);
    for &gap in gaps {
        if gap >= total - k {
            break;
        }
        k += gap;
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
    pairs
}

/// The row `i` of pair `k` (row-major over `i < j < n`) and the index of
/// that row's first pair: the last row whose first pair is at most `k`.
/// Row `r` starts at `r (n − 1) − r (r − 1) / 2`, increasing in `r`.
fn row_of(k: u64, n: u64) -> (u64, u64) {
    let start = |r: u64| {
        let (r, n) = (u128::from(r), u128::from(n));
        // At most n²/2 < 2⁶⁴ (points are fewer than 2³²).
        (r * (n - 1) - r * r.saturating_sub(1) / 2) as u64
    };
    // The first row past `k`'s, in 1..n − 1 (row n − 2 holds the last pair).
    let (mut low, mut high) = (0u64, n - 1);
    while high - low > 1 {
        let mid = low + (high - low) / 2;
        if start(mid) <= k {
            low = mid;
        } else {
            high = mid;
        }
    }
    (low, start(low))
}

/// A chunk of gaps, each as a count of pairs skipped (`u64::MAX` for one
/// past any count: a uniform near 1), and the pairs they span with a kept
/// pair after each (saturating).
struct Drawn {
    gaps: Vec<u64>,
    span: u64,
}

/// The pairs skipped before each kept one, Geometric(p): draw `i` is
/// `⌊ln(1 − u_i) / ln(1 − p)⌋`, `u_i` the `i`-th uniform of the pairs'
/// stream. A uniform is two words of the stream, so a chunk of draws
/// starts its own copy of the stream at its first draw's words and draws
/// the same values as one stream read from the start.
struct Gaps {
    stream: rand_chacha::ChaCha8Rng,
    ln_miss: f64,
    /// Draws made.
    drawn: u64,
}

impl Gaps {
    fn new(seed: u64, p: f64) -> Gaps {
        Gaps {
            stream: crate::random::rng(seed, crate::random::streams::PAIRS),
            ln_miss: (-p).ln_1p(),
            drawn: 0,
        }
    }

    /// The next `count` draws (rounded up to whole chunks), in order, a
    /// chunk at a time.
    fn next_wave(&mut self, count: u64, threads: usize) -> Vec<Drawn> {
        let starts: Vec<u64> = (0..count.div_ceil(GAP_CHUNK))
            .map(|c| self.drawn + c * GAP_CHUNK)
            .collect();
        self.drawn += starts.len() as u64 * GAP_CHUNK;
        crate::parallel::parallel_map(&starts, threads, |&first| {
            let mut stream = self.stream.clone();
            stream.set_word_pos(2 * u128::from(first));
            let gaps: Vec<u64> = (0..GAP_CHUNK)
                .map(|_| {
                    let u: f64 = stream.random();
                    // ≥ 0 (both logarithms ≤ 0), finite or +∞ (u near 1),
                    // never NaN: 0 < p < 1. The cast truncates, which is
                    // the floor for x ≥ 0 (and a floor call was a sixth of
                    // a draw's time), and saturates at 2⁶⁴ − 1, past any
                    // count of pairs.
                    ((-u).ln_1p() / self.ln_miss) as u64
                })
                .collect();
            let span = (gaps.iter()).fold(0u64, |s, &g| s.saturating_add(g).saturating_add(1));
            Drawn { gaps, span }
        })
    }
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

    /// The pairs drawn from one stream read from its start, a gap at a
    /// time (the loop before the draws were shared between threads).
    fn drawn_in_one_stream(points: &[Point], seed: u64) -> Vec<(u32, u32)> {
        let n = points.len() as u64;
        let total = n * (n - 1) / 2;
        let ln_miss = (-(PAIR_TOUCH_BUDGET as f64 / pair_work(points) as f64)).ln_1p();
        let mut rng = crate::random::rng(seed, crate::random::streams::PAIRS);
        let (mut pairs, mut k) = (Vec::new(), 0u64);
        loop {
            let u: f64 = rng.random();
            let gap = ((-u).ln_1p() / ln_miss).floor();
            if gap >= (total - k) as f64 {
                return pairs;
            }
            k += gap as u64;
            let (mut row, mut row_start) = (0, 0);
            while k >= row_start + (n - 1 - row) {
                row_start += n - 1 - row;
                row += 1;
            }
            pairs.push((row as u32, (row + 1 + k - row_start) as u32));
            k += 1;
            if k >= total {
                return pairs;
            }
        }
    }

    /// 1500 points of 100 touches keep about 9·10⁴ of their 1.1·10⁶
    /// pairs: 6 chunks of draws, shared by 2 and 4 threads. The pairs are
    /// those one stream read from its start gives, for several seeds.
    #[test]
    fn the_pairs_drawn_in_chunks_are_those_of_one_stream() {
        let many = points(&[100; 1500]);
        for seed in [0, 1, 7] {
            let want = drawn_in_one_stream(&many, seed);
            assert!(want.len() as u64 > 5 * GAP_CHUNK, "{}", want.len());
            for threads in [1, 2, 4] {
                let PairSet::Sampled { pairs, .. } = pair_set(&many, seed, threads) else {
                    panic!("sampled");
                };
                assert_eq!(pairs, want, "seed {seed}, {threads} threads");
            }
        }
        // Waves of any size continue the stream where the last one ended.
        let mut one = Gaps::new(3, 0.01);
        let gaps = |wave: Vec<Drawn>| wave.into_iter().flat_map(|d| d.gaps).collect::<Vec<u64>>();
        let whole = gaps(one.next_wave(5 * GAP_CHUNK, 1));
        let mut waves = Gaps::new(3, 0.01);
        let mut parts = Vec::new();
        for (count, threads) in [(1, 2), (GAP_CHUNK + 1, 4), (GAP_CHUNK, 1)] {
            parts.extend(gaps(waves.next_wave(count, threads)));
        }
        assert_eq!(parts.len() as u64, 4 * GAP_CHUNK);
        assert_eq!(parts[..], whole[..parts.len()]);
    }

    /// The row of every pair, found by halving, is the one counting rows
    /// from the first finds.
    #[test]
    fn the_row_of_a_pair_is_found_by_halving() {
        for n in [2u64, 3, 4, 7, 50] {
            let (mut row, mut row_start, total) = (0, 0, n * (n - 1) / 2);
            for k in 0..total {
                while k >= row_start + (n - 1 - row) {
                    row_start += n - 1 - row;
                    row += 1;
                }
                assert_eq!(row_of(k, n), (row, row_start), "pair {k} of {n} points");
            }
        }
        // 2³² − 1 points: the last pair's row, without overflow.
        let n = u64::from(u32::MAX);
        assert_eq!(row_of(n * (n - 1) / 2 - 1, n).0, n - 2);
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
        assert_eq!(pair_set(&points(&[10; 1000]), 1, 2), PairSet::All);
        let big = points(&[1000; 1000]);
        let PairSet::Sampled { pairs, sample } = pair_set(&big, 1, 2) else {
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
            pair_set(&big, 1, 1),
            PairSet::Sampled {
                pairs: pairs.clone(),
                sample
            }
        );
        assert_ne!(pair_set(&big, 2, 2), PairSet::Sampled { pairs, sample });
    }
}
