//! The Poisson law of a line's clutter count (Wu Eq. 1), in logs: the one place where the
//! project writes ln N(m; μ).

/// The floor of μ in [`log_poisson`], so that an empty line stays finite.
const MIN_MEAN: f64 = 1e-12;

/// ln N(m; μ) = m ln μ − μ − ln m!, the Poisson law of Wu Eq. 1 with mean μ = λ · (observed
/// length) (docs/MODELS.md, Wu Eq. 1: (λL)^m e^{−λL}/m!). μ is floored at 1e−12 so that an
/// empty line stays finite.
///
/// # Examples
/// ```
/// // N(0; 2) = e^{−2}.
/// assert_eq!(contour_obs::log_poisson(0, 2.0), -2.0);
/// ```
pub fn log_poisson(m: usize, mu: f64) -> f64 {
    let mu = mu.max(MIN_MEAN);
    let ln_fact: f64 = (2..=m).map(|j| (j as f64).ln()).sum();
    log_poisson_with(m, mu, mu.ln(), ln_fact)
}

/// [`log_poisson`] from its parts: μ, ln μ and ln m! already at hand (the likelihoods cache
/// ln μ of a full-length line and a table of ln m!).
#[inline]
pub(crate) fn log_poisson_with(m: usize, mu: f64, ln_mu: f64, ln_fact: f64) -> f64 {
    m as f64 * ln_mu - mu - ln_fact
}

/// E[ln N(m; μ)] for m ~ N(·; μ): minus the entropy of the Poisson law (the sum is cut where
/// the remaining mass is negligible). The typical log-density of a background line's count,
/// used by the neutral hidden line of the occlusion arc
/// ([`crate::OcclusionForm::NeutralArc`]).
pub fn poisson_neg_entropy(mu: f64) -> f64 {
    let mu = mu.max(MIN_MEAN);
    let top = (mu + 12.0 * mu.sqrt() + 12.0) as usize;
    let mut ln_p = -mu;
    let mut sum = 0.0;
    for m in 0..=top {
        if m > 0 {
            ln_p += mu.ln() - (m as f64).ln();
        }
        sum += ln_p.exp() * ln_p;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::LnFactorial;

    #[test]
    fn poisson_neg_entropy_matches_known_values() {
        // H(Poisson(1)) = 1.3048 nats; μ → 0: the law is a point mass.
        assert!((poisson_neg_entropy(1.0) + 1.304_842_24).abs() < 1e-6);
        assert!(poisson_neg_entropy(1e-9).abs() < 1e-6);
    }

    #[test]
    fn log_poisson_matches_the_density_and_the_cached_form() {
        // N(3; 2) = 8 e^{−2} / 6.
        let want = (8.0 * (-2.0f64).exp() / 6.0).ln();
        assert!((log_poisson(3, 2.0) - want).abs() < 1e-12);
        // An empty line at μ → 0 stays finite (μ floored).
        assert!(log_poisson(2, 0.0).is_finite());
        // The likelihoods' table of ln m! gives the same bits as the plain sum.
        let table = LnFactorial::new(22);
        for m in 0..30 {
            let mu = 0.37 * (m + 1) as f64;
            assert_eq!(
                log_poisson(m, mu),
                log_poisson_with(m, mu, mu.ln(), table.get(m)),
                "m = {m}"
            );
        }
    }
}
