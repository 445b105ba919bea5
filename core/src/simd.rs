//! A closure compiled for AVX2 where the CPU has it: 256-bit registers for
//! the loops inlined into it, with the same bits (every lane operation is
//! the scalar IEEE operation; no fused multiply-add — AVX2 does not enable
//! it, and Rust never contracts).

/// Runs `f` in a function compiled for AVX2 when the CPU has it (a cached
/// flag), else as it is. `f` should be an `#[inline(always)]` closure, and
/// the loops it runs inlined into it, or they keep the baseline's
/// instructions.
#[inline(always)]
#[allow(unsafe_code)] // SIMD: the AVX2 copy of a safe closure
pub(crate) fn with_avx2<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: `avx2` needs AVX2, which the CPU was just found to have.
        return unsafe { avx2(f) };
    }
    f()
}

/// `f()` compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn avx2<R>(f: impl FnOnce() -> R) -> R {
    f()
}
