//! Sequential Monte Carlo engine: particles, log weights, resampling, estimators (Odobez et al. 2003 §2).
//!
//! Skeleton: filled in by the issue that owns this crate.
