//! The Python binding of contour-track: the module `contour_track._native`, wrapped by the pure
//! Python package `contour_track` (its `__init__.py` re-exports everything; `__init__.pyi` types
//! it).
//!
//! The binding is thin: [`Tracker`] drives a `Box<dyn trackers::Tracker>` built exactly as
//! `track run` builds it (a preset, or a configuration parsed by
//! [`trackers::TrackerConfig::parse`]), [`estimate_motion`] calls motion-est's
//! [`MotionEstimator`]. What the binding adds is reading numpy frames ([`frames`]) into the grey
//! (and RGB) frame `track run` hands the trackers, and Python errors for every bad input.

use numpy::{PyUntypedArray, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyMemoryError, PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use motion_est::{MaskView, ModelSpec, MotionEstimate, MotionEstimator, MotionModel, Region};
use trackers::{ConfigFormat, Estimate, Preset, TrackerConfig};
use vision_core::{BoundingBox, TrackStatus};

mod batch;
mod frames;

use frames::{ChannelOrder, FrameBuffers, FrameInput};
use track_app::groundtruth::fmt_num;

create_exception!(
    _native,
    UnreliableMotion,
    pyo3::exceptions::PyRuntimeError,
    "The motion estimate is not reliable: its parameters do not describe the region's motion."
);

/// A tracker error as a Python exception: bad frames and settings are the caller's
/// (`ValueError`), the rest is a failure of the computation (`RuntimeError`).
fn tracker_error(e: trackers::Error) -> PyErr {
    match e {
        trackers::Error::InvalidSetting { .. }
        | trackers::Error::BadFrame { .. }
        | trackers::Error::Image(_)
        | trackers::Error::RgbSize { .. }
        | trackers::Error::UnknownPreset { .. } => PyValueError::new_err(e.to_string()),
        other => PyRuntimeError::new_err(other.to_string()),
    }
}

/// An integer argument as Python's `operator.index` reads it: an `int`, or any object with
/// `__index__` (numpy's integer scalars), but not a `bool` (numpy's `bool_` included) nor a float.
///
/// # Errors
/// `TypeError` naming `what` and the type given.
fn index_of<'py>(v: &Bound<'py, PyAny>, what: &str) -> PyResult<Bound<'py, pyo3::types::PyInt>> {
    let type_name = v.get_type().name()?.to_string();
    let refused = || {
        PyTypeError::new_err(format!(
            "{what} must be an int (or a numpy integer), got {type_name}"
        ))
    };
    if v.is_instance_of::<pyo3::types::PyBool>() || type_name == "bool_" || type_name == "bool" {
        return Err(refused());
    }
    if let Ok(i) = v.cast::<pyo3::types::PyInt>() {
        return Ok(i.clone());
    }
    let index = v.py().import("operator")?.call_method1("index", (v,));
    match index {
        Ok(i) => i.cast_into::<pyo3::types::PyInt>().map_err(|_| refused()),
        Err(_) => Err(refused()),
    }
}

/// An integer for a message: as it is up to 20 digits, else its number of digits, so that the
/// message stays one short line.
fn int_text(i: &Bound<'_, pyo3::types::PyInt>) -> String {
    let text = i.to_string();
    let digits = text.trim_start_matches('-').len();
    if digits <= 20 {
        text
    } else {
        format!("an integer of {digits} digits")
    }
}

/// Extracts an optional non-negative integer keyword with a clear `ValueError`/`TypeError`;
/// numpy integer scalars are accepted as ints are.
fn non_negative(value: Option<&Bound<'_, PyAny>>, what: &str) -> PyResult<Option<u64>> {
    let Some(v) = value.filter(|v| !v.is_none()) else {
        return Ok(None);
    };
    let i = index_of(v, what)?;
    i.extract::<u64>().map(Some).map_err(|_| {
        PyValueError::new_err(format!(
            "{what} must be a non-negative integer below 2**64, got {}",
            int_text(&i)
        ))
    })
}

/// The key path of a configuration value in messages: `filter.resample_threshold`, `terms[2]`.
fn key_path(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_owned()
    } else if key.starts_with('[') {
        format!("{path}{key}")
    } else {
        format!("{path}.{key}")
    }
}

