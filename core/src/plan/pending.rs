//! The greedy state's rank-3 steps, applied to the candidates lazily.
//!
//! A step changes every candidate's `U` and `Y` (`U ← U − (U dᵀ) T⁻¹ (d C)`).
//! Applied at once, each step is a sweep over every candidate's blocks
//! (about 3 MB for 2 000 candidates of 30 columns), and so is the search
//! for the best candidate that follows it: the exchange of a chosen row
//! takes it out, searches, puts one in, sometimes takes that out and the
//! first back — up to five sweeps a row, the memory traffic most of
//! choosing 100 of 2 000 poses. Kept here instead, the steps are applied
//! in the next search's sweep, each candidate's steps one after the other
//! while its blocks are in cache, before its gain is computed.
//!
//! A candidate gets the same steps in the same order with the same
//! operations whenever they are applied, so its blocks are the same bits
//! as if each step had been applied at once. One candidate is brought up
//! to date alone when its own blocks are needed first (the rows it adds or
//! takes away, its socket's means).

use super::greedy::{mul3, subtract_rows};
use crate::kernel::{Batch, LaneOp};

/// One rank-3 step: `d` by entry (`[d₀ᵢ, d₁ᵢ, d₂ᵢ, 0]`), `d C`, `d C W`, and
/// `±T⁻¹`.
struct Step {
    d_by_entry: Vec<[f64; 4]>,
    ud: Vec<f64>,
    yd: Vec<f64>,
    ti: [[f64; 3]; 3],
}

/// The steps since every candidate last had them all, and how many of them
/// each candidate has had.
pub(super) struct Pending {
    p: usize,
    steps: Vec<Step>,
    applied: Vec<usize>,
}

impl Pending {
    /// Nothing pending for `n` candidates of `p` columns.
    pub(super) fn new(n: usize, p: usize) -> Pending {
        Pending {
            p,
            steps: Vec::new(),
            applied: vec![0; n],
        }
    }

    /// A step of rows `d` (3 × p) with images `ud`, `yd` and signed `ti`.
    pub(super) fn push(&mut self, d: &[f64], ud: Vec<f64>, yd: Vec<f64>, ti: [[f64; 3]; 3]) {
        let mut d_by_entry = vec![[0.0; 4]; self.p];
        by_entry(d, &mut d_by_entry);
        self.steps.push(Step {
            d_by_entry,
            ud,
            yd,
            ti,
        });
    }

    /// Brings candidate `i` up to date (`u`, `y`: every candidate's blocks).
    pub(super) fn catch_up(&mut self, i: usize, u: &mut [f64], y: &mut [f64]) {
        let (p, from) = (self.p, self.applied[i]);
        if from == self.steps.len() {
            return;
        }
        let r = 3 * i * p..3 * (i + 1) * p;
        crate::kernel::run_lanes(One {
            steps: &self.steps[from..],
            u: &mut u[r.clone()],
            y: &mut y[r],
            p,
        });
        self.applied[i] = self.steps.len();
    }

    /// Brings every candidate up to date and hands each, in order, to
    /// `visit` with its blocks, on the widest lanes the CPU has. Nothing is
    /// pending after.
    pub(super) fn sweep<V: Visit>(&mut self, u: &mut [f64], y: &mut [f64], visit: &mut V) {
        crate::kernel::run_lanes(Sweep {
            steps: &self.steps,
            applied: &self.applied,
            u,
            y,
            p: self.p,
            visit,
        });
        self.steps.clear();
        self.applied.iter_mut().for_each(|a| *a = 0);
    }
}

/// What a sweep hands each candidate to, with its blocks up to date.
pub(super) trait Visit {
    /// Candidate `k`'s `U` and `Y` (`#[inline(always)]`, or it keeps the
    /// baseline's instructions).
    fn visit<L: Batch>(&mut self, k: usize, u: &[f64], y: &[f64]);
}

/// One candidate's pending steps.
struct One<'a> {
    steps: &'a [Step],
    u: &'a mut [f64],
    y: &'a mut [f64],
    p: usize,
}

impl LaneOp for One<'_> {
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        apply_one::<L>(self.steps, self.u, self.y, self.p);
    }
}

/// Every candidate's pending steps, then `visit`.
struct Sweep<'a, V> {
    steps: &'a [Step],
    applied: &'a [usize],
    u: &'a mut [f64],
    y: &'a mut [f64],
    p: usize,
    visit: &'a mut V,
}

