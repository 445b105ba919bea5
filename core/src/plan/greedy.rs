//! Greedy sequential design by rank-3 updates.
//!
//! The state is the covariance `C = M⁻¹` of the parameters (in the plan's
//! scaled columns, σ = 1) given the rows chosen so far and the prior, and
//! for every candidate `U_i = J_i C` and `Y_i = U_i W` (`W` the workspace's
//! mean `JᵀJ`). Adding a pose's rows `d` (3 × p) changes
//!
//! - the I-criterion `tr(W C)` (the mean predicted variance of a position
//!   over the workspace) by `−tr((I + d C dᵀ)⁻¹ (d C W)(d C)ᵀ)`, and
//! - `ln det M` (D-optimality) by `ln det(I + d C dᵀ)`,
//!
//! both from 3 × 3 products of `d`, `d C` and `d C W` — O(p) per
//! candidate. After a choice `d*`, with `B = C d*ᵀ` and `T = I + d* B`,
//! `C ← C − B T⁻¹ Bᵀ` and every `U_i ← U_i − (U_i d*ᵀ) T⁻¹ (d* C)` (and the
//! same for `Y_i`): O(p) per candidate again, so a step costs O(N p) and
//! choosing K of N poses O(K N p + p³). The steps reach `U` and `Y` in the
//! next search's sweep over the candidates ([`super::pending`]), not one
//! sweep each.
//!
//! Touches see the arm only through how they differ within a socket (its
//! centre is eliminated): a socket whose `n` chosen touches have mean row
//! `J̄` gains exactly `n/(n+1) (J_k − J̄)ᵀ(J_k − J̄)` from touch `k`, so
//! `d = sqrt(n/(n+1)) (J_k − J̄)` — nothing from a socket's first touch.
//!
//! A hedge weight `w_k ≤ 1` scales a candidate's rows by `sqrt(w_k)`: the
//! criterion then counts a pose the model may not explain as a noisier one.

use nalgebra::DMatrix;

use super::pending::{Pending, Visit, by_entry, product_by_entry, product_pair};
use super::rows::Blocks;
use crate::kernel::Batch;

/// What a step maximises.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Gain {
    /// The fall of the workspace's mean predicted variance.
    Prediction,
    /// The rise of `ln det M`.
    Determinant,
}

/// The greedy state over one pool of candidates.
pub(crate) struct Greedy<'a> {
    p: usize,
    c: Vec<f64>,
    w: &'a [f64],
    j: &'a Blocks,
    /// Every candidate's `U` and `Y` (3p each), which may lag the steps in
    /// `pending`: read one only after `pending.catch_up`, or inside
    /// `pending.sweep`.
    u: Vec<f64>,
    y: Vec<f64>,
    weight: &'a [f64],
    group: &'a [usize],
    touches: bool,
    members: Vec<Vec<usize>>,
    /// Per group, the means of `J`, `U`, `Y` over its members (3p each).
    means: Vec<[Vec<f64>; 3]>,
    taken: Vec<bool>,
    gain: Gain,
    /// `tr(W C)` now.
    pub(crate) criterion: f64,
    /// `ln det M` now, less its start's.
    log_det: f64,
    /// The steps not yet applied to every candidate's `U` and `Y`.
    pending: Pending,
}

/// What a candidate's gain reads besides its own `U` and `Y`.
struct Gains<'s> {
    p: usize,
    j: &'s [f64],
    weight: &'s [f64],
    group: &'s [usize],
    members: &'s [Vec<usize>],
    means: &'s [[Vec<f64>; 3]],
    touches: bool,
    gain: Gain,
}

/// A candidate's rows scaled (and centred), as the gain reads them: `d`
/// and `d C` by entry (`[x₀ᵢ, x₁ᵢ, x₂ᵢ, 0]`), `d C` and `d C W` by row.
struct GainRows {
    dj: Vec<f64>,
    d_by_entry: Vec<[f64; 4]>,
    ud_by_entry: Vec<[f64; 4]>,
    ud: Vec<f64>,
    yd: Vec<f64>,
}

