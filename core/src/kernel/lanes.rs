//! Four `f64` lanes with element-wise arithmetic. Each operation is exactly
//! the scalar IEEE operation per lane (no fused multiply-add: Rust never
//! contracts), so lane results equal one-pose results bit for bit; LLVM turns
//! the element-wise loops into SSE2 or, inside [`with_avx2`], AVX2 vectors.

use std::ops::{Add, Mul, Neg, Sub};

/// Poses per SIMD batch.
pub const LANES: usize = 4;

/// One value per pose of a batch.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(align(32))]
pub struct Lanes(pub [f64; LANES]);

impl Lanes {
    /// Loads the first [`LANES`] values of `v`.
    #[inline(always)]
    pub fn load(v: &[f64]) -> Lanes {
        Lanes(std::array::from_fn(|l| v[l]))
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

/// Runs `f` in a function compiled for AVX2, so that inlined lane code is
/// 256 bits wide.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn with_avx2<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// Runs a batch body with AVX2 where the CPU has it, else as compiled.
macro_rules! dispatch {
    ($body:expr) => {{
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: AVX2 was just detected.
                return unsafe {
                    $crate::kernel::lanes::with_avx2(
                        #[inline(always)]
                        || $body,
                    )
                };
            }
        }
        $body
    }};
}
pub(crate) use dispatch;
