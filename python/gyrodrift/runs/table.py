"""Tables of alignment runs: the identification inputs and, when known, the true axial drift.

A run is one initial alignment on a static base. The columns (name, unit, type, when needed, meaning) are declared
in `gyrodrift.runs.columns.RUN_TABLE` and listed in docs/outputs.md; `read_runs_csv` reads them and
`write_run_table` is the one writer of a run table (``features``, ``campaign --run-table``, `RunTable.to_csv`).

``label_flagged`` cells are ``true``/``false`` (or ``1``/``0``, any case; empty = unknown); a table keeps
the flag in ``extra`` as 1.0/0.0 (NaN unknown), written back as ``true``/``false``.

The latitude error used by the models is ``lat_deg - lat0_deg`` (computed minus true).
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gyrodrift.errors import InputError
from gyrodrift.files.atomic import atomic_write
from gyrodrift.files.input_files import read_limited
from gyrodrift.runs.columns import (
    ATTRIBUTE_COLUMNS,
    COLUMNS,
    FLAG_COLUMNS,
    KNOWN_COLUMNS,
    OPTIONAL_COLUMNS,
    RUN_TABLE,
    SMOOTHER_THERMAL_COLUMNS,
)

PAPER_LAT0_DEG = 28.222
"""Site latitude of the paper's experiments [deg] (Yu et al. 2013, section 3)."""

MAX_RUN_TABLE_BYTES = 1 << 30
"""Largest run table read [bytes] (a row of `features` is a few hundred bytes: millions of runs); a larger file is
refused after reading this much, never all of it."""

TEMPERATURE_LIMITS_C = (-100.0, 200.0)
"""Plausible system temperatures [deg C], inclusive: every reader (run tables, IMU logs) refuses the rest (a
kelvin value such as 303, or 1e6)."""

NAVIGATION_GRADE_DRIFT_DEG_H = 0.1
"""Largest axial drift [deg/h] of a navigation-grade RLG (`drift_range_problems`): its bias is at most about
0.01 deg/h (the 1 nmi/h class), the paper's 32 runs lie within +-0.0035 deg/h; ten times that bias is no
navigation-grade gyro (a tactical one drifts 1-10 deg/h). A table written in mdeg/h (0.2-3.5 for the paper's
runs) lies beyond it in every row. Drifts beyond 10 deg/h are refused outright as no RLG at all."""

_FLAG_TEXT = {"true": 1.0, "false": 0.0, "1": 1.0, "0": 0.0}


def _parse_flag(text: str, where: str, column: str) -> float:
    """A flag cell: ``true``/``false``/``1``/``0`` (any case) -> 1.0/0.0, empty -> NaN (unknown)."""
    if text == "":
        return math.nan
    value = _FLAG_TEXT.get(text.lower())
    if value is None:
        raise RunTableError(f"{where}, column {column}: expected true or false, got {text!r}")
    return value


class RunTableError(InputError):
    """A run table that cannot be read; the message names the file, row and column."""


