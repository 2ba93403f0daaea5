"""Whole sequences: ``track_video`` (``track run`` as a function) and the run of one OTB run.

Plain functions of picklable arguments, importable without Dask, so that any executor
(``concurrent.futures``, Dask, Ray, multiprocessing) can run them.
"""

import os

import numpy as np

from . import _native

#: The fields of the structured array ``track_video`` returns, one record per tracked frame.
RECORD_DTYPE = np.dtype(
    [
        ("frame", np.int64),  # 0-based index of the frame in the sequence
        ("x", np.float64),  # the box (x, y, w, h), as boxes.txt gives it (unrounded)
        ("y", np.float64),
        ("w", np.float64),
        ("h", np.float64),
        ("cx", np.float64),  # the ellipse: centre, semi-axes, angle in radians
        ("cy", np.float64),
        ("a", np.float64),
        ("b", np.float64),
        ("angle", np.float64),
        ("state", "U7"),  # "locked", "partial", "lost", or "" without a status process
        ("p_locked", np.float64),  # status probabilities, NaN without a status process
        ("p_partial", np.float64),
        ("p_lost", np.float64),
        ("ess", np.float64),  # effective sample size
        ("millis", np.float64),  # tracking time of the frame (a timing: differs run to run)
    ]
)


def _records(columns):
    n = len(columns["frame"])
    out = np.zeros(n, dtype=RECORD_DTYPE)
    out["frame"] = columns["frame"]
    if n:
        boxes = np.asarray(columns["box"], dtype=np.float64).reshape(n, 4)
        ellipses = np.asarray(columns["ellipse"], dtype=np.float64).reshape(n, 5)
        for k, name in enumerate(("x", "y", "w", "h")):
            out[name] = boxes[:, k]
        for k, name in enumerate(("cx", "cy", "a", "b", "angle")):
            out[name] = ellipses[:, k]
    for name in ("state", "p_locked", "p_partial", "p_lost", "ess", "millis"):
        out[name] = columns[name]
    return out


def track_video(source, init=None, preset=_native.DEFAULT_TRACKER, seed=1, particles=None,
                config=None, *, out=None, with_summary=False):
    """Tracks a whole sequence as ``track run`` does, and returns one record per tracked frame.

    Arguments:
        source: a video file (decoded by ffmpeg, which must be on PATH, as ``track run`` decodes
            it), a ``.y4m`` file, a folder of images, or an OTB folder (``img/`` and
            ``groundtruth_rect.txt``); a str or ``os.PathLike``.
        init: the box (x, y, w, h) on the first frame. None for an OTB folder starts at its first
            labelled box, as ``track run`` without ``--init``.
        preset: the tracker preset (default "head"); not with ``config`` (leave it at its
            default then).
        seed: seed of every random draw (default 1); None keeps a config's own seed.
        particles: number of particles (default 200, or the config's).
        config: a configuration replacing the preset: a dict or the path of a JSON or TOML file,
            as for ``Tracker``.
        out: a folder to write ``track.csv``, ``boxes.txt`` and ``summary.json`` into, with
            ``track run``'s writers (the folder is prepared as ``track run --out`` prepares it).
        with_summary: also return the run's summary (the dict ``summary.json`` holds, with the
            scores against the ground truth of an OTB folder).

    Returns:
        A numpy structured array of dtype ``RECORD_DTYPE``, one record per tracked frame (from
        the start frame on): frame, box (x, y, w, h), ellipse (cx, cy, a, b, angle), state,
        p_locked, p_partial, p_lost (NaN without a status process), ess and millis. With
        ``with_summary=True``, the pair (records, summary).

    The boxes are those of ``track run SOURCE --tracker PRESET --seed SEED --init X,Y,W,H`` (its
    ``boxes.txt`` holds them with two decimals); only ``millis`` and the timings of the summary
    differ from run to run. A plain function of picklable arguments: any executor can run it.

    Raises:
        TypeError: an argument of the wrong type (a box that is not four numbers).
        ValueError: a bad setting, box or source (missing, unreadable, not a sequence), named in
            the message.
        OSError: the output folder cannot be written.
        RuntimeError: the tracker failed.
    """
    if config is not None:
        if preset != _native.DEFAULT_TRACKER:
            raise ValueError(
                f"give a preset ({preset!r}) or a config, not both: the config names its own tracker"
            )
        preset = None
    columns = _native._track_video(
        os.fspath(source), init, preset=preset, particles=particles, seed=seed, config=config,
        out=None if out is None else os.fspath(out),
    )
    records = _records(columns)
    if with_summary:
        import json

        return records, json.loads(columns["summary"])
    return records


def otb_run(spec):
    """Tracks one run of an OTB evaluation plan (see ``contour_track.cluster.evaluate_otb``):
    returns (boxes from the start frame on, P(lost) of each, tracking seconds)."""
    return _native._otb_run(spec)
