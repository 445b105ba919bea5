//! Points in mm: the two operations every layer needs.

/// Euclidean distance between two points.
///
/// ```
/// assert_eq!(aacmm_core::geometry::distance(&[0.0; 3], &[3.0, 4.0, 0.0]), 5.0);
/// ```
pub fn distance(p: &[f64; 3], q: &[f64; 3]) -> f64 {
    p.iter()
        .zip(q)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Mean of the points (NaN for none).
///
/// ```
/// let c = aacmm_core::geometry::centroid(&[[0.0; 3], [2.0, 4.0, 6.0]]);
/// assert_eq!(c, [1.0, 2.0, 3.0]);
/// ```
pub fn centroid(points: &[[f64; 3]]) -> [f64; 3] {
    let n = points.len() as f64;
    std::array::from_fn(|k| points.iter().map(|p| p[k]).sum::<f64>() / n)
}
