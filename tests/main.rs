//! The integration tests of this package, in one test binary (one binary per package keeps a
//! cold build short: each test binary links the whole dependency tree).

mod bad_input;
mod cli;
mod common;
mod history_words;
mod self_evaluation;
mod tracking;