impl GainRows {
    fn new(p: usize) -> GainRows {
        GainRows {
            dj: vec![0.0; 3 * p],
            d_by_entry: vec![[0.0; 4]; p],
            ud_by_entry: vec![[0.0; 4]; p],
            ud: vec![0.0; 3 * p],
            yd: vec![0.0; 3 * p],
        }
    }
}

impl Gains<'_> {
    /// What adding candidate `k` (its blocks `uk`, `yk`) gains now: its
    /// rows made in `rows` (kept between calls) as [`Greedy::direction`]
    /// makes them, and their products by entry (the same sums as
    /// [`product`]'s, so the same bits, on lanes).
    #[inline(always)]
    fn of<L: Batch>(&self, k: usize, uk: &[f64], yk: &[f64], rows: &mut GainRows) -> f64 {
        let p = self.p;
        let mut f = self.weight[k].sqrt();
        let means = if self.touches {
            let g = self.group[k];
            let n = self.members[g].len() as f64;
            f *= (n / (n + 1.0)).sqrt();
            Some(&self.means[g])
        } else {
            None
        };
        if !(f > 0.0 && f.is_finite()) {
            return 0.0;
        }
        let jk = &self.j[3 * k * p..3 * (k + 1) * p];
        let mean = |which: usize| means.map(|m| &m[which][..]);
        scale_rows(&mut rows.dj, jk, mean(0), f);
        scale_rows(&mut rows.ud, uk, mean(1), f);
        scale_rows(&mut rows.yd, yk, mean(2), f);
        by_entry(&rows.dj, &mut rows.d_by_entry);
        by_entry(&rows.ud, &mut rows.ud_by_entry);
        let GainRows {
            dj: _,
            d_by_entry,
            ud_by_entry,
            ud,
            yd,
        } = rows;
        match self.gain {
            Gain::Determinant => {
                let a = plus_identity(product_by_entry::<L>(ud, d_by_entry, p));
                det3(&a).max(1e-300).ln()
            }
            Gain::Prediction => {
                let [a, b] = product_pair::<L>([ud, yd], [d_by_entry, ud_by_entry], p);
                let Some(ai) = inverse3(&plus_identity(a)) else {
                    return 0.0;
                };
                (0..3)
                    .map(|i| (0..3).map(|l| ai[i][l] * b[l][i]).sum::<f64>())
                    .sum()
            }
        }
    }
}

/// A candidate's rows `src` as they add to the information, into `out`:
/// `(v − m) f` about its socket's `mean`, `v f` without one.
#[inline(always)]
fn scale_rows(out: &mut [f64], src: &[f64], mean: Option<&[f64]>, f: f64) {
    match mean {
        Some(m) => {
            for ((o, v), m) in out.iter_mut().zip(src).zip(m) {
                *o = (v - m) * f;
            }
        }
        None => {
            for (o, v) in out.iter_mut().zip(src) {
                *o = v * f;
            }
        }
    }
}

/// The eligible candidate of the largest gain (the first of equals), as the
/// sweep hands the candidates over.
struct Search<'s, F> {
    gains: Gains<'s>,
    taken: &'s [bool],
    eligible: F,
    rows: GainRows,
    best: Option<(usize, f64)>,
}

impl<F: Fn(usize) -> bool> Visit for Search<'_, F> {
    #[inline(always)]
    fn visit<L: Batch>(&mut self, k: usize, uk: &[f64], yk: &[f64]) {
        if self.taken[k] || !(self.eligible)(k) {
            return;
        }
        let g = self.gains.of::<L>(k, uk, yk, &mut self.rows);
        if g.is_finite() && self.best.is_none_or(|(_, b)| g > b) {
            self.best = Some((k, g));
        }
    }
}

/// The rows a candidate would add, and their `C`- and `CW`-images.
struct Direction {
    d: Vec<f64>,
    ud: Vec<f64>,
    yd: Vec<f64>,
}

