//! The D-H chain expanded symbolically into the kernel outputs: the probe's
//! position, the tool's full pose, and their Jacobians.
//!
//! Link `i` of a revolute joint: `A_i = Rz(θ_i + q_i)·Tz(d_i)·Tx(a_i)·Rx(α_i)`;
//! of a prismatic joint: `A_i = Rz(θ_i)·Tz(d_i + q_i)·Tx(a_i)·Rx(α_i)` (the
//! reading, mm, slides along the previous z axis, so θ's cos and sin are
//! per-parameter-set constants and the per-pose code gets the reading
//! itself, not its trig). Probe `B` in the last frame. The *extended* chain ([`ChainSpec::hayati`]) appends `Ry(β_i)` to
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
//!   `∂p/∂α_i = x_i × (p − o_i)`, `∂p/∂B = R_n`; and `∂p/∂q_i = ∂p/∂θ_i`
//!   for a revolute joint, `∂p/∂d_i` for a prismatic one.
//!   In the extended chain `x_i` in the `a` and `α` columns is the x axis
//!   before `Ry(β_i)`, and `∂p/∂β_i = y_i × (p − o_i)` (`Ry` turns about `y_i`,
//!   which it leaves unchanged, through `o_i`, which it does not move).
//!   Frame 0 is the identity, which the graph folds into the first link.
//! * The tool frame: the last frame's axes `R_n` (after its `Ry(β_n)`) with
//!   its origin at the probe, `p = o_n + R_n·B`. Its 6-row Jacobian stacks
//!   the position rows above small-rotation rows `ω` with `δR = [ω]× R` in
//!   the base frame: `θ_i → z_{i−1}`, `α_i → x_i` (before `Ry(β_i)`),
//!   `β_i → y_i`, and `a`, `d`, `B → 0`; per joint `[z × (p − o); z]` for a
//!   revolute one and `[z; 0]` for a prismatic one (`z = z_{i−1}`,
//!   `o = o_{i−1}`).

use crate::graph::{Graph, Id, Input};

/// What chain to generate a kernel for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChainSpec {
    /// Number of joints.
    pub joints: usize,
    /// Which joints are prismatic: bit `i` for joint `i` (base first), the
    /// rest revolute; 0 for an all-revolute chain.
    pub prismatic: u16,
    /// Whether a probe offset `B` follows the last frame (3 more parameters).
    pub probe: bool,
    /// The extended chain: every link ends in `Ry(β_i)`, and the d-slot's
    /// Jacobian column is chosen per joint (`∂p/∂d_i` or `∂p/∂β_i`).
    pub hayati: bool,
}

impl ChainSpec {
    /// An all-revolute D-H chain of `joints` joints with a probe.
    ///
    /// ```
    /// let s = aacmm_codegen::ChainSpec::revolute(6);
    /// assert_eq!((s.joints, s.prismatic, s.probe, s.hayati), (6, 0, true, false));
    /// ```
    pub fn revolute(joints: usize) -> ChainSpec {
        ChainSpec {
            joints,
            prismatic: 0,
            probe: true,
            hayati: false,
        }
    }

    /// A D-H chain with a probe of the shape `shape`, one letter per joint
    /// base first, `R` revolute and `P` prismatic (see [`parse_shape`]).
    ///
    /// ```
    /// let s = aacmm_codegen::ChainSpec::of_shape("RRPR").unwrap();
    /// assert_eq!((s.joints, s.prismatic), (4, 0b0100));
    /// assert_eq!(s.shape(), "RRPR");
    /// ```
    pub fn of_shape(shape: &str) -> Result<ChainSpec, String> {
        let (joints, prismatic) = parse_shape(shape)?;
        Ok(ChainSpec {
            prismatic,
            ..ChainSpec::revolute(joints)
        })
    }

    /// Number of geometric parameters: `4n`, plus 3 with a probe.
    pub fn param_count(&self) -> usize {
        4 * self.joints + if self.probe { 3 } else { 0 }
    }

    /// Whether joint `i` (0-based) is prismatic.
    pub fn is_prismatic(&self, i: usize) -> bool {
        i < 16 && self.prismatic & (1 << i) != 0
    }

    /// The shape as letters, base first: `R` revolute, `P` prismatic.
    pub fn shape(&self) -> String {
        (0..self.joints)
            .map(|i| if self.is_prismatic(i) { 'P' } else { 'R' })
            .collect()
    }
}

