"""What every IMU log reader shares: the source interface, the raw block it yields, the header, rate and site checks.

A reader (`gyrodrift.logs.parquet`, `.csv`, `.formatted`, `.memory`, or a scenario simulated on the fly in
`gyrodrift.ins.simulate`) opens its data into a `LogSource`: what the source says about itself (kind, columns,
sample rate, size, site, truth) and how to read it (`LogSource.blocks`, unchecked `RawBlock`s) and name a place in
it (`LogSource.where`). `gyrodrift.logs.log.ImuLog` checks those blocks row by row and streams them.
"""

from __future__ import annotations

import math
import os
import stat
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from gyrodrift import _core
from gyrodrift.errors import InputError, OptionError
from gyrodrift.logs.columns import INCREMENT_COLUMNS, RATE_COLUMNS, REF_HEIGHT_COLUMN, TEMPERATURE, TIME, TRUTH_COLUMNS
from gyrodrift.site import Site

__all__ = [
    "LogError",
    "LogTruth",
    "Provenance",
    "SampleRate",
    "RawBlock",
    "Layout",
    "LogSource",
    "MIN_RATE_HZ",
    "MAX_RATE_HZ",
    "DEFAULT_CHUNK_SAMPLES",
    "check_rate",
    "rate_from_times",
    "merge_site",
    "require_regular",
    "recut",
    "require_cells",
    "short",
]

MIN_RATE_HZ = float(_core.MIN_RATE_HZ)
"""Smallest accepted sample rate [Hz] (the core's limit)."""
MAX_RATE_HZ = float(_core.MAX_RATE_HZ)
"""Largest accepted sample rate [Hz] (the core's limit)."""
DEFAULT_CHUNK_SAMPLES = 100_000
"""Samples per chunk: 1000 s at 100 Hz, about 7 MB of float64 columns."""
RATE_PROBE = 1000
"""Time steps whose median gives the sample rate of a log without a rate in its metadata."""

_SITE_LIMITS = {  # key: (low, high, option, unit), inclusive, the core's limits
    "lat_deg": (-float(_core.MAX_LAT_DEG), float(_core.MAX_LAT_DEG), "--lat0-deg", "deg"),
    "lon_deg": (-float(_core.MAX_LON_DEG), float(_core.MAX_LON_DEG), "--lon0-deg", "deg"),
    "height_m": (float(_core.MIN_HEIGHT_M), float(_core.MAX_HEIGHT_M), "--height-m", "m"),
}
_FORMAT_HINT = (
    "; a log with other column names, units or axes: describe the file's own columns with a log format "
    "(--format FILE, docs/procedure.md)"
)


class LogError(InputError):
    """An IMU log that cannot be used; the message starts with the file (and row and column when known)."""


@dataclass(frozen=True)
class LogTruth:
    """The true attitude of a simulated run at t = 0 (table angle 0) [deg]: pitch, roll, yaw (counter-clockwise
    about Up)."""

    pitch_deg: float
    roll_deg: float
    yaw_deg: float


@dataclass(frozen=True)
class Provenance:
    """What a source says about the run it holds (each None when it does not say): the true static site, the true
    initial attitude and the length of the static part at its start [s] (a simulated moving base's ``static_h``)."""

    site: Site | None = None
    truth: LogTruth | None = None
    static_s: float | None = None


@dataclass(frozen=True)
class SampleRate:
    """A log's sample rate [Hz] and where it comes from: "metadata", "time stamps", "scenario" or "given"."""

    hz: float
    source: str


@dataclass(frozen=True)
class RawBlock:
    """One block of a source before the checks: the columns as numpy arrays (units of the log's kind)."""

    t: np.ndarray
    sensors: tuple[np.ndarray, ...]  # six (n,) arrays, or (gyro (n, 3), accel (n, 3)) from the core
    temp: np.ndarray | None
    truth: tuple[np.ndarray, ...] | None
    ref_height: np.ndarray | None = None
    table_angle_deg: np.ndarray | None = None

    def cut(self, n: int) -> RawBlock:
        """The first `n` samples (views)."""
        return RawBlock(
            self.t[:n],
            tuple(a[:n] for a in self.sensors),
            None if self.temp is None else self.temp[:n],
            None if self.truth is None else tuple(a[:n] for a in self.truth),
            None if self.ref_height is None else self.ref_height[:n],
            None if self.table_angle_deg is None else self.table_angle_deg[:n],
        )