impl<V: Visit> LaneOp for Sweep<'_, V> {
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        let Sweep {
            steps,
            applied,
            u,
            y,
            p,
            visit,
        } = self;
        // Two candidates at a time: their products' sums are independent,
        // so the CPU overlaps them (one candidate's three wait on the adds'
        // latency).
        let (mut us, mut ys) = (u.chunks_exact_mut(6 * p), y.chunks_exact_mut(6 * p));
        let mut k = 0;
        for ((ui, yi), had) in (&mut us).zip(&mut ys).zip(applied.chunks_exact(2)) {
            let ((u0, u1), (y0, y1)) = (ui.split_at_mut(3 * p), yi.split_at_mut(3 * p));
            if had[0] == had[1] {
                for step in &steps[had[0]..] {
                    let b = &step.d_by_entry[..];
                    let [first, second] = product_pair::<L>([u0, u1], [b, b], p);
                    downdate(u0, y0, &first, step, p);
                    downdate(u1, y1, &second, step, p);
                }
            } else {
                apply_one::<L>(&steps[had[0]..], u0, y0, p);
                apply_one::<L>(&steps[had[1]..], u1, y1, p);
            }
            visit.visit::<L>(k, u0, y0);
            visit.visit::<L>(k + 1, u1, y1);
            k += 2;
        }
        let (ui, yi) = (us.into_remainder(), ys.into_remainder());
        if !ui.is_empty() {
            apply_one::<L>(&steps[applied[k]..], ui, yi, p);
            visit.visit::<L>(k, ui, yi);
        }
    }
}

/// `steps` applied to one candidate's blocks.
#[inline(always)]
fn apply_one<L: Batch>(steps: &[Step], u: &mut [f64], y: &mut [f64], p: usize) {
    for step in steps {
        let product = product_by_entry::<L>(u, &step.d_by_entry, p);
        downdate(u, y, &product, step, p);
    }
}

/// One candidate's `U`, `Y` less their share of a step, given `U dᵀ`.
/// (Inlined into the lanes' loop, or it keeps the baseline's
/// instructions.)
#[inline(always)]
fn downdate(u: &mut [f64], y: &mut [f64], product: &[[f64; 3]; 3], step: &Step, p: usize) {
    let g = mul3(product, &step.ti);
    for (block, src) in [(u, &step.ud), (y, &step.yd)] {
        for (k, row) in block.chunks_exact_mut(p).enumerate() {
            subtract_rows(row, &g[k], src, p);
        }
    }
}

/// A 3 × p block `b` by entry into `out` (p long): `[b₀ᵢ, b₁ᵢ, b₂ᵢ, 0]`.
pub(super) fn by_entry(b: &[f64], out: &mut [[f64; 4]]) {
    let p = out.len();
    for (i, o) in out.iter_mut().enumerate() {
        *o = [b[i], b[p + i], b[2 * p + i], 0.0];
    }
}

/// `A Bᵀ` of a 3 × p block `A` and a `B` given by entry: nine sums, each
/// over the `p` entries in order from −0.0 (as `Iterator::sum`, so the same
/// bits as the greedy's `product`), each row of `A` times one lane-wide
/// load of `B`'s column. (Explicit lanes: LLVM packed a plain-array version
/// two-wide.)
#[inline(always)]
pub(super) fn product_by_entry<L: Batch>(a: &[f64], b: &[[f64; 4]], p: usize) -> [[f64; 3]; 3] {
    let (a0, a1, a2) = (&a[..p], &a[p..2 * p], &a[2 * p..3 * p]);
    let mut s = [L::from(-0.0); 3];
    for (((&x0, &x1), &x2), y) in a0.iter().zip(a1).zip(a2).zip(b) {
        let y = L::load(y);
        for (sk, xk) in s.iter_mut().zip([x0, x1, x2]) {
            *sk = *sk + L::from(xk) * y;
        }
    }
    s.map(three)
}

/// [`product_by_entry`] of two pairs side by side, `a[0]` by `b[0]` and
/// `a[1]` by `b[1]`: each sum as there, so the same bits, with six
/// independent sums for the CPU to overlap.
#[inline(always)]
pub(super) fn product_pair<L: Batch>(
    a: [&[f64]; 2],
    b: [&[[f64; 4]]; 2],
    p: usize,
) -> [[[f64; 3]; 3]; 2] {
    let [first, second] = a;
    let (a0, a1, a2) = (&first[..p], &first[p..2 * p], &first[2 * p..3 * p]);
    let (a3, a4, a5) = (&second[..p], &second[p..2 * p], &second[2 * p..3 * p]);
    let mut s = [L::from(-0.0); 6];
    let entries = a0.iter().zip(a1).zip(a2).zip(a3.iter().zip(a4).zip(a5));
    for ((((&x0, &x1), &x2), ((&x3, &x4), &x5)), (y, z)) in entries.zip(b[0].iter().zip(b[1])) {
        let (y, z) = (L::load(y), L::load(z));
        for (sk, xk) in s[..3].iter_mut().zip([x0, x1, x2]) {
            *sk = *sk + L::from(xk) * y;
        }
        for (sk, xk) in s[3..].iter_mut().zip([x3, x4, x5]) {
            *sk = *sk + L::from(xk) * z;
        }
    }
    [
        [three(s[0]), three(s[1]), three(s[2])],
        [three(s[3]), three(s[4]), three(s[5])],
    ]
}

/// The first three lanes.
#[inline(always)]
fn three<L: Batch>(v: L) -> [f64; 3] {
    let r = v.to_array();
    [r[0], r[1], r[2]]
}
