//! Points in mm: distances, centroids, the best rigid motion of one point
//! set onto another and how far they are apart after it.

use nalgebra::{Matrix3, Vector3};

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
    let Some(m) = best_rigid_motion(a, b, reflect) else {
        return f64::INFINITY;
    };
    a.iter()
        .zip(b)
        .map(|(x, y)| (m.rotation * (Vector3::from(*x) - m.from) + m.to - Vector3::from(*y)).norm())
        .fold(0.0, f64::max)
}

/// The best rigid motion of one point set onto another
/// ([`best_rigid_motion`]): `y ≈ rotation (x − from) + to`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RigidMotion {
    /// The rotation (`det = −1`, a mirror, when one was asked for).
    pub rotation: Matrix3<f64>,
    /// The centroid of the points moved.
    pub(crate) from: Vector3<f64>,
    /// The centroid of the points they are moved onto.
    pub(crate) to: Vector3<f64>,
}

impl RigidMotion {
    /// The translation `t` of `y ≈ R x + t`.
    pub(crate) fn translation(&self) -> Vector3<f64> {
        self.to - self.rotation * self.from
    }
}

/// The rigid motion of `a` onto `b` (pairwise) of least squares (Kabsch,
/// Horn: the SVD of their cross-covariance): a proper rotation, or with
/// `mirrored` one with `det = −1`. `None` when the SVD fails.
pub(crate) fn best_rigid_motion(
    a: &[[f64; 3]],
    b: &[[f64; 3]],
    mirrored: bool,
) -> Option<RigidMotion> {
    let mean = |p: &[[f64; 3]]| {
        p.iter()
            .fold(Vector3::zeros(), |s, x| s + Vector3::from(*x))
            / p.len().max(1) as f64
    };
    let (from, to) = (mean(a), mean(b));
    let mut h = Matrix3::zeros();
    for (x, y) in a.iter().zip(b) {
        h += (Vector3::from(*x) - from) * (Vector3::from(*y) - to).transpose();
    }
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    // The sign of the smallest singular direction makes it proper or not.
    let mut d = Matrix3::identity();
    let proper = (v_t.transpose() * u.transpose()).determinant() > 0.0;
    if proper == mirrored {
        d[(2, 2)] = -1.0;
    }
    Some(RigidMotion {
        rotation: v_t.transpose() * d * u.transpose(),
        from,
        to,
    })
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn geometry_best_rigid_motion() {
        use crate::geometry::best_rigid_motion;
        let a = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            [0.0, 0.0, 3.0],
        ];
        let b: Vec<[f64; 3]> = a.iter().map(|p| [-p[1] + 1.0, p[0], p[2] - 2.0]).collect();
        let m = best_rigid_motion(&a, &b, false).unwrap();
        assert!((m.rotation.determinant() - 1.0).abs() < 1e-12);
        assert!((m.translation() - nalgebra::Vector3::new(1.0, 0.0, -2.0)).norm() < 1e-12);
    }
}
