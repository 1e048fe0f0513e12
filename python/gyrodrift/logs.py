"""IMU logs of static-base runs: open, detect the sample rate, stream and validate (Parquet or CSV).

A log is one row per IMU sample, body frame x right, y forward, z up (z = turntable = axial axis). Two
formats, told apart by the file suffix (``.parquet`` / ``.pq`` or ``.csv``):

* Parquet: the simulator's own ``imu.parquet`` (docs/scenarios.md) or any file with the same columns.
* CSV: UTF-8, comma separated, one header row. Columns (order free, extra columns ignored):

  ============================================  ======  ==============================================
  ``t_s``                                       s       end time of the sample, strictly increasing
  ``dtheta_x_rad``, ``dtheta_y_rad``,           rad     angle increments over the sample        } or
  ``dtheta_z_rad``                                                                                }
  ``dv_x_m_s``, ``dv_y_m_s``, ``dv_z_m_s``      m/s     velocity (specific-force) increments    }
  ``gyro_x_rad_s``, ``gyro_y_rad_s``,           rad/s   angular rates, mean over the sample     } or
  ``gyro_z_rad_s``                                                                                }
  ``accel_x_m_s2``, ``accel_y_m_s2``,           m/s^2   specific force, mean over the sample    }
  ``accel_z_m_s2``
  ``temp_c``                                    deg C   system temperature (required)
  ============================================  ======  ==============================================

  The header decides: all six increment columns -> ``kind = "increments"``; else all six rate columns ->
  ``kind = "rates"`` (converted to increments as rate / rate_hz, i.e. the rate is the mean over the
  nominal sample interval ending at ``t_s``). Parquet files may use either set too.

Sample rate: the ``gyrodrift.rate_hz`` metadata of a Parquet file, otherwise 1 / median(dt) over the first
1000 intervals. Every chunk is checked while it streams (a log is never loaded whole; an 88 h log at
200 Hz is 63 million rows), and the first problem raises `LogError` naming the file, row and column:

* time not strictly increasing (duplicated or going back), a gap (an interval off the nominal
  1 / rate_hz by more than 1 %), NaN or empty cells, impossible magnitudes (|rate| > 1000 deg/s,
  |specific force| > 100 g on any axis), a missing column (``temp_c`` included).

Row numbers: for CSV the line of the file (the header is row 1, the first sample row 2, as in
`gyrodrift.runs`); for Parquet the 1-based sample index.

The true static site (latitude, longitude, height) comes from the Parquet metadata ``gyrodrift.site``
when present; otherwise the caller gives it (`open_log(..., site=...)`).
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa

from gyrodrift.errors import InputError

__all__ = [
    "LogError",
    "Site",
    "LogChunk",
    "ImuLog",
    "open_log",
    "INCREMENT_COLUMNS",
    "RATE_COLUMNS",
    "MAX_RATE_DEG_S",
    "MAX_SPECIFIC_FORCE_G",
    "GAP_TOLERANCE",
]

INCREMENT_COLUMNS = ("dtheta_x_rad", "dtheta_y_rad", "dtheta_z_rad", "dv_x_m_s", "dv_y_m_s", "dv_z_m_s")
"""Increment columns: angle [rad] then velocity [m/s] increments over the sample, body x y z."""
RATE_COLUMNS = ("gyro_x_rad_s", "gyro_y_rad_s", "gyro_z_rad_s", "accel_x_m_s2", "accel_y_m_s2", "accel_z_m_s2")
"""Rate columns: angular rate [rad/s] then specific force [m/s^2], body x y z."""
MAX_RATE_DEG_S = 1000.0
"""Largest plausible angular rate [deg/s] on any axis."""
MAX_SPECIFIC_FORCE_G = 100.0
"""Largest plausible specific force [g = 9.80665 m/s^2] on any axis."""
GAP_TOLERANCE = 0.01
"""Largest relative deviation of a time step from the nominal 1 / rate_hz."""

_G0 = 9.80665
_RATE_PROBE = 1000


class LogError(InputError):
    """An IMU log that cannot be used; the message starts with the file (and row and column when known)."""


@dataclass(frozen=True)
class Site:
    """A static site, WGS-84 geodetic: latitude and longitude [deg], height above the ellipsoid [m]."""

    lat_deg: float
    lon_deg: float = 0.0
    height_m: float = 0.0


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
    temp_c : ndarray (n,)
        System temperature [deg C].
    """

    first_index: int
    t_s: np.ndarray
    dtheta_rad: np.ndarray
    dv_m_s: np.ndarray
    temp_c: np.ndarray

    def __len__(self) -> int:
        return len(self.t_s)

    def slice(self, a: int, b: int) -> LogChunk:
        """Samples a..b-1 of the chunk (views)."""
        return LogChunk(self.first_index + a, self.t_s[a:b], self.dtheta_rad[a:b], self.dv_m_s[a:b], self.temp_c[a:b])