@dataclass(frozen=True)
class Layout:
    """The columns a log holds: its kind, its six sensor columns and which optional columns it has."""

    kind: str  # "increments" or "rates"
    columns: tuple[str, ...]  # the six sensor columns (gyro x y z, then accel x y z)
    has_temperature: bool = True
    has_truth_columns: bool = False
    has_reference_height: bool = False

    @classmethod
    def of_kind(cls, kind: str, **optional: bool) -> Layout:
        """The layout of a log of `kind` (``increments`` or ``rates``) with the reader's column names."""
        return cls(kind, INCREMENT_COLUMNS if kind == "increments" else RATE_COLUMNS, **optional)

    @classmethod
    def from_header(cls, names: list[str], label: str, *, require_temperature: bool, file: bool = True) -> Layout:
        """The layout a header gives (see `gyrodrift.logs`); `LogError` for a duplicated or missing column (with
        the ``--format`` hint for a `file`), or no ``temp_c`` when `require_temperature`."""
        hint = _FORMAT_HINT if file else ""
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise LogError(
                f"{label}, row 1: column {', '.join(dup)} appears more than once; column names must be unique"
            )
        if TIME.name not in names:
            raise LogError(f"{label}, row 1: missing column t_s (sample end time, s){hint}")
        if all(c in names for c in INCREMENT_COLUMNS):
            kind = "increments"
        elif all(c in names for c in RATE_COLUMNS):
            kind = "rates"
        else:
            inc = [c for c in INCREMENT_COLUMNS if c not in names]
            rat = [c for c in RATE_COLUMNS if c not in names]
            missing = inc if len(inc) <= len(rat) else rat
            raise LogError(
                f"{label}, row 1: missing column(s) {', '.join(missing)}: a log needs the increments "
                f"{', '.join(INCREMENT_COLUMNS)} or the rates {', '.join(RATE_COLUMNS)}{hint}"
            )
        if require_temperature and TEMPERATURE.name not in names:
            raise LogError(f"{label}, row 1: missing column temp_c (system temperature, deg C; the features need it)")
        return cls.of_kind(
            kind,
            has_temperature=TEMPERATURE.name in names,
            has_truth_columns=all(c in names for c in TRUTH_COLUMNS),
            has_reference_height=REF_HEIGHT_COLUMN in names,
        )

    def wanted(self) -> list[str]:
        """The columns to read, with the reader's names: time, sensors, then the optional ones the log has."""
        return [
            TIME.name,
            *self.columns,
            *([TEMPERATURE.name] if self.has_temperature else []),
            *(TRUTH_COLUMNS if self.has_truth_columns else ()),
            *([REF_HEIGHT_COLUMN] if self.has_reference_height else []),
        ]

    def from_table(
        self, table: pa.Table | pa.RecordBatch, source: LogSource, first: int, raw_names: Mapping[str, str]
    ) -> RawBlock:
        """The block of the `wanted` columns of `table` (rows `first`...; a column named ``raw_names[name]`` in the
        file when given there), as float64; `LogError` at the first empty cell."""
        arrays = {}
        for name in self.wanted():
            col = table.column(raw_names.get(name, name))
            require_cells(col, source, first, name)
            arrays[name] = np.asarray(col.to_numpy(zero_copy_only=False), dtype=np.float64)
        return self.raw_block(arrays)

    def raw_block(self, arrays: Mapping[str, np.ndarray]) -> RawBlock:
        """The block of `arrays` (the `wanted` columns by name)."""
        return RawBlock(
            arrays[TIME.name],
            tuple(arrays[c] for c in self.columns),
            arrays[TEMPERATURE.name] if self.has_temperature else None,
            tuple(arrays[c] for c in TRUTH_COLUMNS) if self.has_truth_columns else None,
            arrays[REF_HEIGHT_COLUMN] if self.has_reference_height else None,
        )


@dataclass(frozen=True, kw_only=True)
class LogSource:
    """An opened source of IMU samples: what it says about itself, and how to read and name its rows.

    A file source holds only its file name and a few numbers, so it pickles cheaply (dask workers reopen the
    file themselves). Subclasses set their `format` and implement `blocks`; a file whose rows or columns are named
    otherwise than by the 1-based sample index and the reader's column name overrides `row` and `column_label`.
    """

    label: str  # what messages call the source (the path, ``<memory>``, ``<scenario>``)
    layout: Layout
    rate: SampleRate
    n_samples: int
    path: Path | None = None  # the file, None for in-memory and simulated sources
    provenance: Provenance = Provenance()
    format: str = ""  # "parquet", "csv", "memory" or "scenario"
    name: str | None = None  # the run name, when not the file's
    scenario: Any = field(default=None, compare=False)  # the scenario simulated on the fly (its route), else None

    def blocks(self, chunk_samples: int) -> Iterator[RawBlock]:
        """Unchecked blocks of `chunk_samples` samples (the last one shorter) from the start."""
        raise NotImplementedError

    def row(self, index: int) -> int:
        """The row that messages name for 0-based sample `index` (the 1-based sample index)."""
        return index + 1

    def column_label(self, column: str) -> str:
        """What messages call the reader's column (or quantity) `column`."""
        return column

    def where(self, index: int, column: str | None = None) -> str:
        """``label, row R, column C`` for 0-based sample `index`."""
        shown = "" if column is None else f", column {self.column_label(column)}"
        return f"{self.label}, row {self.row(index)}{shown}"

    def channels(self, sensor: str, body: tuple[int, ...], axes: bool = False, up_note: str = "") -> str:
        """What a user checks when a plausibility check of `sensor` (``gyro`` or ``accel``) on body axes `body`
        fails: the columns (a log format's keys, and its ``[axes]`` when `axes`); `up_note` says what the up axis
        is checked for."""
        note = f"; {up_note}" if up_note else ""
        k = 0 if sensor == "gyro" else 3
        cols = ", ".join(self.layout.columns[k + j] + (note if j == 2 else "") for j in body)
        hint = (
            "; a log in other units or axes needs a log format (--format FILE, docs/procedure.md)"
            if self.path is not None
            else ""
        )
        return f"column(s) {cols} (body {', '.join(('right', 'forward', 'up')[j] for j in body)}){hint}"


