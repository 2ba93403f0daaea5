//! The `track` command line. All logic lives in the `track_app` library so that tests can drive it
//! in-process.

use std::io::Write;
use std::process::ExitCode;

use clap::Parser;
use track_app::AppError;
use track_app::cli::{Cli, run};

fn main() -> ExitCode {
    let cli = match Cli::try_parse_from(std::env::args_os()) {
        Ok(cli) => cli,
        // Help and version go to standard output like any other output: a closed pipe ends
        // quietly, a full disk is exit 4 (clap's own printing ignores both).
        Err(e) if !e.use_stderr() => {
            let text = e.render().to_string();
            return match track_app::output::print_stdout(&text) {
                Ok(()) | Err(AppError::StdoutClosed) => ExitCode::SUCCESS,
                Err(err) => {
                    let _ = writeln!(std::io::stderr(), "error: {err}");
                    ExitCode::from(err.exit_code())
                }
            };
        }
        // clap prints usage errors itself, with exit 2.
        Err(e) => e.exit(),
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of standard output went away (`| head`): end quietly, as Unix tools do.
        Err(AppError::StdoutClosed) => ExitCode::SUCCESS,
        Err(e) => {
            // `eprintln!` would panic if standard error were closed too; there is nowhere left to
            // report that, so only the exit code tells.
            let _ = writeln!(std::io::stderr(), "error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