def _is_parquet(path: Path) -> bool:
    return path.suffix.lower() in (".parquet", ".pq")


def _kind_from_header(names: list[str], label: str) -> tuple[str, tuple[str, ...]]:
    if "t_s" not in names:
        raise LogError(f"{label}, row 1: missing column t_s (sample end time, s)")
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
            f"{', '.join(INCREMENT_COLUMNS)} or the rates {', '.join(RATE_COLUMNS)}"
        )
    if "temp_c" not in names:
        raise LogError(f"{label}, row 1: missing column temp_c (system temperature, deg C; the features need it)")
    return kind, cols


class ImuLog:
    """An opened IMU log: format, kind, sample rate, size and site; `chunks` streams validated samples.

    Use `open_log` to create one. The object holds only the file name and a few numbers, so it pickles
    cheaply (dask workers reopen the file themselves).

    Attributes
    ----------
    path : pathlib.Path
    name : str
        The file's stem (used as the run name), or its folder's name for a file called ``imu.parquet``.
    format : {"parquet", "csv"}
    kind : {"increments", "rates"}
    rate_hz : float
        Sample rate [Hz].
    n_samples : int or None
        Number of samples (Parquet: exact; CSV: estimated from the first and last time stamps).
    duration_s : float
        n_samples / rate_hz [s].
    site : Site or None
        The true static site when the file says it (Parquet metadata) or the caller gave it.
    """

    def __init__(
        self,
        path: Path,
        fmt: str,
        kind: str,
        columns: tuple[str, ...],
        rate_hz: float,
        n_samples: int,
        site: Site | None,
        rate_source: str,
    ):
        self.path = path
        self.format = fmt
        self.kind = kind
        self._columns = columns
        self.rate_hz = float(rate_hz)
        self.n_samples = int(n_samples)
        self.site = site
        self.rate_source = rate_source
        stem = path.name
        for suffix in (".parquet", ".pq", ".csv"):
            if stem.lower().endswith(suffix):
                stem = stem[: -len(suffix)]
        if stem == "imu" and path.parent.name:
            stem = path.parent.name
        self.name = stem

    def __repr__(self) -> str:
        return (
            f"ImuLog({str(self.path)!r}, format={self.format!r}, kind={self.kind!r}, rate_hz={self.rate_hz:g}, "
            f"n_samples={self.n_samples}, site={self.site})"
        )

    @property
    def duration_s(self) -> float:
        """Length of the log [s] (n_samples / rate_hz)."""
        return self.n_samples / self.rate_hz

    def samples_for(self, seconds: float) -> int:
        """Number of samples spanning `seconds` [s] at the log's rate (rounded)."""
        return int(round(seconds * self.rate_hz))

    def require_duration(self, seconds: float, what: str) -> None:
        """Raise `LogError` if the log is shorter than `seconds` [s] (what: why that much is needed)."""
        if self.n_samples < self.samples_for(seconds):
            raise LogError(
                f"{self.path}: the log lasts {self.duration_s / 3600.0:.3f} h; {what} takes at least "
                f"{seconds / 3600.0:g} h"
            )

    # ------------------------------------------------------------------------------------------
    # Streaming
    # ------------------------------------------------------------------------------------------
    def chunks(self, chunk_samples: int = 100_000, stop: int | None = None) -> Iterator[LogChunk]:
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
        if chunk_samples < 1:
            raise ValueError(f"chunk_samples must be >= 1, got {chunk_samples}")
        validator = _Validator(self)
        done = 0
        for table in self._tables(chunk_samples):
            n = table.num_rows
            if stop is not None and done + n > stop:
                table = table.slice(0, stop - done)
                n = table.num_rows
            chunk = validator.check(table, done)
            done += n
            yield chunk
            if stop is not None and done >= stop:
                return
        if stop is not None and done < stop:
            raise LogError(
                f"{self.path}: the log ends after {done} samples ({done / self.rate_hz / 3600.0:.3f} h); "
                f"{stop} samples ({stop / self.rate_hz / 3600.0:.3f} h) are needed"
            )

    def _tables(self, chunk_samples: int) -> Iterator[pa.Table]:
        cols = ["t_s", *self._columns, "temp_c"]
        if self.format == "parquet":
            import pyarrow.parquet as pq

            pf = pq.ParquetFile(self.path)
            for batch in pf.iter_batches(batch_size=chunk_samples, columns=cols):
                yield pa.Table.from_batches([batch])
            return
        import pyarrow.csv as pcsv

        types = {c: pa.float64() for c in cols}
        try:
            reader = pcsv.open_csv(
                self.path,
                read_options=pcsv.ReadOptions(block_size=1 << 22),
                convert_options=pcsv.ConvertOptions(column_types=types, include_columns=cols),
            )
        except pa.ArrowInvalid as exc:
            raise _csv_conversion_error(self.path, str(exc)) from None
        pending: list[pa.RecordBatch] = []
        size = 0
        try:
            for batch in reader:
                pending.append(batch)
                size += batch.num_rows
                while size >= chunk_samples:
                    table = pa.Table.from_batches(pending)
                    yield table.slice(0, chunk_samples)
                    rest = table.slice(chunk_samples)
                    pending = rest.to_batches()
                    size = rest.num_rows
        except pa.ArrowInvalid as exc:
            raise _csv_conversion_error(self.path, str(exc)) from None
        if size:
            yield pa.Table.from_batches(pending)


