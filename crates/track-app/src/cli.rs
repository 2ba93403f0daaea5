//! Argument parsing and dispatch for the `track` binary.

use std::ffi::OsString;

use clap::{Parser, Subcommand};

use crate::commands;
use crate::{AppError, Result};

/// Visual contour tracking with particle filters (Odobez et al. 2003, Wu et al. 2003).
///
/// Exit codes: 0 success; 1 a computation failed; 2 bad arguments or settings (a `--config` file
/// included); 3 bad input data (images, ground truth, video); 4 an output could not be written.
#[derive(Debug, Parser)]
#[command(
    name = "track",
    version,
    about = "Visual contour tracking with particle filters (Odobez et al. 2003, Wu et al. 2003)",
    propagate_version = true,
    after_help = "Start with `track demo`: it needs no input and writes ./track-demo/report.html.\n\n\
        Exit codes: 0 success; 1 a computation failed; 2 bad arguments or settings (a --config \
        file included); 3 bad input data (images, ground truth, video); 4 an output could not be \
        written."
)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
}

/// The `track` subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Generate a synthetic scene, track it and write overlays, plots and a report.
    Demo(commands::demo::Args),
    /// Track an object through a sequence of images, a video file or a Y4M stream.
    Run(commands::run::Args),
    /// Evaluate trackers: Odobez's Table 1, the switching processes, or OTB sequences.
    Eval(commands::eval::Args),
    /// Estimate the robust parametric motion between two frames.
    Motion(commands::motion::Args),
    /// Learn clutter densities from images (Wu et al. §6.1).
    LearnClutter(commands::learn_clutter::Args),
    /// Learn a tracker's switching parameters (T_β, T_α, σ_γ, λ̄_k) from sequences by
    /// expectation–maximisation on smoothed runs.
    LearnSwitching(commands::learn_switching::Args),
    /// Print a preset's configuration (JSON or TOML): the settings its tracker reads, to edit and
    /// pass to `--config`.
    Config(commands::config::Args),
}

/// Runs a parsed command line.
///
/// # Errors
/// Whatever the command reports; see [`AppError`].
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Demo(args) => commands::demo::run(&args),
        Command::Run(args) => commands::run::run(&args),
        Command::Eval(args) => commands::eval::run(&args),
        Command::Motion(args) => commands::motion::run(&args),
        Command::LearnClutter(args) => commands::learn_clutter::run(&args),
        Command::LearnSwitching(args) => commands::learn_switching::run(&args),
        Command::Config(args) => commands::config::run(&args),
    }
}

/// Parses `args` (the first item is the program name) and runs the command.
///
/// # Errors
/// Parsing errors become [`AppError::InvalidSetting`]; everything else as [`run`].
pub fn try_main_from_args<I, T>(args: I) -> Result<()>
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli =
        Cli::try_parse_from(args).map_err(|e| AppError::setting("arguments", e.to_string()))?;
    run(cli)
}
