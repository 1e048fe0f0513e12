"""The training runs as a drift model records them: the SHA-256 of their values (`training_digest`) and the order of
their optional columns in a model file (`file_column_order`). Light (numpy only): a model file's digest is checked
without importing the estimators."""

from __future__ import annotations

import hashlib
import json

import numpy as np

from gyrodrift.runs.table import RunTable

__all__ = ["file_column_order", "training_digest"]


def file_column_order(names) -> list[str]:
    """Optional run-table columns ``names`` in the order a model file's training runs and `training_digest` have them:
    their declared order (`gyrodrift.runs.columns`) but the label's 1-sigma ``drift_std_deg_h`` first, where the run
    table had it when the model files and exported code written so far were made (they keep their bytes and
    digests)."""
    return sorted(names, key=lambda name: name != "drift_std_deg_h")  # a stable sort: the others keep their order


def training_digest(runs: RunTable) -> str:
    """SHA-256 of the training runs' values (run, latitudes, temperatures, drift, then any optional columns
    by name), order included. A table without optional columns has the digest of gyrodrift 0.2.

    The optional columns are hashed in `file_column_order`; a column with no finite value is hashed as absent (a
    model file's training records leave out unknown values, so such a column does not come back on load)."""
    rows = [
        [str(r), repr(float(a)), repr(float(b)), repr(float(c)), repr(float(d)), repr(float(e))]
        for r, a, b, c, d, e in zip(
            runs.run, runs.lat_deg, runs.lat0_deg, runs.temp_min_c, runs.temp_max_c, runs.drift_deg_h, strict=False
        )
    ]
    known = [name for name in runs.extra if np.isfinite(np.asarray(runs.extra[name], dtype=float)).any()]
    for name in file_column_order(known):
        for row, v in zip(rows, runs.extra[name], strict=True):
            row.append(f"{name}={float(v)!r}")
    return hashlib.sha256(json.dumps(rows).encode()).hexdigest()