class _Validator:
    """Checks chunks one after the other, carrying the last time stamp across chunk boundaries."""

    def __init__(self, log: ImuLog):
        self.log = log
        self.dt = 1.0 / log.rate_hz
        self.prev_t: float | None = None
        self.row_offset = 2 if log.format == "csv" else 1
        self.max_rate = MAX_RATE_DEG_S * math.pi / 180.0
        self.max_force = MAX_SPECIFIC_FORCE_G * _G0

    def where(self, index: int, column: str) -> str:
        return f"{self.log.path}, row {index + self.row_offset}, column {column}"

    def check(self, table: pa.Table, first: int) -> LogChunk:
        log = self.log
        arrays: dict[str, np.ndarray] = {}
        for name in ["t_s", *log._columns, "temp_c"]:
            col = table.column(name)
            if col.null_count:
                i = int(np.flatnonzero(np.asarray(col.is_null().to_numpy(zero_copy_only=False)))[0])
                raise LogError(f"{self.where(first + i, name)}: empty or NaN cell")
            a = np.asarray(col.to_numpy(zero_copy_only=False), dtype=np.float64)
            bad = ~np.isfinite(a)
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                if np.isnan(a[i]):
                    raise LogError(f"{self.where(first + i, name)}: empty or NaN cell")
                raise LogError(f"{self.where(first + i, name)}: expected a finite number, got {float(a[i])!r}")
            arrays[name] = a
        t = arrays["t_s"]
        full = t if self.prev_t is None else np.concatenate([[self.prev_t], t])
        dt = np.diff(full)
        off = 0 if self.prev_t is None else 1  # dt[k] ends at sample first + k + 1 - off
        if len(dt):
            back = dt <= 0.0
            if back.any():
                k = int(np.flatnonzero(back)[0])
                i = first + k + 1 - off
                what = "duplicated time stamp" if dt[k] == 0.0 else "time goes backwards"
                raise LogError(
                    f"{self.where(i, 't_s')}: {what} ({float(full[k + 1])!r} s after {float(full[k])!r} s); "
                    "time must be strictly increasing"
                )
            gap = np.abs(dt - self.dt) > GAP_TOLERANCE * self.dt
            if gap.any():
                k = int(np.flatnonzero(gap)[0])
                i = first + k + 1 - off
                raise LogError(
                    f"{self.where(i, 't_s')}: gap in time: step {dt[k]:.6g} s from {float(full[k])!r} s, expected "
                    f"{self.dt:.6g} s (rate {log.rate_hz:g} Hz, tolerance {GAP_TOLERANCE:.0%})"
                )
        self.prev_t = float(t[-1]) if len(t) else self.prev_t
        scale = log.rate_hz if log.kind == "increments" else 1.0
        for j, name in enumerate(log._columns):
            limit = self.max_rate if j < 3 else self.max_force
            mag = np.abs(arrays[name]) * scale
            over = mag > limit
            if over.any():
                i = int(np.flatnonzero(over)[0])
                if j < 3:
                    msg = f"angular rate {mag[i] * 180.0 / math.pi:.6g} deg/s exceeds {MAX_RATE_DEG_S:g} deg/s"
                else:
                    msg = f"specific force {mag[i] / _G0:.6g} g exceeds {MAX_SPECIFIC_FORCE_G:g} g"
                raise LogError(f"{self.where(first + i, name)}: impossible magnitude: {msg}")
        gyro = np.column_stack([arrays[c] for c in log._columns[:3]])
        acc = np.column_stack([arrays[c] for c in log._columns[3:]])
        if log.kind == "rates":
            gyro = gyro * self.dt
            acc = acc * self.dt
        return LogChunk(first, t, gyro, acc, arrays["temp_c"])


