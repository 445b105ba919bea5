//! Four poses at a time. Every lane operation is exactly the scalar IEEE
//! operation (no fused multiply-add: Rust never contracts), so lane results
//! equal one-pose results bit for bit whichever lane type runs.
//!
//! Two lane types implement [`Batch`]: [`Lanes`], plain arrays that compile
//! to SSE2 everywhere, and on x86-64 `Avx`, explicit 256-bit AVX vectors.
//! (LLVM's auto-vectorizer left the position kernel scalar, hence the
//! intrinsics.) Batch loops are [`LaneOp`]s and [`run`] picks the lane type.
//!
//! `Avx` is private to its submodule, and the only path to it is a function
//! that takes an `AvxToken`, a zero-sized proof returned only by runtime CPU
//! feature detection: no safe function of the crate, public or not, can
//! execute an AVX instruction on a CPU that lacks it.

use std::ops::{Add, Div, Mul, Neg, Sub};

use super::Scalar;

/// Poses per batch.
pub(crate) const LANES: usize = 4;

/// The lanes of each of `v`'s values, as arrays. Inlined, with a loop of
/// its own rather than `array::map`, which LLVM kept out of line and so
/// compiled without the batch loop's target features: each AVX store there
/// was a call.
#[inline(always)]
pub(crate) fn to_arrays<L: Batch, const M: usize>(v: &[L; M]) -> [[f64; LANES]; M] {
    let mut out = [[0.0; LANES]; M];
    for (o, x) in out.iter_mut().zip(v) {
        *o = x.to_array();
    }
    out
}

/// A lane type the batch loops can run the generated code on (and the
/// gravity torques, which divide).
pub(crate) trait Batch: Scalar + Div<Output = Self> {
    /// Loads `LANES` values (a fixed-size array, so the batch loops do
    /// their bounds checks once per call, not once per load).
    fn load(v: &[f64; LANES]) -> Self;
    /// The lanes as an array.
    fn to_array(self) -> [f64; LANES];
    /// Stores the lanes into `dst`.
    fn store(self, dst: &mut [f64; LANES]);
    /// The 4 × 4 transpose: lane `l` of output `r` is lane `r` of input
    /// `l`. Moves values only, so every bit is kept.
    fn transpose4(v: [Self; LANES]) -> [Self; LANES];
}

/// Portable lanes: one value per pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Lanes(pub(crate) [f64; LANES]);

impl Batch for Lanes {
    #[inline(always)]
    fn load(v: &[f64; LANES]) -> Lanes {
        Lanes(*v)
    }

    #[inline(always)]
    fn to_array(self) -> [f64; LANES] {
        self.0
    }

    #[inline(always)]
    fn store(self, dst: &mut [f64; LANES]) {
        *dst = self.0;
    }

    #[inline(always)]
    fn transpose4(v: [Lanes; LANES]) -> [Lanes; LANES] {
        std::array::from_fn(|r| Lanes(std::array::from_fn(|l| v[l].0[r])))
    }
}

impl From<f64> for Lanes {
    #[inline(always)]
    fn from(v: f64) -> Lanes {
        Lanes([v; LANES])
    }
}

macro_rules! lanewise {
    ($tr:ident, $f:ident, $op:tt) => {
        impl $tr for Lanes {
            type Output = Lanes;
            #[inline(always)]
            fn $f(self, o: Lanes) -> Lanes {
                Lanes(std::array::from_fn(|l| self.0[l] $op o.0[l]))
            }
        }
    };
}

lanewise!(Add, add, +);
lanewise!(Sub, sub, -);
lanewise!(Mul, mul, *);
// (For the gravity torques; the generated kernel divides nothing.)
lanewise!(Div, div, /);

impl Neg for Lanes {
    type Output = Lanes;
    #[inline(always)]
    fn neg(self) -> Lanes {
        Lanes(self.0.map(|v| -v))
    }
}

/// Two batches computed together: every operation on both halves, so
/// the generated code carries two independent dependency chains and the
/// CPU overlaps them (one chain alone waits on its latency: the position
/// kernel is a serial product of links). Each half does exactly what one
/// batch does, so the results are the same bits.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Two<L>(pub(crate) L, pub(crate) L);

