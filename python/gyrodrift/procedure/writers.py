"""The procedure's output files: each writer takes results and writes them, nothing else.

Writers of a folder take ``out``: a folder path (the files are then published as one set with
`gyrodrift.files.atomic.OutputFolder`) or a `gyrodrift.files.atomic.Stage` of a larger set (the CLI's ``truth --out``
writes the true drift and the alignment together). Writers of one file write it with
`gyrodrift.files.atomic.atomic_write`, which replaces only a file gyrodrift wrote (recognised by its header). Figures
come from `gyrodrift.procedure.figures`; the rules for outputs are in docs/outputs.md.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from gyrodrift.files.atomic import Stage, atomic_files, check_output_files, recognise_header, staged, write_json
from gyrodrift.procedure.figures import (
    alignment_sigma_figure,
    criterion_figure,
    position_error_figure,
    route_map_figure,
    save_png,
)
from gyrodrift.procedure.results import Alignment, Evaluation, Identification, RunFeatures, TrueDrift
from gyrodrift.runs.columns import (
    CURVES_TABLE,
    EVALUATION_CURVES_TABLE,
    FEATURES_COLUMNS,
    LABEL_COLUMNS,
    TRUTH_LAW_COLUMNS,
)
from gyrodrift.runs.table import run_table_target, run_table_text

__all__ = [
    "ALIGNMENT_FILES",
    "EVALUATION_FILES",
    "EVALUATION_CURVE_COLUMNS",
    "evaluation_curves_table",
    "IDENTIFICATION_FILES",
    "TRUTH_FILES",
    "CURVES_RECOGNISER",
    "write_alignment",
    "write_evaluation",
    "write_identification",
    "write_truth",
    "check_features_outputs",
    "features_csv_text",
    "curves_csv_text",
    "write_features_csv",
]

ALIGNMENT_FILES = ("alignment.json", "alignment_z_sigma.png")
TRUTH_FILES = ("true_drift.json", "criterion.png")
EVALUATION_FILES = ("evaluation.json", "position_error.png", "position_error.parquet")
ROUTE_MAP_FILE = "route_map.png"
"""The route map an evaluation against a reference track (moving base) adds to `EVALUATION_FILES`."""


def evaluation_files(moving: bool) -> tuple[str, ...]:
    """The files `write_evaluation` publishes: `EVALUATION_FILES`, plus the route map on a moving base."""
    return EVALUATION_FILES + ((ROUTE_MAP_FILE,) if moving else ())


EVALUATION_CURVE_COLUMNS = tuple(c.name for c in EVALUATION_CURVES_TABLE)
"""Columns of ``position_error.parquet`` (`gyrodrift.runs.columns.EVALUATION_CURVES_TABLE`)."""
IDENTIFICATION_FILES = ("identification.json",)
CURVES_COLUMNS = tuple(c.name for c in CURVES_TABLE)
"""Columns of the curves table of ``features --curves`` (`gyrodrift.runs.columns.CURVES_TABLE`)."""
CURVES_RECOGNISER = recognise_header(",".join(CURVES_COLUMNS) + "\n")
"""Recognises a curves table written by `write_features_csv` (``curves=``)."""


def _paths(stage: Stage, names: Iterable[str]) -> dict[str, Path]:
    return {name: stage.folder / name for name in names}


def write_alignment(alignment: Alignment, out: str | os.PathLike[str] | Stage, command: str = "align") -> dict:
    """Write ``alignment.json`` (user units) and ``alignment_z_sigma.png`` into `out` (a folder or a stage).

    Returns the final paths, keyed ``"json"`` and ``"png"``.
    """
    with staged(out, command, ALIGNMENT_FILES) as stage:
        write_json(alignment.to_dict(), stage.file("alignment.json"))
        save_png(alignment_sigma_figure(alignment), stage.file("alignment_z_sigma.png"))
    return dict(zip(("json", "png"), _paths(stage, ALIGNMENT_FILES).values(), strict=True))


def write_truth(truth: TrueDrift, out: str | os.PathLike[str] | Stage) -> dict:
    """Write ``true_drift.json`` and ``criterion.png`` (criterion vs drift) into `out` (a folder or a stage).

    Returns the final paths, keyed ``"json"`` and ``"png"``.
    """
    with staged(out, "truth", TRUTH_FILES) as stage:
        write_json(truth.to_dict(), stage.file("true_drift.json"))
        save_png(criterion_figure(truth), stage.file("criterion.png"))
    return dict(zip(("json", "png"), _paths(stage, TRUTH_FILES).values(), strict=True))


def evaluation_curves_table(ev: Evaluation):
    """The curves of `position_error.png` as a pyarrow Table (`EVALUATION_CURVE_COLUMNS`, long format): ``pass``
    (``before``: nothing compensated, ``after``: ``drift_deg_h`` subtracted), ``t_h`` since the end of
    alignment [h], north/east errors [m], latitude/longitude errors [arcsec], position error [nmi, 1852 m];
    all computed minus true."""
    import numpy as np
    import pyarrow as pa

    parts = []
    for name, c in (("before", ev.before), ("after", ev.after)):
        n = len(c.t_h)
        parts.append(
            {
                "pass": np.full(n, name, dtype=object),
                "drift_deg_h": np.full(n, float(c.drift_deg_h)),
                "t_h": c.t_h,
                "north_m": c.north_m,
                "east_m": c.east_m,
                "lat_err_arcsec": c.lat_err_arcsec,
                "lon_err_arcsec": c.lon_err_arcsec,
                "pos_err_nmi": c.pos_err_nmi,
            }
        )
    cols = {k: np.concatenate([p[k] for p in parts]) for k in EVALUATION_CURVE_COLUMNS}
    types = {c.name: pa.string() if c.dtype == "text" else pa.float64() for c in EVALUATION_CURVES_TABLE}
    table = pa.table({k: pa.array(v, types[k]) for k, v in cols.items()})
    return table.replace_schema_metadata({"gyrodrift.format": "gyrodrift-evaluation-curves/1", "gyrodrift.run": ev.run})


def write_evaluation(ev: Evaluation, out: str | os.PathLike[str] | Stage) -> dict[str, Path]:
    """Write ``evaluation.json``, ``position_error.png`` and its curves ``position_error.parquet``
    (`evaluation_curves_table`) into `out` (a folder or a stage), as one set; on a moving base (an evaluation
    against a reference track) also the route map ``route_map.png``.

    Returns the final paths, keyed ``"json"``, ``"png"``, ``"curves"`` (and ``"route_map"``).
    """
    import pyarrow.parquet as pq

    files = evaluation_files(ev.reference is not None)
    with staged(out, "evaluate", files) as stage:
        write_json(ev.to_dict(), stage.file("evaluation.json"))
        save_png(position_error_figure(ev), stage.file("position_error.png"))
        pq.write_table(evaluation_curves_table(ev), stage.file("position_error.parquet"))
        if ev.reference is not None:
            save_png(route_map_figure(ev), stage.file(ROUTE_MAP_FILE))
    keys = ("json", "png", "curves", "route_map")
    return dict(zip(keys, _paths(stage, files).values(), strict=False))


def identification_document(res: Identification) -> dict[str, Any]:
    """`Identification.to_dict` with non-finite numbers as null, also inside its ``features`` (JSON has no NaN;
    e.g. the smoother's thermal columns are NaN under its constant model)."""

    def num(x: Any) -> Any:
        if isinstance(x, dict):
            return {k: num(v) for k, v in x.items()}
        if isinstance(x, list):
            return [num(v) for v in x]
        return None if isinstance(x, float) and not math.isfinite(x) else x

    return num(res.to_dict())


def write_identification(res: Identification, out: str | os.PathLike[str] | Stage) -> dict[str, Path]:
    """Write ``identification.json`` (format ``gyrodrift-identification/1``) into `out` (a folder or a stage)."""
    with staged(out, "identify", IDENTIFICATION_FILES) as stage:
        write_json(identification_document(res), stage.file("identification.json"))
    return {"json": stage.folder / "identification.json"}


def features_csv_text(features: Sequence[RunFeatures]) -> str:
    """The run table of `features` (`gyrodrift.runs.table.run_table_text` of their `RunFeatures.row`):
    ``FEATURES_COLUMNS``, plus the ``LABEL_COLUMNS`` (``drift_deg_h``, its 1-sigma ``drift_std_deg_h`` and
    ``label_flagged``: `truth` flagged the label) when every run has a truth, and the truth's best law
    (``TRUTH_LAW_COLUMNS``) when a truth has one. An unknown value (NaN: e.g. no curve fit) is an empty cell, which
    `gyrodrift.runs.table.read_runs_csv` reads as unknown.
    """
    with_truth = bool(features) and all(math.isfinite(f.drift_deg_h) for f in features)
    law = with_truth and any(f.truth is not None and f.truth.law is not None for f in features)
    columns = FEATURES_COLUMNS + (LABEL_COLUMNS if with_truth else ()) + (TRUTH_LAW_COLUMNS if law else ())
    return run_table_text((f.row() for f in features), columns)


def curves_csv_text(features: Sequence[RunFeatures]) -> str:
    """The hourly latitude-error curves, one row per run and hour: ``run``, ``t_h`` (navigation hour since the
    end of alignment, 0..12), ``lat_err_arcsec`` (computed minus true)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(CURVES_COLUMNS)
    for f in features:
        for h, v in enumerate(f.lat_err_curve_arcsec):
            w.writerow([f.run, h, repr(float(v))])
    return buf.getvalue()


def _features_targets(path, curves, inputs) -> list[dict[str, Any]]:
    inputs = tuple(inputs)
    targets = [run_table_target(path, inputs)]
    if curves is not None:
        targets.append({"path": curves, "inputs": inputs, "recognise": CURVES_RECOGNISER, "what": "curves table"})
    return targets


def check_features_outputs(
    path: str | os.PathLike[str],
    curves: str | os.PathLike[str] | None = None,
    inputs: Iterable[str | os.PathLike[str]] = (),
) -> None:
    """Check, before the work, that `write_features_csv` may write `path` (and `curves`)."""
    check_output_files(*_features_targets(path, curves, inputs))


def write_features_csv(
    features: Sequence[RunFeatures],
    path: str | os.PathLike[str],
    *,
    curves: str | os.PathLike[str] | None = None,
    inputs: Iterable[str | os.PathLike[str]] = (),
) -> None:
    """Write the run table (`features_csv_text`) to `path` and, if given, the curves (`curves_csv_text`) to
    `curves`, together (`gyrodrift.files.atomic.atomic_files`: neither is replaced unless both are written).

    An existing file is replaced only if it is a table of the same kind written by gyrodrift (or empty); no
    output may be one of `inputs` or the other output (docs/outputs.md).
    """
    texts = [features_csv_text(features)] + ([curves_csv_text(features)] if curves is not None else [])
    with atomic_files(*_features_targets(path, curves, inputs)) as temporaries:
        for text, tmp in zip(texts, temporaries, strict=True):
            with open(tmp, "w", encoding="utf-8", newline="") as fh:
                fh.write(text)
