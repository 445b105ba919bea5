//! Strata of a pool: `k` clusters of poses that look alike (k-means on
//! each joint's `cos q`, `sin q`, so a turn is a turn), for a plan that
//! takes one row from each — a sample that represents the pool the way a
//! random one does, with each row the most informative of its stratum.
//!
//! Why: the errors no model explains (compliance, bending, heat, a
//! tracker's own) differ from pose to pose; a fit to rows that represent
//! the workspace averages them as the fit to every pose would, while rows
//! gathered where the information is largest fit those poses' share.

use rand::RngExt;

use crate::domain::Poses;

/// Lloyd iterations at most.
const ITERATIONS: usize = 20;

/// The stratum of every row of `pool`, `k` strata (k-means++ seeded).
pub(crate) fn strata(pool: &Poses, k: usize, seed: u64) -> Vec<usize> {
    let n = pool.len();
    let d = 2 * pool.joints();
    let f: Vec<f64> = (0..n)
        .flat_map(|i| pool.reading(i).iter().flat_map(|q| [q.cos(), q.sin()]))
        .collect();
    let row = |i: usize| &f[i * d..(i + 1) * d];
    let dist = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>();
    let k = k.clamp(1, n.max(1));
    let mut rng = crate::random::rng(seed, crate::random::streams::PLAN);
    // k-means++: each next centre drawn with probability ∝ its squared
    // distance from the nearest centre so far.
    let mut centres: Vec<f64> = row(rng.random_range(0..n)).to_vec();
    let mut near: Vec<f64> = (0..n).map(|i| dist(row(i), &centres[..d])).collect();
    while centres.len() < k * d {
        let total: f64 = near.iter().sum();
        let mut t = rng.random_range(0.0..total.max(f64::MIN_POSITIVE));
        let mut pick = n - 1;
        for (i, w) in near.iter().enumerate() {
            if t < *w {
                pick = i;
                break;
            }
            t -= w;
        }
        let c = row(pick).to_vec();
        for (i, v) in near.iter_mut().enumerate() {
            *v = v.min(dist(row(i), &c));
        }
        centres.extend(c);
    }
    let mut label = vec![0; n];
    let mut nearest = Nearest::new(k, d);
    for _ in 0..ITERATIONS {
        nearest.centres(&centres);
        // (Compiled for AVX2 where the CPU has it: the same bits.)
        let changed = crate::simd::with_avx2(
            #[inline(always)]
            || {
                let mut changed = false;
                for (i, l) in label.iter_mut().enumerate() {
                    let best = nearest.of(row(i));
                    changed |= best != *l;
                    *l = best;
                }
                changed
            },
        );
        let mut sum = vec![0.0; k * d];
        let mut size = vec![0usize; k];
        for (i, &l) in label.iter().enumerate() {
            size[l] += 1;
            for (s, v) in sum[l * d..(l + 1) * d].iter_mut().zip(row(i)) {
                *s += v;
            }
        }
        for c in (0..k).filter(|&c| size[c] > 0) {
            for j in 0..d {
                centres[c * d + j] = sum[c * d + j] / size[c] as f64;
            }
        }
        if !changed {
            break;
        }
    }
    label
}

/// The nearest of `k` centres to a row, all `k` distances at once: the
/// centres kept by coordinate (`d × k`), so that each coordinate's squared
/// difference is added to every centre's sum in one sweep over the
/// centres. Each sum still adds its `d` terms in order from −0.0, as
/// `Iterator::sum` does, so the same bits as one centre at a time; the
/// sweep vectorises (it was 10 % of choosing 100 of 2 000 poses).
struct Nearest {
    k: usize,
    d: usize,
    /// `by_coordinate[j * k + c]`: centre `c`'s coordinate `j`.
    by_coordinate: Vec<f64>,
    sums: Vec<f64>,
}

impl Nearest {
    fn new(k: usize, d: usize) -> Nearest {
        Nearest {
            k,
            d,
            by_coordinate: vec![0.0; k * d],
            sums: vec![0.0; k],
        }
    }

    /// Takes the centres (`k × d`, by centre).
    fn centres(&mut self, centres: &[f64]) {
        for (c, centre) in centres.chunks_exact(self.d).enumerate() {
            for (j, &v) in centre.iter().enumerate() {
                self.by_coordinate[j * self.k + c] = v;
            }
        }
    }

    /// The nearest centre to `row` (the first of equals).
    #[inline(always)]
    fn of(&mut self, row: &[f64]) -> usize {
        let sums = &mut self.sums;
        sums.iter_mut().for_each(|s| *s = -0.0);
        for (&x, centres) in row.iter().zip(self.by_coordinate.chunks_exact(self.k)) {
            for (s, &y) in sums.iter_mut().zip(centres) {
                *s += (x - y) * (x - y);
            }
        }
        sums.iter()
            .enumerate()
            .fold(
                (0, f64::INFINITY),
                |b, (c, &s)| if s < b.1 { (c, s) } else { b },
            )
            .0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// All distances at once pick the same centre as one distance at a
    /// time, and their sums are the same bits.
    #[test]
    fn the_swept_distances_are_the_one_at_a_time_distances() {
        let dist =
            |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>();
        let (k, d) = (7, 5);
        let value = |i: usize| ((i * 7919 % 1009) as f64 / 1009.0 - 0.5) * 1.7;
        let mut centres: Vec<f64> = (0..k * d).map(value).collect();
        // Two equal centres: the first of them is the nearest.
        let (first, rest) = centres.split_at_mut(3 * d);
        rest[..d].copy_from_slice(&first[2 * d..]);
        let mut nearest = Nearest::new(k, d);
        nearest.centres(&centres);
        for r in 0..200 {
            let row: Vec<f64> = (0..d).map(|j| value(r * 31 + j * 3 + 5)).collect();
            let one = (0..k)
                .map(|c| (c, dist(&row, &centres[c * d..(c + 1) * d])))
                .fold((0, f64::INFINITY), |b, x| if x.1 < b.1 { x } else { b })
                .0;
            assert_eq!(nearest.of(&row), one, "row {r}");
            for c in 0..k {
                let one = dist(&row, &centres[c * d..(c + 1) * d]);
                assert_eq!(
                    nearest.sums[c].to_bits(),
                    one.to_bits(),
                    "row {r}, centre {c}"
                );
            }
        }
        let at_a_copy = centres[2 * d..3 * d].to_vec();
        assert_eq!(nearest.of(&at_a_copy), 2);
    }
}