impl<'a> Greedy<'a> {
    /// The state before any choice: `C = (prior + ε I)⁻¹`. `j` are the
    /// candidates' blocks, `group` their socket (all 0 for positions);
    /// `touches` says whether a group's centre is eliminated.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        j: &'a Blocks,
        w: &'a [f64],
        weight: &'a [f64],
        group: &'a [usize],
        touches: bool,
        prior: Option<&DMatrix<f64>>,
        epsilon: f64,
        gain: Gain,
    ) -> Option<Greedy<'a>> {
        let p = j.p;
        let mut m = prior.cloned().unwrap_or_else(|| DMatrix::zeros(p, p));
        for a in 0..p {
            m[(a, a)] += epsilon;
        }
        let inv = crate::residuals::cholesky_inverse(&m.cholesky()?);
        let c: Vec<f64> = (0..p * p).map(|i| inv[(i / p, i % p)]).collect();
        let n = j.len();
        let mut u = vec![0.0; 3 * p * n];
        let mut y = vec![0.0; 3 * p * n];
        for i in 0..n {
            let (ji, ui) = (j.at(i), &mut u[3 * i * p..3 * (i + 1) * p]);
            for k in 0..3 {
                mat_row(&ji[k * p..(k + 1) * p], &c, p, &mut ui[k * p..(k + 1) * p]);
            }
            let yi = &mut y[3 * i * p..3 * (i + 1) * p];
            for k in 0..3 {
                mat_row(&ui[k * p..(k + 1) * p], w, p, &mut yi[k * p..(k + 1) * p]);
            }
        }
        let groups = group.iter().max().map_or(0, |g| g + 1);
        let criterion = (0..p * p).map(|i| w[i] * c[i]).sum();
        Some(Greedy {
            p,
            c,
            w,
            j,
            u,
            y,
            weight,
            group,
            touches,
            members: vec![Vec::new(); groups],
            means: vec![[vec![0.0; 3 * p], vec![0.0; 3 * p], vec![0.0; 3 * p]]; groups],
            taken: vec![false; n],
            gain,
            criterion,
            log_det: 0.0,
            pending: Pending::new(n, p),
        })
    }

    /// What the gain lowers: `tr(W C)`, or `−ln det M`.
    pub(crate) fn value(&self) -> f64 {
        match self.gain {
            Gain::Prediction => self.criterion,
            Gain::Determinant => -self.log_det,
        }
    }

    /// Whether candidate `i` is chosen.
    pub(crate) fn is_taken(&self, i: usize) -> bool {
        self.taken[i]
    }

    /// The chosen touches of group `g`.
    pub(crate) fn members(&self, g: usize) -> &[usize] {
        &self.members[g]
    }

    /// The rows candidate `k` would add now (`None`: nothing — a socket's
    /// first touch, or a weight of zero).
    fn direction(&self, k: usize) -> Option<Direction> {
        self.rows_of(k, false)
    }

    /// The rows candidate `k` adds (`removing`: the rows a chosen `k`
    /// takes away — a touch about its socket's mean with it, weighed
    /// `n/(n−1)`).
    fn rows_of(&self, k: usize, removing: bool) -> Option<Direction> {
        let p = self.p;
        let r = 3 * k * p..3 * (k + 1) * p;
        let mut f = self.weight[k].sqrt();
        let means = if self.touches {
            let g = self.group[k];
            let n = self.members[g].len() as f64;
            f *= if removing {
                (n / (n - 1.0).max(0.0)).sqrt()
            } else {
                (n / (n + 1.0)).sqrt()
            };
            Some(&self.means[g])
        } else {
            None
        };
        if !(f > 0.0 && f.is_finite()) {
            return None;
        }
        let mean = |which: usize| means.map(|m| &m[which][..]);
        let rows = |src: &[f64], which: usize| {
            let mut out = vec![0.0; 3 * p];
            scale_rows(&mut out, src, mean(which), f);
            out
        };
        Some(Direction {
            d: rows(&self.j.j[r.clone()], 0),
            ud: rows(&self.u[r.clone()], 1),
            yd: rows(&self.y[r], 2),
        })
    }

    /// The eligible candidate of the largest gain (the first of equals),
    /// in the sweep that applies the pending steps.
    pub(crate) fn best(&mut self, eligible: impl Fn(usize) -> bool) -> Option<(usize, f64)> {
        let gains = Gains {
            p: self.p,
            j: &self.j.j,
            weight: self.weight,
            group: self.group,
            members: &self.members,
            means: &self.means,
            touches: self.touches,
            gain: self.gain,
        };
        let mut search = Search {
            gains,
            taken: &self.taken,
            eligible,
            rows: GainRows::new(self.p),
            best: None,
        };
        self.pending.sweep(&mut self.u, &mut self.y, &mut search);
        search.best
    }

    /// Chooses candidate `k`: its rows into `C`, every `U` and `Y`.
    pub(crate) fn add(&mut self, k: usize) {
        let p = self.p;
        self.pending.catch_up(k, &mut self.u, &mut self.y);
        if let Some(dir) = self.direction(k) {
            let t = plus_identity(product(&dir.ud, &dir.d, p));
            if let Some(ti) = inverse3(&t) {
                self.update(dir, &ti, 1.0);
                self.log_det += det3(&t).max(1e-300).ln();
            }
        }
        self.taken[k] = true;
        let g = self.group[k];
        self.members[g].push(k);
        self.refresh_means();
    }

    /// Takes a chosen candidate `k` back out: `M − dᵀd`, so
    /// `C ← C + B (I − d B)⁻¹ Bᵀ`.
    pub(crate) fn remove(&mut self, k: usize) {
        let p = self.p;
        self.pending.catch_up(k, &mut self.u, &mut self.y);
        if let Some(dir) = self.rows_of(k, true) {
            let s = product(&dir.ud, &dir.d, p);
            let t: [[f64; 3]; 3] = std::array::from_fn(|i| {
                std::array::from_fn(|j| f64::from(u8::from(i == j)) - s[i][j])
            });
            if let Some(ti) = inverse3(&t) {
                self.update(dir, &ti, -1.0);
                self.log_det += det3(&t).max(1e-300).ln();
            }
        }
        self.taken[k] = false;
        let g = self.group[k];
        self.members[g].retain(|&m| m != k);
        self.refresh_means();
    }

    /// `C` and the criterion after rows `dir` added (`sign` 1) or taken
    /// away (−1), `ti = (I ± d C dᵀ)⁻¹`; the step pending for `U` and `Y`.
    fn update(&mut self, dir: Direction, ti: &[[f64; 3]; 3], sign: f64) {
        let p = self.p;
        // C ∓= (d C)ᵀ T⁻¹ (d C).
        let ti = &ti.map(|r| r.map(|v| sign * v));
        let tud = apply3(ti, &dir.ud, p);
        for a in 0..p {
            for b in 0..p {
                let v: f64 = (0..3).map(|k| dir.ud[k * p + a] * tud[k * p + b]).sum();
                self.c[a * p + b] -= v;
            }
        }
        self.pending.push(&dir.d, dir.ud, dir.yd, *ti);
        self.criterion = (0..p * p).map(|i| self.w[i] * self.c[i]).sum();
    }

    /// Every group's means of `J`, `U`, `Y` over its members.
    fn refresh_means(&mut self) {
        if !self.touches {
            return;
        }
        let p = self.p;
        for &i in self.members.iter().flatten() {
            self.pending.catch_up(i, &mut self.u, &mut self.y);
        }
        for (g, members) in self.members.iter().enumerate() {
            let n = members.len().max(1) as f64;
            for (m, src) in self.means[g].iter_mut().zip([&self.j.j, &self.u, &self.y]) {
                m.iter_mut().for_each(|v| *v = 0.0);
                for &i in members {
                    for (v, x) in m.iter_mut().zip(&src[3 * i * p..3 * (i + 1) * p]) {
                        *v += x / n;
                    }
                }
            }
        }
    }
}