impl<L: From<f64>> From<f64> for Two<L> {
    #[inline(always)]
    fn from(v: f64) -> Two<L> {
        Two(L::from(v), L::from(v))
    }
}

macro_rules! pairwise {
    ($tr:ident, $f:ident) => {
        impl<L: $tr<Output = L>> $tr for Two<L> {
            type Output = Two<L>;
            #[inline(always)]
            fn $f(self, o: Two<L>) -> Two<L> {
                Two(self.0.$f(o.0), self.1.$f(o.1))
            }
        }
    };
}

pairwise!(Add, add);
pairwise!(Sub, sub);
pairwise!(Mul, mul);

impl<L: Neg<Output = L>> Neg for Two<L> {
    type Output = Two<L>;
    #[inline(always)]
    fn neg(self) -> Two<L> {
        Two(-self.0, -self.1)
    }
}

/// A batch loop generic over the lane type: what [`run`] runs on the widest
/// lanes the CPU supports. Its output cannot depend on the lane type, so no
/// lane value leaves `run` except through the loop's own results.
pub(crate) trait LaneOp {
    /// What the loop returns.
    type Output;
    /// Runs the loop with lane type `L`.
    fn run<L: Batch>(self) -> Self::Output;
}

/// Runs `op` with AVX lanes where the CPU has AVX2 (checked once per call,
/// a cached flag), else with the portable [`Lanes`]; the results are the
/// same bits either way.
#[inline(always)]
pub(crate) fn run<O: LaneOp>(op: O) -> O::Output {
    #[cfg(target_arch = "x86_64")]
    if let Some(token) = avx::AvxToken::detect() {
        return avx::run(token, op);
    }
    op.run::<Lanes>()
}

