"""Type stubs of contour_track (the Rust extension contour_track._native)."""

import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

Box = Tuple[float, float, float, float]
Ellipse = Tuple[float, float, float, float, float]
Frame = Union[npt.NDArray[np.uint8], npt.NDArray[np.float32]]
Mask = Union[npt.NDArray[np.bool_], npt.NDArray[np.uint8], npt.NDArray[np.float32], npt.NDArray[np.float64]]

DEFAULT_TRACKER: str
"""The preset `Tracker()` uses without a preset or config: "head", recommended for real footage."""

def presets() -> List[Tuple[str, str]]:
    """The presets, one (name, one-line description) pair each."""

class Status:
    """What a tracker reported for its last frame (`Tracker.status`)."""

    @property
    def frame(self) -> int:
        """Frame index: 0 at init, then 1, 2, ... at each update."""
    @property
    def ellipse(self) -> Ellipse:
        """(cx, cy, a, b, angle): centre, semi-axes in pixels, angle in radians."""
    @property
    def box(self) -> Box:
        """The ellipse's axis-aligned box (x, y, w, h), as `update` returns it."""
    @property
    def state(self) -> str:
        """"locked", "partial" or "lost"."""
    @property
    def ok(self) -> bool:
        """Whether the target is tracked: state is not "lost"."""
    @property
    def p_locked(self) -> Optional[float]:
        """P(locked); None when the tracker has no status process."""
    @property
    def p_partial(self) -> Optional[float]:
        """P(partially occluded); None without a status process."""
    @property
    def p_lost(self) -> Optional[float]:
        """P(lost); None without a status process."""
    @property
    def beta_hat(self) -> Optional[int]:
        """The most probable clutter class; None without clutter switching."""
    @property
    def beta_probs(self) -> List[float]:
        """Posterior probabilities of the clutter classes (empty without clutter switching)."""
    @property
    def lambda_hat(self) -> Optional[float]:
        """E[lambda], the clutter density; None without clutter switching."""
    @property
    def gamma_hat(self) -> Optional[float]:
        """E[gamma], the occluded share of the contour; None without an occlusion model."""
    @property
    def ess(self) -> float:
        """Effective sample size after weighting (the particle count at init)."""
    @property
    def millis(self) -> float:
        """Wall time of the Rust update alone, milliseconds."""

class Tracker:
    """A particle-filter tracker, shaped like OpenCV's trackers.

    Frames: uint8 HxWx3 (BGR, or RGB with rgb=True), uint8 HxW grey, float32 HxW grey levels
    or float32 HxWx3 colour in 0-255; any strides.

    particles and seed take an int or a numpy integer (anything with __index__ but bool).

    Raises: TypeError (a frame of another dtype, an argument of the wrong type), ValueError (a
    bad shape, value, box, setting or config value, named by its key), MemoryError (a frame of
    more than 2**26 pixels, before anything is allocated), RuntimeError (update before init, a
    tracker that failed). One Tracker may be used from several threads: its calls run one at a
    time (a lock, waited on without the GIL); reading status during an update waits for it.
    """

    def __init__(
        self,
        preset: Optional[str] = None,
        particles: Optional[int] = None,
        seed: Optional[int] = None,
        config: Union[None, Mapping[str, Any], str, "os.PathLike[str]"] = None,
    ) -> None: ...
    @property
    def name(self) -> str:
        """The preset's or the configuration's name."""
    @property
    def particles(self) -> int:
        """Number of particles."""
    @property
    def seed(self) -> int:
        """Seed of every random draw."""
    @property
    def config(self) -> Dict[str, Any]:
        """The configuration, in the format of `track config`: the settings the tracker reads (a valid config=)."""
    @property
    def status(self) -> Optional[Status]:
        """What the tracker reported for its last frame; None before init."""
    @property
    def frame_size(self) -> Optional[Tuple[int, int]]:
        """(width, height) of the frames since init; None before it."""
    def init(self, frame: Frame, bbox: Sequence[float], *, rgb: bool = False) -> None:
        """Starts tracking the box (x, y, w, h) on frame (frame 0)."""
    def update(self, frame: Frame, *, rgb: bool = False) -> Tuple[bool, Box]:
        """Tracks into the next frame; returns (ok, (x, y, w, h))."""

class UnreliableMotion(RuntimeError):
    """The motion estimate is not reliable: its parameters do not describe the region's motion.

    Raised by Motion.params, .covariance and .affine of an unreliable estimate, including one
    that could not be computed at all (a region without texture: the parameters are NaN).
    """

class Motion:
    """A motion estimate; params, covariance and affine raise UnreliableMotion when unreliable."""

    @property
    def reliable(self) -> bool: ...
    @property
    def converged(self) -> bool: ...
    @property
    def model(self) -> str:
        """"translation", "scale" or "affine"."""
    @property
    def params(self) -> List[float]:
        """The parameters; raises UnreliableMotion when not reliable."""
    @property
    def covariance(self) -> List[List[float]]:
        """Covariance of params; raises UnreliableMotion when not reliable."""
    @property
    def affine(self) -> Tuple[float, float, float, float, float, float]:
        """The six affine parameters a1..a6 whatever the model; raises when not reliable."""
    @property
    def unchecked_params(self) -> List[float]:
        """The parameters even when unreliable (diagnosis only)."""
    @property
    def unchecked_covariance(self) -> List[List[float]]:
        """The covariance even when unreliable (diagnosis only)."""
    @property
    def origin(self) -> Tuple[float, float]:
        """Origin (x, y) of the model's coordinates, pixels."""
    @property
    def inlier_fraction(self) -> float: ...
    @property
    def scale(self) -> float:
        """Final robust scale of the residuals, grey levels."""
    def __bool__(self) -> bool: ...

def estimate_motion(
    f0: Frame,
    f1: Frame,
    roi: Union[None, Sequence[float], Mask] = None,
    model: str = "affine",
    *,
    offset: bool = False,
    rgb: bool = False,
) -> Motion:
    """Estimates the dominant motion of roi from f0 to f1 (robust, multiresolution).

    roi: None, a box (x, y, w, h), or a mask of the frames' HxW (or HxWx1). A failed estimate
    (constant frames) is returned as an unreliable Motion, never raised. Raises TypeError and
    ValueError for bad arguments, MemoryError for frames too large to allocate.
    """

RECORD_DTYPE: np.dtype
"""The dtype of track_video's records: frame, x, y, w, h, cx, cy, a, b, angle, state, p_locked,
p_partial, p_lost (NaN without a status process), ess, millis."""

def track_video(
    source: Union[str, "os.PathLike[str]"],
    init: Optional[Sequence[float]] = None,
    preset: str = "head",
    seed: Optional[int] = 1,
    particles: Optional[int] = None,
    config: Union[None, Mapping[str, Any], str, "os.PathLike[str]"] = None,
    *,
    out: Union[None, str, "os.PathLike[str]"] = None,
    with_summary: bool = False,
) -> Any:
    """Tracks a video file, image folder or OTB folder as `track run` does: the same boxes, and
    with out= the same boxes.txt, track.csv and summary.json. Returns a structured array of
    RECORD_DTYPE, one record per tracked frame (with with_summary=True, (records, summary)).

    Raises TypeError and ValueError for bad arguments (a missing or unreadable source, a box
    outside the frame), OSError for an output folder that cannot be written, RuntimeError for a
    tracker that failed."""