/// `out = row · M` (M p × p row-major).
fn mat_row(row: &[f64], m: &[f64], p: usize, out: &mut [f64]) {
    out.iter_mut().for_each(|v| *v = 0.0);
    for (a, &ra) in row.iter().enumerate() {
        if ra == 0.0 {
            continue;
        }
        for (v, x) in out.iter_mut().zip(&m[a * p..(a + 1) * p]) {
            *v += ra * x;
        }
    }
}

/// `A Bᵀ` of two 3 × p blocks: nine sums, each over the `p` entries in
/// order from −0.0 (as `Iterator::sum`, so the same bits), run side by side
/// so that they vectorise.
#[inline(always)]
fn product(a: &[f64], b: &[f64], p: usize) -> [[f64; 3]; 3] {
    let (a0, a1, a2) = (&a[..p], &a[p..2 * p], &a[2 * p..3 * p]);
    let (b0, b1, b2) = (&b[..p], &b[p..2 * p], &b[2 * p..3 * p]);
    let mut s = [[-0.0f64; 3]; 3];
    let rows = a0.iter().zip(a1).zip(a2).zip(b0.iter().zip(b1).zip(b2));
    for (((&x0, &x1), &x2), ((&y0, &y1), &y2)) in rows {
        for (sk, xk) in s.iter_mut().zip([x0, x1, x2]) {
            sk[0] += xk * y0;
            sk[1] += xk * y1;
            sk[2] += xk * y2;
        }
    }
    s
}

