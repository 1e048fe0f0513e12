"""A minimal TOML writer for resolved scenarios: tables of numbers, strings, booleans, arrays and inline tables
(the route segments of ``[trajectory]``).

The standard library reads TOML (`tomllib`) but does not write it; scenarios need only this subset.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from typing import Any

from gyrodrift.files.atomic import atomic_write

__all__ = ["dumps_toml", "write_toml"]


def _value(v: Any, where: str) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"{where}: {v!r} cannot be written (non-finite)")
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)  # a JSON string is a valid TOML basic string
    if isinstance(v, (list, tuple)):
        if any(isinstance(x, Mapping) for x in v):  # an array of inline tables: one per line
            return "[\n" + "".join(f"  {_value(x, where)},\n" for x in v) + "]"
        return "[" + ", ".join(_value(x, where) for x in v) + "]"
    if isinstance(v, Mapping):
        for k in v:
            if not (isinstance(k, str) and k.replace("_", "").isalnum()):
                raise ValueError(f"{where}: key {k!r} cannot be written as a bare TOML key")
        return "{ " + ", ".join(f"{k} = {_value(x, where)}" for k, x in v.items()) + " }"
    raise TypeError(f"{where}: cannot write {type(v).__name__} to TOML")


def dumps_toml(data: Mapping[str, Mapping[str, Any]], header: str | None = None) -> str:
    """Render ``{section: {key: value}}`` as TOML text (sections in the given order)."""
    lines: list[str] = []
    if header:
        lines += [f"# {line}" if line else "#" for line in header.splitlines()]
        lines.append("")
    for section, table in data.items():
        lines.append(f"[{section}]")
        for key, v in table.items():
            lines.append(f"{key} = {_value(v, f'[{section}] {key}')}")
        lines.append("")
    return "\n".join(lines)


def write_toml(data: Mapping[str, Mapping[str, Any]], path: str | os.PathLike[str], header: str | None = None) -> None:
    """Write `dumps_toml(data, header)` atomically to `path`."""
    text = dumps_toml(data, header)
    with atomic_write(path, "w") as fh:
        fh.write(text)
