"""Tracker construction, presets, configs, status and help."""

import json
import pydoc
from pathlib import Path

import numpy as np
import pytest

import contour_track as ct
from conftest import scene, start_box

PRESET_NAMES = ["m1", "m2", "m3", "w-fixed", "w-switch", "w-hmm", "w-occ", "w-eval", "full", "head"]


def test_presets_lists_every_preset_with_one_line_each():
    listed = ct.presets()
    assert [name for name, _ in listed] == PRESET_NAMES
    for name, line in listed:
        assert line and "\n" not in line, name
    assert ct.DEFAULT_TRACKER == "head"
    assert "recommended" in dict(listed)["head"]


def test_defaults_follow_track_run():
    t = ct.Tracker()
    assert (t.name, t.particles, t.seed) == ("head", 200, 1)
    t = ct.Tracker("m3", particles=50, seed=7)
    assert (t.name, t.particles, t.seed) == ("m3", 50, 7)
    assert t.status is None and t.frame_size is None
    assert "m3" in repr(t)


def test_unknown_preset_names_the_known_ones():
    with pytest.raises(ValueError, match="w-eval"):
        ct.Tracker("nope")


@pytest.mark.parametrize("particles", [0, -1, 10**7, 2**70])
def test_bad_particle_counts_are_value_errors(particles):
    with pytest.raises(ValueError, match="particles"):
        ct.Tracker("m1", particles=particles)


@pytest.mark.parametrize("kw", [{"particles": "100"}, {"particles": 1.5}, {"seed": "1"}, {"seed": True}])
def test_non_integer_counts_are_type_errors(kw):
    with pytest.raises(TypeError):
        ct.Tracker("m1", **kw)


def test_negative_seed_is_a_value_error():
    with pytest.raises(ValueError, match="seed"):
        ct.Tracker("m1", seed=-1)


def test_config_dict_round_trips():
    c = ct.Tracker("w-hmm", particles=80, seed=4).config
    assert c["name"] == "w-hmm" and c["particles"] == 80 and c["seed"] == 4
    t = ct.Tracker(config=c)
    assert t.config == c
    # particles and seed override the config's, as --particles and --seed do.
    t = ct.Tracker(config=c, particles=30, seed=9)
    assert (t.particles, t.seed) == (30, 9)


def test_config_file_json(tmp_path):
    c = ct.Tracker("m2", particles=60).config
    path = tmp_path / "m2.json"
    path.write_text(json.dumps(c, indent=2))
    assert ct.Tracker(config=path).config == c
    assert ct.Tracker(config=str(path)).config == c


def test_config_file_toml(tmp_path, track_bin):
    import subprocess

    text = subprocess.run(
        [str(track_bin), "config", "w-eval", "--toml", "--particles", "70"],
        check=True, capture_output=True, text=True,
    ).stdout
    path = tmp_path / "w-eval.toml"
    path.write_text(text)
    t = ct.Tracker(config=path)
    assert t.config == ct.Tracker("w-eval", particles=70).config
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("particles = 70", "particles = \"many\""))
    with pytest.raises(ValueError, match="invalid TOML at line"):
        ct.Tracker(config=bad)


def test_bad_configs(tmp_path):
    c = ct.Tracker("m1").config
    with pytest.raises(ValueError, match="unknown field"):
        ct.Tracker(config={**c, "bogus": 1})
    with pytest.raises(ValueError, match="particles"):
        ct.Tracker(config={**c, "particles": 0})
    with pytest.raises(ValueError, match="not both"):
        ct.Tracker("m1", config=c)
    with pytest.raises(FileNotFoundError):
        ct.Tracker(config=tmp_path / "missing.json")
    broken = tmp_path / "broken.json"
    broken.write_text("{")
    with pytest.raises(ValueError, match="invalid JSON"):
        ct.Tracker(config=broken)
    with pytest.raises(TypeError, match="dict or a path"):
        ct.Tracker(config=42)


def _run(tracker, frames, **kw):
    tracker.init(frames[0], start_box(), **kw)
    out = []
    for f in frames[1:]:
        out.append(tracker.update(f, **kw))
    return out


def test_head_status_has_probabilities_and_ess(clip):
    t = ct.Tracker("head", particles=100)
    t.init(clip[0], start_box(), rgb=True)
    s = t.status
    assert s.frame == 0 and s.ess == pytest.approx(100.0)
    out = _run(t, clip, rgb=True)
    s = t.status
    assert s.frame == len(clip) - 1
    probs = [s.p_locked, s.p_partial, s.p_lost]
    assert all(p is not None and 0.0 <= p <= 1.0 for p in probs)
    assert sum(probs) == pytest.approx(1.0)
    assert s.state in ("locked", "partial", "lost")
    assert s.ok == (s.state != "lost") == out[-1][0]
    assert 0.0 < s.ess <= 100.0
    assert tuple(s.box) == out[-1][1]
    cx, cy, a, b, angle = s.ellipse
    x, y, w, h = s.box
    assert cx == pytest.approx(x + w / 2) and cy == pytest.approx(y + h / 2)
    assert s.millis > 0
    # The generated ellipse moved 2 px right and 1 px down per frame.
    k = len(clip) - 1
    assert abs(cx - (50 + 2 * k)) < 6 and abs(cy - (55 + k)) < 6
    assert "p_lost" in repr(s)


def test_hidden_processes_where_the_preset_has_them(clip):
    grey = [f.mean(axis=2).astype(np.float32) for f in clip[:4]]
    t = ct.Tracker("m1", particles=50)
    _run(t, grey)
    s = t.status
    assert s.p_locked is None and s.beta_hat is None and s.lambda_hat is None and s.gamma_hat is None
    assert s.beta_probs == [] and s.state == "locked"
    t = ct.Tracker("w-hmm", particles=50)
    _run(t, grey)
    s = t.status
    assert s.beta_hat is not None and s.lambda_hat > 0
    assert sum(s.beta_probs) == pytest.approx(1.0) and 0 <= s.beta_hat < len(s.beta_probs)
    t = ct.Tracker("w-eval", particles=50)
    _run(t, grey)
    s = t.status
    assert s.gamma_hat is not None and 0.0 <= s.gamma_hat <= 1.0
    assert sum([s.p_locked, s.p_partial, s.p_lost]) == pytest.approx(1.0)


def test_help_is_useful():
    text = pydoc.render_doc(ct.Tracker, renderer=pydoc.plaintext)
    for word in ["init", "update", "status", "presets()", "BGR", "rgb=True", "ValueError", "seed"]:
        assert word in text, word
    assert "UnreliableMotion" in pydoc.render_doc(ct.estimate_motion, renderer=pydoc.plaintext)
    assert ct.Tracker.update.__doc__ and "(ok, (x, y, w, h))" in ct.Tracker.update.__doc__


def test_package_ships_type_stubs():
    package = Path(ct.__file__).parent
    assert (package / "py.typed").exists()
    stub = (package / "__init__.pyi").read_text()
    for name in ["class Tracker", "class Status", "class Motion", "def estimate_motion", "def presets"]:
        assert name in stub
