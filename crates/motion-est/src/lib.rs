//! Robust multiresolution parametric (affine) motion estimation with covariance, and NCC patch likelihood (Odobez et al. 2003 §4.2).
//!
//! Skeleton: filled in by the issue that owns this crate.
