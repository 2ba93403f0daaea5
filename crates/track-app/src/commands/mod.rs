//! One module per subcommand: its clap arguments and its `run` function.

pub mod config;
pub mod demo;
pub mod eval;
pub mod learn_clutter;
pub mod learn_switching;
pub mod motion;
pub mod run;

/// clap's parser of a tracker preset's name. Its possible values are [`trackers::Preset::ALL`], so
/// every command's `--help` lists every preset and cannot go stale.
pub fn preset_parser() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(trackers::Preset::ALL.map(trackers::Preset::name))
}
