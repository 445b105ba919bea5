//! Per-point figures: the paper's eq. 9–12 and the single-point articulation
//! test (SPAT) of ASME B89.4.22.

use super::{MetricsError, Summary, centroid, check_touches, distance};
use serde::{Deserialize, Serialize};

/// Figures of one physical point (cone socket) touched `n` times in different
/// articulations. With centroid `x̄` and `δ_i = |x_i − x̄|`; lengths in mm.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointStats {
    /// The point's label.
    pub label: String,
    /// Number of touches `n`.
    pub touches: usize,
    /// `x̄ = (1/n) Σ x_i`.
    pub centroid: [f64; 3],
    /// `e = (1/n) Σ δ_i` (paper eq. 9–10).
    pub e: f64,
    /// `σ = sqrt((1/n) Σ (δ_i − e)²)`, population std of `δ` (paper eq. 11).
    pub sigma: f64,
    /// `OA = e + 3σ` (paper eq. 12).
    pub oa: f64,
    /// `δ_max = max δ_i` (SPAT).
    pub delta_max: f64,
    /// `2s` with `s = sqrt(Σ δ_i² / (n − 1))` (SPAT; unverified whether vendors
    /// quote this or `δ_max`).
    pub two_s: f64,
    /// `(max − min)/2` of X, Y and Z separately (FARO's SPAT routine).
    pub half_range: [f64; 3],
}

/// Computes [`PointStats`] from the touches of one point.
///
/// # Errors
///
/// [`MetricsError::TooFewTouches`] below [`super::MIN_TOUCHES`] touches;
/// [`MetricsError::NonFinite`] naming the index into `touches`.
pub(crate) fn point_stats(label: &str, touches: &[[f64; 3]]) -> Result<PointStats, MetricsError> {
    check_touches(label, touches)?;
    let n = touches.len();
    let centroid = centroid(touches);
    let deltas: Vec<f64> = touches.iter().map(|x| distance(x, &centroid)).collect();
    // Invariant: `check_touches` above refused fewer than MIN_TOUCHES
    // touches, so `deltas` is not empty.
    let delta = Summary::of(&deltas).expect("check_touches guarantees touches");
    let sum_sq: f64 = deltas.iter().map(|d| d * d).sum();
    Ok(PointStats {
        label: label.to_owned(),
        touches: n,
        centroid,
        e: delta.mean,
        sigma: delta.std,
        oa: delta.mean + 3.0 * delta.std,
        delta_max: delta.max,
        two_s: 2.0 * (sum_sq / (n - 1) as f64).sqrt(),
        half_range: half_range(touches),
    })
}

/// `(max − min)/2` per axis.
fn half_range(touches: &[[f64; 3]]) -> [f64; 3] {
    std::array::from_fn(|k| {
        let axis = touches.iter().map(|p| p[k]);
        let max = axis.clone().fold(f64::NEG_INFINITY, f64::max);
        let min = axis.fold(f64::INFINITY, f64::min);
        (max - min) / 2.0
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unequal_deviations_on_a_line() {
        // x = 0, 0, 0, 4 → centroid 1, δ = 1, 1, 1, 3
        // e = 6/4 = 1.5; (δ − e)² = 0.25·3 + 2.25 = 3; σ = sqrt(3/4)
        // OA = 1.5 + 3·sqrt(0.75); δ_max = 3
        // s = sqrt((1 + 1 + 1 + 9)/3) = 2 → 2s = 4; half-range x = (4 − 0)/2 = 2
        let touches = [
            [0.0, 7.0, 0.0],
            [0.0, 7.0, 0.0],
            [0.0, 7.0, 0.0],
            [4.0, 7.0, 0.0],
        ];
        let p = point_stats("p", &touches).unwrap();
        assert_eq!(p.touches, 4);
        assert_eq!(p.centroid, [1.0, 7.0, 0.0]);
        assert_eq!(p.e, 1.5);
        assert!((p.sigma - 0.75f64.sqrt()).abs() < 1e-15);
        assert!((p.oa - (1.5 + 3.0 * 0.75f64.sqrt())).abs() < 1e-15);
        assert_eq!(p.delta_max, 3.0);
        assert_eq!(p.two_s, 4.0);
        assert_eq!(p.half_range, [2.0, 0.0, 0.0]);
    }

    #[test]
    fn three_dimensional_spread() {
        // Touches ±(1, 2, 2) around the origin plus the origin itself:
        // δ = 3, 3, 0; e = 2; (δ − e)² = 1 + 1 + 4 = 6 → σ = sqrt(2); δ_max = 3
        // s = sqrt((9 + 9 + 0)/2) = 3 → 2s = 6; half-range = (1, 2, 2)
        let touches = [[1.0, 2.0, 2.0], [-1.0, -2.0, -2.0], [0.0, 0.0, 0.0]];
        let p = point_stats("p", &touches).unwrap();
        assert_eq!(p.e, 2.0);
        assert!((p.sigma - 2f64.sqrt()).abs() < 1e-15);
        assert_eq!(p.delta_max, 3.0);
        assert_eq!(p.two_s, 6.0);
        assert_eq!(p.half_range, [1.0, 2.0, 2.0]);
    }

    #[test]
    fn identical_touches_give_zeros() {
        let p = point_stats("p", &[[1.0, 2.0, 3.0]; 3]).unwrap();
        assert_eq!(
            (p.e, p.sigma, p.oa, p.delta_max, p.two_s),
            (0.0, 0.0, 0.0, 0.0, 0.0)
        );
        assert_eq!(p.half_range, [0.0; 3]);
    }

    #[test]
    fn too_few_touches() {
        assert_eq!(
            point_stats("p", &[[0.0; 3]; 2]),
            Err(MetricsError::TooFewTouches {
                label: "p".into(),
                touches: 2
            })
        );
    }

    #[test]
    fn infinite_touch_is_named_by_index() {
        let touches = [[0.0; 3], [0.0; 3], [0.0, 0.0, f64::INFINITY]];
        assert_eq!(
            point_stats("p", &touches),
            Err(MetricsError::NonFinite {
                label: "p".into(),
                at: "touch 2".into()
            })
        );
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn metrics_point_point_stats() {
        use crate::metrics::point_stats;
        // Corners of a square of side 2 around (5, 5, 5): δ = √2 for each touch.
        let touches = [
            [6.0, 6.0, 5.0],
            [4.0, 6.0, 5.0],
            [4.0, 4.0, 5.0],
            [6.0, 4.0, 5.0],
        ];
        let p = point_stats("socket", &touches).unwrap();
        let r2 = 2f64.sqrt();
        assert_eq!(p.centroid, [5.0, 5.0, 5.0]);
        assert!((p.e - r2).abs() < 1e-12);
        assert!(p.sigma.abs() < 1e-12);
        assert!((p.oa - r2).abs() < 1e-12); // e + 3·0
        assert!((p.delta_max - r2).abs() < 1e-12);
        assert!((p.two_s - 2.0 * (4.0 * 2.0 / 3.0f64).sqrt()).abs() < 1e-12);
        assert_eq!(p.half_range, [1.0, 1.0, 0.0]);
    }
}
