//! The tracker-status HMM `{α_t, γ_t}` of Wu et al. §5 (Fig. 9) and §6.3: a three-state Markov
//! chain `α ∈ {locked, partially occluded, lost}` with transition matrix `T_α`, emitting the
//! occlusion degree `γ | α ~ U[a_α, b_α]`. Inferring `α` gives the tracker a rough online
//! self-evaluation.
//!
//! Wu prints `a₂ = 1, b₂ = 0.9` for "partially occluded", an empty interval; docs/MODELS.md settles
//! it as `[0.1, 0.9]`, which is the default here. Reversed ranges are rejected by validation.

use rand::Rng;
use serde::{Deserialize, Serialize};
use vision_core::TrackStatus;

use crate::config::ConfigFile;
use crate::error::{Error, Result};
use crate::estimate::{accumulate_classes, argmax, check_weights, weighted_mean};
use crate::markov::{MarkovChain, sample_categorical, validate_matrix};

/// A closed interval `[low, high] ⊆ [0, 1]` for `γ | α`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GammaRange {
    /// `a_α`.
    pub low: f64,
    /// `b_α`.
    pub high: f64,
}

impl GammaRange {
    /// Checks `0 ≤ low < high ≤ 1` with finite bounds; `name` labels the error.
    ///
    /// # Errors
    /// [`Error::InvalidRange`].
    pub fn validate(&self, name: &str) -> Result<()> {
        let ok = self.low.is_finite()
            && self.high.is_finite()
            && 0.0 <= self.low
            && self.low < self.high
            && self.high <= 1.0;
        if ok {
            Ok(())
        } else {
            Err(Error::InvalidRange {
                name: name.to_owned(),
                low: self.low,
                high: self.high,
            })
        }
    }

    /// Whether `gamma` lies in the closed interval.
    #[must_use]
    pub fn contains(&self, gamma: f64) -> bool {
        self.low <= gamma && gamma <= self.high
    }
}

/// Settings of the status HMM. The default is Wu §6.3 with docs/MODELS.md's fix.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StatusConfig {
    /// `T_α[i][j] = p(α_{t+1} = j | α_t = i)` in the order locked, partially occluded, lost.
    /// Default (Wu §6.3): `[[0.8, 0.1, 0.1], [0.4, 0.5, 0.1], [0.3, 0.2, 0.5]]`.
    pub transition: Vec<Vec<f64>>,
    /// `[a₁, b₁]`, default `[0, 0.2]`.
    pub locked: GammaRange,
    /// `[a₂, b₂]`, default `[0.1, 0.9]` (docs/MODELS.md; Wu's printed `[1, 0.9]` is a typo).
    pub partially_occluded: GammaRange,
    /// `[a₃, b₃]`, default `[0.8, 1]`.
    pub lost: GammaRange,
    /// The status at the first frame. Default: locked, since a tracker starts on its target.
    #[serde(default = "default_initial_status")]
    pub initial_status: TrackStatus,
}

fn default_initial_status() -> TrackStatus {
    TrackStatus::Locked
}

impl Default for StatusConfig {
    fn default() -> Self {
        Self {
            transition: vec![
                vec![0.8, 0.1, 0.1],
                vec![0.4, 0.5, 0.1],
                vec![0.3, 0.2, 0.5],
            ],
            locked: GammaRange {
                low: 0.0,
                high: 0.2,
            },
            partially_occluded: GammaRange {
                low: 0.1,
                high: 0.9,
            },
            lost: GammaRange {
                low: 0.8,
                high: 1.0,
            },
            initial_status: TrackStatus::Locked,
        }
    }
}

impl StatusConfig {
    /// The `γ` range of a status.
    #[must_use]
    pub fn range(&self, status: TrackStatus) -> GammaRange {
        match status {
            TrackStatus::Locked => self.locked,
            TrackStatus::PartiallyOccluded => self.partially_occluded,
            TrackStatus::Lost => self.lost,
        }
    }

