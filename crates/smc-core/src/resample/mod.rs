//! Resampling: turn a weighted set into ancestor indices (Odobez Fig. 2, step 3; Wu Fig. 6).
//!
//! Every scheme takes normalised (or merely non-negative) weights w₁..w_N and an output size M,
//! and writes M ancestor indices into a caller-owned buffer. All are unbiased: the expected
//! number of offspring of particle i is M·wᵢ/Σw. They differ in variance and cost:
//!
//! | scheme | offspring count of particle i (L = M wᵢ / Σw) | cost |
//! |---|---|---|
//! | [`Multinomial`] | Binomial(M, wᵢ/Σw): anything in 0..=M | O(N + M), sorted uniforms by exponential spacings |
//! | [`Residual`] | ⌊L⌋ + a multinomial share of the remainders: at least ⌊L⌋ | O(N + M) |
//! | [`Stratified`] | between ⌊L⌋ − 1 and ⌈L⌉ + 1 (one uniform per stratum; the two strata at the ends of particle i's interval may or may not land in it) | O(N + M) |
//! | [`Systematic`] | ⌊L⌋ or ⌈L⌉, always | O(N + M), one uniform |
//! | [`Ssp`] | ⌊L⌋ or ⌈L⌉, always, negatively associated across particles | O(N + M), one uniform per pair of fractional parts |
//!
//! The guarantees hold in exact arithmetic; in floating point the cumulative sums carry a relative
//! rounding error of order N·ε, which can move a count across an integer only when L is within
//! about N·ε·M of one.

mod multinomial;
mod residual;
mod ssp;
mod stratified;
mod systematic;

pub use multinomial::Multinomial;
pub use residual::Residual;
pub use ssp::Ssp;
pub use stratified::Stratified;
pub use systematic::Systematic;

use crate::error::{Degeneracy, Error, Result};

/// A resampling scheme: writes `output_size` ancestor indices drawn according to the weights.
pub trait Resampler {
    /// Fills `ancestors` (cleared first) with `output_size` indices into `normalized_weights`.
    ///
    /// The weights need only be non-negative and finite with a positive sum; they are treated as
    /// if divided by their sum. Particles with zero weight never get offspring.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for an empty weight slice or `output_size == 0`;
    /// [`Error::InvalidWeights`] for a negative, infinite or NaN weight or an all-zero slice.
    fn resample<R: rand::Rng + ?Sized>(
        &self,
        normalized_weights: &[f64],
        output_size: usize,
        rng: &mut R,
        ancestors: &mut Vec<usize>,
    ) -> Result<()>;

    /// Allocating convenience twin of [`Resampler::resample`].
    ///
    /// # Errors
    /// As [`Resampler::resample`].
    fn resample_vec<R: rand::Rng + ?Sized>(
        &self,
        normalized_weights: &[f64],
        output_size: usize,
        rng: &mut R,
    ) -> Result<Vec<usize>> {
        let mut ancestors = Vec::with_capacity(output_size);
        self.resample(normalized_weights, output_size, rng, &mut ancestors)?;
        Ok(ancestors)
    }
}

/// The built-in schemes, as a value (for settings files and command lines).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum ResamplingScheme {
    /// [`Multinomial`].
    Multinomial,
    /// [`Residual`].
    Residual,
    /// [`Stratified`].
    Stratified,
    /// [`Systematic`], the default: floor/ceil counts and the cheapest scheme.
    #[default]
    Systematic,
    /// [`Ssp`] (Srinivasan sampling process).
    Ssp,
}

impl ResamplingScheme {
    /// All built-in schemes.
    pub const ALL: [Self; 5] = [
        Self::Multinomial,
        Self::Residual,
        Self::Stratified,
        Self::Systematic,
        Self::Ssp,
    ];

    /// Lower-case name, as used in settings files.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Multinomial => "multinomial",
            Self::Residual => "residual",
            Self::Stratified => "stratified",
            Self::Systematic => "systematic",
            Self::Ssp => "ssp",
        }
    }
}

impl Resampler for ResamplingScheme {
    fn resample<R: rand::Rng + ?Sized>(
        &self,
        normalized_weights: &[f64],
        output_size: usize,
        rng: &mut R,
        ancestors: &mut Vec<usize>,
    ) -> Result<()> {
        match self {
            Self::Multinomial => {
                Multinomial.resample(normalized_weights, output_size, rng, ancestors)
            }
            Self::Residual => Residual.resample(normalized_weights, output_size, rng, ancestors),
            Self::Stratified => {
                Stratified.resample(normalized_weights, output_size, rng, ancestors)
            }
            Self::Systematic => {
                Systematic.resample(normalized_weights, output_size, rng, ancestors)
            }
            Self::Ssp => Ssp.resample(normalized_weights, output_size, rng, ancestors),
        }
    }
}

