//! [`Generic`]: the kernel of every chain the toolkit ships no generated
//! kernel for — any mix of revolute and prismatic joints, D-H or Hayati,
//! 1 to 12 joints. It is the generated kernels' algorithm with the joint
//! kinds and models read at run time: closed-form updates per link (the
//! frames' axes and origins, then each Jacobian column as an axis or one
//! cross product), no 4×4 matrix products, generic over the same scalar
//! types, so it runs in the same SIMD lanes with the same bits as one
//! pose. What it cannot do that the generator does is fold a structural
//! zero or one away, and share work across joints by expression sharing:
//! the benches compare the two (`benches/kernel.rs`).

use super::{Chain, Consts, Scalar};

/// The kernel of any chain: the joints' kinds from
/// [`Consts::prismatic`], their models from [`Consts::hayati`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Generic;

type V3<S> = [S; 3];

#[inline(always)]
fn add<S: Scalar>(u: V3<S>, v: V3<S>) -> V3<S> {
    [u[0] + v[0], u[1] + v[1], u[2] + v[2]]
}

#[inline(always)]
fn sub<S: Scalar>(u: V3<S>, v: V3<S>) -> V3<S> {
    [u[0] - v[0], u[1] - v[1], u[2] - v[2]]
}

/// `s·u + t·v`.
#[inline(always)]
fn combine<S: Scalar>(s: S, u: V3<S>, t: S, v: V3<S>) -> V3<S> {
    [
        s * u[0] + t * v[0],
        s * u[1] + t * v[1],
        s * u[2] + t * v[2],
    ]
}

