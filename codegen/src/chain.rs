//! The D-H chain expanded symbolically into the three kernel outputs.
//!
//! Link `i`: `A_i = Rz(θ_i + q_i)·Tz(d_i)·Tx(a_i)·Rx(α_i)`, probe `B` in the last
//! frame. The *extended* chain ([`ChainSpec::hayati`]) appends `Ry(β_i)` to
//! every link, `A_i = Rz(θ_i + q_i)·Tz(d_i)·Tx(a_i)·Rx(α_i)·Ry(β_i)`: with
//! `β_i = 0` a D-H link, with `d_i = 0` the Hayati link (Hayati & Mirmirani
//! 1985) for a joint whose axis is nearly parallel to the previous one. One
//! extended chain serves every subset of Hayati joints: the caller sets β or d
//! per parameter set, and picks per joint whether the d-slot's column is
//! `∂p/∂d_i` or `∂p/∂β_i`. The joint angle's trig comes from the angle-addition formulas
//! `cos(q+θ) = cq·cθ − sq·sθ`, `sin(q+θ) = sq·cθ + cq·sθ`, so the per-pose code
//! has no trig calls.
//!
//! * Position: right to left, `v ← A_i·v` starting at `B` — three-vector
//!   updates, the cheapest way to the point alone.
//! * Jacobians: left to right through the frames (`R_i`, `o_i` in the base
//!   frame), then each column in closed form:
//!   `∂p/∂θ_i = z_{i−1} × (p − o_{i−1})`, `∂p/∂d_i = z_{i−1}`, `∂p/∂a_i = x_i`,
//!   `∂p/∂α_i = x_i × (p − o_i)`, `∂p/∂B = R_n`; and `∂p/∂q_i = ∂p/∂θ_i`.
//!   In the extended chain `x_i` in the `a` and `α` columns is the x axis
//!   before `Ry(β_i)`, and `∂p/∂β_i = y_i × (p − o_i)` (`Ry` turns about `y_i`,
//!   which it leaves unchanged, through `o_i`, which it does not move).
//!   Frame 0 is the identity, which the graph folds into the first link.

use crate::graph::{Graph, Id, Input};

/// What chain to generate a kernel for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChainSpec {
    /// Number of revolute joints.
    pub joints: usize,
    /// Whether a probe offset `B` follows the last frame (3 more parameters).
    pub probe: bool,
    /// The extended chain: every link ends in `Ry(β_i)`, and the d-slot's
    /// Jacobian column is chosen per joint (`∂p/∂d_i` or `∂p/∂β_i`).
    pub hayati: bool,
}

impl ChainSpec {
    /// Number of geometric parameters: `4n`, plus 3 with a probe.
    pub fn param_count(&self) -> usize {
        4 * self.joints + if self.probe { 3 } else { 0 }
    }
}

/// The kernel's outputs as nodes of one graph.
#[derive(Clone, Debug)]
pub struct KernelExprs {
    /// The chain this was built from.
    pub spec: ChainSpec,
    /// All expressions.
    pub graph: Graph,
    /// Probe position by the right-to-left product.
    pub position: [Id; 3],
    /// Probe position by the frames (what the Jacobian functions return).
    pub frame_position: [Id; 3],
    /// `∂p/∂parameter`, one column per parameter in the order
    /// `a1..an, d1..dn, α1..αn, θ1..θn[, Bx, By, Bz]`.
    pub param_jacobian: Vec<[Id; 3]>,
    /// `∂p/∂q_i`, one column per joint.
    pub joint_jacobian: Vec<[Id; 3]>,
    /// `∂p/∂β_i`, one column per joint (extended chain only, else empty):
    /// what replaces `param_jacobian`'s `d_i` column for a Hayati joint.
    pub beta_jacobian: Vec<[Id; 3]>,
}

type V3 = [Id; 3];

/// Vector helpers over the graph; each folds through [`Graph`].
struct Builder {
    g: Graph,
}

impl Builder {
    fn constant(&mut self, v: [f64; 3]) -> V3 {
        v.map(|x| self.g.constant(x))
    }

