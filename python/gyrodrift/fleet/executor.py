"""One executor for fleets of independent tasks (a campaign's runs, the logs of `features --workers`): serially in
this process, on a local process pool, or on a Dask cluster (`gyrodrift.fleet.cluster`).

`run_tasks` hands out at most as many tasks as there are workers (a local pool's processes, the cluster's threads),
so a first Ctrl-C (`Interrupts`) leaves only the tasks in progress to finish, and gives each finished task to the
caller in this process, in the order of completion, as a `Result` (call it: the task's value, or its exception
raised). The caller decides what a task's exception means: a campaign counts it as a run lost to the
infrastructure (its own errors are rows), `features` raises the first bad log's. A local pool whose worker was
killed mid-task breaks: a new pool takes the tasks not yet finished (at most 3 times).
"""

from __future__ import annotations

import concurrent.futures
import multiprocessing
import os
import sys
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from gyrodrift.fleet.cluster import DEFAULT_CONNECT_TIMEOUT_S, dask_client

__all__ = ["Interrupts", "Result", "Workers", "run_tasks"]

Result = Callable[[], Any]
"""A finished task: calling it returns the task's value or raises the task's exception."""

Task = tuple[str, tuple[Any, ...]]
"""A task: its Dask key (unique on a shared scheduler) and the arguments of the function."""


@dataclass(frozen=True)
class Workers:
    """Where the tasks run: a local process pool of `processes`, a Dask ``LocalCluster`` of `dask_workers` (as
    processes or, ``dask_processes=False``, threads), or a running Dask `scheduler` reached within
    `connect_timeout_s` [s]; none of them: serially in this process. The callers allow at most one."""

    processes: int | None = None
    dask_workers: int | None = None
    scheduler: str | None = None
    dask_processes: bool = True
    connect_timeout_s: float = DEFAULT_CONNECT_TIMEOUT_S


class Interrupts:
    """SIGINT while tasks run (a campaign): the first stops new tasks from being handed out (the tasks in progress
    finish and are committed; a note on stderr says so), the second raises KeyboardInterrupt (abort at once).
    Installed only on the main thread (signal handlers live there); the previous handler comes back on exit."""

    def __init__(self) -> None:
        self.count = 0
        self.in_progress: Callable[[], int] = lambda: 0
        self.committing = False  # a result is being written: a second Ctrl-C waits for its rename
        self.abort_pending = False
        self._previous: Any = None
        self._installed = False

    @property
    def stopping(self) -> bool:
        return self.count > 0

    def _handle(self, signum, frame) -> None:
        self.count += 1
        if self.count > 1:
            if self.committing:
                self.abort_pending = True
                return
            raise KeyboardInterrupt
        n = self.in_progress()
        sys.stderr.write(
            f"\ncampaign: interrupted: no new runs are started; finishing and committing the {n} run(s) in progress "
            "(Ctrl-C again aborts them at once; rerunning the same command resumes)\n"
        )
        sys.stderr.flush()

    def abort_note(self, n: int) -> None:
        """Say on stderr that a second Ctrl-C left `n` tasks in progress uncommitted."""
        sys.stderr.write(
            f"\ncampaign: aborted; {n} run(s) in progress were not committed (rerunning the same command resumes)\n"
        )
        sys.stderr.flush()

    def __enter__(self) -> Interrupts:
        import signal
        import threading

        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._handle)
            self._installed = True
        return self

    def __exit__(self, *exc) -> None:
        import signal

        if self._installed:
            signal.signal(signal.SIGINT, self._previous)


@dataclass(frozen=True)
class _Finished:
    """A task run in this process, as a `Result`."""

    value: Any = None
    error: Exception | None = None

    def __call__(self) -> Any:
        if self.error is not None:
            raise self.error
        return self.value


def run_tasks(
    fn: Callable[..., Any],
    tasks: Sequence[Task],
    on_done: Callable[[int, Result], None],
    workers: Workers,
    *,
    interrupts: Interrupts | None = None,
    on_start: Callable[[int], None] | None = None,
) -> int:
    """Run ``fn(*args)`` for every ``(key, args)`` of `tasks` where `workers` says.

    ``on_done(i, result)`` is called in this process as task `i` (its place in `tasks`) finishes, ``on_start(i)``
    as it is handed out. An exception of `on_done` stops the execution (the tasks in progress are cancelled) and
    propagates. With `interrupts`, no new task is handed out once it is `Interrupts.stopping`. Returns the number
    of tasks never finished because the local pool broke too often (0 on Dask and serially).
    """
    if not tasks:
        return 0
    if workers.dask_workers is not None or workers.scheduler is not None:
        with dask_client(
            workers=workers.dask_workers,
            scheduler=workers.scheduler,
            processes=workers.dask_processes,
            connect_timeout_s=workers.connect_timeout_s,
        ) as client:
            _on_dask(client, fn, tasks, on_done, interrupts, on_start)
        return 0
    if workers.processes is not None:
        return _on_pool(fn, tasks, workers.processes, on_done, interrupts, on_start)
    for i, (_key, args) in enumerate(tasks):
        if interrupts is not None and interrupts.stopping:
            break
        if on_start is not None:
            on_start(i)
        try:
            finished = _Finished(value=fn(*args))
        except Exception as exc:  # the caller decides (calling the result raises it)
            finished = _Finished(error=exc)
        on_done(i, finished)
    return 0