def _csv_conversion_error(path: Path, message: str) -> LogError:
    """Turn pyarrow's 'CSV column #k: ... invalid value' into a file/row/column message (scans the file)."""
    m = re.search(r"invalid value '([^']*)'", message)
    value = m.group(1) if m else None
    with open(path, newline="", encoding="utf-8-sig") as fh:
        reader = csv.reader(fh)
        header = [h.strip() for h in next(reader)]
        for rownum, row in enumerate(reader, start=2):
            for name, cell in zip(header, row, strict=False):
                if value is not None and cell.strip() != value:
                    continue
                try:
                    float(cell)
                except ValueError:
                    if name in ("t_s", "temp_c") or name in INCREMENT_COLUMNS or name in RATE_COLUMNS:
                        return LogError(f"{path}, row {rownum}, column {name}: expected a number, got {cell!r}")
    return LogError(f"{path}: unreadable CSV ({message})")


def _read_site(meta: Mapping[str, str], label: str) -> Site | None:
    if "gyrodrift.site" not in meta:
        return None
    try:
        s = json.loads(meta["gyrodrift.site"])
        return Site(float(s["lat_deg"]), float(s["lon_deg"]), float(s["height_m"]))
    except (ValueError, KeyError, TypeError) as exc:
        raise LogError(f"{label}: unreadable gyrodrift.site metadata ({exc})") from None


def _rate_from_times(t: np.ndarray, label: str) -> float:
    dt = np.diff(t)
    if len(dt) < 1 or not np.all(np.isfinite(dt)):
        raise LogError(f"{label}: cannot tell the sample rate (fewer than two finite time stamps)")
    med = float(np.median(dt))
    if not med > 0.0:
        raise LogError(f"{label}: cannot tell the sample rate (time stamps do not increase)")
    return 1.0 / med


def _csv_head_and_tail(path: Path, label: str) -> tuple[list[str], np.ndarray, float | None]:
    """Header names, the first time stamps, and the last time stamp (read from the file's end)."""
    with open(path, newline="", encoding="utf-8-sig") as fh:
        reader = csv.reader(fh)
        try:
            header = [h.strip() for h in next(reader)]
        except StopIteration:
            raise LogError(f"{label}: empty file, expected a header row") from None
        if "t_s" not in header:
            return header, np.zeros(0), None
        it = header.index("t_s")
        times = []
        for rownum, row in enumerate(reader, start=2):
            if len(times) > _RATE_PROBE:
                break
            try:
                times.append(float(row[it]))
            except (ValueError, IndexError):
                raise LogError(
                    f"{label}, row {rownum}, column t_s: expected a number, got {row[it] if it < len(row) else ''!r}"
                ) from None
    last = None
    with open(path, "rb") as fh:
        fh.seek(0, os.SEEK_END)
        size = fh.tell()
        fh.seek(max(0, size - 65536))
        lines = [ln for ln in fh.read().decode("utf-8", "replace").splitlines() if ln.strip()]
    if lines:
        cells = next(csv.reader(io.StringIO(lines[-1])))
        try:
            last = float(cells[it])
        except (ValueError, IndexError):
            last = None
    return header, np.asarray(times, dtype=float), last


