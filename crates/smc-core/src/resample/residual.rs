//! Residual resampling (Liu & Chen 1998).

use super::multinomial::{fill_multinomial, merge_sorted_uniforms};
use super::{Resampler, prepare, push_floor_copies};
use crate::error::Result;

/// Residual resampling: particle i first receives ⌊M wᵢ⌋ copies deterministically; the remaining
/// R = M − Σ⌊M wᵢ⌋ slots are filled by multinomial draws with probabilities proportional to the
/// remainders M wᵢ − ⌊M wᵢ⌋ (O(N + R), sorted uniforms as in [`super::Multinomial`]).
///
/// The deterministic copies come first in the output, then the residual draws.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Residual;

impl Resampler for Residual {
    fn resample<R: rand::Rng + ?Sized>(
        &self,
        normalized_weights: &[f64],
        output_size: usize,
        rng: &mut R,
        ancestors: &mut Vec<usize>,
    ) -> Result<()> {
        let summary = prepare(normalized_weights, output_size, ancestors)?;
        let scale = output_size as f64 / summary.total;
        let remainder = |w: f64| {
            let expected = w * scale;
            expected - expected.floor()
        };
        let mut remainder_total = 0.0;
        let mut last_remainder = None;
        for (i, &w) in normalized_weights.iter().enumerate() {
            let r = push_floor_copies(ancestors, i, w * scale, output_size);
            if r > 0.0 {
                remainder_total += r;
                last_remainder = Some(i);
            }
        }
        let missing = output_size - ancestors.len();
        if missing > 0
            && remainder_total > 0.0
            && let Some(last) = last_remainder
        {
            merge_sorted_uniforms(
                normalized_weights.iter().map(|&w| remainder(w)),
                remainder_total,
                last,
                missing,
                rng,
                ancestors,
            );
        }
        // Slots can be left only through rounding (all remainders zero yet slots left): fall
        // back to plain multinomial draws.
        fill_multinomial(normalized_weights, summary, output_size, rng, ancestors);
        Ok(())
    }
}
