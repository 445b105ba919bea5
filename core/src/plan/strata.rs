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

use crate::io::Poses;

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
    for _ in 0..ITERATIONS {
        let mut changed = false;
        for (i, l) in label.iter_mut().enumerate() {
            let best = (0..k)
                .map(|c| (c, dist(row(i), &centres[c * d..(c + 1) * d])))
                .fold((0, f64::INFINITY), |b, x| if x.1 < b.1 { x } else { b })
                .0;
            changed |= best != *l;
            *l = best;
        }
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
