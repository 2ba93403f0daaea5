//! The trackers' error type.

/// Result alias for the trackers crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can stop a tracker.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A setting is invalid.
    #[error("invalid tracker setting `{name}`: {reason}")]
    InvalidSetting {
        /// The setting.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// A frame does not match what the tracker expects.
    #[error("frame {frame}: {reason}")]
    BadFrame {
        /// Index of the frame (0 = the initialisation frame).
        frame: usize,
        /// What is wrong with it.
        reason: String,
    },
    /// A frame's RGB pixels do not match its size.
    #[error("{got} RGB bytes for a {width}x{height} frame (expected {expected}: 3 per pixel)")]
    RgbSize {
        /// Frame width.
        width: usize,
        /// Frame height.
        height: usize,
        /// `3 · width · height`.
        expected: usize,
        /// Bytes given.
        got: usize,
    },
    /// `update` was called before `init`.
    #[error("the tracker was not initialised: call init() with the first frame")]
    NotInitialised,
    /// The unknown preset name.
    #[error("unknown tracker preset `{name}` (known: {known})")]
    UnknownPreset {
        /// The name given.
        name: String,
        /// The known names, comma separated.
        known: String,
    },
    /// An invalid grey image (empty, wrong length, or a non-finite pixel).
    #[error("image: {0}")]
    Image(#[from] vision_core::Error),
    /// The particle filter failed (degenerate weights and the like).
    #[error("particle filter: {0}")]
    Smc(#[from] smc_core::Error),
    /// The observation layer failed.
    #[error("observation model: {0}")]
    Observation(#[from] contour_obs::Error),
    /// Motion estimation failed in a way that is not a mere non-convergence.
    #[error("motion estimation: {0}")]
    Motion(#[from] motion_est::Error),
    /// A hidden switching process is misconfigured.
    #[error("switching process: {0}")]
    Switching(#[from] dbn_switch::Error),
}
