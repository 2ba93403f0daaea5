"""Frames: every accepted kind gives the trackers the same input; bad frames raise clearly."""

import sys
import threading
import time

import numpy as np
import pytest

import contour_track as ct
from conftest import scene, start_box


def boxes(frames, preset="head", seed=1, particles=100, **kw):
    t = ct.Tracker(preset, particles=particles, seed=seed)
    t.init(frames[0], start_box(), **kw)
    out = [t.status.box]
    for f in frames[1:]:
        out.append(t.update(f, **kw)[1])
    return out


@pytest.fixture
def rgb():
    return [scene(k) for k in range(6)]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_bgr_and_rgb_give_the_same_boxes(rgb, seed):
    bgr = [f[:, :, ::-1] for f in rgb]  # a strided view, as OpenCV's channel flips give
    bgr_copy = [np.ascontiguousarray(f) for f in bgr]
    expected = boxes(rgb, seed=seed, rgb=True)
    assert boxes(bgr, seed=seed) == expected
    assert boxes(bgr_copy, seed=seed) == expected


def test_layouts_do_not_matter(rgb):
    expected = boxes(rgb, rgb=True)
    fortran = [np.asfortranarray(f) for f in rgb]
    assert not fortran[0].flags.c_contiguous
    assert boxes(fortran, rgb=True) == expected
    padded = [np.pad(f, ((0, 0), (0, 4), (0, 0)))[:, :160] for f in rgb]
    assert not padded[0].flags.c_contiguous
    assert boxes(padded, rgb=True) == expected


def test_integer_float_colour_equals_uint8(rgb):
    expected = boxes(rgb, rgb=True)
    assert boxes([f.astype(np.float32) for f in rgb], rgb=True) == expected


@pytest.mark.parametrize("preset", ["head", "m1", "w-eval"])
def test_grey_uint8_float32_and_hx_wx1_agree(rgb, preset):
    grey = [f.mean(axis=2).round().astype(np.uint8) for f in rgb]
    expected = boxes(grey, preset)
    assert boxes([g.astype(np.float32) for g in grey], preset) == expected
    assert boxes([g[:, :, None] for g in grey], preset) == expected
    assert boxes([np.asfortranarray(g.astype(np.float32)) for g in grey], preset) == expected


@pytest.mark.parametrize("convert", [lambda f: f, lambda f: f.mean(axis=2).astype(np.float32)])
def test_read_only_frames_are_accepted(rgb, convert):
    # The binding only reads frames (it borrows C-contiguous ones in place), so a read-only
    # array, as a memory-mapped video would give, is fine.
    frames = [np.ascontiguousarray(convert(f)) for f in rgb[:3]]
    expected = boxes(frames, "m1")
    for f in frames:
        f.flags.writeable = False
    assert boxes(frames, "m1") == expected


@pytest.mark.parametrize(
    "frame, error, message",
    [
        (np.zeros((120, 160, 3), np.int64), TypeError, "dtype int64"),
        (np.zeros((120, 160), np.float64), TypeError, "dtype float64"),
        (np.zeros((120, 160, 3), np.uint16), TypeError, "uint8"),
        ([[0, 1], [2, 3]], TypeError, "numpy array"),
        (None, TypeError, "numpy array"),
        (np.zeros((120, 160, 4), np.uint8), ValueError, "4 channels"),
        (np.zeros((120, 160, 2), np.uint8), ValueError, "channels"),
        (np.zeros(160, np.uint8), ValueError, "H×W"),
        (np.zeros((2, 120, 160, 3), np.uint8), ValueError, "H×W"),
        (np.zeros((0, 160), np.uint8), ValueError, "empty"),
        (np.zeros((120, 0, 3), np.uint8), ValueError, "empty"),
    ],
)
def test_bad_frames_raise_at_init_and_update(rgb, frame, error, message):
    t = ct.Tracker("head")
    with pytest.raises(error, match=message):
        t.init(frame, start_box())
    t.init(rgb[0], start_box())
    with pytest.raises(error, match=message):
        t.update(frame)
    # The tracker is unharmed by the refused frame.
    assert t.update(rgb[1])[1] == boxes(rgb[:2], particles=200, rgb=False)[1]


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_non_finite_float_frames_are_value_errors(rgb, value):
    g = rgb[0].mean(axis=2).astype(np.float32)
    bad = g.copy()
    bad[7, 11] = value
    t = ct.Tracker("m1", particles=30)
    with pytest.raises(ValueError, match="row 7, column 11"):
        t.init(bad, start_box())
    t.init(g, start_box())
    with pytest.raises(ValueError, match="non-finite"):
        t.update(bad)
    colour = rgb[0].astype(np.float32)
    colour[3, 5, 1] = value
    with pytest.raises(ValueError, match="row 3, column 5"):
        ct.Tracker("head").init(colour, start_box())


def test_float_colour_out_of_range_is_a_value_error(rgb):
    f = rgb[0].astype(np.float32)
    f[0, 0, 0] = 300.0
    with pytest.raises(ValueError, match="0–255"):
        ct.Tracker("head").init(f, start_box())


def test_frame_size_must_match_init(rgb):
    t = ct.Tracker("head")
    t.init(rgb[0], start_box())
    assert t.frame_size == (160, 120)
    with pytest.raises(ValueError, match="initialised on 160x120"):
        t.update(np.zeros((120, 161, 3), np.uint8))
    with pytest.raises(ValueError, match="initialised on 160x120"):
        t.update(rgb[1][:100])


def test_update_before_init_is_a_runtime_error(rgb):
    with pytest.raises(RuntimeError, match="init"):
        ct.Tracker("head").update(rgb[0])


@pytest.mark.parametrize(
    "box, error, message",
    [
        ((500, 500, 20, 20), ValueError, "outside"),
        ((10, 10, 0, 20), ValueError, "size"),
        ((10, 10, -5, 20), ValueError, "size"),
        ((np.nan, 10, 20, 20), ValueError, "finite"),
        ((10, 10, 20), TypeError, "four numbers"),
        ("abcd", TypeError, "four numbers"),
    ],
)
def test_bad_boxes(rgb, box, error, message):
    with pytest.raises(error, match=message):
        ct.Tracker("head").init(rgb[0], box)


def test_box_partly_outside_is_accepted(rgb):
    t = ct.Tracker("head")
    t.init(rgb[0], (-10, -10, 40, 40))
    assert t.status.frame == 0


def test_gil_is_released_during_update():
    frame = np.ascontiguousarray(np.tile(scene(0, 640, 480), (1, 1, 1)))
    t = ct.Tracker("m3", particles=400)
    t.init(frame, (200, 150, 120, 160))
    window = {}
    started = threading.Event()

    def work():
        started.set()
        window["start"] = time.perf_counter()
        t.update(frame)
        window["end"] = time.perf_counter()

    old = sys.getswitchinterval()
    # With a one-second switch interval, a thread holding the GIL keeps it for the whole update;
    # the main thread runs during the update only if the update released it.
    sys.setswitchinterval(1.0)
    try:
        worker = threading.Thread(target=work)
        worker.start()
        started.wait()
        ticks = []
        while worker.is_alive():
            ticks.append(time.perf_counter())
        worker.join()
    finally:
        sys.setswitchinterval(old)
    inside = [x for x in ticks if window["start"] < x < window["end"]]
    assert len(inside) > 100, (len(ticks), window)


def test_trackers_in_threads_match_sequential(rgb):
    expected = boxes(rgb, seed=5)
    results = [None] * 3

    def work(i):
        results[i] = boxes(rgb, seed=5)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(3)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert results == [expected] * 3
