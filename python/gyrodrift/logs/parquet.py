"""The Parquet reader of IMU logs: the simulator's own ``imu.parquet`` or any file with the reader's columns.

The site, the true initial attitude, the static part and the sample rate come from the gyrodrift metadata when the
file has it (`gyrodrift.logs.columns`: ``gyrodrift.site``, ``gyrodrift.scenario``, ``gyrodrift.rate_hz``); the rate
otherwise from the time stamps. The file is read row group by row group (`parquet_blocks`), never whole.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from gyrodrift.logs.columns import RATE_KEY, SCENARIO_KEY, SITE_KEY, TIME
from gyrodrift.logs.source import (
    RATE_PROBE,
    Layout,
    LogError,
    LogSource,
    LogTruth,
    Provenance,
    RawBlock,
    SampleRate,
    check_rate,
    rate_from_times,
    recut,
    require_regular,
    short,
)
from gyrodrift.site import Site

__all__ = ["ParquetSource", "open_parquet", "parquet_file", "parquet_blocks", "numeric_type", "read_site"]


def numeric_type(t: pa.DataType) -> bool:
    """Whether a column of type `t` holds numbers (integer or floating point; not bool)."""
    return (pa.types.is_floating(t) or pa.types.is_integer(t)) and not pa.types.is_boolean(t)


def parquet_file(path: Path, label: str) -> tuple[pq.ParquetFile, pa.Schema, dict[str, str]]:
    """The opened file (close it), its Arrow schema and its key-value metadata (decoded); `LogError` when it is
    not a Parquet file."""
    try:
        pf = pq.ParquetFile(path, pre_buffer=False)
        schema = pf.schema_arrow
    except (pa.ArrowException, OSError, UnicodeDecodeError) as exc:  # a damaged schema may hold non-UTF-8 names
        raise LogError(f"{label}: not a Parquet file ({short(exc)})") from None
    meta = {k.decode("utf-8", "replace"): v.decode("utf-8", "replace") for k, v in (schema.metadata or {}).items()}
    return pf, schema, meta


def first_cells(pf: pq.ParquetFile, column: str, label: str) -> pa.Array:
    """The first `RATE_PROBE` + 1 cells of `column` (for the sample rate)."""
    try:
        return next(pf.iter_batches(batch_size=RATE_PROBE + 1, columns=[column])).column(0)
    except (pa.ArrowException, OSError, StopIteration) as exc:
        raise LogError(f"{label}, row 1: damaged Parquet data ({short(exc)})") from None


def parquet_blocks(
    source: LogSource,
    columns: list[str],
    chunk_samples: int,
    convert: Callable[[pa.Table | pa.RecordBatch, int], RawBlock],
) -> Iterator[RawBlock]:
    """The blocks of the file of `source`: its `columns` (names in the file), ``convert``-ed."""
    require_regular(source.path, source.label)
    try:
        # pre_buffer=False: with pre-buffering pyarrow keeps every column chunk it read until the file is
        # closed, so the memory grew with the log (1.2 GB for 76 h at 100 Hz); without it the read is
        # also faster (benchmarks/bench_memory.py).
        pf = pq.ParquetFile(source.path, pre_buffer=False)
        groups = pf.metadata.num_row_groups
    except (pa.ArrowException, OSError, UnicodeDecodeError) as exc:
        raise LogError(f"{source.label}: unreadable Parquet file ({short(exc)})") from None

    def batches() -> Iterator[pa.RecordBatch]:
        # One reader per row group: a single iter_batches over the whole file keeps some state per row group
        # it passed (about 75 kB each, 20 MB over 76 h at 100 Hz); a fresh one per group keeps none.
        for g in range(groups):
            yield from pf.iter_batches(batch_size=chunk_samples, row_groups=[g], columns=columns)

    def damaged(exc: BaseException, done: int) -> LogError:
        return LogError(f"{source.label}, row {done + 1}: damaged Parquet data after sample {done} ({short(exc)})")

    with pf:
        yield from recut(batches(), chunk_samples, convert, damaged)


@dataclass(frozen=True, kw_only=True)
class ParquetSource(LogSource):
    """A Parquet log with the reader's columns."""

    format: str = "parquet"

    def blocks(self, chunk_samples: int) -> Iterator[RawBlock]:
        return parquet_blocks(self, self.layout.wanted(), chunk_samples, self._raw_block)

    def _raw_block(self, table: pa.Table | pa.RecordBatch, first: int) -> RawBlock:
        return self.layout.from_table(table, self, first, {})


