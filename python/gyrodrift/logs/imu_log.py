"""IMU logs: the one reader of IMU data in the package (Parquet, CSV, in-memory arrays, a simulated scenario).

A log is one row per IMU sample, body frame x right, y forward, z up (z = turntable = axial axis). Every
source goes through the same checks and yields the same `LogChunk`s:

* Parquet (``.parquet`` / ``.pq``): the simulator's own ``imu.parquet`` (docs/scenarios.md) or any file with
  the columns below, with or without gyrodrift metadata;
* CSV (``.csv``): UTF-8, comma separated, one header row (names stripped of surrounding spaces);
* a log in its own format (own column names, units, axes, delimiter, time stamps): Parquet or CSV with a log
  format description (`gyrodrift.logs.log_format`, ``open_log(path, format=...)``), converted chunk by chunk into the
  columns below before the same checks; messages then name the file's line and its own column;
* in memory: `ImuLog.from_arrays` (a mapping of the same column names to numpy arrays);
* a scenario simulated on the fly, chunk by chunk, nothing stored: `ImuLog.from_scenario`.

Columns (order free, extra columns ignored):

  ============================================  ======  ==============================================
  ``t_s``                                       s       end time of the sample, strictly increasing
  ``dtheta_x_rad``, ``dtheta_y_rad``,           rad     angle increments over the sample        } or
  ``dtheta_z_rad``                                                                                }
  ``dv_x_m_s``, ``dv_y_m_s``, ``dv_z_m_s``      m/s     velocity (specific-force) increments    }
  ``gyro_x_rad_s``, ``gyro_y_rad_s``,           rad/s   angular rates, mean over the sample     } or
  ``gyro_z_rad_s``                                                                                }
  ``accel_x_m_s2``, ``accel_y_m_s2``,           m/s^2   specific force, mean over the sample    }
  ``accel_z_m_s2``
  ``temp_c``                                    deg C   system temperature (required unless the caller
                                                        says otherwise: `navigate` does not need it)
  ``true_pitch_deg``, ``true_roll_deg``,        deg     optional: the true attitude at the end of the
  ``true_yaw_deg``                                      sample (simulated logs), for attitude errors
  ``ref_height_m``                              m       optional: a known height above the ellipsoid at
                                                        the end of the sample (barometric, map, GNSS),
                                                        the reference of `navigate`'s damped vertical
                                                        channel; finite, within the core's height limits
  ============================================  ======  ==============================================

  The header decides: all six increment columns -> ``kind = "increments"``; else all six rate columns ->
  ``kind = "rates"`` (converted to increments as rate / rate_hz, i.e. the rate is the mean over the
  nominal sample interval ending at ``t_s``). Columns must hold numbers (Parquet: integer or floating point
  types; a bool or text column is refused); a name given twice is refused.

Sample rate: the ``gyrodrift.rate_hz`` metadata of a Parquet file (a JSON number), otherwise 1 / median(dt)
over the first 1000 intervals, rounded to 9 significant digits; it must lie in [`MIN_RATE_HZ`, `MAX_RATE_HZ`].
Every chunk is checked while it streams (a log is never loaded whole; an 88 h log at 200 Hz is 63 million
rows), and the first problem raises `LogError` naming the file, row and column:

* time not strictly increasing (duplicated or going back), a gap (an interval off the nominal
  1 / rate_hz by more than 1 %), NaN or empty cells, infinite values, impossible magnitudes (|rate| >
  `MAX_RATE_DEG_S` deg/s, |specific force| > `MAX_SPECIFIC_FORCE_G` g on any axis), a temperature outside
  `gyrodrift.runs.table.TEMPERATURE_LIMITS_C` (the limits of the run tables: a kelvin value is refused), a missing
  column, a CSV row with the wrong number of cells, a byte that is not UTF-8, damaged Parquet data pages.

Only regular files are read: a device (``/dev/zero``), a FIFO or a folder is refused before it is opened.

Before its first chunk, every log is checked against a static base over its first `STATIC_CHECK_SPAN_S` seconds
(`ImuLog.check_static_base`; a simulated moving-base log's static part when shorter; a log or static part under
`MIN_STATIC_CHECK_SPAN_S` is not checked): the mean specific force magnitude is normal gravity at the site within
`SPECIFIC_FORCE_TOLERANCE_G`, it points along body up (within `MAX_UNDECLARED_TILT_DEG`, or the declared
attitude's tilt), the horizontal gyros de-rotated by the table angle see the Earth rate's horizontal component and,
with the table still, the axial gyro its vertical one (`EARTH_RATE_TOLERANCE_DEG_H` or a factor 2). A unit, scale,
sign or axis slip fails one of them: `ImplausibleLogError` names the check, the measured and expected values and
the columns (a log format's keys) to look at.

Row numbers: for CSV the line of the file (the header is row 1, the first sample row 2, as in
`gyrodrift.runs.table`); for the other sources the 1-based sample index.

The true static site (`gyrodrift.site.Site`) comes from the Parquet metadata ``gyrodrift.site`` (or the
scenario) when present; otherwise the caller gives it (`open_log(..., site=...)`). Simulated logs also carry
their true initial attitude (`LogTruth`, from the ``gyrodrift.scenario`` metadata).
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import stat
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from gyrodrift import _core
from gyrodrift.earth import OMEGA_IE_RAD_S, normal_gravity
from gyrodrift.errors import CoreError, InputError, OptionError
from gyrodrift.logs.log_format import LogFormat, load_log_format
from gyrodrift.runs.table import TEMPERATURE_LIMITS_C
from gyrodrift.site import Site
from gyrodrift.units import DEG_PER_H

__all__ = [
    "LogError",
    "ImplausibleLogError",
    "Site",
    "LogTruth",
    "LogChunk",
    "ImuLog",
    "open_log",
    "INCREMENT_COLUMNS",
    "RATE_COLUMNS",
    "TRUTH_COLUMNS",
    "REF_HEIGHT_COLUMN",
    "MAX_RATE_DEG_S",
    "MAX_SPECIFIC_FORCE_G",
    "MIN_RATE_HZ",
    "MAX_RATE_HZ",
    "GAP_TOLERANCE",
    "DEFAULT_CHUNK_SAMPLES",
    "STATIC_CHECK_SPAN_S",
    "MIN_STATIC_CHECK_SPAN_S",
    "SPECIFIC_FORCE_TOLERANCE_G",
    "EARTH_RATE_TOLERANCE_DEG_H",
    "MAX_UNDECLARED_TILT_DEG",
    "DECLARED_TILT_TOLERANCE_DEG",
    "TABLE_STILL_DEG",
]

INCREMENT_COLUMNS = ("dtheta_x_rad", "dtheta_y_rad", "dtheta_z_rad", "dv_x_m_s", "dv_y_m_s", "dv_z_m_s")
"""Increment columns: angle [rad] then velocity [m/s] increments over the sample, body x y z."""
RATE_COLUMNS = ("gyro_x_rad_s", "gyro_y_rad_s", "gyro_z_rad_s", "accel_x_m_s2", "accel_y_m_s2", "accel_z_m_s2")
"""Rate columns: angular rate [rad/s] then specific force [m/s^2], body x y z."""
TRUTH_COLUMNS = ("true_pitch_deg", "true_roll_deg", "true_yaw_deg")
"""Optional true attitude at the end of each sample [deg] (simulated logs)."""
REF_HEIGHT_COLUMN = "ref_height_m"
"""Optional reference height above the ellipsoid at the end of each sample [m] (barometric or known height)."""
MAX_RATE_DEG_S = float(_core.MAX_ANGULAR_RATE_DEG_S)
"""Largest plausible angular rate [deg/s] on any axis (the core's limit: one limit for every reader and the core)."""
MAX_SPECIFIC_FORCE_G = float(_core.MAX_SPECIFIC_FORCE_G)
"""Largest plausible specific force [g = 9.80665 m/s^2] on any axis (the core's limit)."""
MIN_RATE_HZ = float(_core.MIN_RATE_HZ)
"""Smallest accepted sample rate [Hz] (the core's limit)."""
MAX_RATE_HZ = float(_core.MAX_RATE_HZ)
"""Largest accepted sample rate [Hz] (the core's limit)."""
GAP_TOLERANCE = 0.01
"""Largest relative deviation of a time step from the nominal 1 / rate_hz."""
DEFAULT_CHUNK_SAMPLES = 100_000
"""Samples per chunk: 1000 s at 100 Hz, about 7 MB of float64 columns."""
STATIC_CHECK_SPAN_S = 300.0
"""Span at the start of every log whose means are checked against a static base [s] (`ImplausibleLogError`): the
default coarse alignment (`gyrodrift.procedure.Timeline.coarse_s`), which every procedure needs static; a
simulated moving-base log's static part (``[trajectory] static_h``) when that is shorter."""
MIN_STATIC_CHECK_SPAN_S = 60.0
"""A log (or a known static part) shorter than this [s] is not checked: too short to tell the Earth rate of a
noisy gyro (a 0.05 deg/sqrt(h) ARW averages to 0.4 deg/h over 60 s)."""
SPECIFIC_FORCE_TOLERANCE_G = 0.01
"""Largest accepted difference [g] between the mean specific force magnitude and normal gravity at the site:
10 mg is 100 times a navigation-grade accelerometer bias (<= 0.1 mg) and covers a tactical one, a site height
off by kilometres (0.3 mg/km) and any gravity anomaly (< 0.5 mg); a unit slip is off by a factor 9.8 (g
declared m/s^2), 1000 (mg, ug) or more."""
EARTH_RATE_TOLERANCE_DEG_H = 1.0
"""Additive tolerance [deg/h] of the gyro checks (a measured Earth-rate component is also accepted within a
factor 2 of its expected range): 1 deg/h is 100 times a navigation-grade RLG bias (<= 0.01 deg/h) and covers
the noise of a 60 s mean; a unit slip is off by a factor 57 (deg vs rad), 60, 1000 or 3600 (deg/s vs deg/h)."""
MAX_UNDECLARED_TILT_DEG = 30.0
"""Largest accepted angle [deg] between body up (the turntable axis) and the mean specific force, for a log that
does not declare its mounting attitude: a single-axis rotation INS stands with its table axis near the vertical;
an upside-down axis mapping gives 180 deg, a swapped up axis 90 deg."""
DECLARED_TILT_TOLERANCE_DEG = 5.0
"""Largest accepted difference [deg] between that angle and the one a log's declared attitude gives
(``gyrodrift.scenario`` metadata: acos(cos pitch cos roll))."""
TABLE_STILL_DEG = 10.0
"""The table counts as still over the checked span when its angle (the axial gyro integrated, minus the Earth
rate's vertical component) stays within this range [deg]; only then is the axial gyro's mean checked."""

_G0 = float(_core.STANDARD_GRAVITY_M_S2)
_SITE_LIMITS = {  # key: (low, high, option, unit), inclusive, the core's limits
    "lat_deg": (-float(_core.MAX_LAT_DEG), float(_core.MAX_LAT_DEG), "--lat0-deg", "deg"),
    "lon_deg": (-float(_core.MAX_LON_DEG), float(_core.MAX_LON_DEG), "--lon0-deg", "deg"),
    "height_m": (float(_core.MIN_HEIGHT_M), float(_core.MAX_HEIGHT_M), "--height-m", "m"),
}
_HEIGHT_LIMITS_M = (float(_core.MIN_HEIGHT_M), float(_core.MAX_HEIGHT_M))
_RATE_PROBE = 1000


class LogError(InputError):
    """An IMU log that cannot be used; the message starts with the file (and row and column when known)."""


class ImplausibleLogError(LogError):
    """A log whose first minutes are not what a static base must show (gravity, up, the Earth rate): a unit,
    scale, sign or axis slip; the message names the check, the measured and expected values and the columns (or
    the log format's keys) to look at."""


@dataclass(frozen=True)
class LogTruth:
    """The true attitude of a simulated run at t = 0 (table angle 0) [deg]: pitch, roll, yaw (counter-clockwise
    about Up)."""

    pitch_deg: float
    roll_deg: float
    yaw_deg: float


@dataclass(frozen=True)
class LogChunk:
    """Consecutive validated samples.

    Attributes
    ----------
    first_index : int
        0-based index of the first sample of the chunk in the log.
    t_s : ndarray (n,)
        End time of each sample [s], as recorded.
    dtheta_rad, dv_m_s : ndarray (n, 3)
        Angle [rad] and velocity [m/s] increments over each sample, body frame (rates already converted).
    temp_c : ndarray (n,) or None
        System temperature [deg C] (None when the log has none and the caller did not need it).
    truth : tuple of 3 ndarrays (n,) or None
        True pitch, roll, yaw at the end of each sample [deg] when the log carries them (`true_deg` stacks them).
    ref_height_m : ndarray (n,) or None
        Reference height above the ellipsoid at the end of each sample [m] (``ref_height_m``), when the log has it.
    table_angle_deg : ndarray (n,) or None
        Turntable angle at the end of each sample [deg], when the source carries it (a scenario simulated on the
        fly).
    """

    first_index: int
    t_s: np.ndarray
    dtheta_rad: np.ndarray
    dv_m_s: np.ndarray
    temp_c: np.ndarray | None = None
    truth: tuple[np.ndarray, ...] | None = None
    ref_height_m: np.ndarray | None = None
    table_angle_deg: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.t_s)

    @property
    def true_deg(self) -> np.ndarray | None:
        """The true attitude as one (n, 3) array (pitch, roll, yaw) [deg], or None."""
        return None if self.truth is None else np.column_stack(self.truth)

    def slice(self, a: int, b: int) -> LogChunk:
        """Samples a..b-1 of the chunk (views)."""
        return LogChunk(
            self.first_index + a,
            self.t_s[a:b],
            self.dtheta_rad[a:b],
            self.dv_m_s[a:b],
            None if self.temp_c is None else self.temp_c[a:b],
            None if self.truth is None else tuple(c[a:b] for c in self.truth),
            None if self.ref_height_m is None else self.ref_height_m[a:b],
            None if self.table_angle_deg is None else self.table_angle_deg[a:b],
        )


