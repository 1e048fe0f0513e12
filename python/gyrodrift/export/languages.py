"""The target languages of `gyrodrift export`: the files each writes, and a fitted model exported to one."""

from __future__ import annotations

from collections.abc import Callable

from gyrodrift.errors import OptionError
from gyrodrift.export import c, rust
from gyrodrift.export.spec import ExportSpec, export_spec

__all__ = ["LANGUAGES", "export_model", "output_names"]

_WRITERS: dict[str, tuple[tuple[str, ...], Callable[[ExportSpec], dict[str, str]]]] = {
    "c": (c.FILES, c.c_files),
    "rust": (rust.FILES, rust.rust_files),
}
"""Each language's files and the function writing them from an `ExportSpec` (a new language is a row here)."""

LANGUAGES: dict[str, tuple[str, ...]] = {lang: files for lang, (files, _) in _WRITERS.items()}
"""Target languages and the files each export writes."""


def output_names(lang: str) -> tuple[str, ...]:
    """The files an export to ``lang`` writes; `OptionError` (naming ``--lang``) for an unknown language."""
    try:
        return LANGUAGES[lang]
    except (KeyError, TypeError):
        raise OptionError(f"--lang: unknown language {lang!r}; expected one of {', '.join(LANGUAGES)}") from None


def export_model(model, lang: str, *, model_sha256: str | None = None) -> dict[str, str]:
    """The generated files of ``model`` for ``lang`` (``"c"`` or ``"rust"``): ``{file name: text}``.

    The texts depend only on the model, ``model_sha256`` and the package version (no time stamp), so exporting
    the same model twice gives the same bytes.
    """
    output_names(lang)
    _, write = _WRITERS[lang]
    return write(export_spec(model, model_sha256=model_sha256))
