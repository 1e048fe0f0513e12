"""A campaign's successful runs as the run table `gyrodrift fit` reads (`gyrodrift.runs.columns`): in memory
(`run_table`) or as the rows and columns of `gyrodrift.runs.table.write_run_table` (`run_table_rows`, CLI
``campaign DIR --run-table FILE``)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from gyrodrift.fleet.store import CampaignRuns
from gyrodrift.runs.columns import (
    ATTRIBUTE_COLUMNS,
    FEATURES_COLUMNS,
    FLAG_COLUMNS,
    OPTIONAL_COLUMNS,
    TRUTH_LAW_COLUMNS,
)

__all__ = ["run_table", "run_table_rows"]

LABELLED = tuple(c for c in ATTRIBUTE_COLUMNS if c not in ("run", "split"))
"""The run table's attributes every successful run has: its inputs and its label (the 72 h truth)."""


def run_table(runs: CampaignRuns, source: str = "<campaign>"):
    """The successful `runs` as a `gyrodrift.runs.table.RunTable` (labels: the 72 h truth; optional columns when
    known)."""
    from gyrodrift.runs.table import RunTable, known_values

    ok = runs.select(runs.ok)
    num = {k: known_values(k, ok.numbers(k)) for k in LABELLED + tuple(c for c in OPTIONAL_COLUMNS if c in ok.columns)}
    records = []
    for i, run in enumerate(ok["run"]):
        rec: dict[str, Any] = {"run": str(run)}
        for k, v in num.items():  # a flag (a bool column of the store) stays a bool
            if k in LABELLED or math.isfinite(v[i]):
                rec[k] = bool(v[i]) if k in FLAG_COLUMNS else float(v[i])
        records.append(rec)
    return RunTable.from_records(records, source=source)


def run_table_rows(runs: CampaignRuns) -> tuple[list[dict[str, Any]], tuple[str, ...]]:
    """The successful `runs` as run-table rows and the columns to write: those ``gyrodrift features`` writes, the
    label ``drift_deg_h`` and, each when any run has it, its 1-sigma ``drift_std_deg_h`` and the truth's best law
    (`gyrodrift.runs.columns.TRUTH_LAW_COLUMNS`, as ``features --with-truth`` writes them).

    A 1-sigma of 0 (a noise-free run: no noise to measure) is unknown (`gyrodrift.runs.table.known_values`), as the
    run-table reader expects a 1-sigma > 0: such a column is left out."""
    from gyrodrift.runs.table import known_values

    ok = runs.select(runs.ok)
    columns: tuple[str, ...] = (*FEATURES_COLUMNS, "drift_deg_h")
    values = {c: ok.numbers(c) for c in columns if c != "run"}
    for name in ("drift_std_deg_h", *TRUTH_LAW_COLUMNS):
        if name not in ok.columns:
            continue
        v = known_values(name, ok.numbers(name))
        if np.isfinite(v).any():
            columns += (name,)
            values[name] = v
    rows = [{"run": str(run), **{c: v[i] for c, v in values.items()}} for i, run in enumerate(ok["run"])]
    return rows, columns
