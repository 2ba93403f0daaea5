"""Shared helpers of the contour_track tests: generated frames, a PNG writer, the track binary."""

import os
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]


def scene(k, width=160, height=120, seed=3, centre=(50.0, 55.0), radii=(18.0, 22.0)):
    """Frame k (RGB uint8) of a generated clip: a skin-coloured ellipse with a dark rim moving
    right and down over a fixed textured background."""
    rng = np.random.default_rng(seed)
    background = rng.integers(40, 120, size=(height // 8 + 1, width // 8 + 1, 3), dtype=np.uint8)
    img = np.kron(background, np.ones((8, 8, 1), dtype=np.uint8))[:height, :width].copy()
    ys, xs = np.mgrid[0:height, 0:width]
    cx, cy = centre[0] + 2.0 * k, centre[1] + 1.0 * k
    r = ((xs - cx) / radii[0]) ** 2 + ((ys - cy) / radii[1]) ** 2
    img[r <= 1.15] = (60, 40, 30)
    img[r <= 1.0] = (220, 170, 140)
    return img


def start_box():
    """The ellipse of frame 0 as a box (x, y, w, h)."""
    return (32.0, 33.0, 36.0, 44.0)


def write_png(path, img):
    """Writes an 8-bit grey (H×W) or RGB (H×W×3) PNG, with zlib only."""
    img = np.ascontiguousarray(img)
    height, width = img.shape[:2]
    colour_type = 2 if img.ndim == 3 else 0
    raw = b"".join(b"\x00" + img[y].tobytes() for y in range(height))

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", width, height, 8, colour_type, 0, 0, 0)
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")
    Path(path).write_bytes(png)


def find_track_bin():
    """The `track` binary: $TRACK_BIN, else the newest executable target/*/track of the
    repository (`cargo doc` leaves a folder target/doc/track, which is not one)."""
    env = os.environ.get("TRACK_BIN")
    if env:
        return Path(env)
    found = sorted(
        (p for p in REPO.glob("target/*/track") if p.is_file() and os.access(p, os.X_OK)),
        key=lambda p: p.stat().st_mtime,
        reverse=True,
    )
    return found[0] if found else None


@pytest.fixture
def track_bin():
    path = find_track_bin()
    if path is None or not path.exists():
        if os.environ.get("CONTOUR_TRACK_REQUIRE_TRACK_BIN"):
            pytest.fail("no track binary: set TRACK_BIN or build it (cargo build -p track-app)")
        pytest.skip("no track binary: set TRACK_BIN or build it (cargo build -p track-app)")
    return path


@pytest.fixture
def clip():
    """Twelve generated RGB frames."""
    return [scene(k) for k in range(12)]


def write_clip(folder, frames):
    """Writes frames as an image folder (0001.png, 0002.png, …); returns the folder."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for k, f in enumerate(frames):
        write_png(folder / f"{k + 1:04d}.png", f)
    return folder


def write_otb(folder, frames, truth):
    """Writes an OTB folder: img/0001.png, … and groundtruth_rect.txt (one x,y,w,h per frame,
    0,0,0,0 for None); returns the folder."""
    folder = Path(folder)
    write_clip(folder / "img", frames)
    lines = ["0,0,0,0" if b is None else ",".join(f"{v:g}" for v in b) for b in truth]
    (folder / "groundtruth_rect.txt").write_text("\n".join(lines) + "\n")
    return folder


def scene_truth(k, centre=(50.0, 55.0), radii=(18.0, 22.0)):
    """The box of frame k's ellipse in `scene`."""
    cx, cy = centre[0] + 2.0 * k, centre[1] + 1.0 * k
    return (cx - radii[0], cy - radii[1], 2 * radii[0], 2 * radii[1])
