"""Evaluation of a drift compensation: 72 h of navigation after alignment without and with it.

Both navigations run side by side in one read of the log, from the same alignment: "before" subtracts no
z drift, "after" subtracts ``drift_deg_h`` from the z gyro (measured - estimate). Errors are computed minus
true; position error in nmi (1852 m).
"""

from __future__ import annotations

import math

from gyrodrift.errors import OptionError
from gyrodrift.logs import ImuLog
from gyrodrift.procedure.align import align_log
from gyrodrift.procedure.passes import check_navigation_hours, navigate_after_alignment
from gyrodrift.procedure.results import Alignment, Evaluation
from gyrodrift.procedure.timeline import DEFAULT_TIMELINE, Timeline
from gyrodrift.units import HOUR

__all__ = ["evaluate_compensation"]


def evaluate_compensation(
    log: ImuLog,
    drift_deg_h: float,
    *,
    hours: float | None = None,
    timeline: Timeline = DEFAULT_TIMELINE,
    alignment: Alignment | None = None,
    decimation_s: float = 60.0,
    source: str = "given",
    chunk_samples: int = 100_000,
    quiet: bool = True,
) -> Evaluation:
    """Navigate `hours` (default ``timeline.truth_h``, 72 h) after alignment without and with the drift.

    Parameters
    ----------
    log : ImuLog
        Opened log with a known site, at least ``align_h + hours`` long.
    drift_deg_h : float
        Axial drift [deg/h] subtracted from the z gyro in the "after" navigation.
    hours, timeline, alignment, decimation_s, chunk_samples, quiet
        As in `find_true_drift`.
    source : str
        Recorded in the result (e.g. the model file the drift came from).

    Returns
    -------
    Evaluation
    """
    hours = check_navigation_hours(timeline.truth_h if hours is None else hours, decimation_s)
    if not math.isfinite(drift_deg_h):
        raise OptionError(f"--drift-deg-h: expected a finite drift in deg/h, got {drift_deg_h!r}")
    log.require_duration(
        timeline.log_hours_for(hours) * HOUR,
        f"the evaluation ({timeline.align_h:g} h alignment + {hours:g} h navigation)",
        align_h=timeline.align_h,
    )
    if alignment is None:
        alignment = align_log(log, timeline=timeline, chunk_samples=chunk_samples, quiet=quiet)
    res = navigate_after_alignment(
        log,
        alignment,
        [0.0, float(drift_deg_h)],
        hours,
        decimation_s=decimation_s,
        chunk_samples=chunk_samples,
        quiet=quiet,
        desc="evaluate",
    )
    return Evaluation(
        run=log.name,
        drift_deg_h=float(drift_deg_h),
        hours=hours,
        before=res.curves[0],
        after=res.curves[1],
        alignment=alignment,
        source=source,
    )
