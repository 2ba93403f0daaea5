//! The crate's error type.

use std::fmt;

/// Why a set of weights cannot represent a distribution.
///
/// Carried by [`Error::DegenerateWeights`] (the filter knows the step) and
/// [`Error::InvalidWeights`] (a resampler called directly does not).
#[non_exhaustive]
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Degeneracy {
    /// Every weight is zero (every log weight is −∞): nothing is left to normalise.
    AllZero,
    /// A weight or log-weight increment is NaN.
    NotANumber {
        /// Index of the first offending particle.
        index: usize,
    },
    /// A log-weight increment is +∞ (a likelihood or density ratio overflowed).
    PositiveInfinity {
        /// Index of the first offending particle.
        index: usize,
    },
    /// A linear weight handed to a resampler is negative or infinite.
    OutOfRange {
        /// Index of the first offending particle.
        index: usize,
        /// The offending value.
        value: f64,
    },
}

impl fmt::Display for Degeneracy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::AllZero => write!(f, "every weight is zero (all log weights are -inf)"),
            Self::NotANumber { index } => write!(f, "NaN at particle {index}"),
            Self::PositiveInfinity { index } => write!(f, "+inf log weight at particle {index}"),
            Self::OutOfRange { index, value } => {
                write!(
                    f,
                    "weight {value} at particle {index} is negative or infinite"
                )
            }
        }
    }
}

/// Everything that can go wrong in `smc-core`.
#[non_exhaustive]
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// The weights of a filter step cannot be normalised. Raised at the step where the problem
    /// first appears, so that no NaN travels further.
    #[error("degenerate weights at step {step}: {reason}")]
    DegenerateWeights {
        /// The filter step (as passed by the caller) at which the weights degenerated.
        step: u64,
        /// What is wrong with them.
        reason: Degeneracy,
    },
    /// Weights handed directly to a resampler or a set constructor are unusable.
    #[error("invalid weights: {reason}")]
    InvalidWeights {
        /// What is wrong with them.
        reason: Degeneracy,
    },
    /// A setting or argument is outside its valid range.
    #[error("invalid setting `{name}`: {reason}")]
    InvalidSetting {
        /// Name of the setting or argument.
        name: &'static str,
        /// Why it is invalid.
        reason: String,
    },
    /// Two buffers that must have the same length do not.
    #[error("length mismatch for {what}: expected {expected}, got {got}")]
    LengthMismatch {
        /// Which buffer.
        what: &'static str,
        /// The length it must have.
        expected: usize,
        /// The length it has.
        got: usize,
    },
    /// A state viewed as a vector has the wrong dimension.
    #[error("dimension mismatch: expected {expected}, got {got}")]
    DimensionMismatch {
        /// Dimension of the first state.
        expected: usize,
        /// Dimension of the offending state.
        got: usize,
    },
    /// A particle carries a label that is not below the declared number of labels.
    #[error("label {label} out of range: there are {n_labels} labels")]
    LabelOutOfRange {
        /// The offending label.
        label: usize,
        /// The declared number of labels.
        n_labels: usize,
    },
    /// A smoother was handed a history with no frame.
    #[error("the history holds no frame")]
    EmptyHistory,
    /// A frame after the first has no recorded ancestors, so its genealogy is unknown.
    #[error("frame {frame} of the history has no recorded ancestors")]
    MissingAncestors {
        /// Index of the frame in the history.
        frame: usize,
    },
    /// The backward kernel from a particle of frame `frame + 1` to frame `frame` cannot be
    /// normalised: every filtering weight of frame `frame` times the transition density to that
    /// particle is zero, or a transition log-density is NaN or +∞.
    #[error("degenerate backward kernel from particle {particle} of frame {} to frame {frame}: {reason}", frame + 1)]
    DegenerateBackward {
        /// Index (in the history) of the frame the kernel points into.
        frame: usize,
        /// Index of the particle in frame `frame + 1`.
        particle: usize,
        /// What is wrong.
        reason: Degeneracy,
    },
    /// A transition log-density exceeded the upper bound declared by
    /// [`crate::model::TransitionDensity::log_density_bound`], which the rejection sampler relies on.
    #[error(
        "transition log-density {log_density} into frame {frame} exceeds its declared bound {log_bound}"
    )]
    BoundExceeded {
        /// Index (in the history) of the frame of the next state.
        frame: usize,
        /// The log-density found.
        log_density: f64,
        /// The bound declared for it.
        log_bound: f64,
    },
}

impl Error {
    /// Attaches a step index to an [`Error::InvalidWeights`]; other errors pass unchanged.
    #[must_use]
    pub fn at_step(self, step: u64) -> Self {
        match self {
            Self::InvalidWeights { reason } => Self::DegenerateWeights { step, reason },
            other => other,
        }
    }
}

/// The crate's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
