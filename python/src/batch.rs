//! Whole sequences from Python: `track run` and the runs of `track eval otb` through
//! `track_app::batch`, the library functions the command line's own code paths are built from.
//! The Python side (`contour_track.track_video`, `contour_track.cluster`) wraps these; they are
//! not public API on their own.

use std::path::PathBuf;

use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use track_app::AppError;
use track_app::batch::otb::{self, RunResult, RunSpec, TrackerRuns, TrackerSpec};
use track_app::batch::video;
use vision_core::{BoundingBox, TrackStatus};

/// A `track` error as a Python exception: settings and inputs are the caller's (`ValueError`),
/// an output that cannot be written is an `OSError`, a failed computation a `RuntimeError`.
pub fn app_error(e: AppError) -> PyErr {
    match e {
        AppError::InvalidSetting { .. } | AppError::BadInput { .. } => {
            PyValueError::new_err(e.to_string())
        }
        AppError::Write { .. } => PyOSError::new_err(e.to_string()),
        other => PyRuntimeError::new_err(other.to_string()),
    }
}

/// Tracks a whole sequence as `track run` does; returns the per-frame columns and the summary
/// (JSON text). See `contour_track.track_video`.
#[pyfunction]
#[pyo3(signature = (source, init, preset=None, particles=None, seed=None, config=None, out=None))]
#[allow(clippy::too_many_arguments)]
pub fn _track_video<'py>(
    py: Python<'py>,
    source: PathBuf,
    init: Option<&Bound<'py, PyAny>>,
    preset: Option<&str>,
    particles: Option<&Bound<'py, PyAny>>,
    seed: Option<&Bound<'py, PyAny>>,
    config: Option<&Bound<'py, PyAny>>,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let particles = crate::args::non_negative(particles, "particles")?;
    let seed = crate::args::non_negative(seed, "seed")?;
    let config = crate::config::tracker_config(py, preset, particles, seed, config)?;
    let init = match init.filter(|b| !b.is_none()) {
        Some(b) => {
            let b = crate::args::parse_box(b, "init")?;
            crate::args::check_finite_box(&b, "init")?;
            Some(b)
        }
        None => None,
    };
    let source = source.to_string_lossy().into_owned();
    let run = py
        .detach(|| video::track_video(&source, init, &config, out.as_deref()))
        .map_err(app_error)?;
    let r = &run.records;
    let d = PyDict::new(py);
    d.set_item("start", run.start)?;
    d.set_item("frame", r.iter().map(|r| r.frame).collect::<Vec<_>>())?;
    let boxes: Vec<[f64; 4]> = r
        .iter()
        .map(|r| [r.bbox.x, r.bbox.y, r.bbox.w, r.bbox.h])
        .collect();
    d.set_item("box", boxes)?;
    let ellipses: Vec<[f64; 5]> = r
        .iter()
        .map(|r| {
            let e = r.ellipse;
            [e.cx, e.cy, e.a, e.b, e.angle]
        })
        .collect();
    d.set_item("ellipse", ellipses)?;
    let prob = |k: usize| -> Vec<f64> {
        r.iter()
            .map(|r| r.alpha_probs.get(k).copied().unwrap_or(f64::NAN))
            .collect()
    };
    d.set_item("p_locked", prob(TrackStatus::Locked.index()))?;
    d.set_item("p_partial", prob(TrackStatus::PartiallyOccluded.index()))?;
    d.set_item("p_lost", prob(TrackStatus::Lost.index()))?;
    d.set_item(
        "state",
        r.iter()
            .map(|r| r.alpha_hat.map_or("", |s| s.name()))
            .collect::<Vec<_>>(),
    )?;
    d.set_item("ess", r.iter().map(|r| r.ess).collect::<Vec<_>>())?;
    d.set_item("millis", r.iter().map(|r| r.millis).collect::<Vec<_>>())?;
    let summary = serde_json::to_string(&run.summary)
        .map_err(|e| PyRuntimeError::new_err(format!("summary: {e}")))?;
    d.set_item("summary", summary)?;
    Ok(d)
}

