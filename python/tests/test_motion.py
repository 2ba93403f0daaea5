"""estimate_motion: parameters, covariance, reliability, and its bad inputs."""

import numpy as np
import pytest

import contour_track as ct


def texture(width=128, height=96, dx=0.0, dy=0.0):
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float64)
    x, y = xs - dx, ys - dy
    t = 128 + 40 * np.sin(0.31 * x + 0.1 * y) + 30 * np.cos(0.23 * y - 0.05 * x)
    return t.astype(np.float32)


@pytest.mark.parametrize("shift", [(1.5, -0.75), (-2.0, 1.0), (0.5, 2.5)])
def test_translation_is_recovered_with_a_covariance(shift):
    f0, f1 = texture(), texture(dx=shift[0], dy=shift[1])
    m = ct.estimate_motion(f0, f1, model="translation")
    assert m.reliable and m.converged and bool(m)
    assert m.model == "translation"
    assert m.params == pytest.approx(list(shift), abs=0.02)
    cov = np.array(m.covariance)
    assert cov.shape == (2, 2)
    assert np.allclose(cov, cov.T) and np.all(np.linalg.eigvalsh(cov) > 0)
    a = m.affine
    assert a[0] == pytest.approx(shift[0], abs=0.02) and a[3] == pytest.approx(shift[1], abs=0.02)
    assert "reliable=True" in repr(m)


def test_affine_default_model_with_a_box_and_masks():
    f0, f1 = texture(), texture(dx=1.0, dy=0.5)
    m = ct.estimate_motion(f0, f1, (20, 20, 60, 50))
    assert m.model == "affine" and len(m.params) == 6 and np.array(m.covariance).shape == (6, 6)
    assert m.params[0] == pytest.approx(1.0, abs=0.05) and m.params[3] == pytest.approx(0.5, abs=0.05)
    mask = np.zeros(f0.shape, bool)
    mask[20:70, 20:80] = True
    for roi in [mask, mask.astype(np.uint8) * 255, mask.astype(np.float32), mask.astype(np.float64)]:
        r = ct.estimate_motion(f0, f1, roi, model="translation")
        assert r.params == pytest.approx([1.0, 0.5], abs=0.03)


def test_colour_frames_and_offset():
    g0, g1 = texture(), texture(dx=1.0)
    c0 = np.repeat(g0.round().clip(0, 255).astype(np.uint8)[:, :, None], 3, axis=2)
    c1 = np.repeat(g1.round().clip(0, 255).astype(np.uint8)[:, :, None], 3, axis=2)
    m = ct.estimate_motion(c0, c1, model="translation")
    assert m.params == pytest.approx([1.0, 0.0], abs=0.05)
    m = ct.estimate_motion(g0, g1 + 10.0, model="translation", offset=True)
    assert len(m.params) == 3 and m.params[2] == pytest.approx(10.0, abs=0.5)


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("model", ["translation", "affine"])
def test_unreliable_estimate_cannot_be_mistaken_for_a_good_one(seed, model):
    # Two frames of independent noise: no motion maps one onto the other.
    rng = np.random.default_rng(seed)
    # Grey levels in 0–255, as float32 grey frames must hold.
    f0 = np.clip(128 + rng.normal(0, 30, (96, 128)), 0, 255).astype(np.float32)
    f1 = np.clip(128 + rng.normal(0, 30, (96, 128)), 0, 255).astype(np.float32)
    m = ct.estimate_motion(f0, f1, model=model)
    assert not m.reliable and not bool(m)
    for attribute in ["params", "covariance", "affine"]:
        with pytest.raises(ct.UnreliableMotion, match="not reliable"):
            getattr(m, attribute)
    n = 2 if model == "translation" else 6
    assert len(m.unchecked_params) == n and len(m.unchecked_covariance) == n
    assert issubclass(ct.UnreliableMotion, RuntimeError)
    assert "reliable=False" in repr(m)


@pytest.mark.parametrize(
    "kwargs, error, message",
    [
        ({"model": "projective"}, ValueError, "projective"),
        ({"roi": (0, 0, -5, 10)}, ValueError, "positive size"),
        ({"roi": (np.nan, 0, 5, 10)}, ValueError, "finite"),
        ({"roi": (1, 2, 3)}, TypeError, "four numbers"),
        ({"roi": np.zeros((96, 128), np.int32)}, TypeError, "mask has dtype"),
        ({"roi": np.zeros((50, 128), bool)}, ValueError, "mask is 128x50"),
        ({"roi": np.full((96, 128), 2.0)}, ValueError, r"\[0, 1\]"),
        ({"roi": np.zeros((96, 128), bool)}, ValueError, "motion estimation"),
    ],
)
def test_bad_motion_inputs(kwargs, error, message):
    f0, f1 = texture(), texture(dx=1.0)
    with pytest.raises(error, match=message):
        ct.estimate_motion(f0, f1, **kwargs)


def test_bad_motion_frames():
    f0 = texture()
    with pytest.raises(ValueError, match="must have one size"):
        ct.estimate_motion(f0, texture(width=64))
    bad = f0.copy()
    bad[5, 6] = np.nan
    with pytest.raises(ValueError, match="row 5, column 6"):
        ct.estimate_motion(f0, bad)
    with pytest.raises(TypeError, match="f1"):
        ct.estimate_motion(f0, f0.astype(np.float64))
