"""The run table's columns, each declared once: name, unit, type, when a table needs it, who writes it, meaning.

A run table is the contract between the navigation half (``gyrodrift features``, ``gyrodrift campaign
--run-table``) and the learning half (``fit``, ``predict``, `gyrodrift.learn`): one row per alignment run.
Every column list of the package (the reader's known and optional columns, the flags, the smoother's columns,
what ``features`` writes, the 1-sigma of a physics base) is derived here from `RUN_TABLE`, and the table in
docs/outputs.md is checked against it (tests/runs/test_columns.py). A new column is one `Column` in
`RUN_TABLE` (plus the code computing its value); its place in `RUN_TABLE` is its place in every written file.

The companion tables of a run table (``features --curves``, ``evaluate``'s ``position_error.parquet``) are
declared with the same `Column` in their own sections below.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

DTYPES = ("text", "float", "bool")
"""Cell types: ``text`` as is; ``float`` a number (empty = unknown, NaN); ``bool`` ``true``/``false`` (also
``1``/``0``, any case; empty = unknown), held as 1.0/0.0 in `gyrodrift.runs.table.RunTable.extra`."""

KEPT = ("attribute", "extra", "read")
"""Where `gyrodrift.runs.table.RunTable` keeps a column: an ``attribute`` of its own, in ``extra`` (an optional
per-run value, NaN where unknown), or ``read`` only (checked or converted when read, not kept)."""


@dataclass(frozen=True)
class Column:
    """One column of a table.

    Attributes
    ----------
    name : str
        The header cell; its unit is in the name (``_deg``, ``_c``, ``_deg_h``, ``_deg_h_per_c``).
    unit : str
        The unit of its values (``""`` for text and flags).
    dtype : str
        One of `DTYPES`.
    required : str
        When a table must have it: ``"always"``, ``"for fit"`` (a training table), ``"unless OTHER"`` (the column
        OTHER replaces it and the others of its group), ``"unless --OPTION"`` (unless the caller gives its value) or
        ``""`` (optional); `gyrodrift.runs.table.read_runs_csv` checks it.
    written_by : str
        The command that writes it: in the run table ``features`` (``gyrodrift features`` always, and ``campaign
        --run-table``), ``features --with-truth`` (with the truth only) or ``""`` (an input a user or
        `gyrodrift.runs.table.RunTable.to_csv` writes).
    kept : str
        One of `KEPT`.
    meaning : str
        One line: what the value is.
    tags : tuple of str
        Groups the column belongs to (``"smoother"``, ``"thermal"``, ``"physics base"``).
    std : str
        The column holding this value's 1-sigma (``""``: none).
    sigma : bool
        The value is a 1-sigma (must be > 0).
    """

    name: str
    unit: str
    dtype: str
    required: str
    written_by: str
    kept: str
    meaning: str
    tags: tuple[str, ...] = ()
    std: str = ""
    sigma: bool = False

    def __post_init__(self):
        for field, value, allowed in (("dtype", self.dtype, DTYPES), ("kept", self.kept, KEPT)):
            if value not in allowed:
                raise ValueError(f"column {self.name}: {field} {value!r} is not one of {', '.join(allowed)}")


# --- the run table -----------------------------------------------------------------------------------------

_SMOOTHER_THERMAL = ("smoother", "thermal")

RUN_TABLE: tuple[Column, ...] = (
    Column("run", "", "text", "", "features", "attribute",
           "run identifier (the log's name), unique within a table; a blank cell is numbered by its row"),
    Column("split", "", "text", "", "", "attribute", "`train`, `test` or empty (`fit --split`)"),
    Column("lat_deg", "deg", "float", "always", "features", "attribute",
           "latitude at the 12th hour of free navigation"),
    Column("lat0_deg", "deg", "float", "unless --lat0-deg", "features", "attribute",
           "the true site latitude"),
    Column("temp_min_c", "degC", "float", "unless temp_range_c", "features", "attribute",
           "lowest system temperature over the 12 h"),
    Column("temp_max_c", "degC", "float", "unless temp_range_c", "features", "attribute",
           "highest system temperature over the 12 h"),
    Column("temp_start_c", "degC", "float", "", "features", "read", "system temperature at navigation hour 0"),
    Column("temp_end_c", "degC", "float", "", "features", "read", "system temperature at navigation hour 12"),
    Column("temp_range_c", "degC", "text", "", "", "read",
           "instead of temp_min_c and temp_max_c: a `min~max` cell such as `37.1~39.5`"),
    Column("drift_curvefit_deg_h", "deg/h", "float", "", "features", "extra",
           "drift from the 12 h curve fit of the latitude and longitude errors (`gyrodrift.learn.curve_fit`)",
           tags=("physics base",), std="drift_curvefit_std_deg_h"),
    Column("drift_curvefit_std_deg_h", "deg/h", "float", "", "features", "extra",
           "its least-squares 1-sigma", sigma=True),
    Column("drift_smoother_deg_h", "deg/h", "float", "", "features", "extra",
           "drift of the 16 h smoother carried into navigation (empty with `--no-smoother`)",
           tags=("smoother", "physics base"), std="drift_smoother_std_deg_h"),
    Column("drift_smoother_std_deg_h", "deg/h", "float", "", "features", "extra", "its 1-sigma",
           tags=("smoother",), sigma=True),
    Column("smoother_coeff_deg_h_per_c", "deg/h/degC", "float", "", "features", "extra",
           "the smoother's thermal coefficient k_z (empty under its constant model)",
           tags=_SMOOTHER_THERMAL, std="smoother_coeff_std_deg_h_per_c"),
    Column("smoother_coeff_std_deg_h_per_c", "deg/h/degC", "float", "", "features", "extra", "its 1-sigma",
           tags=_SMOOTHER_THERMAL, sigma=True),
    Column("smoother_end_coeff_cov", "(deg/h)^2/degC", "float", "", "features", "extra",
           "cov(drift_smoother_deg_h, k_z), the joint posterior's off-diagonal term", tags=_SMOOTHER_THERMAL),
    Column("smoother_coeff_prior_std_deg_h_per_c", "deg/h/degC", "float", "", "features", "extra",
           "the smoother's own prior 1-sigma of k_z (mean 0)", tags=_SMOOTHER_THERMAL, sigma=True),
    Column("drift_deg_h", "deg/h", "float", "for fit", "features --with-truth", "attribute",
           "true axial drift, the training label", std="drift_std_deg_h"),
    Column("drift_std_deg_h", "deg/h", "float", "", "features --with-truth", "extra",
           "1-sigma of the label drift_deg_h (weights the training runs)", sigma=True),
    Column("label_flagged", "", "bool", "", "features --with-truth", "extra",
           "`true` when `truth` flagged the label (1-sigma beyond the 1 nmi / 72 h budget): `fit` leaves the run out"),
)  # fmt: skip
"""The run table's columns, in the order every writer writes them."""

