"""The same seed gives the same boxes as `track run` with the same preset, on a generated clip."""

import subprocess

import numpy as np
import pytest

import contour_track as ct
from conftest import scene, start_box, write_png


def python_boxes(frames, preset, seed, particles, **kw):
    t = ct.Tracker(preset, particles=particles, seed=seed)
    t.init(frames[0], start_box(), **kw)
    boxes = [t.status.box]
    for f in frames[1:]:
        boxes.append(t.update(f, **kw)[1])
    return ["{:.2f},{:.2f},{:.2f},{:.2f}".format(*b) for b in boxes]


def track_run_boxes(track_bin, folder, out, preset, seed, particles):
    x, y, w, h = start_box()
    subprocess.run(
        [str(track_bin), "run", str(folder), "--tracker", preset, "--seed", str(seed),
         "--particles", str(particles), "--init", f"{x},{y},{w},{h}", "--out", str(out), "--quiet"],
        check=True, capture_output=True,
    )
    return (out / "boxes.txt").read_text().splitlines()


@pytest.mark.parametrize("preset, seed", [("head", 1), ("head", 2), ("head", 3), ("m1", 1), ("w-eval", 2), ("m3", 1)])
def test_same_boxes_as_track_run_colour(tmp_path, track_bin, preset, seed):
    frames = [scene(k) for k in range(12)]
    folder = tmp_path / "frames"
    folder.mkdir()
    for k, f in enumerate(frames):
        write_png(folder / f"{k:04d}.png", f)
    expected = track_run_boxes(track_bin, folder, tmp_path / "out", preset, seed, 120)
    assert len(expected) == len(frames)
    # As cv2.imread gives them (BGR), and as Pillow gives them (RGB).
    assert python_boxes([f[:, :, ::-1].copy() for f in frames], preset, seed, 120) == expected
    assert python_boxes(frames, preset, seed, 120, rgb=True) == expected
    # Another seed gives other boxes: the comparison is not vacuous.
    assert python_boxes(frames, preset, seed + 10, 120, rgb=True) != expected


@pytest.mark.parametrize("preset", ["head", "w-hmm"])
def test_same_boxes_as_track_run_grey(tmp_path, track_bin, preset):
    frames = [scene(k).mean(axis=2).round().astype(np.uint8) for k in range(10)]
    folder = tmp_path / "frames"
    folder.mkdir()
    for k, f in enumerate(frames):
        write_png(folder / f"{k:04d}.png", f)
    expected = track_run_boxes(track_bin, folder, tmp_path / "out", preset, 1, 100)
    assert python_boxes(frames, preset, 1, 100) == expected
    assert python_boxes([f.astype(np.float32) for f in frames], preset, 1, 100) == expected