/// What every scheme needs to know about its input, gathered in one validating pass.
#[derive(Debug, Clone, Copy)]
pub(crate) struct WeightSummary {
    /// Σ wᵢ (positive).
    pub total: f64,
    /// The largest index with a positive weight: rounding must never hand offspring past it.
    pub last_positive: usize,
}

/// Checks the arguments every scheme shares: at least one weight and at least one output slot.
pub(crate) fn check_arguments(weights: &[f64], output_size: usize) -> Result<()> {
    if weights.is_empty() {
        return Err(Error::InvalidSetting {
            name: "weights",
            reason: "cannot resample from zero particles".into(),
        });
    }
    if output_size == 0 {
        return Err(Error::InvalidSetting {
            name: "output_size",
            reason: "must be at least 1".into(),
        });
    }
    Ok(())
}

/// The common start of [`Resampler::resample`]: validates and summarises the weights (leaving
/// `ancestors` untouched on error), then empties `ancestors` and reserves room for `output_size`
/// indices.
pub(crate) fn prepare(
    weights: &[f64],
    output_size: usize,
    ancestors: &mut Vec<usize>,
) -> Result<WeightSummary> {
    let summary = summarise(weights, output_size)?;
    ancestors.clear();
    ancestors.reserve(output_size);
    Ok(summary)
}

/// Validates the arguments of [`Resampler::resample`] and summarises the weights.
pub(crate) fn summarise(weights: &[f64], output_size: usize) -> Result<WeightSummary> {
    check_arguments(weights, output_size)?;
    // One branch-free pass with four independent accumulators, so that the additions are not one
    // serial dependency chain. A NaN or +∞ shows in the sum, a negative value (−∞ included) in
    // the minimum; the slow scan below only runs on bad input. (Testing each weight with
    // comparisons instead compiles to an integer classification of its bits that cost more than
    // the rest of systematic resampling.)
    let mut sums = [0.0f64; 4];
    let mut mins = [0.0f64; 4];
    let chunks = weights.chunks_exact(4);
    let rest = chunks.remainder();
    for c in chunks {
        for k in 0..4 {
            sums[k] += c[k];
            mins[k] = mins[k].min(c[k]);
        }
    }
    for &w in rest {
        sums[0] += w;
        mins[0] = mins[0].min(w);
    }
    let total = (sums[0] + sums[1]) + (sums[2] + sums[3]);
    let min = mins[0].min(mins[1]).min(mins[2].min(mins[3]));
    let bad = !total.is_finite() || min < 0.0;
    let valid = |w: f64| (0.0..f64::INFINITY).contains(&w);
    if bad {
        let reason = match weights.iter().enumerate().find(|&(_, &w)| !valid(w)) {
            Some((index, &value)) if value.is_nan() => Degeneracy::NotANumber { index },
            Some((index, &value)) => Degeneracy::OutOfRange { index, value },
            // Every weight is valid but the sum overflowed.
            None => Degeneracy::OutOfRange {
                index: 0,
                value: total,
            },
        };
        return Err(Error::InvalidWeights { reason });
    }
    if total <= 0.0 {
        return Err(Error::InvalidWeights {
            reason: Degeneracy::AllZero,
        });
    }
    Ok(WeightSummary {
        total,
        last_positive: last_positive(weights),
    })
}

/// The largest index with a positive weight (0 if there is none).
pub(crate) fn last_positive(weights: &[f64]) -> usize {
    weights.iter().rposition(|&w| w > 0.0).unwrap_or(0)
}

/// Appends the ⌊`expected`⌋ deterministic copies of particle `i` that residual and SSP
/// resampling start from, and returns the fractional part `expected` − ⌊`expected`⌋ left to
/// settle at random. Σ⌊M wᵢ⌋ ≤ M in exact arithmetic; rounding could overshoot by one, so the
/// copies are capped to keep `ancestors` within `output_size`.
pub(crate) fn push_floor_copies(
    ancestors: &mut Vec<usize>,
    i: usize,
    expected: f64,
    output_size: usize,
) -> f64 {
    let floor = expected.floor();
    let copies = (floor as usize).min(output_size.saturating_sub(ancestors.len()));
    ancestors.extend(std::iter::repeat_n(i, copies));
    expected - floor
}

/// Offspring count of each of `n` particles given ancestor indices (out-of-range ones ignored).
#[must_use]
pub fn offspring_counts(ancestors: &[usize], n: usize) -> Vec<usize> {
    let mut counts = vec![0; n];
    for &a in ancestors {
        if let Some(c) = counts.get_mut(a) {
            *c += 1;
        }
    }
    counts
}

/// Number of distinct values in `ancestors`, all below `n`; `seen` is a scratch buffer.
pub(crate) fn count_distinct(ancestors: &[usize], n: usize, seen: &mut Vec<bool>) -> usize {
    seen.clear();
    seen.resize(n, false);
    let mut distinct = 0;
    for &a in ancestors {
        if let Some(s) = seen.get_mut(a)
            && !*s
        {
            *s = true;
            distinct += 1;
        }
    }
    distinct
}

#[cfg(test)]
mod tests;
