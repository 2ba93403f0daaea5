"""contour_track.cluster on a LocalCluster of two worker processes: track_many and evaluate_otb
give what serial runs and `track eval otb` give, figure for figure."""

import csv
import io
import subprocess

import numpy as np
import pytest

pytest.importorskip("dask.distributed")

import contour_track as ct  # noqa: E402
from contour_track import cluster  # noqa: E402
from conftest import scene, scene_truth, write_clip, write_otb  # noqa: E402

# Everything but the timing of each frame.
COMPARED = [name for name in ct.RECORD_DTYPE.names if name != "millis"]


def same_records(a, b):
    """Whether two record arrays agree in every field but the timing (NaN equal to NaN)."""
    if a.shape != b.shape:
        return False
    for name in COMPARED:
        x, y = a[name], b[name]
        if x.dtype.kind == "f":
            if not np.array_equal(x, y, equal_nan=True):
                return False
        elif not np.array_equal(x, y):
            return False
    return True


@pytest.fixture(scope="module")
def client():
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as lc:
        with Client(lc) as c:
            yield c


@pytest.fixture(scope="module")
def clips(tmp_path_factory):
    """Three small generated clips (image folders) and one OTB folder."""
    root = tmp_path_factory.mktemp("clips")
    folders = []
    for s in range(3):
        frames = [scene(k, width=128, height=96, seed=s) for k in range(6)]
        folders.append(write_clip(root / f"clip{s}", frames))
    otb = write_otb(root / "walk", [scene(k, width=128, height=96) for k in range(6)],
                    [scene_truth(k) for k in range(6)])
    return folders, otb


def test_track_many_equals_serial_runs_and_reports_a_failed_job(client, clips, tmp_path):
    folders, otb = clips
    jobs = []
    for k in range(12):
        start = (30.0 + k % 3, 33.0, 36.0, 44.0)
        jobs.append({"source": folders[k % 3], "init": start, "seed": 1 + k, "particles": 40,
                     "preset": "head" if k % 4 else "m1"})
    jobs.insert(5, (str(folders[0].parent / "no-such-clip"), (1, 2, 3, 4)))
    jobs.append(otb)  # an OTB folder starts at its first labelled box
    results = cluster.track_many(jobs, client=client, progress=False)
    assert len(results) == len(jobs)
    failed = [r for r in results if not r.ok]
    assert [r.source for r in failed] == [str(folders[0].parent / "no-such-clip")]
    assert failed[0].error.startswith("ValueError") and "no such file" in failed[0].error
    assert failed[0].records is None
    for job, r in zip(jobs, results):
        if not r.ok:
            continue
        source, init, options = cluster._job(job)
        serial = ct.track_video(source, init, **options)
        assert r.source == source
        assert same_records(r.records, serial), source
    # Different seeds give different boxes: the comparison is not vacuous.
    assert not np.array_equal(results[0].records[["x", "y"]], results[3].records[["x", "y"]])


def test_track_many_writes_track_runs_files(client, clips, tmp_path):
    folders, _ = clips
    jobs = [{"source": f, "init": (30.0, 33.0, 36.0, 44.0), "particles": 30, "out": tmp_path / f.name}
            for f in folders]
    results = cluster.track_many(jobs, client=client, progress=False)
    assert all(r.ok for r in results)
    for f in folders:
        names = {p.name for p in (tmp_path / f.name).iterdir()}
        assert {"boxes.txt", "track.csv", "summary.json"} <= names


def without_fps(table):
    """otb.csv without its frames/s column (a timing)."""
    rows = list(csv.DictReader(io.StringIO(table)))
    for r in rows:
        r.pop("fps")
    return rows


