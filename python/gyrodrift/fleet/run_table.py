"""A campaign's successful runs as the run table `gyrodrift fit` reads (`gyrodrift.runs.table`): in memory
(`run_table`) or as a CSV file (`write_run_table`, CLI ``campaign DIR --run-table FILE``)."""

from __future__ import annotations

import math
import os
from collections.abc import Iterable
from typing import Any

import numpy as np

from gyrodrift.fleet.store import BOOL_COLUMNS, SMOOTHER_COLUMNS, CampaignRuns

__all__ = ["run_table", "write_run_table"]


def run_table(runs: CampaignRuns, source: str = "<campaign>"):
    """The successful `runs` as a `gyrodrift.runs.table.RunTable` (labels: the 72 h truth; optional columns when
    known)."""
    from gyrodrift.runs.table import OPTIONAL_COLUMNS, RunTable

    ok = runs.select(runs.ok)
    base = ("lat_deg", "lat0_deg", "temp_min_c", "temp_max_c", "drift_deg_h")
    num = {k: ok.numbers(k) for k in base + tuple(c for c in OPTIONAL_COLUMNS if c in ok.columns)}
    records = []
    for i, run in enumerate(ok["run"]):
        rec: dict[str, Any] = {"run": str(run)}
        for k, v in num.items():  # a flag (a bool column of the store) stays a bool
            if k in base or math.isfinite(v[i]):
                rec[k] = bool(v[i]) if k in BOOL_COLUMNS else float(v[i])
        records.append(rec)
    return RunTable.from_records(records, source=source)


def write_run_table(
    runs: CampaignRuns, path: str | os.PathLike[str], *, inputs: Iterable[str | os.PathLike[str]] = ()
) -> int:
    """Write the successful `runs` as a run table `gyrodrift fit` reads (``gyrodrift.runs.table``); returns its rows."""
    import csv
    import io

    from gyrodrift.files.atomic import atomic_write
    from gyrodrift.procedure.results import RUN_TABLE_COLUMNS
    from gyrodrift.procedure.writers import RUN_TABLE_RECOGNISER

    ok = runs.select(runs.ok)
    optional = ("drift_std_deg_h", *SMOOTHER_COLUMNS)
    cols = list(RUN_TABLE_COLUMNS) + ["drift_deg_h"]
    cols += [c for c in optional if c not in cols and np.isfinite(ok.numbers(c)).any()]
    values = {c: ok.numbers(c) for c in cols if c != "run"}
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    for i, run in enumerate(ok["run"]):
        w.writerow(
            [run if c == "run" else repr(float(values[c][i])) if math.isfinite(values[c][i]) else "" for c in cols]
        )
    with atomic_write(path, inputs=inputs, recognise=RUN_TABLE_RECOGNISER, what="run table") as fh:
        fh.write(buf.getvalue())
    return len(ok)
