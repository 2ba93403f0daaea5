//! Systematic resampling (Kitagawa 1996; Carpenter, Clifford & Fearnhead 1999).

use super::{Resampler, check_arguments, last_positive, summarise};
use crate::error::Result;

/// Systematic resampling: one uniform u ~ U[0, 1) and the evenly spaced grid j + 1 − u,
/// j = 0..M, laid over the cumulative weights C scaled to end at M.
///
/// Particle i receives the grid points in (C_{i−1}, C_i], whose number is
/// ⌊C_i + u⌋ − ⌊C_{i−1} + u⌋: always ⌊M wᵢ⌋ or ⌈M wᵢ⌉. Computing these counts in a single pass
/// over the weights avoids the data-dependent inner loop of the textbook merge.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Systematic;

/// Slots written unconditionally per particle (see `Systematic::fill`). Four covers the offspring
/// count of most particles in practice; measured 2, 3, 4, 6 and 8, four was fastest.
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

/// What one pass of `Systematic::fill` saw of the weights.
struct PassSummary {
    /// The final cumulative weight Σwᵢ (NaN or ∞ if a weight was).
    total: f64,
    /// The smallest weight (negative if one was).
    min: f64,
    /// Slots filled by the pass (rounding can leave the last ones).
    filled: usize,
}

/// Largest relative difference between the assumed total 1 and the actual sum of the weights
/// for which the single pass is kept. Normalised weights sum to 1 within about N·ε (2e-10 at
/// N = 10⁶); the grid then extends past C_N by at most M·1e-9, which the tail fill absorbs.
const NORMALISED_TOLERANCE: f64 = 1e-9;

impl Systematic {
    /// One pass: resamples with offset `u ∈ [0, 1)` (clamped) and cumulative weights scaled by
    /// M / `total`, and reports what it saw of the weights so that the caller can validate them
    /// afterwards. Never panics, whatever the weights; the output is meaningful only for valid
    /// ones.
    ///
    /// The loop is written to be free of unpredictable branches, which dominated its cost: each
    /// particle unconditionally writes its index into the next `PAD` slots (a zero-count
    /// particle's writes are overwritten by the next particle, which starts at the same slot), and
    /// only counts above `PAD` take a rarely-used extra loop. The buffer carries `PAD` spare
    /// slots during the pass and is truncated to M at the end.
    fn fill(
        weights: &[f64],
        output_size: usize,
        total: f64,
        u: f64,
        out: &mut Vec<usize>,
    ) -> PassSummary {
        let u = u.clamp(0.0, 1.0);
        let scale = output_size as f64 / total;
        // No `clear`: every slot below M is overwritten below, so a reused buffer of length M
        // only needs its PAD spare slots appended, not M zeros written.
        out.resize(output_size + PAD, 0);
        let mut cumulative = 0.0;
        let mut min = 0.0f64;
        let mut filled = 0usize;
        for (i, &w) in weights.iter().enumerate() {
            cumulative += w;
            min = min.min(w);
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
            // `end` never decreases for non-negative weights; keep `filled` monotone regardless.
            filled = filled.max(end);
        }
        out.truncate(output_size);
        PassSummary {
            total: cumulative,
            min,
            filled,
        }
    }

    /// Validates, then resamples with offset `u`. Normalised weights (the common case) are read
    /// once: the pass assumes Σw = 1 and checks the weights as it goes; only weights that turn
    /// out invalid or unnormalised are read again.
    fn run(weights: &[f64], output_size: usize, u: f64, out: &mut Vec<usize>) -> Result<()> {
        check_arguments(weights, output_size)?;
        let mut pass = Self::fill(weights, output_size, 1.0, u, out);
        let valid = pass.total.is_finite() && pass.total > 0.0 && pass.min >= 0.0;
        if !valid || (pass.total - 1.0).abs() > NORMALISED_TOLERANCE {
            let summary = summarise(weights, output_size)?;
            pass = Self::fill(weights, output_size, summary.total, u, out);
        }
        // Rounding can leave the last grid point just beyond C_N; it belongs to the last particle
        // with positive weight.
        if pass.filled < output_size
            && let Some(slots) = out.get_mut(pass.filled..)
        {
            slots.fill(last_positive(weights));
        }
        Ok(())
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
        Self::run(weights, output_size, u, ancestors)
    }
}

impl Resampler for Systematic {
    fn resample<R: rand::Rng + ?Sized>(
        &self,
        normalized_weights: &[f64],
        output_size: usize,
        rng: &mut R,
        ancestors: &mut Vec<usize>,
    ) -> Result<()> {
        let u = rng.random::<f64>();
        Self::run(normalized_weights, output_size, u, ancestors)
    }
}
