"""Sphinx configuration of gyrodrift's documentation: the guides of docs/ (Markdown, MyST), the API reference of
every public module (autodoc with numpydoc) and the CLI reference (sphinx-click).

Build it (``pip install ".[docs]"``): ``python -m sphinx -W -n --keep-going -b html docs /tmp/gyrodrift-docs``.
"""

from __future__ import annotations

from gyrodrift import __version__

project = "gyrodrift"
author = "gyrodrift developers"
release = version = __version__
extensions = ["sphinx.ext.autodoc", "numpydoc", "sphinx_click", "myst_parser"]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build"]
myst_heading_anchors = 4  # the guides link to each other's sections by their GitHub anchors
autodoc_default_options = {
    "members": True,
    "show-inheritance": True,
    # scikit-learn's metadata-routing setters, generated on every estimator: their docstrings are sklearn's
    "exclude-members": "set_fit_request, set_predict_request, set_score_request, set_transform_request",
}
autodoc_member_order = "bysource"
numpydoc_show_class_members = False  # autodoc lists them
numpydoc_validation_checks: set[str] = set()
html_theme = "alabaster"


def _plain_epilog(app, ctx, lines: list[str]) -> None:
    """A command's epilog is plain text (``Example: gyrodrift features fleet/*/imu.parquet ...``), not reST: its
    stars and backslashes are escaped so that they print as the terminal shows them."""
    lines[:] = [line.replace("\\", "\\\\").replace("*", "\\*").replace("`", "\\`") for line in lines]


def setup(app):
    app.connect("sphinx-click-process-epilog", _plain_epilog)
