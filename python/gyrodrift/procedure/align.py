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
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from gyrodrift.logs import ImuLog, LogError, Site
from gyrodrift.procedure.timeline import DEFAULT_TIMELINE, Timeline
from gyrodrift.progress import progress
from gyrodrift.units import ARCSEC, DEG, DEG_PER_H, HOUR, MICRO_G

__all__ = ["Alignment", "align_log", "GYRO_BIAS_Z_STATE"]

GYRO_BIAS_Z_STATE = 8
"""Column of the z-gyro bias in the aligner's covariance history (phi E N U, dv E N U, gyro bias x y z, ...);
`_core.Aligner.STATE_NAMES` (``"gyro_bias_z"``) decides when the core exposes it."""


@dataclass(frozen=True)
class Alignment:
    """The outcome of the alignment, in user units.

    Attributes
    ----------
    run : str
        Name of the log.
    site : Site
        The known static site used [deg, deg, m].
    samples_used : int
        Samples consumed by the alignment; navigation starts with the next one.
    t_s : float
        End of the alignment [s] as the aligner counts it (samples_used / rate_hz).
    pitch_deg, roll_deg, yaw_deg : float
        Attitude at the end of alignment (yaw counter-clockwise about Up).
    coarse_pitch_deg, coarse_roll_deg, coarse_yaw_deg : float
        Attitude from the coarse alignment.
    vel_enu_m_s : tuple of 3 floats
        Velocity estimate at the end (ENU) [m/s].
    gyro_bias_deg_h, gyro_bias_std_deg_h : tuple of 3 floats
        Gyro bias estimates and their 1-sigma, body x y z [deg/h].
    accel_bias_ug, accel_bias_std_ug : tuple of 3 floats
        Accelerometer bias estimates and 1-sigma, body x y z [ug].
    att_std_arcsec : tuple of 3 floats
        Attitude error 1-sigma, E N U [arcsec].
    hist_t_h : ndarray
        Times of the covariance history [h from the start of the log].
    hist_gyro_z_std_deg_h : ndarray
        1-sigma of the z (axial) gyro bias over the alignment [deg/h].
    """

    run: str
    site: Site
    rate_hz: float
    samples_used: int
    t_s: float
    pitch_deg: float
    roll_deg: float
    yaw_deg: float
    coarse_pitch_deg: float
    coarse_roll_deg: float
    coarse_yaw_deg: float
    vel_enu_m_s: tuple[float, float, float]
    gyro_bias_deg_h: tuple[float, float, float]
    gyro_bias_std_deg_h: tuple[float, float, float]
    accel_bias_ug: tuple[float, float, float]
    accel_bias_std_ug: tuple[float, float, float]
    att_std_arcsec: tuple[float, float, float]
    hist_t_h: np.ndarray = field(repr=False)
    hist_gyro_z_std_deg_h: np.ndarray = field(repr=False)

    @property
    def z_drift_deg_h(self) -> float:
        """The alignment's own axial (z) drift estimate [deg/h] (reported, never applied)."""
        return self.gyro_bias_deg_h[2]

    @property
    def z_drift_std_deg_h(self) -> float:
        """Its 1-sigma at the end of alignment [deg/h]."""
        return self.gyro_bias_std_deg_h[2]

    def navigator_config(self) -> dict[str, Any]:
        """SI config of `_core.Navigator` starting at the end of alignment (static site, aligned state)."""
        return {
            "lat_rad": self.site.lat_deg * DEG,
            "lon_rad": self.site.lon_deg * DEG,
            "height_m": float(self.site.height_m),
            "vel_enu_m_s": [float(v) for v in self.vel_enu_m_s],
            "pitch_rad": self.pitch_deg * DEG,
            "roll_rad": self.roll_deg * DEG,
            "yaw_rad": self.yaw_deg * DEG,
            "rate_hz": float(self.rate_hz),
            "vertical": "fixed",
        }

    def gyro_compensation_rad_s(self, z_drift_deg_h: float) -> list[float]:
        """Gyro biases for `Navigator.set_gyro_bias`: estimated x, y and the given z drift [deg/h] (SI)."""
        return [self.gyro_bias_deg_h[0] * DEG_PER_H, self.gyro_bias_deg_h[1] * DEG_PER_H, z_drift_deg_h * DEG_PER_H]

    def accel_compensation_m_s2(self) -> list[float]:
        """All three accelerometer bias estimates for `Navigator.set_accel_bias` [m/s^2]."""
        return [b * MICRO_G for b in self.accel_bias_ug]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (user units; the history as lists)."""
        d = asdict(self)
        d["site"] = asdict(self.site)
        d["hist_t_h"] = [float(x) for x in self.hist_t_h]
        d["hist_gyro_z_std_deg_h"] = [float(x) for x in self.hist_gyro_z_std_deg_h]
        for k, v in list(d.items()):
            if isinstance(v, tuple):
                d[k] = [float(x) for x in v]
        d["format"] = "gyrodrift-alignment/1"
        return d


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
        Extra SI keys of `_core.Aligner` (noise and prior sigmas, see docs/alignment-contract.md).
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
    """
    from gyrodrift import _core

    if log.site is None:
        raise LogError(f"{log.label}: the log carries no site; give its latitude (--lat0-deg / site=)")
    site = log.site
    align_s = timeline.align_h * HOUR
    log.require_duration(align_s, "the alignment")
    config: dict[str, Any] = {
        "lat_rad": site.lat_deg * DEG,
        "lon_rad": site.lon_deg * DEG,
        "height_m": float(site.height_m),
        "rate_hz": log.rate_hz,
        "coarse_s": float(timeline.coarse_s),
        "fine_s": align_s - float(timeline.coarse_s),
    }
    config.update(dict(aligner_options or {}))
    aligner = _core.Aligner(config)
    n_align = log.samples_for(align_s)
    used = 0
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
