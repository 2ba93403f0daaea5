//! The clutter switching process of Wu et al. §4 and §6.1: a Markov chain `β_t` over clutter
//! classes with transition matrix `T_β` (Eq. 15), and the clutter density `λ_t` it emits — either
//! a Gaussian `G(λ̄_β, σ_λβ)` restricted to `λ > 0` (the HMM `{β, λ}` of Fig. 5–6) or the fixed
//! `λ̄_β` of the variant "without the HMM".

use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::config::ConfigFile;
use crate::error::{Error, Result, check_finite, check_std};
use crate::estimate::{accumulate_classes, argmax, check_weights, weighted_mean};
use crate::gauss::{sample_truncated_below, truncated_below_log_pdf};
use crate::markov::{MarkovChain, sample_categorical, validate_matrix};

/// How `λ_t` depends on `β_t`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LambdaModel {
    /// `λ | β ~ G(λ̄_β, σ_λβ)` restricted to `λ > 0`: the HMM `{β, λ}` (Wu Fig. 5–6).
    #[default]
    TruncatedGaussian,
    /// `λ = λ̄_β` exactly: Wu's comparison "without the HMM" (§6.1).
    Fixed,
}

/// Settings of the clutter process. The default is Wu's published model (§6.1, Eq. 15).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClutterConfig {
    /// `T_β[i][j] = p(β_{t+1} = j | β_t = i)`. Default: 0.8 on the diagonal, 0.1 elsewhere
    /// (Wu Eq. 15).
    pub transition: Vec<Vec<f64>>,
    /// `λ̄_k`, the mean clutter density per pixel of each class. Default: 0.01, 0.0824, 0.2144
    /// (light, medium, heavy; Wu §6.1).
    pub lambda_mean: Vec<f64>,
    /// `σ_λk`. Default: 0.002, 0.01, 0.05 (Wu §6.1). Unused by [`LambdaModel::Fixed`] but still
    /// validated, so that one file can switch models.
    pub lambda_std: Vec<f64>,
    /// Whether `λ` is random given `β` (default) or fixed.
    #[serde(default)]
    pub lambda_model: LambdaModel,
}

impl Default for ClutterConfig {
    fn default() -> Self {
        Self {
            transition: vec![
                vec![0.8, 0.1, 0.1],
                vec![0.1, 0.8, 0.1],
                vec![0.1, 0.1, 0.8],
            ],
            lambda_mean: vec![0.01, 0.0824, 0.2144],
            lambda_std: vec![0.002, 0.01, 0.05],
            lambda_model: LambdaModel::TruncatedGaussian,
        }
    }
}

impl ClutterConfig {
    /// Checks the settings.
    ///
    /// # Errors
    /// The matrix errors of [`MarkovChain::new`]; [`Error::DimensionMismatch`] when the number of
    /// means or deviations differs from the number of classes; [`Error::NonFinite`] for a
    /// non-finite mean; [`Error::NonPositive`] for a mean `≤ 0` (a clutter density);
    /// [`Error::InvalidStd`] for a deviation that is not `> 0`.
    pub fn validate(&self) -> Result<()> {
        validate_matrix(&self.transition)?;
        let n = self.transition.len();
        for (name, got) in [
            ("lambda_mean", self.lambda_mean.len()),
            ("lambda_std", self.lambda_std.len()),
        ] {
            if got != n {
                return Err(Error::DimensionMismatch {
                    name: name.to_owned(),
                    expected: n,
                    got,
                });
            }
        }
        for (k, (&mean, &std)) in self.lambda_mean.iter().zip(&self.lambda_std).enumerate() {
            let name = format!("lambda_mean[{k}]");
            check_finite(&name, mean)?;
            if mean <= 0.0 {
                return Err(Error::NonPositive { name, value: mean });
            }
            check_std(&format!("lambda_std[{k}]"), std)?;
        }
        Ok(())
    }
}

impl ConfigFile for ClutterConfig {
    fn check(&self) -> Result<()> {
        self.validate()
    }
}

/// The clutter part of a particle: class `β` (0-based: 0 light, 1 medium, 2 heavy with the
/// defaults) and density `λ` per pixel.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ClutterState {
    /// Clutter class, `0..n_classes`.
    pub beta: usize,
    /// Poisson clutter density per pixel (Wu Eq. 1 with docs/MODELS.md's `λL`).
    pub lambda: f64,
}

