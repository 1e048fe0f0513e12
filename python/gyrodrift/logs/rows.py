"""The row checks of every IMU log: finite cells, strictly increasing time without gaps, possible magnitudes, a
temperature in deg C and a reference height within the core's limits (`RowChecker`).

Each check names the row and column of the first bad cell (`gyrodrift.logs.source.LogSource.where`).
"""

from __future__ import annotations

import math

import numpy as np

from gyrodrift import _core
from gyrodrift.logs.columns import REF_HEIGHT_COLUMN, TEMPERATURE, TIME, TRUTH_COLUMNS
from gyrodrift.logs.source import LogError, LogSource, RawBlock
from gyrodrift.runs.table import TEMPERATURE_LIMITS_C

__all__ = ["RowChecker", "MAX_RATE_DEG_S", "MAX_SPECIFIC_FORCE_G", "GAP_TOLERANCE", "HEIGHT_LIMITS_M", "G0"]

MAX_RATE_DEG_S = float(_core.MAX_ANGULAR_RATE_DEG_S)
"""Largest plausible angular rate [deg/s] on any axis (the core's limit: one limit for every reader and the core)."""
MAX_SPECIFIC_FORCE_G = float(_core.MAX_SPECIFIC_FORCE_G)
"""Largest plausible specific force [g = 9.80665 m/s^2] on any axis (the core's limit)."""
GAP_TOLERANCE = 0.01
"""Largest relative deviation of a time step from the nominal 1 / rate_hz."""
HEIGHT_LIMITS_M = (float(_core.MIN_HEIGHT_M), float(_core.MAX_HEIGHT_M))
"""The core's height limits [m]: a reference height must lie within them."""
G0 = float(_core.STANDARD_GRAVITY_M_S2)
"""Standard gravity [m/s^2]: 1 g."""


def _stack3(columns: tuple[np.ndarray, ...]) -> np.ndarray:
    """Three (n,) columns as one C-contiguous (n, 3) float64 array (what the core takes)."""
    out = np.empty((len(columns[0]), 3))
    for j, c in enumerate(columns):
        out[:, j] = c
    return out


