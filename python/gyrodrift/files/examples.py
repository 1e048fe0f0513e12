"""The example scenarios and campaigns shipped inside the package, found by name from any folder.

``python/gyrodrift/examples/scenarios/NAME.toml`` and ``.../campaigns/NAME.toml`` are package data: they are in the
wheel, so ``gyrodrift simulate --example tour`` and ``gyrodrift campaign --example tiny`` work wherever gyrodrift is
installed (the clone's ``examples/scenarios`` and ``examples/campaigns`` are links to them, not copies).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from gyrodrift.errors import OptionError

__all__ = ["EXAMPLE_KINDS", "example_names", "example_path"]

EXAMPLE_KINDS = {"scenario": "scenarios", "campaign": "campaigns"}
"""Each kind of example and its folder inside ``gyrodrift/examples``."""


def _folder(kind: str) -> Path:
    if kind not in EXAMPLE_KINDS:
        raise ValueError(f"example kind {kind!r}: expected one of {', '.join(EXAMPLE_KINDS)}")
    return Path(str(resources.files("gyrodrift") / "examples" / EXAMPLE_KINDS[kind]))


def example_names(kind: str) -> list[str]:
    """The names (file stems, sorted) of the shipped examples of `kind` (``"scenario"`` or ``"campaign"``)."""
    return sorted(p.stem for p in _folder(kind).glob("*.toml"))


def example_path(kind: str, name: str) -> Path:
    """The file of the shipped example `name` of `kind` (``"scenario"``: ``tour``, ...; ``"campaign"``: ``tiny``, ...).

    Raises
    ------
    OptionError
        No such example: the message lists the names there are.
    """
    path = _folder(kind) / f"{name}.toml"
    if not path.is_file():
        raise OptionError(f"--example {name}: no such {kind}; expected one of {', '.join(example_names(kind))}")
    return path
