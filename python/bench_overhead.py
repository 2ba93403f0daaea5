#!/usr/bin/env python3
"""The binding's overhead on one `update` of a 640×480 frame.

For each kind of frame, times `Tracker.update` from Python (perf_counter around the call) and
the Rust update alone (`status.millis`, the wall time the Rust tracker measures inside the same
call), over the same frames; the difference is what the binding adds: reading the numpy array,
converting it to the trackers' grey (and RGB) frame, releasing the GIL, building the result.

    python python/bench_overhead.py [--preset head] [--frames 200] [--repeats 3]

Frames: a generated 640×480 clip, a 150×200 px head-like ellipse swaying over texture.
"""

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

import contour_track as ct

sys.path.insert(0, str(Path(__file__).resolve().parent / "tests"))
from conftest import scene  # noqa: E402


def run(preset, frames, convert, kw, repeats):
    per_call, rust = [], []
    for _ in range(repeats):
        t = ct.Tracker(preset)
        t.init(convert(frames[0]), (245, 140, 150, 200), **kw)
        for f in frames[1:]:
            g = convert(f)
            t0 = time.perf_counter()
            t.update(g, **kw)
            per_call.append((time.perf_counter() - t0) * 1e3)
            rust.append(t.status.millis)
    return per_call, rust


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--preset", default="head")
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    # A 150×200 px head-like ellipse at the centre, swaying 20 px left and right.
    head = scene(0, 640, 480, centre=(320.0, 240.0), radii=(75.0, 100.0))
    rgb_frames = [np.ascontiguousarray(np.roll(head, int(round(20 * np.sin(k / 10))), axis=1)) for k in range(args.frames)]
    kinds = [
        ("uint8 BGR (cv2.imread)", lambda f: np.ascontiguousarray(f[:, :, ::-1]), {}),
        ("uint8 RGB (rgb=True)", lambda f: f, {"rgb": True}),
        ("uint8 grey", lambda f: np.ascontiguousarray(f.mean(axis=2).astype(np.uint8)), {}),
        ("float32 grey (in place)", lambda f: np.ascontiguousarray(f.mean(axis=2), dtype=np.float32), {}),
    ]
    print(f"preset {args.preset}, 640x480, {args.frames - 1} updates x {args.repeats} runs; medians")
    print(f"{'frame':<26} {'update from Python':>19} {'Rust update':>12} {'overhead':>10} {'share':>7}")
    for name, convert, kw in kinds:
        per_call, rust = run(args.preset, rgb_frames, convert, kw, args.repeats)
        overhead = [p - r for p, r in zip(per_call, rust)]
        med_call, med_rust, med_over = (statistics.median(v) for v in (per_call, rust, overhead))
        print(f"{name:<26} {med_call:16.3f} ms {med_rust:9.3f} ms {med_over * 1e3:7.0f} µs {100 * med_over / med_rust:6.1f}%")


if __name__ == "__main__":
    main()
