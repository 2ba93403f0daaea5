//! The weighted particle set.

use crate::error::{Degeneracy, Error, Result};
use crate::weights::{argmax, checked_max, effective_sample_size, normalize_log_weights};

/// A particle that carries a discrete label (a mode, a class β, a tracker status α) next to its
/// continuous state, as in Wu et al. §4 where each particle is (β, X).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Labelled<S> {
    /// The discrete label, in `0..n_labels`.
    pub label: usize,
    /// The continuous state.
    pub state: S,
}

impl<S> Labelled<S> {
    /// Pairs a label with a state.
    pub fn new(label: usize, state: S) -> Self {
        Self { label, state }
    }
}

/// A weighted set of particles approximating a distribution over `S`.
///
/// Invariant: the weights are always normalised. `log_weights()` satisfy log Σ exp = 0 and
/// `weights()` are their exponentials, which sum to 1. Keeping this invariant is what makes the
/// log-evidence increment returned by [`ParticleSet::reweight`] correct whether or not the step
/// resampled: it is always log Σᵢ Wᵢ · exp(Δᵢ) with Wᵢ the normalised weights before the update
/// (Wᵢ = 1/N after resampling).
#[derive(Debug, Clone, PartialEq)]
pub struct ParticleSet<S> {
    pub(crate) states: Vec<S>,
    pub(crate) log_weights: Vec<f64>,
    pub(crate) weights: Vec<f64>,
}

impl<S> ParticleSet<S> {
    /// A set with the given states and uniform weights 1/N.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] when `states` is empty (zero particles).
    ///
    /// # Examples
    /// ```
    /// let set = smc_core::ParticleSet::from_states(vec![1.0, 2.0, 3.0, 4.0]).unwrap();
    /// assert_eq!(set.weights(), &[0.25; 4]);
    /// ```
    pub fn from_states(states: Vec<S>) -> Result<Self> {
        let n = states.len();
        if n == 0 {
            return Err(zero_particles());
        }
        Ok(Self {
            states,
            log_weights: vec![-(n as f64).ln(); n],
            weights: vec![1.0 / n as f64; n],
        })
    }

    /// A set with the given states and (unnormalised) log weights, which are normalised.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for zero particles, [`Error::LengthMismatch`] when the lengths
    /// differ, [`Error::InvalidWeights`] when the log weights are degenerate.
    pub fn from_log_weights(states: Vec<S>, mut log_weights: Vec<f64>) -> Result<Self> {
        if states.is_empty() {
            return Err(zero_particles());
        }
        check_len("log_weights", states.len(), log_weights.len())?;
        let mut weights = Vec::with_capacity(states.len());
        normalize_log_weights(&mut log_weights, &mut weights)
            .map_err(|reason| Error::InvalidWeights { reason })?;
        Ok(Self {
            states,
            log_weights,
            weights,
        })
    }

    /// Number of particles.
    #[must_use]
    pub fn len(&self) -> usize {
        self.states.len()
    }

    /// Always `false`: a set holds at least one particle. Present for API symmetry with `len`.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.states.is_empty()
    }

    /// The particle states.
    #[must_use]
    pub fn states(&self) -> &[S] {
        &self.states
    }

    /// Mutable access to the states (weights unchanged), e.g. to apply a deterministic move.
    pub fn states_mut(&mut self) -> &mut [S] {
        &mut self.states
    }

    /// Normalised log weights (log Σ exp = 0).
    #[must_use]
    pub fn log_weights(&self) -> &[f64] {
        &self.log_weights
    }

    /// Normalised linear weights (Σ = 1).
    #[must_use]
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Iterates over (state, normalised weight) pairs.
    pub fn iter(&self) -> impl Iterator<Item = (&S, f64)> {
        self.states.iter().zip(self.weights.iter().copied())
    }

    /// Effective sample size 1 / Σ Wᵢ², between 1 and N.
    #[must_use]
    pub fn ess(&self) -> f64 {
        effective_sample_size(&self.weights)
    }

    /// Index and normalised weight of the heaviest particle (the first one on ties).
    #[must_use]
    pub fn max_weight(&self) -> (usize, f64) {
        // The set is never empty, so `argmax` always finds one.
        argmax(&self.weights).unwrap_or((0, 0.0))
    }

    /// Multiplies each weight by exp(`log_increments[i]`) and renormalises (the weight update of
    /// Odobez Eq. 3, with the increment log p(z|x) + log p(x|x′) − log q(x|x′, z) computed by the
    /// caller).
    ///
    /// Returns the log-evidence increment log Σᵢ Wᵢ exp(Δᵢ), an estimate of log p(z_k | z_{1:k−1}).
    /// The set is unchanged when an error is returned.
    ///
    /// # Errors
    /// [`Error::LengthMismatch`] for a wrong-length slice; [`Error::DegenerateWeights`] (with
    /// `step`) when an increment is NaN or +∞ or when every updated weight is zero.
    pub fn reweight(&mut self, log_increments: &[f64], step: u64) -> Result<f64> {
        check_len("log_increments", self.len(), log_increments.len())?;
        // Check everything before touching the set: an error leaves it as it was.
        let _ = checked_max(log_increments).or_else(|reason| match reason {
            // All increments −∞ is reported below, with the updated weights.
            Degeneracy::AllZero => Ok(f64::NEG_INFINITY),
            other => Err(Error::DegenerateWeights {
                step,
                reason: other,
            }),
        })?;
        let all_zero = self
            .log_weights
            .iter()
            .zip(log_increments)
            .all(|(lw, d)| lw + d == f64::NEG_INFINITY);
        if all_zero {
            return Err(Error::DegenerateWeights {
                step,
                reason: Degeneracy::AllZero,
            });
        }
        for (lw, d) in self.log_weights.iter_mut().zip(log_increments) {
            *lw += d;
        }
        normalize_log_weights(&mut self.log_weights, &mut self.weights)
            .map_err(|reason| Error::DegenerateWeights { step, reason })
    }

    /// Resets every weight to 1/N.
    pub fn reset_weights(&mut self) {
        let n = self.len();
        self.log_weights.clear();
        self.log_weights.resize(n, -(n as f64).ln());
        self.weights.clear();
        self.weights.resize(n, 1.0 / n as f64);
    }
}

