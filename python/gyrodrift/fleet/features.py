"""A folder of logs becomes a training table: features of many runs, serially or on a dask cluster (`gyrodrift
features`, ``--workers`` / ``--scheduler``).

Each log is one independent task (open, align, navigate, optionally find the true drift) of
`gyrodrift.fleet.executor`; the table lists the runs in the order the logs were given, whatever order the tasks
finish in, so the serial and the distributed results are identical. dask is an optional extra (``pip install
gyrodrift[dask]``), imported only when a cluster is asked for.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

from gyrodrift.fleet.cluster import DEFAULT_CONNECT_TIMEOUT_S
from gyrodrift.fleet.executor import Result, Workers, run_tasks
from gyrodrift.logs import LogError, open_log
from gyrodrift.logs.log_format import LogFormat, load_log_format
from gyrodrift.procedure.features import extract_features
from gyrodrift.procedure.noise import SensorNoise
from gyrodrift.procedure.results import RunFeatures
from gyrodrift.procedure.timeline import DEFAULT_TIMELINE, Timeline
from gyrodrift.progress import progress
from gyrodrift.site import Site

__all__ = ["features_table"]


def _features_task(
    path: str,
    site: Site | Mapping[str, float] | None,
    log_format: LogFormat | None,
    timeline: Timeline,
    with_truth: bool,
    criterion: str,
    lat0_deg: float | None,
    chunk_samples: int,
    smoother: bool = True,
    noise: SensorNoise | None = None,
) -> RunFeatures:
    log = open_log(path, site=site, format=log_format)
    return extract_features(
        log,
        timeline=timeline,
        with_truth=with_truth,
        criterion=criterion,
        lat0_deg=lat0_deg,
        smoother=smoother,
        noise=noise,
        chunk_samples=chunk_samples,
        quiet=True,
    )


def features_table(
    paths: Sequence[str | os.PathLike[str]],
    *,
    site: Site | Mapping[str, float] | None = None,
    log_format: str | os.PathLike[str] | LogFormat | None = None,
    lat0_deg: float | None = None,
    timeline: Timeline = DEFAULT_TIMELINE,
    with_truth: bool = False,
    criterion: str = "final",
    workers: int | None = None,
    scheduler: str | None = None,
    processes: bool = True,
    connect_timeout_s: float = DEFAULT_CONNECT_TIMEOUT_S,
    chunk_samples: int = 100_000,
    quiet: bool = True,
    smoother: bool = True,
    noise: SensorNoise | None = None,
) -> list[RunFeatures]:
    """Extract the features (and optionally the true drift) of every log.

    Parameters
    ----------
    paths : sequence of path-like
        IMU logs (Parquet or CSV). Run names are the file stems and must be unique.
    site : Site or mapping, optional
        Static site (see `open_log`): a mapping such as ``{"lat_deg": 28.222}`` fills or overrides only the
        keys it gives; logs that carry no site (CSV) need at least the latitude.
    log_format : path-like or LogFormat, optional
        The log format description of every log (`gyrodrift.logs.log_format`, CLI ``--format``); None: native columns.
    lat0_deg : float, optional
        True latitude for the table (default: each log's site latitude).
    timeline, with_truth, criterion, chunk_samples, smoother, noise
        As in `extract_features` (``smoother=False`` skips the 16 h smoother's read of each log: its columns
        are then empty).
    workers : int, optional
        Run on a ``dask.distributed.LocalCluster`` with this many workers (one thread each).
    scheduler : str, optional
        Address of a running dask scheduler (``tcp://host:8786``); exclusive with `workers`.
    processes : bool
        LocalCluster workers as processes (default) or threads (the core releases the GIL).
    connect_timeout_s : float
        Seconds to wait for `scheduler` to answer before `SchedulerUnreachableError`.
    quiet : bool
        True hides the progress bar and the line printed on stderr as each log finishes (its run, its place in
        the list and its wall time: a log takes minutes, the bar alone would sit still).

    Returns
    -------
    list of RunFeatures
        In the order of `paths`.

    Raises
    ------
    LogError
        The first bad log (in the order of `paths`), from whichever worker met it.
    DaskMissingError
        `workers` or `scheduler` without dask installed.
    SchedulerUnreachableError
        Nothing answered at `scheduler` within `connect_timeout_s`.
    """
    if workers is not None and scheduler is not None:
        raise ValueError("give workers or scheduler, not both")
    paths = [str(p) for p in paths]
    if not paths:
        raise ValueError("no logs given")
    fmt = None if log_format is None else load_log_format(log_format)
    logs = [open_log(p, site=site, format=fmt) for p in paths]  # header problems surface before any work starts
    for log in logs:
        if log.site is None:
            raise LogError(f"{log.label}: the log carries no site; give its latitude (--lat0-deg / site=)")
    names = [log.name for log in logs]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise LogError(f"run name(s) {', '.join(dup)} appear more than once (run = the log's file stem)")
    args = (site, fmt, timeline, with_truth, criterion, lat0_deg, chunk_samples, smoother, noise)
    tasks = [(f"features-{i}-{Path(p).name}", (p, *args)) for i, p in enumerate(paths)]
    serial = workers is None and scheduler is None
    where = Workers(
        dask_workers=workers, scheduler=scheduler, dask_processes=processes, connect_timeout_s=connect_timeout_s
    )
    start = time.monotonic()
    out: list[RunFeatures] = []
    finished: dict[int, Result] = {}
    with progress(len(paths), "features", quiet, unit="log") as bar:

        def on_done(i: int, result: Result) -> None:
            finished[i] = result
            while len(out) in finished:  # in the order of the logs: the first bad log's error is raised
                out.append(finished.pop(len(out))())
                bar.update(1)
                if not quiet:
                    bar.write(
                        f"features: {out[-1].run} done ({len(out)}/{len(paths)}, "
                        f"{time.monotonic() - start:.1f} s wall time so far)",
                        file=sys.stderr,
                    )

        show_log = (lambda i: bar.set_postfix_str(names[i])) if serial else None  # a log takes minutes
        run_tasks(_features_task, tasks, on_done, where, on_start=show_log)
    return out
