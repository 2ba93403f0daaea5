//! Sequential Monte Carlo engine: particles, log weights, resampling, estimators.
//!
//! This crate is the particle-filter layer every tracker stands on (Odobez, Gatica-Perez & Ba
//! 2003, §2 and Fig. 2; Wu, Hua & Yu 2003, Fig. 6). It knows nothing of images.
//!
//! - [`ParticleSet`]: states generic over the state type, with log weights kept normalised by
//!   log-sum-exp ([`weights`]); [`Labelled`] attaches a discrete mode to a state.
//! - [`model`]: the capability traits of the general importance update (Odobez Eq. 3),
//!   w ∝ w′ · p(z|x) · p(x|x′) / q(x|x′, z): [`Dynamics`] (the prior), [`Proposal`] (q),
//!   [`Observation`] (the likelihood, with a batch form). [`Bootstrap`] makes any dynamics the
//!   proposal, giving the bootstrap (CONDENSATION) filter.
//! - [`resample`]: multinomial (O(N) by sorted uniforms), residual, stratified, systematic and
//!   SSP resampling, returning ancestor indices; the output size may differ from the input size.
//! - [`ParticleFilter`]: one step (resample if ESS < threshold·N, propagate, weight, normalise),
//!   whole or in pieces, with [`StepDiagnostics`] (ESS, resampled, distinct ancestors, largest
//!   weight, log-evidence increment). The rayon path is bit-identical to the sequential one for
//!   any number of threads: every particle draws from a generator derived from
//!   (seed, step, particle index) ([`rng`]).
//! - [`temper`]: adaptive tempering, the largest exponent φ ≤ 1 of the likelihood that keeps
//!   the effective sample size above a floor.
//! - [`estimate`]: weighted mean and covariance, maximum-weight particle, per-label mass and
//!   label-conditional mean (Wu §4).
//!
//! - [`history`] and [`smooth`]: the filter records its weighted sets and ancestors when
//!   [`FilterSettings::history`] asks for it; FFBSm smooths the marginals (O(N²) per step, with
//!   `faer` for the dense products), backward simulation (FFBS) draws whole trajectories in O(N)
//!   per trajectory and step, or O(1) expected with the accept–reject sampler of Douc et al.
//!   (2011) when the transition density is bounded ([`TransitionDensity`]); a fixed-lag variant
//!   serves near-online use.
//!
//! Degenerate weights (all −∞, a NaN or a +∞) are a typed [`Error::DegenerateWeights`] at the step
//! where they appear.
//!
//! # Example
//! A bootstrap filter for x_k = 0.9 x_{k−1} + N(0, 1), z_k = x_k + N(0, 1):
//! ```
//! // The generator traits come from smc-core's own `rand`, whatever version an application uses.
//! use smc_core::rand::Rng;
//! use smc_core::rand_distr::{Distribution, StandardNormal};
//! use smc_core::model::{Dynamics, FnObservation};
//! use smc_core::{FilterSettings, ParticleFilter, ParticleSet, ResamplingScheme};
//!
//! struct Ar1;
//! impl Dynamics for Ar1 {
//!     type State = f64;
//!     fn sample<R: Rng + ?Sized>(&self, x: &f64, rng: &mut R) -> f64 {
//!         let e: f64 = StandardNormal.sample(rng);
//!         0.9 * x + e
//!     }
//!     fn log_density(&self, x: &f64, y: &f64) -> f64 {
//!         -0.5 * (y - 0.9 * x).powi(2) - 0.5 * (2.0 * std::f64::consts::PI).ln()
//!     }
//! }
//!
//! let mut set = ParticleSet::from_states(vec![0.0; 2000])?;
//! let mut filter = ParticleFilter::new(FilterSettings::default())?;
//! let mut log_evidence = 0.0;
//! for (k, z) in [0.5, 1.1, 0.7].into_iter().enumerate() {
//!     let obs = FnObservation::new(move |x: &f64| {
//!         -0.5 * (z - x).powi(2) - 0.5 * (2.0 * std::f64::consts::PI).ln()
//!     });
//!     let d = filter.step_bootstrap(&mut set, &Ar1, &obs, &ResamplingScheme::Systematic, 7, k as u64)?;
//!     log_evidence += d.log_evidence_increment;
//! }
//! let mean = smc_core::estimate::weighted_mean(&set)?;
//! assert!(mean[0] > 0.0 && mean[0] < 1.5);
//! assert!(log_evidence.is_finite());
//! # Ok::<(), smc_core::Error>(())
//! ```
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod error;
pub mod estimate;
pub mod filter;
pub mod history;
pub mod model;
pub mod particles;
pub mod resample;
pub mod rng;
pub mod smooth;
pub mod temper;
pub mod weights;

// The README's example is compiled and run as a doctest, so it cannot go stale.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
mod readme_doctest {}

/// The `rand` crate that [`Dynamics::sample`], [`Proposal::sample`] and the resamplers take their
/// generators from. A model implemented against another version of `rand` (a `cargo add rand`
/// may pick a newer one) does not compile: import `Rng` from here, `use smc_core::rand::Rng;`.
pub use rand;
/// The `rand_distr` crate of the same `rand` version ([`rand`]), for the noise of a model:
/// `use smc_core::rand_distr::{Distribution, StandardNormal};`.
pub use rand_distr;

pub use error::{Degeneracy, Error, Result};
pub use estimate::{AsVector, LabelEstimate, MeanCovariance};
pub use filter::{FilterSettings, ParticleFilter, ResampleReport, StepDiagnostics, WeightReport};
pub use history::{Frame, History, HistorySettings};
pub use model::{
    Bootstrap, Dynamics, FnObservation, Observation, PriorDensity, Proposal, TransitionDensity,
};
pub use particles::{Labelled, ParticleSet};
pub use resample::{
    Multinomial, Resampler, ResamplingScheme, Residual, Ssp, Stratified, Systematic,
    offspring_counts,
};
pub use smooth::{
    BackwardMethod, SmoothedMarginals, SmootherSettings, Trajectories, sample_trajectories,
    smooth_marginals,
};

#[cfg(test)]
mod readme_tests {
    /// The README's example compiles as a doctest against this crate's own `rand`, whatever an
    /// application's `cargo add rand` picks; it only holds for a user if the example imports the
    /// generator traits through the re-exports, which this checks.
    #[test]
    fn the_examples_import_rand_through_the_re_exports() {
        for (name, text) in [
            ("README.md", include_str!("../README.md")),
            ("lib.rs", include_str!("lib.rs")),
        ] {
            let code_lines = text
                .lines()
                .map(|l| l.trim_start_matches("//!").trim())
                .filter(|l| l.starts_with("use "));
            for line in code_lines {
                assert!(
                    !(line.starts_with("use rand::") || line.starts_with("use rand_distr::")),
                    "{name}: `{line}` names the application's rand, not smc_core::rand"
                );
            }
        }
    }
}
