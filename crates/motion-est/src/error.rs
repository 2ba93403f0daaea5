//! The crate's error type.

use crate::MotionEstimate;

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
    /// The estimate cannot be trusted as the dominant motion of the region
    /// ([`MotionEstimate::reliable`] is false): it did not converge at full resolution, or no
    /// motion explains enough of the region's pixels (a compromise between motions, or the motion
    /// of a minority). Every estimating entry point returns this instead of `Ok`, so the case
    /// cannot be missed; the estimate is kept for diagnostics only (iterations, inlier fraction,
    /// scale): its parameters and covariance do not describe the region's motion.
    #[error("{}", unreliable_message(estimate))]
    Unreliable {
        /// The estimate, for diagnostics.
        estimate: Box<MotionEstimate>,
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

/// Why an estimate is unreliable, in words.
fn unreliable_message(e: &MotionEstimate) -> String {
    if e.converged {
        format!(
            "unreliable motion estimate: no dominant motion could be separated (inliers {:.1} %, \
             noise scale {:.3} grey levels)",
            100.0 * e.inlier_fraction,
            e.scale
        )
    } else {
        format!(
            "unreliable motion estimate: it did not converge at full resolution (iterations per \
             level {:?})",
            e.iterations
        )
    }
}

impl Error {
    /// The unreliable estimate this error carries ([`Error::Unreliable`]), for diagnostics.
    pub fn unreliable_estimate(&self) -> Option<&MotionEstimate> {
        match self {
            Error::Unreliable { estimate } => Some(estimate),
            _ => None,
        }
    }

    /// The estimate of an [`Error::Unreliable`] as `Ok`, any other error as it is: for a caller
    /// that reports failed estimates too (`estimator.estimate(..).or_else(Error::into_unreliable)`),
    /// and must then read [`MotionEstimate::reliable`] itself.
    ///
    /// # Errors
    /// `self`, when it is not [`Error::Unreliable`].
    pub fn into_unreliable(self) -> Result<MotionEstimate> {
        match self {
            Error::Unreliable { estimate } => Ok(*estimate),
            other => Err(other),
        }
    }
}
