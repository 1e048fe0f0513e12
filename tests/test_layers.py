"""The package's layers, declared once, and the import arrows checked against them (every import, function-level and
``TYPE_CHECKING`` ones included).

A module may import from a lower layer or from its own room (package); rooms of one layer do not import each other;
no import cycle anywhere, inside a room neither. docs/architecture.md draws this order; `gyrodrift.procedure` keeps
its own finer order (tests/procedure/test_procedure_layers.py).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "python" / "gyrodrift"

LAYERS: tuple[tuple[str, ...], ...] = (
    # foundation: the core, errors, units and the Earth model, the site, shared choices, progress
    ("_core", "errors", "progress", "choices", "earth", "units", "site", "drift_law", "__init__"),
    ("files",),  # atomic outputs, bounded reads, TOML
    ("runs",),  # the run table (the contract between the halves) and the paper's runs
    ("learn", "sensors", "testing"),  # estimators and the drift model; Allan deviation; optimiser test functions
    ("logs",),  # IMU logs: readers, formats, validator
    ("ins",),  # scenarios, simulation, free navigation
    ("procedure",),  # alignment, truth, smoother, features, identification, planning
    ("export",),  # the drift model as C and Rust
    ("fleet",),  # campaigns, the store, the executor, the study
    ("paper",),  # the paper reproduced
    ("cli",),  # the command line
)
"""Rooms from the bottom up: the top-level modules of the foundation, then packages. The package's ``__init__`` is
in the foundation: it defines ``__version__`` and loads its public names lazily (PEP 562), importing nothing."""

FOUNDATION = set(LAYERS[0])


def room_of(module: str) -> str:
    """The room of a dotted module below ``gyrodrift`` (``learn.lssvr`` -> ``learn``; ``earth`` -> ``earth``)."""
    return module.split(".")[0]


def rank_of(room: str) -> int:
    for rank, rooms in enumerate(LAYERS):
        if room in rooms:
            return rank
    raise AssertionError(f"room {room!r} is in no layer of tests/test_layers.py: declare it")


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE).with_suffix("").parts
    if parts[-1] == "__init__" and len(parts) > 1:
        parts = parts[:-1]
    return ".".join(parts)


def is_package(module: str) -> bool:
    return (PACKAGE / Path(*module.split(".")) / "__init__.py").exists()


def exists(module: str) -> bool:
    path = PACKAGE / Path(*module.split("."))
    return is_package(module) or path.with_suffix(".py").exists() or path.with_suffix(".pyi").exists()


def imports_of(path: Path) -> set[str]:
    """Every gyrodrift module `path` imports, as dotted names below ``gyrodrift`` (``from pkg import submodule`` counts
    as importing the submodule)."""
    this = module_name(path)
    package = this if path.name == "__init__.py" else this.rpartition(".")[0]
    return imports_in(path.read_text(), this, package)


def imports_in(source: str, this: str, package: str) -> set[str]:
    """The gyrodrift modules the `source` of module `this` (in `package`) imports, anywhere in it."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
            found |= {n.removeprefix("gyrodrift.") for n in names if n.startswith("gyrodrift.")}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".") if package else []
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            elif node.module == "gyrodrift":
                target = ""
            elif node.module and node.module.startswith("gyrodrift."):
                target = node.module.removeprefix("gyrodrift.")
            else:
                continue
            for alias in node.names:
                sub = f"{target}.{alias.name}" if target else alias.name
                if exists(sub):
                    found.add(sub)
                elif target:
                    found.add(target)
                else:
                    found.add("__init__")
    found.discard(this)
    return found


def import_graph() -> dict[str, set[str]]:
    return {module_name(p): imports_of(p) for p in sorted(PACKAGE.rglob("*.py"))}


def test_every_arrow_points_down_the_declared_layers() -> None:
    wrong = []
    for module, targets in import_graph().items():
        if module == "__init__":
            continue
        room = room_of(module)
        for target in sorted(targets):
            other = room_of(target)
            if other == room or (room in FOUNDATION and other in FOUNDATION):
                continue
            if rank_of(other) >= rank_of(room):
                wrong.append(f"{module} -> {target} (layer {rank_of(room)} -> {rank_of(other)})")
    assert not wrong, "imports against the layers of tests/test_layers.py:\n" + "\n".join(wrong)


def test_no_import_cycle() -> None:
    graph = import_graph()
    cycles = _cycles(graph)
    assert not cycles, "import cycles:\n" + "\n".join(" -> ".join(c + [c[0]]) for c in cycles)


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each as a list."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for nxt in graph.get(node, ()):
            if nxt not in graph:
                continue
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = []
            while True:
                top = stack.pop()
                on_stack.discard(top)
                component.append(top)
                if top == node:
                    break
            if len(component) > 1:
                components.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return components


def test_every_room_is_declared_and_says_what_it_is_for() -> None:
    rooms = {p.parent.name for p in PACKAGE.glob("*/__init__.py")}
    modules = {p.stem for p in PACKAGE.glob("*.py") if p.stem != "__init__"}
    for room in sorted(rooms | modules):
        rank_of(room)
    for room in sorted(rooms):
        doc = ast.get_docstring(ast.parse((PACKAGE / room / "__init__.py").read_text()))
        assert doc and doc.strip(), f"gyrodrift/{room}/__init__.py: no docstring saying what the room is for"


@pytest.mark.parametrize(
    ("graph", "expected"),
    [
        ({"a": {"b"}, "b": {"a"}}, [["a", "b"]]),
        ({"a": {"b"}, "b": {"c"}, "c": set()}, []),
        ({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}, [["a", "b", "c"]]),
    ],
)
def test_the_cycle_finder_finds_cycles(graph: dict[str, set[str]], expected: list[list[str]]) -> None:
    assert _cycles(graph) == expected


def test_imports_inside_functions_and_type_checking_blocks_are_arrows_too() -> None:
    source = (
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    from gyrodrift.fleet.spec import Campaign\n"
        "def f():\n    from gyrodrift.procedure import navigate\n    from . import columns\n"
        "    import gyrodrift.ins.simulate\n"
    )
    found = imports_in(source, "logs.log", "logs")
    assert found == {"fleet.spec", "procedure.navigate", "logs.columns", "ins.simulate"}
