//! Four poses at a time. Every lane operation is exactly the scalar IEEE
//! operation (no fused multiply-add: Rust never contracts), so lane results
//! equal one-pose results bit for bit whichever lane type runs.
//!
//! Two lane types implement [`Batch`]: [`Lanes`], plain arrays that compile
//! to SSE2 everywhere, and on x86-64 `Avx`, explicit 256-bit AVX vectors,
//! used only inside `with_avx2` after the CPU was checked. (LLVM's
//! auto-vectorizer left the position kernel scalar, hence the intrinsics.)
//!
//! The module is private to the crate: no code outside it can make an `Avx`
//! value, so no safe public API reaches an instruction the CPU might lack.

use std::ops::{Add, Mul, Neg, Sub};

use super::Scalar;

/// Poses per batch.
pub(crate) const LANES: usize = 4;

/// A lane type the batch loops can run the generated code on.
pub(crate) trait Batch: Scalar {
    /// Loads the first [`LANES`] values of `v`.
    fn load(v: &[f64]) -> Self;
    /// The lanes as an array.
    fn to_array(self) -> [f64; LANES];
    /// Stores the lanes into the first [`LANES`] values of `dst`.
    fn store(self, dst: &mut [f64]);
}

/// Portable lanes: one value per pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Lanes(pub(crate) [f64; LANES]);

impl Batch for Lanes {
    #[inline(always)]
    fn load(v: &[f64]) -> Lanes {
        // Invariant: `v[..LANES]` is exactly LANES long (the slice panics
        // first if `v` were shorter, and batch callers pass whole lanes).
        Lanes(v[..LANES].try_into().expect("4 values"))
    }

    #[inline(always)]
    fn to_array(self) -> [f64; LANES] {
        self.0
    }

    #[inline(always)]
    fn store(self, dst: &mut [f64]) {
        dst[..LANES].copy_from_slice(&self.0);
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

impl Neg for Lanes {
    type Output = Lanes;
    #[inline(always)]
    fn neg(self) -> Lanes {
        Lanes(self.0.map(|v| -v))
    }
}

#[cfg(target_arch = "x86_64")]
pub(crate) use avx::{Avx, with_avx2};

// The only unsafe code of the toolkit: AVX intrinsics, reached only after
// the CPU was checked (`dispatch!`).
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod avx {
    use super::{Batch, LANES};
    use std::arch::x86_64::*;
    use std::ops::{Add, Mul, Neg, Sub};

    /// Four lanes in one AVX register.
    ///
    /// Invariant: values of this type exist only on CPUs with AVX2 — they are
    /// made only by code that [`with_avx2`] runs — so the intrinsics below
    /// are always supported where they execute.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Avx(__m256d);

    impl Batch for Avx {
        #[inline(always)]
        fn load(v: &[f64]) -> Avx {
            // Invariant: `v[..LANES]` is exactly LANES long.
            let v: &[f64; LANES] = v[..LANES].try_into().expect("4 values");
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
        fn store(self, dst: &mut [f64]) {
            // Invariant: `dst[..LANES]` is exactly LANES long.
            let dst: &mut [f64; LANES] = (&mut dst[..LANES]).try_into().expect("4 values");
            // SAFETY: AVX is present (type invariant); `dst` holds 4 values.
            unsafe { _mm256_storeu_pd(dst.as_mut_ptr(), self.0) };
        }
    }

    impl From<f64> for Avx {
        #[inline(always)]
        fn from(v: f64) -> Avx {
            // SAFETY: AVX is present (type invariant).
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

    impl Neg for Avx {
        type Output = Avx;
        #[inline(always)]
        fn neg(self) -> Avx {
            // Flipping the sign bit is what scalar negation does.
            // SAFETY: AVX is present (type invariant).
            Avx(unsafe { _mm256_xor_pd(self.0, _mm256_set1_pd(-0.0)) })
        }
    }

    /// Runs `f` in a function compiled for AVX2, so that the inlined lane
    /// code uses 256-bit registers.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[target_feature(enable = "avx2")]
    pub(crate) unsafe fn with_avx2<R>(f: impl FnOnce() -> R) -> R {
        f()
    }
}

/// Evaluates to `$run::<N, L>(args)` with `L` = `Avx` where the CPU has
/// AVX2, else with `L` = [`Lanes`]. An expression: it never returns from its
/// caller.
macro_rules! dispatch {
    ($run:ident::<$n:ident>($($arg:expr),*)) => {{
        #[cfg(target_arch = "x86_64")]
        let out = if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: AVX2 was just detected.
            #[allow(unsafe_code)]
            unsafe {
                $crate::kernel::lanes::with_avx2(
                    #[inline(always)]
                    || $run::<$n, $crate::kernel::lanes::Avx>($($arg),*),
                )
            }
        } else {
            $run::<$n, $crate::kernel::lanes::Lanes>($($arg),*)
        };
        #[cfg(not(target_arch = "x86_64"))]
        let out = $run::<$n, $crate::kernel::lanes::Lanes>($($arg),*);
        out
    }};
}
pub(crate) use dispatch;