class RowChecker:
    """Checks the blocks of one source one after the other, carrying the last time stamp across block boundaries."""

    def __init__(self, source: LogSource):
        self.source = source
        self.dt = 1.0 / source.rate.hz
        self.prev_t: float | None = None
        self.increments = source.layout.kind == "increments"
        scale = self.dt if self.increments else 1.0  # limits on the stored values
        self.limits = (MAX_RATE_DEG_S * math.pi / 180.0 * scale, MAX_SPECIFIC_FORCE_G * G0 * scale)

    def check(self, raw: RawBlock, first: int) -> RawBlock:
        """The block of `raw` (samples `first`...) as float64 increments, gyro and accel as two C-contiguous
        (n, 3) arrays, or `LogError` at its first problem.

        One pass of the core (`_core.check_rows`, the same comparisons as the checks below) decides that a block
        is clean (the usual case) and gives its increments; only a block with a problem goes through the
        detailed checks, in a fixed order (non-finite values, temperature range, time, magnitudes), which name
        the row and column.
        """
        t = np.asarray(raw.t, dtype=np.float64)
        gyro, acc = (raw.sensors[0], raw.sensors[1]) if len(raw.sensors) == 2 else (raw.sensors[:3], raw.sensors[3:])
        temp = None if raw.temp is None else np.asarray(raw.temp, dtype=np.float64)
        truth = None if raw.truth is None else tuple(np.asarray(c, dtype=np.float64) for c in raw.truth)
        href = None if raw.ref_height is None else np.asarray(raw.ref_height, dtype=np.float64)
        clean, gyro_inc, acc_inc = _core.check_rows(
            t,
            gyro,
            acc,
            temperature=temp,
            truth=truth or (),
            ref_height=href,
            previous_t=self.prev_t,
            step_s=self.dt,
            step_tolerance_s=GAP_TOLERANCE * self.dt,
            max_gyro=self.limits[0],
            max_accel=self.limits[1],
            temperature_c=TEMPERATURE_LIMITS_C,
            height_m=HEIGHT_LIMITS_M,
            scale=1.0 if self.increments else self.dt,
        )
        if not clean:
            stacked = tuple(np.asarray(a) if isinstance(a, np.ndarray) else _stack3(a) for a in (gyro, acc))
            self._explain(RawBlock(t, stacked, temp, truth, href), first)
            raise AssertionError("the core found a problem the detailed checks do not")  # pragma: no cover
        self.prev_t = float(t[-1]) if len(t) else self.prev_t
        # None: an (n, 3) array that needed no scaling, kept as it is
        sensors = tuple(
            np.ascontiguousarray(given, dtype=np.float64) if out is None else out
            for given, out in ((gyro, gyro_inc), (acc, acc_inc))
        )
        return RawBlock(t, sensors, temp, truth, href, raw.table_angle_deg)

    def _finite(self, a: np.ndarray, first: int, names: tuple[str, ...]) -> None:
        bad = ~np.isfinite(a)
        if bad.any():
            i, j = (int(k[0]) for k in np.nonzero(bad.reshape(len(a), -1)))
            v = float(a.reshape(len(a), -1)[i, j])
            where = self.source.where(first + i, names[j])
            if math.isnan(v):
                raise LogError(f"{where}: empty or NaN cell")
            raise LogError(f"{where}: expected a finite number, got {v!r}")

    def _in_range(
        self, a: np.ndarray, first: int, column: str, limits: tuple[float, float], what: tuple[str, str, str]
    ) -> None:
        """`LogError` at the first value of column `column` outside `limits` ([low, high], inclusive); `what` is
        ``(quantity, unit, hint)``."""
        low, high = limits
        bad = (a < low) | (a > high)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            quantity, unit, hint = what
            raise LogError(
                f"{self.source.where(first + i, column)}: {quantity} {float(a[i]):.6g} {unit} is outside "
                f"[{low:g}, {high:g}] {unit} ({hint})"
            )

    def _explain(self, raw: RawBlock, first: int) -> None:
        """Raise the `LogError` of the first problem of a block that failed the fast checks."""
        names = self.source.layout.columns
        t, (gyro, acc) = raw.t, raw.sensors
        self._finite(t, first, (TIME.name,))
        self._finite(gyro, first, names[:3])
        self._finite(acc, first, names[3:])
        if raw.temp is not None:
            self._finite(raw.temp, first, (TEMPERATURE.name,))
            self._in_range(
                raw.temp,
                first,
                TEMPERATURE.name,
                TEMPERATURE_LIMITS_C,
                ("temperature", "deg C", "a system temperature in deg C, not kelvin"),
            )
        if raw.truth is not None:
            for c, name in zip(raw.truth, TRUTH_COLUMNS, strict=True):
                self._finite(c, first, (name,))
        if raw.ref_height is not None:
            self._finite(raw.ref_height, first, (REF_HEIGHT_COLUMN,))
            self._in_range(
                raw.ref_height,
                first,
                REF_HEIGHT_COLUMN,
                HEIGHT_LIMITS_M,
                ("reference height", "m", "a height above the ellipsoid in metres"),
            )
        self._check_time(t, first)
        for j, (block, limit) in enumerate(((gyro, self.limits[0]), (acc, self.limits[1]))):
            over = np.abs(block) > limit
            if over.any():
                i, k = (int(x[0]) for x in np.nonzero(over))
                mag = abs(float(block[i, k])) / (self.dt if self.increments else 1.0)
                if j == 0:
                    msg = f"angular rate {mag * 180.0 / math.pi:.6g} deg/s exceeds {MAX_RATE_DEG_S:g} deg/s"
                else:
                    msg = f"specific force {mag / G0:.6g} g exceeds {MAX_SPECIFIC_FORCE_G:g} g"
                raise LogError(f"{self.source.where(first + i, names[3 * j + k])}: impossible magnitude: {msg}")

    def _check_time(self, t: np.ndarray, first: int) -> None:
        if not len(t):
            return
        full = t if self.prev_t is None else np.concatenate([[self.prev_t], t])
        dt = np.diff(full)
        off = 0 if self.prev_t is None else 1  # dt[k] ends at sample first + k + 1 - off
        if not len(dt):
            return
        back = dt <= 0.0
        if back.any():
            k = int(np.flatnonzero(back)[0])
            what = "duplicated time stamp" if dt[k] == 0.0 else "time goes backwards"
            raise LogError(
                f"{self.source.where(first + k + 1 - off, TIME.name)}: {what} ({float(full[k + 1])!r} s after "
                f"{float(full[k])!r} s); time must be strictly increasing"
            )
        gap = np.abs(dt - self.dt) > GAP_TOLERANCE * self.dt
        if gap.any():
            k = int(np.flatnonzero(gap)[0])
            raise LogError(
                f"{self.source.where(first + k + 1 - off, TIME.name)}: gap in time: step {dt[k]:.6g} s from "
                f"{float(full[k])!r} s, expected {self.dt:.6g} s (rate {self.source.rate.hz:g} Hz, tolerance "
                f"{GAP_TOLERANCE:.0%})"
            )
