//! The `Tracker` class, OpenCV-shaped (`init`, then `update` per frame), and `Status`, what it
//! reported for its last frame.

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use trackers::{Estimate, TrackerConfig};
use vision_core::{BoundingBox, TrackStatus};

use crate::args::{non_negative, order, parse_box};
use crate::config::tracker_config;
use crate::errors::{FrameError, tracker_error};
use crate::frames::{self, ChannelOrder, FrameBuffers, FrameInput};

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
        // The check of `track run --init` (vision-core's), so that both say the same.
        b.check_start(w, h)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
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
