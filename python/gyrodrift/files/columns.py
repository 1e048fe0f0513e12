"""A table's column, the one type every table of the package declares its columns with: the run table and its
companions (`gyrodrift.runs.columns`, which adds the run table's contract to it), the IMU log and ``imu.parquet``
(`gyrodrift.logs.columns`) and the navigation output (`gyrodrift.ins.nav_columns`).

Each table's declaration stays in its room; this module holds what they share: the column, its cell types and their
Arrow form, the names of a tuple of columns, a family of columns sharing one meaning, and the docs table
of columns.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import pyarrow as pa

__all__ = ["DTYPES", "Column", "family", "names", "markdown_table"]

DTYPES = ("text", "float", "bool")
"""Cell types: ``float`` a float64 number (in a CSV an empty cell is unknown, NaN); ``text`` a string as is;
``bool`` a flag (``true``/``false`` in a CSV)."""

_ARROW_TYPE_NAMES = {"float": "float64", "text": "string", "bool": "bool_"}
"""The pyarrow factory of each cell type (pyarrow is imported when a Parquet schema is built, not by every command
that declares columns)."""


@dataclass(frozen=True)
class Column:
    """One column of a table.

    Attributes
    ----------
    name : str
        The header cell; its unit is in the name (``_deg``, ``_m_s``, ``_deg_h``).
    unit : str
        The unit of its values as the docs print it (``""`` for text and flags).
    meaning : str
        One line: what the value is.
    dtype : str
        One of `DTYPES` (default ``float``).
    """

    name: str
    unit: str
    meaning: str
    dtype: str = "float"

    def __post_init__(self):
        if self.dtype not in DTYPES:
            raise ValueError(f"column {self.name}: dtype {self.dtype!r} is not one of {', '.join(DTYPES)}")

    @property
    def arrow_type(self) -> pa.DataType:
        """Its type in a Parquet file."""
        import pyarrow as pa

        return getattr(pa, _ARROW_TYPE_NAMES[self.dtype])()


def family(column_names: Sequence[str], units: str | Sequence[str], meaning: str) -> tuple[Column, ...]:
    """Float columns that share one meaning (one row of the docs table); `units` one for all or one per column."""
    per_column = [units] * len(column_names) if isinstance(units, str) else list(units)
    return tuple(Column(n, u, meaning) for n, u in zip(column_names, per_column, strict=True))


def names(columns: Sequence[Column]) -> tuple[str, ...]:
    """The names of `columns`, in order."""
    return tuple(c.name for c in columns)


def markdown_table(columns: Sequence[Column]) -> str:
    """The docs table of `columns`: one row per run of consecutive columns sharing a meaning, their units joined
    (one unit when they all share it)."""
    rows = ["| column | unit | meaning |", "|---|---|---|"]
    groups: list[list[Column]] = []
    for c in columns:
        if groups and groups[-1][0].meaning == c.meaning:
            groups[-1].append(c)
        else:
            groups.append([c])
    for group in groups:
        units = [c.unit for c in group]
        unit = units[0] if len(set(units)) == 1 else ", ".join(units)
        rows.append(f"| {', '.join(f'`{c.name}`' for c in group)} | {unit} | {group[0].meaning} |")
    return "\n".join(rows)
