"""The reader of IMU logs in their own format: Parquet or CSV whose columns a `LogFormat` describes.

Each block is converted by the format (`gyrodrift.logs.log_format`: units, scales, axis mapping and signs, time in
s / ms / us or ISO date-times) into the reader's columns before the same checks as a native log's; messages then
name the file's line (CSV: preamble, comments and blank lines counted) and its own column.
"""

from __future__ import annotations

import csv
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from gyrodrift.logs.columns import REF_HEIGHT_COLUMN, TEMPERATURE, TIME, TRUTH_COLUMNS
from gyrodrift.logs.csv import CsvDialect, csv_blocks, csv_lines, csv_problem, last_cell, n_samples, number_cell
from gyrodrift.logs.log_format import ColumnSpec, LogFormat
from gyrodrift.logs.parquet import first_cells, numeric_type, parquet_blocks, parquet_file, read_site
from gyrodrift.logs.source import (
    RATE_PROBE,
    Layout,
    LogError,
    LogSource,
    Provenance,
    RawBlock,
    rate_from_times,
    require_cells,
    short,
)
from gyrodrift.site import Site

__all__ = ["FormattedSource", "open_formatted", "iso_ns"]

_BODY = ("right", "forward", "up")
_QUANTITY = {TIME.name: "time", TEMPERATURE.name: "temperature", REF_HEIGHT_COLUMN: "ref_height"} | {
    c: c[: -len("_deg")] for c in TRUTH_COLUMNS
}
"""The log format quantity of a reader column."""


def _dialect(fmt: LogFormat) -> CsvDialect:
    return CsvDialect(fmt.delimiter, fmt.header_row, fmt.comment)


def _signed(spec: ColumnSpec, sign: float, j: int) -> str:
    """``body up = -Name``: the file's column behind body axis `j`."""
    return f"body {_BODY[j]} = {'-' if sign < 0 else '+'}{spec.name}"


@dataclass(frozen=True, kw_only=True)
class FormattedSource(LogSource):
    """A Parquet (``format = "parquet"``) or CSV (``"csv"``) log read through its log format."""

    log_format: LogFormat
    t0_ns: int | None = None  # the first ISO time stamp [ns since 1970]: time 0
    raw_names: dict[str, str] = field(default_factory=dict)  # stripped CSV header name -> as written

    def _file_columns(self) -> list[str]:
        return [self.raw_names.get(c.name, c.name) for c in self.log_format.columns]

    def blocks(self, chunk_samples: int) -> Iterator[RawBlock]:
        if self.format == "parquet":
            return parquet_blocks(self, self._file_columns(), chunk_samples, self._raw_block)
        types = {c: pa.float64() for c in self._file_columns()}
        time = self.log_format.column("time")
        assert time is not None
        if time.is_iso_time:
            types[self.raw_names.get(time.name, time.name)] = pa.string()
        return csv_blocks(self, _dialect(self.log_format), types, chunk_samples, self._raw_block, self._problem)

    def _problem(self, message: str) -> LogError:
        fmt = self.log_format
        time = fmt.column("time")
        numbers = {c.name for c in fmt.columns if c is not time or not c.is_iso_time}
        quantity = {c.name: c.quantity for c in fmt.columns}
        return csv_problem(self, _dialect(fmt), numbers, lambda name: self.column_label(quantity[name]), message)

    def _raw_block(self, table: pa.Table | pa.RecordBatch, first: int) -> RawBlock:
        """The file's columns converted by the log format: time [s], body-frame sensors in SI with the axis
        mapping and signs applied, temperature [deg C], truth [deg]."""
        fmt = self.log_format
        values: dict[str, np.ndarray] = {}
        for spec in fmt.columns:
            col = table.column(self.raw_names.get(spec.name, spec.name))
            require_cells(col, self, first, spec.quantity)
            if spec.is_iso_time:
                ns = iso_ns(col, lambda i: self.where(first + i, "time"))
                values["time"] = (ns - (self.t0_ns or 0)).astype(np.float64) * 1e-9
            else:
                values[spec.quantity] = spec.convert(col.to_numpy(zero_copy_only=False))
        sensors = []
        for sensor in ("gyro", "accel"):
            for j in range(3):
                spec, sign = fmt.body_source(sensor, j)
                v = values[spec.quantity]
                sensors.append(-v if sign < 0 else v)
        return RawBlock(
            values["time"],
            tuple(sensors),
            values.get("temperature"),
            tuple(values[q] for q in ("true_pitch", "true_roll", "true_yaw")) if fmt.has_truth else None,
            values.get("ref_height"),
        )

    def row(self, index: int) -> int:
        """The 1-based line of a CSV file that holds data row `index` (scans the file: only called for an error
        message); the sample index in a Parquet file."""
        if self.format != "csv":
            return index + 1
        fmt = self.log_format
        dialect = _dialect(fmt)
        assert self.path is not None
        k = -1
        with open(self.path, "rb") as fh:
            for line_no, line in enumerate(fh, start=1):
                if line_no <= fmt.header_row:
                    continue
                text = line.decode("utf-8", "replace")
                if not text.strip() or dialect.is_comment(text):
                    continue
                k += 1
                if k == index:
                    return line_no
        return fmt.header_row + 1 + index

    def column_label(self, column: str) -> str:
        """The file's column behind a reader column name (``gyro_x_rad_s`` = body right) or a format quantity."""
        fmt = self.log_format
        if column in self.layout.columns:
            k = self.layout.columns.index(column)
            src, sign = fmt.body_source("gyro" if k < 3 else "accel", k % 3)
            return f"{src.name} ({src.quantity}, {src.unit}; {_signed(src, sign, k % 3)})"
        spec = fmt.column(_QUANTITY.get(column, column))
        return column if spec is None else spec.describe()

    def channels(self, sensor: str, body: tuple[int, ...], axes: bool = False, up_note: str = "") -> str:
        note = f"; {up_note}" if up_note else ""
        fmt = self.log_format
        parts = []
        for j in body:
            spec, sign = fmt.body_source(sensor, j)
            parts.append(
                f"[columns.{spec.name}] unit/scale ({spec.quantity}, {spec.unit}; {_signed(spec, sign, j)}"
                f"{note if j == 2 else ''})"
            )
        keys = ", ".join(parts) + (", [axes] up" if axes else "")
        return f"{keys} of the log format {fmt.source}"


