//! Weighted-particle estimators shared by the processes: posterior class masses and their argmax
//! (Wu §4: `β̂ = argmax_k Σ_{n: β_n = k} π_n`) and posterior means (Wu Eq. 14: `γ̂ = Σ_n γ_n π_n`).

use crate::error::{Error, Result};
use crate::filter::check_probability_vector;

/// Checks that `weights` are normalised particle weights for `n_particles` particles.
pub(crate) fn check_weights(n_particles: usize, weights: &[f64]) -> Result<()> {
    if n_particles == 0 {
        return Err(Error::Empty);
    }
    if weights.len() != n_particles {
        return Err(Error::DimensionMismatch {
            name: "weights".to_owned(),
            expected: n_particles,
            got: weights.len(),
        });
    }
    check_probability_vector("weights", weights)
}

/// Accumulates the weight of each class into `out` (`out.len()` classes): the posterior class
/// probabilities `p(label = k | Z) ≈ Σ_{n: label_n = k} π_n`.
///
/// # Errors
/// [`Error::Empty`], [`Error::DimensionMismatch`], [`Error::NotAProbabilityVector`] for weights
/// that are not normalised, [`Error::LabelOutOfRange`].
///
/// # Examples
/// ```
/// let mut probs = [0.0; 3];
/// dbn_switch::class_probabilities_into(&[0, 2, 2], &[0.5, 0.25, 0.25], &mut probs)?;
/// assert_eq!(probs, [0.5, 0.0, 0.5]);
/// # Ok::<(), dbn_switch::Error>(())
/// ```
pub fn class_probabilities_into(labels: &[usize], weights: &[f64], out: &mut [f64]) -> Result<()> {
    check_weights(labels.len(), weights)?;
    accumulate_classes(labels.iter().copied(), weights, out)
}

/// Sums weights per label; the labels come from an iterator so that each process can read them
/// from its own state type without copying.
pub(crate) fn accumulate_classes(
    labels: impl Iterator<Item = usize>,
    weights: &[f64],
    out: &mut [f64],
) -> Result<()> {
    out.fill(0.0);
    let n_states = out.len();
    for (label, &w) in labels.zip(weights) {
        match out.get_mut(label) {
            Some(slot) => *slot += w,
            None => return Err(Error::LabelOutOfRange { label, n_states }),
        }
    }
    Ok(())
}

/// Index of the largest class mass; ties go to the lowest index, so the answer is deterministic.
#[must_use]
pub fn argmax(probs: &[f64]) -> usize {
    let mut best = 0;
    for (k, &p) in probs.iter().enumerate() {
        if p > probs[best] {
            best = k;
        }
    }
    best
}

/// Weighted mean `Σ_n π_n v_n` of a finite quantity.
pub(crate) fn weighted_mean(
    name: &str,
    values: impl Iterator<Item = f64>,
    weights: &[f64],
) -> Result<f64> {
    let mut mean = 0.0;
    for (v, &w) in values.zip(weights) {
        if !v.is_finite() {
            return Err(Error::NonFinite {
                name: name.to_owned(),
                value: v,
            });
        }
        mean += w * v;
    }
    Ok(mean)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn class_probabilities_and_errors() {
        let mut probs = [0.0; 2];
        class_probabilities_into(&[1, 0, 1], &[0.2, 0.3, 0.5], &mut probs).unwrap();
        assert_eq!(probs, [0.3, 0.7]);
        assert_eq!(argmax(&probs), 1);
        assert_eq!(argmax(&[0.4, 0.4, 0.2]), 0);
        assert!(matches!(
            class_probabilities_into(&[0, 2], &[0.5, 0.5], &mut probs),
            Err(Error::LabelOutOfRange {
                label: 2,
                n_states: 2
            })
        ));
        assert!(matches!(
            class_probabilities_into(&[0, 1], &[0.5, 0.6], &mut probs),
            Err(Error::NotAProbabilityVector { .. })
        ));
        assert!(matches!(
            class_probabilities_into(&[], &[], &mut probs),
            Err(Error::Empty)
        ));
        assert!(matches!(
            class_probabilities_into(&[0], &[0.5, 0.5], &mut probs),
            Err(Error::DimensionMismatch {
                expected: 1,
                got: 2,
                ..
            })
        ));
    }
}