def _merge_site(given: Site | Mapping[str, float] | None, from_file: Site | None, label: str) -> Site | None:
    """A full `Site` replaces the file's; a mapping overrides only the keys it has (lon 0, height 0 by default)."""
    if given is None:
        return from_file
    if isinstance(given, Site):
        site = given
    else:
        unknown = set(given) - {"lat_deg", "lon_deg", "height_m"}
        if unknown:
            raise ValueError(f"site: unknown key(s) {sorted(unknown)} (expected lat_deg, lon_deg, height_m)")
        base = from_file or Site(math.nan)
        site = Site(
            float(given.get("lat_deg", base.lat_deg)),
            float(given.get("lon_deg", base.lon_deg)),
            float(given.get("height_m", base.height_m)),
        )
        if not math.isfinite(site.lat_deg):
            raise LogError(f"{label}: the log carries no site; give its latitude (lat_deg / --lat0-deg)")
    if not (-90.0 < site.lat_deg < 90.0) or not math.isfinite(site.lon_deg) or not math.isfinite(site.height_m):
        raise LogError(f"{label}: site {site} is not a valid static position (latitude strictly within +-90 deg)")
    return site


def open_log(path: str | os.PathLike[str], *, site: Site | Mapping[str, float] | None = None) -> ImuLog:
    """Open an IMU log, check its header, detect its kind and sample rate.

    Parameters
    ----------
    path : path-like
        ``.parquet``/``.pq`` or ``.csv`` file (see the module docstring for the columns).
    site : Site or mapping, optional
        The true static site (``lat_deg``, ``lon_deg`` [deg], ``height_m`` [m]). A `Site` replaces the file's
        metadata; a mapping overrides only the keys it gives (the rest from the file, else lon 0, height
        0). CSV files carry no site, so the procedure needs at least the latitude from here.

    Returns
    -------
    ImuLog

    Raises
    ------
    LogError
        Missing file, unreadable file, missing columns, no detectable rate. Row-level problems are found
        while streaming (`ImuLog.chunks`).
    """
    p = Path(path)
    label = str(path)
    if not p.exists():
        raise LogError(f"{label}: no such file")
    if _is_parquet(p):
        import pyarrow.parquet as pq

        try:
            pf = pq.ParquetFile(p)
        except (pa.ArrowInvalid, OSError) as exc:
            raise LogError(f"{label}: not a Parquet file ({exc})") from None
        names = pf.schema_arrow.names
        kind, cols = _kind_from_header(names, label)
        meta = {k.decode(): v.decode() for k, v in (pf.schema_arrow.metadata or {}).items()}
        n = pf.metadata.num_rows
        if n < 2:
            raise LogError(f"{label}: {n} sample(s); a log needs many")
        file_site = _read_site(meta, label)
        rate_source = "metadata"
        try:
            rate = float(json.loads(meta["gyrodrift.rate_hz"])) if "gyrodrift.rate_hz" in meta else None
        except (ValueError, TypeError):
            raise LogError(f"{label}: unreadable gyrodrift.rate_hz metadata") from None
        if rate is None:
            head = next(pf.iter_batches(batch_size=_RATE_PROBE + 1, columns=["t_s"]))
            rate = _rate_from_times(np.asarray(head.column(0).to_numpy(zero_copy_only=False), float), label)
            rate_source = "time stamps"
        if not (math.isfinite(rate) and rate > 0):
            raise LogError(f"{label}: sample rate must be > 0, got {rate!r}")
        return ImuLog(p, "parquet", kind, cols, rate, n, _merge_site(site, file_site, label), rate_source)
    if p.suffix.lower() != ".csv":
        raise LogError(f"{label}: unknown log format {p.suffix!r} (expected .parquet, .pq or .csv)")
    try:
        header, times, last = _csv_head_and_tail(p, label)
    except UnicodeDecodeError as exc:
        raise LogError(f"{label}: not UTF-8 text near byte {exc.start}; expected a CSV log") from None
    kind, cols = _kind_from_header(header, label)
    rate = _rate_from_times(times, label)
    if last is None or not last > times[0]:
        raise LogError(f"{label}: cannot read the last time stamp of the file")
    n = int(round((last - times[0]) * rate)) + 1
    return ImuLog(p, "csv", kind, cols, rate, n, _merge_site(site, None, label), "time stamps")
