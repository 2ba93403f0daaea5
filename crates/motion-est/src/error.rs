//! The crate's error type.

/// Result alias for this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong when estimating motion or comparing patches.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An invalid grey image (empty, wrong length, or a non-finite pixel).
    #[error(transparent)]
    Image(#[from] vision_core::Error),
    /// An image or mask has zero width or height.
    #[error("{what} is empty ({width}×{height})")]
    Empty {
        /// Which input.
        what: &'static str,
        /// Its width.
        width: usize,
        /// Its height.
        height: usize,
    },
    /// A buffer's length does not match the stated dimensions.
    #[error("{what}: buffer holds {got} values, expected {expected}")]
    DimensionMismatch {
        /// Which input.
        what: &'static str,
        /// The expected length.
        expected: usize,
        /// The actual length.
        got: usize,
    },
    /// A NaN or infinite value was found in an input.
    #[error("{what}: non-finite value at index {index}")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// Index of the first offending value.
        index: usize,
    },
    /// A setting or argument is out of its valid range.
    #[error("invalid {name}: {reason}")]
    InvalidSetting {
        /// The setting or argument.
        name: &'static str,
        /// Why it is invalid.
        reason: String,
    },
    /// The support region holds too few usable pixels to estimate the model.
    #[error("support region has {got} usable pixels at the finest level, need at least {needed}")]
    RegionTooSmall {
        /// Usable pixels found.
        got: usize,
        /// Pixels needed.
        needed: usize,
    },
    /// Two pyramids (or a pyramid and the settings) do not fit together.
    #[error("pyramid mismatch: {reason}")]
    PyramidMismatch {
        /// What does not match.
        reason: String,
    },
    /// The normal equations are singular at the finest level (for example a textureless region),
    /// so no covariance can be given.
    #[error("normal equations are singular at level {level}: the region has too little texture")]
    Degenerate {
        /// The pyramid level (0 = full resolution).
        level: usize,
    },
    /// A parameter vector has the wrong length for its model.
    #[error("parameter vector has {got} entries, the model needs {expected}")]
    ParameterCount {
        /// Entries expected.
        expected: usize,
        /// Entries given.
        got: usize,
    },
}
