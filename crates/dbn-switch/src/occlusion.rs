//! The occlusion process of Wu et al. §5: `γ_t ∈ [0, 1]` follows a Gaussian random walk with
//! deviation `σ_γ` whose mass beyond the bounds is put on the bounds (Eq. 13, as docs/MODELS.md
//! reads it), and is estimated by its posterior mean (Eq. 14).
//!
//! The transition law therefore has two atoms, at 0 and 1, and a Gaussian density in between.
//! [`OcclusionProcess::log_transition`] returns its density with respect to the measure
//! "Lebesgue on (0, 1) plus a unit point mass at 0 and at 1": at `γ' = 0` exactly, the log
//! probability of the atom `ln Φ(−γ/σ_γ)`; at `γ' = 1` exactly, `ln Q((1 − γ)/σ_γ)`; inside, the
//! Gaussian log density; outside `[0, 1]`, `−∞`. Importance weights stay correct as long as the
//! proposal's density is taken with respect to the same measure — in particular any proposal
//! that, like this sampler, lands exactly on 0 or 1 with positive probability.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::config::ConfigFile;
use crate::error::{Error, Result, check_finite, check_std};
use crate::estimate::{check_weights, weighted_mean};
use crate::gauss::{ln_lower_tail, ln_upper_tail, normal_cdf, normal_log_pdf};

/// Settings of the occlusion random walk. The default is Wu's (§6.2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OcclusionConfig {
    /// `σ_γ`, the random-walk step deviation. Default 0.1 (Wu §6.2).
    pub sigma_gamma: f64,
    /// `γ` at the first frame. Default 0: a tracker is initialised on a visible target. Wu does
    /// not say.
    #[serde(default)]
    pub initial_gamma: f64,
}

impl Default for OcclusionConfig {
    fn default() -> Self {
        Self {
            sigma_gamma: 0.1,
            initial_gamma: 0.0,
        }
    }
}

impl OcclusionConfig {
    /// Checks the settings.
    ///
    /// # Errors
    /// [`Error::InvalidStd`] unless `σ_γ > 0` and finite; [`Error::NonFinite`] or
    /// [`Error::InvalidRange`] unless `initial_gamma ∈ [0, 1]`.
    pub fn validate(&self) -> Result<()> {
        check_std("sigma_gamma", self.sigma_gamma)?;
        let g = check_finite("initial_gamma", self.initial_gamma)?;
        if !(0.0..=1.0).contains(&g) {
            return Err(Error::InvalidRange {
                name: "initial_gamma".to_owned(),
                low: g,
                high: g,
            });
        }
        Ok(())
    }
}

impl ConfigFile for OcclusionConfig {
    fn check(&self) -> Result<()> {
        self.validate()
    }
}

/// The occlusion part of a particle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OcclusionState {
    /// Degree of occlusion: 0 none, 1 complete (Wu Eq. 11).
    pub gamma: f64,
}

/// Particle estimate of the occlusion process.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OcclusionEstimate {
    /// `γ̂ = Σ_n γ_n π_n` (Wu Eq. 14).
    pub gamma_hat: f64,
}

/// The occlusion random walk, built from a validated [`OcclusionConfig`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OcclusionProcess {
    sigma: f64,
    initial: f64,
}

impl OcclusionProcess {
    /// Builds the process.
    ///
    /// # Errors
    /// Those of [`OcclusionConfig::validate`].
    ///
    /// # Examples
    /// ```
    /// use dbn_switch::{OcclusionConfig, OcclusionProcess, OcclusionState};
    /// use rand::SeedableRng;
    /// let walk = OcclusionProcess::new(&OcclusionConfig::default())?;
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    /// let next = walk.sample_next(&OcclusionState { gamma: 0.0 }, &mut rng);
    /// assert!((0.0..=1.0).contains(&next.gamma));
    /// // Half of the steps from γ = 0 land on the atom at 0.
    /// let at_zero = walk.log_transition(&OcclusionState { gamma: 0.0 }, &OcclusionState { gamma: 0.0 });
    /// assert!((at_zero - 0.5f64.ln()).abs() < 1e-12);
    /// # Ok::<(), dbn_switch::Error>(())
    /// ```
    pub fn new(config: &OcclusionConfig) -> Result<Self> {
        config.validate()?;
        Ok(Self {
            sigma: config.sigma_gamma,
            initial: config.initial_gamma,
        })
    }

    /// `σ_γ`.
    #[must_use]
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// The first-frame state (`initial_gamma`).
    #[must_use]
    pub fn initial(&self) -> OcclusionState {
        OcclusionState {
            gamma: self.initial,
        }
    }

