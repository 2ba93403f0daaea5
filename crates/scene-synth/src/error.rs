//! The crate's error type.

use std::path::PathBuf;

/// Everything that can go wrong while building, rendering or writing a synthetic scene.
#[non_exhaustive]
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An invalid grey image (empty, wrong length, or a non-finite pixel).
    #[error(transparent)]
    GreyImage(#[from] vision_core::Error),
    /// A scenario parameter is out of its documented range (or NaN).
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter {
        /// Dotted path of the parameter, e.g. `target.semi_axes`.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// A scenario name that is not one of the presets.
    #[error("unknown scenario `{name}` (expected one of: mclutter, occlusion, distractor, zoom)")]
    UnknownScenario {
        /// The name that was given.
        name: String,
    },
    /// A frame index beyond the sequence.
    #[error("frame {index} requested from a sequence of {frames} frames")]
    FrameOutOfRange {
        /// The requested 0-based index.
        index: usize,
        /// Number of frames in the sequence.
        frames: usize,
    },
    /// A caller-owned buffer has the wrong size.
    #[error("buffer has {got} elements, expected {expected}")]
    DimensionMismatch {
        /// Required number of elements.
        expected: usize,
        /// Number of elements given.
        got: usize,
    },
    /// Clutter calibration could not reach the requested edge density.
    #[error(
        "clutter calibration for class {class} reached λ = {reached:.4}/px, requested {requested:.4}/px"
    )]
    Calibration {
        /// Clutter class (1–3).
        class: u8,
        /// Requested density (edges per pixel of line).
        requested: f64,
        /// Best density reached.
        reached: f64,
    },
    /// A parameter override could not be applied.
    #[error("cannot apply override: {reason}")]
    Override {
        /// What went wrong.
        reason: String,
    },
    /// Reading or writing a file failed.
    #[error("i/o error on {path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// Encoding a frame as PNG failed.
    #[error("cannot encode {path}: {source}")]
    Image {
        /// The image file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: image::ImageError,
    },
    /// Serialising or parsing JSON failed.
    #[error("json error: {source}")]
    Json {
        /// The underlying error.
        #[from]
        source: serde_json::Error,
    },
}

/// The crate's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
