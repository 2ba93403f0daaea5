//! The `track` command line. All logic lives in the `track_app` library so that tests can drive it
//! in-process.

fn main() -> std::process::ExitCode {
    track_app::cli::main_from_args(std::env::args_os())
}
