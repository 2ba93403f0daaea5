//! The `track` command line: run the trackers on footage, evaluate them, render what they believe,
//! learn clutter statistics and estimate motion.
//!
//! Everything the binary does is reachable from [`cli::try_main_from_args`], which returns a typed
//! [`AppError`] instead of exiting, so tests drive the command line in-process.
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod batch;
pub mod cli;
pub mod commands;
pub mod error;
pub mod evaluation;
pub mod groundtruth;
pub mod metrics;
pub mod otb;
pub mod output;
pub mod plots;
pub mod progress;
pub mod record;
pub mod render;
pub mod report;
pub mod sequence;
pub mod session;
pub mod signals;

// The README's example is compiled and run as a doctest, so it cannot go stale.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
mod readme_doctest {}

pub use error::{AppError, Result};
