//! The Srinivasan sampling process (SSP) resampler (Gerber, Chopin & Whiteley 2019, after
//! Srinivasan 2001).

use super::multinomial::fill_multinomial;
use super::{Resampler, prepare, push_floor_copies};
use crate::error::Result;

/// SSP resampling: particle i first receives ⌊M wᵢ⌋ copies; the fractional parts δᵢ are then
/// settled pairwise so that each particle ends with ⌊M wᵢ⌋ or ⌈M wᵢ⌉ copies and the expected
/// count stays M wᵢ.
///
/// One particle with an unsettled fraction δ_a is kept "active". Meeting the next particle i with
/// fraction δᵢ, s = δ_a + δᵢ:
/// - s < 1: with probability δ_a/s the active particle takes s and i is settled at 0, otherwise i
///   takes s (and becomes active) and a is settled at 0;
/// - s ≥ 1: with probability (1 − δᵢ)/(2 − s) a is settled at 1 (one extra copy) and i carries
///   s − 1, otherwise i gets the extra copy and a carries s − 1.
///
/// Each move keeps the expectation of δ for both particles unchanged, which makes the scheme unbiased; like
/// systematic resampling it never goes beyond ⌈M wᵢ⌉, but unlike it the counts of distant
/// particles are negatively associated rather than tied to one uniform. O(N), one uniform per
/// pair. The floor copies come first in the output, each extra copy when it is settled.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Ssp;

impl Resampler for Ssp {
    fn resample<R: rand::Rng + ?Sized>(
        &self,
        normalized_weights: &[f64],
        output_size: usize,
        rng: &mut R,
        ancestors: &mut Vec<usize>,
    ) -> Result<()> {
        let summary = prepare(normalized_weights, output_size, ancestors)?;
        let scale = output_size as f64 / summary.total;
        let push = |out: &mut Vec<usize>, i: usize| {
            if out.len() < output_size {
                out.push(i);
            }
        };
        let mut active: Option<(usize, f64)> = None;
        for (i, &w) in normalized_weights.iter().enumerate() {
            let delta = push_floor_copies(ancestors, i, w * scale, output_size);
            if delta <= 0.0 {
                continue;
            }
            let Some((a, delta_a)) = active else {
                active = Some((i, delta));
                continue;
            };
            let s = delta_a + delta;
            let u: f64 = rng.random();
            active = if s < 1.0 {
                if u * s < delta_a {
                    Some((a, s))
                } else {
                    Some((i, s))
                }
            } else {
                let (winner, carrier) = if u * (2.0 - s) < 1.0 - delta {
                    (a, i)
                } else {
                    (i, a)
                };
                push(ancestors, winner);
                (s > 1.0).then_some((carrier, s - 1.0))
            };
        }
        // The fractions sum to an integer, so the last active fraction is 0 or 1 up to rounding.
        if let Some((a, delta_a)) = active
            && delta_a > 0.5
        {
            push(ancestors, a);
        }
        // Slots can be left only through rounding: fill them with multinomial draws.
        fill_multinomial(normalized_weights, summary, output_size, rng, ancestors);
        Ok(())
    }
}
