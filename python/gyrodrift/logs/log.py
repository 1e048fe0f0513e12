"""The chunked view of an IMU log (`ImuLog`, `LogChunk`): every source read through the same checks, and `open_log`.

A log is one row per IMU sample, body frame x right, y forward, z up (z = turntable = axial axis). Every
source goes through the same checks and yields the same `LogChunk` objects; one reader per source:

* Parquet (``.parquet`` / ``.pq``, `gyrodrift.logs.parquet`): the simulator's own ``imu.parquet``
  (docs/scenarios.md) or any file with the columns below, with or without gyrodrift metadata;
* CSV (``.csv``, `gyrodrift.logs.csv`): UTF-8, comma separated, one header row (names stripped of surrounding
  spaces);
* a log in its own format (own column names, units, axes, delimiter, time stamps; `gyrodrift.logs.formatted`):
  Parquet or CSV with a log format description (`gyrodrift.logs.log_format`, ``open_log(path, format=...)``),
  converted chunk by chunk into the columns below before the same checks; messages then name the file's line and
  its own column;
* in memory: `ImuLog.from_arrays` (a mapping of the same column names to numpy arrays, `gyrodrift.logs.memory`);
* a scenario simulated on the fly, chunk by chunk, nothing stored: `gyrodrift.ins.simulate.scenario_log`.

Columns (order free, extra columns ignored; names, units and meanings in `gyrodrift.logs.columns`): ``t_s``; the
six increments ``dtheta_{x,y,z}_rad``, ``dv_{x,y,z}_m_s`` or the six rates ``gyro_{x,y,z}_rad_s``,
``accel_{x,y,z}_m_s2``; ``temp_c`` (required unless the caller says otherwise: `navigate` does not need it);
optional ``true_{pitch,roll,yaw}_deg`` (simulated logs, for attitude errors) and ``ref_height_m`` (the reference
of `navigate`'s damped vertical channel; finite, within the core's height limits). The header decides: all six
increment columns -> ``kind = "increments"``; else all six rate columns -> ``kind = "rates"`` (converted to
increments as rate / rate_hz, i.e. the rate is the mean over the nominal sample interval ending at ``t_s``).
Columns must hold numbers (Parquet: integer or floating point types; a bool or text column is refused); a name
given twice is refused.

Sample rate: the ``gyrodrift.rate_hz`` metadata of a Parquet file (a JSON number), otherwise 1 / median(dt)
over the first 1000 intervals, rounded to 9 significant digits; it must lie in [`MIN_RATE_HZ`, `MAX_RATE_HZ`]
(`gyrodrift.logs.source`). Every chunk is checked while it streams (a log is never loaded whole; an 88 h log at
200 Hz is 63 million rows), and the first problem raises `LogError` naming the file, row and column
(`gyrodrift.logs.rows`):

* time not strictly increasing (duplicated or going back), a gap (an interval off the nominal
  1 / rate_hz by more than 1 %), NaN or empty cells, infinite values, impossible magnitudes (``|rate|`` >
  `MAX_RATE_DEG_S` deg/s, ``|specific force|`` > `MAX_SPECIFIC_FORCE_G` g on any axis), a temperature outside
  `gyrodrift.runs.table.TEMPERATURE_LIMITS_C` (the limits of the run tables: a kelvin value is refused), a missing
  column, a CSV row with the wrong number of cells, a byte that is not UTF-8, damaged Parquet data pages.

Only regular files are read: a device (``/dev/zero``), a FIFO or a folder is refused before it is opened.

Before its first chunk, every log is checked against a static base over its first `STATIC_CHECK_SPAN_S` seconds
(`ImuLog.check_static_base`, `gyrodrift.logs.plausibility`; a simulated moving-base log's static part when
shorter; a log or static part under `MIN_STATIC_CHECK_SPAN_S` is not checked): the mean specific force magnitude
is normal gravity at the site within `SPECIFIC_FORCE_TOLERANCE_G`, it points along body up (within
`MAX_UNDECLARED_TILT_DEG`, or the declared attitude's tilt), the horizontal gyros de-rotated by the table angle
see the Earth rate's horizontal component and, with the table still, the axial gyro its vertical one
(`EARTH_RATE_TOLERANCE_DEG_H` or a factor 2). A unit, scale, sign or axis slip fails one of them:
`ImplausibleLogError` names the check, the measured and expected values and the columns (a log format's keys) to
look at.

Row numbers: for CSV the line of the file (the header is row 1, the first sample row 2, as in
`gyrodrift.runs.table`); for the other sources the 1-based sample index.

The true static site (`gyrodrift.site.Site`) comes from the Parquet metadata ``gyrodrift.site`` (or the
scenario) when present; otherwise the caller gives it (`open_log(..., site=...)`). Simulated logs also carry
their true initial attitude (`LogTruth`, from the ``gyrodrift.scenario`` metadata).
"""

from __future__ import annotations

import contextlib
import math
import os
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gyrodrift.errors import CoreError, OptionError
from gyrodrift.files.atomic import check_complete
from gyrodrift.logs.csv import open_csv
from gyrodrift.logs.formatted import open_formatted
from gyrodrift.logs.log_format import LogFormat, load_log_format
from gyrodrift.logs.memory import array_source
from gyrodrift.logs.parquet import open_parquet
from gyrodrift.logs.plausibility import MIN_STATIC_CHECK_SPAN_S, STATIC_CHECK_SPAN_S, StaticMeans
from gyrodrift.logs.rows import RowChecker
from gyrodrift.logs.source import (
    DEFAULT_CHUNK_SAMPLES,
    LogError,
    LogSource,
    LogTruth,
    RawBlock,
    merge_site,
    require_regular,
)
from gyrodrift.site import Site

