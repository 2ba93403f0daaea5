//! Stratified resampling (Kitagawa 1996).

use super::{Resampler, prepare};
use crate::error::Result;

/// Stratified resampling: one independent uniform in each stratum [j/M, (j+1)/M), j = 0..M, merged
/// in a single pass with the cumulative weights.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stratified;

impl Resampler for Stratified {
    fn resample<R: rand::Rng + ?Sized>(
        &self,
        normalized_weights: &[f64],
        output_size: usize,
        rng: &mut R,
        ancestors: &mut Vec<usize>,
    ) -> Result<()> {
        let summary = prepare(normalized_weights, output_size, ancestors)?;
        // Work in units of strata: cumulative weights scaled so that they end at M.
        let scale = output_size as f64 / summary.total;
        let last = summary.last_positive;
        let mut weights = normalized_weights.iter().copied();
        let mut i = 0usize;
        let mut cumulative = weights.next().unwrap_or(0.0) * scale;
        for j in 0..output_size {
            let u = j as f64 + rng.random::<f64>();
            // Particle i owns [C_{i−1}, C_i); advance past every particle whose interval ends at or
            // before u (zero-weight ones included), but never beyond the last positive weight.
            while cumulative <= u && i < last {
                i += 1;
                cumulative += weights.next().unwrap_or(0.0) * scale;
            }
            ancestors.push(i);
        }
        Ok(())
    }
}