COLUMNS: dict[str, Column] = {c.name: c for c in RUN_TABLE}
"""`RUN_TABLE` by name."""


def names(keep: Callable[[Column], bool]) -> tuple[str, ...]:
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

LABEL_COLUMNS = names(lambda c: c.written_by == "features --with-truth")
"""The columns ``features --with-truth`` adds: the label, its 1-sigma and the truth's flag."""

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


# --- the curves table of ``features --curves`` -------------------------------------------------------------

CURVES_TABLE: tuple[Column, ...] = (
    Column("run", "", "text", "always", "features", "attribute", "the run (the run table's `run`)"),
    Column("t_h", "h", "float", "always", "features", "attribute", "navigation hour since the end of alignment, 0..12"),
    Column("lat_err_arcsec", "arcsec", "float", "always", "features", "attribute",
           "latitude error at that hour, computed minus true"),
)  # fmt: skip
"""``features --curves``: one row per run and navigation hour."""


# --- the curves of ``evaluate`` (position_error.parquet) --------------------------------------------------

EVALUATION_CURVES_TABLE: tuple[Column, ...] = (
    Column("pass", "", "text", "always", "evaluate", "attribute",
           "`before` (nothing compensated) or `after` (drift_deg_h subtracted)"),
    Column("drift_deg_h", "deg/h", "float", "always", "evaluate", "attribute", "the z drift subtracted in the pass"),
    Column("t_h", "h", "float", "always", "evaluate", "attribute", "time since the end of alignment"),
    Column("north_m", "m", "float", "always", "evaluate", "attribute", "north position error, computed minus true"),
    Column("east_m", "m", "float", "always", "evaluate", "attribute", "east position error, computed minus true"),
    Column("lat_err_arcsec", "arcsec", "float", "always", "evaluate", "attribute", "latitude error, ditto"),
    Column("lon_err_arcsec", "arcsec", "float", "always", "evaluate", "attribute", "longitude error, ditto"),
    Column("pos_err_nmi", "nmi", "float", "always", "evaluate", "attribute", "position error (1 nmi = 1852 m)"),
)  # fmt: skip
"""``evaluate``'s ``position_error.parquet``: one row per kept time of each pass (``before`` then ``after``)."""
