//! The particle smoothers against the exact Rauch–Tung–Striebel smoother (Särkkä 2013,
//! *Bayesian Filtering and Smoothing*, Theorem 8.2) on linear-Gaussian models: a 1-D AR(1) and a
//! 2-D constant-velocity model observed in position only.
//!
//! Tolerances. With N filter particles, the error of a smoothed mean is about
//! σ_s · sqrt(κ / N), σ_s the exact smoothed standard deviation and κ ≥ 1 an inefficiency factor
//! (weight degeneracy, resampling, and for FFBS the extra draw of M trajectories); a smoothed
//! variance has relative error about sqrt(2κ / N). Each test runs several seeds and checks, for
//! every seed, the worst error over all steps and the root-mean-square error over steps (which
//! averages the noise down and so catches a bias the worst error could hide). The spreads were
//! measured over 20 seeds when the tests were written and are quoted beside each tolerance; a
//! tolerance is at least 4.5 standard deviations of that spread above its mean. The filter's own
//! marginals (no smoothing) miss the RTS variances by far more, which the tests check too, so a
//! smoother that did nothing would fail.
//!
//! The models and the exact smoother are in `models.rs`; the accuracy tests against it in
//! `accuracy.rs`; determinism, recording and bad input in `behaviour.rs`.

mod accuracy;
mod behaviour;
mod models;
