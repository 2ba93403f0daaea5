"""Particle-filter contour and head trackers, and a robust motion estimator, on numpy frames.

The trackers of the contour-track Rust workspace with an interface shaped like OpenCV's::

    import cv2, contour_track
    tracker = contour_track.Tracker("head")          # the recommended preset
    tracker.init(frame, (x, y, w, h))                 # frame: uint8 BGR, as cv2.imread gives
    ok, (x, y, w, h) = tracker.update(next_frame)
    tracker.status.p_lost, tracker.status.ess         # what the tracker believes

``presets()`` lists the trackers; ``estimate_motion(f0, f1)`` estimates the dominant motion
between two frames and says whether it is reliable. Boxes are identical to those of
``track run`` with the same preset, seed and frames. ``track_video(source, init)`` tracks a
whole video file, image folder or OTB folder as ``track run`` does; ``contour_track.cluster``
(with the ``dask`` extra) spreads many of them, and OTB evaluations, over a Dask cluster.

Errors: ``TypeError`` and ``ValueError`` for bad arguments; ``MemoryError`` for a frame too
large to allocate (checked before allocating); ``UnreliableMotion`` for a motion estimate that
failed; ``RuntimeError`` for a tracker that failed; ``OSError`` for outputs that cannot be
written. A ``Tracker`` may be shared by threads: its calls run one at a time (docs/PYTHON.md,
"Errors and threads").
"""

from ._native import (
    DEFAULT_TRACKER,
    Motion,
    Status,
    Tracker,
    UnreliableMotion,
    estimate_motion,
    presets,
)
from ._batch import RECORD_DTYPE, track_video

__all__ = [
    "DEFAULT_TRACKER",
    "RECORD_DTYPE",
    "Motion",
    "Status",
    "Tracker",
    "UnreliableMotion",
    "estimate_motion",
    "presets",
    "track_video",
]
