"""Run a campaign into its folder: every run not yet committed, on local processes or Dask, each committed as it
finishes (`run_campaign`).

The campaign file and its runs are `gyrodrift.fleet.spec`, one run's work `gyrodrift.fleet.science`, the folder
`gyrodrift.fleet.store`, the execution `gyrodrift.fleet.executor`. A rerun skips the runs committed whole and runs
a damaged one again; SIGINT stops new runs (first) or aborts (second); see `run_campaign`.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path

from gyrodrift.errors import GyrodriftError, OptionError
from gyrodrift.fleet.cluster import DEFAULT_CONNECT_TIMEOUT_S
from gyrodrift.fleet.executor import Interrupts, Result, Workers, run_tasks
from gyrodrift.fleet.science import process_run
from gyrodrift.fleet.spec import Campaign, check_feasible
from gyrodrift.fleet.store import CampaignStore, run_schema

__all__ = ["CampaignFailedError", "CampaignSummary", "run_campaign"]


class CampaignFailedError(GyrodriftError, RuntimeError):
    """Every run of a campaign failed (the message says how many and the first error)."""


@dataclass
class CampaignSummary:
    """What a `run_campaign` call did: runs total, already done before, done now, failed now, lost to broken
    workers, seconds, and whether a Ctrl-C stopped it before every run was done."""

    total: int
    skipped: int
    done: int
    failed: int
    lost: int
    elapsed_s: float
    interrupted: bool = False
    failed_before: int = 0
    """Of the `skipped` runs, those committed with an error."""
    redone: dict[int, str] = field(default_factory=dict)
    """The damaged run files found on resume (index -> what was wrong), run again."""
    first_error: str | None = None
    """The error of the lowest-index run that failed now (None when none did)."""

    @property
    def succeeded(self) -> int:
        """Runs of the store that finished without an error (committed before or now)."""
        return self.skipped - self.failed_before + self.done - self.failed


def run_campaign(
    campaign: Campaign,
    out: str | os.PathLike[str],
    *,
    text: str | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    dask_workers: int | None = None,
    connect_timeout_s: float | None = None,
    quiet: bool = True,
    limit: int | None = None,
) -> CampaignSummary:
    """Process every run of `campaign` not yet committed in `out`, committing each as it finishes.

    Parameters
    ----------
    campaign : Campaign
    out : path-like
        The campaign folder (new, empty, or this campaign's: then finished runs are skipped).
    text : str, optional
        The campaign file's text, copied to ``out/campaign.toml`` (default: re-read from ``campaign.source``).
    workers : int, optional
        Local processes (default: the CPU count); exclusive with `scheduler`/`dask_workers`.
    scheduler : str, optional
        Address of a running dask scheduler (`gyrodrift.fleet.cluster.dask_client`, `connect_timeout_s`).
    dask_workers : int, optional
        A dask LocalCluster with this many workers instead (benchmarks, tests).
    limit : int, optional
        Process at most this many of the pending runs (lowest indices first).
    quiet : bool
        Hide the progress bar (runs done, failures, rate, time left).

    SIGINT (Ctrl-C), when called on the main thread: the first stops new runs (the runs in progress finish and
    are committed; the summary says ``interrupted``), the second aborts at once (KeyboardInterrupt; the runs in
    progress are not committed, a run being written is renamed into place first). A rerun resumes either way.
    """
    from gyrodrift.progress import progress

    if workers is not None and (scheduler is not None or dask_workers is not None):
        raise OptionError("give --workers or --scheduler, not both")
    if workers is not None and workers < 1:
        raise OptionError(f"--workers must be >= 1, got {workers}")
    check_feasible(campaign)
    if text is None:
        text = Path(campaign.source).read_text(encoding="utf-8")
    store = CampaignStore.create_or_open(out, campaign, text)
    schema = run_schema(campaign)
    found, broken = store.verify()  # a file numbered past the count is not this campaign's to redo
    good = {i: ok for i, ok in found.items() if i < campaign.count}
    damaged = {i: why for i, why in broken.items() if i < campaign.count}
    store.prepare_redo(damaged)
    todo = [i for i in range(campaign.count) if i not in good]
    if limit is not None:
        todo = todo[:limit]
    if scheduler is not None or dask_workers is not None:
        timeout_s = DEFAULT_CONNECT_TIMEOUT_S if connect_timeout_s is None else connect_timeout_s
        where = Workers(dask_workers=dask_workers, scheduler=scheduler, connect_timeout_s=timeout_s)
    else:
        where = Workers(processes=workers or os.cpu_count() or 1)
    prefix = f"campaign-{campaign.digest()[:8]}"
    t0 = time.perf_counter()
    counts = {"done": 0, "failed": 0, "lost": 0}
    first_error: list[tuple[int, str]] = []
    with Interrupts() as interrupts, progress(len(todo), f"campaign {campaign.name}", quiet, unit="run") as bar:

        def on_done(_position: int, result: Result) -> None:
            try:
                row = result()
            except Exception:  # not the run's error (process_run keeps those in the row): the infrastructure's
                counts["lost"] += 1
                return
            interrupts.committing = True
            try:
                store.write(row, schema)
            finally:
                interrupts.committing = False
            if interrupts.abort_pending:
                raise KeyboardInterrupt
            counts["done"] += 1
            if row.get("error") is not None:
                counts["failed"] += 1
                first_error[:] = [min(first_error + [(int(row["index"]), f"{row['run']}: {row['error']}")])]
            bar.set_postfix(failed=counts["failed"], refresh=False)
            bar.update(1)

        tasks = [(f"{prefix}-{i}", (campaign, i)) for i in todo]
        unfinished = run_tasks(process_run, tasks, on_done, where, interrupts=interrupts)
    return CampaignSummary(
        campaign.count,
        len(good),
        counts["done"],
        counts["failed"],
        unfinished + counts["lost"],
        time.perf_counter() - t0,
        interrupted=interrupts.stopping,
        failed_before=sum(not ok for ok in good.values()),
        redone=damaged,
        first_error=first_error[0][1] if first_error else None,
    )
