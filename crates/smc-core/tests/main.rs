//! The integration tests of this package, in one test binary (one binary per package keeps a
//! cold build short: each test binary links the whole dependency tree).

mod common;
mod determinism;
mod filter_behaviour;
mod kalman;
mod smoothing;