#[inline(always)]
fn cross<S: Scalar>(u: V3<S>, v: V3<S>) -> V3<S> {
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

/// Joint `i`'s `(cos, sin)` of its angle and its offset along the previous
/// z axis: `θ + q` and `d` for a revolute joint (the angle sum from the
/// reading's cos and sin), `θ` and `d + q` for a prismatic one.
#[inline(always)]
fn joint<S: Scalar, const N: usize>(
    k: &Consts<S, N>,
    i: usize,
    cq: &[S; N],
    sq: &[S; N],
) -> (S, S, S) {
    if k.prismatic[i] {
        (k.ct[i], k.st[i], k.d[i] + cq[i])
    } else {
        (
            cq[i] * k.ct[i] - sq[i] * k.st[i],
            sq[i] * k.ct[i] + cq[i] * k.st[i],
            k.d[i],
        )
    }
}

/// Frames 1..=N in the base frame: `x[i]` etc. are frame `i + 1`'s.
struct Frames<S, const N: usize> {
    /// The x axis before the link's `Ry(β)`: `a`'s direction, `α`'s axis.
    xa: [V3<S>; N],
    x: [V3<S>; N],
    y: [V3<S>; N],
    z: [V3<S>; N],
    o: [V3<S>; N],
}

impl<S: Scalar, const N: usize> Frames<S, N> {
    /// Left to right, one link's update at a time; the base frame (the
    /// identity) is folded into the first link by hand.
    #[inline(always)]
    fn new(k: &Consts<S, N>, cq: &[S; N], sq: &[S; N]) -> Self {
        let zero = S::from(0.0);
        let v0 = [zero; 3];
        let mut f = Frames {
            xa: [v0; N],
            x: [v0; N],
            y: [v0; N],
            z: [v0; N],
            o: [v0; N],
        };
        for i in 0..N {
            let (c, s, d) = joint(k, i, cq, sq);
            let (ca, sa) = (k.ca[i], k.sa[i]);
            let (x, y, z, o) = if i == 0 {
                // Rz·Tz·Tx·Rx of the identity, in closed form.
                let x = [c, s, zero];
                let y = [-(ca * s), ca * c, sa];
                let z = [sa * s, -(sa * c), ca];
                (x, y, z, [k.a[i] * c, k.a[i] * s, d])
            } else {
                let (px, py, pz) = (f.x[i - 1], f.y[i - 1], f.z[i - 1]);
                let x = combine(c, px, s, py);
                let u = combine(c, py, -s, px);
                let y = combine(ca, u, sa, pz);
                let z = combine(ca, pz, -sa, u);
                (x, y, z, add(f.o[i - 1], combine(d, pz, k.a[i], x)))
            };
            f.xa[i] = x;
            f.y[i] = y;
            f.o[i] = o;
            if k.hayati[i] {
                // Ry(β): x ← cβ·x − sβ·z, z ← sβ·x + cβ·z; y and o unchanged.
                let (cb, sb) = (k.cb[i], k.sb[i]);
                f.x[i] = combine(cb, x, -sb, z);
                f.z[i] = combine(sb, x, cb, z);
            } else {
                f.x[i] = x;
                f.z[i] = z;
            }
        }
        f
    }

    /// Frame `i`'s z axis and origin (`i = 0`: the base's).
    #[inline(always)]
    fn before(&self, i: usize) -> (V3<S>, V3<S>) {
        if i == 0 {
            let (zero, one) = (S::from(0.0), S::from(1.0));
            ([zero, zero, one], [zero; 3])
        } else {
            (self.z[i - 1], self.o[i - 1])
        }
    }

    /// The probe: `o_n + R_n·B`.
    #[inline(always)]
    fn probe(&self, b: &[S; 3]) -> V3<S> {
        let n = N - 1;
        let xy = combine(b[0], self.x[n], b[1], self.y[n]);
        let z = [
            b[2] * self.z[n][0],
            b[2] * self.z[n][1],
            b[2] * self.z[n][2],
        ];
        add(self.o[n], add(xy, z))
    }

    /// `[R | p]`.
    #[inline(always)]
    fn transform(&self, p: V3<S>) -> [[S; 4]; 3] {
        let (x, y, z) = (self.x[N - 1], self.y[N - 1], self.z[N - 1]);
        std::array::from_fn(|r| [x[r], y[r], z[r], p[r]])
    }

    /// Every parameter's column into `jac` (`R` = 3: the position's, 6:
    /// with the rotation rows `ω` below): `a, d|β, α, θ, B`.
    #[inline(always)]
    fn param_columns<const R: usize>(&self, k: &Consts<S, N>, p: V3<S>, jac: &mut [[S; R]]) {
        let zero = [S::from(0.0); 3];
        for i in 0..N {
            let (z, o) = self.before(i);
            let r = sub(p, self.o[i]);
            put(&mut jac[i], self.xa[i], zero);
            if k.hayati[i] {
                put(&mut jac[N + i], cross(self.y[i], r), self.y[i]);
            } else {
                put(&mut jac[N + i], z, zero);
            }
            put(&mut jac[2 * N + i], cross(self.xa[i], r), self.xa[i]);
            put(&mut jac[3 * N + i], cross(z, sub(p, o)), z);
        }
        let n = N - 1;
        for (c, axis) in [self.x[n], self.y[n], self.z[n]].into_iter().enumerate() {
            put(&mut jac[4 * N + c], axis, zero);
        }
    }

    /// Every joint's column into `jac`: `[z × (p − o); z]` turning,
    /// `[z; 0]` sliding.
    #[inline(always)]
    fn joint_columns<const R: usize>(&self, k: &Consts<S, N>, p: V3<S>, jac: &mut [[S; R]; N]) {
        let zero = [S::from(0.0); 3];
        for (i, col) in jac.iter_mut().enumerate() {
            let (z, o) = self.before(i);
            if k.prismatic[i] {
                put(col, z, zero);
            } else {
                put(col, cross(z, sub(p, o)), z);
            }
        }
    }
}

/// A column: the position rows `p`, and with 6 rows the rotation `w`.
#[inline(always)]
fn put<S: Scalar, const R: usize>(col: &mut [S; R], p: V3<S>, w: V3<S>) {
    col[..3].copy_from_slice(&p);
    if R == 6 {
        col[3..].copy_from_slice(&w);
    }
}

impl<const N: usize> Chain<N> for Generic {
    const PRISMATIC: Option<u16> = None;
    const EXTENDED: bool = true;

    #[inline(always)]
    fn position<S: Scalar>(k: &Consts<S, N>, cq: &[S; N], sq: &[S; N]) -> [S; 3] {
        // Right to left: v ← Rz(θ)·(Rx(α)·Ry(β)·v + (a, 0, d)).
        let mut v = k.b;
        for i in (0..N).rev() {
            if k.hayati[i] {
                let (cb, sb) = (k.cb[i], k.sb[i]);
                v = [cb * v[0] + sb * v[2], v[1], cb * v[2] - sb * v[0]];
            }
            let (c, s, d) = joint(k, i, cq, sq);
            let y = k.ca[i] * v[1] - k.sa[i] * v[2];
            let z = k.sa[i] * v[1] + k.ca[i] * v[2] + d;
            let x = v[0] + k.a[i];
            v = [c * x - s * y, s * x + c * y, z];
        }
        v
    }

    #[inline(always)]
    fn position_jacobian<S: Scalar>(
        k: &Consts<S, N>,
        cq: &[S; N],
        sq: &[S; N],
        jac: &mut [[S; 3]],
    ) -> [S; 3] {
        let f = Frames::new(k, cq, sq);
        let p = f.probe(&k.b);
        f.param_columns(k, p, jac);
        p
    }

    #[inline(always)]
    fn joint_jacobian<S: Scalar>(
        k: &Consts<S, N>,
        cq: &[S; N],
        sq: &[S; N],
        jac: &mut [[S; 3]; N],
    ) -> [S; 3] {
        let f = Frames::new(k, cq, sq);
        let p = f.probe(&k.b);
        f.joint_columns(k, p, jac);
        p
    }

    #[inline(always)]
    fn pose<S: Scalar>(k: &Consts<S, N>, cq: &[S; N], sq: &[S; N]) -> [[S; 4]; 3] {
        let f = Frames::new(k, cq, sq);
        f.transform(f.probe(&k.b))
    }

    #[inline(always)]
    fn pose_jacobian<S: Scalar>(
        k: &Consts<S, N>,
        cq: &[S; N],
        sq: &[S; N],
        jac: &mut [[S; 6]],
    ) -> [[S; 4]; 3] {
        let f = Frames::new(k, cq, sq);
        let p = f.probe(&k.b);
        f.param_columns(k, p, jac);
        f.transform(p)
    }

    #[inline(always)]
    fn joint_pose_jacobian<S: Scalar>(
        k: &Consts<S, N>,
        cq: &[S; N],
        sq: &[S; N],
        jac: &mut [[S; 6]; N],
    ) -> [[S; 4]; 3] {
        let f = Frames::new(k, cq, sq);
        let p = f.probe(&k.b);
        f.joint_columns(k, p, jac);
        f.transform(p)
    }
}