    /// One step of Wu Eq. 13: `γ' = clamp(γ + σ_γ ε, 0, 1)`, `ε ~ N(0, 1)`. A previous `γ`
    /// outside `[0, 1]` is clamped first; a NaN stays NaN (the estimator reports it).
    pub fn sample_next<R: Rng + ?Sized>(
        &self,
        previous: &OcclusionState,
        rng: &mut R,
    ) -> OcclusionState {
        let eps: f64 = StandardNormal.sample(rng);
        let g = previous.gamma.clamp(0.0, 1.0) + self.sigma * eps;
        OcclusionState {
            gamma: g.clamp(0.0, 1.0),
        }
    }

    /// The probabilities of the two atoms from `previous`: `(P(γ' = 0), P(γ' = 1))`
    /// `= (Φ(−γ/σ_γ), Q((1 − γ)/σ_γ))`.
    #[must_use]
    pub fn atom_probabilities(&self, previous: &OcclusionState) -> (f64, f64) {
        let g = previous.gamma.clamp(0.0, 1.0);
        (
            ln_lower_tail(-g / self.sigma).exp(),
            ln_upper_tail((1.0 - g) / self.sigma).exp(),
        )
    }

    /// The CDF `P(γ' ≤ x | γ)` of one step: 0 below 0, `Φ((x − γ)/σ_γ)` on `[0, 1)`, 1 from 1.
    #[must_use]
    pub fn transition_cdf(&self, previous: &OcclusionState, x: f64) -> f64 {
        let g = previous.gamma.clamp(0.0, 1.0);
        if x < 0.0 {
            0.0
        } else if x < 1.0 {
            normal_cdf((x - g) / self.sigma)
        } else {
            1.0
        }
    }

    /// Log density of one step; see the module documentation for how the atoms at 0 and 1 are
    /// handled. NaN in either state gives NaN.
    #[must_use]
    pub fn log_transition(&self, previous: &OcclusionState, next: &OcclusionState) -> f64 {
        let g = previous.gamma.clamp(0.0, 1.0);
        let x = next.gamma;
        if g.is_nan() || x.is_nan() {
            f64::NAN
        } else if x == 0.0 {
            ln_lower_tail(-g / self.sigma)
        } else if x == 1.0 {
            ln_upper_tail((1.0 - g) / self.sigma)
        } else if x > 0.0 && x < 1.0 {
            normal_log_pdf(x, g, self.sigma)
        } else {
            f64::NEG_INFINITY
        }
    }

    /// Propagates every state in place.
    pub fn propagate_in_place<R: Rng + ?Sized>(&self, states: &mut [OcclusionState], rng: &mut R) {
        for s in states {
            *s = self.sample_next(s, rng);
        }
    }

