//! Systematic resampling (Kitagawa 1996; Carpenter, Clifford & Fearnhead 1999).

use super::{Resampler, summarise};
use crate::error::Result;

/// Systematic resampling: one uniform u ~ U[0, 1) and the evenly spaced grid j + 1 − u,
/// j = 0..M, laid over the cumulative weights C scaled to end at M.
///
/// Particle i receives the grid points in (C_{i−1}, C_i], whose number is
/// ⌊C_i + u⌋ − ⌊C_{i−1} + u⌋: always ⌊M wᵢ⌋ or ⌈M wᵢ⌉. Computing these counts in a single pass
/// over the weights avoids the data-dependent inner loop of the textbook merge.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Systematic;

impl Systematic {
    /// The deterministic part: resamples with a given offset `u ∈ [0, 1)` (values outside are
    /// clamped). Weights must already have passed validation.
    ///
    /// The loop is written to be free of unpredictable branches, which dominated its cost: each
    /// particle unconditionally writes its index into the next [`PAD`] slots (a zero-count
    /// particle's writes are overwritten by the next particle, which starts at the same slot), and
    /// only counts above [`PAD`] take a rarely-used extra loop. The buffer carries `PAD` spare
    /// slots during the pass and is truncated to M at the end.
    fn fill(
        weights: &[f64],
        output_size: usize,
        total: f64,
        last_positive: usize,
        u: f64,
        out: &mut Vec<usize>,
    ) {
        let u = u.clamp(0.0, 1.0);
        let scale = output_size as f64 / total;
        // No `clear`: every slot below M is overwritten below, so a reused buffer of length M
        // only needs its PAD spare slots appended, not M zeros written.
        out.resize(output_size + PAD, 0);
        let mut cumulative = 0.0;
        let mut filled = 0usize;
        for (i, &w) in weights.iter().enumerate() {
            cumulative += w;
            let end = floor_index(cumulative * scale + u).min(output_size);
            // `filled ≤ M` and the buffer has M + PAD slots, so this slice always exists.
            if let Some(slots) = out.get_mut(filled..filled + PAD) {
                slots.copy_from_slice(&[i; PAD]);
            }
            if end > filled + PAD
                && let Some(slots) = out.get_mut(filled + PAD..end)
            {
                slots.fill(i);
            }
            // `end` never decreases (the weights are non-negative), but keep `filled` monotone
            // regardless of rounding.
            filled = filled.max(end);
        }
        // Rounding can leave the last grid point just beyond C_N; it belongs to the last particle
        // with positive weight.
        out.truncate(output_size);
        if let Some(slots) = out.get_mut(filled..) {
            slots.fill(last_positive);
        }
    }

    /// Resamples with a caller-chosen offset `u ∈ [0, 1)` instead of a random one (useful to make
    /// the grid explicit, e.g. in tests or for quasi-random offsets).
    ///
    /// # Errors
    /// As [`Resampler::resample`].
    pub fn resample_with_offset(
        &self,
        weights: &[f64],
        output_size: usize,
        u: f64,
        ancestors: &mut Vec<usize>,
    ) -> Result<()> {
        let summary = summarise(weights, output_size)?;
        Self::fill(
            weights,
            output_size,
            summary.total,
            summary.last_positive,
            u,
            ancestors,
        );
        Ok(())
    }
}

/// Slots written unconditionally per particle (see `Systematic::fill`).
const PAD: usize = 4;

/// ⌊y⌋ for y ≥ 0, as an index.
///
/// `f64::floor` is a libm call on baseline x86-64 (no SSE4.1 `roundsd`), and float-to-`usize`
/// conversions need several fix-up instructions; a truncation through `i64` is one instruction
/// plus a saturation check, and equals the floor for non-negative values.
#[inline(always)]
fn floor_index(y: f64) -> usize {
    (y as i64).max(0) as usize
}

impl Resampler for Systematic {
    fn resample<R: rand::Rng + ?Sized>(
        &self,
        normalized_weights: &[f64],
        output_size: usize,
        rng: &mut R,
        ancestors: &mut Vec<usize>,
    ) -> Result<()> {
        let summary = summarise(normalized_weights, output_size)?;
        let u = rng.random::<f64>();
        Self::fill(
            normalized_weights,
            output_size,
            summary.total,
            summary.last_positive,
            u,
            ancestors,
        );
        Ok(())
    }
}
