"""Dask connections: a local cluster of N workers, or an existing scheduler reached within a timeout.

The one place that talks to dask.distributed (an optional dependency: ``pip install 'gyrodrift[dask]'``).
"""

from __future__ import annotations

import contextlib
import logging
import math
from collections.abc import Iterator
from typing import Any

from gyrodrift.errors import GyrodriftError, MissingExtraError, OptionError

__all__ = ["DEFAULT_CONNECT_TIMEOUT_S", "DaskMissingError", "SchedulerUnreachableError", "dask_client"]

DEFAULT_CONNECT_TIMEOUT_S = 10.0
"""How long [s] to wait for a scheduler to answer before giving up (CLI: ``--connect-timeout-s``)."""


class DaskMissingError(MissingExtraError):
    """dask.distributed is needed for --workers / --scheduler but is not installed."""


class SchedulerUnreachableError(GyrodriftError, ConnectionError):
    """No dask scheduler answered at the given address within the connect timeout."""


def _import_dask() -> tuple[Any, Any]:
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise DaskMissingError(
            "distributed processing (--workers / --scheduler) needs dask.distributed: pip install 'gyrodrift[dask]'"
        ) from None
    return Client, LocalCluster


@contextlib.contextmanager
def dask_client(
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    processes: bool = True,
    connect_timeout_s: float = DEFAULT_CONNECT_TIMEOUT_S,
) -> Iterator[Any]:
    """A `dask.distributed.Client`, closed (with its local cluster) when the block ends.

    Parameters
    ----------
    workers : int, optional
        Start a ``LocalCluster`` with this many workers, one thread each.
    scheduler : str, optional
        Address of a running scheduler (``tcp://host:8786``); exclusive with `workers`.
    processes : bool
        LocalCluster workers as processes (default) or threads.
    connect_timeout_s : float
        Seconds to wait for `scheduler` to answer (> 0, finite).

    Raises
    ------
    OptionError
        Neither or both of `workers` / `scheduler`, `workers` < 1, or a bad timeout.
    DaskMissingError
        dask.distributed is not installed.
    SchedulerUnreachableError
        Nothing answered at `scheduler` within `connect_timeout_s`.
    """
    if (workers is None) == (scheduler is None):
        raise OptionError("give exactly one of --workers or --scheduler")
    if workers is not None and workers < 1:
        raise OptionError(f"--workers must be >= 1, got {workers}")
    if not (isinstance(connect_timeout_s, int | float) and math.isfinite(connect_timeout_s) and connect_timeout_s > 0):
        raise OptionError(f"--connect-timeout-s must be a finite number of seconds > 0, got {connect_timeout_s!r}")
    Client, LocalCluster = _import_dask()
    cluster = None
    if scheduler is None:
        # dashboard_address=None alone still makes the scheduler serve its HTTP routes on port 8787 (distributed's
        # default_port), with a "Port 8787 is already in use" warning when another cluster has it: bind them to a
        # free loopback port instead, with no dashboard.
        cluster = LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=processes,
            dashboard_address=None,
            scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"},
        )
        client = Client(cluster)
    else:
        try:
            client = Client(scheduler, timeout=connect_timeout_s)
        except (OSError, TimeoutError, ValueError) as exc:
            reason = " ".join(str(exc).split()) or type(exc).__name__
            raise SchedulerUnreachableError(
                f"--scheduler {scheduler}: no dask scheduler answered within {connect_timeout_s:g} s "
                f"(--connect-timeout-s changes the wait): {reason}"
            ) from None
    try:
        yield client
    finally:
        _close_quietly(client, cluster)


_DASK_LOGGERS = ("distributed", "tornado")


def _silence_dask_logs() -> None:
    """Raise dask's and tornado's loggers to CRITICAL in this process (run on our own workers before shutdown)."""
    for name in _DASK_LOGGERS:
        logging.getLogger(name).setLevel(logging.CRITICAL)


def _close_quietly(client: Any, cluster: Any | None) -> None:
    """Close `client`, then our own `cluster`, without dask's shutdown noise.

    Under load a LocalCluster's workers may still send a heartbeat after the scheduler closed, and log it as an
    ERROR with a `CommClosedError` traceback ("Failed to communicate with scheduler during heartbeat"), or the
    nanny warns "Worker process still alive after 4.0 seconds, killing": neither is a failure of the command
    (its results are in). So our own workers are told to log nothing more (never the workers of a scheduler
    given with --scheduler: they outlive us), and this process's dask loggers are raised to CRITICAL while the
    client and cluster close, then restored.
    """
    loggers = [logging.getLogger(name) for name in _DASK_LOGGERS]
    levels = [lg.level for lg in loggers]  # before the workers are told: threads of a LocalCluster share them
    try:
        if cluster is not None:
            with contextlib.suppress(Exception):  # a worker already gone: nothing to silence there
                client.run(_silence_dask_logs, on_error="ignore")
        _silence_dask_logs()
        client.close()
        if cluster is not None:
            cluster.close()
    finally:
        for lg, level in zip(loggers, levels, strict=True):
            lg.setLevel(level)