    /// `γ̂ = Σ_n γ_n π_n` (Wu Eq. 14) from particles and their normalised weights.
    ///
    /// # Errors
    /// [`Error::Empty`], [`Error::DimensionMismatch`], [`Error::NotAProbabilityVector`],
    /// [`Error::NonFinite`] for a NaN `γ`.
    pub fn estimate(
        &self,
        states: &[OcclusionState],
        weights: &[f64],
    ) -> Result<OcclusionEstimate> {
        check_weights(states.len(), weights)?;
        let gamma_hat = weighted_mean("gamma", states.iter().map(|s| s.gamma), weights)?;
        Ok(OcclusionEstimate { gamma_hat })
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
    fn default_is_wus_sigma_and_invalid_settings_are_rejected() {
        assert_eq!(OcclusionConfig::default().sigma_gamma, 0.1);
        assert!(OcclusionConfig::default().validate().is_ok());
        let bad = OcclusionConfig {
            sigma_gamma: 0.0,
            ..OcclusionConfig::default()
        };
        assert!(matches!(bad.validate(), Err(Error::InvalidStd { value, .. }) if value == 0.0));
        let bad = OcclusionConfig {
            sigma_gamma: f64::NAN,
            ..OcclusionConfig::default()
        };
        assert!(matches!(bad.validate(), Err(Error::InvalidStd { .. })));
        let bad = OcclusionConfig {
            initial_gamma: 1.5,
            ..OcclusionConfig::default()
        };
        assert!(matches!(bad.validate(), Err(Error::InvalidRange { .. })));
        let bad = OcclusionConfig {
            initial_gamma: f64::NAN,
            ..OcclusionConfig::default()
        };
        assert!(matches!(bad.validate(), Err(Error::NonFinite { .. })));
    }

    /// The boundary-mass sampler against its mixed CDF, from starting points that put visible
    /// mass on one, both or neither atom. n = 20 000 per case; bound `1.95/√n` (0.1 % critical
    /// value, conservative with atoms). The atom frequencies are also checked on their own,
    /// within 4 binomial standard errors `√(p(1 − p)/n)`.
    #[test]
    fn boundary_mass_sampler_matches_its_distribution() {
        let n = 20_000;
        let bound = KS_BOUND_COEFF / (n as f64).sqrt();
        let mut rng = Pcg64Mcg::seed_from_u64(21);
        for (sigma, g0) in [(0.1, 0.05), (0.1, 0.5), (0.1, 0.97), (0.5, 0.3)] {
            let walk = OcclusionProcess::new(&OcclusionConfig {
                sigma_gamma: sigma,
                initial_gamma: 0.0,
            })
            .unwrap();
            let prev = OcclusionState { gamma: g0 };
            let mut draws: Vec<f64> = (0..n)
                .map(|_| walk.sample_next(&prev, &mut rng).gamma)
                .collect();
            let (p0, p1) = walk.atom_probabilities(&prev);
            for (atom, p) in [(0.0, p0), (1.0, p1)] {
                let freq = draws.iter().filter(|&&x| x == atom).count() as f64 / n as f64;
                let se = (p * (1.0 - p) / n as f64).sqrt().max(1.0 / n as f64);
                assert!(
                    (freq - p).abs() < 4.0 * se,
                    "σ {sigma} γ {g0} atom {atom}: {freq} vs {p}"
                );
            }
            let d = ks_statistic(
                &mut draws,
                |x| walk.transition_cdf(&prev, x),
                |x| {
                    if x <= 0.0 {
                        0.0
                    } else if x <= 1.0 {
                        normal_cdf((x - g0) / sigma).min(1.0)
                    } else {
                        1.0
                    }
                },
            );
            eprintln!(
                "occlusion σ {sigma} γ {g0}: P(0) = {p0:.4}, P(1) = {p1:.4}, KS D = {d:.5} (bound {bound:.5})"
            );
            assert!(d < bound, "σ {sigma} γ {g0}: D = {d} ≥ {bound}");
        }
    }

    #[test]
    fn transition_density_and_atoms_integrate_to_one() {
        // Atoms plus the midpoint-rule integral of the interior density; the Gaussian is smooth,
        // so 10⁵ cells leave a quadrature error far below the 1e-9 asserted.
        let walk = OcclusionProcess::new(&OcclusionConfig {
            sigma_gamma: 0.3,
            initial_gamma: 0.0,
        })
        .unwrap();
        for g in [0.0, 0.2, 0.9, 1.0] {
            let prev = OcclusionState { gamma: g };
            let cells = 100_000;
            let h = 1.0 / cells as f64;
            let inside: f64 = (0..cells)
                .map(|i| {
                    walk.log_transition(
                        &prev,
                        &OcclusionState {
                            gamma: (i as f64 + 0.5) * h,
                        },
                    )
                    .exp()
                        * h
                })
                .sum();
            let atoms = walk
                .log_transition(&prev, &OcclusionState { gamma: 0.0 })
                .exp()
                + walk
                    .log_transition(&prev, &OcclusionState { gamma: 1.0 })
                    .exp();
            assert_relative_eq!(inside + atoms, 1.0, epsilon = 1e-9);
        }
        let prev = OcclusionState { gamma: 0.5 };
        assert_eq!(
            walk.log_transition(&prev, &OcclusionState { gamma: 1.1 }),
            f64::NEG_INFINITY
        );
        assert!(
            walk.log_transition(&prev, &OcclusionState { gamma: f64::NAN })
                .is_nan()
        );
    }

    #[test]
    fn estimate_is_the_weighted_mean() {
        let walk = OcclusionProcess::new(&OcclusionConfig::default()).unwrap();
        let states = [0.0, 0.5, 1.0].map(|gamma| OcclusionState { gamma });
        let e = walk.estimate(&states, &[0.5, 0.3, 0.2]).unwrap();
        assert_relative_eq!(e.gamma_hat, 0.35, epsilon = 1e-15);
        assert!(matches!(
            walk.estimate(&states, &[0.5, 0.5]),
            Err(Error::DimensionMismatch { .. })
        ));
        assert!(matches!(walk.estimate(&[], &[]), Err(Error::Empty)));
    }
}