@dataclass(frozen=True)
class RunTable:
    """Alignment runs as parallel arrays (one element per run).

    Attributes
    ----------
    run : ndarray of str
        Run identifiers.
    lat_deg : ndarray of float
        Latitude at the 12th hour of free navigation [deg].
    lat0_deg : ndarray of float
        True site latitude [deg].
    temp_min_c, temp_max_c : ndarray of float
        Temperature extremes over the 12 h [deg C].
    drift_deg_h : ndarray of float
        True axial drift [deg/h]; NaN where unknown.
    split : ndarray of str
        ``"train"``, ``"test"`` or ``""``.
    source : str
        Where the table came from (file name), for messages.
    extra : dict of str -> ndarray of float
        The ``OPTIONAL_COLUMNS`` the table has (NaN where a run has no value); :meth:`column` reads them.
    """

    run: np.ndarray
    lat_deg: np.ndarray
    lat0_deg: np.ndarray
    temp_min_c: np.ndarray
    temp_max_c: np.ndarray
    drift_deg_h: np.ndarray
    split: np.ndarray = field(default=None)  # type: ignore[arg-type]  # filled in by __post_init__
    source: str = "<memory>"
    extra: dict = field(default=None)  # type: ignore[arg-type]  # filled in by __post_init__

    def __post_init__(self):
        n = len(self.run)
        if self.split is None:
            object.__setattr__(self, "split", np.array([""] * n, dtype=object))
        extra = {} if self.extra is None else dict(self.extra)
        for name, values in extra.items():
            if name not in OPTIONAL_COLUMNS:
                raise RunTableError(f"{self.source}: unknown optional column {name!r}")
            extra[name] = np.asarray(values, dtype=float)
            if extra[name].shape != (n,):
                raise RunTableError(f"{self.source}: column {name} has {extra[name].size} values, run has {n}")
        object.__setattr__(self, "extra", {k: extra[k] for k in OPTIONAL_COLUMNS if k in extra})
        for name in ATTRIBUTE_COLUMNS:
            if len(getattr(self, name)) != n:
                raise RunTableError(f"{self.source}: column {name} has {len(getattr(self, name))} values, run has {n}")

    def __len__(self) -> int:
        return len(self.run)

    @property
    def shape(self) -> tuple[int]:
        """``(n_runs,)``: a table is a 1-D sequence of runs to scikit-learn (``cross_val_score``, ``GridSearchCV``)."""
        return (len(self),)

    def __getitem__(self, key) -> RunTable:
        """The runs selected by ``key`` (an index, a slice, an index array or a boolean mask) as a table.

        ``table[key, ...]`` (how scikit-learn's splitters index arrays) is the same as ``table[key]``.
        """
        if isinstance(key, tuple) and len(key) == 2 and key[1] is Ellipsis:
            key = key[0]
        if isinstance(key, (int, np.integer)):
            key = [int(key)]
        if not isinstance(key, slice):
            key = np.asarray(key)
            if key.dtype != bool and not np.issubdtype(key.dtype, np.integer):
                if key.size:
                    raise IndexError(f"runs are selected by integers, slices or boolean masks, got {key.dtype}")
                key = key.astype(int)
        return self.select(key)

    def to_structured(self) -> np.ndarray:
        """The table as a 1-D numpy structured array (fields ``ATTRIBUTE_COLUMNS``, then the optional columns
        the table has); see :func:`as_run_table`."""
        dtype = np.dtype(STRUCTURED_DTYPE.descr + [(name, float) for name in self.extra])
        out = np.empty(len(self), dtype=dtype)
        for name in ATTRIBUTE_COLUMNS:
            out[name] = getattr(self, name)
        for name, values in self.extra.items():
            out[name] = values
        return out

    def has_column(self, name: str) -> bool:
        """True when the table has optional column ``name`` with a value for every run."""
        return name in self.extra and bool(np.all(np.isfinite(self.extra[name])))

    def column(self, name: str) -> np.ndarray:
        """An optional column (``OPTIONAL_COLUMNS``; [deg/h], or 1.0/0.0 for a flag): NaN for every run when the
        table has none."""
        if name not in OPTIONAL_COLUMNS:
            raise RunTableError(
                f"{self.source}: unknown optional column {name!r}; expected one of {', '.join(OPTIONAL_COLUMNS)}"
            )
        return self.extra.get(name, np.full(len(self), np.nan))

    def replace(self, **changes) -> RunTable:
        """A copy with some columns replaced (keyword = attribute name, e.g. ``drift_deg_h=...``)."""
        values = {name: getattr(self, name) for name in (*ATTRIBUTE_COLUMNS, "source", "extra")}
        values.update(changes)
        return RunTable(**values)

    @classmethod
    def from_records(cls, records, *, source: str = "<records>") -> RunTable:
        """A table from ``records()``-style dicts, with the checks of :func:`read_runs_csv`.

        Each record needs ``lat_deg``, ``lat0_deg``, ``temp_min_c``, ``temp_max_c`` (numbers) and may have
        ``run`` (text), ``drift_deg_h`` (number) and ``split`` (``"train"``, ``"test"`` or ``""``). Raises
        :class:`RunTableError` naming ``source``, the record (1-based) and the key.
        """
        if not isinstance(records, list) or not records:
            raise RunTableError(f"{source}: expected a non-empty list of runs")
        cols: dict[str, list] = {name: [] for name in ATTRIBUTE_COLUMNS}
        extra: dict[str, list] = {}
        for i, rec in enumerate(records, start=1):
            where = f"{source}, run {i}"
            if not isinstance(rec, dict):
                raise RunTableError(f"{where}: expected an object with the run's values, got {type(rec).__name__}")
            unknown = sorted(set(rec) - set(ATTRIBUTE_COLUMNS) - set(OPTIONAL_COLUMNS))
            if unknown:
                raise RunTableError(f"{where}: unknown key {unknown[0]!r}")
            run = rec.get("run", str(i))
            if not isinstance(run, str):
                raise RunTableError(f"{where}, key run: expected text, got {type(run).__name__}")
            values = {}
            for key in _RECORD_NUMBERS:
                if key not in rec:
                    if key == "drift_deg_h":
                        values[key] = math.nan
                        continue
                    raise RunTableError(f"{where}: missing key {key!r}")
                values[key] = _record_number(rec[key], where, key)
            split = rec.get("split", "")
            _check_run_values(where, split=split, **values)
            cols["run"].append(run)
            cols["split"].append(split)
            for key, value in values.items():
                cols[key].append(value)
            for key in OPTIONAL_COLUMNS:
                if key in FLAG_COLUMNS and key in rec:
                    v = rec[key]
                    if v is not None and not isinstance(v, bool):
                        raise RunTableError(f"{where}, key {key}: expected true or false, got {v!r}")
                    extra.setdefault(key, [math.nan] * (i - 1)).append(math.nan if v is None else float(v))
                elif key in rec:
                    v = rec[key]
                    value = (
                        math.nan
                        if v is None or (isinstance(v, float) and math.isnan(v))
                        else (_record_number(v, where, key))
                    )
                    _check_optional(where, key, value)
                    extra.setdefault(key, [math.nan] * (i - 1)).append(value)
            for vals in extra.values():
                if len(vals) < i:
                    vals.append(math.nan)
        _check_unique_runs(cols["run"], source)
        return cls(
            run=np.array(cols["run"], dtype=object),
            lat_deg=np.array(cols["lat_deg"], dtype=float),
            lat0_deg=np.array(cols["lat0_deg"], dtype=float),
            temp_min_c=np.array(cols["temp_min_c"], dtype=float),
            temp_max_c=np.array(cols["temp_max_c"], dtype=float),
            drift_deg_h=np.array(cols["drift_deg_h"], dtype=float),
            split=np.array(cols["split"], dtype=object),
            source=source,
            extra={k: np.array(v, dtype=float) for k, v in extra.items()},
        )

    @property
    def lat_err_arcsec(self) -> np.ndarray:
        """Latitude error at 12 h, computed minus true [arcsec]."""
        return (self.lat_deg - self.lat0_deg) * 3600.0

    @property
    def has_truth(self) -> bool:
        """True when every run has a known drift."""
        return bool(np.all(np.isfinite(self.drift_deg_h)))

    def select(self, mask) -> RunTable:
        """The runs where ``mask`` is true (boolean array or indices)."""
        columns = {name: getattr(self, name)[mask] for name in ATTRIBUTE_COLUMNS}
        return RunTable(**columns, source=self.source, extra={k: v[mask] for k, v in self.extra.items()})

    def records(self) -> list[dict]:
        """One dict per run with unit-carrying keys (for JSON and CSV output)."""
        out = []
        for i in range(len(self)):
            rec = {
                "run": str(self.run[i]),
                "lat_deg": float(self.lat_deg[i]),
                "lat0_deg": float(self.lat0_deg[i]),
                "temp_min_c": float(self.temp_min_c[i]),
                "temp_max_c": float(self.temp_max_c[i]),
            }
            if math.isfinite(self.drift_deg_h[i]):
                rec["drift_deg_h"] = float(self.drift_deg_h[i])
            if self.split[i]:
                rec["split"] = str(self.split[i])
            for name, values in self.extra.items():
                if math.isfinite(values[i]):
                    rec[name] = bool(values[i]) if name in FLAG_COLUMNS else float(values[i])
            out.append(rec)
        return out

    def to_csv(self, path) -> None:
        """Write the table as a run-table CSV that `read_runs_csv` (and ``gyrodrift fit``/``predict``) reads back
        to an equal table (`write_run_table`): ``run, split, lat_deg, lat0_deg, temp_min_c, temp_max_c``, the
        optional columns the table has and ``drift_deg_h``, in the order of `gyrodrift.runs.columns.RUN_TABLE`.

        >>> import gyrodrift as gd
        >>> gd.load_paper().runs.to_csv("paper.csv")
        >>> read_runs_csv("paper.csv").select(gd.load_paper().runs.split == "test").run.tolist()[:3]
        ['23', '24', '25']
        """
        write_run_table(path, self.records(), (*ATTRIBUTE_COLUMNS, *self.extra))