// The only unsafe code of the toolkit: AVX intrinsics.
//
// Why they are sound: the lane type `Avx` is private to this module, so code
// elsewhere can neither name it nor call its constructors (`From<f64>`,
// `Batch::load`). The one place that instantiates generic lane code with
// `Avx` is `run`, which takes an `AvxToken`, and the only way to get a token
// is `AvxToken::detect`, which returns one only where the CPU has AVX2. So an
// `Avx` value, and every intrinsic below, exists only in a process that has
// checked its CPU.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod avx {
    use super::{Batch, LANES, LaneOp};
    use std::arch::x86_64::*;
    use std::ops::{Add, Div, Mul, Neg, Sub};

    /// Proof that the CPU supports AVX2: made only by [`AvxToken::detect`].
    /// Zero-sized, so carrying it costs nothing.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct AvxToken(());

    impl AvxToken {
        /// A token if the CPU supports AVX2 (a cached flag after the first
        /// call), else `None`.
        #[inline(always)]
        pub(crate) fn detect() -> Option<AvxToken> {
            std::arch::is_x86_feature_detected!("avx2").then_some(AvxToken(()))
        }
    }

    /// Runs `op` with [`Avx`] lanes in a function compiled for AVX2, so that
    /// the inlined lane code uses 256-bit registers. The token is the proof
    /// that the CPU can execute it.
    #[inline(always)]
    pub(crate) fn run<O: LaneOp>(_: AvxToken, op: O) -> O::Output {
        // SAFETY: `run_avx2` needs AVX2; the token exists only where
        // `detect` found it.
        unsafe { run_avx2(op) }
    }

    #[target_feature(enable = "avx2")]
    fn run_avx2<O: LaneOp>(op: O) -> O::Output {
        op.run::<Avx>()
    }

    /// Four lanes in one AVX register.
    ///
    /// Invariant: values of this type exist only on CPUs with AVX2. The type
    /// is private to this module and only [`run`] (which takes an
    /// [`AvxToken`]) hands it to generic code, so every constructor below runs
    /// downstream of a successful [`AvxToken::detect`].
    #[derive(Clone, Copy, Debug)]
    struct Avx(__m256d);

    impl Batch for Avx {
        #[inline(always)]
        fn load(v: &[f64; LANES]) -> Avx {
            // SAFETY: AVX is present (type invariant); `v` holds 4 values.
            Avx(unsafe { _mm256_loadu_pd(v.as_ptr()) })
        }

        #[inline(always)]
        fn to_array(self) -> [f64; LANES] {
            let mut out = [0.0; LANES];
            // SAFETY: AVX is present (type invariant); `out` holds 4 values.
            unsafe { _mm256_storeu_pd(out.as_mut_ptr(), self.0) };
            out
        }

        #[inline(always)]
        fn store(self, dst: &mut [f64; LANES]) {
            // SAFETY: AVX is present (type invariant); `dst` holds 4 values.
            unsafe { _mm256_storeu_pd(dst.as_mut_ptr(), self.0) };
        }

        #[inline(always)]
        fn transpose4([a, b, c, d]: [Avx; LANES]) -> [Avx; LANES] {
            // SAFETY: AVX is present (type invariant). Pairs within each
            // 128-bit half, then the halves swapped across: the usual
            // eight-shuffle 4 × 4 transpose.
            unsafe {
                let ab_even = _mm256_unpacklo_pd(a.0, b.0); // a0 b0 a2 b2
                let ab_odd = _mm256_unpackhi_pd(a.0, b.0); // a1 b1 a3 b3
                let cd_even = _mm256_unpacklo_pd(c.0, d.0); // c0 d0 c2 d2
                let cd_odd = _mm256_unpackhi_pd(c.0, d.0); // c1 d1 c3 d3
                [
                    Avx(_mm256_permute2f128_pd(ab_even, cd_even, 0x20)),
                    Avx(_mm256_permute2f128_pd(ab_odd, cd_odd, 0x20)),
                    Avx(_mm256_permute2f128_pd(ab_even, cd_even, 0x31)),
                    Avx(_mm256_permute2f128_pd(ab_odd, cd_odd, 0x31)),
                ]
            }
        }
    }

    impl From<f64> for Avx {
        #[inline(always)]
        fn from(v: f64) -> Avx {
            // SAFETY: AVX is present (type invariant: this constructor is
            // reachable only through `run`, see the module comment).
            Avx(unsafe { _mm256_set1_pd(v) })
        }
    }

    macro_rules! avx_op {
        ($tr:ident, $f:ident, $intrinsic:ident) => {
            impl $tr for Avx {
                type Output = Avx;
                #[inline(always)]
                fn $f(self, o: Avx) -> Avx {
                    // SAFETY: AVX is present (type invariant).
                    Avx(unsafe { $intrinsic(self.0, o.0) })
                }
            }
        };
    }

    avx_op!(Add, add, _mm256_add_pd);
    avx_op!(Sub, sub, _mm256_sub_pd);
    avx_op!(Mul, mul, _mm256_mul_pd);
    avx_op!(Div, div, _mm256_div_pd);

    impl Neg for Avx {
        type Output = Avx;
        #[inline(always)]
        fn neg(self) -> Avx {
            // Flipping the sign bit is what scalar negation does.
            // SAFETY: AVX is present (type invariant).
            Avx(unsafe { _mm256_xor_pd(self.0, _mm256_set1_pd(-0.0)) })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{Batch, LANES, LaneOp, Lanes};

    /// Transposes four lanes of distinct values with whichever lane type
    /// runs.
    struct Transpose([[f64; LANES]; LANES]);

    impl LaneOp for Transpose {
        type Output = [[f64; LANES]; LANES];
        fn run<L: Batch>(self) -> Self::Output {
            L::transpose4(self.0.map(|r| L::load(&r))).map(L::to_array)
        }
    }

    /// Both lane types move lane `l` of row `r` to lane `r` of row `l`,
    /// every bit kept (a NaN's payload, −0).
    #[test]
    fn transpose4_moves_every_value_to_its_place() {
        let nan = f64::from_bits(0x7ff8_0000_dead_beef);
        let mut rows = [[0.0; LANES]; LANES];
        for (r, row) in rows.iter_mut().enumerate() {
            for (l, v) in row.iter_mut().enumerate() {
                *v = (r * LANES + l) as f64 + 0.25;
            }
        }
        (rows[1][2], rows[3][0]) = (nan, -0.0);
        let want: [[u64; LANES]; LANES] =
            std::array::from_fn(|r| std::array::from_fn(|l| rows[l][r].to_bits()));
        let bits = |t: [[f64; LANES]; LANES]| t.map(|r| r.map(f64::to_bits));
        assert_eq!(bits(Transpose(rows).run::<Lanes>()), want);
        // AVX where this CPU has it, else the portable lanes again.
        assert_eq!(bits(super::run(Transpose(rows))), want);
    }
}
