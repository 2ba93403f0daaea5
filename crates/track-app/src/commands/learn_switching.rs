//! `track learn-switching`: the switching parameters of a tracker (T_β, T_α, σ_γ, optionally
//! λ̄_k) learnt from recorded sequences by expectation–maximisation.
//!
//! Each iteration tracks every sequence with the current configuration, smooths the run
//! (`Tracker::smoothed`), sums the expected transition counts of the hidden processes over all
//! sequences (the E-step, Baum–Welch on the particle approximation) and sets each parameter to
//! its maximum-likelihood value given those counts (the M-step,
//! `SwitchingStatistics::maximise`). Wu names this learning as future work; his matrices were
//! set by hand.

use std::path::{Path, PathBuf};

use trackers::{SmootherSettings, SwitchingStatistics, TrackerConfig};

use crate::commands::eval::track_otb;
use crate::commands::run::{DEFAULT_PARTICLES, DEFAULT_SEED, Overrides, tracker_config};
use crate::{AppError, Result};

/// Arguments of `track learn-switching`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:\n  \
    cargo xtask gen-clutter --all --frames 400 --out scenes\n  \
    track learn-switching scenes/mclutter scenes/occlusion --tracker w-eval --out w-eval-learnt.json\n  \
    track run SEQ --config w-eval-learnt.json")]
pub struct Args {
    /// OTB folders (img/ + groundtruth_rect.txt): each is tracked from its first labelled box.
    #[arg(required = true, value_name = "SEQUENCES")]
    pub sequences: Vec<PathBuf>,
    /// The tracker preset whose parameters are learnt (one with switching processes: w-switch,
    /// w-hmm, w-occ, w-eval, full) [default: w-eval]. Not with --config, which names its own
    /// tracker.
    #[arg(long, value_parser = crate::commands::preset_parser(), conflicts_with = "config")]
    pub tracker: Option<String>,
    /// Start from this configuration instead of the preset's.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Expectation–maximisation iterations.
    #[arg(long, default_value_t = 3)]
    pub iterations: usize,
    /// Also learn the clutter class means λ̄_k.
    #[arg(long)]
    pub lambda: bool,
    /// Number of particles [default: 200, or the configuration file's].
    #[arg(long)]
    pub particles: Option<usize>,
    /// Random seed [default: 1, or the configuration file's].
    #[arg(long)]
    pub seed: Option<u64>,
    /// The learnt configuration (JSON, loadable by `track run --config`).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// No progress bars.
    #[arg(long)]
    pub quiet: bool,
}

/// Most EM iterations (each tracks every sequence once).
pub const MAX_ITERATIONS: usize = 100;

/// The statistics of one smoothed run of `config` on the OTB folder `dir`.
///
/// # Errors
/// As tracking and smoothing.
pub fn run_statistics(
    dir: &Path,
    config: &TrackerConfig,
    quiet: bool,
) -> Result<SwitchingStatistics> {
    let mut config = config.clone();
    config.filter.history = Some(Default::default());
    let (mut session, _, _) = track_otb(dir, &config, quiet)?;
    let (_, statistics) = session.smoothed(&SmootherSettings::default())?;
    Ok(statistics)
}

/// One EM iteration over `sequences`: returns the next configuration.
///
/// # Errors
/// As tracking and smoothing, or a learnt value that makes the configuration invalid.
pub fn em_step(
    sequences: &[PathBuf],
    config: &TrackerConfig,
    lambda: bool,
    quiet: bool,
) -> Result<TrackerConfig> {
    let mut total = SwitchingStatistics::default();
    for dir in sequences {
        total.add(&run_statistics(dir, config, quiet)?);
    }
    let mut next = config.clone();
    total
        .maximise(&mut next, lambda)
        .map_err(|e| AppError::computation("learning the switching parameters", e))?;
    Ok(next)
}

/// Runs `track learn-switching`.
///
/// # Errors
/// Invalid settings, unreadable sequences, a tracker without switching processes, or a failed
/// write.
pub fn run(args: &Args) -> Result<()> {
    if !(1..=MAX_ITERATIONS).contains(&args.iterations) {
        return Err(AppError::setting(
            "--iterations",
            format!("{} must be between 1 and {MAX_ITERATIONS}", args.iterations),
        ));
    }
    let mut config = tracker_config(
        args.tracker.as_deref().unwrap_or("w-eval"),
        args.config.as_deref(),
        Overrides {
            particles: Some(args.particles.unwrap_or(DEFAULT_PARTICLES)),
            seed: Some(args.seed.unwrap_or(DEFAULT_SEED)),
            parallel: false,
            edge_threshold: None,
        },
    )?;
    let switching = matches!(config.clutter, trackers::ClutterMode::Switching(_))
        || !matches!(config.occlusion, trackers::OcclusionMode::None);
    if !switching {
        return Err(AppError::setting(
            "--tracker",
            format!("{} has no switching process to learn", config.name),
        ));
    }
    // Claimed before the work: never an input, never a file of the user's.
    let inputs = args.sequences.iter().chain(args.config.as_ref());
    let out = crate::output::OutputGuard::new(inputs).file(&args.out)?;
    crate::output::probe_dir(
        args.out
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new(".")),
    )?;
    for _ in 0..args.iterations {
        config = em_step(&args.sequences, &config, args.lambda, args.quiet)?;
    }
    config.name = format!("{}-learnt", config.name);
    let json = serde_json::to_string_pretty(&config)
        .map_err(|e| AppError::computation("writing the configuration", e))?;
    out.write(json.as_bytes())?;
    if !args.quiet {
        crate::output::println_stdout(&format!("wrote {}", args.out.display()))?;
    }
    Ok(())
}
