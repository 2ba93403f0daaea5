//! `cargo xtask`: project automation. Thin by design: generation logic lives in library crates.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Project automation for the contour-tracking workspace.
#[derive(Debug, Parser)]
#[command(name = "cargo xtask")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Placeholder until the scene generator lands.
    Noop,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Noop => ExitCode::SUCCESS,
    }
}