    fn add(&mut self, u: V3, v: V3) -> V3 {
        [0, 1, 2].map(|k| self.g.add(u[k], v[k]))
    }

    fn sub(&mut self, u: V3, v: V3) -> V3 {
        [0, 1, 2].map(|k| self.g.sub(u[k], v[k]))
    }

    fn scale(&mut self, s: Id, v: V3) -> V3 {
        v.map(|x| self.g.mul(s, x))
    }

    /// `s·u + t·v`.
    fn combine(&mut self, s: Id, u: V3, t: Id, v: V3) -> V3 {
        let su = self.scale(s, u);
        let tv = self.scale(t, v);
        self.add(su, tv)
    }

    fn cross(&mut self, u: V3, v: V3) -> V3 {
        let mut component = |i: usize, j: usize| {
            let l = self.g.mul(u[i], v[j]);
            let r = self.g.mul(u[j], v[i]);
            self.g.sub(l, r)
        };
        [component(1, 2), component(2, 0), component(0, 1)]
    }

    /// cos and sin of `q_i + θ_i` by angle addition.
    fn joint_trig(&mut self, i: usize) -> (Id, Id) {
        let cq = self.g.input(Input::CosQ(i));
        let sq = self.g.input(Input::SinQ(i));
        let ct = self.g.input(Input::CosTheta(i));
        let st = self.g.input(Input::SinTheta(i));
        let cc = self.g.mul(cq, ct);
        let ss = self.g.mul(sq, st);
        let sc = self.g.mul(sq, ct);
        let cs = self.g.mul(cq, st);
        (self.g.sub(cc, ss), self.g.add(sc, cs))
    }

    fn link(&mut self, i: usize, hayati: bool) -> Link {
        let (c, s) = self.joint_trig(i);
        let beta = hayati.then(|| {
            (
                self.g.input(Input::CosBeta(i)),
                self.g.input(Input::SinBeta(i)),
            )
        });
        Link {
            beta,
            c,
            s,
            ca: self.g.input(Input::CosAlpha(i)),
            sa: self.g.input(Input::SinAlpha(i)),
            a: self.g.input(Input::A(i)),
            d: self.g.input(Input::D(i)),
        }
    }

    fn probe(&mut self, spec: ChainSpec) -> V3 {
        if spec.probe {
            [0, 1, 2].map(|k| self.g.input(Input::Probe(k)))
        } else {
            self.constant([0.0; 3])
        }
    }
}

#[derive(Clone, Copy)]
struct Link {
    /// cos and sin of `β` (extended chain only).
    beta: Option<(Id, Id)>,
    c: Id,
    s: Id,
    ca: Id,
    sa: Id,
    a: Id,
    d: Id,
}

/// A frame in the base frame: axes and origin.
#[derive(Clone, Copy)]
struct Frame {
    /// The x axis before the link's `Ry(β)` (equal to `x` in a D-H link): the
    /// direction of `a` and the axis of `α`.
    xa: V3,
    x: V3,
    y: V3,
    z: V3,
    o: V3,
}

