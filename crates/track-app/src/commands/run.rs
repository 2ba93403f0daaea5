//! `track run`.

use crate::{AppError, Result};

/// Arguments of `track run`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `track run`.
///
/// # Errors
/// See [`AppError`].
pub fn run(_args: &Args) -> Result<()> {
    Err(AppError::NotImplemented("run"))
}