@dataclass(frozen=True)
class _Raw:
    """One block of a source before the checks: the columns as numpy arrays (names as in the log)."""

    t: np.ndarray
    sensors: tuple[np.ndarray, ...]  # six (n,) arrays, or (gyro (n, 3), accel (n, 3)) from the core
    temp: np.ndarray | None
    truth: tuple[np.ndarray, ...] | None
    ref_height: np.ndarray | None = None
    table_angle_deg: np.ndarray | None = None


class ImuLog:
    """An opened IMU log: source, kind, sample rate, size, site and truth; `chunks` streams validated samples.

    Use `open_log`, `ImuLog.from_arrays` or `ImuLog.from_scenario` to create one. A file log holds only the
    file name and a few numbers, so it pickles cheaply (dask workers reopen the file themselves).

    Attributes
    ----------
    path : pathlib.Path or None
        The file (None for in-memory and simulated sources).
    label : str
        What messages call the source (the path, ``<memory>``, ``<scenario>``).
    name : str
        The run name: the file's stem, or its folder's name for a file called ``imu.parquet``.
    format : {"parquet", "csv", "memory", "scenario"}
    kind : {"increments", "rates"}
    rate_hz : float
        Sample rate [Hz].
    rate_source : {"metadata", "time stamps", "scenario", "given"}
    n_samples : int
        Number of samples (CSV: estimated from the first and last time stamps).
    site : Site or None
        The true static site when the source says it or the caller gave it.
    truth : LogTruth or None
        The true initial attitude (simulated logs).
    has_temperature, has_truth_columns, has_reference_height : bool
        Whether chunks carry ``temp_c``, ``truth`` and ``ref_height_m``.
    """

    def __init__(
        self,
        *,
        path: Path | None,
        label: str,
        fmt: str,
        kind: str,
        columns: tuple[str, ...],
        rate_hz: float,
        n_samples: int,
        site: Site | None,
        rate_source: str,
        truth: LogTruth | None = None,
        has_temperature: bool = True,
        has_truth_columns: bool = False,
        has_reference_height: bool = False,
        name: str | None = None,
        raw_names: Mapping[str, str] | None = None,
        blocks: Callable[[int], Iterator[_Raw]] | None = None,
        log_format: LogFormat | None = None,
        t0_ns: int | None = None,
        scenario: Any = None,
        static_s: float | None = None,
    ):
        self.path = path
        # The known length of the static part at the start [s] (a simulated moving-base log's static_h), or None:
        # the static-base check then reads `STATIC_CHECK_SPAN_S`. `_static_checked` once that check has passed.
        self.static_s = static_s
        self._static_checked = False
        self.scenario = scenario  # the `gyrodrift.ins.Scenario` of a log simulated on the fly (its route), else None
        self.log_format = log_format
        self._t0_ns = t0_ns
        self.label = label
        self.format = fmt
        self.kind = kind
        self._columns = columns
        self.rate_hz = float(rate_hz)
        self.n_samples = int(n_samples)
        self.site = site
        self.rate_source = rate_source
        self.truth = truth
        self.has_temperature = has_temperature
        self.has_truth_columns = has_truth_columns
        self.has_reference_height = has_reference_height
        self._raw_names = dict(raw_names or {})
        self._blocks = blocks
        if name is None:
            stem = path.name if path is not None else label
            for suffix in (".parquet", ".pq", ".csv"):
                if stem.lower().endswith(suffix):
                    stem = stem[: -len(suffix)]
            if path is not None and stem == "imu" and path.parent.name:
                stem = path.parent.name
            name = stem
        self.name = name

    def __repr__(self) -> str:
        return (
            f"ImuLog({self.label!r}, format={self.format!r}, kind={self.kind!r}, rate_hz={self.rate_hz:g}, "
            f"n_samples={self.n_samples}, site={self.site})"
        )

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        if self.format in ("parquet", "csv"):
            state["_blocks"] = None  # rebuilt from the path
        return state

    # ------------------------------------------------------------------------------------------
    # Other sources
    # ------------------------------------------------------------------------------------------
    @classmethod
    def from_arrays(
        cls,
        columns: Mapping[str, Any],
        *,
        rate_hz: float | None = None,
        site: Site | Mapping[str, float] | None = None,
        source_site: Site | None = None,
        truth: LogTruth | None = None,
        label: str = "<memory>",
        require_temperature: bool = True,
        static_s: float | None = None,
    ) -> ImuLog:
        """A log over in-memory columns (the names of the module docstring, 1-D arrays of one length).

        The arrays are not copied; chunks are checked exactly as a file's. `rate_hz` defaults to the
        time stamps' (1 / median dt of the first 1000 intervals). `source_site` is the site the data come
        with (as a file's metadata), `site` replaces or completes it as in `open_log`; `truth` the true
        initial attitude; `static_s` the length of the static part at the start [s] when the data say it (a
        simulated moving base), for `check_static_base`.
        """
        names = list(columns)
        kind, cols = _kind_from_header(names, label, file=False)
        if require_temperature and "temp_c" not in names:
            raise LogError(f"{label}, row 1: missing column temp_c (system temperature, deg C; the features need it)")
        arrays: dict[str, np.ndarray] = {}
        n = None
        for c in ["t_s", *cols, "temp_c", *TRUTH_COLUMNS, REF_HEIGHT_COLUMN]:
            if c not in columns:
                continue
            a = np.asarray(columns[c])
            if a.ndim != 1 or a.dtype.kind not in "iuf":
                raise LogError(f"{label}, column {c}: expected a 1-D array of numbers, got {a.dtype} {a.shape}")
            if n is not None and len(a) != n:
                raise LogError(f"{label}, column {c}: {len(a)} values, expected {n} like t_s")
            n = len(a)
            arrays[c] = a
        if n is None or n < 2:
            raise LogError(f"{label}: {n or 0} sample(s); a log needs many")
        if rate_hz is None:
            rate, rate_source = (
                _rate_from_times(np.asarray(arrays["t_s"][: _RATE_PROBE + 1], float), label),
                "time stamps",
            )
        else:
            rate, rate_source = _check_rate(rate_hz, label), "given"
        has_temp = "temp_c" in arrays
        has_truth = all(c in arrays for c in TRUTH_COLUMNS)
        has_href = REF_HEIGHT_COLUMN in arrays

        def blocks(chunk_samples: int) -> Iterator[_Raw]:
            for a in range(0, n, chunk_samples):
                b = min(n, a + chunk_samples)
                yield _Raw(
                    arrays["t_s"][a:b],
                    tuple(arrays[c][a:b] for c in cols),
                    arrays["temp_c"][a:b] if has_temp else None,
                    tuple(arrays[c][a:b] for c in TRUTH_COLUMNS) if has_truth else None,
                    arrays[REF_HEIGHT_COLUMN][a:b] if has_href else None,
                )

        return cls(
            path=None,
            label=label,
            fmt="memory",
            kind=kind,
            columns=cols,
            rate_hz=rate,
            n_samples=n,
            site=_merge_site(site, source_site, label),
            rate_source=rate_source,
            truth=truth,
            has_temperature=has_temp,
            has_truth_columns=has_truth,
            has_reference_height=has_href,
            blocks=blocks,
            static_s=static_s,
        )

    @classmethod
    def from_scenario(cls, scenario: Any, *, site: Site | Mapping[str, float] | None = None) -> ImuLog:
        """A log simulated on the fly from a `gyrodrift.ins.Scenario`, chunk by chunk (nothing stored).

        Site, true initial attitude and true attitude columns come from the scenario.
        """
        from gyrodrift.ins.simulate import iter_core_chunks

        s = scenario
        label = "<scenario>"

        def blocks(chunk_samples: int) -> Iterator[_Raw]:
            for c in iter_core_chunks(s, chunk_samples):
                truth = tuple(np.rad2deg(np.asarray(c[k], dtype=float)) for k in ("pitch_rad", "roll_rad", "yaw_rad"))
                yield _Raw(
                    np.asarray(c["t_s"], dtype=float),
                    (np.asarray(c["dtheta_rad"], dtype=float), np.asarray(c["dv_m_s"], dtype=float)),
                    np.asarray(c["temp_c"], dtype=float),
                    truth,
                    table_angle_deg=np.rad2deg(np.asarray(c["table_angle_rad"], dtype=float)),
                )

        return cls(
            path=None,
            label=label,
            fmt="scenario",
            kind="increments",
            columns=INCREMENT_COLUMNS,
            rate_hz=_check_rate(s.run.rate_hz, label),
            n_samples=s.n_samples,
            site=_merge_site(site, Site(s.site.lat_deg, s.site.lon_deg, s.site.height_m), label),
            rate_source="scenario",
            truth=LogTruth(s.attitude.pitch_deg, s.attitude.roll_deg, s.attitude.yaw_deg),
            has_temperature=True,
            has_truth_columns=True,
            name="scenario",
            blocks=blocks,
            scenario=s,
            static_s=None if s.trajectory is None else s.trajectory.static_h * 3600.0,
        )

    # ------------------------------------------------------------------------------------------
    # Sizes
    # ------------------------------------------------------------------------------------------
    @property
    def duration_s(self) -> float:
        """Length of the log [s] (n_samples / rate_hz)."""
        return self.n_samples / self.rate_hz

    def samples_for(self, seconds: float) -> int:
        """Number of samples spanning `seconds` [s] at the log's rate (rounded); `OptionError` if not finite."""
        x = float(seconds) * self.rate_hz
        if not math.isfinite(x):
            raise OptionError(f"{self.label}: a duration of {seconds!r} s is not a finite number of samples")
        return int(round(x))

    def require_duration(self, seconds: float, what: str, *, align_h: float | None = None) -> None:
        """Raise `LogError` if the log is shorter than `seconds` [s] (what: why that much is needed).

        The message says the fix: a longer log (the scenario key and the ``simulate`` option that give one) and,
        when `align_h` [h] (the alignment before a navigation whose length ``--hours`` sets) is given, the
        navigation hours the log does hold.
        """
        if not float(seconds) * self.rate_hz <= self.n_samples + 0.5:
            need_h = math.ceil(seconds / 3600.0 - 1e-9)
            fix = f"simulate >= {need_h} h (duration_h = {need_h} in the scenario, or simulate --duration-h {need_h})"
            fix += " or record a longer log"
            if align_h is not None and (hold_h := math.floor(self.duration_s / 3600.0 - align_h + 1e-9)) >= 1:
                fix += f", or navigate less (--hours {hold_h})"
            raise LogError(
                f"{self.label}: the log lasts {self.duration_s / 3600.0:.3f} h; {what} takes at least "
                f"{seconds / 3600.0:g} h: {fix}"
            )

    def require_temperature(self, what: str) -> None:
        """Raise `LogError` if the log has no ``temp_c`` column (what: who needs it)."""
        if not self.has_temperature:
            raise LogError(f"{self.label}, row 1: missing column temp_c (system temperature, deg C; {what} needs it)")

    @contextlib.contextmanager
    def core_errors(self, first: int = 0) -> Iterator[None]:
        """Name this log in a `CoreError` the Rust core raises inside the block (its aligner, smoother or
        navigators refusing this log's samples or diverging on them), so that the one-line error says which file.

        The core's message is kept (the quantity, and the time ``t`` [s] counted from the first sample it was
        given when it says one); `first` is that sample's 0-based index in the log, named as a row when it is not
        the log's first. The class (the core's kind) and its attributes (``key``, ``t_s``, ...) are kept too. An
        error that already names the log passes unchanged.
        """
        try:
            yield
        except CoreError as exc:
            text = str(exc)
            if text.startswith(f"{self.label}: "):
                raise
            since = "" if first == 0 else f" (t counted from {_where(self, first).removeprefix(self.label + ', ')})"
            err = type(exc)(f"{self.label}: {text}{since}")
            err.__dict__.update(exc.__dict__)  # the kind's attributes (key, index, t_s, ...)
            raise err from exc

    # ------------------------------------------------------------------------------------------
    # Streaming
    # ------------------------------------------------------------------------------------------
    def chunks(self, chunk_samples: int = DEFAULT_CHUNK_SAMPLES, stop: int | None = None) -> Iterator[LogChunk]:
        """Yield validated chunks of at most `chunk_samples` samples from the start of the log.

        Parameters
        ----------
        chunk_samples : int
            Rows per chunk (Parquet batches / CSV blocks are re-cut to this size).
        stop : int, optional
            Stop after this many samples; `LogError` if the log ends before.

        Raises
        ------
        LogError
            At the first bad row (see the module docstring), or when the log ends before `stop`.
        """
        if not (isinstance(chunk_samples, int) and chunk_samples >= 1):
            raise OptionError(f"chunk_samples must be a positive integer, got {chunk_samples!r}")
        if not self._static_checked:
            self.check_static_base()
        validator = _Validator(self)
        done = 0
        for raw in self._source_blocks(chunk_samples):
            n = len(raw.t)
            if stop is not None and done + n > stop:
                raw = _cut(raw, stop - done)
                n = stop - done
            chunk = validator.check(raw, done)
            done += n
            yield chunk
            if stop is not None and done >= stop:
                return
        if stop is not None and done < stop:
            raise LogError(
                f"{self.label}: the log ends after {done} samples ({done / self.rate_hz / 3600.0:.3f} h); "
                f"{stop} samples ({stop / self.rate_hz / 3600.0:.3f} h) are needed"
            )

    def check_static_base(self) -> None:
        """Check that the start of the log is what a static base must show; `ImplausibleLogError` otherwise.

        Reads (and validates) the first `STATIC_CHECK_SPAN_S` seconds (the static part, when the log says a
        shorter one), chunk by chunk, and compares their means with the site (docs/procedure.md, "A log is
        physically plausible"): the specific force magnitude with normal gravity, its direction with body up,
        the horizontal gyros (de-rotated by the table angle the axial gyro gives) with the Earth rate's horizontal
        component and, when the table stands still, the axial gyro with its vertical component. `chunks` calls it
        before its first chunk, so every command checks every log before computing anything from it; a log (or
        static part) shorter than `MIN_STATIC_CHECK_SPAN_S` is not checked. Passing is remembered.
        """
        span_s = STATIC_CHECK_SPAN_S if self.static_s is None else min(STATIC_CHECK_SPAN_S, float(self.static_s))
        n = min(self.samples_for(span_s), self.n_samples)
        if n / self.rate_hz < MIN_STATIC_CHECK_SPAN_S:
            self._static_checked = True
            return
        validator = _Validator(self)
        means = _StaticMeans(self)
        done = 0
        blocks = self._source_blocks(min(n, DEFAULT_CHUNK_SAMPLES))
        try:
            for raw in blocks:
                k = len(raw.t)
                if done + k > n:
                    raw = _cut(raw, n - done)
                    k = n - done
                try:
                    chunk = validator.check(raw, done)
                except LogError:  # a bad row: the stream itself names it when it gets there, as without this check
                    return
                means.add(chunk)
                done += k
                if done >= n:
                    break
        finally:
            close = getattr(blocks, "close", None)
            if close is not None:
                close()
        if done / self.rate_hz >= MIN_STATIC_CHECK_SPAN_S:
            means.verdict()
        self._static_checked = True

    def _source_blocks(self, chunk_samples: int) -> Iterator[_Raw]:
        if self._blocks is not None:
            return self._blocks(chunk_samples)
        if self.format == "parquet":
            return self._parquet_blocks(chunk_samples)
        return self._csv_blocks(chunk_samples)

    def _wanted(self) -> list[str]:
        """The file's columns to read (their names in the file)."""
        if self.log_format is not None:
            return [c.name for c in self.log_format.columns]
        cols = ["t_s", *self._columns]
        if self.has_temperature:
            cols.append("temp_c")
        if self.has_truth_columns:
            cols.extend(TRUTH_COLUMNS)
        if self.has_reference_height:
            cols.append(REF_HEIGHT_COLUMN)
        return cols

    def _from_table(self, table: pa.Table | pa.RecordBatch, first: int) -> _Raw:
        if self.log_format is not None:
            return self._from_formatted_table(table, first)
        names = self._wanted()
        arrays = {}
        for name in names:
            col = table.column(self._raw_names.get(name, name))
            if col.null_count:
                i = int(np.flatnonzero(np.asarray(col.is_null().to_numpy(zero_copy_only=False)))[0])
                raise LogError(f"{_where(self, first + i, name)}: empty or NaN cell")
            arrays[name] = np.asarray(col.to_numpy(zero_copy_only=False), dtype=np.float64)
        return _Raw(
            arrays["t_s"],
            tuple(arrays[c] for c in self._columns),
            arrays.get("temp_c"),
            tuple(arrays[c] for c in TRUTH_COLUMNS) if self.has_truth_columns else None,
            arrays.get(REF_HEIGHT_COLUMN),
        )

    def _from_formatted_table(self, table: pa.Table | pa.RecordBatch, first: int) -> _Raw:
        """The file's columns converted by the log format: time [s], body-frame sensors in SI with the axis
        mapping and signs applied, temperature [deg C], truth [deg]."""
        fmt = self.log_format
        assert fmt is not None
        values: dict[str, np.ndarray] = {}
        for spec in fmt.columns:
            col = table.column(self._raw_names.get(spec.name, spec.name))
            if col.null_count:
                i = int(np.flatnonzero(np.asarray(col.is_null().to_numpy(zero_copy_only=False)))[0])
                raise LogError(f"{_where(self, first + i, spec.quantity)}: empty or NaN cell")
            if spec.is_iso_time:
                ns = _iso_ns(col, lambda i: _where(self, first + i, "time"))
                values["time"] = (ns - (self._t0_ns or 0)).astype(np.float64) * 1e-9
            else:
                values[spec.quantity] = spec.convert(col.to_numpy(zero_copy_only=False))
        sensors = []
        for sensor in ("gyro", "accel"):
            for j in range(3):
                spec, sign = fmt.body_source(sensor, j)
                v = values[spec.quantity]
                sensors.append(-v if sign < 0 else v)
        return _Raw(
            values["time"],
            tuple(sensors),
            values.get("temperature"),
            tuple(values[q] for q in ("true_pitch", "true_roll", "true_yaw")) if fmt.has_truth else None,
            values.get("ref_height"),
        )

    def _parquet_blocks(self, chunk_samples: int) -> Iterator[_Raw]:
        import pyarrow.parquet as pq

        _require_regular(self.path, self.label)
        try:
            # pre_buffer=False: with pre-buffering pyarrow keeps every column chunk it read until the file is
            # closed, so the memory grew with the log (1.2 GB for 76 h at 100 Hz); without it the read is
            # also faster (benchmarks/bench_memory.py).
            pf = pq.ParquetFile(self.path, pre_buffer=False)
            groups = pf.metadata.num_row_groups
        except (pa.ArrowException, OSError, UnicodeDecodeError) as exc:
            raise LogError(f"{self.label}: unreadable Parquet file ({_short(exc)})") from None
        columns = [self._raw_names.get(c, c) for c in self._wanted()]

        def batches() -> Iterator[pa.RecordBatch]:
            # One reader per row group: a single iter_batches over the whole file keeps some state per row group
            # it passed (about 75 kB each, 20 MB over 76 h at 100 Hz); a fresh one per group keeps none.
            for g in range(groups):
                yield from pf.iter_batches(batch_size=chunk_samples, row_groups=[g], columns=columns)

        def damaged(exc: BaseException, done: int) -> LogError:
            return LogError(f"{self.label}, row {done + 1}: damaged Parquet data after sample {done} ({_short(exc)})")

        with pf:
            yield from self._recut(batches(), chunk_samples, damaged)

    def _csv_blocks(self, chunk_samples: int) -> Iterator[_Raw]:
        import pyarrow.csv as pcsv

        _require_regular(self.path, self.label)
        cols = [self._raw_names.get(c, c) for c in self._wanted()]
        fmt = self.log_format
        types = {c: pa.float64() for c in cols}
        read_options = pcsv.ReadOptions(block_size=1 << 22)
        parse_options = pcsv.ParseOptions()
        source: Any = self.path
        if fmt is not None:
            time = fmt.column("time")
            if time is not None and time.is_iso_time:
                types[self._raw_names.get(time.name, time.name)] = pa.string()
            parse_options = pcsv.ParseOptions(delimiter=fmt.delimiter)
            if fmt.comment is not None:  # pyarrow has no comment lines: a filtered stream drops them
                assert self.path is not None  # only file logs are CSV
                source = io.BufferedReader(_SkipLines(self.path, fmt.header_row - 1, fmt.comment), 1 << 20)
            else:
                read_options = pcsv.ReadOptions(block_size=1 << 22, skip_rows=fmt.header_row - 1)
        try:
            reader = pcsv.open_csv(
                source,
                read_options=read_options,
                parse_options=parse_options,
                convert_options=pcsv.ConvertOptions(column_types=types, include_columns=cols),
            )
        except (pa.ArrowException, OSError) as exc:
            if source is not self.path:
                source.close()
            raise _csv_problem(self, str(exc)) from None
        try:
            yield from self._recut(reader, chunk_samples, lambda exc, done: _csv_problem(self, str(exc)))
        finally:
            if source is not self.path:
                source.close()

    def _recut(
        self,
        batches: Iterator[pa.RecordBatch],
        chunk_samples: int,
        problem: Callable[[BaseException, int], LogError],
    ) -> Iterator[_Raw]:
        """Blocks of exactly `chunk_samples` rows (the last one shorter) from record batches of any size;
        a read error becomes ``problem(exc, rows_read_so_far)``."""
        pending: list[pa.RecordBatch] = []
        size = 0
        done = 0
        while True:
            try:
                batch = next(batches)
            except StopIteration:
                break
            except (pa.ArrowException, OSError) as exc:
                raise problem(exc, done + size) from None
            if not pending and batch.num_rows == chunk_samples:  # the usual case: no re-cut
                raw = self._from_table(batch, done)
                done += chunk_samples
                del batch
                yield raw
                continue
            pending.append(batch)
            size += batch.num_rows
            while size >= chunk_samples:
                table = pa.Table.from_batches(pending)
                raw = self._from_table(table.slice(0, chunk_samples), done)
                done += chunk_samples
                rest = table.slice(chunk_samples)
                pending = rest.to_batches()
                size = rest.num_rows
                del table, rest
                yield raw
        if size:
            yield self._from_table(pa.Table.from_batches(pending), done)


