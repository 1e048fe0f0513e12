"""gyrodrift.fleet.executor: the one executor of campaigns and `features --workers` gives every task's value or
exception to the caller, serially, on a local process pool and on Dask alike."""

from __future__ import annotations

import operator

import pytest

from gyrodrift.fleet.executor import Interrupts, Workers, run_tasks

TASKS = [("div-0", (1.0, 2.0)), ("div-1", (1.0, 0.0)), ("div-2", (3.0, 1.0))]


def _outcomes(workers: Workers, **kw) -> tuple[dict[int, object], int]:
    got: dict[int, object] = {}

    def on_done(i, result) -> None:
        try:
            got[i] = result()
        except ZeroDivisionError as exc:
            got[i] = type(exc)

    unfinished = run_tasks(operator.truediv, TASKS, on_done, workers, **kw)
    return got, unfinished


@pytest.mark.parametrize(
    "workers", [Workers(), Workers(processes=2), Workers(dask_workers=1, dask_processes=False)], ids=str
)
def test_every_task_gives_its_value_or_its_exception(workers):
    if workers.dask_workers is not None:
        pytest.importorskip("dask.distributed")
    assert _outcomes(workers) == ({0: 0.5, 1: ZeroDivisionError, 2: 3.0}, 0)


def test_serial_tasks_start_in_order_and_a_callers_error_stops_them():
    started: list[int] = []

    def on_done(i, result) -> None:
        if i == 1:
            result()  # the task's ZeroDivisionError, raised by the caller

    with pytest.raises(ZeroDivisionError):
        run_tasks(operator.truediv, TASKS, on_done, Workers(), on_start=started.append)
    assert started == [0, 1]


def test_no_task_is_handed_out_once_stopping():
    interrupts = Interrupts()
    interrupts.count = 1  # as after a first Ctrl-C
    for workers in (Workers(), Workers(processes=2)):
        assert _outcomes(workers, interrupts=interrupts) == ({}, 0)
