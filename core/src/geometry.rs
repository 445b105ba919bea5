//! Points in mm: distances, centroids, and how far two point sets are apart
//! after the best rigid motion.

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

/// The largest distance between the points `a` and `b` (pairwise) after the
/// best rigid motion of `a` onto `b` in the least-squares sense (Kabsch):
/// a proper one (a rotation), or with `reflect` one that mirrors. How far
/// a calibrated arm is from a true one whatever the base frame — and,
/// comparing the two, whether it is the true arm's mirror image.
///
/// ```
/// use aacmm_core::geometry::rigid_distance;
/// let a = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]];
/// let moved: Vec<[f64; 3]> = a.iter().map(|p| [p[1] + 5.0, -p[0], p[2]]).collect();
/// let mirrored: Vec<[f64; 3]> = a.iter().map(|p| [p[0], p[1], -p[2]]).collect();
/// assert!(rigid_distance(&a, &moved, false) < 1e-12);
/// assert!(rigid_distance(&a, &mirrored, false) > 1.0);
/// assert!(rigid_distance(&a, &mirrored, true) < 1e-12);
/// ```
pub fn rigid_distance(a: &[[f64; 3]], b: &[[f64; 3]], reflect: bool) -> f64 {
    use nalgebra::{Matrix3, Vector3};
    let mean = |p: &[[f64; 3]]| {
        p.iter()
            .fold(Vector3::zeros(), |s, x| s + Vector3::from(*x))
            / p.len().max(1) as f64
    };
    let (ca, cb) = (mean(a), mean(b));
    let mut h = Matrix3::zeros();
    for (x, y) in a.iter().zip(b) {
        h += (Vector3::from(*x) - ca) * (Vector3::from(*y) - cb).transpose();
    }
    let svd = h.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return f64::INFINITY;
    };
    let mut d = Matrix3::identity();
    let proper = (v_t.transpose() * u.transpose()).determinant() > 0.0;
    if proper == reflect {
        d[(2, 2)] = -1.0;
    }
    let r = v_t.transpose() * d * u.transpose();
    a.iter()
        .zip(b)
        .map(|(x, y)| (r * (Vector3::from(*x) - ca) + cb - Vector3::from(*y)).norm())
        .fold(0.0, f64::max)
}
