//! Particle-filter contour trackers composed from smc-core, motion-est, contour-obs and dbn-switch.
//!
//! Skeleton: filled in by the issue that owns this crate.
