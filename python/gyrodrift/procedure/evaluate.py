"""Evaluation of a drift compensation: 72 h of navigation after alignment without and with it.

Both navigations run side by side in one read of the log, from the same alignment: "before" subtracts no
z drift, "after" subtracts the compensation from the z gyro (measured - estimate): a constant drift, or a drift law
evaluated sample by sample on the log's temperature (`gyrodrift.ins.compensation`). Errors are computed minus
true; position error in nmi (1852 m). On a moving base the truth is a reference track
(`gyrodrift.ins.track`): the simulated route of a moving-base imu.parquet by default, or a GNSS file.
"""

from __future__ import annotations

import math
import os
from typing import Any

from gyrodrift.drift_law import DriftLaw
from gyrodrift.errors import OptionError
from gyrodrift.ins.compensation import require_temperature_for
from gyrodrift.logs import ImuLog
from gyrodrift.procedure.align import align_log
from gyrodrift.procedure.passes import check_navigation_hours, navigate_after_alignment
from gyrodrift.procedure.results import Alignment, Evaluation
from gyrodrift.procedure.timeline import DEFAULT_TIMELINE, Timeline
from gyrodrift.units import HOUR

__all__ = ["evaluate_compensation"]


def evaluate_compensation(
    log: ImuLog,
    drift: float | DriftLaw,
    *,
    hours: float | None = None,
    timeline: Timeline = DEFAULT_TIMELINE,
    alignment: Alignment | None = None,
    decimation_s: float = 60.0,
    source: str = "given",
    chunk_samples: int = 100_000,
    quiet: bool = True,
    reference: Any = None,
) -> Evaluation:
    """Navigate `hours` (default ``timeline.truth_h``, 72 h) after alignment without and with the drift.

    Parameters
    ----------
    log : ImuLog
        Opened log with a known site, at least ``align_h + hours`` long.
    drift : float or DriftLaw
        Axial drift subtracted from the z gyro in the "after" navigation: a constant [deg/h] or a drift law (a law
        reading the temperature needs the log's ``temp_c``). The result's ``drift_law`` says which.
    hours, timeline, alignment, decimation_s, chunk_samples, quiet
        As in `find_true_drift`.
    source : str
        Recorded in the result (e.g. the model file the drift came from).
    reference : ReferenceTrack or path, optional
        The true track to compute the errors against (moving base): a `gyrodrift.ins.track.ReferenceTrack` or a
        GNSS CSV/Parquet file (``t_s, lat_deg, lon_deg, height_m``, optional ``vel_{e,n,u}_m_s``, times on the
        log's time base, interpolated). Default: the route of a simulated moving-base log, else the static site.

    Returns
    -------
    Evaluation
    """
    hours = check_navigation_hours(timeline.truth_h if hours is None else hours, decimation_s)
    if isinstance(drift, DriftLaw):
        law = drift
    elif not math.isfinite(drift):
        raise OptionError(f"--drift-deg-h: expected a finite drift in deg/h, got {drift!r}")
    else:
        law = DriftLaw.constant(float(drift))
    require_temperature_for(law, log)
    log.require_duration(
        timeline.log_hours_for(hours) * HOUR,
        f"the evaluation ({timeline.align_h:g} h alignment + {hours:g} h navigation)",
        align_h=timeline.align_h,
    )
    _require_stand(log, timeline)
    if alignment is None:
        alignment = align_log(log, timeline=timeline, chunk_samples=chunk_samples, quiet=quiet)
    ref = reference_for(log, reference)
    res = navigate_after_alignment(
        log,
        alignment,
        [0.0, law],
        hours,
        decimation_s=decimation_s,
        chunk_samples=chunk_samples,
        quiet=quiet,
        desc="evaluate",
        reference=ref,
    )
    return Evaluation(
        run=log.name,
        drift_deg_h=law.eps_ref_deg_h,
        drift_law=law,
        hours=hours,
        before=res.curves[0],
        after=res.curves[1],
        alignment=alignment,
        source=source,
        reference=ref,
        start_s=alignment.samples_used / alignment.rate_hz,
        vertical=res.vertical,
        vertical_reference=res.vertical_reference,
    )


def _require_stand(log: Any, timeline: Timeline) -> None:
    """Refuse a simulated moving-base log whose vehicle drives off before the static alignment ends."""
    from gyrodrift.ins.track import route_of

    scenario = route_of(log)
    if scenario is not None and scenario.trajectory.static_h < timeline.align_h:
        raise OptionError(
            f"{log.label}: the vehicle drives off at {scenario.trajectory.static_h:g} h, before the end of the "
            f"{timeline.align_h:g} h static alignment ([trajectory] static_h >= {timeline.align_h:g} needed)"
        )


def reference_for(log: Any, reference: Any = None) -> Any:
    """The reference track of an evaluation: `reference` (a ReferenceTrack, or a track file path), else the
    simulated route behind a moving-base `log`, else None (static base: the site)."""
    from gyrodrift.ins.track import ReferenceTrack, load_track, route_of

    if isinstance(reference, ReferenceTrack):
        return reference
    if isinstance(reference, (str, os.PathLike)):
        return load_track(reference)
    scenario = route_of(log)
    return None if scenario is None else ReferenceTrack.from_scenario(scenario)
