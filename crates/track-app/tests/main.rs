//! The integration tests of this package, in one test binary (one binary per package keeps a
//! cold build short: each test binary links the whole dependency tree).

mod bad_inputs;
mod common;
mod config_files;
mod golden;
mod learn_switching;
mod messages;
mod motion_failures;
mod otb_protocols;
mod output_guard;
mod outputs;
mod readme_examples;
mod real_footage;
mod reliability;
mod silent_results;
mod smoothing_cli;
mod stress_suite;
mod user_files;
mod video;
