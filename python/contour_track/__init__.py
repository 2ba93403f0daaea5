"""Particle-filter contour and head trackers, and a robust motion estimator, on numpy frames.

The trackers of the contour-track Rust workspace with an interface shaped like OpenCV's::

    import cv2, contour_track
    tracker = contour_track.Tracker("head")          # the recommended preset
    tracker.init(frame, (x, y, w, h))                 # frame: uint8 BGR, as cv2.imread gives
    ok, (x, y, w, h) = tracker.update(next_frame)
    tracker.status.p_lost, tracker.status.ess         # what the tracker believes

``presets()`` lists the trackers; ``estimate_motion(f0, f1)`` estimates the dominant motion
between two frames and says whether it is reliable. Boxes are identical to those of
``track run`` with the same preset, seed and frames.
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

__all__ = [
    "DEFAULT_TRACKER",
    "Motion",
    "Status",
    "Tracker",
    "UnreliableMotion",
    "estimate_motion",
    "presets",
]