def test_evaluate_otb_equals_track_eval_otb(client, tmp_path, track_bin):
    # Two OTB folders, the second with unlabelled frames, as the OTB benchmark has them.
    n = 8
    a = write_otb(tmp_path / "seqs" / "ahead", [scene(k, width=128, height=96) for k in range(n)],
                  [scene_truth(k) for k in range(n)])
    b = write_otb(tmp_path / "seqs" / "bdrift", [scene(k, width=128, height=96, seed=7) for k in range(n)],
                  [None if k in (0, 4, 5) else scene_truth(k) for k in range(n)])
    protocols = ["ope", "tre", "sre"]
    cli = tmp_path / "cli"
    subprocess.run(
        [str(track_bin), "eval", "otb", str(a), str(b), "--tracker", "head", "--tracker", "m1",
         "--particles", "30", "--seed", "3", "--quiet", "--out", str(cli)]
        + [w for p in protocols for w in ("--protocol", p)],
        check=True, capture_output=True,
    )
    py = tmp_path / "py"
    rows = cluster.evaluate_otb([a, b], ["head", "m1"], protocols=protocols, seeds=[np.int64(3)],
                                client=client, out=py, particles=30, progress=False)
    for p in protocols:
        cli_table = (cli / p / "otb.csv").read_text()
        py_table = (py / p / "otb.csv").read_text()
        assert without_fps(py_table) == without_fps(cli_table)
        # Every run's box file, byte for byte.
        cli_boxes = sorted(f.relative_to(cli) for f in (cli / p).rglob("*.txt"))
        py_boxes = sorted(f.relative_to(py) for f in (py / p).rglob("*.txt"))
        assert py_boxes == cli_boxes and len(cli_boxes) > 2
        for f in cli_boxes:
            assert (py / f).read_bytes() == (cli / f).read_bytes(), f
        assert (py / p / "plots" / "success.svg").is_file()
    sre = (py / "sre" / "otb.md").read_text()
    assert "start convention" in sre and sre.split("start convention")[1] == (cli / "sre" / "otb.md").read_text().split("start convention")[1]
    assert (py / "index.html").is_file()
    # The returned table is otb.csv's, with the seed.
    assert {(r["protocol"], r["sequence"], r["tracker"]) for r in rows} == {
        (r["protocol"], r["sequence"], r["tracker"]) for p in protocols for r in without_fps((cli / p / "otb.csv").read_text())
    }
    assert all(r["seed"] == 3 for r in rows)
    # track eval otb --results reads the box files back.
    subprocess.run(
        [str(track_bin), "eval", "otb", str(a), str(b), "--results", f"head={py}", "--quiet",
         "--out", str(tmp_path / "reread")],
        check=True, capture_output=True,
    )
    reread = without_fps((tmp_path / "reread" / "ope" / "otb.csv").read_text())
    assert [r["runs"] for r in reread] == [r["runs"] for r in without_fps((cli / "ope" / "otb.csv").read_text()) if r["tracker"] == "head"]


def test_evaluate_otb_writes_one_folder_per_seed_and_refuses_bad_arguments(client, tmp_path):
    a = write_otb(tmp_path / "seqs" / "ahead", [scene(k, width=128, height=96) for k in range(6)],
                  [scene_truth(k) for k in range(6)])
    rows = cluster.evaluate_otb([a], seeds=(1, 2), client=client, out=tmp_path / "out", particles=30,
                                progress=False)
    assert {r["seed"] for r in rows} == {1, 2}
    assert (tmp_path / "out" / "seed-1" / "ope" / "head" / "ahead.txt").is_file()
    assert (tmp_path / "out" / "seed-2" / "ope" / "otb.csv").is_file()
    with pytest.raises(ValueError, match="neither a preset"):
        cluster.evaluate_otb([a], ["nope"], client=client, out=tmp_path / "x", progress=False)
    with pytest.raises(ValueError, match="protocol"):
        cluster.evaluate_otb([a], protocols=["xyz"], client=client, out=tmp_path / "x", progress=False)
    with pytest.raises(TypeError):
        cluster.evaluate_otb([a], seeds=[True], client=client, out=tmp_path / "x", progress=False)
    plain = write_clip(tmp_path / "plain", [scene(k) for k in range(3)])
    with pytest.raises(ValueError, match="groundtruth_rect.txt is missing"):
        cluster.evaluate_otb([plain], client=client, out=tmp_path / "x", progress=False)
