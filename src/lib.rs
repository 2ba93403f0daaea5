//! Visual contour tracking with particle filters.
//!
//! This umbrella crate re-exports the workspace crates under one roof; each can also be used alone.
//! The top-level `tests/` folder holds the end-to-end tests of the whole product.

#[doc(inline)]
pub use contour_obs;
#[doc(inline)]
pub use dbn_switch;
#[doc(inline)]
pub use motion_est;
#[doc(inline)]
pub use scene_synth;
#[doc(inline)]
pub use smc_core;
#[doc(inline)]
pub use track_app;
#[doc(inline)]
pub use trackers;
#[doc(inline)]
pub use vision_core;

// Any Rust code in the top-level README, and the README of motion-est (whose sources this
// crate does not own) is compiled and run as doctests of this crate.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
mod readme_doctest {}

#[cfg(doctest)]
#[doc = include_str!("../crates/motion-est/README.md")]
mod motion_est_readme_doctest {}
