#!/usr/bin/env python3
"""Runs OpenCV's CSRT, KCF and MedianFlow trackers and contour-track's recommended preset ("head")
in one frame loop over OTB folders, and prints success AUC, precision@20 and frames/s per tracker.

    python examples/python/compare_opencv.py OTB_DIR [OTB_DIR ...] [--seed 1] [--particles 200]

An OTB folder holds img/ (frames in name order) and groundtruth_rect.txt (x,y,w,h per frame,
0,0,0,0 or NaN when unlabelled). Every tracker starts from the first labelled box; that frame and
the unlabelled ones are not scored (as `track eval otb`). Success AUC is the mean over the IoU
thresholds 0, 0.05, ..., 1 of the share of frames whose IoU is above the threshold; precision@20
is the share whose centre error is at most 20 px. Frames/s counts update calls only (decoding
excluded). Needs numpy and OpenCV (opencv-contrib-python-headless for CSRT, KCF, MedianFlow):
without OpenCV it says so and runs ours alone (frames decoded with Pillow).
"""

import argparse
import math
import re
import sys
import time
from pathlib import Path

import numpy as np

import contour_track

try:
    import cv2
except ImportError:  # OpenCV is optional.
    cv2 = None

IMAGE_EXTENSIONS = {".png", ".jpg", ".jpeg", ".bmp", ".gif", ".tif", ".tiff", ".webp"}
SUCCESS_STEPS = 21


def natural_key(path):
    return [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", path.name)]


def load_otb(folder):
    folder = Path(folder)
    images = sorted((p for p in (folder / "img").iterdir() if p.suffix.lower() in IMAGE_EXTENSIONS), key=natural_key)
    truth = []
    for line in (folder / "groundtruth_rect.txt").read_text().split("\n"):
        if not line.strip():
            continue
        values = [float(v) for v in re.split(r"[,\s]+", line.strip())]
        box = tuple(values[:4])
        labelled = all(math.isfinite(v) for v in box) and box[2] > 0 and box[3] > 0
        truth.append(box if labelled else None)
    if len(truth) != len(images):
        raise SystemExit(f"{folder}: {len(truth)} ground-truth lines for {len(images)} frames")
    return images, truth


def read_frame(path):
    """A colour frame as OpenCV reads it (BGR), or with Pillow when OpenCV is absent (converted to
    BGR so that every tracker sees the same array)."""
    if cv2 is not None:
        frame = cv2.imread(str(path), cv2.IMREAD_COLOR)
        if frame is None:
            raise SystemExit(f"{path}: cannot decode")
        return frame
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB"))[:, :, ::-1].copy()


def iou(a, b):
    ax2, ay2, bx2, by2 = a[0] + a[2], a[1] + a[3], b[0] + b[2], b[1] + b[3]
    w = max(0.0, min(ax2, bx2) - max(a[0], b[0]))
    h = max(0.0, min(ay2, by2) - max(a[1], b[1]))
    inter = w * h
    union = a[2] * a[3] + b[2] * b[3] - inter
    return inter / union if union > 0 else 0.0


def centre_error(a, b):
    return math.hypot(a[0] + a[2] / 2 - b[0] - b[2] / 2, a[1] + a[3] / 2 - b[1] - b[3] / 2)


def scores(boxes, truth, start):
    ious, errors = [], []
    for k in range(start + 1, len(truth)):
        if truth[k] is None:
            continue
        box = boxes[k] if boxes[k] is not None else (0.0, 0.0, 0.0, 0.0)
        ious.append(iou(box, truth[k]))
        errors.append(centre_error(box, truth[k]))
    n = max(len(ious), 1)
    thresholds = [i / (SUCCESS_STEPS - 1) for i in range(SUCCESS_STEPS)]
    auc = sum(sum(v > t for v in ious) / n for t in thresholds) / SUCCESS_STEPS
    p20 = sum(e <= 20.0 for e in errors) / n
    return auc, p20


class OpenCvTracker:
    def __init__(self, name, make):
        self.name, self.make, self.tracker = name, make, None

    def init(self, frame, box):
        self.tracker = self.make()
        self.tracker.init(frame, tuple(int(round(v)) for v in box))

    def update(self, frame):
        ok, box = self.tracker.update(frame)
        return tuple(float(v) for v in box) if ok else None


class Ours:
    def __init__(self, preset, particles, seed):
        self.name = f"contour_track {preset}"
        self.preset, self.particles, self.seed = preset, particles, seed

    def init(self, frame, box):
        self.tracker = contour_track.Tracker(self.preset, particles=self.particles, seed=self.seed)
        self.tracker.init(frame, box)

    def update(self, frame):
        ok, box = self.tracker.update(frame)
        return box  # the estimate's box even when lost, as `track run` writes it


def opencv_trackers():
    if cv2 is None:
        return []
    found = []
    legacy = getattr(cv2, "legacy", None)
    for name, candidates in [
        ("OpenCV csrt", ["TrackerCSRT_create"]),
        ("OpenCV kcf", ["TrackerKCF_create"]),
        ("OpenCV medianflow", ["TrackerMedianFlow_create"]),
    ]:
        make = None
        for module in (cv2, legacy):
            for attr in candidates:
                if module is not None and hasattr(module, attr):
                    make = getattr(module, attr)
                    break
            if make:
                break
        if make is None:
            print(f"note: {name} is not in this OpenCV build (install opencv-contrib-python-headless)", file=sys.stderr)
            continue
        found.append(OpenCvTracker(name, make))
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("sequences", nargs="+", metavar="OTB_DIR")
    parser.add_argument("--preset", default=contour_track.DEFAULT_TRACKER)
    parser.add_argument("--particles", type=int, default=200)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    if cv2 is None:
        print("OpenCV is not installed (pip install opencv-contrib-python-headless): running contour_track alone", file=sys.stderr)
        try:
            import PIL  # noqa: F401
        except ImportError:
            raise SystemExit("without OpenCV, frames are decoded with Pillow: pip install pillow")
    totals = {}
    print(f"{'sequence':<24} {'tracker':<26} {'AUC':>6} {'P@20':>6} {'frames/s':>9}")
    for folder in args.sequences:
        images, truth = load_otb(folder)
        start = next(k for k, b in enumerate(truth) if b is not None)
        trackers = opencv_trackers() + [Ours(args.preset, args.particles, args.seed)]
        boxes = {t.name: [None] * len(images) for t in trackers}
        seconds = {t.name: 0.0 for t in trackers}
        for k in range(start, len(images)):
            frame = read_frame(images[k])  # decoded once, shared by every tracker
            for t in trackers:
                if k == start:
                    t.init(frame, truth[start])
                    boxes[t.name][k] = truth[start]
                    continue
                t0 = time.perf_counter()
                boxes[t.name][k] = t.update(frame)
                seconds[t.name] += time.perf_counter() - t0
        updates = max(len(images) - start - 1, 1)
        for t in trackers:
            auc, p20 = scores(boxes[t.name], truth, start)
            fps = updates / seconds[t.name] if seconds[t.name] > 0 else float("inf")
            totals.setdefault(t.name, []).append((auc, p20, fps))
            print(f"{Path(folder).name:<24} {t.name:<26} {auc:6.3f} {p20:6.3f} {fps:9.1f}")
    if len(args.sequences) > 1:
        for name, rows in totals.items():
            mean = [sum(r[i] for r in rows) / len(rows) for i in range(3)]
            print(f"{'mean':<24} {name:<26} {mean[0]:6.3f} {mean[1]:6.3f} {mean[2]:9.1f}")


if __name__ == "__main__":
    main()
