"""Many videos on a Dask cluster: ``track_many`` and ``evaluate_otb``.

Installed with ``pip install "contour-track[dask]"`` (from a checkout: ``pip install
"./python[dask]"``); the base package does not need Dask. Both functions take a
``dask.distributed.Client``: one connected to an existing scheduler
(``Client("tcp://scheduler:8786")``) spreads the work over its workers; with no client, a
``LocalCluster`` of one single-threaded worker process per core is started for the call and
closed after it.

The work itself is ``track run`` and ``track eval otb``'s own code (the Rust library behind
both), one task per video or per OTB run; Dask only schedules it. Every task is seeded on its
own, and results are gathered in the order of the jobs, so the results are identical to a
serial run for any number of workers (timings aside). The workers must have this package
installed and read the sources at the same paths as the caller.
"""

import csv
import io
import operator
import os
import sys
import uuid
from dataclasses import dataclass
from typing import Any, Optional

try:
    from dask.distributed import Client, LocalCluster, as_completed
except ImportError as e:  # pragma: no cover - the message is the point
    raise ImportError(
        "contour_track.cluster needs Dask: pip install \"contour-track[dask]\" "
        "(from a checkout: pip install \"./python[dask]\")"
    ) from e

from . import _native
from ._batch import otb_run, track_video

__all__ = ["JobResult", "evaluate_otb", "track_many"]


@dataclass
class JobResult:
    """The outcome of one job of ``track_many``, in the order of the jobs.

    ``records`` is what ``track_video`` returned (None when the job failed); ``error`` is the
    job's error as "ExceptionType: message" (None when it succeeded).
    """

    source: str
    init: Optional[tuple]
    records: Any = None
    error: Optional[str] = None

    @property
    def ok(self):
        """Whether the job succeeded."""
        return self.error is None


def _job(job):
    """A job as (source, init, keyword arguments of track_video)."""
    if isinstance(job, dict):
        job = dict(job)
        try:
            source = job.pop("source")
        except KeyError:
            raise ValueError(f"a job dict needs a 'source': {job!r}") from None
        return os.fspath(source), job.pop("init", None), job
    if isinstance(job, (str, os.PathLike)):
        return os.fspath(job), None, {}
    try:
        items = tuple(job)
    except TypeError:
        raise TypeError(
            f"a job is a source, a (source, init) pair, a (source, init, options) triple or a "
            f"dict, not {type(job).__name__}"
        ) from None
    if len(items) == 2:
        return os.fspath(items[0]), items[1], {}
    if len(items) == 3 and isinstance(items[2], dict):
        return os.fspath(items[0]), items[1], dict(items[2])
    raise ValueError(
        f"a job is a source, a (source, init) pair or a (source, init, options) triple, "
        f"got {len(items)} items"
    )


class _Progress:
    """One line on standard error: tasks done out of the total, and failures."""

    def __init__(self, what, total, enabled):
        self.what, self.total, self.enabled = what, total, enabled
        self.done = self.failed = 0
        self.tty = enabled and sys.stderr.isatty()

    def step(self, failed=False):
        self.done += 1
        self.failed += failed
        if not self.enabled:
            return
        text = f"{self.what}: {self.done}/{self.total} done"
        if self.failed:
            text += f", {self.failed} failed"
        if self.tty:
            sys.stderr.write("\r" + text + ("\n" if self.done == self.total else ""))
        elif self.done == self.total or self.failed and failed:
            sys.stderr.write(text + "\n")
        sys.stderr.flush()


class _ClientOf:
    """The client given, or a LocalCluster's started for the call (and closed after it)."""

    def __init__(self, client):
        self.client, self.cluster, self.own = client, None, client is None

    def __enter__(self):
        if self.own:
            self.cluster = LocalCluster(
                n_workers=os.cpu_count() or 1,
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
            )
            self.client = Client(self.cluster)
        return self.client

    def __exit__(self, *exc):
        if self.own:
            self.client.close()
            self.cluster.close()


