"""Issue 22: the API reference (docs/api.rst, built by Sphinx in .ci/run) names every public module of the package,
each once; the CLI reference renders the one click group."""

import pkgutil
import re
from pathlib import Path

import gyrodrift

ROOT = Path(__file__).resolve().parents[1]


def test_the_api_page_lists_every_public_module_once():
    public = {
        m.name
        for m in pkgutil.walk_packages(gyrodrift.__path__, "gyrodrift.")
        if not m.name.rpartition(".")[2][0] == "_"
    }
    listed = re.findall(r"^\.\. automodule:: (\S+)$", (ROOT / "docs" / "api.rst").read_text(), flags=re.M)
    assert len(listed) == len(set(listed))
    assert set(listed) == public | {"gyrodrift"}


def test_the_cli_reference_renders_the_main_group_and_the_index_links_every_guide():
    text = (ROOT / "docs" / "cli-reference.rst").read_text()
    assert ".. click:: gyrodrift.cli:main" in text and ":nested: full" in text
    index = (ROOT / "docs" / "index.rst").read_text()
    for guide in (ROOT / "docs").glob("*.md"):
        assert f"\n   {guide.stem}\n" in index, guide.name
