//! The crate's error type.

/// Result alias for this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in `contour-obs`. Each variant names the value at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A setting is out of its valid range.
    #[error("invalid setting {name}: {reason}")]
    InvalidSetting {
        /// The setting's field name.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// An invalid grey image (wrong size, empty, or a non-finite pixel).
    #[error(transparent)]
    Image(#[from] vision_core::Error),
    /// An image is too small for the requested operation.
    #[error("image of {width}x{height} is too small: at least {min}x{min} pixels are needed")]
    ImageTooSmall {
        /// Image width.
        width: usize,
        /// Image height.
        height: usize,
        /// Minimum side length.
        min: usize,
    },
    /// A value that must be finite is NaN or infinite.
    #[error("{what} at index {index} is not finite")]
    NonFinite {
        /// What the value is (an image pixel, a pose, λ, γ, …).
        what: &'static str,
        /// Where it is (pixel index, hypothesis index, point index).
        index: usize,
    },
    /// A per-hypothesis parameter is outside its valid range.
    #[error("{what} at index {index} is {value}, outside {range}")]
    OutOfRange {
        /// The parameter (λ, γ, …).
        what: &'static str,
        /// Hypothesis index.
        index: usize,
        /// The offending value.
        value: f64,
        /// The valid range, for the message.
        range: &'static str,
    },
    /// Two slices that must have matching lengths do not.
    #[error("{what}: expected length {expected}, got {got}")]
    LengthMismatch {
        /// Which slice.
        what: &'static str,
        /// The required length.
        expected: usize,
        /// The given length.
        got: usize,
    },
    /// A geometric construction (conic fit, B-spline) has no valid solution for the input.
    #[error("degenerate geometry: {reason}")]
    Degenerate {
        /// Why.
        reason: String,
    },
    /// Clustering cannot form the requested number of clusters.
    #[error("cannot form {k} clusters from {distinct} distinct values")]
    TooFewDistinct {
        /// Requested number of clusters.
        k: usize,
        /// Number of distinct values available.
        distinct: usize,
    },
    /// No training images were given.
    #[error("no images given")]
    NoImages,
}
