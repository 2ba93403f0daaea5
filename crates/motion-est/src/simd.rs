//! Run-time selection of the instruction set for the hot loops.
//!
//! The loops are written on plain `f32` arrays (`[f32; 8]` lanes, separate products and sums in
//! a fixed order), which the compiler vectorises; [`simd`] compiles them once per instruction set
//! (AVX-512, AVX2 + FMA, baseline) through pulp's run-time dispatch and runs the best one this CPU
//! has. Products and sums are never fused, so every instruction set gives the same bits (tested
//! against the baseline below).

/// Runs `f` compiled for the best instruction set of this CPU. `f` and what it calls must be
/// inlined into it (mark them `#[inline(always)]`, the closure too) to benefit.
#[inline(always)]
pub(crate) fn simd<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(test)]
    if tests::BASELINE.get() {
        tests::BASELINE_CALLS.set(tests::BASELINE_CALLS.get() + 1);
        return pulp::Arch::Scalar.dispatch(f);
    }
    pulp::Arch::new().dispatch(f)
}

#[cfg(test)]
pub(crate) mod tests {
    use std::cell::Cell;

    thread_local! {
        /// Forces the baseline instruction set on this thread (tests only).
        pub(crate) static BASELINE: Cell<bool> = const { Cell::new(false) };
        /// Dispatches that took the forced baseline.
        pub(crate) static BASELINE_CALLS: Cell<usize> = const { Cell::new(0) };
    }

    /// Runs `f` with the baseline instruction set forced on this thread; also returns how many
    /// dispatches took it (so that a test can check it exercised the dispatched loops).
    pub(crate) fn on_baseline<R>(f: impl FnOnce() -> R) -> (R, usize) {
        BASELINE_CALLS.set(0);
        BASELINE.set(true);
        let r = f();
        BASELINE.set(false);
        (r, BASELINE_CALLS.get())
    }
}
