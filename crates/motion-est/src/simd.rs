//! Run-time selection of the instruction set for the hot loops.
//!
//! The loops are written on plain `f32` arrays (`[f32; 8]` lanes, separate products and sums in
//! a fixed order), which the compiler vectorises; [`simd`] compiles them once per instruction set
//! (AVX-512, AVX2 + FMA, baseline) through pulp's run-time dispatch and runs the best one this CPU
//! has. Products and sums are never fused, so every instruction set gives the same bits.

/// Runs `f` compiled for the best instruction set of this CPU. `f` and what it calls must be
/// inlined into it (mark them `#[inline(always)]`, the closure too) to benefit.
#[inline(always)]
pub(crate) fn simd<R>(f: impl FnOnce() -> R) -> R {
    pulp::Arch::new().dispatch(f)
}