    /// Checks the settings.
    ///
    /// # Errors
    /// The matrix errors of [`MarkovChain::new`]; [`Error::DimensionMismatch`] unless `T_α` is
    /// 3 × 3; [`Error::InvalidRange`] for a range that is not `0 ≤ low < high ≤ 1` (Wu's printed
    /// `[1, 0.9]` among them).
    pub fn validate(&self) -> Result<()> {
        validate_matrix(&self.transition)?;
        if self.transition.len() != TrackStatus::ALL.len() {
            return Err(Error::DimensionMismatch {
                name: "status transition matrix".to_owned(),
                expected: TrackStatus::ALL.len(),
                got: self.transition.len(),
            });
        }
        self.locked.validate("locked")?;
        self.partially_occluded.validate("partially_occluded")?;
        self.lost.validate("lost")
    }
}

impl ConfigFile for StatusConfig {
    fn check(&self) -> Result<()> {
        self.validate()
    }
}

/// The status part of a particle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StatusState {
    /// Tracker status `α`.
    pub alpha: TrackStatus,
    /// Degree of occlusion `γ ∈ [0, 1]`, emitted by `α`.
    pub gamma: f64,
}

/// Particle estimate of the status HMM.
#[derive(Debug, Clone, PartialEq)]
pub struct StatusEstimate {
    /// `α̂ = argmax_k Σ_{n: α_n = k} π_n`, as `β̂` in Wu §4.
    pub alpha_hat: TrackStatus,
    /// Posterior status probabilities, indexed by [`TrackStatus::index`].
    pub alpha_probs: [f64; 3],
    /// `γ̂ = Σ_n γ_n π_n` (Wu Eq. 14).
    pub gamma_hat: f64,
}

/// The status HMM, built from a validated [`StatusConfig`].
#[derive(Debug, Clone)]
pub struct StatusHmm {
    chain: MarkovChain,
    ranges: [GammaRange; 3],
    initial: TrackStatus,
}

impl StatusHmm {
    /// Builds the process.
    ///
    /// # Errors
    /// Those of [`StatusConfig::validate`].
    ///
    /// # Examples
    /// ```
    /// use dbn_switch::{TrackStatus, StatusConfig, StatusHmm};
    /// use rand::SeedableRng;
    /// let hmm = StatusHmm::new(&StatusConfig::default())?;
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    /// let first = hmm.sample_initial(&mut rng);
    /// assert_eq!(first.alpha, TrackStatus::Locked);
    /// assert!(first.gamma <= 0.2);
    /// let next = hmm.sample_next(&first, &mut rng);
    /// assert!(hmm.log_transition(&first, &next).is_finite());
    /// # Ok::<(), dbn_switch::Error>(())
    /// ```
    pub fn new(config: &StatusConfig) -> Result<Self> {
        config.validate()?;
        Ok(Self {
            chain: MarkovChain::new(&config.transition)?,
            ranges: TrackStatus::ALL.map(|s| config.range(s)),
            initial: config.initial_status,
        })
    }

    /// The chain `T_α`.
    #[must_use]
    pub fn chain(&self) -> &MarkovChain {
        &self.chain
    }

    /// The `γ` range `[a_α, b_α]` of a status.
    #[must_use]
    pub fn range(&self, alpha: TrackStatus) -> GammaRange {
        self.ranges[alpha.index()]
    }

    /// Draws `γ | α ~ U[a_α, b_α]`.
    pub fn sample_gamma<R: Rng + ?Sized>(&self, alpha: TrackStatus, rng: &mut R) -> f64 {
        let r = self.range(alpha);
        let u: f64 = rng.random();
        r.low + (r.high - r.low) * u
    }

    /// `ln p(γ | α)`: `−ln(b_α − a_α)` inside the closed range, `−∞` outside, NaN for NaN.
    #[must_use]
    pub fn log_gamma_density(&self, alpha: TrackStatus, gamma: f64) -> f64 {
        let r = self.range(alpha);
        if gamma.is_nan() {
            f64::NAN
        } else if r.contains(gamma) {
            -(r.high - r.low).ln()
        } else {
            f64::NEG_INFINITY
        }
    }

    /// The first-frame state: the configured status and `γ` drawn from its range.
    pub fn sample_initial<R: Rng + ?Sized>(&self, rng: &mut R) -> StatusState {
        StatusState {
            alpha: self.initial,
            gamma: self.sample_gamma(self.initial, rng),
        }
    }