/// A copy of a configuration dict made of JSON's own types, each value checked on the way so
/// that a bad one is named by its key: numpy integers become ints and numpy floats floats; a NaN
/// or infinity, an integer beyond 64 bits, or a value JSON cannot hold is refused.
///
/// # Errors
/// `ValueError` naming the key for a non-finite number or an integer out of range; `TypeError`
/// naming the key for a value of another type.
fn json_value<'py>(v: &Bound<'py, PyAny>, path: &str) -> PyResult<Bound<'py, PyAny>> {
    use pyo3::types::{PyBool, PyFloat, PyList, PyString, PyTuple};
    let py = v.py();
    let at = if path.is_empty() { "config" } else { path };
    if v.is_none() || v.is_instance_of::<PyBool>() || v.is_instance_of::<PyString>() {
        return Ok(v.clone());
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let out = PyDict::new(py);
        for (k, value) in d.iter() {
            let key: String = k.extract().map_err(|_| {
                PyTypeError::new_err(format!("config: {at} has a key that is not a string: {k}"))
            })?;
            out.set_item(&key, json_value(&value, &key_path(path, &key))?)?;
        }
        return Ok(out.into_any());
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let out = PyList::empty(py);
        for (k, item) in v.try_iter()?.enumerate() {
            out.append(json_value(&item?, &key_path(path, &format!("[{k}]")))?)?;
        }
        return Ok(out.into_any());
    }
    let type_name = v.get_type().name()?.to_string();
    if type_name == "bool_" {
        return Ok(PyBool::new(py, v.is_truthy()?).to_owned().into_any());
    }
    if !v.is_instance_of::<PyFloat>()
        && let Ok(i) = index_of(v, at)
    {
        if i.extract::<i64>().is_err() && i.extract::<u64>().is_err() {
            return Err(PyValueError::new_err(format!(
                "config: {at} is out of range (an integer of at most 64 bits), got {}",
                int_text(&i)
            )));
        }
        return Ok(i.into_any());
    }
    if let Ok(x) = v.extract::<f64>()
        && (v.is_instance_of::<PyFloat>() || type_name.starts_with("float"))
    {
        if !x.is_finite() {
            return Err(PyValueError::new_err(format!(
                "config: {at} = {x} is not a finite number"
            )));
        }
        return Ok(PyFloat::new(py, x).into_any());
    }
    Err(PyTypeError::new_err(format!(
        "config: {at} is a {type_name}, which a configuration cannot hold (give numbers, \
         strings, booleans, lists and dicts)"
    )))
}

/// The key at a position of `json` (text as `json.dumps(..., indent=1)` writes it, one key per
/// line): the dotted path of the keys open at line `line` (1-based).
fn key_at_line(json: &str, line: usize) -> Option<String> {
    let mut stack: Vec<String> = Vec::new();
    let mut here = None;
    for (i, text) in json.lines().enumerate().take(line) {
        let t = text.trim();
        let key = t
            .strip_prefix('"')
            .and_then(|r| r.split_once("\": "))
            .map(|(k, _)| k.to_owned());
        if i + 1 == line {
            here = key.or_else(|| stack.last().cloned().map(|_| String::new()));
            break;
        }
        if t.ends_with('{') || t.ends_with('[') {
            stack.push(key.unwrap_or_else(|| "[]".to_owned()));
        } else if t.starts_with('}') || t.starts_with(']') {
            stack.pop();
        }
    }
    let mut parts: Vec<String> = stack.into_iter().filter(|k| k != "[]").collect();
    if let Some(k) = here.filter(|k| !k.is_empty()) {
        parts.push(k);
    }
    (!parts.is_empty()).then(|| parts.join("."))
}

/// A configuration parser's message made short and pointed at the key: `at line L column C` is
/// replaced by the key found at that line of `json`.
fn config_message(message: &str, json: &str) -> String {
    let Some(pos) = message.find(" at line ") else {
        return message.to_owned();
    };
    let line = message[pos + 9..]
        .split_whitespace()
        .next()
        .and_then(|n| n.parse::<usize>().ok());
    match line.and_then(|l| key_at_line(json, l)) {
        Some(key) => format!("{key}: {}", &message[..pos]),
        None => message.to_owned(),
    }
}

/// The configuration a `Tracker(...)` call describes: `track run`'s rules (a preset at
/// [`trackers::DEFAULT_PARTICLES`] and [`trackers::DEFAULT_SEED`], or a configuration), then the
/// `particles` and `seed` overrides.
fn tracker_config(
    py: Python<'_>,
    preset: Option<&str>,
    particles: Option<u64>,
    seed: Option<u64>,
    config: Option<&Bound<'_, PyAny>>,
) -> PyResult<TrackerConfig> {
    let mut c = match config.filter(|c| !c.is_none()) {
        Some(config) => {
            if let Some(name) = preset {
                return Err(PyValueError::new_err(format!(
                    "give a preset ({name:?}) or a config, not both: the config names its own tracker"
                )));
            }
            let c = if config.is_instance_of::<PyDict>() {
                let clean = json_value(config, "")?;
                let kwargs = PyDict::new(py);
                kwargs.set_item("indent", 1)?;
                let json: String = py
                    .import("json")?
                    .call_method("dumps", (clean,), Some(&kwargs))?
                    .extract()?;
                TrackerConfig::parse(&json, ConfigFormat::Json).map_err(|e| {
                    PyValueError::new_err(format!(
                        "config: {}",
                        config_message(&e.to_string(), &json)
                    ))
                })?
            } else {
                let path: std::path::PathBuf = config.extract().map_err(|_| {
                    PyTypeError::new_err(format!(
                        "config must be a dict or a path (str or os.PathLike), got {}",
                        config
                            .get_type()
                            .name()
                            .map_or_else(|_| "?".into(), |n| n.to_string())
                    ))
                })?;
                let text = std::fs::read_to_string(&path).map_err(|e| {
                    let message = format!("config {}: cannot read it: {e}", path.display());
                    match e.kind() {
                        std::io::ErrorKind::NotFound => {
                            pyo3::exceptions::PyFileNotFoundError::new_err(message)
                        }
                        _ => pyo3::exceptions::PyOSError::new_err(message),
                    }
                })?;
                TrackerConfig::parse(&text, ConfigFormat::of_path(&path))
                    .map_err(|e| PyValueError::new_err(format!("config {}: {e}", path.display())))?
            };
            c.validate()
                .map_err(|e| PyValueError::new_err(format!("config: {e}")))?;
            c
        }
        None => {
            let p = Preset::from_name(preset.unwrap_or(DEFAULT_TRACKER)).map_err(tracker_error)?;
            p.config(trackers::DEFAULT_PARTICLES, trackers::DEFAULT_SEED)
        }
    };
    if let Some(s) = seed {
        c.seed = s;
    }
    if let Some(n) = particles {
        c.particles = usize::try_from(n).unwrap_or(usize::MAX);
        c.validate()
            .map_err(|e| PyValueError::new_err(format!("particles: {e}")))?;
    }
    Ok(c)
}