/// The trackers of an evaluation: `("preset", NAME)` or `("config", PATH)` pairs.
fn tracker_runs(
    trackers: Vec<(String, PathBuf)>,
    particles: Option<&Bound<'_, PyAny>>,
    seed: Option<&Bound<'_, PyAny>>,
) -> PyResult<TrackerRuns> {
    let trackers = trackers
        .into_iter()
        .map(|(kind, value)| match kind.as_str() {
            "preset" => Ok(TrackerSpec::Preset(value.to_string_lossy().into_owned())),
            "config" => Ok(TrackerSpec::Config(value)),
            other => Err(PyValueError::new_err(format!(
                "a tracker is a preset or a config, not {other:?}"
            ))),
        })
        .collect::<PyResult<_>>()?;
    let particles = crate::args::non_negative(particles, "particles")?
        .map(|n| usize::try_from(n).unwrap_or(usize::MAX));
    Ok(TrackerRuns {
        trackers,
        particles,
        seed: crate::args::non_negative(seed, "seed")?,
    })
}

fn protocols(names: &[String]) -> PyResult<Vec<track_app::otb::Protocol>> {
    names
        .iter()
        .map(|n| otb::parse_protocol(n).map_err(app_error))
        .collect()
}

/// Every run of `track eval otb FOLDERS` with these trackers, protocols, particles and seed, as
/// JSON run specs, in its order. See `contour_track.cluster.evaluate_otb`.
#[pyfunction]
#[pyo3(signature = (folders, trackers, protocols, particles=None, seed=None))]
pub fn _otb_plan(
    py: Python<'_>,
    folders: Vec<PathBuf>,
    trackers: Vec<(String, PathBuf)>,
    protocols: Vec<String>,
    particles: Option<&Bound<'_, PyAny>>,
    seed: Option<&Bound<'_, PyAny>>,
) -> PyResult<Vec<String>> {
    let runs = tracker_runs(trackers, particles, seed)?;
    let protocols = self::protocols(&protocols)?;
    let specs = py
        .detach(|| otb::plan(&folders, &runs, &protocols))
        .map_err(app_error)?;
    specs
        .iter()
        .map(|s| serde_json::to_string(s).map_err(|e| PyRuntimeError::new_err(e.to_string())))
        .collect()
}

fn parse_spec(text: &str) -> PyResult<RunSpec> {
    serde_json::from_str(text).map_err(|e| PyValueError::new_err(format!("run spec: {e}")))
}

/// The outcome of one run as Python objects: boxes (x, y, w, h) from the start frame on, P(lost)
/// of each (None without a status process), and the tracking time in seconds.
type RunTuple = (Vec<(f64, f64, f64, f64)>, Vec<Option<f64>>, f64);

/// Tracks one run of a plan. See `contour_track.cluster.evaluate_otb`.
#[pyfunction]
pub fn _otb_run(py: Python<'_>, spec: &str) -> PyResult<RunTuple> {
    let spec = parse_spec(spec)?;
    let r = py.detach(|| otb::run(&spec)).map_err(app_error)?;
    Ok((
        r.boxes.iter().map(|b| (b.x, b.y, b.w, b.h)).collect(),
        r.p_lost,
        r.seconds,
    ))
}

/// Scores the runs of a plan and writes `track eval otb`'s files into `out`; returns
/// `(protocol, otb.md, otb.csv)` per protocol.
#[pyfunction]
#[pyo3(signature = (out, folders, trackers, protocols, specs, results, particles=None, seed=None, command=""))]
#[allow(clippy::too_many_arguments)]
pub fn _otb_score(
    py: Python<'_>,
    out: PathBuf,
    folders: Vec<PathBuf>,
    trackers: Vec<(String, PathBuf)>,
    protocols: Vec<String>,
    specs: Vec<String>,
    results: Vec<RunTuple>,
    particles: Option<&Bound<'_, PyAny>>,
    seed: Option<&Bound<'_, PyAny>>,
    command: &str,
) -> PyResult<Vec<(String, String, String)>> {
    let runs = tracker_runs(trackers, particles, seed)?;
    let protocols = self::protocols(&protocols)?;
    if specs.len() != results.len() {
        return Err(PyValueError::new_err(format!(
            "{} run specs but {} results",
            specs.len(),
            results.len()
        )));
    }
    let pairs: Vec<(RunSpec, RunResult)> = specs
        .iter()
        .zip(results)
        .map(|(s, (boxes, p_lost, seconds))| {
            Ok((
                parse_spec(s)?,
                RunResult {
                    boxes: boxes
                        .into_iter()
                        .map(|(x, y, w, h)| BoundingBox::new(x, y, w, h))
                        .collect(),
                    p_lost,
                    seconds,
                },
            ))
        })
        .collect::<PyResult<_>>()?;
    let tables = py
        .detach(|| otb::score(&out, &folders, &runs, &protocols, &pairs, command))
        .map_err(app_error)?;
    Ok(tables
        .into_iter()
        .map(|t| (t.protocol.name().to_owned(), t.markdown, t.csv))
        .collect())
}