    /// One transition (Wu Fig. 9): `α' ~ T_α[α]`, then `γ' ~ U[a_α', b_α']`. The previous `γ`
    /// does not enter: in the HMM, `γ_t` is the output of `α_t` alone.
    pub fn sample_next<R: Rng + ?Sized>(&self, previous: &StatusState, rng: &mut R) -> StatusState {
        let alpha = self
            .chain
            .row(previous.alpha.index())
            .map(|row| sample_categorical(row, rng))
            .and_then(TrackStatus::from_index)
            .unwrap_or(previous.alpha);
        StatusState {
            alpha,
            gamma: self.sample_gamma(alpha, rng),
        }
    }

    /// [`Self::sample_next`] with `α'` drawn from the defensive mixture of
    /// [`MarkovChain::sample_next_exploring`] (identical to it for `ε = 0`).
    pub fn sample_next_exploring<R: Rng + ?Sized>(
        &self,
        previous: &StatusState,
        exploration: f64,
        rng: &mut R,
    ) -> StatusState {
        if exploration <= 0.0 {
            return self.sample_next(previous, rng);
        }
        let alpha = TrackStatus::from_index(self.chain.sample_next_exploring(
            previous.alpha.index(),
            exploration,
            rng,
        ))
        .unwrap_or(previous.alpha);
        StatusState {
            alpha,
            gamma: self.sample_gamma(alpha, rng),
        }
    }

    /// `ln p(α', γ' | α) = ln T_α[α][α'] − ln(b_α' − a_α')` when `γ' ∈ [a_α', b_α']`, else `−∞`.
    #[must_use]
    pub fn log_transition(&self, previous: &StatusState, next: &StatusState) -> f64 {
        self.chain
            .log_transition(previous.alpha.index(), next.alpha.index())
            + self.log_gamma_density(next.alpha, next.gamma)
    }

    /// Propagates every state in place.
    pub fn propagate_in_place<R: Rng + ?Sized>(&self, states: &mut [StatusState], rng: &mut R) {
        for s in states {
            *s = self.sample_next(s, rng);
        }
    }