def _stack3(columns: tuple[np.ndarray, ...]) -> np.ndarray:
    """Three (n,) columns as one C-contiguous (n, 3) float64 array (what the core takes)."""
    out = np.empty((len(columns[0]), 3))
    for j, c in enumerate(columns):
        out[:, j] = c
    return out


def _cut(raw: _Raw, n: int) -> _Raw:
    return _Raw(
        raw.t[:n],
        tuple(a[:n] for a in raw.sensors),
        None if raw.temp is None else raw.temp[:n],
        None if raw.truth is None else tuple(a[:n] for a in raw.truth),
        None if raw.ref_height is None else raw.ref_height[:n],
        None if raw.table_angle_deg is None else raw.table_angle_deg[:n],
    )


def _where(log: ImuLog, index: int, column: str | None = None) -> str:
    """``file, row R, column C`` for sample `index` (0-based); a formatted log names the file's own column."""
    if log.log_format is not None and log.format == "csv":
        row = _csv_line_of(log, index)
    else:
        row = index + (2 if log.format == "csv" else 1)
    if column is not None and log.log_format is not None:
        column = _format_column_label(log, column)
    return f"{log.label}, row {row}" + ("" if column is None else f", column {column}")


_CANONICAL_QUANTITY = {"t_s": "time", "temp_c": "temperature", REF_HEIGHT_COLUMN: "ref_height"} | {
    c: c[: -len("_deg")] for c in TRUTH_COLUMNS
}


