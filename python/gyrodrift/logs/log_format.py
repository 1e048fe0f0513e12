"""Log format descriptions: how a recorded IMU log's own columns map to gyrodrift's quantities (a small TOML file).

A real INS log has its own column names, units (deg/s, deg/h, g, mg, pulse counts), increments or rates, time
in s / ms / us or ISO date-times, a delimiter, a preamble before its header and axes that are not body
right-forward-up. A `LogFormat` describes that once; `gyrodrift.logs.open_log(path, format=...)` (CLI
``--format FILE``) reads the log through it with the same checks and errors as a native log, naming the file's
own columns. Example (docs/procedure.md has the full reference and examples/logs/ two complete files)::

    [csv]                    # ignored for Parquet logs
    delimiter = ";"
    header_row = 3           # 1-based line naming the columns (the lines before it are skipped)
    comment = "#"            # lines starting with this are skipped

    [axes]                   # body axis = signed file axis (the file's x, y, z of the gyro_/accel_ quantities)
    right = "-y"
    forward = "x"
    up = "z"

    [columns.Time]
    quantity = "time"
    unit = "ms"

    [columns.GyroX]
    quantity = "gyro_x"
    unit = "deg/s"
    scale = 1.0              # value = raw * scale + offset, in `unit`
    offset = 0.0

A pulse-count column has ``unit = "pulse"`` with ``pulse_weight`` (a number > 0) and ``pulse_unit`` (an
increment unit: ``arcsec`` per pulse, ``mm/s`` per pulse, ...). Whether the log holds increments or rates follows
from the units; all six sensor columns must agree.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from gyrodrift.errors import InputError
from gyrodrift.files.toml_input import read_toml
from gyrodrift.files.toml_schema import Number, Scope, show, type_name

__all__ = ["LogFormatError", "LogFormat", "ColumnSpec", "load_log_format", "QUANTITIES", "UNITS"]

_G0 = 9.80665
_ARCSEC = math.pi / 180.0 / 3600.0

# unit -> (dimension, factor to SI, shift added after the factor)
UNITS: dict[str, dict[str, tuple[float, float]]] = {
    "time": {"s": (1.0, 0.0), "ms": (1e-3, 0.0), "us": (1e-6, 0.0), "ns": (1e-9, 0.0), "iso": (1.0, 0.0)},
    "angle": {  # increments [rad]
        "rad": (1.0, 0.0),
        "mrad": (1e-3, 0.0),
        "urad": (1e-6, 0.0),
        "deg": (math.pi / 180.0, 0.0),
        "arcsec": (_ARCSEC, 0.0),
    },
    "angular_rate": {  # rates [rad/s]
        "rad/s": (1.0, 0.0),
        "mrad/s": (1e-3, 0.0),
        "deg/s": (math.pi / 180.0, 0.0),
        "deg/h": (math.pi / 180.0 / 3600.0, 0.0),
    },
    "velocity": {"m/s": (1.0, 0.0), "mm/s": (1e-3, 0.0), "g*s": (_G0, 0.0)},  # increments [m/s]
    "acceleration": {  # rates [m/s^2]
        "m/s^2": (1.0, 0.0),
        "g": (_G0, 0.0),
        "mg": (_G0 * 1e-3, 0.0),
        "ug": (_G0 * 1e-6, 0.0),
    },
    "temperature": {"degC": (1.0, 0.0), "K": (1.0, -273.15), "degF": (5.0 / 9.0, -32.0 * 5.0 / 9.0)},
    "attitude": {"deg": (1.0, 0.0), "rad": (180.0 / math.pi, 0.0)},  # truth columns are stored in deg
    "height": {"m": (1.0, 0.0), "km": (1e3, 0.0), "ft": (0.3048, 0.0)},  # reference height [m]
}
"""Accepted units per dimension: factor and shift to the reader's units (s, rad, rad/s, m/s, m/s^2, deg C, deg,
m)."""

QUANTITIES = {
    "time": ("time",),
    "gyro_x": ("angle", "angular_rate"),
    "gyro_y": ("angle", "angular_rate"),
    "gyro_z": ("angle", "angular_rate"),
    "accel_x": ("velocity", "acceleration"),
    "accel_y": ("velocity", "acceleration"),
    "accel_z": ("velocity", "acceleration"),
    "temperature": ("temperature",),
    "true_pitch": ("attitude",),
    "true_roll": ("attitude",),
    "true_yaw": ("attitude",),
    "ref_height": ("height",),
}
"""Quantities a column can hold (``gyro_``/``accel_`` x y z are the file's axes) and the dimensions their unit may
have."""

_SECTIONS = ("csv", "axes", "columns")
_COLUMN_KEYS = ("quantity", "unit", "scale", "offset", "pulse_weight", "pulse_unit")
_CSV_KEYS = ("delimiter", "header_row", "comment")
_BODY = ("right", "forward", "up")
MAX_FORMAT_BYTES = 1_000_000
_NUMBER = Number()


class LogFormatError(InputError):
    """A log format file (or dict) is invalid; the message names the file and the key."""


@dataclass(frozen=True)
class ColumnSpec:
    """One column of the file: its name in the file, quantity, unit and the affine map to the reader's units.

    ``value = (raw * scale + offset) * factor + shift`` in s, rad, rad/s, m/s, m/s^2, deg C, deg (the truth) or m
    (the reference height).
    """

    name: str
    quantity: str
    unit: str
    dimension: str
    scale: float
    offset: float
    factor: float
    shift: float

    @property
    def is_iso_time(self) -> bool:
        return self.quantity == "time" and self.unit == "iso"

    def convert(self, raw: np.ndarray) -> np.ndarray:
        """The column in the reader's units (float64)."""
        a = np.asarray(raw, dtype=np.float64)
        k = self.scale * self.factor
        b = self.offset * self.factor + self.shift
        if k == 1.0 and b == 0.0:
            return a
        return a * k + b if b != 0.0 else a * k

    def describe(self) -> str:
        """How messages name the column: ``GyroY (gyro_y, deg/s)``."""
        unit = self.unit if self.unit != "pulse" else "pulses"
        return f"{self.name} ({self.quantity}, {unit})"


@dataclass(frozen=True)
class LogFormat:
    """A validated log format description (`load_log_format`, `LogFormat.from_dict`).

    Attributes
    ----------
    source : str
        The file (or ``<dict>``) it came from, for messages.
    delimiter : str
        CSV cell delimiter (one character; default ``,``).
    header_row : int
        1-based line of a CSV file that names the columns; earlier lines are skipped (default 1).
    comment : str or None
        CSV lines starting with this prefix are skipped anywhere (default none).
    columns : tuple of ColumnSpec
        The columns the format names (other columns of the file are ignored).
    axes : tuple of 3 (int, float)
        For body right, forward, up: the file axis (0 = x, 1 = y, 2 = z) and its sign (+1 or -1).
    kind : {"increments", "rates"}
        What the six sensor columns hold, from their units.
    """

    source: str
    delimiter: str
    header_row: int
    comment: str | None
    columns: tuple[ColumnSpec, ...]
    axes: tuple[tuple[int, float], ...]
    kind: str

    def column(self, quantity: str) -> ColumnSpec | None:
        """The column holding `quantity`, or None."""
        for c in self.columns:
            if c.quantity == quantity:
                return c
        return None

    @property
    def has_temperature(self) -> bool:
        return self.column("temperature") is not None

    @property
    def has_truth(self) -> bool:
        return all(self.column(q) is not None for q in ("true_pitch", "true_roll", "true_yaw"))

    def body_source(self, sensor: str, j: int) -> tuple[ColumnSpec, float]:
        """The file column and sign that give body axis `j` (0 right, 1 forward, 2 up) of ``gyro`` or ``accel``."""
        axis, sign = self.axes[j]
        spec = self.column(f"{sensor}_{'xyz'[axis]}")
        assert spec is not None  # validated: all six sensor columns exist
        return spec, sign

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "<dict>") -> LogFormat:
        """Validate a TOML-shaped mapping; `LogFormatError` naming `source` and the key otherwise."""
        return _Validator(source).format(data)