def _gather(client, futures, progress):
    """Waits for every future; returns (results, errors) in the futures' order."""
    index = {f.key: k for k, f in enumerate(futures)}
    results = [None] * len(futures)
    errors = [None] * len(futures)
    for f in as_completed(futures):
        k = index[f.key]
        if f.status == "error":
            e = f.exception()
            errors[k] = e
            progress.step(failed=True)
        else:
            results[k] = f.result()
            progress.step()
        f.release()
    return results, errors


def track_many(jobs, client=None, *, progress=True):
    """Runs ``track_video`` on every job, spread over a Dask cluster.

    Arguments:
        jobs: an iterable of jobs, each a source (an OTB folder, which gives its own start), a
            ``(source, init)`` pair, a ``(source, init, options)`` triple, or a dict with
            ``source``, ``init`` and any other keyword of ``track_video`` (``preset``, ``seed``,
            ``particles``, ``config``, ``out``, ``with_summary``).
        client: a ``dask.distributed.Client``; None starts a ``LocalCluster`` for the call.
        progress: show the number of jobs done (and failed) on standard error.

    Returns:
        A list of ``JobResult`` in the order of the jobs: ``records`` is ``track_video``'s result,
        or ``error`` says why the job failed ("ExceptionType: message"). A failed job does not
        stop the others; each failure is also reported on standard error with its source.

    The records are identical to those of ``track_video`` called job by job in one process, for
    any number of workers (``millis``, a timing, aside).

    Raises:
        TypeError, ValueError: a job that is not of one of the forms above.
    """
    parsed = [_job(j) for j in jobs]
    with _ClientOf(client) as c:
        tag = uuid.uuid4().hex[:8]
        futures = [
            c.submit(track_video, source, init, key=f"track_video-{tag}-{k}", pure=False, **kw)
            for k, (source, init, kw) in enumerate(parsed)
        ]
        results, errors = _gather(c, futures, _Progress("track_many", len(futures), progress))
    out = []
    for (source, init, _), records, error in zip(parsed, results, errors):
        message = None if error is None else f"{type(error).__name__}: {error}"
        if message is not None and progress:
            sys.stderr.write(f"track_many: {source} failed: {message}\n")
        out.append(JobResult(source=source, init=init, records=records, error=message))
    return out


def _trackers(trackers):
    """Trackers as ("preset", NAME) or ("config", PATH) pairs: a preset's name, else a path."""
    if isinstance(trackers, (str, os.PathLike)):
        trackers = [trackers]
    names = {name for name, _ in _native.presets()}
    out = []
    for t in trackers:
        if isinstance(t, str) and t in names:
            out.append(("preset", t))
        elif isinstance(t, (str, os.PathLike)):
            path = os.fspath(t)
            if not os.path.isfile(path):
                raise ValueError(
                    f"tracker {path!r} is neither a preset ({', '.join(sorted(names))}) nor a "
                    "configuration file"
                )
            out.append(("config", os.path.abspath(path)))
        else:
            raise TypeError(
                f"a tracker is a preset's name or a configuration file's path, not "
                f"{type(t).__name__}"
            )
    return out


def _seed(s):
    """A seed as ``operator.index`` reads it (numpy integers too), not a bool."""
    if isinstance(s, bool) or type(s).__name__ == "bool_":
        raise TypeError(f"a seed must be an int, got {type(s).__name__}")
    try:
        s = operator.index(s)
    except TypeError:
        raise TypeError(f"a seed must be an int, got {type(s).__name__}") from None
    if not 0 <= s < 2**64:
        raise ValueError(f"a seed must be a non-negative integer below 2**64, got {s}")
    return s


def _number(text):
    if text == "":
        return None
    try:
        return int(text)
    except ValueError:
        return float(text)


def _rows(table, seed):
    rows = []
    for row in csv.DictReader(io.StringIO(table)):
        parsed = {k: (v if k in ("protocol", "sequence", "tracker") else _number(v))
                  for k, v in row.items()}
        parsed["seed"] = seed
        rows.append(parsed)
    return rows


