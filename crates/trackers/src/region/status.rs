//! Whether the region tracker still holds its target: a two-state chain (locked, lost) filtered
//! forward on the colour similarity of the estimate to the target model, the region tracker's
//! counterpart of Wu's status α (§6.3).
//!
//! The observation is the Bhattacharyya coefficient ρ of the estimate's histogram to the target
//! model, rescaled by what the background scored against the target at the first frame:
//! q = (ρ − ρ_bg) / (1 − ρ_bg), 1 for a perfect match and 0 for a patch of background. Each
//! state reads q through a Gaussian: locked around 1, lost around 0, both of spread
//! [`SPREAD`]; the chain keeps its state with the configured persistence.

use dbn_switch::{StatusEstimate, TrackStatus};

/// Spread of the rescaled similarity q under either state.
const SPREAD: f64 = 0.3;
/// Locked and lost centres of q.
const LOCKED_Q: f64 = 1.0;
const LOST_Q: f64 = 0.0;
/// Largest background similarity used for the rescaling (a target that looks like its
/// background cannot be told from it by colour; the rescaling then saturates).
const MAX_BACKGROUND_SIMILARITY: f64 = 0.9;

/// The filtered lost/locked chain.
#[derive(Debug, Clone, PartialEq)]
pub struct LostChain {
    persistence: f64,
    background_similarity: f64,
    p_lost: f64,
}

impl LostChain {
    /// A chain that starts locked, keeps its state with probability `persistence`, and rescales
    /// similarities by `background_similarity` (ρ of the first frame's background ring to the
    /// target model).
    pub fn new(persistence: f64, background_similarity: f64) -> Self {
        Self {
            persistence,
            background_similarity: background_similarity.clamp(0.0, MAX_BACKGROUND_SIMILARITY),
            p_lost: 0.0,
        }
    }

    /// One forward step on the estimate's similarity `rho` to the target model.
    pub fn update(&mut self, rho: f64) {
        self.observe((rho - self.background_similarity) / (1.0 - self.background_similarity));
    }

    /// One forward step on an observation `q` already on the chain's scale: about 1 when the
    /// target is held, about 0 when it is not.
    pub fn observe(&mut self, q: f64) {
        let stay = self.persistence;
        let prior_lost = self.p_lost * stay + (1.0 - self.p_lost) * (1.0 - stay);
        let log_locked = -0.5 * ((q - LOCKED_Q) / SPREAD).powi(2);
        let log_lost = -0.5 * ((q - LOST_Q) / SPREAD).powi(2);
        // Posterior odds in log space: no underflow for q far from both centres.
        let lost = prior_lost.ln() + log_lost;
        let locked = (1.0 - prior_lost).ln() + log_locked;
        let m = lost.max(locked);
        let (el, ek) = ((lost - m).exp(), (locked - m).exp());
        self.p_lost = el / (el + ek);
    }

    /// P(lost) after the last update.
    pub fn p_lost(&self) -> f64 {
        self.p_lost
    }

    /// The chain as a status estimate: α̂ locked or lost, and γ̂ = P(lost) (the region tracker
    /// has no partial-occlusion state; its probability is 0).
    pub fn estimate(&self) -> StatusEstimate {
        let p = self.p_lost;
        StatusEstimate {
            alpha_hat: if p > 0.5 {
                TrackStatus::Lost
            } else {
                TrackStatus::Locked
            },
            alpha_probs: [1.0 - p, 0.0, p],
            gamma_hat: p,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_of_background_matches_raises_p_lost_and_a_match_lowers_it() {
        let mut chain = LostChain::new(0.95, 0.4);
        for _ in 0..5 {
            chain.update(0.97);
        }
        assert!(chain.p_lost() < 0.05);
        for _ in 0..5 {
            chain.update(0.4);
        }
        assert!(chain.p_lost() > 0.95);
        for _ in 0..5 {
            chain.update(0.97);
        }
        assert!(chain.p_lost() < 0.05);
        let e = chain.estimate();
        assert_eq!(e.alpha_hat, TrackStatus::Locked);
        assert!((e.alpha_probs.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }
}