def iso_ns(col: Any, where: Callable[[int], str]) -> np.ndarray:
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
                f"{where(i)}: expected an ISO 8601 date-time (2024-05-01T12:00:00.010), got {short(str(v))!r}"
            )
    raise LogError(f"{where(0)}: ISO date-times with and without a time zone mixed in one column")


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


def _parquet_head(p: Path, label: str, fmt: LogFormat, time: ColumnSpec) -> tuple[pa.Array, int, Site | None]:
    """The first time cells, the number of rows and the metadata site of a formatted Parquet log."""
    pf, schema, meta = parquet_file(p, label)
    with pf:
        n = pf.metadata.num_rows
        _check_format_columns(list(schema.names), fmt, label, 1)
        for spec in fmt.columns:
            t = schema.field(spec.name).type
            ok = (pa.types.is_timestamp(t) or pa.types.is_string(t)) if spec.is_iso_time else numeric_type(t)
            if not ok:
                want = "ISO date-times (timestamp or text)" if spec.is_iso_time else "numbers"
                raise LogError(f"{label}, column {spec.describe()}: expected {want}, got a column of type {t}")
        if n < 2:
            raise LogError(f"{label}: {n} sample(s); a log needs many")
        head = first_cells(pf, time.name, label)
    return head, n, read_site(meta, label)


def _formatted_data_lines(p: Path, label: str, fmt: LogFormat) -> Iterator[tuple[int, str]]:
    """(line number, text) of the header and data lines of a formatted CSV log (preamble, comments and
    blank lines skipped)."""
    for line_no, text in enumerate(csv_lines(p, label), start=1):
        if line_no < fmt.header_row:
            continue
        if not text.strip() or _dialect(fmt).is_comment(text):
            if line_no == fmt.header_row:
                raise LogError(
                    f"{label}, row {line_no}: expected the header row here ([csv] header_row of {fmt.source})"
                )
            continue
        yield line_no, text


