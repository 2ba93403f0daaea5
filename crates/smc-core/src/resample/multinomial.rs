//! Multinomial resampling in O(N + M) via sorted uniforms.

use rand::SeedableRng;
use rand_distr::{Distribution, Exp1};
use rand_pcg::Pcg64Mcg;

use super::{Resampler, WeightSummary, prepare};
use crate::error::Result;

/// Multinomial resampling: M independent draws from the categorical distribution of the weights.
///
/// Drawing M uniforms and searching each in the cumulative weights costs O(M log N); sorting them
/// first and merging costs O(M log M). Instead the uniforms are generated already sorted, by
/// exponential spacings: with E₁..E_{M+1} i.i.d. Exp(1) and S_j = E₁ + … + E_j, the vector
/// (S₁/S_{M+1}, …, S_M/S_{M+1}) has the law of M sorted uniforms. S_{M+1} is needed before the
/// first comparison, so the exponentials are drawn twice from a local generator seeded by `rng`
/// (cheaper than a scratch buffer of M floats, and nothing to allocate).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Multinomial;

impl Resampler for Multinomial {
    fn resample<R: rand::Rng + ?Sized>(
        &self,
        normalized_weights: &[f64],
        output_size: usize,
        rng: &mut R,
        ancestors: &mut Vec<usize>,
    ) -> Result<()> {
        let summary = prepare(normalized_weights, output_size, ancestors)?;
        fill_multinomial(normalized_weights, summary, output_size, rng, ancestors);
        Ok(())
    }
}

/// Fills the slots of `ancestors` still missing up to `output_size` (all of them after
/// [`super::prepare`]) with multinomial draws from `weights`, summarised by `summary`; draws
/// nothing from `rng` when none is missing.
pub(crate) fn fill_multinomial<R: rand::Rng + ?Sized>(
    weights: &[f64],
    summary: WeightSummary,
    output_size: usize,
    rng: &mut R,
    ancestors: &mut Vec<usize>,
) {
    let missing = output_size.saturating_sub(ancestors.len());
    if missing > 0 {
        merge_sorted_uniforms(
            weights.iter().copied(),
            summary.total,
            summary.last_positive,
            missing,
            rng,
            ancestors,
        );
    }
}

/// Appends `count` multinomial draws from `weights` (total `total`, last positive index `last`) to
/// `out`, by merging sorted uniforms from exponential spacings with the cumulative weights.
pub(crate) fn merge_sorted_uniforms<R: rand::Rng + ?Sized>(
    mut weights: impl Iterator<Item = f64>,
    total: f64,
    last: usize,
    count: usize,
    rng: &mut R,
    out: &mut Vec<usize>,
) {
    let local = Pcg64Mcg::seed_from_u64(rng.random::<u64>());
    // First pass: S_{M+1}.
    let mut first = local.clone();
    let spacing_total: f64 = (0..=count)
        .map(|_| -> f64 { Exp1.sample(&mut first) })
        .sum();
    // Second pass: the same exponentials again, scaled so that the uniforms live on [0, total).
    let mut second = local;
    let scale = total / spacing_total;
    let mut partial = 0.0;
    let mut i = 0usize;
    let mut cumulative = weights.next().unwrap_or(0.0);
    for _ in 0..count {
        let e: f64 = Exp1.sample(&mut second);
        partial += e;
        let u = partial * scale;
        while cumulative <= u && i < last {
            i += 1;
            cumulative += weights.next().unwrap_or(0.0);
        }
        out.push(i);
    }
}