__all__ = ["ImuLog", "LogChunk", "open_log"]


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


class ImuLog:
    """An opened IMU log: source, kind, sample rate, size, site and truth; `chunks` streams validated samples.

    Use `open_log`, `ImuLog.from_arrays` or `gyrodrift.ins.simulate.scenario_log` to create one; `ImuLog(source,
    site=...)` wraps any `gyrodrift.logs.source.LogSource`. A file log holds only the file name and a few numbers,
    so it pickles cheaply (dask workers reopen the file themselves).

    Attributes
    ----------
    source : LogSource
        What reads the samples and names a place in them.
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
        The true static site when the source says it or the caller gave it (`site` replaces or completes the
        source's as in `open_log`).
    truth : LogTruth or None
        The true initial attitude (simulated logs).
    has_temperature, has_truth_columns, has_reference_height : bool
        Whether chunks carry ``temp_c``, ``truth`` and ``ref_height_m``.
    static_s : float or None
        The known length of the static part at the start [s] (a simulated moving-base log's ``static_h``), or
        None: `check_static_base` then reads `STATIC_CHECK_SPAN_S`.
    scenario : Scenario or None
        The `gyrodrift.ins.Scenario` of a log simulated on the fly (its route), else None.
    """

    def __init__(self, source: LogSource, *, site: Site | Mapping[str, float] | None = None):
        layout = source.layout
        self.source = source
        self.path = source.path
        self.label = source.label
        self.name = source.name or _run_name(source.path, source.label)
        self.format = source.format
        self.kind = layout.kind
        self.rate_hz = float(source.rate.hz)
        self.rate_source = source.rate.source
        self.n_samples = int(source.n_samples)
        self.site = merge_site(site, source.provenance.site, source.label)
        self.truth = source.provenance.truth
        self.has_temperature = layout.has_temperature
        self.has_truth_columns = layout.has_truth_columns
        self.has_reference_height = layout.has_reference_height
        self.static_s = source.provenance.static_s
        self.scenario = source.scenario
        self._static_checked = False  # once `check_static_base` has passed

    def __repr__(self) -> str:
        return (
            f"ImuLog({self.label!r}, format={self.format!r}, kind={self.kind!r}, rate_hz={self.rate_hz:g}, "
            f"n_samples={self.n_samples}, site={self.site})"
        )

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
        source = array_source(
            columns,
            rate_hz=rate_hz,
            source_site=source_site,
            truth=truth,
            label=label,
            require_temperature=require_temperature,
            static_s=static_s,
        )
        return cls(source, site=site)

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
            since = (
                "" if first == 0 else f" (t counted from {self.source.where(first).removeprefix(self.label + ', ')})"
            )
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
        rows = RowChecker(self.source)
        done = 0
        for raw in self._source_blocks(chunk_samples):
            n = len(raw.t)
            if stop is not None and done + n > stop:
                raw = raw.cut(stop - done)
                n = stop - done
            chunk = _chunk(rows.check(raw, done), done)
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
        rows = RowChecker(self.source)
        means = StaticMeans(self.source, self.site)
        done = 0
        blocks = self._source_blocks(min(n, DEFAULT_CHUNK_SAMPLES))
        try:
            for raw in blocks:
                k = len(raw.t)
                if done + k > n:
                    raw = raw.cut(n - done)
                    k = n - done
                try:
                    block = rows.check(raw, done)
                except LogError:  # a bad row: the stream itself names it when it gets there, as without this check
                    return
                means.add(*block.sensors)
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

    def _source_blocks(self, chunk_samples: int) -> Iterator[RawBlock]:
        return self.source.blocks(chunk_samples)


def _chunk(block: RawBlock, first: int) -> LogChunk:
    """The chunk of a checked block (`RowChecker.check`) whose first sample is `first`."""
    dtheta, dv = block.sensors
    return LogChunk(first, block.t, dtheta, dv, block.temp, block.truth, block.ref_height, block.table_angle_deg)


def _run_name(path: Path | None, label: str) -> str:
    """The file's stem, or its folder's name for a file called ``imu.parquet``; the label without a file."""
    stem = path.name if path is not None else label
    for suffix in (".parquet", ".pq", ".csv"):
        if stem.lower().endswith(suffix):
            stem = stem[: -len(suffix)]
    if path is not None and stem == "imu" and path.parent.name:
        stem = path.parent.name
    return stem


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
    p = Path(path)
    label = str(path)
    require_regular(p, label)
    check_complete(p)  # a log whose output set an interrupted `simulate` left unfinished (docs/outputs.md)
    suffix = p.suffix.lower()
    source: LogSource
    if format is not None:
        source = open_formatted(p, label, load_log_format(format), require_temperature)
    elif suffix in (".parquet", ".pq"):
        source = open_parquet(p, label, require_temperature)
    elif suffix == ".csv":
        source = open_csv(p, label, require_temperature)
    else:
        raise LogError(f"{label}: unknown log format {p.suffix!r} (expected .parquet, .pq or .csv)")
    return ImuLog(source, site=site)
