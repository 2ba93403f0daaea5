//! `track motion`.

use crate::{AppError, Result};

/// Arguments of `track motion`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `track motion`.
///
/// # Errors
/// See [`AppError`].
pub fn run(_args: &Args) -> Result<()> {
    Err(AppError::NotImplemented("motion"))
}