/// The preset `Tracker()` uses when neither a preset nor a config is given (as `track run`).
const DEFAULT_TRACKER: &str = "head";

/// What a tracker reported for its last frame (`Tracker.status`): the ellipse and its box, the
/// status probabilities, the hidden processes' estimates where the preset has them (None
/// otherwise), and the effective sample size.
#[pyclass(frozen, module = "contour_track", get_all)]
#[derive(Debug, Clone)]
pub struct Status {
    /// Frame index: 0 at `init`, then 1, 2, … at each `update`.
    frame: usize,
    /// The estimated contour (cx, cy, a, b, angle): centre, semi-axes in pixels, angle in radians.
    ellipse: (f64, f64, f64, f64, f64),
    /// Its axis-aligned box (x, y, w, h), as `update` returns it.
    #[pyo3(name = "box")]
    bbox: (f64, f64, f64, f64),
    /// "locked", "partial" or "lost".
    state: &'static str,
    /// P(locked), or None when the tracker has no status process.
    p_locked: Option<f64>,
    /// P(partially occluded), or None.
    p_partial: Option<f64>,
    /// P(lost), or None.
    p_lost: Option<f64>,
    /// β̂, the most probable clutter class, or None without clutter switching.
    beta_hat: Option<usize>,
    /// Posterior probabilities of the clutter classes (empty without clutter switching).
    beta_probs: Vec<f64>,
    /// λ̂ = E[λ], or None without clutter switching.
    lambda_hat: Option<f64>,
    /// γ̂ = E[γ], the occluded share of the contour, or None without an occlusion model.
    gamma_hat: Option<f64>,
    /// Effective sample size after weighting (the particle count at `init`).
    ess: f64,
    /// Wall time of the Rust update alone, milliseconds (without the binding's frame reading).
    millis: f64,
}

impl Status {
    fn of(e: &Estimate) -> Self {
        let probs = e.status.as_ref().map(|s| s.alpha_probs);
        let b = e.bbox;
        let el = e.ellipse;
        Self {
            frame: e.frame,
            ellipse: (el.cx, el.cy, el.a, el.b, el.angle),
            bbox: (b.x, b.y, b.w, b.h),
            state: e.track_status().name(),
            p_locked: probs.map(|p| p[TrackStatus::Locked.index()]),
            p_partial: probs.map(|p| p[TrackStatus::PartiallyOccluded.index()]),
            p_lost: probs.map(|p| p[TrackStatus::Lost.index()]),
            beta_hat: e.clutter.as_ref().map(|c| c.beta_hat),
            beta_probs: e
                .clutter
                .as_ref()
                .map(|c| c.beta_probs.clone())
                .unwrap_or_default(),
            lambda_hat: e.clutter.as_ref().map(|c| c.lambda_hat),
            gamma_hat: e.gamma,
            ess: e.ess,
            millis: e.millis,
        }
    }
}

#[pymethods]
impl Status {
    /// Whether the target is tracked: `state` is not "lost".
    #[getter]
    fn ok(&self) -> bool {
        self.state != TrackStatus::Lost.name()
    }

    fn __repr__(&self) -> String {
        let opt = |v: Option<f64>| v.map_or_else(|| "None".to_owned(), |v| format!("{v:.3}"));
        let (x, y, w, h) = self.bbox;
        format!(
            "Status(frame={}, box=({x:.2}, {y:.2}, {w:.2}, {h:.2}), state={:?}, p_locked={}, \
             p_partial={}, p_lost={}, beta_hat={}, lambda_hat={}, gamma_hat={}, ess={:.1})",
            self.frame,
            self.state,
            opt(self.p_locked),
            opt(self.p_partial),
            opt(self.p_lost),
            self.beta_hat
                .map_or_else(|| "None".to_owned(), |b| b.to_string()),
            opt(self.lambda_hat),
            opt(self.gamma_hat),
            self.ess
        )
    }
}

