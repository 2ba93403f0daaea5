"""examples/python/compare_opencv.py: its OTB scoring and its frame loop on a generated OTB folder."""

import importlib.util
import sys

import numpy as np
import pytest

from conftest import REPO, scene, start_box, write_png


@pytest.fixture
def example():
    path = REPO / "examples" / "python" / "compare_opencv.py"
    spec = importlib.util.spec_from_file_location("compare_opencv", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_scores_follow_otb(example):
    truth = [(100, 100, 10, 10), (100, 100, 10, 10), None, (100, 100, 10, 10), (100, 100, 10, 10)]
    # The start frame (0) and the unlabelled frame (2) are not scored.
    perfect = [(50, 50, 1, 1), (100, 100, 10, 10), (9, 9, 1, 1), (100, 100, 10, 10), (100, 100, 10, 10)]
    auc, p20 = example.scores(perfect, truth, 0)
    assert auc == pytest.approx(20 / 21) and p20 == 1.0  # IoU 1 is above 20 of 21 thresholds
    half = [None, (105, 100, 10, 10), None, (100, 100, 10, 10), None]  # IoU 1/3, 1, a missing box
    auc, p20 = example.scores(half, truth, 0)
    assert auc == pytest.approx((7 + 20 + 0) / (3 * 21)) and p20 == pytest.approx(2 / 3)


def test_frame_loop_on_a_generated_otb_folder(example, tmp_path, monkeypatch, capsys):
    folder = tmp_path / "Gen"
    (folder / "img").mkdir(parents=True)
    frames = [scene(k) for k in range(10)]
    for k, f in enumerate(frames):
        write_png(folder / "img" / f"{k + 1:04d}.png", f)
    truth = [(32.0 + 2 * k, 33.0 + k, 36.0, 44.0) for k in range(10)]
    (folder / "groundtruth_rect.txt").write_text("".join("{},{},{},{}\n".format(*b) for b in truth))
    assert start_box() == truth[0]
    # Frames as OpenCV would decode them (BGR), whatever decoder this machine has.
    monkeypatch.setattr(example, "read_frame", lambda path: frames[int(path.stem) - 1][:, :, ::-1].copy())
    monkeypatch.setattr(sys, "argv", ["compare_opencv.py", str(folder), "--particles", "100"])
    if example.cv2 is None:
        monkeypatch.setitem(sys.modules, "PIL", type(sys)("PIL"))
    example.main()
    out, err = capsys.readouterr()
    rows = [line.split() for line in out.splitlines() if line.startswith("Gen")]
    ours = [r for r in rows if "contour_track" in r]
    assert len(ours) == 1
    auc, p20, fps = (float(v) for v in ours[0][-3:])
    assert auc > 0.6 and p20 == 1.0 and fps > 0
    if example.cv2 is None:
        assert "OpenCV is not installed" in err and len(rows) == 1
    else:
        assert len(rows) >= 2