STRUCTURED_DTYPE = np.dtype(  # the structured array of `RunTable.to_structured`
    [(name, float if COLUMNS[name].dtype == "float" else object) for name in ATTRIBUTE_COLUMNS]
)

_RECORD_NUMBERS = tuple(name for name in ATTRIBUTE_COLUMNS if COLUMNS[name].dtype == "float")
"""The numbers of a record (`RunTable.from_records`): each required but the last, the label ``drift_deg_h`` (NaN
when absent)."""


def as_run_table(X, *, source: str = "<array>") -> RunTable:
    """``X`` as a :class:`RunTable`: a table as it is, or a 1-D structured array with the fields
    ``lat_deg``, ``lat0_deg``, ``temp_min_c``, ``temp_max_c`` (and optionally ``run``, ``drift_deg_h``,
    ``split``), checked as :meth:`RunTable.from_records` checks records. Anything else is a
    :class:`RunTableError` saying what is expected."""
    if isinstance(X, RunTable):
        return X
    names = getattr(getattr(X, "dtype", None), "names", None)
    if not isinstance(X, np.ndarray) or names is None or X.ndim != 1:
        raise RunTableError(
            f"expected a RunTable or a 1-D structured array with fields {', '.join(_RECORD_NUMBERS[:-1])}, "
            f"got {type(X).__name__}"
        )
    records = []
    for row in X:
        rec = {}
        for name in names:
            value = row[name]
            if name in ("run", "split"):
                rec[name] = "" if value is None else str(value)
            else:
                rec[name] = value.item() if isinstance(value, np.generic) else value
        records.append(rec)
    return RunTable.from_records(records, source=source)