/// A particle-filter tracker, shaped like OpenCV's trackers (`cv2.TrackerCSRT` and friends).
///
/// Arguments:
///     preset: a preset name (see `contour_track.presets()`); default "head", the one
///         recommended for real footage. Not with `config`.
///     particles: number of particles (default 200, or the config's).
///     seed: seed of every random draw (default 1, or the config's). The same seed gives the
///         same boxes, run after run, and the same boxes as `track run` with the same settings.
///     config: a full configuration replacing the preset: a dict, or the path of a JSON or TOML
///         file (TOML for a .toml extension), in the format `track config PRESET` prints.
///         `Tracker(...).config` gives one to edit.
///
/// Frames (for `init` and `update`) are numpy arrays:
///     uint8 H×W×3 colour, BGR as `cv2.imread` gives (pass `rgb=True` for RGB, e.g. Pillow);
///     uint8 H×W grey; float32 H×W grey levels (0–255); float32 H×W×3 colour in 0–255.
///     Any strides (slices, Fortran order); C-contiguous uint8 colour frames (BGR or RGB) and
///     float32 grey frames are read in place, without a copy. A colour frame becomes grey by the BT.601 weights, as
///     `track run` does with colour images; a grey image stays grey (read grey footage with
///     `cv2.IMREAD_GRAYSCALE` for the same boxes as `track run`).
///
/// `particles` and `seed` take an int or a numpy integer (anything with `__index__`, but not a
/// bool).
///
/// Errors: a frame of another dtype, or an argument of the wrong type, raises TypeError;
/// another shape, an empty frame, a frame of another size than at `init`, a NaN or infinity in
/// a float frame, a level outside 0–255 in a float32 frame, a box outside the frame, or a bad
/// config value (named by its key) raise ValueError; a frame of more than 2**26 pixels raises
/// MemoryError before anything is allocated; `update` before `init` raises RuntimeError.
///
/// Threads: one tracker may be used from several threads. Its calls run one at a time, in the
/// order they take its lock; a call waits for the lock, and computes, without the GIL, so other
/// Python threads go on meanwhile. Reading `status` during an `update` in another thread waits
/// for that update and gives its result.
///
/// Example:
///     >>> t = contour_track.Tracker("head", seed=1)
///     >>> t.init(frame0, (120, 40, 60, 70))
///     >>> ok, (x, y, w, h) = t.update(frame1)
///     >>> t.status.p_lost, t.status.ess
#[pyclass(frozen, module = "contour_track")]
pub struct Tracker {
    /// The tracker's configuration, for the getters.
    config: TrackerConfig,
    /// Everything a call changes, behind one lock: calls from several threads run one at a
    /// time, in the order they take the lock, each waiting without the GIL.
    state: std::sync::Mutex<TrackerState>,
}

/// The mutable part of a [`Tracker`].
struct TrackerState {
    tracker: Box<dyn trackers::Tracker>,
    buffers: FrameBuffers,
    /// (width, height) of the frames since `init`.
    size: Option<(usize, usize)>,
    last: Option<Status>,
}

/// Reads the `rgb` keyword.
fn order(rgb: bool) -> ChannelOrder {
    if rgb {
        ChannelOrder::Rgb
    } else {
        ChannelOrder::Bgr
    }
}

/// A box (x, y, w, h) from any sequence of four real numbers.
fn parse_box(value: &Bound<'_, PyAny>, what: &str) -> PyResult<BoundingBox> {
    let v: Vec<f64> = value
        .extract()
        .ok()
        .filter(|v: &Vec<f64>| v.len() == 4)
        .ok_or_else(|| PyTypeError::new_err(format!("{what} must be four numbers (x, y, w, h)")))?;
    Ok(BoundingBox::new(v[0], v[1], v[2], v[3]))
}

/// A box for a message, each number short ([`fmt_num`]: `1e300`, not 301 digits).
fn box_text(b: &BoundingBox) -> String {
    format!(
        "({}, {}, {}, {})",
        fmt_num(b.x),
        fmt_num(b.y),
        fmt_num(b.w),
        fmt_num(b.h)
    )
}

/// The checks of a box that need no frame: finite, of positive size.
fn check_finite_box(b: &BoundingBox, what: &str) -> PyResult<()> {
    if !b.is_finite() {
        return Err(PyValueError::new_err(format!(
            "{what} {} is not finite",
            box_text(b)
        )));
    }
    if b.w <= 0.0 || b.h <= 0.0 {
        return Err(PyValueError::new_err(format!(
            "{what} {} has zero or negative size",
            box_text(b)
        )));
    }
    Ok(())
}

/// The checks `track run` makes on `--init`: finite, positive size, centre inside the frame.
fn check_box(b: &BoundingBox, width: usize, height: usize) -> PyResult<()> {
    check_finite_box(b, "box")?;
    let (cx, cy) = b.centre();
    if cx < 0.0 || cy < 0.0 || cx >= width as f64 || cy >= height as f64 {
        return Err(PyValueError::new_err(format!(
            "box {} lies outside the {width}x{height} frame (its centre is outside)",
            box_text(b)
        )));
    }
    Ok(())
}