def short(exc: BaseException | str) -> str:
    """A message on one line of at most 200 characters."""
    text = " ".join(str(exc).split())
    return text if len(text) <= 200 else text[:197] + "..."


def check_rate(rate: Any, label: str, what: str = "sample rate") -> float:
    """`rate` [Hz] as a float within [`MIN_RATE_HZ`, `MAX_RATE_HZ`]; `LogError` naming `what` otherwise."""
    if isinstance(rate, bool) or not isinstance(rate, (int, float, np.integer, np.floating)):
        raise LogError(f"{label}: {what} must be a number in Hz, got {rate!r}")
    try:
        r = float(rate)
    except OverflowError:
        r = math.inf
    if not (math.isfinite(r) and MIN_RATE_HZ <= r <= MAX_RATE_HZ):
        raise LogError(f"{label}: {what} must be in [{MIN_RATE_HZ:g}, {MAX_RATE_HZ:g}] Hz, got {rate!r}")
    return r


def rate_from_times(t: np.ndarray, label: str) -> SampleRate:
    """The sample rate of time stamps `t` [s]: 1 / their median step [Hz], rounded to 9 significant digits."""
    dt = np.diff(t)
    if len(dt) < 1 or not np.all(np.isfinite(dt)):
        raise LogError(f"{label}: cannot tell the sample rate (fewer than two finite time stamps)")
    med = float(np.median(dt))
    if not med > 0.0:
        raise LogError(f"{label}: cannot tell the sample rate (time stamps do not increase)")
    # 9 significant digits: differences of decimal time stamps make 9.99999999999998 Hz of a 10 Hz log, and the
    # navigation would then differ (by 1e-13 deg) from the same log whose metadata says 10.
    return SampleRate(check_rate(float(f"{1.0 / med:.9g}"), label, "the sample rate of the time stamps"), "time stamps")


def merge_site(given: Site | Mapping[str, float] | None, from_source: Site | None, label: str) -> Site | None:
    """A `Site` replaces the source's; a mapping overrides only the keys it has (lon 0, height 0 by default).

    Every value must lie within the core's limits: `OptionError` naming the option for a given value, `LogError`
    naming the file for the source's own.
    """
    given_keys: set[str] = set()
    if given is None:
        site = from_source
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
        if "lat_deg" not in given and from_source is None:
            raise LogError(f"{label}: the log carries no site; give its latitude (--lat0-deg / site=)")
        given_keys = set(given)
        base = from_source or Site(math.nan, 0.0, 0.0)
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


def require_regular(path: Path | None, label: str) -> None:
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


def recut(
    batches: Iterator[pa.RecordBatch],
    chunk_samples: int,
    convert: Callable[[pa.Table | pa.RecordBatch, int], RawBlock],
    problem: Callable[[BaseException, int], LogError],
) -> Iterator[RawBlock]:
    """Blocks of exactly `chunk_samples` rows (the last one shorter) from record batches of any size, each
    ``convert(table, index of its first row)``; a read error becomes ``problem(exc, rows_read_so_far)``."""
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
            raw = convert(batch, done)
            done += chunk_samples
            del batch
            yield raw
            continue
        pending.append(batch)
        size += batch.num_rows
        while size >= chunk_samples:
            table = pa.Table.from_batches(pending)
            raw = convert(table.slice(0, chunk_samples), done)
            done += chunk_samples
            rest = table.slice(chunk_samples)
            pending = rest.to_batches()
            size = rest.num_rows
            del table, rest
            yield raw
    if size:
        yield convert(pa.Table.from_batches(pending), done)


def require_cells(col: pa.ChunkedArray | pa.Array, source: LogSource, first: int, column: str) -> None:
    """`LogError` at the first empty cell of `col` (rows `first`...), naming `column`."""
    if col.null_count:
        i = int(np.flatnonzero(np.asarray(col.is_null().to_numpy(zero_copy_only=False)))[0])
        raise LogError(f"{source.where(first + i, column)}: empty or NaN cell")
