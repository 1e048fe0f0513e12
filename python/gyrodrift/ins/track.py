"""Reference tracks: the true (or GNSS) position of a moving base over time, interpolated to navigation times.

A `ReferenceTrack` holds time stamps [s, on the IMU log's time base], geodetic latitude/longitude [rad], height
[m] and, optionally, the ENU velocity [m/s]. `ReferenceTrack.at(t_s)` interpolates it: cubic Hermite in time
with the position rates from the velocity when it is known (dlat/dt = v_N / (R_M + h),
dlon/dt = v_E / ((R_N + h) cos lat)), linear otherwise. Sources:

* `ReferenceTrack.from_scenario(scenario)`: the route of a scenario with ``[trajectory]`` (the simulated truth),
  computed by the core simulator at 1 Hz without sensor errors or table (the position does not depend on them;
  the route's position is integrated by 4th-order Runge-Kutta split at segment boundaries, so 1 s steps are
  exact to far below a millimetre);
* `load_track(path)`: a GNSS (or any reference) CSV or Parquet file with columns ``t_s``, ``lat_deg``,
  ``lon_deg``, ``height_m`` and optionally ``vel_e_m_s``, ``vel_n_m_s``, ``vel_u_m_s``
  (`gyrodrift.ins.nav_columns.TRACK_REQUIRED`, `TRACK_VELOCITY`);
* `route_of(imu)`: the scenario of a simulated moving-base source (a Scenario, an ImuData, or an imu.parquet
  whose ``gyrodrift.scenario`` metadata has a ``[trajectory]``), or None.

`ReferenceTrack.require_cover(t0, t1)` refuses, in one line, a track that does not cover the navigated span.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gyrodrift import _core
from gyrodrift.earth import radii_of_curvature
from gyrodrift.errors import InputError
from gyrodrift.ins.nav_columns import TRACK_COLUMNS, TRACK_VELOCITY_COLUMNS
from gyrodrift.ins.scenario import Accel, Gyro, Rotation, Scenario, Temperature

__all__ = ["ReferenceTrack", "TrackError", "load_track", "route_of"]

TRUTH_RATE_HZ = 1.0
"""Rate of the truth track computed from a scenario's route [Hz]."""


class TrackError(InputError):
    """A reference track that cannot be used (bad file, or it does not cover the navigation)."""