#[pymethods]
impl Tracker {
    #[new]
    #[pyo3(signature = (preset=None, particles=None, seed=None, config=None))]
    fn new(
        py: Python<'_>,
        preset: Option<&str>,
        particles: Option<&Bound<'_, PyAny>>,
        seed: Option<&Bound<'_, PyAny>>,
        config: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let particles = non_negative(particles, "particles")?;
        let seed = non_negative(seed, "seed")?;
        let c = tracker_config(py, preset, particles, seed, config)?;
        let tracker = trackers::build(c.clone()).map_err(tracker_error)?;
        Ok(Self {
            config: c,
            state: std::sync::Mutex::new(TrackerState {
                tracker,
                buffers: FrameBuffers::default(),
                size: None,
                last: None,
            }),
        })
    }

    /// The tracker's name: its preset, or the configuration's `name`.
    #[getter]
    fn name(&self) -> &str {
        &self.config.name
    }

    /// Number of particles.
    #[getter]
    fn particles(&self) -> usize {
        self.config.particles
    }

    /// Seed of every random draw.
    #[getter]
    fn seed(&self) -> u64 {
        self.config.seed
    }

    /// The configuration as a dict, in the format of `track config` (the settings the tracker
    /// reads; a valid `config=`).
    #[getter]
    fn config<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let json = serde_json::to_string(&self.config)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        py.import("json")?.call_method1("loads", (json,))
    }

    /// What the tracker reported for its last frame, or None before `init`. Read during an
    /// `init` or `update` in another thread, it waits for that call to end.
    #[getter]
    fn status(&self, py: Python<'_>) -> PyResult<Option<Status>> {
        self.with_state(py, |s| Ok(s.last.clone()))
    }

    /// The frame size (width, height) given at `init`, or None before it.
    #[getter]
    fn frame_size(&self, py: Python<'_>) -> PyResult<Option<(usize, usize)>> {
        self.with_state(py, |s| Ok(s.size))
    }

    /// Starts tracking the box (x, y, w, h) on `frame` (frame 0).
    ///
    /// The tracker starts from the ellipse inscribed in the box, as `track run --init x,y,w,h`.
    /// The box must be finite, of positive size, with its centre inside the frame. Calling
    /// `init` again restarts the tracker (the frame size may change then). `rgb=True` reads a
    /// colour frame as RGB instead of OpenCV's BGR.
    #[pyo3(signature = (frame, bbox, *, rgb=false))]
    fn init(
        &self,
        py: Python<'_>,
        frame: &Bound<'_, PyAny>,
        bbox: &Bound<'_, PyAny>,
        rgb: bool,
    ) -> PyResult<()> {
        let input = FrameInput::read(frame, "frame")?;
        let (w, h) = (input.width, input.height);
        let b = parse_box(bbox, "box")?;
        check_box(&b, w, h)?;
        let view = input.view();
        let order = order(rgb);
        self.with_state(py, |s| {
            let estimate = s.run(&view, order, Some(b))?;
            s.size = Some((w, h));
            s.last = Some(Status::of(&estimate));
            Ok(())
        })
    }

    /// Tracks the target into the next frame; returns `(ok, (x, y, w, h))`.
    ///
    /// `ok` is False when the tracker believes the target lost (`status.state == "lost"`);
    /// the box is the estimate's axis-aligned box either way. `status` holds the rest of the
    /// estimate. The frame must have the size given at `init`.
    #[pyo3(signature = (frame, *, rgb=false))]
    fn update(
        &self,
        py: Python<'_>,
        frame: &Bound<'_, PyAny>,
        rgb: bool,
    ) -> PyResult<(bool, (f64, f64, f64, f64))> {
        let input = FrameInput::read(frame, "frame")?;
        let view = input.view();
        let order = order(rgb);
        let (w, h) = (input.width, input.height);
        self.with_state(py, |s| {
            let Some((w0, h0)) = s.size else {
                return Err(FrameError::NotStarted);
            };
            if (w, h) != (w0, h0) {
                return Err(FrameError::Value(format!(
                    "frame is {w}x{h} but the tracker was initialised on {w0}x{h0} frames"
                )));
            }
            let estimate = s.run(&view, order, None)?;
            let status = Status::of(&estimate);
            let out = (status.ok(), status.bbox);
            s.last = Some(status);
            Ok(out)
        })
    }

    fn __repr__(&self) -> String {
        let c = &self.config;
        format!(
            "Tracker({:?}, particles={}, seed={})",
            c.name, c.particles, c.seed
        )
    }
}

impl Tracker {
    /// Runs `f` on the state under the lock, without the GIL: a call from another thread waits
    /// for the lock while this one computes, and Python threads go on meanwhile.
    fn with_state<T: Send>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&mut TrackerState) -> Result<T, FrameError> + Send,
    ) -> PyResult<T> {
        py.detach(|| {
            let mut state = self.state.lock().map_err(|_| FrameError::Poisoned)?;
            f(&mut state)
        })
        .map_err(PyErr::from)
    }
}

