//! One module per subcommand: its clap arguments and its `run` function.

pub mod config;
pub mod demo;
pub mod eval;
pub mod learn_clutter;
pub mod learn_switching;
pub mod motion;
pub mod run;