def _format_column_label(log: ImuLog, column: str) -> str:
    """The file's column behind a reader column name (``gyro_x_rad_s`` = body right) or a format quantity."""
    fmt = log.log_format
    assert fmt is not None
    if column in log._columns:
        k = log._columns.index(column)
        src, sign = fmt.body_source("gyro" if k < 3 else "accel", k % 3)
        body = ("right", "forward", "up")[k % 3]
        return f"{src.name} ({src.quantity}, {src.unit}; body {body} = {'-' if sign < 0 else '+'}{src.name})"
    spec = fmt.column(_CANONICAL_QUANTITY.get(column, column))
    return column if spec is None else spec.describe()


def _csv_line_of(log: ImuLog, index: int) -> int:
    """The 1-based line of the file that holds data row `index` of a formatted CSV log (scans the file: only
    called for an error message)."""
    fmt = log.log_format
    assert fmt is not None and log.path is not None
    k = -1
    with open(log.path, "rb") as fh:
        for line_no, line in enumerate(fh, start=1):
            if line_no <= fmt.header_row:
                continue
            text = line.decode("utf-8", "replace")
            if not text.strip() or (fmt.comment is not None and text.lstrip().startswith(fmt.comment)):
                continue
            k += 1
            if k == index:
                return line_no
    return fmt.header_row + 1 + index


class _SkipLines(io.RawIOBase):
    """A file's bytes without its first `skip` lines and without lines starting with `comment` (for pyarrow's
    CSV reader, which has no comment lines). Filters 1 MB blocks at a time (a line-by-line filter was 100 times
    slower than the reader itself)."""

    def __init__(self, path: Path, skip: int, comment: str):
        self._fh = open(path, "rb")  # closed by close()
        self._skip = skip
        self._comment = comment.encode("utf-8")
        self._buf = b""
        self._pos = 0
        self._tail = b""
        self._eof = False

    def readable(self) -> bool:
        return True

    def _fill(self) -> None:
        while self._pos >= len(self._buf) and not self._eof:
            block = self._fh.read(1 << 20)
            if block:
                data = self._tail + block
                cut = max(data.rfind(b"\n"), data.rfind(b"\r")) + 1
                if cut == 0:
                    self._tail = data
                    continue
                data, self._tail = data[:cut], data[cut:]
            else:
                self._eof = True
                data, self._tail = self._tail, b""
            lines = data.splitlines(keepends=True)
            if self._skip:
                k = min(self._skip, len(lines))
                lines = lines[k:]
                self._skip -= k
            c = self._comment
            self._buf = b"".join(ln for ln in lines if not ln.lstrip().startswith(c))
            self._pos = 0

    def readinto(self, b) -> int:  # type: ignore[override]
        self._fill()
        n = min(len(b), len(self._buf) - self._pos)
        b[:n] = self._buf[self._pos : self._pos + n]
        self._pos += n
        return n

    def close(self) -> None:
        self._fh.close()
        super().close()


def _iso_ns(col: Any, where: Callable[[int], str]) -> np.ndarray:
    """ISO 8601 date-times (text or a timestamp column) as int64 nanoseconds since 1970 (a time without a zone
    is taken as written, one with a zone or ``Z`` in UTC); `LogError` at the first cell that is not one."""
    if isinstance(col, pa.ChunkedArray):
        col = col.combine_chunks()
    if pa.types.is_timestamp(col.type):
        return np.asarray(col.cast(pa.int64()).to_numpy(zero_copy_only=False), dtype=np.int64)
    for ty in (pa.timestamp("ns"), pa.timestamp("ns", tz="UTC")):
        try:
            return np.asarray(col.cast(ty).cast(pa.int64()).to_numpy(zero_copy_only=False), dtype=np.int64)
        except (pa.ArrowInvalid, pa.ArrowNotImplementedError):
            continue
    for i, v in enumerate(col.to_pylist()):
        ok = False
        for ty in (pa.timestamp("ns"), pa.timestamp("ns", tz="UTC")):
            try:
                pa.array([v]).cast(ty)
                ok = True
                break
            except (pa.ArrowInvalid, pa.ArrowNotImplementedError):
                pass
        if not ok:
            raise LogError(
                f"{where(i)}: expected an ISO 8601 date-time (2024-05-01T12:00:00.010), got {_short(str(v))!r}"
            )
    raise LogError(f"{where(0)}: ISO date-times with and without a time zone mixed in one column")