impl TrackerState {
    /// Reads `view` into the frame the trackers see and runs `init` (with `start`) or `update`.
    fn run(
        &mut self,
        view: &frames::FrameView<'_>,
        order: ChannelOrder,
        start: Option<BoundingBox>,
    ) -> Result<Estimate, FrameError> {
        let frame = self.buffers.frame(view, order)?;
        match start {
            Some(b) => self.tracker.init(frame, b.inscribed_ellipse()),
            None => self.tracker.update(frame),
        }
        .map_err(FrameError::Tracker)
    }
}

/// An error met without the GIL, turned into a Python exception once it is held again.
#[derive(Debug)]
enum FrameError {
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

/// The presets, one `(name, description)` pair each, in the order of `track --help`.
#[pyfunction]
fn presets() -> Vec<(&'static str, &'static str)> {
    Preset::ALL
        .iter()
        .map(|p| (p.name(), p.description()))
        .collect()
}

/// A motion estimate between two frames (`estimate_motion`).
///
/// An unreliable estimate cannot be taken for a good one: `params`, `covariance` and `affine`
/// raise `UnreliableMotion` when `reliable` is False, and `bool(motion)` is `reliable`. The
/// `unchecked_*` properties give the numbers anyway, for diagnosis.
#[pyclass(frozen, module = "contour_track")]
pub struct Motion {
    estimate: MotionEstimate,
    /// Why no estimate could be made at all (the normal equations of a region without texture
    /// are singular), when that is the case: the parameters are then NaN.
    failure: Option<String>,
}

#[pymethods]
impl Motion {
    /// Whether the estimate can be trusted as the dominant motion of the region.
    #[getter]
    fn reliable(&self) -> bool {
        self.estimate.reliable
    }

    /// Whether the full-resolution iterations met the tolerance.
    #[getter]
    fn converged(&self) -> bool {
        self.estimate.converged
    }

    /// The model: "translation", "scale" or "affine".
    #[getter]
    fn model(&self) -> &'static str {
        self.estimate.spec.model.name()
    }

    /// The parameters; raises `UnreliableMotion` when the estimate is not reliable.
    #[getter]
    fn params(&self) -> PyResult<Vec<f64>> {
        self.check()?;
        Ok(self.estimate.params.clone())
    }

    /// The covariance of `params` (a list of rows); raises `UnreliableMotion` when unreliable.
    #[getter]
    fn covariance(&self) -> PyResult<Vec<Vec<f64>>> {
        self.check()?;
        Ok(self.rows())
    }

    /// The six affine parameters [a1..a6] whatever the model; raises `UnreliableMotion` when
    /// unreliable.
    #[getter]
    fn affine(&self) -> PyResult<[f64; 6]> {
        self.check()?;
        Ok(self.estimate.affine())
    }

    /// The parameters even when the estimate is unreliable (for diagnosis only).
    #[getter]
    fn unchecked_params(&self) -> Vec<f64> {
        self.estimate.params.clone()
    }

    /// The covariance even when the estimate is unreliable (for diagnosis only).
    #[getter]
    fn unchecked_covariance(&self) -> Vec<Vec<f64>> {
        self.rows()
    }

    /// Origin (x, y) of the model's coordinates, in pixels.
    #[getter]
    fn origin(&self) -> (f64, f64) {
        (self.estimate.origin[0], self.estimate.origin[1])
    }

    /// The weighted share of the region's pixels explained at the noise scale.
    #[getter]
    fn inlier_fraction(&self) -> f64 {
        self.estimate.inlier_fraction
    }

    /// Final robust scale of the residuals, grey levels.
    #[getter]
    fn scale(&self) -> f64 {
        self.estimate.scale
    }

    fn __bool__(&self) -> bool {
        self.estimate.reliable
    }

    fn __repr__(&self) -> String {
        let py_bool = |b: bool| if b { "True" } else { "False" };
        format!(
            "Motion(model={:?}, reliable={}, converged={}, params={:?}, inlier_fraction={:.3})",
            self.model(),
            py_bool(self.estimate.reliable),
            py_bool(self.estimate.converged),
            self.estimate.params,
            self.estimate.inlier_fraction
        )
    }
}

impl Motion {
    fn check(&self) -> PyResult<()> {
        if self.estimate.reliable {
            return Ok(());
        }
        if let Some(why) = &self.failure {
            return Err(UnreliableMotion::new_err(format!(
                "no {} motion could be estimated ({why}); read .unchecked_params to see them \
                 (NaN) anyway",
                self.model()
            )));
        }
        Err(UnreliableMotion::new_err(format!(
            "the {} motion estimate is not reliable (converged: {}, inlier fraction {:.3}): its \
             parameters do not describe the region's motion; read .unchecked_params to see them \
             anyway",
            self.model(),
            self.estimate.converged,
            self.estimate.inlier_fraction
        )))
    }

    fn rows(&self) -> Vec<Vec<f64>> {
        let n = self.estimate.params.len();
        self.estimate
            .covariance
            .chunks(n.max(1))
            .map(<[f64]>::to_vec)
            .collect()
    }
}