def _csv_head(p: Path, label: str, fmt: LogFormat) -> tuple[list[str], list[str], list[tuple[int, list[str]]]]:
    """The header cells (stripped and as written) and the first `RATE_PROBE` + 1 data rows with their line
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
            if len(rows) > RATE_PROBE:
                break
    except csv.Error as exc:
        raise LogError(f"{label}: unreadable CSV ({short(exc)})") from None
    if header is None:
        raise LogError(f"{label}: no header row at line {fmt.header_row} ([csv] header_row of {fmt.source})")
    return header, raw, rows


def _csv_time_cells(label: str, time: ColumnSpec, it: int, rows: list[tuple[int, list[str]]]) -> pa.Array:
    """The time cells of the first rows (text for ISO date-times, else numbers)."""
    if time.is_iso_time:
        return pa.array([row[it].strip() if it < len(row) else "" for _, row in rows], pa.string())
    cells = [number_cell(row, it, f"{label}, row {line_no}, column {time.describe()}") for line_no, row in rows]
    return pa.array(cells, pa.float64())


def _seconds(time: ColumnSpec, cell: str, t0_ns: int | None) -> float | None:
    """Time cell `cell` [s] after `t0_ns` (ISO date-times) or converted by the format, or None."""
    try:
        if time.is_iso_time:
            ns = iso_ns(pa.array([cell.strip()]), lambda i: "")
            return (int(ns[0]) - (t0_ns or 0)) * 1e-9
        return float(time.convert(np.array([float(cell)]))[0])
    except (ValueError, LogError):
        return None


def open_formatted(p: Path, label: str, fmt: LogFormat, require_temperature: bool) -> FormattedSource:
    """Open a log whose columns a `LogFormat` describes (CSV with its delimiter, header row and comments, or
    Parquet); the blocks are converted to the reader's columns and checked like a native log's."""
    suffix = p.suffix.lower()
    time = fmt.column("time")
    assert time is not None
    if require_temperature and not fmt.has_temperature:
        raise LogError(
            f"{label}: the log format {fmt.source} names no temperature column (the features need the system "
            'temperature; add a [columns.NAME] table with quantity = "temperature")'
        )
    site: Site | None = None
    lines: list[int] | None = None  # the line of each first row (CSV)
    raw_names: dict[str, str] = {}
    if suffix in (".parquet", ".pq"):
        container = "parquet"
        head, n, site = _parquet_head(p, label, fmt, time)
    elif suffix == ".csv":
        container = "csv"
        header, raw_header, first_rows = _csv_head(p, label, fmt)
        raw_names = {h: r for h, r in zip(header, raw_header, strict=True) if h != r}
        _check_format_columns(header, fmt, label, fmt.header_row)
        it = header.index(time.name)
        head = _csv_time_cells(label, time, it, first_rows)
        lines = [line_no for line_no, _ in first_rows]
    else:
        raise LogError(f"{label}: unknown log format {p.suffix!r} (expected .parquet, .pq or .csv)")
    if len(head) < 2:
        raise LogError(f"{label}: {len(head)} sample(s); a log needs many")
    t0_ns = None
    if time.is_iso_time:
        ns = iso_ns(head, lambda i: f"{label}, row {i + 1 if lines is None else lines[i]}, column {time.describe()}")
        t0_ns = int(ns[0])
        t = (ns - t0_ns).astype(np.float64) * 1e-9
    else:
        t = time.convert(head.to_numpy(zero_copy_only=False))
    rate = rate_from_times(t, label)
    if container == "csv":
        cell = last_cell(p, _dialect(fmt), it)
        n = n_samples(label, float(t[0]), None if cell is None else _seconds(time, cell, t0_ns), rate.hz)
    return FormattedSource(
        label=label,
        layout=Layout.of_kind(
            fmt.kind,
            has_temperature=fmt.has_temperature,
            has_truth_columns=fmt.has_truth,
            has_reference_height=fmt.column("ref_height") is not None,
        ),
        rate=rate,
        n_samples=n,
        path=p,
        provenance=Provenance(site),
        format=container,
        log_format=fmt,
        t0_ns=t0_ns,
        raw_names=raw_names,
    )