def _worker_init() -> None:
    """Pool-worker initializer: ignore SIGINT (a Ctrl-C in the terminal reaches the whole process group; the
    client decides: finish the tasks in progress, or terminate the workers on a second Ctrl-C), and exit when the
    client that started the pool is gone (kill -9 of the client must not leave workers computing tasks nobody
    will commit). The client is not the worker's parent process when a fork server started it (`_pool_context`):
    the worker waits on multiprocessing's sentinel of the client (a pipe end the client holds, closed by the
    kernel when it exits, whatever the start method)."""
    import signal
    import threading

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    client = multiprocessing.parent_process()
    if client is None:  # not started by multiprocessing: nobody to watch
        return

    def watch() -> None:
        client.join()
        os._exit(1)

    threading.Thread(target=watch, daemon=True, name="gyrodrift-client-watch").start()


def _terminate_workers(pool: concurrent.futures.ProcessPoolExecutor) -> None:
    """Stop a pool's worker processes now (they ignore SIGINT). Python 3.14 has ``terminate_workers``; before it,
    the executor's process table."""
    terminate = getattr(pool, "terminate_workers", None)
    if terminate is not None:
        terminate()
        return
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        proc.terminate()


def _pool_round(pool, fn, tasks, queue: deque[int], size: int, on_done, interrupts, on_start, finished: set[int]):
    """Hand out the tasks of `queue` to `pool`, at most `size` at a time, giving each to `on_done` as it finishes
    (into `finished`); returns when all are done or a first Ctrl-C has let the tasks in progress finish.
    BrokenProcessPool when a worker died (the tasks of the batch that did finish are given first)."""
    running: dict[concurrent.futures.Future, int] = {}
    if interrupts is not None:
        interrupts.in_progress = running.__len__

    def refill() -> None:
        while queue and len(running) < size and not (interrupts is not None and interrupts.stopping):
            i = queue.popleft()
            running[pool.submit(fn, *tasks[i][1])] = i
            if on_start is not None:
                on_start(i)

    try:
        refill()
        while running:
            done, _ = concurrent.futures.wait(running, return_when=concurrent.futures.FIRST_COMPLETED)
            results, broken = [], None
            for fut in done:
                i = running.pop(fut)
                if isinstance(fut.exception(), concurrent.futures.process.BrokenProcessPool):
                    broken = fut.exception()
                else:
                    results.append((i, fut.result))
            if broken is None:
                refill()  # the idle workers start their next tasks while the client commits these
            for i, result in results:
                on_done(i, result)
                finished.add(i)
            if broken is not None:
                raise broken
    except KeyboardInterrupt:  # a second Ctrl-C
        if interrupts is not None:
            interrupts.abort_note(len(running))
        raise


POOL_PRELOAD = ("gyrodrift.fleet.science", "gyrodrift.fleet.features", "gyrodrift.procedure", "scipy.optimize")
"""The modules of the tasks a local pool runs, imported once by the client's fork server (`_pool_context`):
scipy.optimize (and scipy.linalg with it) too, which the procedure imports on first use (the features' curve fit,
the best drift law)."""


def _pool_context() -> multiprocessing.context.BaseContext:
    """The start method of pool workers: a fork server where the platform has one, else spawn.

    Both start a worker from a fresh, single-threaded interpreter (never a fork of the client, whose threads may
    hold locks). The fork server is that interpreter started once per client process, with `POOL_PRELOAD`
    imported (about 1 s of CPU): each worker is a fork of it and starts with the modules loaded, where a spawned
    worker imports them again. The working directory and ``sys.path`` are the client's at each pool's start (as
    with spawn); the environment variables are those of the client when its fork server started.
    """
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(list(POOL_PRELOAD))
    return ctx


def _on_pool(fn, tasks, size: int, on_done, interrupts, on_start) -> int:
    """The tasks on a local process pool of `size` processes (`_pool_context`). A worker killed mid-task breaks
    the pool: a new pool takes the tasks not yet finished (at most 3 times). Returns the tasks never finished."""
    remaining = list(range(len(tasks)))
    ctx = _pool_context()
    for _attempt in range(4):
        if not remaining or (interrupts is not None and interrupts.stopping):
            return 0
        finished: set[int] = set()
        pool = concurrent.futures.ProcessPoolExecutor(max_workers=size, mp_context=ctx, initializer=_worker_init)
        try:
            _pool_round(pool, fn, tasks, deque(remaining), size, on_done, interrupts, on_start, finished)
        except concurrent.futures.process.BrokenProcessPool:
            pass
        except BaseException:  # a second Ctrl-C or the client's own failure: the workers stop now
            _terminate_workers(pool)
            raise
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
        remaining = [i for i in remaining if i not in finished]
        if interrupts is not None and interrupts.stopping:
            return 0
    return len(remaining)


def _on_dask(client, fn, tasks, on_done, interrupts, on_start) -> None:
    """The tasks on a Dask cluster, as many handed out at a time as the cluster has threads."""
    from dask.distributed import as_completed

    queue = deque(range(len(tasks)))
    running: dict[Any, int] = {}
    if interrupts is not None:
        interrupts.in_progress = running.__len__
    flow = as_completed()

    def refill() -> None:
        window = max(1, sum(client.nthreads().values()))
        while queue and len(running) < window and not (interrupts is not None and interrupts.stopping):
            i = queue.popleft()
            key, args = tasks[i]
            fut = client.submit(fn, *args, pure=False, key=key)
            running[fut] = i
            flow.add(fut)
            if on_start is not None:
                on_start(i)

    refill()
    try:
        for fut in flow:
            i = running.pop(fut)
            refill()  # the idle worker starts its next task while the client commits this one
            on_done(i, fut.result)
    except BaseException as exc:
        if isinstance(exc, KeyboardInterrupt) and interrupts is not None:
            interrupts.abort_note(len(running))
        client.cancel(list(running))
        raise
