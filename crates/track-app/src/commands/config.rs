//! `track config`: print a preset's configuration, the starting point of a `--config` file: every
//! setting the preset's tracker reads, and nothing else (a section it does not read, such as
//! `motion` without the motion proposal, is left out, and loads as its default; see
//! `trackers::TrackerConfig`).

use trackers::Preset;

use crate::commands::run::{DEFAULT_PARTICLES, DEFAULT_SEED};
use crate::{AppError, Result};

/// Arguments of `track config`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:\n  \
    track config m3 > m3.json                      # edit, then: track run SEQ --config m3.json\n  \
    track config full --toml --particles 500 > full.toml")]
pub struct Args {
    /// Tracker preset.
    #[arg(value_parser = crate::commands::preset_parser())]
    pub preset: String,
    /// Number of particles.
    #[arg(long, default_value_t = DEFAULT_PARTICLES)]
    pub particles: usize,
    /// Random seed.
    #[arg(long, default_value_t = DEFAULT_SEED)]
    pub seed: u64,
    /// Print TOML instead of JSON.
    #[arg(long)]
    pub toml: bool,
}

/// Runs `track config`.
///
/// # Errors
/// [`AppError::InvalidSetting`] for an unknown preset, or a configuration that would not load
/// (`--particles` out of range): nothing is printed then.
pub fn run(args: &Args) -> Result<()> {
    let preset =
        Preset::from_name(&args.preset).map_err(|e| AppError::setting("preset", e.to_string()))?;
    let config = preset.config(args.particles, args.seed);
    config
        .validate()
        .map_err(|e| AppError::setting("--particles", e.to_string()))?;
    let text = if args.toml {
        toml::to_string_pretty(&config).map_err(|e| AppError::computation("TOML", e))?
    } else {
        serde_json::to_string_pretty(&config).map_err(|e| AppError::computation("JSON", e))?
    };
    crate::output::println_stdout(&text)
}