def evaluate_otb(folders, trackers=(_native.DEFAULT_TRACKER,), protocols=("ope",), seeds=(1,),
                 client=None, *, out="track-eval", particles=None, progress=True):
    """The OTB protocols as ``track eval otb`` runs them, spread over a Dask cluster run by run.

    Arguments:
        folders: OTB folders (``img/`` and ``groundtruth_rect.txt``).
        trackers: preset names and configuration files (JSON or TOML), as ``--tracker`` and
            ``--config`` (default "head"). The tables list them in this order (``track eval
            otb`` lists presets before files).
        protocols: any of "ope", "tre", "sre".
        seeds: one evaluation per seed, as ``track eval otb --seed SEED``.
        client: a ``dask.distributed.Client``; None starts a ``LocalCluster`` for the call.
        out: the output folder. With one seed it is laid out as ``track eval otb --out OUT``:
            per protocol ``P/otb.md``, ``P/otb.csv``, ``P/plots/*.svg`` and every run's boxes
            ``P/TRACKER/SEQ[.RUN].txt`` (readable by ``track eval otb --results``), and
            ``index.html``. With several seeds, ``OUT/seed-S/`` holds that of seed S.
        particles: particles of every tracker (default: a preset's 200, or a file's own).
        progress: show the number of runs done on standard error.

    Returns:
        The per-sequence table of every protocol and seed: a list of dicts with the columns of
        ``otb.csv`` (protocol, sequence, tracker, runs, frames, labelled, success_auc,
        precision_20, mean_iou, fps, lost_auc; each tracker's mean as sequence "mean") and the
        seed. The figures are those of ``track eval otb`` on the same folders, seed and trackers
        (fps, a timing, aside), for any number of workers.

    The folders are checked on the caller (as ``track eval otb`` checks them, every frame
    decoded) and the box files and tables are written there; the workers read the folders at
    the same paths.

    Raises:
        TypeError, ValueError: bad arguments, or a folder that is not a usable OTB folder.
        OSError: the output folder cannot be written.
        RuntimeError: a run failed (the first failure, naming its run).
    """
    folders = [os.path.abspath(os.fspath(f)) for f in folders]
    specs_of = _trackers(trackers)
    if isinstance(protocols, str):
        protocols = [protocols]
    protocols = [str(p) for p in protocols]
    seeds = [_seed(s) for s in seeds]
    if not seeds:
        raise ValueError("give at least one seed")
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"seeds must differ, got {seeds}")
    plans = [
        _native._otb_plan(folders, specs_of, protocols, particles=particles, seed=s) for s in seeds
    ]
    with _ClientOf(client) as c:
        tag = uuid.uuid4().hex[:8]
        futures = [
            c.submit(otb_run, spec, key=f"otb_run-{tag}-{i}-{k}", pure=False)
            for i, plan in enumerate(plans)
            for k, spec in enumerate(plan)
        ]
        results, errors = _gather(c, futures, _Progress("evaluate_otb", len(futures), progress))
    flat_specs = [spec for plan in plans for spec in plan]
    for spec, error in zip(flat_specs, errors):
        if error is not None:
            raise RuntimeError(f"OTB run {spec} failed: {type(error).__name__}: {error}") from error
    command = (
        f"contour_track.cluster.evaluate_otb({folders!r}, trackers={[t for _, t in specs_of]!r}, "
        f"protocols={protocols!r}, seeds={seeds!r}, particles={particles!r})"
    )
    rows = []
    start = 0
    for seed, plan in zip(seeds, plans):
        mine = results[start:start + len(plan)]
        start += len(plan)
        target = out if len(seeds) == 1 else os.path.join(os.fspath(out), f"seed-{seed}")
        tables = _native._otb_score(
            os.fspath(target), folders, specs_of, protocols, plan, mine,
            particles=particles, seed=seed, command=command,
        )
        for _, _, table in tables:
            rows.extend(_rows(table, seed))
    return rows
