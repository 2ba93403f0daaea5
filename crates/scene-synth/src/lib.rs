//! Deterministic synthetic clutter sequences with full ground truth for contour tracking.
//!
//! Skeleton: filled in by the issue that owns this crate.
