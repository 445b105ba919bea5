//! Reference lengths: calibrated distances between socket pairs, as a ball
//! bar or a cone plate would give them.

use rand::RngExt;
use rand_chacha::ChaCha8Rng;

use super::SimError;
use super::truth::normal;
use crate::domain::ReferenceLength;
use crate::error::quoted;
use crate::geometry::distance;

/// `count` distinct socket pairs and their true distances (mm), chosen with
/// `rng` among the longer half of all pairs (at least `count` of them), the
/// way a ball bar is set to span the volume; written longest first. With
/// `uncertainty` (mm), each distance gets Gaussian noise of that σ and
/// states it. `line` is the row's line in `lengths.csv`.
///
/// ```
/// use aacmm_core::simulate::reference_lengths;
/// use rand::SeedableRng;
/// let s = vec![("A".to_string(), [0.0; 3]), ("B".into(), [3.0, 4.0, 0.0]), ("C".into(), [1.0, 0.0, 0.0])];
/// let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
/// let l = reference_lengths(&s, 1, None, &mut rng).unwrap();
/// assert!(l[0].distance >= 4.0); // from the longer half: A–B (5) or B–C (√20)
/// ```
pub fn reference_lengths(
    sockets: &[(String, [f64; 3])],
    count: usize,
    uncertainty: Option<f64>,
    rng: &mut ChaCha8Rng,
) -> Result<Vec<ReferenceLength>, SimError> {
    let mut pairs: Vec<(usize, usize, f64)> = Vec::new();
    for i in 0..sockets.len() {
        for j in i + 1..sockets.len() {
            pairs.push((i, j, distance(&sockets[i].1, &sockets[j].1)));
        }
    }
    if count > pairs.len() {
        return Err(SimError::setting(
            "reference_lengths",
            format!(
                "{count} reference lengths asked for, but {} sockets make only {} distinct pairs",
                sockets.len(),
                pairs.len()
            ),
        ));
    }
    // Longest first; ties keep the pair order.
    pairs.sort_by(|x, y| y.2.total_cmp(&x.2));
    let pool = count.max(pairs.len().div_ceil(2));
    let mut order: Vec<usize> = (0..pool).collect();
    for i in 0..count {
        let j = rng.random_range(i..pool);
        order.swap(i, j);
    }
    let mut chosen = order[..count].to_vec();
    chosen.sort_unstable();
    chosen
        .into_iter()
        .enumerate()
        .map(|(row, p)| {
            let (i, j, d) = pairs[p];
            if d.is_nan() || d <= 0.0 {
                // Not the noise: the sockets themselves coincide.
                return Err(SimError::setting(
                    "sockets.points",
                    format!(
                        "sockets {} and {} are at the same place: no reference length \
                         between them",
                        quoted(&sockets[i].0),
                        quoted(&sockets[j].0)
                    ),
                ));
            }
            let distance = match uncertainty {
                Some(u) => d + u * normal(rng),
                None => d,
            };
            if distance.is_nan() || distance <= 0.0 {
                return Err(SimError::setting(
                    "length_uncertainty_mm",
                    format!(
                        "the noisy distance {}–{} came out {distance} mm: the uncertainty is \
                         too large for a {d:.3} mm length",
                        sockets[i].0, sockets[j].0
                    ),
                ));
            }
            Ok(ReferenceLength {
                a: sockets[i].0.clone(),
                b: sockets[j].0.clone(),
                distance,
                uncertainty,
                line: row + 2,
            })
        })
        .collect()
}
