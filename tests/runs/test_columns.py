"""The run table declared once (`gyrodrift.runs.columns`): the docs table, every derived list, the one writer."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from gyrodrift.choices import PHYSICS_COLUMNS
from gyrodrift.errors import OutputError
from gyrodrift.runs.columns import (
    CURVES_TABLE,
    EVALUATION_CURVES_TABLE,
    FEATURES_COLUMNS,
    FLAG_COLUMNS,
    KNOWN_COLUMNS,
    LABEL_COLUMNS,
    OPTIONAL_COLUMNS,
    PHYSICS_BASE_COLUMNS,
    RUN_TABLE,
    SIGMA_COLUMNS,
    SMOOTHER_COLUMNS,
    SMOOTHER_DRIFT_COLUMNS,
    SMOOTHER_THERMAL_COLUMNS,
    STD_COLUMNS,
    RunColumn,
)
from gyrodrift.runs.table import (
    RunTable,
    RunTableError,
    read_runs_csv,
    recognise_run_table,
    run_table_text,
    write_run_table,
)

OUTPUTS_MD = Path(__file__).resolve().parents[2] / "docs" / "outputs.md"


def _markdown(table: tuple[RunColumn, ...], *, written: bool) -> str:
    """The docs table of `table`: one row per column, in declaration order."""
    if written:
        head = "| column | unit | type | needed | written by | meaning |\n|---|---|---|---|---|---|\n"
        rows = [
            f"| `{c.name}` | {c.unit} | {c.dtype} | {c.required or 'optional'} | {c.written_by or '-'} | {c.meaning} |"
            for c in table
        ]
    else:
        head = "| column | unit | type | meaning |\n|---|---|---|---|\n"
        rows = [f"| `{c.name}` | {c.unit} | {c.dtype} | {c.meaning} |" for c in table]
    return head + "\n".join(rows) + "\n"


@pytest.mark.parametrize(
    ("table", "written"), [(RUN_TABLE, True), (CURVES_TABLE, False), (EVALUATION_CURVES_TABLE, False)]
)
def test_the_docs_tables_are_the_declaration(table, written):
    """docs/outputs.md lists each declared table as it is declared: a new column is one edit in columns.py, and
    this test prints the docs table to paste."""
    expected = _markdown(table, written=written)
    assert expected in OUTPUTS_MD.read_text(encoding="utf-8"), f"docs/outputs.md should hold:\n\n{expected}"


def test_names_are_unique_and_carry_their_units():
    for table in (RUN_TABLE, CURVES_TABLE, EVALUATION_CURVES_TABLE):
        names = [c.name for c in table]
        assert len(set(names)) == len(names)
    suffix = {"deg": "_deg", "degC": "_c", "deg/h": "_deg_h", "deg/h/degC": "_deg_h_per_c"}
    for c in RUN_TABLE:
        if c.unit in suffix:
            assert c.name.endswith(suffix[c.unit]), c.name
        assert c.unit == "" or c.dtype != "bool", c.name


def test_the_derived_groups():
    assert KNOWN_COLUMNS == tuple(c.name for c in RUN_TABLE)
    assert FLAG_COLUMNS == ("label_flagged",)
    assert set(SMOOTHER_THERMAL_COLUMNS) | set(SMOOTHER_DRIFT_COLUMNS) == set(SMOOTHER_COLUMNS)
    assert len(SMOOTHER_THERMAL_COLUMNS) == 4 and set(SMOOTHER_COLUMNS) <= set(OPTIONAL_COLUMNS)
    assert set(FEATURES_COLUMNS).isdisjoint(LABEL_COLUMNS)
    assert LABEL_COLUMNS == ("drift_deg_h", "drift_std_deg_h", "label_flagged")
    for value, std in STD_COLUMNS.items():
        assert std in SIGMA_COLUMNS and value not in SIGMA_COLUMNS, value
    # the physics bases a table carries are the hybrid's choices that are not computed by the model
    computed = {"drift_inversion_deg_h", "drift_smoother_fleet_deg_h"}
    assert set(PHYSICS_COLUMNS) - computed == set(PHYSICS_BASE_COLUMNS)
    assert all(name in STD_COLUMNS for name in PHYSICS_BASE_COLUMNS)


def test_a_column_is_checked_when_declared():
    with pytest.raises(ValueError, match="column x: dtype 'int' is not one of text, float, bool"):
        RunColumn("x", "", "nothing", dtype="int", kept="extra")
    with pytest.raises(ValueError, match="column x: kept 'kept' is not one of attribute, extra, read"):
        RunColumn("x", "", "nothing", kept="kept")


def _rows():
    return [
        {"run": "a", "lat_deg": 28.5, "lat0_deg": 28.0, "temp_min_c": 30.0, "temp_max_c": 31.5, "drift_deg_h": 1e-3,
         "drift_std_deg_h": 1e-4, "label_flagged": True, "drift_smoother_deg_h": np.float64(0.1) / 3},
        {"run": "b", "lat_deg": 28.25, "lat0_deg": 28.0, "temp_min_c": 30.0, "temp_max_c": 31.0, "drift_deg_h": 2e-3,
         "drift_std_deg_h": math.nan, "label_flagged": np.bool_(False)},
    ]  # fmt: skip


def test_the_writer_orders_by_the_declaration_and_reads_back(tmp_path):
    """Whatever order the caller names the columns in, the header follows RUN_TABLE; cells: repr of the float,
    true/false, empty for NaN or a missing name; read back to the same values."""
    columns = ["label_flagged", "drift_deg_h", "run", "drift_smoother_deg_h", "drift_std_deg_h", "lat0_deg"]
    columns += ["temp_max_c", "lat_deg", "temp_min_c"]
    text = run_table_text(_rows(), columns)
    header, first, second = text.splitlines()
    assert header.split(",") == [n for n in KNOWN_COLUMNS if n in columns]
    assert first.split(",")[header.split(",").index("drift_smoother_deg_h")] == repr(float(np.float64(0.1) / 3))
    assert second.endswith(",0.002,,false")
    path = tmp_path / "runs.csv"
    write_run_table(path, _rows(), columns)
    assert path.read_text() == text
    back = read_runs_csv(path, require_truth=True)
    assert back.column("label_flagged").tolist() == [1.0, 0.0]
    assert np.isnan(back.column("drift_std_deg_h")[1]) and np.isnan(back.column("drift_smoother_deg_h")[1])
    with pytest.raises(ValueError, match="not run-table columns: drift_mdeg_h"):
        run_table_text(_rows(), [*columns, "drift_mdeg_h"])


def test_one_recogniser_for_every_run_table(tmp_path):
    """Tables of features, of campaign --run-table, of RunTable.to_csv and of an earlier version are run tables;
    a predictions file, a table with an unknown column and a header cut short are not."""
    for header in (
        ",".join(FEATURES_COLUMNS),
        ",".join((*FEATURES_COLUMNS, *LABEL_COLUMNS)),
        "run,split,lat_deg,lat0_deg,temp_min_c,temp_max_c,drift_deg_h",
        ",".join(FEATURES_COLUMNS[: FEATURES_COLUMNS.index("drift_smoother_std_deg_h") + 1]),
    ):
        assert recognise_run_table(("\ufeff" + header + "\r\n1,2\n").encode()), header
    for head in ("run,drift_identified_deg_h,drift_deg_h\n", "lat_deg,run\n", "run,lat_deg", "my notes\n"):
        assert not recognise_run_table(head.encode()), head
    notes = tmp_path / "notes.csv"
    notes.write_text("run,drift_identified_deg_h\nr1,0.001\n")
    with pytest.raises(OutputError, match="notes.csv"):
        write_run_table(notes, _rows(), FEATURES_COLUMNS)
    assert notes.read_text() == "run,drift_identified_deg_h\nr1,0.001\n"


def test_the_reader_takes_units_and_sigmas_from_the_declaration(tmp_path):
    """An optional column's error names its declared unit; a declared 1-sigma must be > 0."""
    base = "run,lat_deg,lat0_deg,temp_min_c,temp_max_c,{}\na,28.1,28.0,30,31,{}\n"
    for column in OPTIONAL_COLUMNS:
        if column in FLAG_COLUMNS:
            continue
        unit = next(c.unit for c in RUN_TABLE if c.name == column)
        (tmp_path / "t.csv").write_text(base.format(column, "11"))
        with pytest.raises(RunTableError, match=rf"column {column}: \|11.0\| {re.escape(unit)} is not"):
            read_runs_csv(tmp_path / "t.csv")
        (tmp_path / "t.csv").write_text(base.format(column, "0"))
        if column in SIGMA_COLUMNS:
            with pytest.raises(RunTableError, match=f"column {column}: expected a 1-sigma > 0"):
                read_runs_csv(tmp_path / "t.csv")
        else:
            assert read_runs_csv(tmp_path / "t.csv").column(column).tolist() == [0.0]


def test_to_csv_writes_through_the_one_writer(tmp_path):
    runs = RunTable.from_records([{**r, "label_flagged": bool(r["label_flagged"])} for r in _rows()])
    runs.to_csv(tmp_path / "t.csv")
    header = (tmp_path / "t.csv").read_text().splitlines()[0].split(",")
    assert header == [n for n in KNOWN_COLUMNS if n in ("run", "split", *runs.extra, *runs.to_structured().dtype.names)]
    assert read_runs_csv(tmp_path / "t.csv").records() == runs.records()
