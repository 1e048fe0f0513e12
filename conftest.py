"""The documentation runs as written: every ```python and ```bash block of README.md and docs/*.md, and every
docstring example (``>>>``) of the package, is a test (Sybil, collected through pyproject's testpaths).

Each document runs in its own temporary folder (its blocks in order, sharing the folder and, for Python, one
namespace), with ``examples/`` reachable there as a symbolic link to the repository's, so that the documented
commands (``gyrodrift simulate examples/scenarios/tour.toml ...``) run unchanged and nothing is written into the
repository. A bash block runs with ``bash -euo pipefail``: any failing command fails the test. The only block not
run is one that installs the package (``pip install``), behind a ``<!-- skip: next -->`` directive: the tests run
inside that installation; tests/test_docs.py checks that no other block is skipped or left unlabelled.

It also orders the session: the files of `LONGEST_FIRST` run first (pytest_collection_modifyitems), so that
``python -m pytest -n auto`` (each file whole on one worker) does not end with one long file running alone, and gives
the test processes and those they start one OpenBLAS thread (``OPENBLAS_NUM_THREADS``, unless set).
"""

from __future__ import annotations

import gc
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest
from sybil import Sybil
from sybil.parsers.markdown import CodeBlockParser, PythonCodeBlockParser, SkipParser
from sybil.parsers.rest import DocTestParser

# One OpenBLAS thread in the test processes and every process they start (CLI subprocesses, campaign and dask
# workers, the documents' bash blocks), set before anything here imports numpy: the suite's matrices are small, where
# a second BLAS thread gives no time and burns CPU waiting, and under `pytest -n auto` each worker's threads compete
# with the other worker (as `gyrodrift.learn.tuning` explains for its own factorisations). The tests compare values
# computed under this same setting. Measured one process at a time (user + sys of the tests, loaded 2-core machine,
# at a369db7): tests/learn 47 -> 32 s, tests/fleet/test_campaign.py 52 -> 43 s. An explicit setting is kept.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

ROOT = Path(__file__).resolve().parent
EXECUTED_LANGUAGES = ("bash", "python")
"""The fenced-block languages that are executed; every other block must say what it is (text, toml, c, ...)."""
BASH_TIMEOUT_S = 600


def _enter_folder(namespace: dict) -> None:
    folder = Path(tempfile.mkdtemp(prefix="gyrodrift-docs-"))
    (folder / "examples").symlink_to(ROOT / "examples", target_is_directory=True)
    namespace["_docs_previous_cwd"] = os.getcwd()
    namespace["_docs_folder"] = folder
    os.chdir(folder)


def _leave_folder(namespace: dict) -> None:
    os.chdir(namespace.pop("_docs_previous_cwd"))
    shutil.rmtree(namespace.pop("_docs_folder"), ignore_errors=True)


class BashBlockParser(CodeBlockParser):
    """Runs a ```bash block with ``bash -euo pipefail`` in the document's folder; fails with its output."""

    language = "bash"

    def evaluate(self, example) -> str | None:
        env = {**os.environ, "MPLBACKEND": "Agg"}
        proc = subprocess.run(
            ["bash", "-euo", "pipefail", "-c", example.parsed],
            cwd=os.getcwd(),
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            timeout=BASH_TIMEOUT_S,
        )
        if proc.returncode != 0:
            return f"bash block exited with status {proc.returncode}:\n{example.parsed}\n--- output ---\n{proc.stdout}"
        return None


markdown_sybil = Sybil(
    parsers=[PythonCodeBlockParser(), BashBlockParser(), SkipParser()],
    patterns=["README.md", "docs/*.md"],
    setup=_enter_folder,
    teardown=_leave_folder,
    name="docs",
)

docstring_sybil = Sybil(
    parsers=[DocTestParser()],
    patterns=["python/gyrodrift/*.py", "python/gyrodrift/*/*.py"],
    setup=_enter_folder,
    teardown=_leave_folder,
    name="docstrings",
)

pytest_collect_file = (markdown_sybil + docstring_sybil).pytest()

LONGEST_FIRST = (
    "README.md",
    "tests/procedure/test_smoother.py",
    "tests/fleet/test_campaign.py",
    "tests/fleet/test_identification_study.py",
    "tests/procedure/test_procedure.py",
    "docs/campaigns.md",
    "tests/sensors/test_allan.py",
    "tests/cli/test_cli_errors.py",
    "tests/export/test_export_compiled.py",
    "tests/fleet/test_campaign_interrupt.py",
    "tests/procedure/test_plan.py",
    "docs/procedure.md",
    "tests/fleet/test_campaign_dask_cluster.py",
    "tests/fleet/test_dask_shutdown.py",
    "tests/ins/test_ins_navigation.py",
    "tests/ins/test_ins_reference.py",
    "docs/export.md",
    "tests/paper/test_reproduce.py",
    "tests/procedure/test_truth_law.py",
    "tests/fleet/test_campaign_store_checks.py",
    "tests/ins/test_ins_vehicle.py",
)
"""The files with the most test time, the longest first (58 down to 6 s each: setup + call + teardown of each test
summed per file, from `python -m pytest -n auto --durations=0` at 9ae8057, 2026-11-28, quiet 2-core machine; the
sum over all files was 546 s); the rest follow in their collection order. pytest-xdist's --dist loadfile hands
whole files to the workers in the session's order (--no-loadscope-reorder in pyproject's addopts; its default
orders files by their number of tests, which sent the long few-test files last). A file missing from the tree fails
tests/test_suite_order.py."""


def longest_first_key(item: pytest.Item) -> int:
    """The item's file's place in `LONGEST_FIRST`, or len(LONGEST_FIRST) for every other file."""
    try:
        name = Path(item.path).resolve().relative_to(ROOT).as_posix()
    except ValueError:  # a file outside the repository (a test's own scratch suite)
        return len(LONGEST_FIRST)
    return LONGEST_FIRST.index(name) if name in LONGEST_FIRST else len(LONGEST_FIRST)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Moves the files of `LONGEST_FIRST` to the front, in its order; a stable sort, so each file's items stay
    together and in order (a document's blocks, a module's fixtures) and the other files keep their order."""
    items.sort(key=longest_first_key)


def pytest_collection_finish(session: pytest.Session) -> None:
    """Moves every object alive after the collection (the imported modules of numpy, scipy, scikit-learn,
    matplotlib, the tests' own) out of reach of Python's cyclic garbage collector (`gc.freeze`): they live as long
    as the process, and each full collection walked them all again."""
    gc.freeze()