@dataclass(frozen=True)
class ReferenceTrack:
    """A reference position track (see the module docs).

    Attributes
    ----------
    t_s : ndarray (n,)
        Strictly increasing time stamps [s] on the IMU log's time base (the end time of its samples).
    lat_rad, lon_rad, height_m : ndarray (n,)
        Geodetic position [rad, rad, m].
    vel_enu_m_s : ndarray (n, 3) or None
        ENU velocity [m/s], when known.
    label : str
        What messages call the track (a path, ``<route>``).
    """

    t_s: np.ndarray
    lat_rad: np.ndarray
    lon_rad: np.ndarray
    height_m: np.ndarray
    vel_enu_m_s: np.ndarray | None = None
    label: str = "<track>"

    @classmethod
    def from_scenario(cls, scenario: Scenario) -> ReferenceTrack:
        """The true route of a moving-base `scenario` (``[trajectory]``) at 1 Hz, including t = 0."""
        if scenario.trajectory is None:
            raise TrackError("the scenario has no [trajectory]: its truth is the static site")
        truth_run = dataclasses.replace(
            scenario,
            run=dataclasses.replace(scenario.run, rate_hz=TRUTH_RATE_HZ),
            rotation=Rotation(scheme="none"),
            gyro=Gyro(),
            accel=Accel(),
            temperature=Temperature(),
        )
        sim = _core.ImuSimulator(truth_run.to_core_config())
        parts: dict[str, list[np.ndarray]] = {k: [] for k in ("t_s", "lat_rad", "lon_rad", "height_m", "vel_enu_m_s")}
        while (chunk := sim.next_chunk(1 << 20)) is not None:
            for k, v in parts.items():
                v.append(np.asarray(chunk[k], dtype=float))
        s = scenario.site
        t = np.concatenate([[0.0], *parts["t_s"]])
        return cls(
            t_s=t,
            lat_rad=np.concatenate([[s.lat_rad], *parts["lat_rad"]]),
            lon_rad=np.concatenate([[s.lon_rad], *parts["lon_rad"]]),
            height_m=np.concatenate([[float(s.height_m)], *parts["height_m"]]),
            vel_enu_m_s=np.concatenate([np.zeros((1, 3)), *parts["vel_enu_m_s"]]),
            label="<route>",
        )

    def require_cover(self, t0: float, t1: float, what: str = "the navigation") -> None:
        """Refuse (`TrackError`, one line) a track that does not span [t0, t1] [s]."""
        eps = 1e-6
        if len(self.t_s) < 2 or self.t_s[0] > t0 + eps or self.t_s[-1] < t1 - eps:
            span = f"{self.t_s[0]:.6g} .. {self.t_s[-1]:.6g} s" if len(self.t_s) else "no samples"
            raise TrackError(
                f"{self.label}: the reference track covers {span}, {what} needs {t0:.6g} .. {t1:.6g} s "
                "(time stamps on the IMU log's time base)"
            )

    def at(self, t_s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(lat [rad], lon [rad], height [m]) at the times `t_s` [s] (within the track; see `require_cover`)."""
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        i = np.clip(np.searchsorted(self.t_s, t, side="right") - 1, 0, len(self.t_s) - 2)
        t0, t1 = self.t_s[i], self.t_s[i + 1]
        dt = t1 - t0
        x = (t - t0) / dt
        h = self.height_m[i] + x * (self.height_m[i + 1] - self.height_m[i])
        if self.vel_enu_m_s is None:
            lat = self.lat_rad[i] + x * (self.lat_rad[i + 1] - self.lat_rad[i])
            lon = self.lon_rad[i] + x * (self.lon_rad[i + 1] - self.lon_rad[i])
            return lat, lon, h
        rates = self._position_rates
        h00, h10 = 2 * x**3 - 3 * x**2 + 1, x**3 - 2 * x**2 + x
        h01, h11 = -2 * x**3 + 3 * x**2, x**3 - x**2
        out = []
        for p, r in ((self.lat_rad, rates[0]), (self.lon_rad, rates[1])):
            out.append(h00 * p[i] + h10 * dt * r[i] + h01 * p[i + 1] + h11 * dt * r[i + 1])
        return out[0], out[1], h

    @functools.cached_property
    def _position_rates(self) -> tuple[np.ndarray, np.ndarray]:
        """(dlat/dt, dlon/dt) [rad/s] at the track's time stamps, from the velocity (computed at the first `at`,
        kept for the next: a navigation asks for every chunk)."""
        assert self.vel_enu_m_s is not None
        rm, rn = radii_of_curvature(self.lat_rad)
        v = self.vel_enu_m_s
        return v[:, 1] / (rm + self.height_m), v[:, 0] / ((rn + self.height_m) * np.cos(self.lat_rad))


def load_track(path: str | os.PathLike[str]) -> ReferenceTrack:
    """Read a reference-track file (CSV or Parquet; columns `TRACK_COLUMNS`, optionally `TRACK_VELOCITY_COLUMNS`).

    Raises
    ------
    TrackError
        Naming the file, and the row and column of a bad value.
    """
    import pyarrow as pa
    import pyarrow.csv as pacsv
    import pyarrow.parquet as pq

    p = Path(path)
    label = str(path)
    try:
        if p.suffix.lower() in (".parquet", ".pq"):
            table = pq.read_table(p)
            first_row = 0  # rows counted from 0 in Parquet
        else:
            table = pacsv.read_csv(p)
            first_row = 2  # CSV: the header is line 1
    except (OSError, pa.ArrowInvalid) as exc:
        raise TrackError(f"{label}: cannot read the reference track: {str(exc).splitlines()[0]}") from None
    names = table.column_names
    missing = [c for c in TRACK_COLUMNS if c not in names]
    if missing:
        raise TrackError(f"{label}: missing column(s) {', '.join(missing)} (expected {', '.join(TRACK_COLUMNS)})")
    has_vel = [c in names for c in TRACK_VELOCITY_COLUMNS]
    if any(has_vel) and not all(has_vel):
        raise TrackError(f"{label}: give all of {', '.join(TRACK_VELOCITY_COLUMNS)} or none")
    cols: dict[str, np.ndarray] = {}
    for c in TRACK_COLUMNS + (TRACK_VELOCITY_COLUMNS if all(has_vel) else ()):
        try:
            a = table.column(c).to_numpy(zero_copy_only=False).astype(float)
        except (TypeError, ValueError, pa.ArrowInvalid):
            raise TrackError(f"{label}: column {c}: expected numbers") from None
        bad = np.flatnonzero(~np.isfinite(a))
        if len(bad):
            raise TrackError(f"{label}: row {int(bad[0]) + first_row}, column {c}: expected a finite number")
        cols[c] = a
    t = cols["t_s"]
    if len(t) < 2:
        raise TrackError(f"{label}: a reference track needs at least 2 rows, got {len(t)}")
    back = np.flatnonzero(np.diff(t) <= 0)
    if len(back):
        r = int(back[0]) + 1
        raise TrackError(f"{label}: row {r + first_row}, column t_s: time stamps must increase strictly")
    lat = cols["lat_deg"]
    far = np.flatnonzero(np.abs(lat) > 89.0)
    if len(far):
        raise TrackError(f"{label}: row {int(far[0]) + first_row}, column lat_deg: must be within +-89 deg")
    vel = np.column_stack([cols[c] for c in TRACK_VELOCITY_COLUMNS]) if all(has_vel) else None
    return ReferenceTrack(
        t_s=t,
        lat_rad=np.radians(lat),
        lon_rad=np.unwrap(np.radians(cols["lon_deg"])),
        height_m=cols["height_m"],
        vel_enu_m_s=vel,
        label=label,
    )


def route_of(imu: Any) -> Any:
    """The moving-base `Scenario` behind an IMU source (Scenario, ImuData, ImuLog or path), or None."""
    scenario = imu if isinstance(imu, Scenario) else getattr(imu, "scenario", None)
    if scenario is None:
        path = imu if isinstance(imu, (str, os.PathLike)) else getattr(imu, "path", None)
        if path is not None and Path(path).suffix.lower() in (".parquet", ".pq"):
            import pyarrow.parquet as pq

            try:
                meta = pq.read_schema(path).metadata or {}
            except OSError:
                return None
            raw = meta.get(b"gyrodrift.scenario")
            if raw is not None:
                try:
                    data = json.loads(raw)
                except ValueError:
                    return None
                if isinstance(data, dict) and "trajectory" in data:
                    scenario = Scenario.from_dict(data, source=f"{path} (gyrodrift.scenario metadata)")
    if isinstance(scenario, Scenario) and scenario.trajectory is not None:
        return scenario
    return None