def _short(exc: BaseException | str) -> str:
    text = " ".join(str(exc).split())
    return text if len(text) <= 200 else text[:197] + "..."


class _Validator:
    """Checks chunks one after the other, carrying the last time stamp across chunk boundaries."""

    def __init__(self, log: ImuLog):
        self.log = log
        self.dt = 1.0 / log.rate_hz
        self.prev_t: float | None = None
        scale = self.dt if log.kind == "increments" else 1.0  # limits on the stored values
        self.limits = (MAX_RATE_DEG_S * math.pi / 180.0 * scale, MAX_SPECIFIC_FORCE_G * _G0 * scale)

    def _finite(self, a: np.ndarray, first: int, names: tuple[str, ...]) -> None:
        bad = ~np.isfinite(a)
        if bad.any():
            i, j = (int(k[0]) for k in np.nonzero(bad.reshape(len(a), -1)))
            v = float(a.reshape(len(a), -1)[i, j])
            where = _where(self.log, first + i, names[j])
            if math.isnan(v):
                raise LogError(f"{where}: empty or NaN cell")
            raise LogError(f"{where}: expected a finite number, got {v!r}")

    def check(self, raw: _Raw, first: int) -> LogChunk:
        """The chunk of `raw` (samples `first`...), or `LogError` at its first problem.

        One vectorised pass per quantity decides that a chunk is clean (the usual case); only a chunk with a
        problem goes through the detailed checks, in a fixed order (non-finite values, temperature range, time,
        magnitudes), which name the row and column.
        """
        log = self.log
        t = np.asarray(raw.t, dtype=np.float64)
        if len(raw.sensors) == 2:
            gyro, acc = raw.sensors
        else:
            gyro, acc = _stack3(raw.sensors[:3]), _stack3(raw.sensors[3:])
        temp = None if raw.temp is None else np.asarray(raw.temp, dtype=np.float64)
        truth = None if raw.truth is None else tuple(np.asarray(c, dtype=np.float64) for c in raw.truth)
        href = None if raw.ref_height is None else np.asarray(raw.ref_height, dtype=np.float64)
        low, high = TEMPERATURE_LIMITS_C
        clean = (
            bool(np.isfinite(t).all())
            and self._time_ok(t)
            and bool((np.abs(gyro) <= self.limits[0]).all())  # NaN and inf fail too
            and bool((np.abs(acc) <= self.limits[1]).all())
            and (temp is None or bool(((temp >= low) & (temp <= high)).all()))
            and (truth is None or all(bool(np.isfinite(c).all()) for c in truth))
            and (href is None or bool(((href >= _HEIGHT_LIMITS_M[0]) & (href <= _HEIGHT_LIMITS_M[1])).all()))
        )
        if not clean:
            self._explain(t, gyro, acc, temp, truth, first, href)
        self.prev_t = float(t[-1]) if len(t) else self.prev_t
        if log.kind == "rates":
            gyro = gyro * self.dt
            acc = acc * self.dt
        return LogChunk(
            first, t, np.ascontiguousarray(gyro), np.ascontiguousarray(acc), temp, truth, href, raw.table_angle_deg
        )

    def _time_ok(self, t: np.ndarray) -> bool:
        if not len(t):
            return True
        full = t if self.prev_t is None else np.concatenate([[self.prev_t], t])
        return bool((np.abs(np.diff(full) - self.dt) <= GAP_TOLERANCE * self.dt).all())

    def _explain(self, t, gyro, acc, temp, truth, first: int, href=None) -> None:
        """Raise the `LogError` of the first problem of a chunk that failed the fast checks."""
        log = self.log
        names = log._columns
        self._finite(t, first, ("t_s",))
        self._finite(gyro, first, names[:3])
        self._finite(acc, first, names[3:])
        if temp is not None:
            self._finite(temp, first, ("temp_c",))
            low, high = TEMPERATURE_LIMITS_C
            bad = (temp < low) | (temp > high)
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                raise LogError(
                    f"{_where(log, first + i, 'temp_c')}: temperature {float(temp[i]):.6g} deg C is outside "
                    f"[{low:g}, {high:g}] deg C (a system temperature in deg C, not kelvin)"
                )
        if truth is not None:
            for c, name in zip(truth, TRUTH_COLUMNS, strict=True):
                self._finite(c, first, (name,))
        if href is not None:
            self._finite(href, first, (REF_HEIGHT_COLUMN,))
            low, high = _HEIGHT_LIMITS_M
            bad = (href < low) | (href > high)
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                raise LogError(
                    f"{_where(log, first + i, REF_HEIGHT_COLUMN)}: reference height {float(href[i]):.6g} m is outside "
                    f"[{low:g}, {high:g}] m (a height above the ellipsoid in metres)"
                )
        self._check_time(t, first)
        for j, (block, limit) in enumerate(((gyro, self.limits[0]), (acc, self.limits[1]))):
            over = np.abs(block) > limit
            if over.any():
                i, k = (int(x[0]) for x in np.nonzero(over))
                mag = abs(float(block[i, k])) / (self.dt if log.kind == "increments" else 1.0)
                if j == 0:
                    msg = f"angular rate {mag * 180.0 / math.pi:.6g} deg/s exceeds {MAX_RATE_DEG_S:g} deg/s"
                else:
                    msg = f"specific force {mag / _G0:.6g} g exceeds {MAX_SPECIFIC_FORCE_G:g} g"
                raise LogError(f"{_where(log, first + i, names[3 * j + k])}: impossible magnitude: {msg}")

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
                f"{_where(self.log, first + k + 1 - off, 't_s')}: {what} ({float(full[k + 1])!r} s after "
                f"{float(full[k])!r} s); time must be strictly increasing"
            )
        gap = np.abs(dt - self.dt) > GAP_TOLERANCE * self.dt
        if gap.any():
            k = int(np.flatnonzero(gap)[0])
            raise LogError(
                f"{_where(self.log, first + k + 1 - off, 't_s')}: gap in time: step {dt[k]:.6g} s from "
                f"{float(full[k])!r} s, expected {self.dt:.6g} s (rate {self.log.rate_hz:g} Hz, tolerance "
                f"{GAP_TOLERANCE:.0%})"
            )


class _StaticMeans:
    """Running sums over the start of a log for `ImuLog.check_static_base` (flat memory: a few numbers).

    The table turns about body up, so body up keeps its direction on a static base: the mean up specific force is
    g cos(tilt) whatever the table does, and the horizontal gyros see the Earth rate's horizontal component
    turning against the table. Rotating each sample's x/y angle increment by the table angle phi (the axial gyro
    integrated, minus the Earth rate's vertical component w_ie sin L) brings them back to one frame fixed on the
    ground, where their mean is that component (the x/y biases average out as the table turns); a wrong axial
    gyro (unit, sign) smears it away.
    """

    def __init__(self, log: ImuLog):
        self.log = log
        self.dt = 1.0 / log.rate_hz
        lat = None if log.site is None else math.radians(log.site.lat_deg)
        self.w_up = 0.0 if lat is None else OMEGA_IE_RAD_S * math.sin(lat)  # [rad/s]
        self.n = 0
        self.phi = 0.0  # table angle [rad]
        self.phi_low = self.phi_high = 0.0
        self.h = np.zeros(2)  # de-rotated horizontal angle increments [rad]
        self.z = 0.0  # axial angle [rad]
        self.f_up = 0.0  # up velocity increments [m/s]
        self.f_abs = 0.0  # sum of |dv| [m/s]

    def add(self, chunk: LogChunk) -> None:
        dth, dv = chunk.dtheta_rad, chunk.dv_m_s
        dphi = dth[:, 2] - self.w_up * self.dt
        phi = self.phi + np.cumsum(dphi)
        mid = phi - 0.5 * dphi  # the table angle in the middle of each sample
        c, s = np.cos(mid), np.sin(mid)
        self.h += (float(np.sum(c * dth[:, 0] - s * dth[:, 1])), float(np.sum(s * dth[:, 0] + c * dth[:, 1])))
        if len(phi):
            self.phi = float(phi[-1])
            self.phi_low = min(self.phi_low, float(phi.min()))
            self.phi_high = max(self.phi_high, float(phi.max()))
        self.z += float(np.sum(dth[:, 2]))
        self.f_up += float(np.sum(dv[:, 2]))
        self.f_abs += float(np.sum(np.sqrt(np.einsum("ij,ij->i", dv, dv))))
        self.n += len(dth)

    def verdict(self) -> None:
        """Raise `ImplausibleLogError` at the first check the sums fail (the order of docs/procedure.md)."""
        log = self.log
        span = self.n * self.dt
        site = log.site
        g0 = _G0
        f_abs = self.f_abs / span  # [m/s^2]
        f_up = self.f_up / span
        tol = SPECIFIC_FORCE_TOLERANCE_G * g0
        if site is not None:
            g_lo = g_hi = float(normal_gravity(math.radians(site.lat_deg), site.height_m))
            where = f"normal gravity at {site.lat_deg:g} deg, {site.height_m:g} m"
        else:
            g_lo = float(normal_gravity(0.0, _HEIGHT_LIMITS_M[1]))
            g_hi = float(normal_gravity(math.radians(float(_core.MAX_LAT_DEG)), _HEIGHT_LIMITS_M[0]))
            where = "normal gravity anywhere (the log has no site)"
        head = f"{log.label}: not a static base over its first {span:g} s"
        if not g_lo - tol <= f_abs <= g_hi + tol:
            want = f"{g_lo:.4f}" if g_lo == g_hi else f"{g_lo:.4f} to {g_hi:.4f}"
            raise ImplausibleLogError(
                f"{head} (specific force magnitude): measured {f_abs:.6g} m/s^2 ({f_abs / g0:.6g} g), expected "
                f"{want} m/s^2 ({where}) +- {SPECIFIC_FORCE_TOLERANCE_G * 1e3:g} mg (any accelerometer bias); "
                f"a unit or scale slip: check {_channels(log, 'accel', (0, 1, 2))}"
            )
        tilt = math.degrees(math.acos(max(-1.0, min(1.0, f_up / f_abs))))
        if log.truth is not None:
            p, r = math.radians(log.truth.pitch_deg), math.radians(log.truth.roll_deg)
            declared = math.degrees(math.acos(max(-1.0, min(1.0, math.cos(p) * math.cos(r)))))
            ok = abs(tilt - declared) <= DECLARED_TILT_TOLERANCE_DEG
            want = (
                f"{declared:.4g} deg +- {DECLARED_TILT_TOLERANCE_DEG:g} deg (the declared pitch "
                f"{log.truth.pitch_deg:g} deg, roll {log.truth.roll_deg:g} deg)"
            )
        else:
            ok = tilt <= MAX_UNDECLARED_TILT_DEG
            want = f"at most {MAX_UNDECLARED_TILT_DEG:g} deg (the table axis near the vertical)"
        if not ok:
            raise ImplausibleLogError(
                f"{head} (specific force points up): body up is {tilt:.4g} deg from the measured vertical (mean up "
                f"specific force {f_up:.6g} m/s^2 of {f_abs:.6g}), expected {want}; a sign or axis slip: check "
                f"{_channels(log, 'accel', (2,), axes=True)}"
            )
        # The Earth rate's direction makes an angle alpha with body up: 90 deg - latitude, +- the tilt (and 1 deg
        # for the tilt's own error); the horizontal gyros see w_ie sin(alpha), the axial one w_ie cos(alpha).
        w = OMEGA_IE_RAD_S / DEG_PER_H
        t = min(180.0, tilt + 1.0)
        if site is not None:
            c = 90.0 - site.lat_deg
            a_lo, a_hi = abs(c - t), min(c + t, 360.0 - c - t)
            h_lo = w * min(math.sin(math.radians(a_lo)), math.sin(math.radians(a_hi)))
            h_hi = w if a_lo <= 90.0 <= a_hi else w * max(math.sin(math.radians(a_lo)), math.sin(math.radians(a_hi)))
            z_lo, z_hi = w * math.cos(math.radians(a_hi)), w * math.cos(math.radians(a_lo))
            at = f"at {site.lat_deg:g} deg, the site's latitude"
        else:
            h_lo, h_hi, z_lo, z_hi = 0.0, w, -w, w
            at = "(the log has no site: anywhere)"
        horizontal = float(np.hypot(*self.h)) / span / DEG_PER_H
        axial = self.z / span / DEG_PER_H
        still = math.degrees(self.phi_high - self.phi_low) <= TABLE_STILL_DEG
        table = (
            "the table standing still by the axial gyro"
            if still
            else f"de-rotated by the table angle of the axial gyro ({math.degrees(self.phi):.6g} deg at the end)"
        )
        if not _plausible(horizontal, h_lo, h_hi):
            raise ImplausibleLogError(
                f"{head} (horizontal Earth rate): the mean horizontal rate ({table}) is {horizontal:.6g} deg/h, "
                f"expected {_shown_range(h_lo, h_hi)} deg/h (w_ie cos(latitude) {at}, tilt {tilt:.3g} deg) "
                f"+- {EARTH_RATE_TOLERANCE_DEG_H:g} deg/h or within a factor 2; a unit, scale or sign slip: check "
                f"{_channels(log, 'gyro', (0, 1, 2), up_note='the table angle')}"
            )
        if still:
            if site is None:  # the whole Earth rate is w_ie anywhere
                total = math.hypot(horizontal, axial)
                ok, shown, want = _plausible(total, w, w), f"the Earth rate magnitude {total:.6g}", f"{w:.6g}"
            else:
                ok, shown, want = (
                    _plausible(axial, z_lo, z_hi),
                    f"the mean axial rate {axial:.6g}",
                    _shown_range(z_lo, z_hi),
                )
            if not ok:
                raise ImplausibleLogError(
                    f"{head} (axial Earth rate): the table stands still and {shown} deg/h, expected {want} deg/h "
                    f"(w_ie sin(latitude) {at}, tilt {tilt:.3g} deg) +- {EARTH_RATE_TOLERANCE_DEG_H:g} deg/h or "
                    f"within a factor 2; a unit, scale or sign slip: check {_channels(log, 'gyro', (2,))}"
                )


