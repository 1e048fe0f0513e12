"""Property tests of the IMU log reader (issue 8): any bytes, or a mutated valid log, give data or a LogError.

Whatever a file holds, `open_log` followed by streaming every chunk either returns validated samples or raises
the package's error (`gyrodrift.errors.GyrodriftError`, with a message naming the file); never another
exception, never a hang. Few examples (the suite stays fast; ``GYRODRIFT_FUZZ_EXAMPLES=5000`` searches longer), no
deadline (file I/O).
"""

from __future__ import annotations

import io
import json
import os
import tempfile

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gyrodrift.errors import GyrodriftError
from gyrodrift.logs import INCREMENT_COLUMNS, RATE_COLUMNS, open_log

RATE = 10.0
FUZZ = settings(
    max_examples=int(os.environ.get("GYRODRIFT_FUZZ_EXAMPLES", "60")),  # raise it for a longer search
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)


def _columns(n: int = 40, kind: str = "increments") -> dict[str, np.ndarray]:
    t = np.arange(1, n + 1) / RATE
    w, f = np.array([0.0, 6.4e-5, 3.4e-5]), np.array([0.0, 0.0, 9.79])
    names = INCREMENT_COLUMNS if kind == "increments" else RATE_COLUMNS
    scale = 1.0 / RATE if kind == "increments" else 1.0
    cols = {"t_s": t}
    for j, c in enumerate(names):
        cols[c] = np.full(n, (w if j < 3 else f)[j % 3] * scale)
    cols["temp_c"] = np.linspace(20.0, 21.0, n)
    return cols


def _valid_csv(kind: str = "increments") -> bytes:
    cols = _columns(kind=kind)
    names = list(cols)
    lines = [",".join(names)] + [",".join(repr(float(cols[c][i])) for c in names) for i in range(len(cols["t_s"]))]
    return ("\n".join(lines) + "\n").encode()


def _valid_parquet() -> bytes:
    buf = io.BytesIO()
    table = pa.table(_columns()).replace_schema_metadata(
        {"gyrodrift.rate_hz": "10.0", "gyrodrift.site": '{"lat_deg": 28.0, "lon_deg": 112.0, "height_m": 0.0}'}
    )
    pq.write_table(table, buf, compression="none", row_group_size=16)
    return buf.getvalue()


VALID_CSV = _valid_csv()
VALID_RATES_CSV = _valid_csv("rates")
VALID_PARQUET = _valid_parquet()


def _read(data: bytes, suffix: str) -> int:
    """Write `data` to a temporary file with `suffix`, open and stream it; the samples read (or an error)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "log" + suffix)
        with open(path, "wb") as fh:
            fh.write(data)
        try:
            log = open_log(path, site={"lat_deg": 28.0})
            n = sum(len(c) for c in log.chunks(7))
        except GyrodriftError as exc:
            assert str(exc).startswith(path), str(exc)  # the message names the file
            return -1
        assert n >= 2
        return n


def test_the_unmutated_logs_are_read():
    assert _read(VALID_CSV, ".csv") == 40
    assert _read(VALID_RATES_CSV, ".csv") == 40
    assert _read(VALID_PARQUET, ".parquet") == 40


def _mutate(data: bytes, edits: list[tuple[str, int, int]]) -> bytes:
    out = bytearray(data)
    for op, pos, value in edits:
        if not out:
            break
        i = pos % len(out)
        if op == "set":
            out[i] = value
        elif op == "insert":
            out.insert(i, value)
        elif op == "delete":
            del out[i]
        else:  # truncate
            del out[i:]
    return bytes(out)


EDITS = st.lists(
    st.tuples(st.sampled_from(["set", "insert", "delete", "truncate"]), st.integers(0, 1 << 16), st.integers(0, 255)),
    min_size=1,
    max_size=6,
)


@FUZZ
@given(data=st.binary(max_size=2000), suffix=st.sampled_from([".csv", ".parquet"]))
def test_any_bytes_give_data_or_a_log_error(data, suffix):
    _read(data, suffix)


@FUZZ
@given(edits=EDITS, base=st.sampled_from([VALID_CSV, VALID_RATES_CSV]))
def test_a_mutated_csv_log_gives_data_or_a_log_error(edits, base):
    _read(_mutate(base, edits), ".csv")


@FUZZ
@given(edits=EDITS)
def test_a_mutated_parquet_log_gives_data_or_a_log_error(edits):
    _read(_mutate(VALID_PARQUET, edits), ".parquet")


@FUZZ
@given(
    cell=st.one_of(
        st.text(max_size=12),
        st.floats(allow_nan=True, allow_infinity=True).map(repr),
        st.integers(-(10**400), 10**400).map(str),
    ),
    row=st.integers(0, 40),
    column=st.integers(0, 7),
)
def test_a_csv_log_with_any_cell_gives_data_or_a_log_error(cell, row, column):
    lines = VALID_CSV.decode().splitlines()
    cells = lines[row].split(",")
    cells[column] = cell.replace("\n", " ").replace("\r", " ")
    lines[row] = ",".join(cells)
    _read(("\n".join(lines) + "\n").encode("utf-8", "surrogatepass"), ".csv")


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_an_empty_file_is_a_log_error(suffix):
    assert _read(b"", suffix) == -1


JSON = st.recursive(
    st.none() | st.booleans() | st.floats() | st.integers(-(10**30), 10**30) | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=8), inner, max_size=3),
    max_leaves=8,
)


@FUZZ
@given(
    key=st.sampled_from(["gyrodrift.rate_hz", "gyrodrift.site", "gyrodrift.scenario"]),
    value=st.one_of(JSON.map(json.dumps), st.text(max_size=20)),
    as_site=st.booleans(),
)
def test_any_gyrodrift_metadata_gives_data_or_a_log_error(key, value, as_site):
    if as_site:  # the value in every key of a site table: {"lat_deg": v, "lon_deg": v, "height_m": v}
        value = json.dumps(dict.fromkeys(("lat_deg", "lon_deg", "height_m"), value))
    buf = io.BytesIO()
    pq.write_table(pa.table(_columns()).replace_schema_metadata({key: value}), buf)
    _read(buf.getvalue(), ".parquet")
