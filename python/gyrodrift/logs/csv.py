"""The CSV reader of IMU logs: UTF-8, one header row naming the reader's columns (stripped of surrounding spaces).

The CSV machinery here (`CsvDialect`, `csv_blocks`, `csv_problem`, `last_cell`) also reads a log in its own format
(`gyrodrift.logs.formatted`: another delimiter, a preamble before the header, comment lines). The file is read
with pyarrow's streaming CSV reader, 4 MB at a time; when pyarrow refuses a block, the file is scanned for the
first bad row (cell count, number, UTF-8) to name it.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.csv as pcsv

from gyrodrift.logs.columns import TIME
from gyrodrift.logs.source import (
    RATE_PROBE,
    Layout,
    LogError,
    LogSource,
    RawBlock,
    rate_from_times,
    recut,
    require_regular,
    short,
)

__all__ = [
    "CsvDialect",
    "CsvSource",
    "open_csv",
    "csv_blocks",
    "csv_problem",
    "csv_lines",
    "last_cell",
    "n_samples",
    "number_cell",
]


@dataclass(frozen=True)
class CsvDialect:
    """How a CSV file is laid out: its delimiter, the 1-based line of its header and its comment prefix."""

    delimiter: str = ","
    header_row: int = 1
    comment: str | None = None

    def is_comment(self, text: str) -> bool:
        """Whether line `text` is a comment line."""
        return self.comment is not None and text.lstrip().startswith(self.comment)


def csv_lines(path: Path, label: str) -> Iterator[str]:
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


def csv_blocks(
    source: LogSource,
    dialect: CsvDialect,
    types: dict[str, pa.DataType],
    chunk_samples: int,
    convert: Callable[[pa.Table | pa.RecordBatch, int], RawBlock],
    problem: Callable[[str], LogError],
) -> Iterator[RawBlock]:
    """The blocks of the CSV file of `source`: the columns of `types` (names as in the file, and their Arrow
    types), ``convert``-ed; a block pyarrow refuses becomes ``problem(pyarrow's message)``."""
    require_regular(source.path, source.label)
    assert source.path is not None  # only file logs are CSV
    read_options = pcsv.ReadOptions(block_size=1 << 22)
    parse_options = pcsv.ParseOptions(delimiter=dialect.delimiter)
    stream: Any = source.path
    if dialect.comment is not None:  # pyarrow has no comment lines: a filtered stream drops them
        stream = io.BufferedReader(_SkipLines(source.path, dialect.header_row - 1, dialect.comment), 1 << 20)
    else:
        read_options = pcsv.ReadOptions(block_size=1 << 22, skip_rows=dialect.header_row - 1)
    try:
        reader = pcsv.open_csv(
            stream,
            read_options=read_options,
            parse_options=parse_options,
            convert_options=pcsv.ConvertOptions(column_types=types, include_columns=list(types)),
        )
    except (pa.ArrowException, OSError) as exc:
        if stream is not source.path:
            stream.close()
        raise problem(str(exc)) from None
    try:
        yield from recut(reader, chunk_samples, convert, lambda exc, done: problem(str(exc)))
    finally:
        if stream is not source.path:
            stream.close()


def csv_problem(
    source: LogSource,
    dialect: CsvDialect,
    numbers: set[str],
    shown: Callable[[str], str],
    message: str,
) -> LogError:
    """The first bad row of a CSV file that pyarrow refused with `message` (scans the file): a row with another
    cell count than the header, or a cell of the columns `numbers` (header names) that is not a number (named
    ``shown(header name)``), or a byte that is not UTF-8."""
    label = source.label
    try:
        assert source.path is not None  # only file logs are CSV
        lines = csv_lines(source.path, label)
        skip = dialect.header_row - 1
        for _ in range(skip):
            next(lines)
        reader = csv.reader(lines, delimiter=dialect.delimiter)
        header = [h.strip() for h in next(reader)]
        for row in reader:
            rownum = reader.line_num + skip
            if not row or all(not c.strip() for c in row):
                continue
            if dialect.is_comment(row[0]):
                continue
            if len(row) != len(header):
                return LogError(
                    f"{label}, row {rownum}: {len(row)} cells, expected {len(header)} (one per header column)"
                )
            for name, cell in zip(header, row, strict=True):
                if name not in numbers:
                    continue
                try:
                    float(cell)
                except ValueError:
                    if cell.strip() == "":
                        return LogError(f"{label}, row {rownum}, column {shown(name)}: empty or NaN cell")
                    return LogError(
                        f"{label}, row {rownum}, column {shown(name)}: expected a number, got {short(cell)!r}"
                    )
    except LogError as exc:
        return exc
    except (csv.Error, StopIteration) as exc:
        return LogError(f"{label}: unreadable CSV ({short(exc)})")
    return LogError(f"{label}: unreadable CSV ({short(message)})")


def last_cell(path: Path, dialect: CsvDialect, column: int) -> str | None:
    """Cell `column` (0-based) of the last data line of the file (read from its last 64 kB), or None."""
    with open(path, "rb") as fh:
        fh.seek(0, os.SEEK_END)
        size = fh.tell()
        fh.seek(max(0, size - 65536))
        lines = [
            ln for ln in fh.read().decode("utf-8", "replace").splitlines() if ln.strip() and not dialect.is_comment(ln)
        ]
    if not lines:
        return None
    try:
        return next(csv.reader([lines[-1]], delimiter=dialect.delimiter))[column]
    except (IndexError, StopIteration, csv.Error):
        return None


def number_cell(row: list[str], column: int, where: str) -> float:
    """Cell `column` (0-based) of `row` as a number (an empty cell when the row is short); `LogError` at `where`
    (``file, row R, column C``) when it is not one."""
    cell = row[column] if column < len(row) else ""
    try:
        return float(cell)
    except ValueError:
        raise LogError(f"{where}: expected a number, got {short(cell)!r}") from None


def n_samples(label: str, first_s: float, last_s: float | None, rate_hz: float) -> int:
    """The number of samples of a CSV log from its first and last time stamps [s] and its rate [Hz]."""
    if last_s is None or not (math.isfinite(last_s) and last_s > first_s):
        raise LogError(f"{label}: cannot read the last time stamp of the file")
    n = (last_s - first_s) * rate_hz + 1.0
    if not n < 1e15:
        raise LogError(f"{label}: the last time stamp {last_s!r} s is not plausible for {rate_hz:g} Hz")
    return int(round(n))


@dataclass(frozen=True, kw_only=True)
class CsvSource(LogSource):
    """A CSV log with the reader's columns; rows are the file's lines (the header is row 1)."""

    format: str = "csv"

    raw_names: dict[str, str] = field(default_factory=dict)  # stripped header name -> as written, where they differ

    def blocks(self, chunk_samples: int) -> Iterator[RawBlock]:
        types = {self.raw_names.get(c, c): pa.float64() for c in self.layout.wanted()}
        return csv_blocks(self, CsvDialect(), types, chunk_samples, self._raw_block, self._problem)

    def _raw_block(self, table: pa.Table | pa.RecordBatch, first: int) -> RawBlock:
        return self.layout.from_table(table, self, first, self.raw_names)

    def _problem(self, message: str) -> LogError:
        return csv_problem(self, CsvDialect(), set(self.layout.wanted()), lambda name: name, message)

    def row(self, index: int) -> int:
        return index + 2


def open_csv(path: Path, label: str, require_temperature: bool) -> CsvSource:
    """Open a CSV log with the reader's columns: header, sample rate (first time steps), size (last time stamp)."""
    raw_header: list[str] = []
    times: list[float] = []
    try:
        reader = csv.reader(csv_lines(path, label))
        try:
            raw_header = next(reader)
        except StopIteration:
            raise LogError(f"{label}: empty file, expected a header row") from None
        header = [h.strip() for h in raw_header]
        layout = Layout.from_header(header, label, require_temperature=require_temperature)
        it = header.index(TIME.name)
        for row in reader:
            if len(times) > RATE_PROBE:
                break
            times.append(number_cell(row, it, f"{label}, row {reader.line_num}, column t_s"))
    except csv.Error as exc:
        raise LogError(f"{label}: unreadable CSV ({short(exc)})") from None
    rate = rate_from_times(np.asarray(times, dtype=float), label)
    last_text = last_cell(path, CsvDialect(), it)
    try:
        last = None if last_text is None else float(last_text)
    except ValueError:
        last = None
    n = n_samples(label, times[0], last, rate.hz)
    raw_names = {h: r for h, r in zip(header, raw_header, strict=True) if h != r}
    return CsvSource(label=label, layout=layout, rate=rate, n_samples=n, path=path, raw_names=raw_names)
