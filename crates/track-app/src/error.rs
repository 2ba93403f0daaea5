//! The command line's error type and its exit codes.

use std::path::PathBuf;

/// Result alias for the command line.
pub type Result<T, E = AppError> = std::result::Result<T, E>;

/// Everything that can stop a `track` command. Each variant names the file or value at fault.
///
/// Exit codes (also in `track --help` and docs/CLI.md's table): 0 success, 1 a computation failed
/// (for example the filter degenerated, or `track motion` found no reliable motion), 2 bad
/// command-line arguments or settings — a `--config` file included, whether it does not parse or
/// holds a value out of range —, 3 bad input data (images, ground truth, video, ffmpeg missing
/// for a video), 4 an output could not be written. A closed standard output ends a command quietly
/// with 0; a run stopped by a signal exits with 128 + the signal number (130 for Ctrl-C, 143 for
/// SIGTERM) after writing what it had computed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum AppError {
    /// A command-line value or configuration setting is invalid.
    #[error("invalid value for {name}: {reason}")]
    InvalidSetting {
        /// The option or configuration key.
        name: String,
        /// What is wrong with it.
        reason: String,
    },
    /// An input file or folder is missing, unreadable or malformed.
    #[error("{}: {reason}", path.display())]
    BadInput {
        /// The offending file or folder.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// An output could not be written.
    #[error("cannot write {}: {source}", path.display())]
    Write {
        /// The output path.
        path: PathBuf,
        /// The underlying I/O error.
        source: std::io::Error,
    },
    /// A computation failed (the library's own error, with its context).
    #[error("{context}: {message}")]
    Computation {
        /// What was being computed.
        context: String,
        /// The library's error message.
        message: String,
    },
    /// The command is not available yet.
    #[error("`track {0}` is not implemented yet")]
    NotImplemented(&'static str),
    /// Standard output was closed by its reader (for example `track config full | head -c 10`):
    /// the command stops quietly with exit 0, as Unix tools do.
    #[error("standard output closed")]
    StdoutClosed,
    /// The run was stopped by a signal (Ctrl-C, SIGTERM) after writing what it had computed.
    #[error(
        "interrupted by {signal} after {frames} frames; the outputs of those frames are in {}",
        out.display()
    )]
    Interrupted {
        /// The signal's name (`SIGINT`, `SIGTERM`, …).
        signal: &'static str,
        /// The signal's number: the exit code is 128 + it, the shells' convention.
        number: u8,
        /// Frames tracked and written.
        frames: usize,
        /// The output folder.
        out: PathBuf,
    },
    /// `track eval otb` was stopped by a signal after the runs in progress: the tables of the runs
    /// that finished were written, and say so.
    #[error(
        "interrupted by {signal} after {runs} of {total} runs; the tables of those runs are in {}",
        out.display()
    )]
    InterruptedRuns {
        /// The signal's name.
        signal: &'static str,
        /// The signal's number: the exit code is 128 + it.
        number: u8,
        /// Runs finished and scored.
        runs: usize,
        /// Runs asked for.
        total: usize,
        /// The output folder.
        out: PathBuf,
    },
    /// A signal stopped the command before it began tracking: nothing was written.
    #[error("interrupted by {signal} before tracking began; nothing was written")]
    InterruptedBeforeStart {
        /// The signal's name.
        signal: &'static str,
        /// The signal's number: the exit code is 128 + it.
        number: u8,
    },
}

impl AppError {
    /// The process exit code for this error (see the type's documentation).
    pub fn exit_code(&self) -> u8 {
        match self {
            AppError::Computation { .. } | AppError::NotImplemented(_) => 1,
            AppError::InvalidSetting { .. } => 2,
            AppError::BadInput { .. } => 3,
            AppError::Write { .. } => 4,
            AppError::StdoutClosed => 0,
            AppError::Interrupted { number, .. }
            | AppError::InterruptedRuns { number, .. }
            | AppError::InterruptedBeforeStart { number, .. } => 128u8.saturating_add(*number),
        }
    }

    /// Shorthand for [`AppError::InvalidSetting`].
    pub fn setting(name: impl Into<String>, reason: impl Into<String>) -> Self {
        AppError::InvalidSetting {
            name: name.into(),
            reason: reason.into(),
        }
    }

    /// Shorthand for [`AppError::BadInput`].
    pub fn input(path: impl Into<PathBuf>, reason: impl Into<String>) -> Self {
        AppError::BadInput {
            path: path.into(),
            reason: reason.into(),
        }
    }

    /// Shorthand for [`AppError::Computation`] from any library error.
    pub fn computation(context: impl Into<String>, error: impl std::fmt::Display) -> Self {
        AppError::Computation {
            context: context.into(),
            message: error.to_string(),
        }
    }
}
