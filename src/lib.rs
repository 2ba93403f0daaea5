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
