"""Validating a TOML document (scenario, log format, ...): typed field specs and one-line errors naming the key.

A validator declares each table's fields once and reads them through a `Scope`, which knows the file and the
place in it, so that every refusal is one line ``<file>: [table] key: what was expected, got what``::

    SITE = {"lat_deg": Number.in_range(-89.0, 89.0), "height_m": Number.non_negative()}
    root = Scope("s.toml", ScenarioError)
    table = root.table(data, "site", allowed=SITE)           # {} when absent; unknown keys refused
    values = root.section("site").fields(table, SITE, Site())  # absent keys take Site()'s defaults
    seed = root.section("run").value(run_table, "seed", Integer(ge=0), 0)   # one key

Nested places are scopes too: ``root.section("trajectory").item("segments[0]")`` names its keys
``[trajectory] segments[0].kind``, and `Scope.tables` walks an array of tables that way. The specs:
`Number` (a finite number with optional bounds), `Integer`, `Numbers` (an array of finite numbers, of a fixed
length or non-empty), `Choice` (one of some values) and `Flag` (true or false). Reading the file itself is
`gyrodrift.files.toml_input.read_toml`'s job.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Iterator, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

__all__ = ["Scope", "Field", "Number", "Integer", "Numbers", "Choice", "Flag", "type_name", "show", "fmt_number"]


def type_name(v: Any) -> str:
    """The TOML type of `v` for a message: boolean, string, array, table, number (else the Python type's name)."""
    if isinstance(v, bool):
        return "boolean"
    if isinstance(v, str):
        return "string"
    if isinstance(v, (list, tuple)):
        return "array"
    if isinstance(v, Mapping):
        return "table"
    if isinstance(v, (int, float)):
        return "number"
    return type(v).__name__


def show(v: Any) -> str:
    """`v` for a message: its repr, cut to 60 characters (an integer of thousands of digits is described)."""
    if isinstance(v, int) and not isinstance(v, bool) and v.bit_length() > 200:
        return f"an integer of about {int(v.bit_length() * 0.30103) + 1} digits"
    try:
        r = repr(v)
    except (ValueError, RecursionError):
        return f"a {type_name(v)}"
    return r if len(r) <= 60 else r[:57] + "..."


def fmt_number(v: float) -> str:
    """A number for a message: 90.0 as 90, 0.5 as 0.5."""
    return str(int(v)) if float(v).is_integer() and abs(v) < 1e15 else repr(float(v))


def _finite(v: int | float) -> float | None:
    """`v` as a finite float, or None (NaN, infinity, or an integer beyond the float range)."""
    try:
        f = float(v)
    except OverflowError:
        return None
    return f if math.isfinite(f) else None


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


class Scope:
    """A place in one TOML document: the file (`source`), a ``[table]`` (None: the top) and a key path inside it
    (``segments[0]``). `fail` builds the error (the caller's class) naming the place; the readers refuse values
    with it."""

    def __init__(
        self, source: str, error: Callable[[str], Exception], table: str | None = None, path: str | None = None
    ):
        self.source = source
        self.error = error
        self.table_name = table
        self.path = path

    def section(self, name: str) -> Scope:
        """The scope of the document's ``[name]`` table."""
        return Scope(self.source, self.error, name)

    def item(self, key: str) -> Scope:
        """The scope of a table nested at `key` (``segments[0]``): its keys are named ``segments[0].KEY``."""
        return Scope(self.source, self.error, self.table_name, self.name(key))

    def name(self, key: str | None) -> str | None:
        """How messages name `key` here (None: the scope itself)."""
        if key is None:
            return self.path
        return f"{self.path}.{key}" if self.path else key

    def fail(self, key: str | None, message: str) -> Exception:
        """The error ``<file>: [table] key: message`` (the parts that exist) for `key` of this scope."""
        where = self.source
        if self.table_name is not None:
            where += f": [{self.table_name}]"
        name = self.name(key)
        if name:
            where += f" {name}"
        return self.error(f"{where}: {message}")

    def table(self, data: Mapping[str, Any], name: str, allowed: Collection[str]) -> Mapping[str, Any]:
        """The ``[name]`` table of `data` (this scope's table of sections; {} when absent), with only `allowed`
        keys."""
        t = data.get(name, {})
        if not isinstance(t, Mapping):
            raise self.fail(None, f"[{name}] must be a table, got {type_name(t)}")
        self.section(name).keys(t, allowed)
        return t

    def keys(self, t: Mapping[str, Any], allowed: Collection[str], what: str = "") -> None:
        """Refuse a key of `t` not in `allowed` (``unknown key<what> (expected one of: ...)``)."""
        for key in t:
            if key not in allowed:
                raise self.fail(key, f"unknown key{what} (expected one of: {', '.join(allowed)})")

    def require(self, t: Mapping[str, Any], keys: Collection[str]) -> None:
        """Refuse `t` without one of `keys` (``missing KEY``, named at this scope)."""
        for key in keys:
            if key not in t:
                raise self.fail(None, f"missing {key}")

    def one_of(self, t: Mapping[str, Any], a: str, b: str) -> None:
        """Refuse `t` unless it has exactly one of the keys `a` and `b` (``give exactly one of a and b``)."""
        if (a in t) == (b in t):
            raise self.fail(None, f"give exactly one of {a} and {b}")

    def value(self, t: Mapping[str, Any], key: str, spec: Field, default: Any) -> Any:
        """The value of `key` in `t` checked by `spec`, or `default` (converted by the spec; None stays None)
        when absent."""
        if key in t:
            return spec.read(self, key, t[key])
        return None if default is None else spec.default(default)

    def fields(self, t: Mapping[str, Any], specs: Mapping[str, Field], defaults: object = None) -> dict[str, Any]:
        """`value` of every key of `specs`, in their order; an absent key takes the attribute of `defaults` (a
        dataclass of defaults; None: absent keys are None)."""
        return {key: self.value(t, key, spec, getattr(defaults, key, None)) for key, spec in specs.items()}

    def tables(self, key: str, value: Any, *, non_empty: bool = False) -> Iterator[tuple[Scope, Mapping[str, Any]]]:
        """The tables of the array of tables `value` at `key`, each with its scope (``key[i]``): the array is
        checked now, each element when it is reached."""
        if not isinstance(value, (list, tuple)) or (non_empty and not value):
            want = "a non-empty array of tables" if non_empty else "an array of tables"
            raise self.fail(key, f"expected {want}, got {type_name(value)} {show(value)}")
        return self._elements(key, value)

    def _elements(self, key: str, value: list[Any] | tuple[Any, ...]) -> Iterator[tuple[Scope, Mapping[str, Any]]]:
        for i, element in enumerate(value):
            scope = self.item(f"{key}[{i}]")
            if not isinstance(element, Mapping):
                raise scope.fail(None, f"expected a table, got {type_name(element)} {show(element)}")
            yield scope, element


class Field(Protocol):
    """A field spec: checks a value that is present, converts a default that is not."""

    def read(self, scope: Scope, key: str, v: Any) -> Any:
        """`v` checked and converted, or ``scope.fail(key, ...)`` raised."""
        ...

    def default(self, v: Any) -> Any:
        """A default value in the type `read` returns."""
        ...


@dataclass(frozen=True)
class Number:
    """A finite number (TOML integer or float; returned as float). Bounds, each with its message: `gt` (``must be >
    gt``), `ge` (``must be >= ge``), `le` (``must be at most le<unit>``) checked in that order, or `between` (``must
    be between lo and hi``, exclusive with `strictly`). Build it with the class methods."""

    gt: float | None = None
    ge: float | None = None
    le: float | None = None
    unit: str = ""
    between: tuple[float, float] | None = None
    strictly: bool = False

    @classmethod
    def positive(cls, at_most: float | None = None, unit: str = "") -> Number:
        """A number > 0 (and at most `at_most`, printed with `unit`, e.g. " deg/s")."""
        return cls(gt=0.0, le=at_most, unit=unit)

    @classmethod
    def non_negative(cls) -> Number:
        """A number >= 0."""
        return cls(ge=0.0)

    @classmethod
    def in_range(cls, lo: float, hi: float, *, strictly: bool = False) -> Number:
        """A number in [lo, hi] (in (lo, hi) when `strictly`)."""
        return cls(between=(lo, hi), strictly=strictly)

    def read(self, scope: Scope, key: str, v: Any) -> float:
        if not _is_number(v):
            raise scope.fail(key, f"expected a number, got {type_name(v)} {show(v)}")
        f = _finite(v)
        if f is None:
            raise scope.fail(key, f"expected a finite number, got {show(v)}")
        if self.gt is not None and not f > self.gt:
            raise scope.fail(key, f"must be > {fmt_number(self.gt)}, got {fmt_number(f)}")
        if self.ge is not None and f < self.ge:
            raise scope.fail(key, f"must be >= {fmt_number(self.ge)}, got {fmt_number(f)}")
        if self.le is not None and f > self.le:
            raise scope.fail(key, f"must be at most {self.le:.6g}{self.unit}, got {fmt_number(f)}")
        if self.between is not None:
            lo, hi = self.between
            if not (lo < f < hi if self.strictly else lo <= f <= hi):
                kind = "strictly between" if self.strictly else "between"
                raise scope.fail(key, f"must be {kind} {fmt_number(lo)} and {fmt_number(hi)}, got {fmt_number(f)}")
        return f

    def default(self, v: Any) -> float:
        return float(v)


@dataclass(frozen=True)
class Integer:
    """A TOML integer >= `ge` (``must be >= ge``) and < `lt` (``must be < lt``) when given; returned as int."""

    ge: int | None = None
    lt: int | None = None
    lt_text: str | None = None
    """How a message writes `lt` (e.g. ``2**64``; default its digits)."""

    def read(self, scope: Scope, key: str, v: Any) -> int:
        if isinstance(v, bool) or not isinstance(v, int):
            raise scope.fail(key, f"expected an integer, got {type_name(v)} {show(v)}")
        if self.ge is not None and v < self.ge:
            raise scope.fail(key, f"must be >= {self.ge}, got {show(v)}")
        if self.lt is not None and v >= self.lt:
            raise scope.fail(key, f"must be < {self.lt_text or self.lt}, got {show(v)}")
        return v

    def default(self, v: Any) -> int:
        return int(v)


@dataclass(frozen=True)
class Numbers:
    """An array of finite numbers: exactly `n` of them (``expected 3 numbers, got 2``), or at least one when `n`
    is None; returned as a tuple of floats."""

    n: int | None = None

    def read(self, scope: Scope, key: str, v: Any) -> tuple[float, ...]:
        n = self.n
        if not isinstance(v, (list, tuple)):
            want = f"{n} numbers" if n is not None else "an array of numbers"
            raise scope.fail(key, f"expected {want}, got {type_name(v)} {show(v)}")
        if n is not None and len(v) != n:
            raise scope.fail(key, f"expected {n} numbers, got {len(v)}")
        if n is None and len(v) == 0:
            raise scope.fail(key, "expected at least 1 number, got 0")
        out = []
        for i, x in enumerate(v):
            if not _is_number(x):
                raise scope.fail(key, f"element {i}: expected a number, got {type_name(x)} {show(x)}")
            f = _finite(x)
            if f is None:
                raise scope.fail(key, f"element {i}: expected a finite number, got {show(x)}")
            out.append(f)
        return tuple(out)

    def default(self, v: Any) -> tuple[float, ...]:
        return tuple(float(x) for x in v)


@dataclass(frozen=True)
class Choice:
    """One of `options` (``expected one of 'a', 'b', got 'c'``)."""

    options: tuple[Any, ...]

    def read(self, scope: Scope, key: str, v: Any) -> Any:
        if not any(type(v) is type(o) and v == o for o in self.options):
            raise scope.fail(key, f"expected one of {', '.join(map(repr, self.options))}, got {show(v)}")
        return v

    def default(self, v: Any) -> Any:
        return v


@dataclass(frozen=True)
class Flag:
    """A TOML boolean (``expected true or false``)."""

    def read(self, scope: Scope, key: str, v: Any) -> bool:
        if not isinstance(v, bool):
            raise scope.fail(key, f"expected true or false, got {type_name(v)} {show(v)}")
        return v

    def default(self, v: Any) -> bool:
        return bool(v)
