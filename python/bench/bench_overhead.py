#!/usr/bin/env python3
"""The binding's overhead on one `update` of a 640×480 colour frame.

Compares, on the same frames, the time of `Tracker.update(frame)` seen from Python
(perf_counter around the call, a uint8 BGR frame as cv2.imread gives) with the same update in a
Rust timing loop (`contour_track._native._rust_update_times`: the grey conversion `track run`
applies to a decoded colour image, the frame with its RGB pixels, then `update`, timed in Rust
without Python). The difference is what the binding adds: reading the numpy array, reordering BGR,
releasing the GIL, building the result. Both loops give the same boxes (checked).

Also shown, per kind of frame: the update from Python against the Rust update alone
(`status.millis`, the tracker's own timing inside the same call), whose difference includes the
conversion to the trackers' grey frame that any caller pays.

    python python/bench/bench_overhead.py [--preset head] [--frames 150] [--repeats 3]

Frames: a generated 640×480 clip, a 150×200 px head-like ellipse swaying over texture.
"""

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

import contour_track as ct
from contour_track import _native

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from conftest import scene  # noqa: E402

BOX = (245.0, 140.0, 150.0, 200.0)


def python_loop(preset, frames, kw):
    t = ct.Tracker(preset)
    t.init(frames[0], BOX, **kw)
    calls, cpu, rust, boxes = [], [], [], [t.status.box]
    for f in frames[1:]:
        c0 = time.thread_time()
        t0 = time.perf_counter()
        _, box = t.update(f, **kw)
        calls.append((time.perf_counter() - t0) * 1e3)
        cpu.append((time.thread_time() - c0) * 1e3)
        rust.append(t.status.millis)
        boxes.append(box)
    return calls, cpu, rust, boxes


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--preset", default="head")
    ap.add_argument("--frames", type=int, default=150)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    head = scene(0, 640, 480, centre=(320.0, 240.0), radii=(75.0, 100.0))
    rgb = [np.ascontiguousarray(np.roll(head, int(round(20 * np.sin(k / 10))), axis=1)) for k in range(args.frames)]
    bgr = [np.ascontiguousarray(f[:, :, ::-1]) for f in rgb]

    py_wall, py_cpu, rust_wall, rust_cpu = [], [], [], []
    for _ in range(args.repeats):  # interleaved, so that the machine's load hits both alike
        calls, cpu, _, py_boxes = python_loop(args.preset, bgr, {})
        wall, rcpu, rust_boxes = _native._rust_update_times(args.preset, rgb, BOX)
        assert py_boxes == rust_boxes, "the Python and Rust loops disagree"
        py_wall += calls
        py_cpu += cpu
        rust_wall += wall
        rust_cpu += rcpu
    print(f"preset {args.preset}, 640x480 colour, {args.frames - 1} updates x {args.repeats} runs, medians")
    for clock, py, rs in [("wall", py_wall, rust_wall), ("thread CPU", py_cpu, rust_cpu)]:
        p, r = statistics.median(py), statistics.median(rs)
        print(f"{clock:>10}: update(BGR frame) from Python {p:.3f} ms; the same in a Rust loop {r:.3f} ms; "
              f"binding overhead {1e3 * (p - r):.0f} µs = {100 * (p - r) / r:.1f} %")
    print()
    print(f"{'frame':<26} {'update from Python':>19} {'Rust update alone':>18} {'difference':>11}")
    kinds = [
        ("uint8 BGR (cv2.imread)", bgr, {}),
        ("uint8 RGB (rgb=True)", rgb, {"rgb": True}),
        ("uint8 grey", [np.ascontiguousarray(f.mean(axis=2).astype(np.uint8)) for f in rgb], {}),
        ("float32 grey (in place)", [np.ascontiguousarray(f.mean(axis=2), dtype=np.float32) for f in rgb], {}),
    ]
    for name, frames, kw in kinds:
        calls, rust = [], []
        for _ in range(args.repeats):
            c, _, m, _ = python_loop(args.preset, frames, kw)
            calls += c
            rust += m
        mc, mr = statistics.median(calls), statistics.median(rust)
        print(f"{name:<26} {mc:16.3f} ms {mr:15.3f} ms {1e3 * (mc - mr):8.0f} µs")


if __name__ == "__main__":
    main()
