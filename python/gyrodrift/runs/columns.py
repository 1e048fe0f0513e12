"""The run table's columns, each declared once: name, unit, type, when a table needs it, who writes it, meaning.

A run table is the contract between the navigation half (``gyrodrift features``, ``gyrodrift campaign
--run-table``) and the learning half (``fit``, ``predict``, `gyrodrift.learn`): one row per alignment run.
Every column list of the package (the reader's known and optional columns, the flags, the smoother's columns,
what ``features`` writes, the 1-sigma of a physics base) is derived here from `RUN_TABLE`, and the table in
docs/outputs.md is checked against it (tests/runs/test_columns.py). A new column is one `RunColumn` in
`RUN_TABLE` (plus the code computing its value); its place in `RUN_TABLE` is its place in every written file.

The companion tables of a run table (``features --curves``, ``evaluate``'s ``position_error.parquet``) are
declared with the same `RunColumn` in their own sections below.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from gyrodrift.files.columns import Column

KEPT = ("attribute", "extra", "read")
"""Where `gyrodrift.runs.table.RunTable` keeps a column: an ``attribute`` of its own, in ``extra`` (an optional
per-run value, NaN where unknown), or ``read`` only (checked or converted when read, not kept)."""


@dataclass(frozen=True, kw_only=True)
class RunColumn(Column):
    """One column of the run table or a companion table: a `gyrodrift.files.columns.Column` (name, unit, meaning,
    cell type: a ``bool`` is ``true``/``false`` in a CSV, also ``1``/``0`` in any case, held as 1.0/0.0 in
    `gyrodrift.runs.table.RunTable.extra`) and its part of the contract between the halves, keyword-only.

    Attributes
    ----------
    kept : str
        One of `KEPT`.
    required : str
        When a table must have it: ``"always"``, ``"for fit"`` (a training table), ``"unless OTHER"`` (the column
        OTHER replaces it and the others of its group), ``"unless --OPTION"`` (unless the caller gives its value) or
        ``""`` (optional); `gyrodrift.runs.table.read_runs_csv` checks it.
    written_by : str
        The command that writes it: in the run table ``features`` (``gyrodrift features`` always, and ``campaign
        --run-table``), ``features --with-truth`` (with the truth only) or ``""`` (an input a user or
        `gyrodrift.runs.table.RunTable.to_csv` writes).
    tags : tuple of str
        Groups the column belongs to (``"smoother"``, ``"thermal"``, ``"physics base"``).
    std : str
        The column holding this value's 1-sigma (``""``: none).
    sigma : bool
        The value is a 1-sigma (must be > 0).
    """

    kept: str
    required: str = ""
    written_by: str = ""
    tags: tuple[str, ...] = ()
    std: str = ""
    sigma: bool = False

    def __post_init__(self):
        super().__post_init__()
        if self.kept not in KEPT:
            raise ValueError(f"column {self.name}: kept {self.kept!r} is not one of {', '.join(KEPT)}")


# --- the run table -----------------------------------------------------------------------------------------

_SMOOTHER_THERMAL = ("smoother", "thermal")
_TRUTH_LAW = ("truth law",)

RUN_TABLE: tuple[RunColumn, ...] = (
    RunColumn("run", "", "run identifier (the log's name), unique within a table; a blank cell is numbered by its row",
              dtype="text", written_by="features", kept="attribute"),
    RunColumn("split", "", "`train`, `test` or empty (`fit --split`)", dtype="text", kept="attribute"),
    RunColumn("lat_deg", "deg", "latitude at the 12th hour of free navigation", required="always",
              written_by="features", kept="attribute"),
    RunColumn("lat0_deg", "deg", "the true site latitude", required="unless --lat0-deg", written_by="features",
              kept="attribute"),
    RunColumn("temp_min_c", "degC", "lowest system temperature over the 12 h", required="unless temp_range_c",
              written_by="features", kept="attribute"),
    RunColumn("temp_max_c", "degC", "highest system temperature over the 12 h", required="unless temp_range_c",
              written_by="features", kept="attribute"),
    RunColumn("temp_start_c", "degC", "system temperature at navigation hour 0", written_by="features", kept="read"),
    RunColumn("temp_end_c", "degC", "system temperature at navigation hour 12", written_by="features", kept="read"),
    RunColumn("temp_range_c", "degC", "instead of temp_min_c and temp_max_c: a `min~max` cell such as `37.1~39.5`",
              dtype="text", kept="read"),
    RunColumn("drift_curvefit_deg_h", "deg/h",
              "drift from the 12 h curve fit of the latitude and longitude errors (`gyrodrift.learn.curve_fit`)",
              written_by="features", kept="extra", tags=("physics base",), std="drift_curvefit_std_deg_h"),
    RunColumn("drift_curvefit_std_deg_h", "deg/h", "its least-squares 1-sigma", written_by="features", kept="extra",
              sigma=True),
    RunColumn("drift_smoother_deg_h", "deg/h",
              "drift of the 16 h smoother carried into navigation (empty with `--no-smoother`)", written_by="features",
              kept="extra", tags=("smoother", "physics base"), std="drift_smoother_std_deg_h"),
    RunColumn("drift_smoother_std_deg_h", "deg/h", "its 1-sigma", written_by="features", kept="extra",
              tags=("smoother",), sigma=True),
    RunColumn("smoother_coeff_deg_h_per_c", "deg/h/degC",
              "the smoother's thermal coefficient k_z (empty under its constant model)", written_by="features",
              kept="extra", tags=_SMOOTHER_THERMAL, std="smoother_coeff_std_deg_h_per_c"),
    RunColumn("smoother_coeff_std_deg_h_per_c", "deg/h/degC", "its 1-sigma", written_by="features", kept="extra",
              tags=_SMOOTHER_THERMAL, sigma=True),
    RunColumn("smoother_end_coeff_cov", "(deg/h)^2/degC",
              "cov(drift_smoother_deg_h, k_z), the joint posterior's off-diagonal term", written_by="features",
              kept="extra", tags=_SMOOTHER_THERMAL),
    RunColumn("smoother_coeff_prior_std_deg_h_per_c", "deg/h/degC", "the smoother's own prior 1-sigma of k_z (mean 0)",
              written_by="features", kept="extra", tags=_SMOOTHER_THERMAL, sigma=True),
    RunColumn("truth_law_eps_ref_deg_h", "deg/h",
              "truth's best drift law eps_ref + k1 (T - T_ref): eps_ref (the best constant when k1 is undetermined)",
              written_by="features --with-truth", kept="extra", tags=_TRUTH_LAW, std="truth_law_eps_ref_std_deg_h"),
    RunColumn("truth_law_eps_ref_std_deg_h", "deg/h", "its 1-sigma", written_by="features --with-truth",
              kept="extra", tags=_TRUTH_LAW, sigma=True),
    RunColumn("truth_law_k1_deg_h_per_c", "deg/h/degC", "the best law's k1 (0 when undetermined)",
              written_by="features --with-truth", kept="extra", tags=_TRUTH_LAW, std="truth_law_k1_std_deg_h_per_c"),
    RunColumn("truth_law_k1_std_deg_h_per_c", "deg/h/degC", "its 1-sigma (empty when k1 is undetermined)",
              written_by="features --with-truth", kept="extra", tags=_TRUTH_LAW, sigma=True),
    RunColumn("truth_law_eps_k1_cov", "(deg/h)^2/degC", "cov(eps_ref, k1) of the best law (empty likewise)",
              written_by="features --with-truth", kept="extra", tags=_TRUTH_LAW),
    RunColumn("truth_law_t_ref_c", "degC", "the best law's T_ref: the temperature at navigation hour 12",
              written_by="features --with-truth", kept="read", tags=_TRUTH_LAW),
    RunColumn("drift_deg_h", "deg/h", "true axial drift, the training label", required="for fit",
              written_by="features --with-truth", kept="attribute", std="drift_std_deg_h"),
    RunColumn("drift_std_deg_h", "deg/h", "1-sigma of the label drift_deg_h (weights the training runs)",
              written_by="features --with-truth", kept="extra", sigma=True),
    RunColumn("label_flagged", "",
              "`true` when `truth` flagged the label (1-sigma beyond the 1 nmi / 72 h budget): "
              "`fit` leaves the run out",
              dtype="bool", written_by="features --with-truth", kept="extra"),
)  # fmt: skip
"""The run table's columns, in the order every writer writes them."""

