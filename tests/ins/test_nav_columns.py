"""The navigation output declared once (gyrodrift.ins.nav_columns): what a navigation returns and writes, the docs
table and the reference-track reader all follow the declaration."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from gyrodrift.files.columns import markdown_table
from gyrodrift.ins import Scenario
from gyrodrift.ins.nav_columns import (
    NAV_COLUMNS,
    NAV_ERROR_COLUMNS,
    NAV_FORMAT,
    NAV_OUTPUT,
    POSITION_ERROR_COLUMNS,
    TRACK_COLUMNS,
    nav_table,
)
from gyrodrift.ins.track import TrackError, load_track
from gyrodrift.procedure import navigate

ROOT = Path(__file__).resolve().parents[2]

SCENARIO = {
    "run": {"duration_h": 0.05, "rate_hz": 10.0, "seed": 2},
    "gyro": {"bias_deg_h": [0.0, 0.0, 0.01]},
}


def test_the_docs_table_is_the_declaration():
    text = (ROOT / "docs" / "scenarios.md").read_text(encoding="utf-8")
    table = markdown_table(NAV_OUTPUT)
    assert table in text, f"docs/scenarios.md: the nav.parquet table differs from gyrodrift.ins.nav_columns:\n{table}"


def test_every_declared_column_is_named_once_with_a_unit_and_a_dtype():
    names = [c.name for c in NAV_OUTPUT]
    assert len(names) == len(set(names))
    for c in NAV_OUTPUT:
        assert c.unit and c.meaning, c
        assert c.arrow_type == pa.float64(), c


def test_a_written_navigation_holds_the_declared_columns_in_order_with_their_dtypes(tmp_path):
    res = navigate(Scenario.from_dict(SCENARIO), decimation_s=10.0, out_dir=tmp_path / "nav")
    assert list(res.columns) == list(NAV_COLUMNS + NAV_ERROR_COLUMNS)
    table = pq.read_table(tmp_path / "nav" / "nav.parquet")
    by_name = {c.name: c for c in NAV_OUTPUT}
    assert table.column_names == list(res.columns)
    for field in table.schema:
        assert field.type == by_name[field.name].arrow_type, field
    assert table.schema.metadata[b"gyrodrift.format"].decode() == NAV_FORMAT
    assert res.table().equals(table.replace_schema_metadata(None))
    for checkpoint in res.summary["checkpoints"] + [res.summary["final"]]:
        assert set(POSITION_ERROR_COLUMNS) <= set(checkpoint)


def test_nothing_writes_an_undeclared_column_or_changes_the_order():
    columns = {name: np.zeros(2) for name in NAV_COLUMNS}
    with pytest.raises(ValueError, match=r"undeclared column\(s\) \['speed_m_s'\]"):
        nav_table({**columns, "speed_m_s": np.zeros(2)})
    with pytest.raises(ValueError, match="out of the declared order"):
        nav_table({"lat_deg": np.zeros(2), "t_s": np.zeros(2)})
    assert nav_table(columns).column_names == list(NAV_COLUMNS)


def test_a_track_file_is_read_by_its_declared_columns(tmp_path):
    path = tmp_path / "gnss.csv"
    path.write_text("t_s,lat_deg,lon_deg\n0,28.2,113.0\n1,28.2,113.0\n")
    with pytest.raises(TrackError, match=f"missing column\\(s\\) height_m \\(expected {', '.join(TRACK_COLUMNS)}\\)"):
        load_track(path)