def _record_number(value, where: str, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise RunTableError(f"{where}, key {key}: expected a number, got {type(value).__name__}")
    try:
        as_float = float(value)
    except OverflowError:
        raise RunTableError(
            f"{where}, key {key}: expected a finite number, got an integer too large for a float"
        ) from None
    if not math.isfinite(as_float):
        raise RunTableError(f"{where}, key {key}: expected a finite number, got {as_float}")
    return as_float


def _check_run_values(
    where: str, *, lat_deg: float, lat0_deg: float, temp_min_c: float, temp_max_c: float, drift_deg_h: float, split
) -> None:
    """The value checks of one run (latitudes, temperatures, drift, split); ``where`` names it in messages."""
    for key, lat in (("lat_deg", lat_deg), ("lat0_deg", lat0_deg)):
        if not -90.0 <= lat <= 90.0:
            raise RunTableError(f"{where}, key {key}: expected a latitude within [-90, 90] deg, got {lat}")
    if temp_max_c < temp_min_c:
        raise RunTableError(
            f"{where}, key temp_max_c: maximum temperature {temp_max_c} is below the minimum {temp_min_c}"
        )
    t_low, t_high = TEMPERATURE_LIMITS_C
    for key, t in (("temp_min_c", temp_min_c), ("temp_max_c", temp_max_c)):
        if not t_low <= t <= t_high:
            raise RunTableError(f"{where}, key {key}: temperature {t} outside [{t_low:g}, {t_high:g}] deg C")
    if math.isfinite(drift_deg_h) and abs(drift_deg_h) > 10.0:
        raise RunTableError(
            f"{where}, key drift_deg_h: |{drift_deg_h}| deg/h is not an RLG drift (expected |drift| <= 10 deg/h)"
        )
    if split not in ("", "train", "test"):
        raise RunTableError(f"{where}, key split: expected 'train', 'test' or '', got {split!r}")


def _check_required(header: set[str], where: str, *, caller_gives: set[str], require_truth: bool) -> None:
    """The columns a header must have, as each `gyrodrift.runs.columns.RunColumn.required` says: ``always``, ``for
    fit`` (with `require_truth`), ``unless OTHER`` (the column OTHER replaces it and its group) or ``unless
    --OPTION`` (unless the caller gives its value: a name in `caller_gives`)."""
    for column in RUN_TABLE:
        need, c = column.required, column.name
        if not need or c in header:
            continue
        if need == "always" or (need == "for fit" and require_truth):
            purpose = " for training" if need == "for fit" else ""
            raise RunTableError(f"{where}: missing column {c!r} ({column.meaning}, {column.unit}){purpose}")
        instead = need.removeprefix("unless ")
        if instead.startswith("--") and c not in caller_gives:
            raise RunTableError(f"{where}: no {c} column; give {column.meaning} ({instead}, or {c}= in Python)")
        if instead in COLUMNS and instead not in header:
            group = " and ".join(n.name for n in RUN_TABLE if n.required == need)
            raise RunTableError(f"{where}: missing columns: expected {group}, or {instead}")


def _check_optional(where: str, key: str, value: float) -> None:
    """An optional column's value: NaN (unknown) or a drift-sized number (|value| <= 10 in its unit); a 1-sigma
    (`gyrodrift.runs.columns.RunColumn.sigma`) must be > 0."""
    if math.isnan(value):
        return
    unit = COLUMNS[key].unit
    if abs(value) > 10.0:
        raise RunTableError(
            f"{where}, column {key}: |{value}| {unit} is not an RLG {'drift' if unit == 'deg/h' else 'value'} "
            f"(expected |value| <= 10 {unit})"
        )
    if COLUMNS[key].sigma and not value > 0:
        raise RunTableError(f"{where}, column {key}: expected a 1-sigma > 0 {unit}, got {value}")


def drift_range_problems(drift_deg_h, labels_deg_h=None) -> list[str | None]:
    """Why each drift [deg/h] is implausible, or None: beyond a navigation-grade RLG's
    `NAVIGATION_GRADE_DRIFT_DEG_H`, or far outside the training labels `labels_deg_h` [deg/h] (beyond their range
    by more than its width: a model that extrapolates that far has left what it learned). Used by ``fit`` on its
    labels and by ``predict`` and ``identify`` on their drifts (flagged, not refused: the drift may be real)."""
    d = np.atleast_1d(np.asarray(drift_deg_h, dtype=float))
    lim = NAVIGATION_GRADE_DRIFT_DEG_H
    labels = None if labels_deg_h is None else np.asarray(labels_deg_h, dtype=float)
    labels = None if labels is None or not np.isfinite(labels).any() else labels[np.isfinite(labels)]
    out: list[str | None] = []
    for x in d:
        why = []
        if math.isfinite(x) and abs(x) > lim:
            why.append(f"|{x:.6g}| deg/h is beyond a navigation-grade RLG's {lim:g} deg/h (a table in mdeg/h?)")
        if labels is not None and math.isfinite(x):
            lo, hi = float(labels.min()), float(labels.max())
            w = hi - lo
            if x < lo - w or x > hi + w:
                why.append(
                    f"{x:.6g} deg/h is far outside the training labels' range [{lo:.6g}, {hi:.6g}] deg/h (beyond it "
                    "by more than its width)"
                )
        out.append("; ".join(why) if why else None)
    return out


def _check_unique_runs(runs: list[str], source: str) -> None:
    seen: dict[str, int] = {}
    for i, r in enumerate(runs, start=1):
        if r in seen:
            raise RunTableError(f"{source}, run {i}: run {r!r} appears more than once (first as run {seen[r]})")
        seen[r] = i


def _csv_rows(handle, name: str):
    """``csv.reader`` rows; a malformed CSV (``csv.Error``, e.g. a field over the size limit) is a RunTableError."""
    reader = csv.reader(handle)
    while True:
        try:
            row = next(reader)
        except StopIteration:
            return
        except csv.Error as exc:
            raise RunTableError(f"{name}, row {reader.line_num}: malformed CSV ({exc})") from None
        yield row


def _parse_float(text: str, where: str, column: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise RunTableError(f"{where}, column {column}: expected {what}, got {text!r}") from None
    if not math.isfinite(value):
        raise RunTableError(f"{where}, column {column}: expected a finite number, got {text!r}")
    return value


def parse_temp_range(text: str, where: str = "temp_range_c") -> tuple[float, float]:
    """Parse a temperature range cell ``"37.1~39.5"`` (also ``-``-free forms with ``～`` or ``..``) [deg C]."""
    for sep in ("~", "\uff5e", ".."):
        if sep in text:
            lo_text, hi_text = text.split(sep, 1)
            lo = _parse_float(lo_text.strip(), where, "temp_range_c", "a range like 37.1~39.5")
            hi = _parse_float(hi_text.strip(), where, "temp_range_c", "a range like 37.1~39.5")
            return lo, hi
    raise RunTableError(f"{where}, column temp_range_c: expected a range like 37.1~39.5, got {text!r}")


def read_runs_csv(path, *, lat0_deg: float | None = None, require_truth: bool = False) -> RunTable:
    """Read a CSV table of runs (see the module docstring for the columns).

    Parameters
    ----------
    path : str or Path
        The CSV file (UTF-8, header row, comma separated).
    lat0_deg : float, optional
        Site latitude [deg] for tables without a ``lat0_deg`` column. Required in that case.
    require_truth : bool
        When true every row must have ``drift_deg_h`` (training data).

    Raises
    ------
    RunTableError
        Naming the file, the row (1-based, header is row 1) and the column, and what was expected.
    """
    path = Path(path)
    name = str(path)
    if lat0_deg is not None and not (math.isfinite(lat0_deg) and -90.0 <= lat0_deg <= 90.0):
        raise RunTableError(f"{name}: site latitude lat0_deg must be within [-90, 90] deg, got {lat0_deg}")
    try:
        raw = read_limited(path, MAX_RUN_TABLE_BYTES)  # a device or FIFO is refused, never read or waited on
    except OSError as exc:
        raise RunTableError(f"{name}: cannot open: {exc.strerror}") from None
    if len(raw) > MAX_RUN_TABLE_BYTES:
        raise RunTableError(f"{name}: more than {MAX_RUN_TABLE_BYTES} bytes; a run table holds at most that")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise RunTableError(f"{name}, row {line}: not UTF-8 text (byte {exc.start}); expected a CSV table") from None
    with io.StringIO(text, newline="") as handle:
        reader = _csv_rows(handle, name)
        try:
            header = next(reader)
        except StopIteration:
            raise RunTableError(f"{name}: empty file, expected a header row") from None
        header = [h.strip() for h in header]
        unknown = [h for h in header if h not in KNOWN_COLUMNS]
        if unknown:
            raise RunTableError(
                f"{name}, row 1: unknown column {unknown[0]!r}; expected columns among {', '.join(KNOWN_COLUMNS)}"
            )
        if len(set(header)) != len(header):
            dup = next(h for h in header if header.count(h) > 1)
            raise RunTableError(f"{name}, row 1: column {dup!r} appears twice")
        col = {h: i for i, h in enumerate(header)}
        _check_required(set(header), f"{name}, row 1", caller_gives=set() if lat0_deg is None else {"lat0_deg"},
                        require_truth=require_truth)  # fmt: skip
        has_minmax = "temp_min_c" in col and "temp_max_c" in col

        runs: list[str] = []
        split: list[str] = []
        rows: list[int] = []
        lat: list[float] = []
        lat0: list[float] = []
        tmin: list[float] = []
        tmax: list[float] = []
        drift: list[float] = []
        optional = [h for h in header if h in OPTIONAL_COLUMNS]
        extra: dict[str, list[float]] = {h: [] for h in optional}
        for rownum, row in enumerate(reader, start=2):
            if not row or all(not cell.strip() for cell in row):
                continue
            where = f"{name}, row {rownum}"
            if len(row) != len(header):
                raise RunTableError(f"{where}: expected {len(header)} cells, got {len(row)}")
            cell = {h: row[i].strip() for h, i in col.items()}
            runs.append(cell.get("run") or str(len(runs) + 1))
            rows.append(rownum)
            la = _parse_float(cell["lat_deg"], where, "lat_deg", "a latitude in degrees")
            if not -90.0 <= la <= 90.0:
                raise RunTableError(f"{where}, column lat_deg: expected a latitude within [-90, 90] deg, got {la}")
            lat.append(la)
            if "lat0_deg" in col:
                l0 = _parse_float(cell["lat0_deg"], where, "lat0_deg", "a latitude in degrees")
                if not -90.0 <= l0 <= 90.0:
                    raise RunTableError(f"{where}, column lat0_deg: expected a latitude within [-90, 90] deg, got {l0}")
            else:
                assert lat0_deg is not None  # checked with the header
                l0 = float(lat0_deg)
            lat0.append(l0)
            if has_minmax:
                lo = _parse_float(cell["temp_min_c"], where, "temp_min_c", "a temperature in deg C")
                hi = _parse_float(cell["temp_max_c"], where, "temp_max_c", "a temperature in deg C")
                bad_col = "temp_max_c"
            else:
                lo, hi = parse_temp_range(cell["temp_range_c"], where)
                bad_col = "temp_range_c"
            if hi < lo:
                raise RunTableError(f"{where}, column {bad_col}: maximum temperature {hi} is below the minimum {lo}")
            t_low, t_high = TEMPERATURE_LIMITS_C
            if not (t_low <= lo <= t_high and t_low <= hi <= t_high):
                raise RunTableError(f"{where}, column {bad_col}: temperature outside [{t_low:g}, {t_high:g}] deg C")
            tmin.append(lo)
            tmax.append(hi)
            if "drift_deg_h" in col and cell["drift_deg_h"] != "":
                d = _parse_float(cell["drift_deg_h"], where, "drift_deg_h", "a drift in deg/h")
                if abs(d) > 10.0:
                    raise RunTableError(
                        f"{where}, column drift_deg_h: |{d}| deg/h is not an RLG drift (expected |drift| <= 10 deg/h)"
                    )
            elif require_truth:
                raise RunTableError(
                    f"{where}, column drift_deg_h: expected a drift in deg/h for training, got an empty cell"
                )
            else:
                d = math.nan
            drift.append(d)
            sp = cell.get("split", "")
            if sp not in ("", "train", "test"):
                raise RunTableError(f"{where}, column split: expected 'train' or 'test', got {sp!r}")
            split.append(sp)
            for h in optional:
                if h in FLAG_COLUMNS:
                    extra[h].append(_parse_flag(cell[h], where, h))
                    continue
                v = math.nan if cell[h] == "" else _parse_float(cell[h], where, h, f"a number in {COLUMNS[h].unit}")
                _check_optional(where, h, v)
                extra[h].append(v)
    if not runs:
        raise RunTableError(f"{name}: no data rows after the header")
    seen: dict[str, int] = {}
    for r, rownum in zip(runs, rows, strict=False):
        if r in seen:
            raise RunTableError(
                f"{name}, row {rownum}, column run: run {r!r} appears more than once (first in row {seen[r]}; "
                "a blank run cell is numbered by its position among the data rows)"
            )
        seen[r] = rownum
    return RunTable(
        run=np.array(runs, dtype=object),
        lat_deg=np.array(lat),
        lat0_deg=np.array(lat0),
        temp_min_c=np.array(tmin),
        temp_max_c=np.array(tmax),
        drift_deg_h=np.array(drift),
        split=np.array(split, dtype=object),
        source=name,
        extra={h: np.array(v, dtype=float) for h, v in extra.items()},
    )


def check_smoother_thermal(runs: RunTable, what: str) -> None:
    """Refuse runs that carry some but not all of ``SMOOTHER_THERMAL_COLUMNS`` (`RunTableError` naming the table,
    the runs and the missing columns; `what`: who needs them). A run has all four (the smoother's thermal model)
    or none (its constant model): a partial one would silently be taken as the constant model."""
    present = np.array([np.isfinite(runs.column(c)) for c in SMOOTHER_THERMAL_COLUMNS])  # (4, n_runs)
    partial = np.flatnonzero(present.any(axis=0) & ~present.all(axis=0))
    if partial.size:
        names = np.array(SMOOTHER_THERMAL_COLUMNS)
        shown = [f"{runs.run[i]} (missing {', '.join(names[~present[:, i]])})" for i in partial[:5]]
        raise RunTableError(
            f"{runs.source}: run(s) {'; '.join(shown)}{' ...' if partial.size > 5 else ''} have some but not all of "
            f"the smoother's thermal columns ({what}): give all four (its thermal model) or none (its constant model)"
        )


def recognise_run_table(head: bytes) -> bool:
    """True when `head` (a file's first bytes) starts with a run table's header: ``run`` and then only run-table
    columns (`gyrodrift.runs.columns.KNOWN_COLUMNS`). The only kind of file `write_run_table` replaces; a table
    written before a column was added is still recognised."""
    line, newline, _ = head.lstrip(b"\xef\xbb\xbf").partition(b"\n")
    names = line.rstrip(b"\r").decode("utf-8", "replace").split(",")
    return bool(newline) and names[0] == "run" and all(name in KNOWN_COLUMNS for name in names)


def run_table_target(path, inputs: Iterable = ()) -> dict:
    """`path` as a run-table output of `gyrodrift.files.atomic` (``check_output_files``, ``atomic_files``): it may
    replace only a run table (`recognise_run_table`) and none of `inputs`."""
    return {"path": path, "inputs": tuple(inputs), "recognise": recognise_run_table, "what": "run table"}


def known_values(name: str, values):
    """The values of run-table column `name` as a run table holds them: a 1-sigma of 0 (`RunColumn.sigma`; a
    noise-free run, no noise measured or given) is unknown (NaN), as a 1-sigma must be > 0; any other column's values
    as they are. The writer (`run_table_text`) and a campaign's run table (`gyrodrift.fleet.run_table`) take them
    from here."""
    if not COLUMNS[name].sigma:
        return values
    v = np.asarray(np.nan if values is None else values, dtype=float)
    return np.where(v == 0.0, np.nan, v)


def _cell(value) -> str:
    """A run-table cell: text as is, a flag ``true``/``false``, a number by ``repr`` of its float (the shortest
    exact round trip), an unknown value (None, NaN) empty."""
    if value is None or isinstance(value, str):
        return value or ""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    number = float(value)
    return repr(number) if math.isfinite(number) else ""


def run_table_text(rows: Iterable[Mapping[str, object]], columns: Iterable[str]) -> str:
    """The CSV text of a run table: a header of `columns`, in the order of `gyrodrift.runs.columns.RUN_TABLE`, and
    one line per row (a mapping of column name -> value; a missing name and a 1-sigma of 0, `known_values`, are
    empty cells). Raises ValueError for a column that is not a run-table column."""
    wanted = set(columns)
    unknown = sorted(wanted - set(KNOWN_COLUMNS))
    if unknown:
        raise ValueError(f"not run-table columns: {', '.join(unknown)}")
    header = [name for name in KNOWN_COLUMNS if name in wanted]
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(header)
    for row in rows:
        writer.writerow([_cell(known_values(name, row.get(name))) for name in header])
    return buf.getvalue()


def write_run_table(
    path, rows: Iterable[Mapping[str, object]], columns: Iterable[str], *, inputs: Iterable = ()
) -> None:
    """Write a run table (`run_table_text`) to `path`, atomically; an existing file is replaced only if it is a
    run table (`recognise_run_table`) and is none of `inputs` (docs/outputs.md). The one writer of a run table."""
    with atomic_write(path, **{k: v for k, v in run_table_target(path, inputs).items() if k != "path"}) as handle:
        handle.write(run_table_text(rows, columns))