/// Particle estimate of the clutter process.
#[derive(Debug, Clone, PartialEq)]
pub struct ClutterEstimate {
    /// `β̂ = argmax_k Σ_{n: β_n = k} π_n` (Wu §4).
    pub beta_hat: usize,
    /// Posterior class probabilities `Σ_{n: β_n = k} π_n`.
    pub beta_probs: Vec<f64>,
    /// `λ̂ = E[λ | Z] = Σ_n π_n λ_n`.
    pub lambda_hat: f64,
}

/// The clutter process `{β_t, λ_t}`, built from a validated [`ClutterConfig`].
#[derive(Debug, Clone)]
pub struct ClutterHmm {
    chain: MarkovChain,
    means: Vec<f64>,
    stds: Vec<f64>,
    model: LambdaModel,
    /// Distribution of `β` at the first frame: the stationary one, or uniform when the chain
    /// has none that is unique.
    initial: Vec<f64>,
}

impl ClutterHmm {
    /// Builds the process.
    ///
    /// # Errors
    /// Those of [`ClutterConfig::validate`].
    ///
    /// # Examples
    /// ```
    /// use dbn_switch::{ClutterConfig, ClutterHmm, ClutterState};
    /// use rand::SeedableRng;
    /// let hmm = ClutterHmm::new(&ClutterConfig::default())?;
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    /// let next = hmm.sample_next(&ClutterState { beta: 0, lambda: 0.01 }, &mut rng);
    /// assert!(next.lambda > 0.0);
    /// assert!(hmm.log_transition(&ClutterState { beta: 0, lambda: 0.01 }, &next).is_finite());
    /// # Ok::<(), dbn_switch::Error>(())
    /// ```
    pub fn new(config: &ClutterConfig) -> Result<Self> {
        config.validate()?;
        let chain = MarkovChain::new(&config.transition)?;
        let n = chain.n_states();
        let initial = chain
            .stationary()
            .unwrap_or_else(|_| vec![1.0 / n as f64; n]);
        Ok(Self {
            chain,
            means: config.lambda_mean.clone(),
            stds: config.lambda_std.clone(),
            model: config.lambda_model,
            initial,
        })
    }

    /// Number of clutter classes `N_β`.
    #[must_use]
    pub fn n_classes(&self) -> usize {
        self.chain.n_states()
    }

    /// The chain `T_β`.
    #[must_use]
    pub fn chain(&self) -> &MarkovChain {
        &self.chain
    }

    /// How `λ` depends on `β`.
    #[must_use]
    pub fn lambda_model(&self) -> LambdaModel {
        self.model
    }

    /// Draws `λ | β` (Wu Fig. 6 step 2c). A class out of range gives NaN, which the estimators
    /// then report.
    pub fn sample_lambda<R: Rng + ?Sized>(&self, beta: usize, rng: &mut R) -> f64 {
        match (self.means.get(beta), self.stds.get(beta), self.model) {
            (Some(&mean), _, LambdaModel::Fixed) => mean,
            (Some(&mean), Some(&std), LambdaModel::TruncatedGaussian) => {
                sample_truncated_below(mean, std, 0.0, rng)
            }
            _ => f64::NAN,
        }
    }

    /// `ln p(λ | β)`: the truncated Gaussian log density, normalised by its mass above 0; for
    /// [`LambdaModel::Fixed`], a Dirac at `λ̄_β` (0 when `λ` equals it exactly, `−∞` otherwise).
    #[must_use]
    pub fn log_lambda_density(&self, beta: usize, lambda: f64) -> f64 {
        match (self.means.get(beta), self.stds.get(beta), self.model) {
            (Some(&mean), _, LambdaModel::Fixed) if lambda == mean => 0.0,
            (Some(_), _, LambdaModel::Fixed) => f64::NEG_INFINITY,
            (Some(&mean), Some(&std), LambdaModel::TruncatedGaussian) => {
                truncated_below_log_pdf(lambda, mean, std, 0.0)
            }
            _ => f64::NEG_INFINITY,
        }
    }

    /// Draws a first-frame state: `β` from the stationary distribution of `T_β`, then `λ | β`.
    pub fn sample_initial<R: Rng + ?Sized>(&self, rng: &mut R) -> ClutterState {
        let beta = sample_categorical(&self.initial, rng);
        ClutterState {
            beta,
            lambda: self.sample_lambda(beta, rng),
        }
    }

