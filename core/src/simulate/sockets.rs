//! Socket placement: positions spread over the part of the workspace that
//! the true arm reaches comfortably, in many articulations.

use std::f64::consts::PI;

use rand::RngExt;
use rand_chacha::ChaCha8Rng;

use super::SimError;
use crate::domain::Arm;
use crate::geometry::distance;
use crate::kernel::ArmKernel;

/// Random configurations whose probe centres are the candidate positions
/// (at least this many; more for many sockets).
pub(crate) const SOCKET_CANDIDATES: usize = 4000;
/// The comfortable volume: distance from the shoulder between these
/// fractions of the arm's reach.
pub(crate) const REACH_BAND: [f64; 2] = [0.3, 0.8];
/// Sockets are at least this fraction of the reach apart.
pub(crate) const MIN_SOCKET_SEPARATION: f64 = 0.05;
/// Sockets are at least this fraction of the reach from the base axis,
/// clear of the arm's own base column.
pub(crate) const MIN_AXIS_DISTANCE: f64 = 0.2;

/// A random configuration: each reading uniform within its joint's limits,
/// or in `[-π, π)` for a joint without limits.
pub(crate) fn random_configuration(limits: &[Option<[f64; 2]>], rng: &mut ChaCha8Rng) -> Vec<f64> {
    limits
        .iter()
        .map(|lim| match lim {
            Some([lo, hi]) => rng.random_range(*lo..=*hi),
            None => rng.random_range(-PI..PI),
        })
        .collect()
}

/// The shoulder: the point of the base axis at height `d1`, where the arm's
/// reach is measured from.
pub fn shoulder(arm: &Arm) -> [f64; 3] {
    [0.0, 0.0, arm.params.joints.first().map_or(0.0, |j| j.d)]
}

/// `count` socket centres `S1..Scount` for the true arm.
///
/// Candidates are the probe centres of random configurations (within the
/// joint limits), so every one is reachable. Those whose distance from the
/// [`shoulder`] is within 30–80 % of the reach (the largest distance
/// seen), that lie above the mounting plane (the base frame's `z = 0`, as on
/// a bench; no other obstacle is modelled) and at least 20 % of the reach
/// from the base axis are split into three equal strata by distance from the base axis —
/// near, middle, far, as in ASME B89.4.22 — and socket `i` is taken from
/// stratum `i mod 3`: the first at random, each next the candidate farthest
/// from the sockets already placed (farthest-point sampling), which must be
/// at least 5 % of the reach from all of them
/// (another stratum is tried before giving up). Centres are rounded to 1 nm
/// (6 decimals in mm), so that `sockets.csv` holds them exactly.
pub fn place_sockets(
    arm: &Arm,
    count: usize,
    rng: &mut ChaCha8Rng,
) -> Result<Vec<(String, [f64; 3])>, SimError> {
    let k = ArmKernel::new(&arm.params)?;
    let c = shoulder(arm);
    let pool = SOCKET_CANDIDATES.max(200 * count);
    let configurations: Vec<Vec<f64>> = (0..pool)
        .map(|_| random_configuration(&arm.limits, rng))
        .collect();
    let points = k.positions_of(&configurations)?;
    let reach = points.iter().map(|p| distance(p, &c)).fold(0.0, f64::max);
    let mut band: Vec<[f64; 3]> = points
        .into_iter()
        .filter(|p| {
            let r = distance(p, &c) / reach;
            (REACH_BAND[0]..=REACH_BAND[1]).contains(&r)
                && p[2] >= 0.0
                && p[0].hypot(p[1]) >= MIN_AXIS_DISTANCE * reach
        })
        .collect();
    band.sort_by(|a, b| a[0].hypot(a[1]).total_cmp(&b[0].hypot(b[1])));
    let strata: Vec<usize> = (0..band.len()).map(|i| i * 3 / band.len().max(1)).collect();
    let min_sep = MIN_SOCKET_SEPARATION * reach;
    let mut nearest = vec![f64::INFINITY; band.len()];
    let mut out = Vec::with_capacity(count);
    for i in 0..count {
        let stratum = i % 3;
        let pick = if i == 0 {
            let members: Vec<usize> = (0..band.len()).filter(|&c| strata[c] == stratum).collect();
            (!members.is_empty()).then(|| members[rng.random_range(0..members.len())])
        } else {
            farthest(&nearest, |c| strata[c] == stratum, min_sep)
                .or_else(|| farthest(&nearest, |_| true, min_sep))
        };
        let Some(pick) = pick else {
            return Err(SimError::SocketsNotPlaced {
                wanted: count,
                placed: i,
                min_separation_mm: min_sep,
            });
        };
        let p = band[pick];
        for (d, q) in nearest.iter_mut().zip(&band) {
            *d = d.min(distance(q, &p));
        }
        out.push((format!("S{}", i + 1), p.map(round_nm)));
    }
    Ok(out)
}

/// The candidate (among those `keep` accepts) farthest from the placed
/// sockets, if it is at least `min_sep` from all of them.
fn farthest(nearest: &[f64], keep: impl Fn(usize) -> bool, min_sep: f64) -> Option<usize> {
    let (best, d) = nearest
        .iter()
        .enumerate()
        .filter(|&(c, _)| keep(c))
        .max_by(|a, b| a.1.total_cmp(b.1))?;
    (*d >= min_sep).then_some(best)
}

/// `x` rounded to 6 decimals: the value `{:.6}` prints and reads back exactly.
pub(crate) fn round_nm(x: f64) -> f64 {
    format!("{x:.6}").parse().unwrap_or(x)
}