def _plausible(x: float, lo: float, hi: float) -> bool:
    """Whether a measured Earth-rate component `x` [deg/h] can be one expected in [lo, hi]: within
    `EARTH_RATE_TOLERANCE_DEG_H` of the range, or (a range of one sign) within a factor 2 of it."""
    tol = EARTH_RATE_TOLERANCE_DEG_H
    if lo - tol <= x <= hi + tol:
        return True
    if lo > 0.0:
        return 0.5 * lo <= x <= 2.0 * hi
    if hi < 0.0:
        return 2.0 * lo <= x <= 0.5 * hi
    return False


def _shown_range(lo: float, hi: float) -> str:
    return f"{lo:.4g}" if abs(hi - lo) < 5e-4 else f"{lo:.4g} to {hi:.4g}"


def _channels(log: ImuLog, sensor: str, body: tuple[int, ...], axes: bool = False, up_note: str = "") -> str:
    """What a user checks for a failed static-base check: the columns of body axes `body` of `sensor` (a log
    format's ``[columns.NAME]`` unit and scale keys, and its ``[axes]`` when `axes`); `up_note` says what the up
    axis is checked for."""
    fmt = log.log_format
    names = ("right", "forward", "up")
    note = f"; {up_note}" if up_note else ""
    if fmt is None:
        k = 0 if sensor == "gyro" else 3
        cols = ", ".join(log._columns[k + j] + (note if j == 2 else "") for j in body)
        hint = (
            "; a log in other units or axes needs a log format (--format FILE, docs/procedure.md)"
            if log.path is not None
            else ""
        )
        return f"column(s) {cols} (body {', '.join(names[j] for j in body)}){hint}"
    parts = []
    for j in body:
        spec, sign = fmt.body_source(sensor, j)
        parts.append(
            f"[columns.{spec.name}] unit/scale ({spec.quantity}, {spec.unit}; body {names[j]} = "
            f"{'-' if sign < 0 else '+'}{spec.name}{note if j == 2 else ''})"
        )
    keys = ", ".join(parts) + (", [axes] up" if axes else "")
    return f"{keys} of the log format {fmt.source}"


# ----------------------------------------------------------------------------------------------
# Opening
# ----------------------------------------------------------------------------------------------


def _require_regular(path: Path | None, label: str) -> None:
    """Refuse what is not a regular file (devices such as /dev/zero, FIFOs that would block, folders)."""
    if path is None:
        return
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise LogError(f"{label}: no such file") from None
    except OSError as exc:
        raise LogError(f"{label}: cannot read ({exc.strerror or exc})") from None
    if stat.S_ISDIR(st.st_mode):
        raise LogError(f"{label}: is a folder; expected a log file (.parquet, .pq or .csv)")
    if not stat.S_ISREG(st.st_mode):
        raise LogError(f"{label}: not a regular file (a device, FIFO or socket); expected a log file")


_FORMAT_HINT = (
    "; a log with other column names, units or axes: describe the file's own columns with a log format "
    "(--format FILE, docs/procedure.md)"
)


def _kind_from_header(names: list[str], label: str, file: bool = True) -> tuple[str, tuple[str, ...]]:
    """The kind and sensor columns the header gives; `LogError` (with the ``--format`` hint for a `file`)."""
    hint = _FORMAT_HINT if file else ""
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise LogError(f"{label}, row 1: column {', '.join(dup)} appears more than once; column names must be unique")
    if "t_s" not in names:
        raise LogError(f"{label}, row 1: missing column t_s (sample end time, s){hint}")
    if all(c in names for c in INCREMENT_COLUMNS):
        kind, cols = "increments", INCREMENT_COLUMNS
    elif all(c in names for c in RATE_COLUMNS):
        kind, cols = "rates", RATE_COLUMNS
    else:
        inc = [c for c in INCREMENT_COLUMNS if c not in names]
        rat = [c for c in RATE_COLUMNS if c not in names]
        missing = inc if len(inc) <= len(rat) else rat
        raise LogError(
            f"{label}, row 1: missing column(s) {', '.join(missing)}: a log needs the increments "
            f"{', '.join(INCREMENT_COLUMNS)} or the rates {', '.join(RATE_COLUMNS)}{hint}"
        )
    return kind, cols


def _check_rate(rate: Any, label: str, what: str = "sample rate") -> float:
    if isinstance(rate, bool) or not isinstance(rate, (int, float, np.integer, np.floating)):
        raise LogError(f"{label}: {what} must be a number in Hz, got {rate!r}")
    try:
        r = float(rate)
    except OverflowError:
        r = math.inf
    if not (math.isfinite(r) and MIN_RATE_HZ <= r <= MAX_RATE_HZ):
        raise LogError(f"{label}: {what} must be in [{MIN_RATE_HZ:g}, {MAX_RATE_HZ:g}] Hz, got {rate!r}")
    return r


def _json_value(meta: Mapping[str, str], key: str, label: str) -> Any:
    try:
        return json.loads(meta[key])
    except (ValueError, RecursionError) as exc:
        raise LogError(f"{label}: unreadable {key} metadata ({_short(exc)})") from None


