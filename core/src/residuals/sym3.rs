//! Symmetric 3 × 3 matrices: a touch's weight, a centre's covariance.

/// A symmetric 3 × 3 matrix: `[xx, yy, zz, xy, xz, yz]`.
pub(crate) type Sym3 = [f64; 6];

/// `A·v` for a symmetric `A`.
#[inline(always)]
pub(crate) fn sym_mul(a: &Sym3, v: &[f64; 3]) -> [f64; 3] {
    [
        a[0] * v[0] + a[3] * v[1] + a[4] * v[2],
        a[3] * v[0] + a[1] * v[1] + a[5] * v[2],
        a[4] * v[0] + a[5] * v[1] + a[2] * v[2],
    ]
}

/// The inverse of a symmetric positive-definite 3 × 3 matrix (adjugate).
pub(crate) fn sym_inv(a: &Sym3) -> Sym3 {
    let [xx, yy, zz, xy, xz, yz] = *a;
    let c = [
        yy * zz - yz * yz,
        xx * zz - xz * xz,
        xx * yy - xy * xy,
        xz * yz - xy * zz,
        xy * yz - xz * yy,
        xy * xz - xx * yz,
    ];
    let det = xx * c[0] + xy * c[3] + xz * c[4];
    c.map(|v| v / det)
}

/// The centroid covariance `(Σ A_i)⁻¹` of a point from its touches'
/// weights, summed in touch order.
pub(crate) fn centroid_cov(touch: &[Sym3]) -> Sym3 {
    let mut sum = [0.0; 6];
    for a in touch {
        for (s, v) in sum.iter_mut().zip(a) {
            *s += v;
        }
    }
    sym_inv(&sum)
}