def _json_value(meta: Mapping[str, str], key: str, label: str) -> Any:
    try:
        return json.loads(meta[key])
    except (ValueError, RecursionError) as exc:
        raise LogError(f"{label}: unreadable {key} metadata ({short(exc)})") from None


def _number(value: Any, label: str, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise LogError(f"{label}: {key} must be a number, got {short(repr(value))}")
    try:
        x = float(value)
    except OverflowError:
        x = math.inf
    if not math.isfinite(x):
        raise LogError(f"{label}: {key} must be a finite number, got {short(repr(value))}")
    return x


def read_site(meta: Mapping[str, str], label: str) -> Site | None:
    """The true static site of the ``gyrodrift.site`` metadata, or None."""
    if SITE_KEY not in meta:
        return None
    s = _json_value(meta, SITE_KEY, label)
    if not isinstance(s, dict) or not all(k in s for k in ("lat_deg", "lon_deg", "height_m")):
        raise LogError(f"{label}: gyrodrift.site metadata must be {{lat_deg, lon_deg, height_m}}")
    return Site(*(_number(s[k], label, f"gyrodrift.site {k}") for k in ("lat_deg", "lon_deg", "height_m")))


def _read_provenance(meta: Mapping[str, str], label: str) -> Provenance:
    """The true site (``gyrodrift.site``), initial attitude and static part (``gyrodrift.scenario``: its
    ``[attitude]`` and ``[trajectory] static_h``) of the metadata, each None when it does not say."""
    site = read_site(meta, label)
    if SCENARIO_KEY not in meta:
        return Provenance(site)
    s = _json_value(meta, SCENARIO_KEY, label)
    att = s.get("attitude", {}) if isinstance(s, dict) else None
    if not isinstance(att, dict):
        raise LogError(f"{label}: gyrodrift.scenario metadata must be a table with an [attitude] table")
    truth = LogTruth(
        *(
            _number(att.get(k, 0.0), label, f"gyrodrift.scenario attitude {k}")
            for k in ("pitch_deg", "roll_deg", "yaw_deg")
        )
    )
    tr = s.get("trajectory")
    if not isinstance(tr, dict):
        return Provenance(site, truth)
    static_h = _number(tr.get("static_h", 0.0), label, "gyrodrift.scenario trajectory static_h")
    return Provenance(site, truth, static_h * 3600.0)


def open_parquet(path: Path, label: str, require_temperature: bool) -> ParquetSource:
    """Open a Parquet log with the reader's columns: header, column types, size, metadata and sample rate."""
    pf, schema, meta = parquet_file(path, label)
    with pf:
        n = pf.metadata.num_rows
        layout = Layout.from_header(list(schema.names), label, require_temperature=require_temperature)
        for c in layout.wanted():
            t = schema.field(c).type
            if not numeric_type(t):
                raise LogError(f"{label}, column {c}: expected numbers (float64), got a column of type {t}")
        if n < 2:
            raise LogError(f"{label}: {n} sample(s); a log needs many")
        known = _read_provenance(meta, label)
        if RATE_KEY in meta:
            hz = check_rate(_json_value(meta, RATE_KEY, label), label, "gyrodrift.rate_hz metadata")
            rate = SampleRate(hz, "metadata")
        else:
            times = np.asarray(first_cells(pf, TIME.name, label).to_numpy(zero_copy_only=False), float)
            rate = rate_from_times(times, label)
    return ParquetSource(label=label, layout=layout, rate=rate, n_samples=n, path=path, provenance=known)
