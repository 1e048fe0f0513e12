"""The campaign folder: one Parquet file per run, each committed whole, checked on every resume and read.

``DIR/campaign.toml`` (the campaign file as given), ``DIR/campaign.json`` (its resolved content and hash),
``DIR/runs/run-NNNNNN.parquet`` (one row per run, the columns of `run_schema`, each written atomically by
`gyrodrift.files.atomic.atomic_write`). A run is done when its file is whole and holds that run
(`CampaignStore.verify`); a rerun skips it and runs a damaged one again, so an interrupted campaign (SIGINT, kill -9
of the client or of a worker) resumes without duplicates or half-written runs. The results are one Parquet dataset
(`read_runs`, ``pyarrow.dataset`` over ``DIR/runs``) with the linear 72 h error curves, from which the position
error after compensating any drift is computed without navigating again (`linear_error_nmi`).
"""

from __future__ import annotations

import json
import math
import os
import re
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gyrodrift.errors import InputError, OutputError
from gyrodrift.fleet.spec import CAMPAIGN_FORMAT, Campaign, load_campaign, run_id
from gyrodrift.runs.columns import FLAG_COLUMNS, SMOOTHER_COLUMNS, TRUTH_LAW_COLUMNS

__all__ = [
    "BOOL_COLUMNS",
    "CURVE_COLUMNS",
    "CampaignRuns",
    "CampaignStore",
    "STAGES",
    "linear_error_nmi",
    "param_column",
    "read_runs",
    "run_schema",
]

BOOL_COLUMNS = ("truth_verified", *FLAG_COLUMNS)
"""The yes/no columns of a run file (empty when unknown): the truth verified (``[options] verify``), then the run
table's flags (`gyrodrift.runs.columns.FLAG_COLUMNS`)."""
STAGES = ("align", "passes", "smoother", "twin")
"""The timed stages of a run (columns ``t_STAGE_s`` wall and ``cpu_STAGE_s`` CPU seconds, and ``_total``)."""
CURVE_COLUMNS = (
    "curve_t_h",
    "curve_north0_m",
    "curve_east0_m",
    "curve_north_per_deg_h",
    "curve_east_per_deg_h",
    "curve_north_per_k1",
    "curve_east_per_k1",
)
"""The linear 72 h error curves of a run (float32 lists): time since the end of alignment [h], uncompensated
north/east position error [m], their change per deg/h of compensated z drift [m/(deg/h)], and per deg/h/degC of a
compensated k1 (T - T_ref) about the best law's T_ref ``truth_law_t_ref_c`` [m/(deg/h/degC)] (empty without a
temperature): with them the error after compensating any law eps_ref + k1 (T - T_ref) is
``hypot(n0 + eps_ref gn + k1 hn, e0 + eps_ref ge + k1 he)`` to first order."""
_RUN_FILE_RE = re.compile(r"^run-(?P<index>[0-9]{6})\.parquet$")


def param_column(name: str) -> str:
    """The run-table column of a varied parameter: ``site.lat_deg`` -> ``param_site_lat_deg``."""
    return "param_" + re.sub(r"[^a-z0-9_]+", "_", name).strip("_")


def run_schema(campaign: Campaign):
    """The columns of a run file (a `pyarrow.Schema`): what `gyrodrift.fleet.science.process_run` returns."""
    import pyarrow as pa

    f64, s = pa.float64(), pa.string()
    fields = [("run", s), ("index", pa.int64()), ("seed", pa.int64()), ("grade", s)]
    for name in campaign.param_names:
        if name == "grade":
            continue
        kind = campaign.vary[name]
        numeric = kind.kind != "choice" or all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in kind.args[0]
        )
        fields.append((param_column(name), f64 if numeric else s))
    fields += [(c, f64) for c in ("arw_deg_rth", "vrw_ug_rthz", "lat0_deg", "lat_deg")]
    fields += [(c, f64) for c in ("temp_start_c", "temp_end_c", "temp_min_c", "temp_max_c")]
    fields += [
        (c, f64)
        for c in (
            "drift_deg_h",
            "drift_std_deg_h",
            "drift_effective_deg_h",
            "drift_curvefit_deg_h",
            "drift_curvefit_std_deg_h",
            *SMOOTHER_COLUMNS,
            "drift_align_deg_h",
            "drift_align_std_deg_h",
            "uncompensated_final_nmi",
            "hours_truth",
        )
    ]
    fields += [(c, f64) for c in TRUTH_LAW_COLUMNS]
    fields += [(c, pa.bool_()) for c in BOOL_COLUMNS]
    fields += [(f"{k}_{c}_s", f64) for k in ("t", "cpu") for c in STAGES + ("total",)]
    fields += [("error", s), ("smoother_error", s), ("worker", s)]
    fields += [(c, pa.list_(pa.float32())) for c in CURVE_COLUMNS]
    return pa.schema(fields)


