//! Contours, measurement lines, 1-D edges, Poisson clutter and occlusion likelihoods, clutter learning (Wu et al. 2003 §3, §5, §6.1).
//!
//! Skeleton: filled in by the issue that owns this crate.
