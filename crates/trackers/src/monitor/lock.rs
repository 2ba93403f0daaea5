//! Whether the target is still held: a two-state chain (locked, lost) on dbn-switch's
//! [`MarkovChain`], filtered forward (Wu Eq. 7–8 for a discrete state) on an observation q that is
//! about 1 when the estimate looks like the target and about 0 when it looks like background.
//! Each state reads q through a Gaussian of a common spread (locked around a centre near 1, lost
//! around one near 0); the chain keeps its state with the configured persistence. Persistence,
//! spread and centres are the caller's: the appearance trackers' are settings
//! (`AppearanceSettings::lock_persistence`, `lock_spread`, `lock_centres`). It is the appearance trackers' counterpart of Wu's
//! status α (§6.3), which reads the contour likelihood instead.

use dbn_switch::{MarkovChain, StatusEstimate, TrackStatus};

use crate::{Error, Result};

const LOCKED: usize = 0;
const LOST: usize = 1;

/// The filtered lost/locked chain.
#[derive(Debug, Clone, PartialEq)]
pub struct LockChain {
    chain: MarkovChain,
    /// Spread of q under either state.
    spread: f64,
    /// The centres of q: locked, lost.
    centres: [f64; 2],
    belief: [f64; 2],
    predicted: [f64; 2],
}

impl LockChain {
    /// A chain that starts locked and keeps its state with probability `persistence`, and
    /// reads q through N(q; `centres[0]`, `spread`²) when locked and N(q; `centres[1]`,
    /// `spread`²) when lost.
    ///
    /// # Errors
    /// A persistence outside [0, 1], a spread that is not positive and finite, or centres that
    /// are not finite with the locked one above the lost one.
    pub fn new(persistence: f64, spread: f64, centres: [f64; 2]) -> Result<Self> {
        if !(spread > 0.0 && spread.is_finite()) {
            return Err(Error::InvalidSetting {
                name: "lock spread",
                reason: format!("{spread} must be positive and finite"),
            });
        }
        let [locked, lost] = centres;
        if !(locked.is_finite() && lost.is_finite() && locked > lost) {
            return Err(Error::InvalidSetting {
                name: "lock centres",
                reason: format!(
                    "[{locked}, {lost}] must be finite, the locked centre above the lost one"
                ),
            });
        }
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
            spread,
            centres,
            belief: [1.0, 0.0],
            predicted: [1.0, 0.0],
        })
    }

    /// One forward step on an observation `q`: about 1 when the target is held, about 0 when
    /// it is not. The Gaussian log-likelihoods are scaled by their maximum before they are
    /// exponentiated, so that a q far from both centres cannot underflow both to zero.
    pub fn observe(&mut self, q: f64) {
        let log = self.centres.map(|c| -0.5 * ((q - c) / self.spread).powi(2));
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

    /// Whether an observation `q` reads as the target rather than background: the locked
    /// state's emission at least the lost one's (q nearer the locked centre).
    pub fn reads_as_locked(&self, q: f64) -> bool {
        (q - self.centres[LOCKED]).abs() <= (q - self.centres[LOST]).abs()
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
    fn an_observation_reads_as_the_nearer_state() {
        let chain = LockChain::new(0.95, 0.3, [1.0, 0.0]).unwrap();
        for (q, locked) in [
            (0.9, true),
            (0.51, true),
            (0.5, true),
            (0.49, false),
            (-0.2, false),
        ] {
            assert_eq!(chain.reads_as_locked(q), locked, "q = {q}");
        }
        // With other centres the boundary is their midpoint.
        let chain = LockChain::new(0.95, 0.3, [0.8, 0.2]).unwrap();
        assert!(chain.reads_as_locked(0.55) && !chain.reads_as_locked(0.45));
    }

    #[test]
    fn a_run_of_background_raises_p_lost_and_a_match_lowers_it() {
        let mut chain = LockChain::new(0.95, 0.3, [1.0, 0.0]).unwrap();
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
        let mut chain = LockChain::new(0.9, 0.3, [1.0, 0.0]).unwrap();
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
        let new = |p| LockChain::new(p, 0.3, [1.0, 0.0]);
        assert!(new(1.0).is_ok());
        assert!(new(1.5).is_err() && new(f64::NAN).is_err());
    }

    #[test]
    fn spread_and_centres_are_the_callers() {
        // The same observation under other spreads and centres: Bayes' rule with those.
        for (spread, centres, q) in [
            (0.3, [1.0, 0.0], 0.4),
            (0.1, [1.0, 0.0], 0.4),
            (0.5, [0.8, 0.1], 0.4),
            (0.3, [0.7, -0.2], 0.9),
        ] {
            let mut chain = LockChain::new(0.9, spread, centres).unwrap();
            chain.observe(q);
            let l = centres.map(|c: f64| (-0.5 * ((q - c) / spread).powi(2)).exp());
            let expected = 0.1 * l[1] / (0.9 * l[0] + 0.1 * l[1]);
            assert!(
                (chain.p_lost() - expected).abs() < 1e-12,
                "{spread} {centres:?}: {} against {expected}",
                chain.p_lost()
            );
        }
        // q = 0.6 is nearer the locked centre at [1, 0], nearer the lost one at [1.4, 0.5].
        let p = |centres| {
            let mut chain = LockChain::new(0.5, 0.3, centres).unwrap();
            chain.observe(0.6);
            chain.p_lost()
        };
        assert!(p([1.0, 0.0]) < 0.5 && p([1.4, 0.5]) > 0.5);
        for spread in [0.0, -0.3, f64::NAN, f64::INFINITY] {
            let e = LockChain::new(0.95, spread, [1.0, 0.0]).unwrap_err();
            assert!(e.to_string().contains("lock spread"), "{e}");
        }
        for centres in [
            [0.0, 1.0],
            [0.5, 0.5],
            [f64::NAN, 0.0],
            [1.0, f64::NEG_INFINITY],
        ] {
            let e = LockChain::new(0.95, 0.3, centres).unwrap_err();
            assert!(e.to_string().contains("lock centres"), "{e}");
        }
    }
}
