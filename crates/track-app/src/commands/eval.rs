//! `track eval`.

use crate::{AppError, Result};

/// Arguments of `track eval`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `track eval`.
///
/// # Errors
/// See [`AppError`].
pub fn run(_args: &Args) -> Result<()> {
    Err(AppError::NotImplemented("eval"))
}