def _number(value: Any, label: str, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise LogError(f"{label}: {key} must be a number, got {_short(repr(value))}")
    try:
        x = float(value)
    except OverflowError:
        x = math.inf
    if not math.isfinite(x):
        raise LogError(f"{label}: {key} must be a finite number, got {_short(repr(value))}")
    return x


def _read_site(meta: Mapping[str, str], label: str) -> Site | None:
    if "gyrodrift.site" not in meta:
        return None
    s = _json_value(meta, "gyrodrift.site", label)
    if not isinstance(s, dict) or not all(k in s for k in ("lat_deg", "lon_deg", "height_m")):
        raise LogError(f"{label}: gyrodrift.site metadata must be {{lat_deg, lon_deg, height_m}}")
    return Site(*(_number(s[k], label, f"gyrodrift.site {k}") for k in ("lat_deg", "lon_deg", "height_m")))


def _read_truth(meta: Mapping[str, str], label: str) -> LogTruth | None:
    if "gyrodrift.scenario" not in meta:
        return None
    s = _json_value(meta, "gyrodrift.scenario", label)
    att = s.get("attitude", {}) if isinstance(s, dict) else None
    if not isinstance(att, dict):
        raise LogError(f"{label}: gyrodrift.scenario metadata must be a table with an [attitude] table")
    return LogTruth(
        *(
            _number(att.get(k, 0.0), label, f"gyrodrift.scenario attitude {k}")
            for k in ("pitch_deg", "roll_deg", "yaw_deg")
        )
    )


def _read_static_s(meta: Mapping[str, str], label: str) -> float | None:
    """The static part [s] of a simulated moving-base log (``[trajectory] static_h`` of its scenario metadata),
    or None (a static-base log, or no scenario)."""
    if "gyrodrift.scenario" not in meta:
        return None
    s = _json_value(meta, "gyrodrift.scenario", label)
    tr = s.get("trajectory") if isinstance(s, dict) else None
    if not isinstance(tr, dict):
        return None
    return _number(tr.get("static_h", 0.0), label, "gyrodrift.scenario trajectory static_h") * 3600.0


def _rate_from_times(t: np.ndarray, label: str) -> float:
    dt = np.diff(t)
    if len(dt) < 1 or not np.all(np.isfinite(dt)):
        raise LogError(f"{label}: cannot tell the sample rate (fewer than two finite time stamps)")
    med = float(np.median(dt))
    if not med > 0.0:
        raise LogError(f"{label}: cannot tell the sample rate (time stamps do not increase)")
    # 9 significant digits: differences of decimal time stamps make 9.99999999999998 Hz of a 10 Hz log, and the
    # navigation would then differ (by 1e-13 deg) from the same log whose metadata says 10.
    return _check_rate(float(f"{1.0 / med:.9g}"), label, "the sample rate of the time stamps")


def _merge_site(given: Site | Mapping[str, float] | None, from_file: Site | None, label: str) -> Site | None:
    """A `Site` replaces the file's; a mapping overrides only the keys it has (lon 0, height 0 by default).

    Every value must lie within the core's limits (`_SITE_LIMITS`): `OptionError` naming the option for a
    given value, `LogError` naming the file for the file's own.
    """
    given_keys: set[str] = set()
    if given is None:
        site = from_file
        if site is None:
            return None
    elif isinstance(given, Mapping):
        flags = {"lat_deg": "--lat0-deg", "lon_deg": "--lon0-deg", "height_m": "--height-m"}
        unknown = set(given) - set(flags)
        if unknown:
            raise OptionError(f"site: unknown key(s) {sorted(unknown)} (expected lat_deg, lon_deg, height_m)")
        for k, v in given.items():
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(float(v)):
                raise OptionError(f"{flags[k]} ({k}): expected a finite number, got {v!r}")
        if "lat_deg" not in given and from_file is None:
            raise LogError(f"{label}: the log carries no site; give its latitude (--lat0-deg / site=)")
        given_keys = set(given)
        base = from_file or Site(math.nan, 0.0, 0.0)
        site = Site(
            float(given.get("lat_deg", base.lat_deg)),
            float(given.get("lon_deg", base.lon_deg)),
            float(given.get("height_m", base.height_m)),
        )
    elif all(hasattr(given, k) for k in _SITE_LIMITS):
        site = Site(float(given.lat_deg), float(given.lon_deg), float(given.height_m))
        given_keys = set(_SITE_LIMITS)
    else:
        raise OptionError(f"site: expected a gyrodrift.site.Site or a mapping, got {type(given).__name__}")
    for key, (low, high, flag, unit) in _SITE_LIMITS.items():
        v = getattr(site, key)
        if math.isfinite(v) and low <= v <= high:
            continue
        if key in given_keys:
            raise OptionError(f"{flag} ({key}): {v!r} {unit} is outside [{low:g}, {high:g}] {unit}")
        raise LogError(f"{label}: the site's {key} {v!r} {unit} is outside [{low:g}, {high:g}] {unit}")
    return site


def _numeric_type(t: pa.DataType) -> bool:
    return (pa.types.is_floating(t) or pa.types.is_integer(t)) and not pa.types.is_boolean(t)


def _open_parquet(p: Path, label: str, site, require_temperature: bool) -> ImuLog:
    import pyarrow.parquet as pq

    try:
        pf = pq.ParquetFile(p, pre_buffer=False)
        schema = pf.schema_arrow
        n = pf.metadata.num_rows
    except (pa.ArrowException, OSError, UnicodeDecodeError) as exc:  # a damaged schema may hold non-UTF-8 names
        raise LogError(f"{label}: not a Parquet file ({_short(exc)})") from None
    with pf:
        names = list(schema.names)
        kind, cols = _kind_from_header(names, label)
        if require_temperature and "temp_c" not in names:
            raise LogError(f"{label}, row 1: missing column temp_c (system temperature, deg C; the features need it)")
        has_temp = "temp_c" in names
        has_truth = all(c in names for c in TRUTH_COLUMNS)
        has_href = REF_HEIGHT_COLUMN in names
        optional = [*(["temp_c"] if has_temp else []), *(TRUTH_COLUMNS if has_truth else ())]
        for c in ["t_s", *cols, *optional, *([REF_HEIGHT_COLUMN] if has_href else [])]:
            t = schema.field(c).type
            if not _numeric_type(t):
                raise LogError(f"{label}, column {c}: expected numbers (float64), got a column of type {t}")
        meta = {k.decode("utf-8", "replace"): v.decode("utf-8", "replace") for k, v in (schema.metadata or {}).items()}
        if n < 2:
            raise LogError(f"{label}: {n} sample(s); a log needs many")
        file_site = _read_site(meta, label)
        truth = _read_truth(meta, label)
        static_s = _read_static_s(meta, label)
        if "gyrodrift.rate_hz" in meta:
            rate = _check_rate(_json_value(meta, "gyrodrift.rate_hz", label), label, "gyrodrift.rate_hz metadata")
            rate_source = "metadata"
        else:
            try:
                head = next(pf.iter_batches(batch_size=_RATE_PROBE + 1, columns=["t_s"]))
                times = np.asarray(head.column(0).to_numpy(zero_copy_only=False), float)
            except (pa.ArrowException, OSError, StopIteration) as exc:
                raise LogError(f"{label}, row 1: damaged Parquet data ({_short(exc)})") from None
            rate, rate_source = _rate_from_times(times, label), "time stamps"
    return ImuLog(
        path=p,
        label=label,
        fmt="parquet",
        kind=kind,
        columns=cols,
        rate_hz=rate,
        n_samples=n,
        site=_merge_site(site, file_site, label),
        rate_source=rate_source,
        truth=truth,
        has_temperature=has_temp,
        has_truth_columns=has_truth,
        has_reference_height=has_href,
        static_s=static_s,
    )


def _csv_lines(path: Path, label: str) -> Iterator[str]:
    """The file's lines decoded as UTF-8 (a BOM on the first is dropped); `LogError` with the row otherwise."""
    with open(path, "rb") as fh:
        for rownum, line in enumerate(fh, start=1):
            try:
                text = line.decode("utf-8-sig" if rownum == 1 else "utf-8")
            except UnicodeDecodeError as exc:
                raise LogError(
                    f"{label}, row {rownum}: not UTF-8 text (byte 0x{line[exc.start]:02x} at character "
                    f"{exc.start + 1}); expected a CSV log"
                ) from None
            yield text


def _csv_problem(log: ImuLog, message: str) -> LogError:
    """Find the first bad row of a CSV that pyarrow refused (scans the file): cell count, number, UTF-8."""
    label = log.label
    used = set(log._wanted())
    fmt = log.log_format
    iso = None if fmt is None or not fmt.column("time").is_iso_time else fmt.column("time").name  # type: ignore[union-attr]
    try:
        assert log.path is not None  # only file logs are CSV
        lines = _csv_lines(log.path, label)
        skip = 0 if fmt is None else fmt.header_row - 1
        for _ in range(skip):
            next(lines)
        reader = csv.reader(lines, delimiter="," if fmt is None else fmt.delimiter)
        header = [h.strip() for h in next(reader)]
        for row in reader:
            rownum = reader.line_num + skip
            if not row or all(not c.strip() for c in row):
                continue
            if fmt is not None and fmt.comment is not None and row[0].lstrip().startswith(fmt.comment):
                continue
            if len(row) != len(header):
                return LogError(
                    f"{label}, row {rownum}: {len(row)} cells, expected {len(header)} (one per header column)"
                )
            for name, cell in zip(header, row, strict=True):
                if name not in used or name == iso:
                    continue
                shown = name if fmt is None else _format_column_label(log, _quantity_of(fmt, name))
                try:
                    float(cell)
                except ValueError:
                    if cell.strip() == "":
                        return LogError(f"{label}, row {rownum}, column {shown}: empty or NaN cell")
                    return LogError(f"{label}, row {rownum}, column {shown}: expected a number, got {_short(cell)!r}")
    except LogError as exc:
        return exc
    except (csv.Error, StopIteration) as exc:
        return LogError(f"{label}: unreadable CSV ({_short(exc)})")
    return LogError(f"{label}: unreadable CSV ({_short(message)})")


def _quantity_of(fmt: LogFormat, name: str) -> str:
    return next(c.quantity for c in fmt.columns if c.name == name)


def _open_csv(p: Path, label: str, site, require_temperature: bool) -> ImuLog:
    raw_header: list[str] = []
    times: list[float] = []
    try:
        reader = csv.reader(_csv_lines(p, label))
        try:
            raw_header = next(reader)
        except StopIteration:
            raise LogError(f"{label}: empty file, expected a header row") from None
        header = [h.strip() for h in raw_header]
        kind, cols = _kind_from_header(header, label)
        if require_temperature and "temp_c" not in header:
            raise LogError(f"{label}, row 1: missing column temp_c (system temperature, deg C; the features need it)")
        it = header.index("t_s")
        for row in reader:
            if len(times) > _RATE_PROBE:
                break
            cell = row[it] if it < len(row) else ""
            try:
                times.append(float(cell))
            except ValueError:
                raise LogError(
                    f"{label}, row {reader.line_num}, column t_s: expected a number, got {_short(cell)!r}"
                ) from None
    except csv.Error as exc:
        raise LogError(f"{label}: unreadable CSV ({_short(exc)})") from None
    t = np.asarray(times, dtype=float)
    rate = _rate_from_times(t, label)
    last = _csv_last_time(p, it)
    if last is None or not (math.isfinite(last) and last > t[0]):
        raise LogError(f"{label}: cannot read the last time stamp of the file")
    n = (last - t[0]) * rate + 1.0
    if not n < 1e15:
        raise LogError(f"{label}: the last time stamp {last!r} s is not plausible for {rate:g} Hz")
    has_truth = all(c in header for c in TRUTH_COLUMNS)
    return ImuLog(
        path=p,
        label=label,
        fmt="csv",
        kind=kind,
        columns=cols,
        rate_hz=rate,
        n_samples=int(round(n)),
        site=_merge_site(site, None, label),
        rate_source="time stamps",
        has_temperature="temp_c" in header,
        has_truth_columns=has_truth,
        has_reference_height=REF_HEIGHT_COLUMN in header,
        raw_names={h: r for h, r in zip(header, raw_header, strict=True) if h != r},
    )


def _csv_last_time(path: Path, it: int) -> float | None:
    with open(path, "rb") as fh:
        fh.seek(0, os.SEEK_END)
        size = fh.tell()
        fh.seek(max(0, size - 65536))
        lines = [ln for ln in fh.read().decode("utf-8", "replace").splitlines() if ln.strip()]
    if not lines:
        return None
    try:
        cells = next(csv.reader(io.StringIO(lines[-1])))
        return float(cells[it])
    except (ValueError, IndexError, StopIteration, csv.Error):
        return None


def _open_formatted(p: Path, label: str, fmt: LogFormat, site, require_temperature: bool) -> ImuLog:
    """Open a log whose columns a `LogFormat` describes (CSV with its delimiter, header row and comments, or
    Parquet); the chunks are converted to the reader's columns and checked like a native log's."""
    suffix = p.suffix.lower()
    time = fmt.column("time")
    assert time is not None
    if require_temperature and not fmt.has_temperature:
        raise LogError(
            f"{label}: the log format {fmt.source} names no temperature column (the features need the system "
            'temperature; add a [columns.NAME] table with quantity = "temperature")'
        )
    names: list[str]
    if suffix in (".parquet", ".pq"):
        import pyarrow.parquet as pq

        try:
            pf = pq.ParquetFile(p, pre_buffer=False)
            schema = pf.schema_arrow
            n = pf.metadata.num_rows
        except (pa.ArrowException, OSError, UnicodeDecodeError) as exc:  # non-UTF-8 names in a damaged schema
            raise LogError(f"{label}: not a Parquet file ({_short(exc)})") from None
        with pf:
            names = list(schema.names)
            _check_format_columns(names, fmt, label, 1)
            for spec in fmt.columns:
                t = schema.field(spec.name).type
                ok = (pa.types.is_timestamp(t) or pa.types.is_string(t)) if spec.is_iso_time else _numeric_type(t)
                if not ok:
                    want = "ISO date-times (timestamp or text)" if spec.is_iso_time else "numbers"
                    raise LogError(f"{label}, column {spec.describe()}: expected {want}, got a column of type {t}")
            meta = {
                k.decode("utf-8", "replace"): v.decode("utf-8", "replace") for k, v in (schema.metadata or {}).items()
            }
            if n < 2:
                raise LogError(f"{label}: {n} sample(s); a log needs many")
            try:
                head = next(pf.iter_batches(batch_size=_RATE_PROBE + 1, columns=[time.name])).column(0)
            except (pa.ArrowException, OSError, StopIteration) as exc:
                raise LogError(f"{label}, row 1: damaged Parquet data ({_short(exc)})") from None
        file_site = _read_site(meta, label)
        kind = "parquet"
        first_rows: list[tuple[int, list[str]]] = []
        raw_names: dict[str, str] = {}
    elif suffix == ".csv":
        header, raw_header, first_rows = _formatted_csv_head(p, label, fmt)
        raw_names = {h: r for h, r in zip(header, raw_header, strict=True) if h != r}
        names = header
        _check_format_columns(names, fmt, label, fmt.header_row)
        it = header.index(time.name)
        if time.is_iso_time:
            head = pa.array([row[it].strip() if it < len(row) else "" for _, row in first_rows], pa.string())
        else:
            cells = []
            for line_no, row in first_rows:
                cell = row[it] if it < len(row) else ""
                try:
                    cells.append(float(cell))
                except ValueError:
                    raise LogError(
                        f"{label}, row {line_no}, column {time.describe()}: expected a number, got {_short(cell)!r}"
                    ) from None
            head = pa.array(cells, pa.float64())
        file_site = None
        kind = "csv"
        n = 0
    else:
        raise LogError(f"{label}: unknown log format {p.suffix!r} (expected .parquet, .pq or .csv)")
    if len(head) < 2:
        raise LogError(f"{label}: {len(head)} sample(s); a log needs many")
    t0_ns = None
    if time.is_iso_time:
        lines = [line_no for line_no, _ in first_rows] if kind == "csv" else None

        def where(i: int) -> str:
            return f"{label}, row {i + 1 if lines is None else lines[i]}, column {time.describe()}"

        ns = _iso_ns(head, where)
        t0_ns = int(ns[0])
        t = (ns - t0_ns).astype(np.float64) * 1e-9
    else:
        t = time.convert(head.to_numpy(zero_copy_only=False))
    rate = _rate_from_times(t, label)
    if kind == "csv":
        last = _formatted_csv_last_time(p, fmt, names.index(time.name), t0_ns)
        if last is None or not (math.isfinite(last) and last > t[0]):
            raise LogError(f"{label}: cannot read the last time stamp of the file")
        est = (last - t[0]) * rate + 1.0
        if not est < 1e15:
            raise LogError(f"{label}: the last time stamp {last!r} s is not plausible for {rate:g} Hz")
        n = int(round(est))
    cols = INCREMENT_COLUMNS if fmt.kind == "increments" else RATE_COLUMNS
    return ImuLog(
        path=p,
        label=label,
        fmt=kind,
        kind=fmt.kind,
        columns=cols,
        rate_hz=rate,
        n_samples=n,
        site=_merge_site(site, file_site, label),
        rate_source="time stamps",
        has_temperature=fmt.has_temperature,
        has_truth_columns=fmt.has_truth,
        has_reference_height=fmt.column("ref_height") is not None,
        log_format=fmt,
        t0_ns=t0_ns,
        raw_names=raw_names,
    )


def _check_format_columns(names: list[str], fmt: LogFormat, label: str, header_row: int) -> None:
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise LogError(
            f"{label}, row {header_row}: column {', '.join(dup)} appears more than once; column names must be unique"
        )
    for spec in fmt.columns:
        if spec.name not in names:
            shown = ", ".join(names[:12]) + (", ..." if len(names) > 12 else "")
            raise LogError(
                f"{label}, row {header_row}: no column {spec.name!r} (the {spec.quantity} column of the log format "
                f"{fmt.source}); the file's columns are: {shown}"
            )


def _formatted_data_lines(p: Path, label: str, fmt: LogFormat) -> Iterator[tuple[int, str]]:
    """(line number, text) of the header and data lines of a formatted CSV log (preamble, comments and
    blank lines skipped)."""
    for line_no, text in enumerate(_csv_lines(p, label), start=1):
        if line_no < fmt.header_row:
            continue
        if not text.strip() or (fmt.comment is not None and text.lstrip().startswith(fmt.comment)):
            if line_no == fmt.header_row:
                raise LogError(
                    f"{label}, row {line_no}: expected the header row here ([csv] header_row of {fmt.source})"
                )
            continue
        yield line_no, text


def _formatted_csv_head(
    p: Path, label: str, fmt: LogFormat
) -> tuple[list[str], list[str], list[tuple[int, list[str]]]]:
    """The header cells (stripped and as written) and the first `_RATE_PROBE` + 1 data rows with their line
    numbers."""
    header: list[str] | None = None
    raw: list[str] = []
    rows: list[tuple[int, list[str]]] = []
    try:
        for line_no, text in _formatted_data_lines(p, label, fmt):
            cells = next(csv.reader([text], delimiter=fmt.delimiter), [])
            if header is None:
                raw = list(cells)
                header = [h.strip() for h in cells]
                continue
            rows.append((line_no, cells))
            if len(rows) > _RATE_PROBE:
                break
    except csv.Error as exc:
        raise LogError(f"{label}: unreadable CSV ({_short(exc)})") from None
    if header is None:
        raise LogError(f"{label}: no header row at line {fmt.header_row} ([csv] header_row of {fmt.source})")
    return header, raw, rows


def _formatted_csv_last_time(p: Path, fmt: LogFormat, it: int, t0_ns: int | None) -> float | None:
    spec = fmt.column("time")
    assert spec is not None
    with open(p, "rb") as fh:
        fh.seek(0, os.SEEK_END)
        size = fh.tell()
        fh.seek(max(0, size - 65536))
        lines = [
            ln
            for ln in fh.read().decode("utf-8", "replace").splitlines()
            if ln.strip() and not (fmt.comment is not None and ln.lstrip().startswith(fmt.comment))
        ]
    if not lines:
        return None
    try:
        cell = next(csv.reader([lines[-1]], delimiter=fmt.delimiter))[it]
        if spec.is_iso_time:
            ns = _iso_ns(pa.array([cell.strip()]), lambda i: "")
            return (int(ns[0]) - (t0_ns or 0)) * 1e-9
        return float(spec.convert(np.array([float(cell)]))[0])
    except (ValueError, IndexError, StopIteration, csv.Error, LogError):
        return None


def open_log(
    path: str | os.PathLike[str],
    *,
    site: Site | Mapping[str, float] | None = None,
    require_temperature: bool = True,
    format: str | os.PathLike[str] | LogFormat | None = None,
) -> ImuLog:
    """Open an IMU log file, check its header, detect its kind and sample rate.

    Parameters
    ----------
    path : path-like
        ``.parquet``/``.pq`` or ``.csv`` file (see the module docstring for the columns); a regular file.
    site : Site or mapping, optional
        The true static site (``lat_deg``, ``lon_deg`` [deg], ``height_m`` [m]). A `Site` replaces the file's
        metadata; a mapping overrides only the keys it gives (the rest from the file, else lon 0, height
        0). CSV files carry no site, so the procedure needs at least the latitude from here.
    require_temperature : bool
        Refuse a log without ``temp_c`` (default; the features need it). `navigate` does not.
    format : path-like or LogFormat, optional
        A log format description (`gyrodrift.logs.log_format`, CLI ``--format FILE``) for a log with its own column
        names, units, axes, delimiter or time stamps; None (default) reads the columns of the module docstring.

    Returns
    -------
    ImuLog

    Raises
    ------
    LogError
        Missing file, not a regular file, unreadable file, missing or duplicated columns, columns that are not
        numbers, no usable rate. Row-level problems are found while streaming (`ImuLog.chunks`).
    OptionError
        A site value that is not a finite number or a latitude outside (-90, 90) deg.
    LogFormatError
        An invalid log format file (naming the file and key).
    OutputError
        The log belongs to a gyrodrift output set that an interrupted run left unfinished (docs/outputs.md).
    """
    from gyrodrift.files.atomic import check_complete

    p = Path(path)
    label = str(path)
    _require_regular(p, label)
    check_complete(p)  # a log whose output set an interrupted `simulate` left unfinished (docs/outputs.md)
    if format is not None:
        return _open_formatted(p, label, load_log_format(format), site, require_temperature)
    suffix = p.suffix.lower()
    if suffix in (".parquet", ".pq"):
        return _open_parquet(p, label, site, require_temperature)
    if suffix == ".csv":
        return _open_csv(p, label, site, require_temperature)
    raise LogError(f"{label}: unknown log format {p.suffix!r} (expected .parquet, .pq or .csv)")
