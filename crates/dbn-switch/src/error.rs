//! The crate's error type.

use std::path::PathBuf;

/// Everything that can go wrong when building, running or loading a switching process.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A transition matrix has no rows.
    #[error("transition matrix is empty")]
    EmptyMatrix,

    /// A transition matrix is not square: row `row` has `cols` entries, but there are `rows` rows.
    #[error("transition matrix is not square: row {row} has {cols} entries, expected {rows}")]
    NonSquareMatrix {
        /// Number of rows.
        rows: usize,
        /// The offending row.
        row: usize,
        /// Number of entries in that row.
        cols: usize,
    },

    /// A transition probability is negative or not finite.
    #[error("transition matrix entry ({row}, {col}) = {value} is not a probability")]
    InvalidProbability {
        /// Row of the entry.
        row: usize,
        /// Column of the entry.
        col: usize,
        /// The value found.
        value: f64,
    },

    /// A row of a transition matrix does not sum to 1 within [`crate::ROW_SUM_TOLERANCE`].
    #[error("transition matrix row {row} sums to {sum}, not 1")]
    InvalidTransitionMatrix {
        /// The offending row.
        row: usize,
        /// Its sum.
        sum: f64,
    },

    /// An interval `[low, high]` is empty, reversed, not finite, or leaves its allowed domain.
    #[error("invalid range for {name}: [{low}, {high}]")]
    InvalidRange {
        /// Which range (e.g. `"partially_occluded"`).
        name: String,
        /// Lower bound.
        low: f64,
        /// Upper bound.
        high: f64,
    },

    /// A standard deviation is not strictly positive and finite.
    #[error("standard deviation {name} = {value} must be finite and > 0")]
    InvalidStd {
        /// Which parameter.
        name: String,
        /// The value found.
        value: f64,
    },

    /// A parameter that must be strictly positive (such as a fixed clutter density λ) is not.
    #[error("{name} = {value} must be > 0")]
    NonPositive {
        /// Which parameter.
        name: String,
        /// The value found.
        value: f64,
    },

    /// A number that must be finite is NaN or infinite.
    #[error("{name} is not finite: {value}")]
    NonFinite {
        /// Which quantity.
        name: String,
        /// The value found.
        value: f64,
    },

    /// Two sizes that must agree do not.
    #[error("dimension mismatch for {name}: expected {expected}, got {got}")]
    DimensionMismatch {
        /// Which quantity.
        name: String,
        /// The size required.
        expected: usize,
        /// The size given.
        got: usize,
    },

    /// A discrete label is outside `0..n_states`.
    #[error("label {label} is out of range for {n_states} states")]
    LabelOutOfRange {
        /// The label found.
        label: usize,
        /// Number of states of the chain.
        n_states: usize,
    },

    /// A probability vector (initial distribution or particle weights) is not one: a negative,
    /// non-finite entry, or a sum away from 1.
    #[error("{name} is not a probability vector (sum {sum})")]
    NotAProbabilityVector {
        /// Which vector.
        name: String,
        /// Its sum (NaN when an entry is invalid).
        sum: f64,
    },

    /// An observation likelihood is negative or not finite.
    #[error("likelihood at step {step}, state {state} is invalid: {value}")]
    InvalidLikelihood {
        /// Time step.
        step: usize,
        /// State index.
        state: usize,
        /// The value found.
        value: f64,
    },

    /// Every state has zero posterior mass after an observation: the observations are impossible
    /// under the model.
    #[error("observation at step {step} has zero probability under every state")]
    ZeroEvidence {
        /// Time step.
        step: usize,
    },

    /// The chain has no unique stationary distribution (it is reducible).
    #[error("the Markov chain has no unique stationary distribution")]
    NoUniqueStationary,

    /// No particles were given to an estimator.
    #[error("no particles")]
    Empty,

    /// Reading or writing a configuration file failed.
    #[error("i/o error on {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },

    /// A JSON configuration could not be parsed or written.
    #[error("JSON: {source}")]
    Json {
        /// The underlying error.
        #[from]
        source: serde_json::Error,
    },

    /// A TOML configuration could not be parsed.
    #[error("TOML: {source}")]
    TomlDe {
        /// The underlying error.
        #[from]
        source: toml::de::Error,
    },

    /// A TOML configuration could not be written.
    #[error("TOML: {source}")]
    TomlSer {
        /// The underlying error.
        #[from]
        source: toml::ser::Error,
    },

    /// A configuration file has an extension other than `.json` or `.toml`.
    #[error("unknown configuration format for {path} (expected .json or .toml)")]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
}

/// The crate's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Returns `Err(NonFinite)` when `value` is NaN or infinite.
pub(crate) fn check_finite(name: &str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::NonFinite {
            name: name.to_owned(),
            value,
        })
    }
}

/// Returns `Err(InvalidStd)` unless `value` is finite and strictly positive.
pub(crate) fn check_std(name: &str, value: f64) -> Result<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(Error::InvalidStd {
            name: name.to_owned(),
            value,
        })
    }
}
