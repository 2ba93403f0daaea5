//! Residual resampling (Liu & Chen 1998).

use super::multinomial::merge_sorted_uniforms;
use super::{Resampler, summarise};
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
        let summary = summarise(normalized_weights, output_size)?;
        let scale = output_size as f64 / summary.total;
        let remainder = |w: f64| {
            let expected = w * scale;
            expected - expected.floor()
        };
        ancestors.clear();
        ancestors.reserve(output_size);
        let mut remainder_total = 0.0;
        let mut last_remainder = None;
        for (i, &w) in normalized_weights.iter().enumerate() {
            let expected = w * scale;
            let copies = expected.floor();
            // Σ⌊M wᵢ⌋ ≤ M in exact arithmetic; rounding could overshoot by one, so cap.
            let copies = (copies as usize).min(output_size - ancestors.len());
            ancestors.extend(std::iter::repeat_n(i, copies));
            let r = expected - expected.floor();
            if r > 0.0 {
                remainder_total += r;
                last_remainder = Some(i);
            }
        }
        let missing = output_size - ancestors.len();
        if missing > 0 {
            match last_remainder {
                Some(last) if remainder_total > 0.0 => merge_sorted_uniforms(
                    normalized_weights.iter().map(|&w| remainder(w)),
                    remainder_total,
                    last,
                    missing,
                    rng,
                    ancestors,
                ),
                // Only reachable through rounding (all remainders zero yet slots left): fall back
                // to plain multinomial draws.
                _ => merge_sorted_uniforms(
                    normalized_weights.iter().copied(),
                    summary.total,
                    summary.last_positive,
                    missing,
                    rng,
                    ancestors,
                ),
            }
        }
        Ok(())
    }
}