    /// One transition (Wu Fig. 6 steps 2b–2c): `β' ~ T_β[β]`, then `λ' ~ p(λ | β')`. The
    /// previous `λ` does not enter: in the HMM, `λ_t` is the output of `β_t` alone.
    pub fn sample_next<R: Rng + ?Sized>(
        &self,
        previous: &ClutterState,
        rng: &mut R,
    ) -> ClutterState {
        let beta = self.chain.sample_next(previous.beta, rng);
        ClutterState {
            beta,
            lambda: self.sample_lambda(beta, rng),
        }
    }

    /// [`Self::sample_next`] with `β'` drawn from the defensive mixture of
    /// [`MarkovChain::sample_next_exploring`] (identical to it for `ε = 0`).
    pub fn sample_next_exploring<R: Rng + ?Sized>(
        &self,
        previous: &ClutterState,
        exploration: f64,
        rng: &mut R,
    ) -> ClutterState {
        let beta = self
            .chain
            .sample_next_exploring(previous.beta, exploration, rng);
        ClutterState {
            beta,
            lambda: self.sample_lambda(beta, rng),
        }
    }

    /// `ln p(β', λ' | β) = ln T_β[β][β'] + ln p(λ' | β')`, the density of [`Self::sample_next`]
    /// with respect to counting measure on `β` times Lebesgue measure on `λ` (a Dirac in `λ`
    /// for [`LambdaModel::Fixed`], see [`Self::log_lambda_density`]).
    #[must_use]
    pub fn log_transition(&self, previous: &ClutterState, next: &ClutterState) -> f64 {
        self.chain.log_transition(previous.beta, next.beta)
            + self.log_lambda_density(next.beta, next.lambda)
    }

    /// Propagates every state in place.
    pub fn propagate_in_place<R: Rng + ?Sized>(&self, states: &mut [ClutterState], rng: &mut R) {
        for s in states {
            *s = self.sample_next(s, rng);
        }
    }

    /// `β̂`, the class probabilities and `λ̂` from particles and their normalised weights,
    /// writing the class probabilities into `probs` (`n_classes` long).
    ///
    /// # Errors
    /// [`Error::Empty`], [`Error::DimensionMismatch`], [`Error::NotAProbabilityVector`] for
    /// unnormalised weights, [`Error::LabelOutOfRange`], [`Error::NonFinite`] for a NaN `λ`.
    pub fn estimate_into(
        &self,
        states: &[ClutterState],
        weights: &[f64],
        probs: &mut [f64],
    ) -> Result<(usize, f64)> {
        check_weights(states.len(), weights)?;
        if probs.len() != self.n_classes() {
            return Err(Error::DimensionMismatch {
                name: "class probability buffer".to_owned(),
                expected: self.n_classes(),
                got: probs.len(),
            });
        }
        accumulate_classes(states.iter().map(|s| s.beta), weights, probs)?;
        let lambda_hat = weighted_mean("lambda", states.iter().map(|s| s.lambda), weights)?;
        Ok((argmax(probs), lambda_hat))
    }