    /// `α̂`, the status probabilities and `γ̂` from particles and their normalised weights.
    ///
    /// # Errors
    /// [`Error::Empty`], [`Error::DimensionMismatch`], [`Error::NotAProbabilityVector`],
    /// [`Error::NonFinite`] for a NaN `γ`.
    pub fn estimate(&self, states: &[StatusState], weights: &[f64]) -> Result<StatusEstimate> {
        check_weights(states.len(), weights)?;
        let mut alpha_probs = [0.0; 3];
        accumulate_classes(
            states.iter().map(|s| s.alpha.index()),
            weights,
            &mut alpha_probs,
        )?;
        let gamma_hat = weighted_mean("gamma", states.iter().map(|s| s.gamma), weights)?;
        let alpha_hat =
            TrackStatus::from_index(argmax(&alpha_probs)).unwrap_or(TrackStatus::Locked);
        Ok(StatusEstimate {
            alpha_hat,
            alpha_probs,
            gamma_hat,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::{KS_BOUND_COEFF, ks_statistic};
    use approx::assert_relative_eq;
    use rand::SeedableRng;
    use rand_pcg::Pcg64Mcg;

    #[test]
    fn defaults_are_wus_values_with_the_typo_fixed() {
        let c = StatusConfig::default();
        assert_eq!(
            c.transition,
            vec![
                vec![0.8, 0.1, 0.1],
                vec![0.4, 0.5, 0.1],
                vec![0.3, 0.2, 0.5]
            ]
        );
        assert_eq!(
            c.locked,
            GammaRange {
                low: 0.0,
                high: 0.2
            }
        );
        assert_eq!(
            c.partially_occluded,
            GammaRange {
                low: 0.1,
                high: 0.9
            }
        );
        assert_eq!(
            c.lost,
            GammaRange {
                low: 0.8,
                high: 1.0
            }
        );
        assert!(c.validate().is_ok());
    }

    #[test]
    fn invalid_ranges_and_matrices_are_rejected() {
        // Wu's printed range for "partially occluded" is empty.
        let typo = StatusConfig {
            partially_occluded: GammaRange {
                low: 1.0,
                high: 0.9,
            },
            ..StatusConfig::default()
        };
        match typo.validate() {
            Err(Error::InvalidRange { name, low, high }) => {
                assert_eq!((name.as_str(), low, high), ("partially_occluded", 1.0, 0.9));
            }
            other => panic!("expected InvalidRange, got {other:?}"),
        }
        let outside = StatusConfig {
            lost: GammaRange {
                low: 0.8,
                high: 1.2,
            },
            ..StatusConfig::default()
        };
        assert!(matches!(
            outside.validate(),
            Err(Error::InvalidRange { .. })
        ));
        let nan = StatusConfig {
            locked: GammaRange {
                low: f64::NAN,
                high: 0.2,
            },
            ..StatusConfig::default()
        };
        assert!(matches!(nan.validate(), Err(Error::InvalidRange { .. })));
        let two = StatusConfig {
            transition: vec![vec![0.5, 0.5], vec![0.5, 0.5]],
            ..StatusConfig::default()
        };
        assert!(matches!(
            two.validate(),
            Err(Error::DimensionMismatch {
                expected: 3,
                got: 2,
                ..
            })
        ));
        let mut bad_row = StatusConfig::default();
        bad_row.transition[1] = vec![0.4, 0.5, 0.2];
        assert!(matches!(
            bad_row.validate(),
            Err(Error::InvalidTransitionMatrix { row: 1, .. })
        ));
        assert!(StatusHmm::new(&bad_row).is_err());
    }

    /// γ | α is uniform on its range: KS against the uniform CDF for each status,
    /// n = 20 000, bound `1.95/√n` (0.1 % critical value).
    #[test]
    fn gamma_given_alpha_is_uniform_on_its_range() {
        let hmm = StatusHmm::new(&StatusConfig::default()).unwrap();
        let mut rng = Pcg64Mcg::seed_from_u64(31);
        let n = 20_000;
        let bound = KS_BOUND_COEFF / (n as f64).sqrt();
        for alpha in TrackStatus::ALL {
            let r = hmm.range(alpha);
            let mut draws: Vec<f64> = (0..n).map(|_| hmm.sample_gamma(alpha, &mut rng)).collect();
            assert!(draws.iter().all(|&g| r.contains(g)));
            let cdf = |x: f64| ((x - r.low) / (r.high - r.low)).clamp(0.0, 1.0);
            let d = ks_statistic(&mut draws, cdf, cdf);
            eprintln!("status {alpha:?}: uniform KS D = {d:.5} (bound {bound:.5})");
            assert!(d < bound, "{alpha:?}: D = {d}");
        }
    }

    #[test]
    fn log_transition_and_estimate() {
        let hmm = StatusHmm::new(&StatusConfig::default()).unwrap();
        let prev = StatusState {
            alpha: TrackStatus::PartiallyOccluded,
            gamma: 0.5,
        };
        let next = StatusState {
            alpha: TrackStatus::Locked,
            gamma: 0.15,
        };
        assert_relative_eq!(
            hmm.log_transition(&prev, &next),
            0.4f64.ln() - 0.2f64.ln(),
            epsilon = 1e-15
        );
        let outside = StatusState {
            alpha: TrackStatus::Locked,
            gamma: 0.5,
        };
        assert_eq!(hmm.log_transition(&prev, &outside), f64::NEG_INFINITY);

        let states = [
            StatusState {
                alpha: TrackStatus::Locked,
                gamma: 0.1,
            },
            StatusState {
                alpha: TrackStatus::Lost,
                gamma: 0.9,
            },
            StatusState {
                alpha: TrackStatus::Lost,
                gamma: 1.0,
            },
            StatusState {
                alpha: TrackStatus::PartiallyOccluded,
                gamma: 0.5,
            },
        ];
        let e = hmm.estimate(&states, &[0.45, 0.2, 0.2, 0.15]).unwrap();
        assert_eq!(e.alpha_hat, TrackStatus::Locked);
        for (got, want) in e.alpha_probs.iter().zip([0.45, 0.15, 0.4]) {
            assert_relative_eq!(*got, want, epsilon = 1e-15);
        }
        assert_relative_eq!(e.gamma_hat, 0.045 + 0.18 + 0.2 + 0.075, epsilon = 1e-15);
    }
}