/// `row −= f[0] src₀ − f[1] src₁ − f[2] src₂` (`src` a 3 × p block), the
/// three terms subtracted one after the other and a zero factor's skipped,
/// in one sweep over the row.
#[inline(always)]
pub(super) fn subtract_rows(row: &mut [f64], f: &[f64; 3], src: &[f64], p: usize) {
    let (s0, s1, s2) = (&src[..p], &src[p..2 * p], &src[2 * p..3 * p]);
    match (f[0] != 0.0, f[1] != 0.0, f[2] != 0.0) {
        (true, true, true) => {
            for i in 0..p {
                row[i] = ((row[i] - f[0] * s0[i]) - f[1] * s1[i]) - f[2] * s2[i];
            }
        }
        (use0, use1, use2) => {
            for (l, (used, s)) in [(use0, s0), (use1, s1), (use2, s2)].into_iter().enumerate() {
                if used {
                    for (v, x) in row.iter_mut().zip(s) {
                        *v -= f[l] * x;
                    }
                }
            }
        }
    }
}

/// `M · X` of a 3 × 3 and a 3 × p block.
fn apply3(m: &[[f64; 3]; 3], x: &[f64], p: usize) -> Vec<f64> {
    let mut out = vec![0.0; 3 * p];
    for k in 0..3 {
        for l in 0..3 {
            for (v, s) in out[k * p..(k + 1) * p]
                .iter_mut()
                .zip(&x[l * p..(l + 1) * p])
            {
                *v += m[k][l] * s;
            }
        }
    }
    out
}

fn plus_identity(mut s: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    for (k, row) in s.iter_mut().enumerate() {
        row[k] += 1.0;
    }
    s
}

