"""The IMU log vocabulary declared once (gyrodrift.logs.columns): the readers' column tuples, the imu.parquet schema
the simulator writes and the docs' column tables all follow the declaration."""

from __future__ import annotations

import re
from pathlib import Path

import pyarrow as pa
import pytest

from gyrodrift.files.columns import names
from gyrodrift.ins import Scenario
from gyrodrift.ins.simulate import imu_schema, simulate
from gyrodrift.logs import columns as C
from gyrodrift.logs.source import Layout, LogError

DOCS = Path(__file__).resolve().parents[2] / "docs"
MOVING = {"static_h": 0.005, "segments": [{"kind": "accelerate", "accel_m_s2": 1.0, "to_speed_m_s": 5.0}]}


def _table(doc: str, heading: str) -> list[list[str]]:
    """The cells of the rows of the first Markdown table after `heading` in docs/`doc` (header row left out)."""
    text = (DOCS / doc).read_text(encoding="utf-8")
    after = text[text.index(heading) :]
    rows = []
    for line in after.splitlines()[1:]:
        if line.startswith("|"):
            rows.append([c.strip() for c in line.strip().strip("|").split("|")])
        elif rows:
            break
    return rows[2:]  # header and rule


def _documented(doc: str, heading: str) -> list[tuple[str, str]]:
    """(name, unit) of every column a docs table lists: one unit for the row, or one per name."""
    out = []
    for cells in _table(doc, heading):
        names = re.findall(r"`([^`]+)`", cells[0])
        units = cells[1].split(", ")
        out += [(n, units[0] if len(units) == 1 else units[k]) for k, n in enumerate(names)]
    return out


def test_the_reader_tuples_come_from_the_declaration():
    assert C.INCREMENT_COLUMNS == ("dtheta_x_rad", "dtheta_y_rad", "dtheta_z_rad", "dv_x_m_s", "dv_y_m_s", "dv_z_m_s")
    assert C.RATE_COLUMNS == names(C.RATES) and C.TRUTH_COLUMNS == names(C.TRUTH)
    assert C.REF_HEIGHT_COLUMN == C.REF_HEIGHT.name == "ref_height_m"
    assert C.ROUTE_COLUMNS[3:] == ("true_vel_e_m_s", "true_vel_n_m_s", "true_vel_u_m_s")
    assert len({c.name for c in C.LOG_COLUMNS}) == len(C.LOG_COLUMNS) == 18
    for column in (*C.LOG_COLUMNS, C.TABLE_ANGLE, *C.ROUTE):
        assert column.name.endswith(("_s", "_rad", "_m_s", "_rad_s", "_m_s2", "_c", "_deg", "_m")), column
        assert column.arrow_type == pa.float64() and column.unit and column.meaning


def test_the_docs_tables_list_the_declared_columns_and_units():
    log_table = _documented("procedure.md", "Columns (body frame x right, y forward, z up")
    assert log_table == [(c.name, c.unit) for c in C.LOG_COLUMNS]
    schema = imu_schema(Scenario.from_dict({"trajectory": MOVING}))
    file_table = _documented("scenarios.md", "## `imu.parquet` (written by `simulate`)")
    declared = {c.name: c.unit for c in (*C.LOG_COLUMNS, C.TABLE_ANGLE, *C.ROUTE)}
    assert file_table == [(name, declared[name]) for name in schema.names]
    keys = [re.findall(r"`([^`]+)`", cells[0])[0] for cells in _table("scenarios.md", "File key-value metadata")]
    assert keys == [C.FORMAT_KEY, C.SCENARIO_KEY, C.SITE_KEY, C.RATE_KEY] == list(k.decode() for k in schema.metadata)


@pytest.mark.parametrize("moving", [False, True], ids=["static", "moving"])
def test_the_simulator_writes_the_declared_schema(moving, tmp_path):
    data = {"run": {"duration_h": 0.01, "rate_hz": 10.0}}
    if moving:
        data["trajectory"] = MOVING
    scn = Scenario.from_dict(data)
    run = simulate(scn)
    want = C.IMU_COLUMNS + (C.ROUTE_COLUMNS if moving else ())
    assert tuple(run.table().schema.names) == want
    assert all(t == pa.float64() for t in run.table().schema.types)
    assert run.table().schema.metadata[C.FORMAT_KEY.encode()] == C.IMU_FORMAT.encode()


def test_a_header_gives_the_layout_and_the_columns_to_read():
    names = ["t_s", *C.RATE_COLUMNS, "temp_c", *C.TRUTH_COLUMNS, "other"]
    layout = Layout.from_header(names, "x.csv", require_temperature=True)
    assert (layout.kind, layout.columns) == ("rates", C.RATE_COLUMNS)
    assert layout.wanted() == ["t_s", *C.RATE_COLUMNS, "temp_c", *C.TRUTH_COLUMNS]
    with pytest.raises(LogError, match=r"^x.csv, row 1: missing column temp_c \(system temperature"):
        Layout.from_header(names[:7], "x.csv", require_temperature=True)
