//! Hidden switching processes of Wu, Hua & Yu 2003 (§4–§6): the dynamic-Bayesian-network layer
//! whose discrete and continuous hidden variables particles carry next to the target state, so
//! that a tracker can switch observation models and evaluate itself.
//!
//! - [`MarkovChain`]: a finite chain with a validated transition matrix, sampling, its
//!   stationary distribution, and exact forward filtering of class posteriors (Eq. 7–8).
//! - [`ClutterHmm`]: clutter class `β` with `T_β` (Eq. 15) emitting the clutter density
//!   `λ | β ~ G(λ̄_β, σ_λβ)` restricted to `λ > 0` (Fig. 5–6), or a fixed `λ̄_β`.
//! - [`OcclusionProcess`]: occlusion degree `γ ∈ [0, 1]`, a Gaussian random walk with the mass
//!   beyond the bounds on the bounds (Eq. 13), `γ̂ = E[γ]` (Eq. 14).
//! - [`StatusHmm`]: tracker status `α ∈ {locked, partially occluded, lost}` with `T_α` (§6.3)
//!   emitting `γ | α ~ U[a_α, b_α]` (Fig. 9), with docs/MODELS.md's fix `[0.1, 0.9]` for
//!   "partially occluded".
//!
//! Each process has a state type, `sample_next(previous, rng)` and `log_transition(previous,
//! next)`, and implements [`smc_core::Dynamics`]; its estimator takes `(states, normalised
//! weights)` and returns the estimate with the posterior class probabilities (`β̂ = argmax_k
//! Σ_{n: β_n = k} π_n`, Wu §4). Settings default to Wu's published values and load and save as
//! JSON or TOML through [`ConfigFile`].
//!
//! ```
//! use dbn_switch::{ClutterConfig, ClutterHmm};
//! use rand::SeedableRng;
//!
//! let hmm = ClutterHmm::new(&ClutterConfig::default())?;
//! let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(7);
//! let mut particles: Vec<_> = (0..500).map(|_| hmm.sample_initial(&mut rng)).collect();
//! hmm.propagate_in_place(&mut particles, &mut rng);
//! let weights = vec![1.0 / 500.0; 500];
//! let estimate = hmm.estimate(&particles, &weights)?;
//! assert_eq!(estimate.beta_probs.len(), 3);
//! assert!(estimate.lambda_hat > 0.0);
//! # Ok::<(), dbn_switch::Error>(())
//! ```
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod clutter;
mod config;
mod dynamics;
pub mod error;
mod estimate;
mod filter;
pub mod gauss;
mod markov;
mod occlusion;
#[cfg(test)]
mod proptests;
mod smooth;
mod status;
mod switching;
#[cfg(test)]
mod test_util;

// The README's example is compiled and run as a doctest, so it cannot go stale.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
mod readme_doctest {}

pub use clutter::{ClutterConfig, ClutterEstimate, ClutterHmm, ClutterState, LambdaModel};
pub use config::ConfigFile;
pub use error::{Error, Result};
pub use estimate::{argmax, class_probabilities_into};
pub use filter::ForwardResult;
pub use markov::{MarkovChain, ROW_SUM_TOLERANCE, validate_matrix};
pub use occlusion::{OcclusionConfig, OcclusionEstimate, OcclusionProcess, OcclusionState};
/// The `rand` crate whose `Rng` this crate's samplers take (`sample_next`, `sample_initial`, …):
/// import it from here (`use dbn_switch::rand::Rng;`) so that an application's own `rand`, whatever its
/// version, does not matter.
pub use rand;
pub use smooth::SmoothedChain;
pub use status::{GammaRange, StatusConfig, StatusEstimate, StatusHmm, StatusState};
pub use switching::SwitchingConfig;
/// The tracker status α, shared with the rest of the workspace.
pub use vision_core::TrackStatus;
