//! Whether the target is still held: a two-state chain (locked, lost) on dbn-switch's
//! [`MarkovChain`], filtered forward (Wu Eq. 7–8 for a discrete state) on an observation q that is
//! about 1 when the estimate looks like the target and about 0 when it looks like background.
//! Each state reads q through a Gaussian (locked around 1, lost around 0); the chain keeps its
//! state with the configured persistence. It is the appearance trackers' counterpart of Wu's
//! status α (§6.3), which reads the contour likelihood instead.

use dbn_switch::{MarkovChain, StatusEstimate, TrackStatus};

use crate::{Error, Result};

/// Spread of q under either state.
const SPREAD: f64 = 0.3;
/// The centres of q: locked, lost.
const CENTRES: [f64; 2] = [1.0, 0.0];
const LOCKED: usize = 0;
const LOST: usize = 1;

/// The filtered lost/locked chain.
#[derive(Debug, Clone, PartialEq)]
pub struct LockChain {
    chain: MarkovChain,
    belief: [f64; 2],
    predicted: [f64; 2],
}

impl LockChain {
    /// A chain that starts locked and keeps its state with probability `persistence`.
    ///
    /// # Errors
    /// A persistence outside (0, 1).
    pub fn new(persistence: f64) -> Result<Self> {
        let leave = 1.0 - persistence;
        let chain =
            MarkovChain::new(&[[persistence, leave], [leave, persistence]]).map_err(|e| {
                Error::InvalidSetting {
                    name: "lock persistence",
                    reason: e.to_string(),
                }
            })?;
        Ok(Self {
            chain,
            belief: [1.0, 0.0],
            predicted: [1.0, 0.0],
        })
    }

    /// One forward step on an observation `q`: about 1 when the target is held, about 0 when
    /// it is not. The Gaussian log-likelihoods are scaled by their maximum before they are
    /// exponentiated, so that a q far from both centres cannot underflow both to zero.
    pub fn observe(&mut self, q: f64) {
        let log = CENTRES.map(|c| -0.5 * ((q - c) / SPREAD).powi(2));
        let top = log[0].max(log[1]);
        let likelihood = log.map(|l| {
            if top.is_finite() {
                (l - top).exp()
            } else {
                1.0
            }
        });
        // Both cannot fail: two states, finite non-negative likelihoods, one of them 1.
        if self
            .chain
            .predict_into(&self.belief, &mut self.predicted)
            .is_ok()
        {
            let mut posterior = self.predicted;
            if self
                .chain
                .update_in_place(&mut posterior, &likelihood, 0)
                .is_ok()
            {
                self.belief = posterior;
            }
        }
    }

    /// P(lost) after the last step.
    pub fn p_lost(&self) -> f64 {
        self.belief[LOST]
    }

    /// The chain as a status estimate: α̂ locked or lost, and γ̂ = P(lost) (no partial-occlusion
    /// state; its probability is 0).
    pub fn estimate(&self) -> StatusEstimate {
        let p = self.p_lost();
        StatusEstimate {
            alpha_hat: if p > 0.5 {
                TrackStatus::Lost
            } else {
                TrackStatus::Locked
            },
            alpha_probs: [self.belief[LOCKED], 0.0, p],
            gamma_hat: p,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_of_background_raises_p_lost_and_a_match_lowers_it() {
        let mut chain = LockChain::new(0.95).unwrap();
        for _ in 0..5 {
            chain.observe(0.95);
        }
        assert!(chain.p_lost() < 0.05);
        for _ in 0..5 {
            chain.observe(0.0);
        }
        assert!(chain.p_lost() > 0.95);
        for _ in 0..5 {
            chain.observe(0.95);
        }
        assert!(chain.p_lost() < 0.05);
        let e = chain.estimate();
        assert_eq!(e.alpha_hat, TrackStatus::Locked);
        assert!((e.alpha_probs.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn one_step_is_bayes_rule_and_extreme_observations_stay_finite() {
        let mut chain = LockChain::new(0.9).unwrap();
        chain.observe(0.4);
        // Prior after one step from locked: (0.9, 0.1); likelihoods N(0.4; 1, 0.3), N(0.4; 0, 0.3).
        let (l0, l1) = (
            (-0.5f64 * (0.6f64 / 0.3).powi(2)).exp(),
            (-0.5f64 * (0.4f64 / 0.3).powi(2)).exp(),
        );
        let expected = 0.1 * l1 / (0.9 * l0 + 0.1 * l1);
        assert!((chain.p_lost() - expected).abs() < 1e-12);
        for q in [1e6, -1e6, f64::INFINITY, f64::NAN] {
            chain.observe(q);
            assert!(
                chain.p_lost().is_finite() && (0.0..=1.0).contains(&chain.p_lost()),
                "{q}"
            );
        }
        // A chain that never leaves its state is still a chain; a probability above 1 is not.
        assert!(LockChain::new(1.0).is_ok());
        assert!(LockChain::new(1.5).is_err() && LockChain::new(f64::NAN).is_err());
    }
}