def _parquet_recogniser(head: bytes) -> bool:
    return head.startswith(b"PAR1")


class CampaignStore:
    """The campaign folder: ``campaign.toml``, ``campaign.json`` and ``runs/run-NNNNNN.parquet``."""

    def __init__(self, path: str | os.PathLike[str]):
        self.path = Path(path)
        self.runs_dir = self.path / "runs"

    @classmethod
    def create_or_open(cls, path: str | os.PathLike[str], campaign: Campaign, text: str) -> CampaignStore:
        """Open the store of `campaign` at `path`, creating it if new or empty; refuse a folder holding another
        campaign or anything else (`OutputError`)."""
        from gyrodrift.files.atomic import atomic_write, atomic_write_json, recognise_json_format

        store = cls(path)
        p = store.path
        if p.exists() and not p.is_dir():
            raise OutputError(f"{p}: is a file, not a folder; give a new or empty folder to --out")
        manifest = p / "campaign.json"
        if manifest.exists():
            doc = store.manifest()
            if doc.get("digest") != campaign.digest():
                raise OutputError(
                    f"{p}: holds campaign {doc.get('name')!r} ({doc.get('source')}), not {campaign.source}; give "
                    "another --out folder (a campaign resumes only into its own folder)"
                )
            return store
        if p.exists() and any(p.iterdir()):
            raise OutputError(f"{p}: is not empty and holds no campaign; give a new or empty --out folder")
        store.runs_dir.mkdir(parents=True, exist_ok=True)
        with atomic_write(p / "campaign.toml", what="campaign file") as fh:
            fh.write(text)
        doc = {
            "format": CAMPAIGN_FORMAT,
            "name": campaign.name,
            "source": campaign.source,
            "digest": campaign.digest(),
            "resolved": campaign.resolved(),
        }
        atomic_write_json(doc, manifest, recognise=recognise_json_format(CAMPAIGN_FORMAT), what="campaign manifest")
        return store

    def manifest(self) -> dict[str, Any]:
        p = self.path / "campaign.json"
        try:
            doc = json.loads(p.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise InputError(f"{self.path}: not a campaign folder (no campaign.json)") from None
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise InputError(f"{p}: not a campaign manifest: {exc}") from None
        if not isinstance(doc, dict) or doc.get("format") != CAMPAIGN_FORMAT:
            raise InputError(f"{p}: not a campaign manifest (format {CAMPAIGN_FORMAT} expected)")
        return doc

    def campaign(self) -> Campaign:
        """The campaign of this folder (from its ``campaign.toml``)."""
        self.manifest()
        return load_campaign(self.path / "campaign.toml")

    def run_path(self, index: int) -> Path:
        return self.runs_dir / f"run-{index:06d}.parquet"

    def done(self) -> set[int]:
        """Indices of the run files present (committed whole by `write`; `verify` checks what they hold)."""
        if not self.runs_dir.is_dir():
            return set()
        return {int(m["index"]) for e in os.listdir(self.runs_dir) if (m := _RUN_FILE_RE.match(e))}

    def check_run(self, index: int, *, full: bool = False) -> tuple[str | None, bool]:
        """``(problem, ok)`` of run file `index`: ``problem`` None when it is a whole, readable Parquet file of
        exactly one row holding run `index` (its footer and metadata read, its index, run and error columns
        decoded; `full`: every column), else what is wrong (a truncated file, another run's row, an unreadable
        column); ``ok``: that row has no error."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        path = self.run_path(index)
        try:
            table = pq.ParquetFile(path).read(columns=None if full else ["index", "run", "error"])
        except (pa.ArrowException, OSError, ValueError) as exc:
            return f"not a readable Parquet file ({' '.join(str(exc).split())[:200] or type(exc).__name__})", False
        if table.num_rows != 1:
            return f"holds {table.num_rows} rows, one run expected", False
        missing = [c for c in ("index", "run", "error") if c not in table.column_names]
        if missing:
            return f"has no column {missing[0]}", False
        row = {c: table.column(c)[0].as_py() for c in ("index", "run", "error")}
        if row["index"] != index or row["run"] != run_id(index):
            return f"holds run {row['run']!r} (index {row['index']!r}), not {run_id(index)}", False
        return None, row["error"] is None

    def verify(self, *, full: bool = False) -> tuple[dict[int, bool], dict[int, str]]:
        """Check every run file (`check_run`): ``(good, damaged)``, ``good`` maps a whole run's index to True
        when it succeeded (False: a failed run, its error recorded), ``damaged`` a damaged one's to what is
        wrong. About 0.6 ms of CPU a file (`full`: every column decoded, about 2 ms)."""
        good: dict[int, bool] = {}
        damaged: dict[int, str] = {}
        for i in sorted(self.done()):
            problem, ok = self.check_run(i, full=full)
            if problem is None:
                good[i] = ok
            else:
                damaged[i] = problem
        return good, damaged

    def write(self, row: Mapping[str, Any], schema) -> None:
        """Commit one run atomically (temporary, fsync, rename): a kill leaves the run absent or whole."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        from gyrodrift.files.atomic import atomic_write

        path = self.run_path(int(row["index"]))
        table = pa.Table.from_pylist([{k: row.get(k) for k in schema.names}], schema=schema)
        with atomic_write(path, "wb", recognise=_parquet_recogniser, what="campaign run") as fh:
            pq.write_table(table, fh, compression="zstd")

    def prepare_redo(self, damaged: Mapping[int, str]) -> None:
        """Before any work: each damaged run file (index -> what is wrong) must be one gyrodrift may replace (a
        regular file with a Parquet head, or empty: else `OutputError` naming it, nothing is done); then one line on
        stderr per file says it is run again."""
        from gyrodrift.files.atomic import check_output_file

        for i in sorted(damaged):
            path = self.run_path(i)
            if path.is_symlink():  # replacing it would write wherever it points
                raise OutputError(
                    f"{path}: damaged ({damaged[i]}) and a symbolic link, not a run file gyrodrift wrote; move it out "
                    f"of {self.runs_dir} and rerun"
                )
            check_output_file(path, recognise=_parquet_recogniser, what="campaign run")
        for i in sorted(damaged):
            sys.stderr.write(f"campaign: {self.run_path(i)}: damaged ({damaged[i]}): run {i} is run again\n")
        sys.stderr.flush()


def linear_error_nmi(north0_m, east0_m, north_per_deg_h, east_per_deg_h, drift_deg_h) -> np.ndarray:
    """Position error [nmi] after compensating `drift_deg_h` [deg/h], from linear error curves (north/east [m]
    and their sensitivities [m/(deg/h)]; numpy broadcasting)."""
    from gyrodrift.earth import NMI_M

    n = np.asarray(north0_m, float) + drift_deg_h * np.asarray(north_per_deg_h, float)
    e = np.asarray(east0_m, float) + drift_deg_h * np.asarray(east_per_deg_h, float)
    return np.hypot(n, e) / NMI_M


@dataclass
class CampaignRuns:
    """The committed runs of a campaign as columns (`read_runs`), sorted by run index.

    ``columns``: one numpy array per scalar column (strings and missing values as object arrays);
    ``curves``: the linear error curves (``CURVE_COLUMNS``) as float64 arrays of shape (runs, points), or None.
    """

    columns: dict[str, np.ndarray]
    curves: dict[str, np.ndarray] | None = None

    def __len__(self) -> int:
        return len(self.columns["index"])

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    def numbers(self, name: str) -> np.ndarray:
        """A numeric column as float64 (missing = NaN)."""
        return np.array([math.nan if v is None else v for v in self.columns[name]], dtype=float)

    @property
    def ok(self) -> np.ndarray:
        """Mask of the runs that finished without an error."""
        return np.array([e is None for e in self.columns["error"]], dtype=bool)

    def select(self, which) -> CampaignRuns:
        """The runs at indices or mask `which` (a new object)."""
        which = np.asarray(which)
        curves = None if self.curves is None else {k: v[which] for k, v in self.curves.items()}
        return CampaignRuns({k: v[which] for k, v in self.columns.items()}, curves)

    def errors_nmi(self, drift_deg_h) -> np.ndarray:
        """Position error [nmi], shape (runs, points), after compensating `drift_deg_h` [deg/h] per run, from the
        linear curves: ``hypot(n0 + d gn, e0 + d ge)`` (a static base: the error is linear in the drift)."""
        if self.curves is None:
            raise ValueError("the runs were read without their curves")
        d = np.asarray(drift_deg_h, float).reshape(-1, 1)
        c = self.curves
        return linear_error_nmi(
            c["curve_north0_m"], c["curve_east0_m"], c["curve_north_per_deg_h"], c["curve_east_per_deg_h"], d
        )


def read_runs(path: str | os.PathLike[str], *, curves: bool = True) -> CampaignRuns:
    """All committed runs of a campaign folder (one Parquet dataset over ``DIR/runs``), sorted by run index;
    ``curves=False`` leaves out the linear error curves. ``pyarrow.dataset.dataset(DIR / "runs")`` reads the
    same rows with any Parquet tool (pandas, polars)."""
    import pyarrow as pa
    import pyarrow.compute as pc
    import pyarrow.dataset as ds

    store = CampaignStore(path)
    store.manifest()
    if not store.runs_dir.is_dir():
        raise InputError(f"{store.runs_dir}: no such folder: {store.path} is a campaign folder without its runs/")
    good, damaged = store.verify()
    _raise_damaged(store, damaged)
    campaign = store.campaign()
    files = [str(store.run_path(i)) for i in sorted(good)]  # the run files only: any other file there is not read
    try:
        # one schema over every run file and the current code's: a store written before a column existed
        # (resumed by newer code, or read as it is) gets that column as null in its older runs, whichever file
        # comes first
        found = ds.dataset(files, format="parquet")
        schemas = [f.physical_schema for f in found.get_fragments()] + [run_schema(campaign)]
        dataset = ds.dataset(files, format="parquet", schema=pa.unify_schemas(schemas))
        names = [n for n in dataset.schema.names if n not in CURVE_COLUMNS]
        table = dataset.to_table(columns=names + (list(CURVE_COLUMNS) if curves else []))
    except (pa.ArrowException, OSError, ValueError) as exc:  # a column the quick check did not decode
        _raise_damaged(store, store.verify(full=True)[1])
        reason = " ".join(str(exc).split())
        raise InputError(f"{store.runs_dir}: the run files do not read as one table: {reason}") from None
    table = table.take(pc.sort_indices(table, [("index", "ascending")]))
    cols: dict[str, np.ndarray] = {}
    for n in names:
        col = table.column(n)
        t = col.type
        if col.null_count == 0 and (pa.types.is_floating(t) or pa.types.is_integer(t) or pa.types.is_boolean(t)):
            cols[n] = col.to_numpy()
        else:
            cols[n] = np.array(col.to_pylist(), dtype=object)
    curve_arrays = None
    if curves:
        curve_arrays = {}
        for n in CURVE_COLUMNS:
            lists = table.column(n).to_pylist()
            width = max((len(x) for x in lists if x is not None), default=0)
            arr = np.full((len(lists), width), np.nan)
            for i, x in enumerate(lists):
                if x is not None:
                    arr[i, : len(x)] = x
            curve_arrays[n] = arr
    return CampaignRuns(cols, curve_arrays)


def _raise_damaged(store: CampaignStore, damaged: Mapping[int, str]) -> None:
    """`InputError` naming the first damaged run file of `store` (and how many), if any."""
    if damaged:
        first = min(damaged)
        more = f" ({len(damaged)} damaged run files in all)" if len(damaged) > 1 else ""
        raise InputError(
            f"{store.run_path(first)}: damaged run file: {damaged[first]}{more}; rerun the campaign command that "
            f"made {store.path} (the same campaign file, --out {store.path}) to run it again"
        )