COLUMNS: dict[str, RunColumn] = {c.name: c for c in RUN_TABLE}
"""`RUN_TABLE` by name."""


def names(keep: Callable[[RunColumn], bool]) -> tuple[str, ...]:
    """The names of the `RUN_TABLE` columns for which ``keep(column)`` is true, in table order."""
    return tuple(c.name for c in RUN_TABLE if keep(c))


KNOWN_COLUMNS = names(lambda c: True)
"""Every column a run table may have (any other header cell is refused)."""

ATTRIBUTE_COLUMNS = names(lambda c: c.kept == "attribute")
"""The columns `gyrodrift.runs.table.RunTable` holds as attributes (and its structured array's fields)."""

OPTIONAL_COLUMNS = names(lambda c: c.kept == "extra")
"""Optional per-run values (``RunTable.extra``, ``RunTable.column``; NaN where unknown)."""

FLAG_COLUMNS = names(lambda c: c.dtype == "bool")
"""Columns holding a yes/no flag (1.0/0.0 in ``RunTable.extra``, ``true``/``false`` in a CSV)."""

SIGMA_COLUMNS = names(lambda c: c.sigma)
"""Columns holding a 1-sigma (> 0 where known)."""

STD_COLUMNS: dict[str, str] = {c.name: c.std for c in RUN_TABLE if c.std}
"""A value's column -> the column of its 1-sigma."""

