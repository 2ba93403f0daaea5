"""Bad input raises only the documented exceptions (docs/PYTHON.md, "Errors and threads"), with
short messages that name what is wrong; numpy integer scalars are accepted wherever an int is."""

import threading

import numpy as np
import pytest

import contour_track as ct
from conftest import scene, start_box


def test_a_frame_too_large_to_allocate_raises_memory_error_before_allocating():
    # One pixel broadcast to 200000×200000: 160 GB as float32 grey, were it allocated.
    huge = np.broadcast_to(np.zeros((1, 1), np.uint8), (200000, 200000))
    t = ct.Tracker(particles=20)
    with pytest.raises(MemoryError, match="200000x200000"):
        t.init(huge, (10, 10, 20, 20))
    with pytest.raises(MemoryError):
        ct.estimate_motion(huge, huge)
    # The tracker is still usable.
    t.init(scene(0), start_box())
    assert t.status.frame == 0


def test_constant_frames_give_an_unreliable_motion_not_a_value_error():
    f = np.full((48, 64), 90, np.uint8)
    for model in ["translation", "scale", "affine"]:
        m = ct.estimate_motion(f, f, model=model)
        assert not m.reliable and not bool(m) and not m.converged
        with pytest.raises(ct.UnreliableMotion, match="singular"):
            m.params
        assert all(np.isnan(m.unchecked_params))


def test_one_tracker_used_from_two_threads_serialises_its_calls():
    frames = [scene(k) for k in range(6)]
    t = ct.Tracker(particles=150)
    t.init(frames[0], start_box())
    errors, seen = [], []
    stop = threading.Event()

    def updater():
        try:
            for _ in range(10):
                for f in frames[1:]:
                    t.update(f)
        except Exception as e:  # noqa: BLE001 - any exception fails the test
            errors.append(e)
        finally:
            stop.set()

    def reader():
        try:
            for _ in range(200):
                seen.append(t.status.frame)
                if stop.is_set():
                    break
        except Exception as e:  # noqa: BLE001
            errors.append(e)

    threads = [threading.Thread(target=updater), threading.Thread(target=updater), threading.Thread(target=reader)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert errors == []
    # Every update ran, one at a time: 2 threads × 10 × 5 updates.
    assert t.status.frame == 100
    assert seen == sorted(seen)


def test_a_bad_config_value_is_named_by_its_key():
    c = ct.Tracker("m2").config
    key = next(k for k, v in c["filter"].items() if isinstance(v, float))
    c["filter"][key] = "x"
    with pytest.raises(ValueError) as e:
        ct.Tracker(config=c)
    message = str(e.value)
    assert f"filter.{key}" in message and "column" not in message, message
    c = ct.Tracker("m2").config
    c["particles"] = 10**30
    with pytest.raises(ValueError) as e:
        ct.Tracker(config=c)
    assert "particles" in str(e.value) and "floating point" not in str(e.value), str(e.value)
    assert len(str(e.value)) < 120
    c = ct.Tracker("m2").config
    c["filter"][key] = float("nan")
    with pytest.raises(ValueError, match=f"filter.{key}.*not a finite number"):
        ct.Tracker(config=c)


def test_numpy_integers_are_accepted_as_ints_and_bools_and_floats_are_not():
    t = ct.Tracker(particles=np.int64(50), seed=np.uint64(3))
    assert (t.particles, t.seed) == (50, 3)
    assert ct.Tracker(particles=np.int32(40), seed=np.int16(2)).particles == 40
    c = ct.Tracker("m2").config
    c["particles"] = np.int64(70)
    c["seed"] = np.uint32(5)
    assert ct.Tracker(config=c).particles == 70
    for bad in [True, np.bool_(True), 50.0, np.float64(50.0), "50"]:
        with pytest.raises(TypeError, match="particles must be an int"):
            ct.Tracker(particles=bad)
    with pytest.raises(ValueError, match="particles"):
        ct.Tracker(particles=np.int64(-1))


def test_a_mask_of_shape_h_w_1_is_a_mask():
    f0, f1 = scene(0), scene(1)
    mask = np.zeros((120, 160), np.uint8)
    mask[:, :80] = 255
    flat = ct.estimate_motion(f0, f1, roi=mask)
    deep = ct.estimate_motion(f0, f1, roi=mask[:, :, None])
    assert flat.unchecked_params == deep.unchecked_params
    with pytest.raises(ValueError, match="mask has shape"):
        ct.estimate_motion(f0, f1, roi=np.ones((120, 160, 2), np.uint8))


def test_a_huge_box_gives_a_short_message():
    t = ct.Tracker(particles=20)
    with pytest.raises(ValueError) as e:
        t.init(scene(0), (100, 100, 1e300, 1e300))
    message = str(e.value)
    assert len(message) < 120 and "1e300" in message, message
    # The message of `track run --init 100,100,1e300,1e300` (vision-core's BoundingBox::check_start).
    assert message == "box 100,100,1e300,1e300 lies outside the 160×120 frame (its centre is outside)"
    with pytest.raises(ValueError) as e:
        ct.estimate_motion(scene(0), scene(1), roi=(0, 0, -1e300, 5))
    assert len(str(e.value)) < 120, str(e.value)


def test_float32_grey_frames_are_range_checked_as_colour_ones_are():
    grey = scene(0).mean(axis=2).astype(np.float32)
    t = ct.Tracker(particles=20)
    t.init(grey, start_box())
    for bad in [grey * 2.0, grey - 200.0]:
        with pytest.raises(ValueError, match="0–255"):
            t.update(bad.astype(np.float32))
    # Strided (copied) frames are checked too.
    wide = np.zeros((120, 320), np.float32)
    wide[:, ::2] = grey * 3
    with pytest.raises(ValueError, match="0–255"):
        t.update(wide[:, ::2])