/// Most joints a chain may have; most serial arms have 6 or 7, and the expression
/// size grows with the square of the count.
pub const MAX_JOINTS: usize = 12;

/// A shape's letters (`"PRRRRRRR"`: base first, `R` revolute, `P`
/// prismatic; 1 to [`MAX_JOINTS`] of them) as the joint count and the
/// prismatic joints' bits (bit `i` for joint `i`).
///
/// ```
/// use aacmm_codegen::chain::parse_shape;
/// assert_eq!(parse_shape("PRR"), Ok((3, 0b001)));
/// assert!(parse_shape("RXR").unwrap_err().contains("`X` at joint 2"));
/// assert!(parse_shape("").is_err());
/// ```
pub fn parse_shape(shape: &str) -> Result<(usize, u16), String> {
    let mut prismatic = 0u16;
    let mut joints = 0;
    for (i, c) in shape.chars().enumerate() {
        match c {
            'R' => {}
            'P' if i < MAX_JOINTS => prismatic |= 1 << i,
            'P' => {}
            other => {
                return Err(format!(
                    "`{}` at joint {}: a shape has one letter per joint, `R` (revolute) or \
                     `P` (prismatic)",
                    other.escape_debug(),
                    i + 1
                ));
            }
        }
        joints = i + 1;
    }
    if !(1..=MAX_JOINTS).contains(&joints) {
        return Err(format!(
            "a chain has 1 to {MAX_JOINTS} joints, this shape has {joints}"
        ));
    }
    Ok((joints, prismatic))
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
    /// The tool frame's rotation (the last frame's axes as columns),
    /// row-major: `rotation[r][c]` is row `r` of axis `c`.
    pub rotation: [[Id; 3]; 3],
    /// `∂p/∂parameter`, one column per parameter in the order
    /// `a1..an, d1..dn, α1..αn, θ1..θn[, Bx, By, Bz]`.
    pub param_jacobian: Vec<[Id; 3]>,
    /// `∂p/∂q_i`, one column per joint.
    pub joint_jacobian: Vec<[Id; 3]>,
    /// `∂p/∂β_i`, one column per joint (extended chain only, else empty):
    /// what replaces `param_jacobian`'s `d_i` column for a Hayati joint.
    pub beta_jacobian: Vec<[Id; 3]>,
    /// The tool pose's Jacobian, one 6-row column (position, then the
    /// small rotation `ω`) per parameter, in `param_jacobian`'s order.
    pub pose_jacobian: Vec<[Id; 6]>,
    /// The pose columns of `β_i` (extended chain only, else empty).
    pub beta_pose_jacobian: Vec<[Id; 6]>,
    /// The pose's 6-row column per joint.
    pub joint_pose_jacobian: Vec<[Id; 6]>,
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

    /// The link of joint `i`. A prismatic joint's angle is its constant
    /// θ, and its reading adds to `d`.
    fn link(&mut self, i: usize, hayati: bool, prismatic: bool) -> Link {
        let (c, s) = if prismatic {
            (
                self.g.input(Input::CosTheta(i)),
                self.g.input(Input::SinTheta(i)),
            )
        } else {
            self.joint_trig(i)
        };
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
            d: self.slide(i, prismatic),
        }
    }

    /// The link's offset along the previous z axis: `d`, plus the reading
    /// of a prismatic joint.
    fn slide(&mut self, i: usize, prismatic: bool) -> Id {
        let d = self.g.input(Input::D(i));
        if prismatic {
            let q = self.g.input(Input::Q(i));
            self.g.add(d, q)
        } else {
            d
        }
    }

    /// A 6-row column: position rows `p` above rotation rows `w`.
    fn six(p: V3, w: V3) -> [Id; 6] {
        [p[0], p[1], p[2], w[0], w[1], w[2]]
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
    /// `d`, plus the reading for a prismatic joint.
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
/// let k = expand_chain(ChainSpec::revolute(6));
/// assert_eq!(k.param_jacobian.len(), 27);
/// assert_eq!(k.joint_jacobian.len(), 6);
/// assert_eq!(k.pose_jacobian.len(), 27);
/// ```
pub fn expand_chain(spec: ChainSpec) -> KernelExprs {
    let mut b = Builder { g: Graph::new() };
    let links: Vec<Link> = (0..spec.joints)
        .map(|i| b.link(i, spec.hayati, spec.is_prismatic(i)))
        .collect();
    let probe = b.probe(spec);
    let position = right_to_left(&mut b, &links, probe);
    let frames = frames(&mut b, &links);
    let last = *frames.last().expect("base frame");
    let p = {
        let xy = b.combine(probe[0], last.x, probe[1], last.y);
        let z = b.scale(probe[2], last.z);
        let rb = b.add(xy, z);
        b.add(last.o, rb)
    };
    let cols = Columns::new(&mut b, spec, &frames, p);
    let mut param_jacobian: Vec<V3> = Vec::with_capacity(spec.param_count());
    let n = spec.joints;
    param_jacobian.extend((0..n).map(|i| frames[i + 1].xa));
    param_jacobian.extend((0..n).map(|i| frames[i].z));
    param_jacobian.extend(cols.alpha.iter().copied());
    param_jacobian.extend(cols.theta.iter().copied());
    if spec.probe {
        param_jacobian.extend([last.x, last.y, last.z]);
    }
    let joint_jacobian = (0..n)
        .map(|i| {
            if spec.is_prismatic(i) {
                frames[i].z
            } else {
                cols.theta[i]
            }
        })
        .collect();
    let pose = pose_columns(&mut b, spec, &frames, &cols);
    KernelExprs {
        spec,
        rotation: [0, 1, 2].map(|r| [last.x[r], last.y[r], last.z[r]]),
        graph: b.g,
        position,
        frame_position: p,
        param_jacobian,
        joint_jacobian,
        beta_jacobian: cols.beta,
        pose_jacobian: pose.params,
        beta_pose_jacobian: pose.beta,
        joint_pose_jacobian: pose.joints,
    }
}

/// The probe's position right to left: `v ← Rz(θ)·(Rx(α)·Ry(β)·v + (a, 0, d))`
/// from `v = B`, three-vector updates only.
fn right_to_left(b: &mut Builder, links: &[Link], probe: V3) -> V3 {
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
    v
}

/// The frames left to right: `frames[i]` is frame `i` in the base frame
/// (`frames[0]` the base itself, constants the graph folds away).
fn frames(b: &mut Builder, links: &[Link]) -> Vec<Frame> {
    let mut frames = vec![Frame {
        xa: b.constant([1.0, 0.0, 0.0]),
        x: b.constant([1.0, 0.0, 0.0]),
        y: b.constant([0.0, 1.0, 0.0]),
        z: b.constant([0.0, 0.0, 1.0]),
        o: b.constant([0.0; 3]),
    }];
    for l in links {
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
    frames
}

/// The position columns that need a cross product, per joint.
struct Columns {
    /// `∂p/∂θ_i = z_{i−1} × (p − o_{i−1})`.
    theta: Vec<V3>,
    /// `∂p/∂α_i = x_i × (p − o_i)` (`x_i` before `Ry(β_i)`).
    alpha: Vec<V3>,
    /// `∂p/∂β_i = y_i × (p − o_i)` (extended chain only, else empty).
    beta: Vec<V3>,
}

impl Columns {
    fn new(b: &mut Builder, spec: ChainSpec, frames: &[Frame], p: V3) -> Columns {
        let n = spec.joints;
        let theta = (0..n)
            .map(|i| {
                let r = b.sub(p, frames[i].o);
                b.cross(frames[i].z, r)
            })
            .collect();
        let alpha = (0..n)
            .map(|i| {
                let r = b.sub(p, frames[i + 1].o);
                b.cross(frames[i + 1].xa, r)
            })
            .collect();
        let beta = if spec.hayati {
            (0..n)
                .map(|i| {
                    let r = b.sub(p, frames[i + 1].o);
                    b.cross(frames[i + 1].y, r)
                })
                .collect()
        } else {
            Vec::new()
        };
        Columns { theta, alpha, beta }
    }
}

/// The tool pose's 6-row columns.
struct PoseColumns {
    params: Vec<[Id; 6]>,
    beta: Vec<[Id; 6]>,
    joints: Vec<[Id; 6]>,
}

/// The pose columns from the position columns: a translation turns
/// nothing (`ω = 0`), a rotation about an axis turns the tool about it.
fn pose_columns(b: &mut Builder, spec: ChainSpec, frames: &[Frame], cols: &Columns) -> PoseColumns {
    let n = spec.joints;
    let zero = b.constant([0.0; 3]);
    let last = frames[n];
    let mut params = Vec::with_capacity(spec.param_count());
    params.extend((0..n).map(|i| Builder::six(frames[i + 1].xa, zero)));
    params.extend((0..n).map(|i| Builder::six(frames[i].z, zero)));
    params.extend((0..n).map(|i| Builder::six(cols.alpha[i], frames[i + 1].xa)));
    params.extend((0..n).map(|i| Builder::six(cols.theta[i], frames[i].z)));
    if spec.probe {
        params.extend([last.x, last.y, last.z].map(|axis| Builder::six(axis, zero)));
    }
    let beta = (cols.beta.iter().enumerate())
        .map(|(i, &col)| Builder::six(col, frames[i + 1].y))
        .collect();
    let joints = (0..n)
        .map(|i| {
            if spec.is_prismatic(i) {
                Builder::six(frames[i].z, zero)
            } else {
                Builder::six(cols.theta[i], frames[i].z)
            }
        })
        .collect();
    PoseColumns {
        params,
        beta,
        joints,
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
        /// Which joints slide.
        prismatic: Vec<bool>,
    }

    /// A 4×4 homogeneous transform.
    type T4 = [[f64; 4]; 4];

    fn product(x: &T4, y: &T4) -> T4 {
        let mut out = [[0.0; 4]; 4];
        for r in 0..4 {
            for c in 0..4 {
                out[r][c] = (0..4).map(|k| x[r][k] * y[k][c]).sum();
            }
        }
        out
    }

    /// `(R(+h) − R(−h))/(2h)·Rᵀ`'s axial vector: the small rotation `ω`
    /// with `δR = [ω]× R`.
    fn omega(plus: &T4, minus: &T4, at: &T4, h: f64) -> [f64; 3] {
        let mut m = [[0.0; 3]; 3];
        for r in 0..3 {
            for c in 0..3 {
                m[r][c] = (0..3)
                    .map(|k| (plus[r][k] - minus[r][k]) / (2.0 * h) * at[c][k])
                    .sum();
            }
        }
        [
            (m[2][1] - m[1][2]) / 2.0,
            (m[0][2] - m[2][0]) / 2.0,
            (m[1][0] - m[0][1]) / 2.0,
        ]
    }

    impl Point {
        /// The tool pose's 6-row column of `∂/∂x` for column `col` of an
        /// `n`-joint chain (a, d, α, θ, the probe, then β), or of joint
        /// `col − 5n − 3` past those, by central differences, step 1e-6.
        fn central_difference(&self, n: usize, col: usize) -> [f64; 6] {
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
                    _ if col < 5 * n + 3 => p.beta[col - 4 * n - 3] += delta,
                    _ => p.q[col - 5 * n - 3] += delta,
                }
                p.tool()
            };
            let (plus, minus) = (shifted(h), shifted(-h));
            let w = omega(&plus, &minus, &self.tool(), h);
            let dp = [0, 1, 2].map(|r| (plus[r][3] - minus[r][3]) / (2.0 * h));
            [dp[0], dp[1], dp[2], w[0], w[1], w[2]]
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
                prismatic: vec![false; n],
            }
        }

        /// A sample with every link's β random too (the extended chain).
        fn sample_extended(n: usize, seed: u64) -> Point {
            let mut p = Point::sample(n, seed);
            let other = Point::sample(n, seed ^ 0x5eed);
            p.beta = other.theta;
            p
        }

        /// A sample of the chain `spec` (prismatic readings over ±300 mm).
        fn sample_of(spec: ChainSpec, seed: u64) -> Point {
            let n = spec.joints;
            let mut p = if spec.hayati {
                Point::sample_extended(n, seed)
            } else {
                Point::sample(n, seed)
            };
            p.prismatic = (0..n).map(|i| spec.is_prismatic(i)).collect();
            for (q, &slides) in p.q.iter_mut().zip(&p.prismatic) {
                if slides {
                    *q *= 100.0;
                }
            }
            p
        }

        fn leaf(&self, i: Input) -> f64 {
            match i {
                Input::CosQ(j) => self.q[j].cos(),
                Input::SinQ(j) => self.q[j].sin(),
                Input::Q(j) => self.q[j],
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

        /// The textbook product of 4×4 link matrices and the probe's
        /// translation, written independently of the generator: the tool
        /// frame.
        fn tool(&self) -> T4 {
            let mut t = [[0.0f64; 4]; 4];
            for (i, row) in t.iter_mut().enumerate() {
                row[i] = 1.0;
            }
            for j in 0..self.q.len() {
                let (angle, d) = if self.prismatic[j] {
                    (self.theta[j], self.d[j] + self.q[j])
                } else {
                    (self.q[j] + self.theta[j], self.d[j])
                };
                let (st, ct) = angle.sin_cos();
                let (sa, ca) = self.alpha[j].sin_cos();
                let (sb, cb) = self.beta[j].sin_cos();
                let a = [
                    [ct, -ca * st, sa * st, self.a[j] * ct],
                    [st, ca * ct, -sa * ct, self.a[j] * st],
                    [0.0, sa, ca, d],
                    [0.0, 0.0, 0.0, 1.0],
                ];
                let ry = [
                    [cb, 0.0, sb, 0.0],
                    [0.0, 1.0, 0.0, 0.0],
                    [-sb, 0.0, cb, 0.0],
                    [0.0, 0.0, 0.0, 1.0],
                ];
                t = product(&product(&t, &a), &ry);
            }
            let probe = [
                [1.0, 0.0, 0.0, self.b[0]],
                [0.0, 1.0, 0.0, self.b[1]],
                [0.0, 0.0, 1.0, self.b[2]],
                [0.0, 0.0, 0.0, 1.0],
            ];
            product(&t, &probe)
        }

        fn position(&self) -> [f64; 3] {
            let t = self.tool();
            [t[0][3], t[1][3], t[2][3]]
        }

        fn eval(&self, k: &KernelExprs, out: &[Id; 3]) -> [f64; 3] {
            let v = k.graph.eval(|i| self.leaf(i));
            out.map(|id| v[id.index()])
        }
    }

    fn close<const R: usize>(x: [f64; R], y: [f64; R], tol: f64) -> bool {
        (0..R).all(|k| (x[k] - y[k]).abs() <= tol)
    }

    /// Mixed chains of every length: the prismatic joints at the base, in
    /// the middle, at the end, everywhere.
    fn mixed_shapes() -> Vec<&'static str> {
        vec![
            "P",
            "R",
            "PR",
            "RP",
            "RRPR",
            "PRRRRRR",
            "PRRRRRRR",
            "RRPRPR",
            "PPP",
            "RPRPRPRPRPRP",
        ]
    }

    #[test]
    fn both_position_paths_match_the_matrix_product() {
        for n in 1..=7 {
            let k = expand_chain(ChainSpec::revolute(n));
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
        let k = expand_chain(ChainSpec::revolute(n));
        for seed in 0..20 {
            let pt = Point::sample(n, seed);
            let v = k.graph.eval(|i| pt.leaf(i));
            for (col, ids) in k.param_jacobian.iter().enumerate() {
                let fd = pt.central_difference(n, col);
                let got = ids.map(|id| v[id.index()]);
                assert!(
                    close(got, [fd[0], fd[1], fd[2]], 1e-5),
                    "column {col}: {got:?} vs {fd:?}"
                );
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
                hayati: true,
                ..ChainSpec::revolute(n)
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
                        close(got, [fd[0], fd[1], fd[2]], 1e-5),
                        "n={n} column {col}: {got:?} vs {fd:?}"
                    );
                }
            }
        }
    }

    /// Mixed revolute/prismatic chains, D-H and extended: both position
    /// paths and the rotation against the 4×4 product, and every column of
    /// every Jacobian (parameters, β, joints; 3-row and 6-row, both row
    /// blocks) against central differences of that product.
    #[test]
    fn mixed_chains_match_the_matrix_product_and_differences() {
        for shape in mixed_shapes() {
            for hayati in [false, true] {
                let spec = ChainSpec {
                    hayati,
                    ..ChainSpec::of_shape(shape).unwrap()
                };
                let k = expand_chain(spec);
                for seed in 0..10 {
                    check_pose_outputs(&k, &Point::sample_of(spec, seed), shape);
                }
            }
        }
    }

    fn check_pose_outputs(k: &KernelExprs, pt: &Point, shape: &str) {
        let n = k.spec.joints;
        let tool = pt.tool();
        let v = k.graph.eval(|i| pt.leaf(i));
        let at = |ids: &[Id; 6]| ids.map(|id| v[id.index()]);
        assert!(
            close(pt.eval(k, &k.position), pt.position(), 1e-8),
            "{shape}"
        );
        assert!(close(pt.eval(k, &k.frame_position), pt.position(), 1e-8));
        for (ids, t) in k.rotation.iter().zip(&tool) {
            let row = ids.map(|id| v[id.index()]);
            assert!(close(row, [t[0], t[1], t[2]], 1e-12));
        }
        let params = k.pose_jacobian.iter().chain(&k.beta_pose_jacobian);
        let joints = k.joint_pose_jacobian.iter();
        let columns = params.chain(joints).enumerate().map(|(c, ids)| {
            // β's columns sit past the probe's, the joints' past β's.
            let col = if k.spec.hayati || c < 4 * n + 3 {
                c
            } else {
                c + n
            };
            (col, at(ids))
        });
        for (col, got) in columns {
            let fd = pt.central_difference(n, col);
            // Readings of a prismatic joint are hundreds of mm: a looser
            // absolute tolerance for the differences' rounding.
            assert!(
                close(got, fd, 1e-4),
                "{shape} column {col}: {got:?} vs {fd:?}"
            );
        }
        // The 3-row functions are the 6-row ones' position rows.
        let three = |cols: &[[Id; 3]], six: &[[Id; 6]]| {
            for (c3, c6) in cols.iter().zip(six) {
                let (x, y) = (c3.map(|id| v[id.index()]), at(c6));
                assert_eq!(x, [y[0], y[1], y[2]], "{shape}");
            }
        };
        three(&k.param_jacobian, &k.pose_jacobian);
        three(&k.beta_jacobian, &k.beta_pose_jacobian);
        three(&k.joint_jacobian, &k.joint_pose_jacobian);
    }

    #[test]
    fn a_prismatic_joint_has_no_reading_trig() {
        let k = expand_chain(ChainSpec::of_shape("PRP").unwrap());
        let live = k.graph.reachable(
            &(k.pose_jacobian.iter().flatten())
                .chain(&k.position)
                .copied()
                .collect::<Vec<_>>(),
        );
        let inputs: Vec<Input> = live
            .iter()
            .filter_map(|&id| match k.graph.node(id) {
                crate::graph::Node::Input(i) => Some(i),
                _ => None,
            })
            .collect();
        for j in [0, 2] {
            assert!(inputs.contains(&Input::Q(j)));
            assert!(!inputs.contains(&Input::CosQ(j)) && !inputs.contains(&Input::SinQ(j)));
        }
        assert!(inputs.contains(&Input::CosQ(1)) && !inputs.contains(&Input::Q(1)));
        // ∂p/∂q1 of a slide along the base z axis: constants.
        assert_eq!(
            k.joint_jacobian[0].map(|id| k.graph.as_const(id)),
            [Some(0.0), Some(0.0), Some(1.0)]
        );
    }

    #[test]
    fn shapes_parse_and_refuse() {
        assert_eq!(parse_shape("RRPR"), Ok((4, 0b0100)));
        assert_eq!(parse_shape("PRRRRRRR"), Ok((8, 1)));
        assert!(parse_shape(&"R".repeat(13)).unwrap_err().contains("has 13"));
        assert!(parse_shape("rr").unwrap_err().contains("`r` at joint 1"));
        assert_eq!(ChainSpec::of_shape("RPP").unwrap().shape(), "RPP");
    }

    #[test]
    fn first_frame_is_folded() {
        let k = expand_chain(ChainSpec::revolute(6));
        // ∂p/∂d1 is the base z axis: constants, no arithmetic.
        let d1 = k.param_jacobian[6];
        assert_eq!(
            d1.map(|id| k.graph.as_const(id)),
            [Some(0.0), Some(0.0), Some(1.0)]
        );
        // ∂p/∂θ1 = z0 × p has a structural zero z component.
        assert_eq!(k.graph.as_const(k.param_jacobian[18][2]), Some(0.0));
        // θ1 turns the tool about the base z axis.
        let w = &k.pose_jacobian[18][3..];
        assert_eq!(
            [w[0], w[1], w[2]].map(|id| k.graph.as_const(id)),
            [Some(0.0), Some(0.0), Some(1.0)]
        );
    }

    #[test]
    fn a_chain_without_probe_has_4n_columns() {
        let k = expand_chain(ChainSpec {
            probe: false,
            ..ChainSpec::revolute(3)
        });
        assert_eq!(k.param_jacobian.len(), 12);
        assert_eq!(k.pose_jacobian.len(), 12);
        let pt = Point {
            b: [0.0; 3],
            ..Point::sample(3, 7)
        };
        assert!(close(pt.eval(&k, &k.position), pt.position(), 1e-9));
    }
}
