"""The session's order (root conftest.py): the files of LONGEST_FIRST run first, in its order, each file's items
together and in their own order, every other file after them in its collection order; and pytest-xdist is told to
keep that order (--no-loadscope-reorder beside --dist loadfile in pyproject's addopts)."""

from __future__ import annotations

import importlib.util
import tomllib
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _root_conftest():
    """The root conftest.py, loaded by path (`import conftest` finds tests/conftest.py here)."""
    spec = importlib.util.spec_from_file_location("session_order", ROOT / "conftest.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


conftest = _root_conftest()


@dataclass
class _Item:
    path: Path
    name: str


def test_every_listed_file_exists_and_is_collected():
    listed = conftest.LONGEST_FIRST
    assert len(set(listed)) == len(listed), "a file listed twice"
    testpaths = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]["testpaths"]
    for name in listed:
        assert (ROOT / name).is_file(), f"conftest.py LONGEST_FIRST: {name} is not a file (renamed or removed?)"
        assert any(name == p or name.startswith(p + "/") for p in testpaths), f"{name}: not under {testpaths}"


def test_listed_files_move_to_the_front_in_their_order_and_the_rest_keep_theirs():
    first, second = conftest.LONGEST_FIRST[:2]
    files = ["tests/a_first.py", second, "docs/b.md", first, "python/gyrodrift/c.py", "/elsewhere/d.py"]
    items = [_Item(Path(f) if f.startswith("/") else ROOT / f, f"{f}::{k}") for f in files for k in range(3)]
    conftest.pytest_collection_modifyitems(items)
    order = [str(i.path) for i in items]
    expected_files = [first, second, "tests/a_first.py", "docs/b.md", "python/gyrodrift/c.py", "/elsewhere/d.py"]
    expected = [str(Path(f) if f.startswith("/") else ROOT / f) for f in expected_files for _ in range(3)]
    assert order == expected
    assert [i.name.rsplit("::", 1)[1] for i in items] == ["0", "1", "2"] * len(files)  # each file's items in order


def test_xdist_keeps_the_session_order():
    addopts = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]["addopts"]
    assert "--dist loadfile" in addopts and "--no-loadscope-reorder" in addopts