/// Expands `spec` into its kernel expressions.
///
/// ```
/// use aacmm_codegen::chain::{expand_chain, ChainSpec};
/// let k = expand_chain(ChainSpec { joints: 6, probe: true, hayati: false });
/// assert_eq!(k.param_jacobian.len(), 27);
/// assert_eq!(k.joint_jacobian.len(), 6);
/// ```
pub fn expand_chain(spec: ChainSpec) -> KernelExprs {
    let mut b = Builder { g: Graph::new() };
    let links: Vec<Link> = (0..spec.joints).map(|i| b.link(i, spec.hayati)).collect();
    let probe = b.probe(spec);

    // Right to left: v ← Rz(θ)·(Rx(α)·Ry(β)·v + (a, 0, d)).
    let mut v = probe;
    for l in links.iter().rev() {
        if let Some((cb, sb)) = l.beta {
            let x = {
                let p = b.g.mul(cb, v[0]);
                let q = b.g.mul(sb, v[2]);
                b.g.add(p, q)
            };
            let z = {
                let p = b.g.mul(cb, v[2]);
                let q = b.g.mul(sb, v[0]);
                b.g.sub(p, q)
            };
            v = [x, v[1], z];
        }
        let y = {
            let p = b.g.mul(l.ca, v[1]);
            let q = b.g.mul(l.sa, v[2]);
            b.g.sub(p, q)
        };
        let z = {
            let p = b.g.mul(l.sa, v[1]);
            let q = b.g.mul(l.ca, v[2]);
            b.g.add(p, q)
        };
        let x = b.g.add(v[0], l.a);
        let z = b.g.add(z, l.d);
        let x_rot = {
            let p = b.g.mul(l.c, x);
            let q = b.g.mul(l.s, y);
            b.g.sub(p, q)
        };
        let y_rot = {
            let p = b.g.mul(l.s, x);
            let q = b.g.mul(l.c, y);
            b.g.add(p, q)
        };
        v = [x_rot, y_rot, z];
    }
    let position = v;

    // Left to right: frames[i] is frame i (frames[0] the base).
    let mut frames = vec![Frame {
        xa: b.constant([1.0, 0.0, 0.0]),
        x: b.constant([1.0, 0.0, 0.0]),
        y: b.constant([0.0, 1.0, 0.0]),
        z: b.constant([0.0, 0.0, 1.0]),
        o: b.constant([0.0; 3]),
    }];
    for l in &links {
        let f = *frames.last().expect("base frame");
        let x = b.combine(l.c, f.x, l.s, f.y);
        let ns = b.g.neg(l.s);
        let u = b.combine(l.c, f.y, ns, f.x);
        let y = b.combine(l.ca, u, l.sa, f.z);
        let nsa = b.g.neg(l.sa);
        let z = b.combine(l.ca, f.z, nsa, u);
        let step = b.combine(l.d, f.z, l.a, x);
        let o = b.add(f.o, step);
        // Ry(β): x ← cβ·x − sβ·z, z ← sβ·x + cβ·z; y and o unchanged.
        let (xb, zb) = match l.beta {
            Some((cb, sb)) => {
                let nsb = b.g.neg(sb);
                (b.combine(cb, x, nsb, z), b.combine(sb, x, cb, z))
            }
            None => (x, z),
        };
        frames.push(Frame {
            xa: x,
            x: xb,
            y,
            z: zb,
            o,
        });
    }
    let last = *frames.last().expect("base frame");
    let rb = {
        let xy = b.combine(probe[0], last.x, probe[1], last.y);
        let z = b.scale(probe[2], last.z);
        b.add(xy, z)
    };
    let p = b.add(last.o, rb);

    let n = spec.joints;
    let col_theta: Vec<V3> = (0..n)
        .map(|i| {
            let r = b.sub(p, frames[i].o);
            b.cross(frames[i].z, r)
        })
        .collect();
    let col_alpha: Vec<V3> = (0..n)
        .map(|i| {
            let r = b.sub(p, frames[i + 1].o);
            b.cross(frames[i + 1].xa, r)
        })
        .collect();
    let beta_jacobian: Vec<V3> = if spec.hayati {
        (0..n)
            .map(|i| {
                let r = b.sub(p, frames[i + 1].o);
                b.cross(frames[i + 1].y, r)
            })
            .collect()
    } else {
        Vec::new()
    };
    let mut param_jacobian: Vec<V3> = Vec::with_capacity(spec.param_count());
    param_jacobian.extend((0..n).map(|i| frames[i + 1].xa));
    param_jacobian.extend((0..n).map(|i| frames[i].z));
    param_jacobian.extend(col_alpha);
    param_jacobian.extend(col_theta.iter().copied());
    if spec.probe {
        param_jacobian.extend([last.x, last.y, last.z]);
    }

    KernelExprs {
        spec,
        graph: b.g,
        position,
        frame_position: p,
        param_jacobian,
        joint_jacobian: col_theta,
        beta_jacobian,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values of the leaves for a parameter set and a pose.
    #[derive(Clone)]
    struct Point {
        a: Vec<f64>,
        d: Vec<f64>,
        alpha: Vec<f64>,
        theta: Vec<f64>,
        /// Hayati rotations (zero for a D-H chain).
        beta: Vec<f64>,
        b: [f64; 3],
        q: Vec<f64>,
    }

    impl Point {
        /// `∂p/∂x` of column `col` of an `n`-joint chain (a, d, α, θ, the
        /// probe, then β) by central differences, step 1e-6.
        fn central_difference(&self, n: usize, col: usize) -> [f64; 3] {
            let h = 1e-6;
            let shifted = |delta: f64| {
                let mut p = self.clone();
                let (block, j) = (col / n, col % n);
                match block {
                    0 => p.a[j] += delta,
                    1 => p.d[j] += delta,
                    2 => p.alpha[j] += delta,
                    3 => p.theta[j] += delta,
                    _ if col < 4 * n + 3 => p.b[col - 4 * n] += delta,
                    _ => p.beta[col - 4 * n - 3] += delta,
                }
                p.position()
            };
            let (plus, minus) = (shifted(h), shifted(-h));
            [0, 1, 2].map(|r| (plus[r] - minus[r]) / (2.0 * h))
        }

        fn sample(n: usize, seed: u64) -> Point {
            // A small LCG keeps this crate free of dependencies.
            let mut s = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
            let mut next = move |scale: f64| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) * scale
            };
            Point {
                a: (0..n).map(|_| next(300.0)).collect(),
                d: (0..n).map(|_| next(300.0)).collect(),
                alpha: (0..n).map(|_| next(3.0)).collect(),
                theta: (0..n).map(|_| next(3.0)).collect(),
                beta: vec![0.0; n],
                b: [next(100.0), next(100.0), next(100.0)],
                q: (0..n).map(|_| next(3.0)).collect(),
            }
        }

        /// A sample with every link's β random too (the extended chain).
        fn sample_extended(n: usize, seed: u64) -> Point {
            let mut p = Point::sample(n, seed);
            let other = Point::sample(n, seed ^ 0x5eed);
            p.beta = other.theta;
            p
        }

        fn leaf(&self, i: Input) -> f64 {
            match i {
                Input::CosQ(j) => self.q[j].cos(),
                Input::SinQ(j) => self.q[j].sin(),
                Input::CosTheta(j) => self.theta[j].cos(),
                Input::SinTheta(j) => self.theta[j].sin(),
                Input::CosAlpha(j) => self.alpha[j].cos(),
                Input::SinAlpha(j) => self.alpha[j].sin(),
                Input::A(j) => self.a[j],
                Input::D(j) => self.d[j],
                Input::CosBeta(j) => self.beta[j].cos(),
                Input::SinBeta(j) => self.beta[j].sin(),
                Input::Probe(k) => self.b[k],
            }
        }

        /// The textbook 4×4 product, written independently of the generator.
        fn position(&self) -> [f64; 3] {
            let mut t = [[0.0f64; 4]; 4];
            for (i, row) in t.iter_mut().enumerate() {
                row[i] = 1.0;
            }
            for j in 0..self.q.len() {
                let (st, ct) = (self.q[j] + self.theta[j]).sin_cos();
                let (sa, ca) = self.alpha[j].sin_cos();
                let (sb, cb) = self.beta[j].sin_cos();
                let a = [
                    [ct, -ca * st, sa * st, self.a[j] * ct],
                    [st, ca * ct, -sa * ct, self.a[j] * st],
                    [0.0, sa, ca, self.d[j]],
                    [0.0, 0.0, 0.0, 1.0],
                ];
                let ry = [
                    [cb, 0.0, sb, 0.0],
                    [0.0, 1.0, 0.0, 0.0],
                    [-sb, 0.0, cb, 0.0],
                    [0.0, 0.0, 0.0, 1.0],
                ];
                for m in [a, ry] {
                    let mut prod = [[0.0; 4]; 4];
                    for r in 0..4 {
                        for c in 0..4 {
                            prod[r][c] = (0..4).map(|k| t[r][k] * m[k][c]).sum();
                        }
                    }
                    t = prod;
                }
            }
            let h = [self.b[0], self.b[1], self.b[2], 1.0];
            [0, 1, 2].map(|r| (0..4).map(|k| t[r][k] * h[k]).sum())
        }

        fn eval(&self, k: &KernelExprs, out: &[Id; 3]) -> [f64; 3] {
            let v = k.graph.eval(|i| self.leaf(i));
            out.map(|id| v[id.index()])
        }
    }

    fn close(x: [f64; 3], y: [f64; 3], tol: f64) -> bool {
        (0..3).all(|k| (x[k] - y[k]).abs() <= tol)
    }

    #[test]
    fn both_position_paths_match_the_matrix_product() {
        for n in 1..=7 {
            let k = expand_chain(ChainSpec {
                joints: n,
                probe: true,
                hayati: false,
            });
            for seed in 0..50 {
                let pt = Point::sample(n, seed);
                let want = pt.position();
                assert!(close(pt.eval(&k, &k.position), want, 1e-9), "n={n}");
                assert!(close(pt.eval(&k, &k.frame_position), want, 1e-9), "n={n}");
            }
        }
    }

    #[test]
    fn jacobian_columns_match_central_differences() {
        let n = 6;
        let k = expand_chain(ChainSpec {
            joints: n,
            probe: true,
            hayati: false,
        });
        for seed in 0..20 {
            let pt = Point::sample(n, seed);
            let v = k.graph.eval(|i| pt.leaf(i));
            for (col, ids) in k.param_jacobian.iter().enumerate() {
                let fd = pt.central_difference(n, col);
                let got = ids.map(|id| v[id.index()]);
                assert!(close(got, fd, 1e-5), "column {col}: {got:?} vs {fd:?}");
            }
            for (j, ids) in k.joint_jacobian.iter().enumerate() {
                let got = ids.map(|id| v[id.index()]);
                let want = k.param_jacobian[3 * n + j].map(|id| v[id.index()]);
                assert_eq!(got, want, "∂p/∂q equals ∂p/∂θ");
            }
        }
    }

    #[test]
    fn extended_chain_matches_the_matrix_product_and_differences() {
        for n in 1..=7 {
            let k = expand_chain(ChainSpec {
                joints: n,
                probe: true,
                hayati: true,
            });
            assert_eq!(k.beta_jacobian.len(), n);
            for seed in 0..20 {
                let pt = Point::sample_extended(n, seed);
                let want = pt.position();
                assert!(close(pt.eval(&k, &k.position), want, 1e-9), "n={n}");
                assert!(close(pt.eval(&k, &k.frame_position), want, 1e-9), "n={n}");
                let v = k.graph.eval(|i| pt.leaf(i));
                // Every column, β's appended after the probe's.
                let cols = k.param_jacobian.iter().chain(&k.beta_jacobian);
                for (col, ids) in cols.enumerate() {
                    let fd = pt.central_difference(n, col);
                    let got = ids.map(|id| v[id.index()]);
                    assert!(
                        close(got, fd, 1e-5),
                        "n={n} column {col}: {got:?} vs {fd:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn first_frame_is_folded() {
        let k = expand_chain(ChainSpec {
            joints: 6,
            probe: true,
            hayati: false,
        });
        // ∂p/∂d1 is the base z axis: constants, no arithmetic.
        let d1 = k.param_jacobian[6];
        assert_eq!(
            d1.map(|id| k.graph.as_const(id)),
            [Some(0.0), Some(0.0), Some(1.0)]
        );
        // ∂p/∂θ1 = z0 × p has a structural zero z component.
        assert_eq!(k.graph.as_const(k.param_jacobian[18][2]), Some(0.0));
    }

    #[test]
    fn a_chain_without_probe_has_4n_columns() {
        let k = expand_chain(ChainSpec {
            joints: 3,
            probe: false,
            hayati: false,
        });
        assert_eq!(k.param_jacobian.len(), 12);
        let pt = Point {
            b: [0.0; 3],
            ..Point::sample(3, 7)
        };
        assert!(close(pt.eval(&k, &k.position), pt.position(), 1e-9));
    }
}
