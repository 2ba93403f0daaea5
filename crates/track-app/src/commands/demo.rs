//! `track demo`.

use crate::{AppError, Result};

/// Arguments of `track demo`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `track demo`.
///
/// # Errors
/// See [`AppError`].
pub fn run(_args: &Args) -> Result<()> {
    Err(AppError::NotImplemented("demo"))
}
