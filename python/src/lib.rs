//! The Python binding of contour-track: the module `contour_track._native`, wrapped by the pure
//! Python package `contour_track` (its `__init__.py` re-exports everything; `__init__.pyi` types
//! it).
//!
//! The binding is thin: [`Tracker`](tracker::Tracker) drives a `Box<dyn trackers::Tracker>`
//! built exactly as `track run` builds it (a preset, or a configuration parsed by
//! [`trackers::TrackerConfig::parse`]), [`estimate_motion`](motion::estimate_motion) calls
//! motion-est's [`MotionEstimator`](motion_est::MotionEstimator). What the binding adds is reading
//! numpy frames ([`frames`]) into the grey (and RGB) frame `track run` hands the trackers, and
//! Python errors for every bad input.
//!
//! The modules: [`tracker`] (the `Tracker` class and its `Status`), [`motion`]
//! (`estimate_motion` and `Motion`), [`config`] (the configuration a call describes, and the
//! presets), [`args`] (reading integers and boxes), [`frames`] (numpy frames), [`errors`] (Python
//! exceptions), [`batch`] (whole sequences through `track_app::batch`) and [`bench`] (the Rust
//! side of the overhead benchmark).

use pyo3::prelude::*;

mod args;
mod batch;
mod bench;
mod config;
mod errors;
mod frames;
mod motion;
mod tracker;

use errors::UnreliableMotion;
use motion::Motion;
use tracker::{Status, Tracker};

/// The extension module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Tracker>()?;
    m.add_class::<Status>()?;
    m.add_class::<Motion>()?;
    m.add_function(wrap_pyfunction!(config::presets, m)?)?;
    m.add_function(wrap_pyfunction!(motion::estimate_motion, m)?)?;
    m.add_function(wrap_pyfunction!(bench::_rust_update_times, m)?)?;
    m.add_function(wrap_pyfunction!(batch::_track_video, m)?)?;
    m.add_function(wrap_pyfunction!(batch::_otb_plan, m)?)?;
    m.add_function(wrap_pyfunction!(batch::_otb_run, m)?)?;
    m.add_function(wrap_pyfunction!(batch::_otb_score, m)?)?;
    m.add("UnreliableMotion", m.py().get_type::<UnreliableMotion>())?;
    m.add("DEFAULT_TRACKER", config::DEFAULT_TRACKER)?;
    Ok(())
}
