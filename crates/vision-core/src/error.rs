//! The crate's error type.

/// Result alias for this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in `vision-core`: a grey image that is not what it claims to be.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An image with a zero side.
    #[error("image of {width}x{height} is empty")]
    Empty {
        /// Stated width.
        width: usize,
        /// Stated height.
        height: usize,
    },
    /// An image buffer does not match its stated size.
    #[error("image of {width}x{height} needs {expected} pixels, got {got}")]
    ImageSize {
        /// Stated width.
        width: usize,
        /// Stated height.
        height: usize,
        /// `width * height` (`usize::MAX` when that overflows).
        expected: usize,
        /// Length of the buffer.
        got: usize,
    },
    /// A pixel is NaN or infinite.
    #[error("image pixel at index {index} is not finite")]
    NonFinite {
        /// Row-major index of the first such pixel.
        index: usize,
    },
    /// A box that cannot start a tracker in its frame ([`crate::BoundingBox::check_start`]);
    /// the reason shows the box compactly ([`crate::fmt_num`]).
    #[error("{reason}")]
    StartBox {
        /// What is wrong, with the box and the frame size.
        reason: String,
    },
}
