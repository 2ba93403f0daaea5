"""track_video: `track run` as a function, with the same boxes and the same files."""

import json
import pickle
import shutil
import subprocess

import numpy as np
import pytest

import contour_track as ct
from conftest import scene, scene_truth, start_box, write_clip, write_otb


def track_run(track_bin, source, out, *extra):
    subprocess.run(
        [str(track_bin), "run", str(source), "--out", str(out), "--quiet", *extra],
        check=True, capture_output=True,
    )
    return out


def box_lines(records):
    return ["{:.2f},{:.2f},{:.2f},{:.2f}".format(*b) for b in zip(records["x"], records["y"], records["w"], records["h"])]


@pytest.mark.parametrize("preset, seed", [("head", 1), ("head", 4), ("m3", 2)])
def test_same_boxes_and_files_as_track_run_on_an_image_folder(tmp_path, track_bin, preset, seed):
    folder = write_clip(tmp_path / "clip", [scene(k) for k in range(10)])
    x, y, w, h = start_box()
    expected = track_run(track_bin, folder, tmp_path / "cli", "--tracker", preset, "--seed", str(seed),
                         "--particles", "80", "--init", f"{x},{y},{w},{h}")
    records, summary = ct.track_video(folder, start_box(), preset=preset, seed=seed, particles=80,
                                      out=tmp_path / "py", with_summary=True)
    assert records.dtype == ct.RECORD_DTYPE and len(records) == 10
    assert list(records["frame"]) == list(range(10))
    assert box_lines(records) == (expected / "boxes.txt").read_text().splitlines()
    # The same files, written by the same writers: byte for byte but for the timings.
    assert (tmp_path / "py" / "boxes.txt").read_bytes() == (expected / "boxes.txt").read_bytes()
    strip = lambda text: [line.rsplit(",", 1)[0] for line in text.splitlines()]  # noqa: E731
    cli_csv = (expected / "track.csv").read_text()
    py_csv = (tmp_path / "py" / "track.csv").read_text()
    assert cli_csv.splitlines()[0].endswith("millis")
    assert strip(py_csv) == strip(cli_csv)
    cli_summary = json.loads((expected / "summary.json").read_text())
    py_summary = json.loads((tmp_path / "py" / "summary.json").read_text())
    assert py_summary == summary
    timings = {"seconds", "fps", "mean_millis", "wall_seconds", "outputs"}
    assert {k: v for k, v in py_summary.items() if k not in timings} == {
        k: v for k, v in cli_summary.items() if k not in timings
    }
    assert set(py_summary["outputs"]) <= set(cli_summary["outputs"])


def test_an_otb_folder_starts_at_its_first_labelled_box_as_track_run(tmp_path, track_bin):
    frames = [scene(k) for k in range(12)]
    truth = [None, None] + [scene_truth(k) for k in range(2, 12)]
    folder = write_otb(tmp_path / "walk", frames, truth)
    expected = track_run(track_bin, folder, tmp_path / "cli", "--particles", "60", "--seed", "2")
    records, summary = ct.track_video(folder, particles=60, seed=2, out=tmp_path / "py", with_summary=True)
    assert records["frame"][0] == 2 and len(records) == 10
    assert (tmp_path / "py" / "boxes.txt").read_bytes() == (expected / "boxes.txt").read_bytes()
    cli = json.loads((expected / "summary.json").read_text())["metrics"]
    for k in ["success_auc", "precision_20", "mean_iou", "labelled_frames", "success_curve"]:
        assert summary["metrics"][k] == cli[k]


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="ffmpeg is not on PATH")
def test_same_boxes_as_track_run_on_a_video_file(tmp_path, track_bin):
    folder = write_clip(tmp_path / "clip", [scene(k) for k in range(8)])
    video = tmp_path / "clip.mkv"
    subprocess.run(["ffmpeg", "-loglevel", "error", "-framerate", "10", "-i", str(folder / "%04d.png"),
                    "-c:v", "ffv1", str(video)], check=True)
    x, y, w, h = start_box()
    expected = track_run(track_bin, video, tmp_path / "cli", "--particles", "60", "--init", f"{x},{y},{w},{h}")
    records = ct.track_video(video, start_box(), particles=60)
    assert box_lines(records) == (expected / "boxes.txt").read_text().splitlines()


def test_track_video_is_a_plain_function_of_picklable_arguments(tmp_path):
    folder = write_clip(tmp_path / "clip", [scene(k) for k in range(4)])
    f = pickle.loads(pickle.dumps(ct.track_video))
    records = f(str(folder), start_box(), "head", np.int64(3), np.int32(40))
    again = pickle.loads(pickle.dumps(records))
    assert np.array_equal(again[["x", "y", "w", "h"]], records[["x", "y", "w", "h"]])
    assert records[0]["state"] == "" or records[0]["state"] in ("locked", "partial", "lost")
    assert records[-1]["state"] in ("locked", "partial", "lost")
    assert np.all(np.isfinite(records["p_lost"][1:]))


def test_bad_sources_and_boxes_raise_value_error(tmp_path):
    folder = write_clip(tmp_path / "clip", [scene(k) for k in range(3)])
    with pytest.raises(ValueError, match="no such file"):
        ct.track_video(tmp_path / "missing", start_box())
    with pytest.raises(ValueError, match="no ground truth"):
        ct.track_video(folder)
    with pytest.raises(ValueError, match="outside"):
        ct.track_video(folder, (1000, 1000, 10, 10))
    with pytest.raises(ValueError) as e:
        ct.track_video(folder, (100, 100, 1e300, 1e300))
    assert len(str(e.value)) < 200, str(e.value)
    with pytest.raises(TypeError):
        ct.track_video(folder, (1, 2, 3))
    with pytest.raises(ValueError, match="not both"):
        ct.track_video(folder, start_box(), preset="m1", config={"name": "x"})