impl<S: Clone> ParticleSet<S> {
    /// Replaces the set by the particles `ancestors[j]`, j = 0..M, with uniform weights 1/M.
    /// `scratch` is a caller-owned buffer (its contents are overwritten) so that no allocation is
    /// needed in steady state; after the call it holds the previous states.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] when `ancestors` is empty or an index is out of range.
    pub fn select(&mut self, ancestors: &[usize], scratch: &mut Vec<S>) -> Result<()> {
        if ancestors.is_empty() {
            return Err(zero_particles());
        }
        let n = self.len();
        if let Some(&bad) = ancestors.iter().find(|&&a| a >= n) {
            return Err(Error::InvalidSetting {
                name: "ancestors",
                reason: format!("index {bad} out of range for {n} particles"),
            });
        }
        scratch.clear();
        scratch.extend(ancestors.iter().map(|&a| self.states[a].clone()));
        std::mem::swap(&mut self.states, scratch);
        self.reset_weights();
        Ok(())
    }
}

pub(crate) fn zero_particles() -> Error {
    Error::InvalidSetting {
        name: "particles",
        reason: "a particle set needs at least one particle".into(),
    }
}

pub(crate) fn check_len(what: &'static str, expected: usize, got: usize) -> Result<()> {
    if expected == got {
        Ok(())
    } else {
        Err(Error::LengthMismatch {
            what,
            expected,
            got,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn empty_sets_are_rejected() {
        assert!(matches!(
            ParticleSet::<f64>::from_states(vec![]),
            Err(Error::InvalidSetting { .. })
        ));
    }

    #[test]
    fn reweight_returns_the_log_evidence_increment() {
        // Weights (1/4, 3/4) times likelihoods (2, 1/3): evidence 1/2 + 1/4 = 3/4, new weights
        // (2/3, 1/3).
        let mut set = ParticleSet::from_log_weights(vec![0.0, 1.0], vec![0.0, 3f64.ln()]).unwrap();
        let inc = set.reweight(&[2f64.ln(), -(3f64.ln())], 1).unwrap();
        assert_relative_eq!(inc, 0.75f64.ln(), epsilon = 1e-14);
        assert_relative_eq!(set.weights()[0], 2.0 / 3.0, epsilon = 1e-14);
        assert_relative_eq!(set.ess(), 1.0 / (4.0 / 9.0 + 1.0 / 9.0), epsilon = 1e-12);
        assert_eq!(set.max_weight().0, 0);
    }

    #[test]
    fn degenerate_updates_are_errors_and_leave_the_set_alone() {
        let mut set = ParticleSet::from_states(vec![0.0; 3]).unwrap();
        let before = set.clone();
        let nan = set.reweight(&[0.0, f64::NAN, 0.0], 7);
        assert_eq!(
            nan,
            Err(Error::DegenerateWeights {
                step: 7,
                reason: Degeneracy::NotANumber { index: 1 }
            })
        );
        let inf = set.reweight(&[0.0, 0.0, f64::INFINITY], 8);
        assert!(matches!(
            inf,
            Err(Error::DegenerateWeights {
                step: 8,
                reason: Degeneracy::PositiveInfinity { index: 2 }
            })
        ));
        let zero = set.reweight(&[f64::NEG_INFINITY; 3], 9);
        assert!(matches!(
            zero,
            Err(Error::DegenerateWeights {
                step: 9,
                reason: Degeneracy::AllZero
            })
        ));
        assert_eq!(set, before);
        assert!(matches!(
            set.reweight(&[0.0; 2], 1),
            Err(Error::LengthMismatch { .. })
        ));
    }

    #[test]
    fn mass_only_on_particles_with_zero_weight_is_degenerate() {
        // Particle 0 has zero weight; the only finite increment is on it.
        let mut set =
            ParticleSet::from_log_weights(vec![0, 1], vec![f64::NEG_INFINITY, 0.0]).unwrap();
        assert!(matches!(
            set.reweight(&[0.0, f64::NEG_INFINITY], 2),
            Err(Error::DegenerateWeights {
                reason: Degeneracy::AllZero,
                ..
            })
        ));
    }

    #[test]
    fn select_copies_ancestors_and_resets_weights() {
        let mut set = ParticleSet::from_log_weights(vec![10, 20, 30], vec![0.0, 1.0, 2.0]).unwrap();
        let mut scratch = Vec::new();
        set.select(&[2, 2, 0, 1, 2], &mut scratch).unwrap();
        assert_eq!(set.states(), &[30, 30, 10, 20, 30]);
        assert_eq!(set.weights(), &[0.2; 5]);
        assert!(set.select(&[5], &mut scratch).is_err());
    }
}
