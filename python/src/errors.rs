//! The binding's errors as Python exceptions: `UnreliableMotion`, the mapping of the trackers'
//! errors to `ValueError` or `RuntimeError`, and [`FrameError`], the error of the work done
//! without the GIL.

use pyo3::create_exception;
use pyo3::exceptions::{PyMemoryError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;

create_exception!(
    _native,
    UnreliableMotion,
    pyo3::exceptions::PyRuntimeError,
    "The motion estimate is not reliable: its parameters do not describe the region's motion."
);

/// A tracker error as a Python exception: bad frames and settings are the caller's
/// (`ValueError`), the rest is a failure of the computation (`RuntimeError`).
pub(crate) fn tracker_error(e: trackers::Error) -> PyErr {
    match e {
        trackers::Error::InvalidSetting { .. }
        | trackers::Error::BadFrame { .. }
        | trackers::Error::Image(_)
        | trackers::Error::RgbSize { .. }
        | trackers::Error::UnknownPreset { .. } => PyValueError::new_err(e.to_string()),
        other => PyRuntimeError::new_err(other.to_string()),
    }
}

/// An error met without the GIL, turned into a Python exception once it is held again.
#[derive(Debug)]
pub(crate) enum FrameError {
    /// A bad value in the frame (`ValueError`).
    Value(String),
    /// A frame too large to allocate its buffers (`MemoryError`).
    Memory(String),
    /// `update` before `init` (`RuntimeError`).
    NotStarted,
    /// A call panicked while it held the tracker (`RuntimeError`).
    Poisoned,
    /// The tracker's own error.
    Tracker(trackers::Error),
    /// The motion estimator's error.
    Motion(motion_est::Error),
}

impl From<FrameError> for PyErr {
    fn from(e: FrameError) -> Self {
        match e {
            FrameError::Value(m) => PyValueError::new_err(m),
            FrameError::Memory(m) => PyMemoryError::new_err(m),
            FrameError::NotStarted => PyRuntimeError::new_err(
                "the tracker was not initialised: call init(frame, box) first",
            ),
            FrameError::Poisoned => {
                PyRuntimeError::new_err("the tracker failed in an earlier call")
            }
            FrameError::Tracker(e) => tracker_error(e),
            FrameError::Motion(e) => PyValueError::new_err(format!("motion estimation: {e}")),
        }
    }
}