    /// Allocating twin of [`Self::estimate_into`].
    ///
    /// # Errors
    /// As [`Self::estimate_into`].
    pub fn estimate(&self, states: &[ClutterState], weights: &[f64]) -> Result<ClutterEstimate> {
        let mut beta_probs = vec![0.0; self.n_classes()];
        let (beta_hat, lambda_hat) = self.estimate_into(states, weights, &mut beta_probs)?;
        Ok(ClutterEstimate {
            beta_hat,
            beta_probs,
            lambda_hat,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gauss::truncated_below_cdf;
    use crate::test_util::{KS_BOUND_COEFF, ks_statistic};
    use approx::assert_relative_eq;
    use rand::SeedableRng;
    use rand_pcg::Pcg64Mcg;

    #[test]
    fn defaults_are_wus_published_values() {
        let c = ClutterConfig::default();
        assert_eq!(
            c.transition,
            vec![
                vec![0.8, 0.1, 0.1],
                vec![0.1, 0.8, 0.1],
                vec![0.1, 0.1, 0.8]
            ]
        );
        assert_eq!(c.lambda_mean, vec![0.01, 0.0824, 0.2144]);
        assert_eq!(c.lambda_std, vec![0.002, 0.01, 0.05]);
        assert_eq!(c.lambda_model, LambdaModel::TruncatedGaussian);
        assert!(c.validate().is_ok());
    }

    #[test]
    fn invalid_configs_are_typed_errors() {
        let mut c = ClutterConfig::default();
        c.transition[2] = vec![0.1, 0.1, 0.7];
        assert!(matches!(
            c.validate(),
            Err(Error::InvalidTransitionMatrix { row: 2, .. })
        ));
        let mut c = ClutterConfig::default();
        c.lambda_std.pop();
        assert!(matches!(
            c.validate(),
            Err(Error::DimensionMismatch {
                expected: 3,
                got: 2,
                ..
            })
        ));
        let mut c = ClutterConfig::default();
        c.lambda_std[1] = f64::NAN;
        assert!(matches!(c.validate(), Err(Error::InvalidStd { .. })));
        let mut c = ClutterConfig::default();
        c.lambda_mean[0] = f64::NAN;
        assert!(matches!(c.validate(), Err(Error::NonFinite { .. })));
        let mut c = ClutterConfig::default();
        c.lambda_mean[0] = -0.01;
        assert!(matches!(c.validate(), Err(Error::NonPositive { .. })));
        assert!(ClutterHmm::new(&c).is_err());
    }

    /// λ | β sampler against its CDF for each of Wu's classes, and for two harder truncations
    /// exercising both sampler branches (mean below 0: exponential proposal; σ large relative to
    /// the mean: plain rejection). n = 20 000 draws per case; the bound `1.95/√n` is the 0.1 %
    /// critical value of the Kolmogorov statistic, so a correct sampler fails with probability
    /// 0.001 per case, and the seeds are fixed.
    #[test]
    fn truncated_gaussian_sampler_matches_its_cdf() {
        let n = 20_000;
        let bound = KS_BOUND_COEFF / (n as f64).sqrt();
        let mut rng = Pcg64Mcg::seed_from_u64(11);
        let cases = [
            (0.01, 0.002),
            (0.0824, 0.01),
            (0.2144, 0.05),
            (-0.05, 0.02),
            (0.01, 0.05),
        ];
        for (mean, std) in cases {
            let mut draws: Vec<f64> = (0..n)
                .map(|_| sample_truncated_below(mean, std, 0.0, &mut rng))
                .collect();
            assert!(draws.iter().all(|&x| x > 0.0));
            let d = ks_statistic(
                &mut draws,
                |x| truncated_below_cdf(x, mean, std, 0.0),
                |x| truncated_below_cdf(x, mean, std, 0.0),
            );
            eprintln!("truncated Gaussian mean {mean} std {std}: KS D = {d:.5} (bound {bound:.5})");
            assert!(d < bound, "mean {mean} std {std}: D = {d} ≥ {bound}");
        }
    }

    #[test]
    fn fixed_variant_emits_the_class_mean_and_a_dirac_density() {
        let config = ClutterConfig {
            lambda_model: LambdaModel::Fixed,
            ..ClutterConfig::default()
        };
        let hmm = ClutterHmm::new(&config).unwrap();
        let mut rng = Pcg64Mcg::seed_from_u64(5);
        let mut state = hmm.sample_initial(&mut rng);
        for _ in 0..200 {
            let next = hmm.sample_next(&state, &mut rng);
            assert_eq!(next.lambda, config.lambda_mean[next.beta]);
            assert_relative_eq!(
                hmm.log_transition(&state, &next),
                config.transition[state.beta][next.beta].ln(),
                epsilon = 1e-15
            );
            state = next;
        }
        let off = ClutterState {
            beta: 1,
            lambda: 0.05,
        };
        assert_eq!(hmm.log_transition(&state, &off), f64::NEG_INFINITY);
    }

    #[test]
    fn log_transition_is_chain_plus_truncated_gaussian() {
        let hmm = ClutterHmm::new(&ClutterConfig::default()).unwrap();
        let prev = ClutterState {
            beta: 0,
            lambda: 0.3,
        };
        let next = ClutterState {
            beta: 2,
            lambda: 0.25,
        };
        // ln 0.1 + ln G(0.25; 0.2144, 0.05) − ln Q(−0.2144/0.05), by the formula's pieces.
        let z: f64 = (0.25 - 0.2144) / 0.05;
        let log_g = -0.5 * z * z - 0.05f64.ln() - 0.5 * (2.0 * std::f64::consts::PI).ln();
        let mass = 1.0 - 0.5 * libm::erfc(0.2144 / 0.05 / std::f64::consts::SQRT_2);
        assert_relative_eq!(
            hmm.log_transition(&prev, &next),
            0.1f64.ln() + log_g - mass.ln(),
            epsilon = 1e-12
        );
        assert_eq!(
            hmm.log_transition(
                &prev,
                &ClutterState {
                    beta: 2,
                    lambda: -0.1
                }
            ),
            f64::NEG_INFINITY
        );
        assert_eq!(
            hmm.log_transition(
                &prev,
                &ClutterState {
                    beta: 3,
                    lambda: 0.1
                }
            ),
            f64::NEG_INFINITY
        );
    }

    #[test]
    fn estimator_is_argmax_class_mass_and_posterior_mean() {
        let hmm = ClutterHmm::new(&ClutterConfig::default()).unwrap();
        let states = [
            ClutterState {
                beta: 0,
                lambda: 0.01,
            },
            ClutterState {
                beta: 1,
                lambda: 0.08,
            },
            ClutterState {
                beta: 1,
                lambda: 0.09,
            },
            ClutterState {
                beta: 2,
                lambda: 0.2,
            },
        ];
        let weights = [0.4, 0.25, 0.25, 0.1];
        let e = hmm.estimate(&states, &weights).unwrap();
        // Class masses (0.4, 0.5, 0.1): class 1 wins although the single heaviest particle is
        // in class 0, which is the point of summing per class.
        assert_eq!(e.beta_hat, 1);
        for (got, want) in e.beta_probs.iter().zip([0.4, 0.5, 0.1]) {
            assert_relative_eq!(*got, want, epsilon = 1e-15);
        }
        assert_relative_eq!(
            e.lambda_hat,
            0.4 * 0.01 + 0.25 * 0.08 + 0.25 * 0.09 + 0.1 * 0.2,
            epsilon = 1e-15
        );
        let bad = [ClutterState {
            beta: 0,
            lambda: f64::NAN,
        }];
        assert!(matches!(
            hmm.estimate(&bad, &[1.0]),
            Err(Error::NonFinite { .. })
        ));
    }

    /// The particle estimator `β̂`/class probabilities against the exact forward filter: a
    /// bootstrap filter over the β chain (fixed-λ variant, so the state is β alone) with known
    /// per-class likelihoods must reproduce the exact posteriors. N = 50 000 particles,
    /// multinomial resampling each step; one class probability has Monte Carlo standard error
    /// about √(0.25/N) ≈ 0.0022 per step, inflated by at most a few times by the accumulated
    /// resampling noise, so 0.015 is about 4 of those inflated errors.
    #[test]
    fn particle_class_probabilities_match_the_exact_forward_filter() {
        let config = ClutterConfig {
            lambda_model: LambdaModel::Fixed,
            ..ClutterConfig::default()
        };
        let hmm = ClutterHmm::new(&config).unwrap();
        // The target moves light → medium → heavy clutter: likelihoods favour each in turn.
        let likelihoods: Vec<[f64; 3]> = (0..9)
            .map(|t| match t / 3 {
                0 => [0.6, 0.3, 0.1],
                1 => [0.2, 0.5, 0.3],
                _ => [0.1, 0.3, 0.6],
            })
            .collect();
        let exact = hmm
            .chain()
            .forward_filter(&[1.0 / 3.0; 3], &likelihoods)
            .unwrap();

        let n = 50_000;
        let mut rng = Pcg64Mcg::seed_from_u64(41);
        let mut states: Vec<ClutterState> = (0..n).map(|_| hmm.sample_initial(&mut rng)).collect();
        let mut weights = vec![0.0; n];
        for (t, l) in likelihoods.iter().enumerate() {
            if t > 0 {
                hmm.propagate_in_place(&mut states, &mut rng);
            }
            for (w, s) in weights.iter_mut().zip(&states) {
                *w = l[s.beta];
            }
            let total: f64 = weights.iter().sum();
            weights.iter_mut().for_each(|w| *w /= total);
            let e = hmm.estimate(&states, &weights).unwrap();
            for (k, (got, want)) in e.beta_probs.iter().zip(&exact.posteriors[t]).enumerate() {
                assert!(
                    (got - want).abs() < 0.015,
                    "step {t} class {k}: {got} vs {want}"
                );
            }
            eprintln!(
                "step {t}: particle {:.4?} vs exact {:.4?}",
                e.beta_probs, exact.posteriors[t]
            );
            assert_eq!(e.beta_hat, argmax(&exact.posteriors[t]), "step {t}");
            // Multinomial resampling by inversion of the cumulative weights.
            let mut cumulative = Vec::with_capacity(n);
            let mut acc = 0.0;
            for w in &weights {
                acc += w;
                cumulative.push(acc);
            }
            states = (0..n)
                .map(|_| {
                    let u: f64 = rng.random::<f64>() * acc;
                    states[cumulative.partition_point(|&c| c <= u).min(n - 1)]
                })
                .collect();
        }
    }
}