/// The estimate of a computation that failed: every number NaN, not converged, not reliable.
fn failed_estimate(spec: ModelSpec) -> MotionEstimate {
    let n = spec.len();
    MotionEstimate {
        spec,
        params: vec![f64::NAN; n],
        covariance: vec![f64::NAN; n * n],
        origin: [f64::NAN; 2],
        scale: f64::NAN,
        noise_sigma: f64::NAN,
        inlier_fraction: 0.0,
        iterations: Vec::new(),
        converged: false,
        reliable: false,
    }
}

/// The support region of `estimate_motion`.
enum Roi {
    Full,
    Rect(BoundingBox),
    Mask(Vec<f32>),
}

fn parse_roi(roi: Option<&Bound<'_, PyAny>>, width: usize, height: usize) -> PyResult<Roi> {
    let Some(roi) = roi.filter(|r| !r.is_none()) else {
        return Ok(Roi::Full);
    };
    if let Ok(array) = roi.cast::<PyUntypedArray>()
        && array.ndim() >= 2
    {
        let shape = array.shape().to_vec();
        // An H×W×1 mask (as OpenCV and Pillow give single-channel images) is read as H×W.
        if array.ndim() == 3 && shape[2] == 1 {
            let squeezed = roi.call_method1("squeeze", (2,))?;
            return parse_roi(Some(&squeezed), width, height);
        }
        if array.ndim() != 2 {
            return Err(PyValueError::new_err(format!(
                "mask has shape ({}): give an H×W (or H×W×1) mask of the frames' size, or a box \
                 (x, y, w, h)",
                shape
                    .iter()
                    .map(usize::to_string)
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
        if (shape[1], shape[0]) != (width, height) {
            return Err(PyValueError::new_err(format!(
                "mask is {}x{} but the frames are {width}x{height}",
                shape[1], shape[0]
            )));
        }
        return frames::mask_weights(array).map(Roi::Mask);
    }
    let b = parse_box(roi, "roi")?;
    if !b.is_finite() || b.w <= 0.0 || b.h <= 0.0 {
        return Err(PyValueError::new_err(format!(
            "roi {} must be finite with a positive size",
            box_text(&b)
        )));
    }
    Ok(Roi::Rect(b))
}

/// Estimates the dominant motion of a region from frame `f0` to frame `f1`.
///
/// The robust multiresolution estimator of motion-est (Odobez & Bouthemy): IRLS with Tukey's
/// biweight, coarse to fine, with a covariance.
///
/// Arguments:
///     f0, f1: frames of one size, as `Tracker.update` takes them (`rgb=True` for RGB colour).
///     roi: None (the whole frame), a box (x, y, w, h), or a mask of the frames' H×W (or
///         H×W×1): bool,
///         uint8 (non-zero pixels count, as OpenCV's 0/255 masks) or float weights in [0, 1].
///     model: "translation" [tx, ty], "scale" [tx, ty, k] or "affine" [a1..a6] (Odobez Eq. 13:
///         dx = a1 + a2·x + a3·y, dy = a4 + a5·x + a6·y, with x, y from `origin`).
///     offset: also estimate an intensity offset (last parameter).
///
/// Returns a `Motion`; its `params` raise `UnreliableMotion` when the estimate is not
/// reliable, including when none could be computed (a region without texture, such as constant
/// frames: the parameters are NaN). Bad frames, masks or boxes raise TypeError or ValueError;
/// frames of more than 2**26 pixels raise MemoryError before anything is allocated. A mask may
/// be H×W or H×W×1.
#[pyfunction]
#[pyo3(signature = (f0, f1, roi=None, model="affine", *, offset=false, rgb=false))]
fn estimate_motion(
    py: Python<'_>,
    f0: &Bound<'_, PyAny>,
    f1: &Bound<'_, PyAny>,
    roi: Option<&Bound<'_, PyAny>>,
    model: &str,
    offset: bool,
    rgb: bool,
) -> PyResult<Motion> {
    let model: MotionModel = model
        .parse()
        .map_err(|e: motion_est::Error| PyValueError::new_err(e.to_string()))?;
    let in0 = FrameInput::read(f0, "f0")?;
    let in1 = FrameInput::read(f1, "f1")?;
    if (in0.width, in0.height) != (in1.width, in1.height) {
        return Err(PyValueError::new_err(format!(
            "f0 is {}x{} but f1 is {}x{}: the frames must have one size",
            in0.width, in0.height, in1.width, in1.height
        )));
    }
    let (w, h) = (in0.width, in0.height);
    let roi = parse_roi(roi, w, h)?;
    let (v0, v1) = (in0.view(), in1.view());
    let order = order(rgb);
    let estimate = py.detach(|| {
        let (mut b0, mut b1) = (FrameBuffers::default(), FrameBuffers::default());
        let g0 = b0.frame(&v0, order)?.grey();
        let g1 = b1.frame(&v1, order)?.grey();
        let region = match &roi {
            Roi::Full => Region::Full,
            Roi::Rect(b) => Region::Rect {
                x: b.x,
                y: b.y,
                width: b.w,
                height: b.h,
            },
            Roi::Mask(weights) => {
                Region::Mask(MaskView::new(w, h, weights).map_err(FrameError::Motion)?)
            }
        };
        let estimator =
            MotionEstimator::new(motion_est::Settings::default()).map_err(FrameError::Motion)?;
        let spec = ModelSpec::new(model, offset);
        match estimator
            .estimate_images(g0, g1, &region, spec, None)
            // An unreliable estimate is kept: `Motion` makes it impossible to mistake for a
            // good one (its parameters raise `UnreliableMotion`).
            .or_else(motion_est::Error::into_unreliable)
        {
            Ok(estimate) => Ok((estimate, None)),
            // A region without texture (constant frames) has no motion to estimate: a failed
            // computation, not a bad argument, reported as an unreliable estimate.
            Err(e @ motion_est::Error::Degenerate { .. }) => {
                Ok((failed_estimate(spec), Some(e.to_string())))
            }
            Err(e) => Err(FrameError::Motion(e)),
        }
    })?;
    let (estimate, failure) = estimate;
    Ok(Motion { estimate, failure })
}

/// The Rust side of `bench/bench_overhead.py`: tracks RGB frames the way `track run` feeds a
/// decoded colour image to a tracker (grey by [`vision_core::luma_bt601`], the frame with its RGB
/// pixels, `init` then `update`), timing each update's conversion and update in Rust, without the
/// GIL. Returns, for each update, its wall time and its thread CPU time in milliseconds (the CPU
/// time of the calling thread, which a loaded machine disturbs less), and the boxes of every frame.
/// Not public API.
#[pyfunction]
#[pyo3(signature = (preset, frames, bbox, particles=200, seed=1))]
#[allow(clippy::type_complexity)]
fn _rust_update_times(
    py: Python<'_>,
    preset: &str,
    frames: Vec<numpy::PyReadonlyArray3<'_, u8>>,
    bbox: (f64, f64, f64, f64),
    particles: usize,
    seed: u64,
) -> PyResult<(Vec<f64>, Vec<f64>, Vec<(f64, f64, f64, f64)>)> {
    let mut size = None;
    let mut pixels = Vec::with_capacity(frames.len());
    for f in &frames {
        let (h, w, c) = f.as_array().dim();
        if c != 3 || size.is_some_and(|s| s != (w, h)) {
            return Err(PyValueError::new_err(
                "frames must be RGB uint8 H×W×3 of one size",
            ));
        }
        size = Some((w, h));
        pixels.push(f.as_array().iter().copied().collect::<Vec<u8>>());
    }
    let Some((w, h)) = size else {
        return Ok((Vec::new(), Vec::new(), Vec::new()));
    };
    let config = Preset::from_name(preset)
        .map_err(tracker_error)?
        .config(particles, seed);
    let start = BoundingBox::new(bbox.0, bbox.1, bbox.2, bbox.3).inscribed_ellipse();
    py.detach(move || {
        let mut tracker = trackers::build(config)?;
        let (mut wall, mut cpu, mut boxes) = (Vec::new(), Vec::new(), Vec::new());
        // One grey buffer, reused, as the binding reuses its own.
        let mut grey: Vec<f32> = Vec::with_capacity(w * h);
        for (k, rgb) in pixels.iter().enumerate() {
            let t0 = std::time::Instant::now();
            let c0 = cpu_time::ThreadTime::now();
            grey.clear();
            grey.extend(
                rgb.chunks_exact(3)
                    .map(|p| vision_core::luma_bt601(p[0], p[1], p[2])),
            );
            let frame = trackers::Frame::with_rgb(w, h, &grey, rgb)?;
            let e = if k == 0 {
                tracker.init(frame, start)?
            } else {
                tracker.update(frame)?
            };
            if k > 0 {
                cpu.push(c0.elapsed().as_secs_f64() * 1e3);
                wall.push(t0.elapsed().as_secs_f64() * 1e3);
            }
            boxes.push((e.bbox.x, e.bbox.y, e.bbox.w, e.bbox.h));
        }
        Ok((wall, cpu, boxes))
    })
    .map_err(tracker_error)
}

/// The extension module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Tracker>()?;
    m.add_class::<Status>()?;
    m.add_class::<Motion>()?;
    m.add_function(wrap_pyfunction!(presets, m)?)?;
    m.add_function(wrap_pyfunction!(estimate_motion, m)?)?;
    m.add_function(wrap_pyfunction!(_rust_update_times, m)?)?;
    m.add_function(wrap_pyfunction!(batch::_track_video, m)?)?;
    m.add_function(wrap_pyfunction!(batch::_otb_plan, m)?)?;
    m.add_function(wrap_pyfunction!(batch::_otb_run, m)?)?;
    m.add_function(wrap_pyfunction!(batch::_otb_score, m)?)?;
    m.add("UnreliableMotion", m.py().get_type::<UnreliableMotion>())?;
    m.add("DEFAULT_TRACKER", DEFAULT_TRACKER)?;
    Ok(())
}
