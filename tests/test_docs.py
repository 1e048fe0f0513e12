"""The documentation cannot drift from the code: every ```bash and ```python block of README.md and docs/*.md is
collected by the root conftest.py (Sybil) and run by `python -m pytest`; these tests check that none escapes."""

from __future__ import annotations

import importlib.util
import re
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _docs_runner():
    """The root conftest.py (the Sybil runner), loaded by path: here `import conftest` finds tests/conftest.py."""
    spec = importlib.util.spec_from_file_location("docs_runner", ROOT / "conftest.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


conftest = _docs_runner()
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
STUDIES = sorted((ROOT / "docs" / "studies").glob("2*.md"))
"""Dated measurement pages: docs/studies/YYYY-MM-DD-topic.md, indexed by docs/studies/README.md."""
FENCE = re.compile(r"^```(\S*)\s*$")
SKIP = "<!-- skip: next -->"
LANGUAGES = {*conftest.EXECUTED_LANGUAGES, "text", "toml", "json", "c", "rust"}
"""Executed (bash, python) or plainly not code to run: a shell session or synopsis is ```text, not ```sh."""


def _blocks(path: Path):
    """(line of the opening fence, language, body, directive on the line before) of every fenced block."""
    lines = path.read_text(encoding="utf-8").splitlines()
    out, i = [], 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if m:
            j = i + 1
            while not lines[j].startswith("```"):
                j += 1
            before = lines[i - 1].strip() if i else ""
            out.append((i + 1, m.group(1), "\n".join(lines[i + 1 : j]), before))
            i = j
        i += 1
    return out


@pytest.mark.parametrize("path", [*DOCUMENTS, *STUDIES], ids=lambda p: p.name)
def test_every_block_says_its_language(path):
    for line, language, _, _ in _blocks(path):
        assert language in LANGUAGES, f"{path.name}:{line}: block language {language!r}, expected one of {LANGUAGES}"


@pytest.mark.parametrize("path", DOCUMENTS, ids=lambda p: p.name)
def test_every_bash_and_python_block_is_executed(path):
    fenced = [(line, lang, body, before) for line, lang, body, before in _blocks(path) if lang in ("bash", "python")]
    skipped = [line for line, _, body, before in fenced if before == SKIP]
    for line, _, body, before in fenced:
        if before == SKIP:
            assert "pip install" in body, f"{path.name}:{line}: only the block installing the package may be skipped"
    text = path.read_text(encoding="utf-8")
    assert text.count("<!-- skip") == len(skipped), f"{path.name}: a skip directive other than before a pip install"
    document = conftest.markdown_sybil.parse(path)
    directives = {line - 1 for line in skipped}  # a skip directive is a region of its own, on the line before
    executed = sorted(e.line for e in document.examples() if e.line not in directives)
    assert executed == [line for line, *_ in fenced], f"{path.name}: blocks Sybil does not run"


def test_pytest_runs_the_docs_and_the_docstrings():
    testpaths = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]["testpaths"]
    assert {"tests", "README.md", "docs", "python/gyrodrift"} <= set(testpaths)
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]["test"]
    assert any(e.startswith("sybil") for e in extras)


def test_the_readme_opens_with_the_two_setup_commands():
    blocks = _blocks(ROOT / "README.md")
    assert blocks[0][2].splitlines() == [
        "python -m pip install . && gyrodrift reproduce",
        'python -m pip install ".[test]" && python -m pytest -n auto',
    ]


def test_ci_runs_the_readmes_test_command():
    """.ci/run runs the README's test command as written, nothing weaker."""
    readme_test = _blocks(ROOT / "README.md")[0][2].splitlines()[1].split(" && ")[1]
    ci = [line.split("#")[0].strip() for line in (ROOT / ".ci" / "run").read_text().splitlines()]
    assert ci[-1] == readme_test
    assert 'python -m pip install ".[test,docs]"' in ci  # the README's test extras, and the docs site's


LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")


@pytest.mark.parametrize("path", [*DOCUMENTS, *STUDIES, ROOT / "docs" / "studies" / "README.md"], ids=lambda p: p.name)
def test_every_relative_link_names_a_file_of_the_repository(path):
    for target in LINK.findall(path.read_text(encoding="utf-8")):
        if "://" not in target:
            assert (path.parent / target).exists(), f"{path.name}: link to {target}, not in the repository"


STUDY_TITLE = re.compile(r"^# (\d{4}-\d{2}-\d{2}): \S")
COMMIT = re.compile(r"\b[0-9a-f]{7,40}\b")


@pytest.mark.parametrize("path", STUDIES, ids=lambda p: p.name)
def test_a_study_opens_with_its_date_question_commands_and_commit(path):
    """A number keeps the command and the commit that produced it (issue 19): the page's title carries the date of
    its file name, and before its first section it names the question, the command(s) and the commit."""
    text = path.read_text(encoding="utf-8")
    title = STUDY_TITLE.match(text)
    assert title and path.name.startswith(title.group(1) + "-"), f"{path.name}: title '# {path.name[:10]}: ...'"
    opening = text.split("\n## ", 1)[0]
    assert "**Question.**" in opening, f"{path.name}: no **Question.** before the first section"
    assert "**Command" in opening and "```text" in opening, f"{path.name}: no **Commands** block before the numbers"
    assert "**Commit" in opening and COMMIT.search(opening.split("**Commit", 1)[1]), f"{path.name}: no commit named"


@pytest.mark.parametrize("path", STUDIES, ids=lambda p: p.name)
def test_a_study_runs_nothing_in_the_suite(path):
    """conftest.py's Sybil runs the blocks of README.md and docs/*.md only: a bash or python block in a study would
    be silently skipped, so a study's commands are ```text (most take minutes to hours)."""
    for line, language, _, _ in _blocks(path):
        assert language not in conftest.EXECUTED_LANGUAGES, f"{path.name}:{line}: a ```{language} block is never run"


def test_the_studies_index_lists_every_study():
    index = (ROOT / "docs" / "studies" / "README.md").read_text(encoding="utf-8")
    listed = set(re.findall(r"\]\((\d{4}-\d{2}-\d{2}-[a-z0-9-]+\.md)\)", index))
    assert listed == {p.name for p in STUDIES}


def test_the_architecture_names_only_what_the_repository_holds():
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    for absent in ("method.md", "../shared", "issue "):
        assert absent not in text, absent
    modules = {p.stem for p in (ROOT / "python" / "gyrodrift").glob("*.py") if not p.stem.startswith("_")}
    described = set(re.findall(r"\*\*`([a-z_]+)`\*\*", text)) | set(re.findall(r"`([a-z_]+)`", text))
    assert modules <= described, f"modules without a word in docs/architecture.md: {sorted(modules - described)}"