def load_log_format(path: str | os.PathLike[str] | LogFormat) -> LogFormat:
    """Read and validate a log format TOML file (a `LogFormat` is returned as is).

    Raises
    ------
    LogFormatError
        Missing or unreadable file, invalid TOML, unknown or invalid key (the message names the file and key).
    """
    if isinstance(path, LogFormat):
        return path
    source = str(path)
    data = read_toml(path, LogFormatError, expected="a log format TOML file", max_bytes=MAX_FORMAT_BYTES)
    return LogFormat.from_dict(data, source)


class _Validator:
    """Turns a TOML-shaped mapping into a `LogFormat`, naming the file and key in every error."""

    def __init__(self, source: str):
        self.source = source
        self.root = Scope(source, LogFormatError)

    def format(self, data: Mapping[str, Any]) -> LogFormat:
        root = self.root
        if not isinstance(data, Mapping):
            raise root.fail(None, f"expected a table, got {type_name(data)}")
        for k in data:
            if k not in _SECTIONS:
                raise root.section(k).fail(None, f"unknown section (expected one of: {', '.join(_SECTIONS)})")
        csv = root.table(data, "csv", _CSV_KEYS)
        where = root.section("csv")
        delimiter = csv.get("delimiter", ",")
        if not isinstance(delimiter, str) or len(delimiter) != 1 or delimiter in '\r\n"':
            raise where.fail("delimiter", f"expected one character (not a quote or newline), got {delimiter!r}")
        header_row = csv.get("header_row", 1)
        if isinstance(header_row, bool) or not isinstance(header_row, int) or not 1 <= header_row <= 1000:
            raise where.fail("header_row", f"expected an integer line number in [1, 1000], got {show(header_row)}")
        comment = csv.get("comment")
        if comment is not None and (not isinstance(comment, str) or not comment.strip() or "\n" in comment):
            raise where.fail("comment", f'expected a non-empty prefix such as "#", got {comment!r}')
        axes = self.axes(root.table(data, "axes", _BODY))
        cols = data.get("columns")
        where = root.section("columns")
        if not isinstance(cols, Mapping) or not cols:
            raise where.fail(None, "missing: give one [columns.NAME] table per column of the file used")
        specs = [self.column(str(name), spec) for name, spec in cols.items()]
        seen: dict[str, str] = {}
        for s in specs:
            if s.quantity in seen:
                raise root.section(f"columns.{s.name}").fail(
                    "quantity", f"{s.quantity!r} is already given by column {seen[s.quantity]!r}; each quantity once"
                )
            seen[s.quantity] = s.name
        missing = [q for q in ("time", *(f"{s}_{a}" for s in ("gyro", "accel") for a in "xyz")) if q not in seen]
        if missing:
            raise where.fail(None, f"no column for {', '.join(missing)} (a log needs time and six sensor axes)")
        truth = [q for q in ("true_pitch", "true_roll", "true_yaw") if q in seen]
        if truth and len(truth) != 3:
            raise where.fail(None, "give all three of true_pitch, true_roll, true_yaw or none")
        kinds = {s.name: ("increments" if s.dimension in ("angle", "velocity") else "rates") for s in specs}
        sensor = [s for s in specs if s.quantity.startswith(("gyro_", "accel_"))]
        if len({kinds[s.name] for s in sensor}) != 1:
            inc = [s.name for s in sensor if kinds[s.name] == "increments"]
            rat = [s.name for s in sensor if kinds[s.name] == "rates"]
            raise where.fail(
                None,
                f"mixed increments ({', '.join(inc)}) and rates ({', '.join(rat)}); all six sensor columns must "
                "hold increments (angle, velocity, pulse units) or all rates (deg/s, g, ... units)",
            )
        return LogFormat(
            source=self.source,
            delimiter=delimiter,
            header_row=header_row,
            comment=comment,
            columns=tuple(specs),
            axes=axes,
            kind=kinds[sensor[0].name],
        )

    def axes(self, t: Mapping[str, Any]) -> tuple[tuple[int, float], ...]:
        where = self.root.section("axes")
        out = []
        default = {"right": "x", "forward": "y", "up": "z"}
        for body in _BODY:
            v = t.get(body, default[body])
            text = v.strip().lower() if isinstance(v, str) else ""
            sign = -1.0 if text.startswith("-") else 1.0
            axis = text.lstrip("+-")
            if axis not in ("x", "y", "z"):
                raise where.fail(body, f"expected a file axis with an optional sign (x, -y, +z), got {v!r}")
            out.append(("xyz".index(axis), sign))
        if len({a for a, _ in out}) != 3:
            raise where.fail(None, f"each file axis once: right, forward, up = {[t.get(b, default[b]) for b in _BODY]}")
        # A proper rotation keeps right-forward-up right-handed; a mirror would flip the turntable's sense.
        m = np.zeros((3, 3))
        for j, (a, s) in enumerate(out):
            m[j, a] = s
        if np.linalg.det(m) < 0:
            raise where.fail(
                None, "the mapping is a mirror (determinant -1): the file's axes must form a right-handed triad"
            )
        return tuple(out)

    def column(self, name: str, spec: Any) -> ColumnSpec:
        where = self.root.section(f"columns.{name}")
        if not isinstance(spec, Mapping):
            raise where.fail(None, f"expected a table with quantity and unit, got {type_name(spec)}")
        where.keys(spec, _COLUMN_KEYS)
        q = spec.get("quantity")
        if not isinstance(q, str) or q not in QUANTITIES:
            raise where.fail("quantity", f"expected one of {', '.join(QUANTITIES)}, got {show(q)}")
        unit = spec.get("unit")
        dims = QUANTITIES[q]
        allowed = [u for d in dims for u in UNITS[d]] + (["pulse"] if q.startswith(("gyro_", "accel_")) else [])
        if unit not in allowed:
            raise where.fail("unit", f"expected one of {', '.join(allowed)} for {q}, got {show(unit)}")
        scale = where.value(spec, "scale", _NUMBER, 1.0)
        if scale == 0.0:
            raise where.fail("scale", "must not be 0")
        offset = where.value(spec, "offset", _NUMBER, 0.0)
        pulse = [k for k in ("pulse_weight", "pulse_unit") if k in spec]
        if unit == "pulse":
            if len(pulse) != 2:
                raise where.fail(None, "a pulse column needs pulse_weight (a number > 0) and pulse_unit")
            weight = where.value(spec, "pulse_weight", Number.positive(), None)
            dim = "angle" if q.startswith("gyro_") else "velocity"
            punit = spec["pulse_unit"]
            if not isinstance(punit, str) or punit not in UNITS[dim]:
                raise where.fail("pulse_unit", f"expected one of {', '.join(UNITS[dim])}, got {show(punit)}")
            factor, shift = UNITS[dim][punit]
            factor *= weight
        else:
            if pulse:
                raise where.fail(pulse[0], 'only for unit = "pulse"')
            dim = next(d for d in dims if unit in UNITS[d])
            factor, shift = UNITS[dim][unit]
            if unit == "iso" and (scale != 1.0 or offset != 0.0):
                raise where.fail(None, "ISO date-times take no scale or offset")
        return ColumnSpec(name, q, unit, dim, scale, offset, factor, shift)