#[inline(always)]
pub(super) fn mul3(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

fn det3(m: &[[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

fn inverse3(m: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let det = det3(m);
    if det.abs() < 1e-300 || !det.is_finite() {
        return None;
    }
    let c = |i: usize, j: usize| {
        let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
        let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
        m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]
    };
    // The inverse is the transposed cofactor matrix over the determinant.
    Some(std::array::from_fn(|i| {
        std::array::from_fn(|j| c(j, i) / det)
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::LaneOp;

    /// The pending steps' products of `a` (two candidates' 3 × p blocks):
    /// the first's alone, then both side by side.
    struct Products<'a> {
        a: &'a [f64],
        b: &'a [[f64; 4]],
        p: usize,
    }

    impl LaneOp for Products<'_> {
        type Output = [[[f64; 3]; 3]; 3];
        fn run<L: Batch>(self) -> Self::Output {
            let (p, b) = (self.p, self.b);
            let (first, second) = self.a.split_at(3 * p);
            let [x, y] = product_pair::<L>([first, second], [b, b], p);
            [product_by_entry::<L>(first, b, p), x, y]
        }
    }

    /// `n` candidates' blocks of `p` columns, entries in ±1.
    fn random_blocks(seed: u64, p: usize, n: usize) -> Blocks {
        let mut rng = crate::random::rng(seed, 0);
        Blocks {
            p,
            j: (0..3 * p * n)
                .map(|_| rand::RngExt::random_range(&mut rng, -1.0..1.0))
                .collect(),
        }
    }

    /// The side-by-side sums (the eager products, and the pending steps'
    /// products by entry, one candidate or two, on the portable lanes and
    /// on the widest the CPU has) and the one-sweep subtraction are the
    /// same bits as the sums one at a time (`Iterator::sum`) and the three
    /// subtractions one after the other.
    #[test]
    fn the_vectorised_loops_are_the_same_bits() {
        let mut rng = crate::random::rng(5, 0);
        let mut draw = |n: usize| -> Vec<f64> {
            (0..n)
                .map(|_| rand::RngExt::random_range(&mut rng, -1.0..1.0) * 1e3)
                .collect()
        };
        for p in [1, 3, 7, 24, 31] {
            let (a, b) = (draw(6 * p), draw(3 * p));
            let sums = |a: &[f64]| -> [[u64; 3]; 3] {
                std::array::from_fn(|k| {
                    std::array::from_fn(|l| {
                        (a[k * p..(k + 1) * p].iter().zip(&b[l * p..(l + 1) * p]))
                            .map(|(x, y)| x * y)
                            .sum::<f64>()
                            .to_bits()
                    })
                })
            };
            let (first, second) = a.split_at(3 * p);
            let bits = |m: [[f64; 3]; 3]| m.map(|r| r.map(f64::to_bits));
            assert_eq!(bits(product(first, &b, p)), sums(first), "p = {p}");
            let mut b_by_entry = vec![[0.0; 4]; p];
            by_entry(&b, &mut b_by_entry);
            let op = || Products {
                a: &a,
                b: &b_by_entry,
                p,
            };
            let want = [sums(first), sums(first), sums(second)];
            for got in [
                op().run::<crate::kernel::Lanes>(),
                crate::kernel::run_lanes(op()),
            ] {
                assert_eq!(got.map(bits), want, "p = {p}");
            }
            for f in [[0.5, -2.0, 3.0], [0.0, 1.5, 0.0], [-1.0, 0.0, 2.0]] {
                let mut want = first[..p].to_vec();
                for (l, &fl) in f.iter().enumerate() {
                    if fl != 0.0 {
                        for (v, x) in want.iter_mut().zip(&b[l * p..(l + 1) * p]) {
                            *v -= fl * x;
                        }
                    }
                }
                let mut got = first[..p].to_vec();
                subtract_rows(&mut got, &f, &b, p);
                assert!(
                    got.iter()
                        .zip(&want)
                        .all(|(x, y)| x.to_bits() == y.to_bits())
                );
            }
        }
    }

    /// Steps applied lazily (in the next search's sweep, or to one
    /// candidate when its rows are needed) leave every candidate's `U` and
    /// `Y` the same bits as steps applied at once, and the searches pick
    /// the same candidates with the same gains. Thirteen candidates: a pair
    /// sweep's odd one out, and pairs whose two have had different steps.
    #[test]
    fn lazy_steps_are_the_same_bits_as_steps_at_once() {
        let (p, n) = (7, 13);
        let j = random_blocks(11, p, n);
        let w = super::super::rows::mean_gram(&j);
        let weight: Vec<f64> = (0..n)
            .map(|i| {
                if i == 4 {
                    0.0
                } else {
                    1.0 / (1 + i % 3) as f64
                }
            })
            .collect();
        let group: Vec<usize> = (0..n).map(|i| i % 3).collect();
        for (touches, gain) in [
            (false, Gain::Prediction),
            (false, Gain::Determinant),
            (true, Gain::Prediction),
            (true, Gain::Determinant),
        ] {
            let make = || Greedy::new(&j, &w, &weight, &group, touches, None, 1e-3, gain).unwrap();
            let (mut lazy, mut eager) = (make(), make());
            let mut picks = Vec::new();
            let script: [(bool, usize); 12] = [
                (true, 0),
                (true, 3),
                (true, 7),
                (true, 1),
                (false, 3),
                (true, 12),
                (true, 5),
                (false, 0),
                (true, 9),
                (true, 3),
                (false, 12),
                (true, 11),
            ];
            for (adding, k) in script {
                for g in [&mut lazy, &mut eager] {
                    if adding { g.add(k) } else { g.remove(k) }
                }
                // At once: every step swept in before the next.
                eager.best(|_| false);
                if k % 2 == 1 {
                    let got = lazy.best(|i| i != 2);
                    assert_eq!(
                        got.map(|(i, v)| (i, v.to_bits())),
                        eager.best(|i| i != 2).map(|(i, v)| (i, v.to_bits()))
                    );
                    picks.extend(got.map(|b| b.0));
                }
            }
            assert!(picks.len() >= 5, "{picks:?}");
            lazy.best(|_| false);
            let bits =
                |g: &Greedy| -> Vec<u64> { g.u.iter().chain(&g.y).map(|v| v.to_bits()).collect() };
            assert_eq!(bits(&lazy), bits(&eager), "{touches} {gain:?}");
            assert_eq!(lazy.criterion.to_bits(), eager.criterion.to_bits());
        }
    }

    /// The rank-3 updates and downdates agree with the criterion recomputed
    /// from scratch.
    #[test]
    fn the_updates_match_a_fresh_inverse() {
        let (p, n) = (5, 12);
        let j = random_blocks(3, p, n);
        let w = super::super::rows::mean_gram(&j);
        let weight = vec![1.0; n];
        let group: Vec<usize> = (0..n).map(|i| i % 2).collect();
        for touches in [false, true] {
            let mut g = Greedy::new(
                &j,
                &w,
                &weight,
                &group,
                touches,
                None,
                1e-3,
                Gain::Prediction,
            )
            .unwrap();
            let picks = [0, 2, 1, 5, 3, 4, 7];
            for &k in &picks {
                let before = g.criterion;
                let gain = g.best(|i| i == k).map_or(0.0, |(_, gain)| gain);
                g.add(k);
                assert!((before - gain - g.criterion).abs() < 1e-9 * before.abs().max(1.0));
            }
            // Taking rows back out is the same as never adding them.
            g.remove(2);
            g.remove(3);
            let picks = [0, 1, 5, 4, 7];
            // From scratch: M = ε I + Σ (centred per socket) JᵀJ.
            let mut m = DMatrix::<f64>::identity(p, p) * 1e-3;
            for s in 0..2 {
                let mem: Vec<usize> = picks.iter().copied().filter(|&k| group[k] == s).collect();
                for k in 0..3 {
                    let rows: Vec<Vec<f64>> = mem
                        .iter()
                        .map(|&i| j.at(i)[k * p..(k + 1) * p].to_vec())
                        .collect();
                    let mean: Vec<f64> = (0..p)
                        .map(|c| rows.iter().map(|r| r[c]).sum::<f64>() / rows.len() as f64)
                        .collect();
                    for r in &rows {
                        for a in 0..p {
                            for b in 0..p {
                                let (ra, rb) = if touches {
                                    (r[a] - mean[a], r[b] - mean[b])
                                } else {
                                    (r[a], r[b])
                                };
                                m[(a, b)] += ra * rb;
                            }
                        }
                    }
                }
            }
            let c = m.try_inverse().unwrap();
            let want: f64 = (0..p * p).map(|i| w[i] * c[(i / p, i % p)]).sum();
            assert!(
                (want - g.criterion).abs() < 1e-8 * want,
                "{touches}: {want} {}",
                g.criterion
            );
        }
    }
}
