//! `track learn-clutter`.

use crate::{AppError, Result};

/// Arguments of `track learn-clutter`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `track learn-clutter`.
///
/// # Errors
/// See [`AppError`].
pub fn run(_args: &Args) -> Result<()> {
    Err(AppError::NotImplemented("learn-clutter"))
}
