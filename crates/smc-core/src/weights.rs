//! Log-domain weight arithmetic: log-sum-exp normalisation, effective sample size.
//!
//! Importance weights of a particle filter span hundreds of orders of magnitude (a contour
//! likelihood is a product over many measurement lines), so they are kept as logarithms and only
//! exponentiated after the largest one has been subtracted.

use crate::error::Degeneracy;

/// log Σᵢ exp(aᵢ), computed without overflow by factoring out the maximum.
///
/// Returns −∞ for an empty slice or when every entry is −∞. A NaN anywhere gives NaN; a +∞ gives
/// +∞ (callers that must reject those use [`normalize_log_weights`]).
///
/// # Examples
/// ```
/// let lse = smc_core::weights::log_sum_exp(&[1000.0, 1000.0]);
/// assert!((lse - (1000.0 + 2f64.ln())).abs() < 1e-12);
/// ```
#[must_use]
pub fn log_sum_exp(values: &[f64]) -> f64 {
    let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if values.iter().any(|v| v.is_nan()) {
        return f64::NAN;
    }
    if max.is_infinite() {
        return max;
    }
    let sum: f64 = values.iter().map(|&v| (v - max).exp()).sum();
    max + sum.ln()
}

/// Checks log weights for NaN and +∞ (in that order of scanning) and returns their maximum.
///
/// # Errors
/// The first NaN or +∞ found, or [`Degeneracy::AllZero`] when every entry is −∞ (or the slice is
/// empty).
pub fn checked_max(log_weights: &[f64]) -> Result<f64, Degeneracy> {
    let mut max = f64::NEG_INFINITY;
    for (index, &v) in log_weights.iter().enumerate() {
        if v.is_nan() {
            return Err(Degeneracy::NotANumber { index });
        }
        if v == f64::INFINITY {
            return Err(Degeneracy::PositiveInfinity { index });
        }
        max = max.max(v);
    }
    if max == f64::NEG_INFINITY {
        return Err(Degeneracy::AllZero);
    }
    Ok(max)
}

/// Normalises `log_weights` in place so that Σ exp = 1, writes the linear weights into `weights`,
/// and returns the log of the sum before normalisation (the log-sum-exp).
///
/// `weights` is resized to `log_weights.len()`; nothing is changed when an error is returned.
///
/// # Errors
/// Any NaN or +∞, or every entry −∞ (see [`checked_max`]).
pub fn normalize_log_weights(
    log_weights: &mut [f64],
    weights: &mut Vec<f64>,
) -> Result<f64, Degeneracy> {
    let max = checked_max(log_weights)?;
    weights.clear();
    weights.extend(log_weights.iter().map(|&v| (v - max).exp()));
    let sum: f64 = weights.iter().sum();
    // sum ≥ 1 because the maximum contributes exp(0); the logarithm is finite.
    let lse = max + sum.ln();
    let inv = 1.0 / sum;
    for (lw, w) in log_weights.iter_mut().zip(weights.iter_mut()) {
        *lw -= lse;
        *w *= inv;
    }
    Ok(lse)
}

/// Effective sample size (Σwᵢ)² / Σwᵢ² of linear weights (normalised or not).
///
/// It is N for uniform weights and 1 when one particle holds all the mass; 0 for an empty or
/// all-zero slice.
///
/// # Examples
/// ```
/// assert!((smc_core::weights::effective_sample_size(&[0.25; 4]) - 4.0).abs() < 1e-12);
/// ```
#[must_use]
pub fn effective_sample_size(weights: &[f64]) -> f64 {
    let (sum, sum_sq) = weights
        .iter()
        .fold((0.0, 0.0), |(s, q), &w| (s + w, q + w * w));
    if sum_sq > 0.0 {
        sum * sum / sum_sq
    } else {
        0.0
    }
}

/// Index and value of the largest weight (the first one on ties); `None` for an empty slice.
#[must_use]
pub fn argmax(weights: &[f64]) -> Option<(usize, f64)> {
    let mut best: Option<(usize, f64)> = None;
    for (i, &w) in weights.iter().enumerate() {
        if best.is_none_or(|(_, b)| w > b) {
            best = Some((i, w));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use proptest::prelude::*;

    #[test]
    fn log_sum_exp_survives_huge_and_tiny_values() {
        assert_relative_eq!(log_sum_exp(&[-1e4, -1e4]), -1e4 + 2f64.ln(), epsilon = 1e-9);
        assert_relative_eq!(log_sum_exp(&[0.0, f64::NEG_INFINITY]), 0.0);
        assert_eq!(log_sum_exp(&[]), f64::NEG_INFINITY);
        assert!(log_sum_exp(&[0.0, f64::NAN]).is_nan());
    }

    #[test]
    fn normalisation_reports_each_degeneracy() {
        let mut w = Vec::new();
        let mut all_neg = vec![f64::NEG_INFINITY; 3];
        assert_eq!(
            normalize_log_weights(&mut all_neg, &mut w),
            Err(Degeneracy::AllZero)
        );
        let mut nan = vec![0.0, f64::NAN, 1.0];
        assert_eq!(
            normalize_log_weights(&mut nan, &mut w),
            Err(Degeneracy::NotANumber { index: 1 })
        );
        let mut inf = vec![0.0, 1.0, f64::INFINITY];
        assert_eq!(
            normalize_log_weights(&mut inf, &mut w),
            Err(Degeneracy::PositiveInfinity { index: 2 })
        );
        // Nothing was modified by the failed calls.
        assert_eq!(inf[..2], [0.0, 1.0]);
    }

    #[test]
    fn normalisation_matches_direct_computation() {
        let mut lw = vec![0.0, 2f64.ln(), f64::NEG_INFINITY, 5f64.ln()];
        let mut w = Vec::new();
        let lse = normalize_log_weights(&mut lw, &mut w).unwrap();
        assert_relative_eq!(lse, 8f64.ln(), epsilon = 1e-14);
        for (got, want) in w.iter().zip([1.0 / 8.0, 2.0 / 8.0, 0.0, 5.0 / 8.0]) {
            assert_relative_eq!(*got, want, epsilon = 1e-15);
        }
        assert_relative_eq!(effective_sample_size(&w), 1.0 / (1.0 + 4.0 + 25.0) * 64.0);
        assert_eq!(argmax(&w), Some((3, 5.0 / 8.0)));
    }

    proptest! {
        /// Normalised weights sum to one within 1e-12, whatever the spread of the log weights
        /// (up to 1400 nats, far beyond what exp can represent directly) and with −∞ entries.
        #[test]
        fn normalised_weights_sum_to_one(
            raw in prop::collection::vec(
                prop_oneof![9 => -700.0f64..700.0, 1 => Just(f64::NEG_INFINITY)], 1..500),
            anchor in -700.0f64..700.0,
        ) {
            let mut lw = raw;
            // At least one finite entry, so the set is not degenerate.
            lw.push(anchor);
            let mut w = Vec::new();
            normalize_log_weights(&mut lw, &mut w).unwrap();
            let sum: f64 = w.iter().sum();
            prop_assert!((sum - 1.0).abs() <= 1e-12, "sum = {}", sum);
            // The normalised log weights agree with the linear ones.
            prop_assert!(log_sum_exp(&lw).abs() <= 1e-12);
            for (l, x) in lw.iter().zip(&w) {
                prop_assert!((l.exp() - x).abs() <= 1e-12);
            }
        }
    }
}
