#!/usr/bin/env python3
"""The cost of spreading an OTB evaluation over a Dask cluster.

Runs one protocol of one tracker on OTB folders twice on this machine: `track eval otb` (rayon
over every core, each sequence decoded once), then `contour_track.cluster.evaluate_otb` on a
`LocalCluster` of N single-threaded worker processes (one Dask task per run, each decoding its
sequence). Prints the wall time of both, the overhead per run, and checks that the two give the
same tables (frames/s aside) and the same box files.

    python python/bench/bench_cluster.py --track target/release/track --workers 2 \\
        --protocol tre ../shared/data/real/*/
"""

import argparse
import csv
import filecmp
import io
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from dask.distributed import Client, LocalCluster

from contour_track.cluster import evaluate_otb


def without_fps(path):
    rows = list(csv.DictReader(io.StringIO(Path(path).read_text())))
    for r in rows:
        r.pop("fps")
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("folders", nargs="+")
    p.add_argument("--track", required=True, help="the track binary (a release build)")
    p.add_argument("--tracker", default="head")
    p.add_argument("--protocol", default="tre")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--out", default=None, help="folder for both outputs (default: a temporary one)")
    a = p.parse_args()
    out = Path(a.out or tempfile.mkdtemp(prefix="bench-cluster-"))
    folders = [f.rstrip("/") for f in a.folders if Path(f, "groundtruth_rect.txt").is_file()]

    t0 = time.perf_counter()
    subprocess.run([a.track, "eval", "otb", *folders, "--tracker", a.tracker, "--protocol", a.protocol,
                    "--seed", str(a.seed), "--quiet", "--out", str(out / "cli")],
                   check=True, stdout=subprocess.DEVNULL)
    cli = time.perf_counter() - t0

    t0 = time.perf_counter()
    with LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        client.wait_for_workers(a.workers)
        started = time.perf_counter() - t0
        t1 = time.perf_counter()
        evaluate_otb(folders, [a.tracker], protocols=[a.protocol], seeds=[a.seed], client=client,
                     out=out / "dask", progress=False)
        dask = time.perf_counter() - t1

    runs = sorted(f.relative_to(out / "cli") for f in (out / "cli" / a.protocol).rglob("*.txt"))
    same_boxes = all(filecmp.cmp(out / "cli" / f, out / "dask" / f, shallow=False) for f in runs)
    same_table = without_fps(out / "cli" / a.protocol / "otb.csv") == without_fps(out / "dask" / a.protocol / "otb.csv")
    mean = [r for r in without_fps(out / "dask" / a.protocol / "otb.csv") if r["sequence"] == "mean"][0]
    print(f"{len(folders)} sequences, {len(runs)} {a.protocol.upper()} runs of {a.tracker}, seed {a.seed}")
    print(f"track eval otb:            {cli:8.1f} s wall")
    print(f"evaluate_otb, {a.workers} workers:  {dask:8.1f} s wall (+ {started:.1f} s to start the LocalCluster)")
    print(f"overhead per run:          {(dask - cli) / len(runs):8.2f} s ({100 * (dask / cli - 1):+.0f} %)")
    print(f"mean success AUC {mean['success_auc']}, precision@20 {mean['precision_20']}")
    print(f"same tables (frames/s aside): {same_table}; same box files: {same_boxes}")
    print(f"outputs in {out}")
    return 0 if same_table and same_boxes else 1


if __name__ == "__main__":
    sys.exit(main())
