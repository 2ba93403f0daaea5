//! Hidden switching processes: clutter HMM, occlusion and tracker status (Wu et al. 2003 §4-§6).
//!
//! Skeleton: filled in by the issue that owns this crate.