FEATURES_COLUMNS = names(lambda c: c.written_by == "features")
"""The columns ``gyrodrift features`` always writes (empty cells where unknown)."""

LABEL_COLUMNS = names(lambda c: c.written_by == "features --with-truth" and "truth law" not in c.tags)
"""The columns ``features --with-truth`` adds: the label, its 1-sigma and the truth's flag."""

TRUTH_LAW_COLUMNS = names(lambda c: "truth law" in c.tags)
"""The truth's best drift law (`gyrodrift.procedure.best_law.BestLaw.columns`): eps_ref and its 1-sigma [deg/h], k1
and its 1-sigma [deg/h/degC], their covariance [(deg/h)^2/degC], T_ref [deg C]; ``features --with-truth`` writes
them when the truth has a law (a log with a temperature)."""

SMOOTHER_COLUMNS = names(lambda c: "smoother" in c.tags)
"""The 16 h smoother's columns: its drift and 1-sigma [deg/h], then `SMOOTHER_THERMAL_COLUMNS`."""

SMOOTHER_DRIFT_COLUMNS = names(lambda c: "smoother" in c.tags and "thermal" not in c.tags)
"""The smoother's drift carried into navigation and its 1-sigma [deg/h]."""

SMOOTHER_THERMAL_COLUMNS = names(lambda c: "thermal" in c.tags)
"""The smoother's thermal estimate (empty under its constant model): k_z [deg/h/degC], its 1-sigma, cov(end drift,
k_z) [(deg/h)^2/degC] and its own prior 1-sigma of k_z [deg/h/degC]; what the fleet prior on k_z needs
(`gyrodrift.learn.fleet_prior`). A run has all four or none (`gyrodrift.runs.table.check_smoother_thermal`)."""

PHYSICS_BASE_COLUMNS = names(lambda c: "physics base" in c.tags)
"""The physics estimates of the drift a table carries (a hybrid model's base; `gyrodrift.choices.PHYSICS_COLUMNS`
adds those a model computes)."""


# --- the companion tables ---------------------------------------------------------------------------------


def _companion(name: str, unit: str, meaning: str, written_by: str, dtype: str = "float") -> RunColumn:
    """A column of a companion table: every row has it, kept as it is (``required="always"``, ``kept="attribute"``)."""
    return RunColumn(name, unit, meaning, dtype=dtype, required="always", written_by=written_by, kept="attribute")


# --- the curves table of ``features --curves`` -------------------------------------------------------------

CURVES_TABLE: tuple[RunColumn, ...] = (
    _companion("run", "", "the run (the run table's `run`)", "features", dtype="text"),
    _companion("t_h", "h", "navigation hour since the end of alignment, 0..12", "features"),
    _companion("lat_err_arcsec", "arcsec", "latitude error at that hour, computed minus true", "features"),
)  # fmt: skip
"""``features --curves``: one row per run and navigation hour."""


# --- the curves of ``evaluate`` (position_error.parquet) --------------------------------------------------

EVALUATION_CURVES_TABLE: tuple[RunColumn, ...] = (
    _companion("pass", "", "`before` (nothing compensated) or `after` (drift_deg_h subtracted)", "evaluate",
               dtype="text"),
    _companion("drift_deg_h", "deg/h", "the z drift subtracted in the pass", "evaluate"),
    _companion("t_h", "h", "time since the end of alignment", "evaluate"),
    _companion("north_m", "m", "north position error, computed minus true", "evaluate"),
    _companion("east_m", "m", "east position error, computed minus true", "evaluate"),
    _companion("lat_err_arcsec", "arcsec", "latitude error, ditto", "evaluate"),
    _companion("lon_err_arcsec", "arcsec", "longitude error, ditto", "evaluate"),
    _companion("pos_err_nmi", "nmi", "position error (1 nmi = 1852 m)", "evaluate"),
)  # fmt: skip
"""``evaluate``'s ``position_error.parquet``: one row per kept time of each pass (``before`` then ``after``)."""
