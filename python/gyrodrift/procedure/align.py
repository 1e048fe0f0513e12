"""Initial alignment of a logged static run with the Rust `_core.Aligner` (docs/alignment-contract.md).

Coarse (analytic) then Kalman fine alignment over the first ``Timeline.align_h`` hours of the log, with the
turntable rotating. The result, in user units, seeds every navigation pass of the procedure: attitude and
velocity at the end of alignment, the x/y gyro biases and all accelerometer biases (compensated), and the
z-gyro bias estimate, which is only reported: a 4 h alignment leaves it weakly observable (its 1-sigma stays
near the prior), which is why the axial drift is identified from the 12 h navigation instead.

Signs: a bias estimate is subtracted from the measurement (corrected = measured - estimate).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from gyrodrift import _core
from gyrodrift.logs import ImuLog, LogError
from gyrodrift.procedure.results import Alignment
from gyrodrift.procedure.timeline import DEFAULT_TIMELINE, Timeline
from gyrodrift.progress import progress
from gyrodrift.units import ARCSEC, DEG_PER_H, HOUR, MICRO_G

__all__ = ["align_log", "GYRO_BIAS_Z_STATE"]

GYRO_BIAS_Z_STATE = 8
"""Column of the z-gyro bias in the aligner's covariance history (phi E N U, dv E N U, gyro bias x y z, ...);
`_core.Aligner.STATE_NAMES` (``"gyro_bias_z"``) decides when the core exposes it."""


def _vec(result: Mapping[str, Any], key: str, scale: float) -> tuple[float, float, float]:
    v = np.asarray(result[key], dtype=float).reshape(3) / scale
    return (float(v[0]), float(v[1]), float(v[2]))


def align_log(
    log: ImuLog,
    *,
    timeline: Timeline = DEFAULT_TIMELINE,
    aligner_options: Mapping[str, Any] | None = None,
    chunk_samples: int = 100_000,
    quiet: bool = True,
) -> Alignment:
    """Align a static run: coarse + Kalman fine alignment over the first ``timeline.align_h`` hours.

    Parameters
    ----------
    log : ImuLog
        An opened log (`gyrodrift.logs.open_log`) whose ``site`` is known.
    timeline : Timeline
        ``align_h`` [h] and ``coarse_s`` [s].
    aligner_options : mapping, optional
        Extra SI keywords of `_core.AlignerConfig` (noise and prior sigmas, see docs/alignment-contract.md).
    chunk_samples : int
        Samples read and passed to the core at a time.
    quiet : bool
        True hides the progress bar.

    Returns
    -------
    Alignment

    Raises
    ------
    LogError
        Bad rows in the first hours, a log shorter than the alignment, or no site known for the log.
    CoreError
        The core's aligner refuses the log (e.g. no static base: an estimate leaves its range); the message names
        the log, the quantity and the time (`ImuLog.core_errors`).
    """
    if log.site is None:
        raise LogError(f"{log.label}: the log carries no site; give its latitude (--lat0-deg / site=)")
    site = log.site
    align_s = timeline.align_h * HOUR
    log.require_duration(align_s, "the alignment")
    config: dict[str, Any] = {
        **site.core_position(),
        "rate_hz": log.rate_hz,
        "coarse_s": float(timeline.coarse_s),
        "fine_s": align_s - float(timeline.coarse_s),
    }
    config.update(dict(aligner_options or {}))
    n_align = log.samples_for(align_s)
    used = 0
    with log.core_errors():  # the core's refusals name the log
        aligner = _core.Aligner(_core.AlignerConfig(**config))
        with progress(n_align, f"align {log.name}", quiet) as bar:
            for chunk in log.chunks(chunk_samples):
                k = int(aligner.process(np.ascontiguousarray(chunk.dtheta_rad), np.ascontiguousarray(chunk.dv_m_s)))
                used += k
                bar.update(k)
                if aligner.done:
                    break
        if not aligner.done:
            raise LogError(f"{log.label}: the aligner did not finish after {used} samples")
        r = aligner.result()
    hist_std = np.asarray(r["hist_std"], dtype=float)
    hist_t = np.asarray(r["hist_t_s"], dtype=float)
    names = list(getattr(_core.Aligner, "STATE_NAMES", []))
    iz = names.index("gyro_bias_z") if "gyro_bias_z" in names else GYRO_BIAS_Z_STATE
    z_std = hist_std[:, iz] if hist_std.ndim == 2 and len(hist_std) else np.zeros(0)
    return Alignment(
        run=log.name,
        site=site,
        rate_hz=log.rate_hz,
        samples_used=used,
        t_s=float(r["t_s"]),
        pitch_deg=math.degrees(float(r["pitch_rad"])),
        roll_deg=math.degrees(float(r["roll_rad"])),
        yaw_deg=math.degrees(float(r["yaw_rad"])),
        coarse_pitch_deg=math.degrees(float(r["coarse_pitch_rad"])),
        coarse_roll_deg=math.degrees(float(r["coarse_roll_rad"])),
        coarse_yaw_deg=math.degrees(float(r["coarse_yaw_rad"])),
        vel_enu_m_s=_vec(r, "vel_enu_m_s", 1.0),
        gyro_bias_deg_h=_vec(r, "gyro_bias_rad_s", DEG_PER_H),
        gyro_bias_std_deg_h=_vec(r, "gyro_bias_std_rad_s", DEG_PER_H),
        accel_bias_ug=_vec(r, "accel_bias_m_s2", MICRO_G),
        accel_bias_std_ug=_vec(r, "accel_bias_std_m_s2", MICRO_G),
        att_std_arcsec=_vec(r, "att_std_rad", ARCSEC),
        hist_t_h=hist_t / HOUR,
        hist_gyro_z_std_deg_h=z_std / DEG_PER_H,
    )
