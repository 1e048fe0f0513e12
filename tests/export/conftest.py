"""The fitted export cases (`fitted`, all of them, for test_export_compiled.py) and the two models test_export.py
needs (`default_model`, `first_model`), each built once per session."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner
from export_cases import (
    CASE_IDS,
    CASES,
    CLI_EXPORTS,
    COS_CASE,
    DEFAULT_CASE,
    FLEET,
    fit_case,
    hybrid_runs,
    probe_rows,
    python_reference,
)

from gyrodrift.choices import default_encoding
from gyrodrift.cli import main
from gyrodrift.export.languages import LANGUAGES
from gyrodrift.learn.model_io import load_model


@pytest.fixture(scope="session")
def default_fit_file(tmp_path_factory):
    """A model file of `gyrodrift fit` with every default, on the hybrid synthetic table (CSV)."""
    folder = tmp_path_factory.mktemp("default_fit")
    table = folder / "runs.csv"
    hybrid_runs(np.random.default_rng(20130613)).to_csv(table)
    r = CliRunner().invoke(main, ["fit", str(table), "--out", str(folder / "model.json"), "--quiet"])
    assert r.exit_code == 0, r.output
    return folder / "model.json"


@pytest.fixture(scope="session")
def default_model(default_fit_file, tmp_path_factory):
    """The model of `default_fit_file`, its files of `gyrodrift export` put in CLI_EXPORTS (DEFAULT_CASE)."""
    model = load_model(default_fit_file)
    assert (model.encoding, model.target, model.physics_column) == (default_encoding("residual"), "residual", "auto")
    assert model.physics_column_ == FLEET and model.coefficient_prior_ is not None  # resolved on the smoother's k_z
    assert model.training["weighted"] and model.training_["left_out"]
    for lang in LANGUAGES:
        folder = tmp_path_factory.mktemp(f"default_export_{lang}")
        args = ["export", "--model", str(default_fit_file), "--lang", lang, "--out", str(folder), "--quiet"]
        r = CliRunner().invoke(main, args)
        assert r.exit_code == 0, r.output
        CLI_EXPORTS[lang] = {name: (folder / name).read_text() for name in LANGUAGES[lang]}
    return model


@pytest.fixture(scope="session")
def first_model():
    """The model of the first case (CASE_IDS[0]), for the tests that need one model and not all of `fitted`."""
    _, train, encoding, scaling, kernel, physics = CASES[0]
    return fit_case(train, encoding, scaling, kernel, physics)


@pytest.fixture(scope="session")
def fitted(default_model):
    """Case id -> (model, rows, expected), built once for the C and the Rust tests."""
    rng = np.random.default_rng(7)
    out = {}
    for case_id, (_, train, encoding, scaling, kernel, physics) in zip(CASE_IDS, CASES, strict=True):
        model = fit_case(train, encoding, scaling, kernel, physics)
        rows = probe_rows(model.training_["runs"], rng)
        out[case_id] = (model, rows, python_reference(model, rows))
    out[COS_CASE] = out[CASE_IDS[0]]
    rows = probe_rows(default_model.training_["runs"], rng)
    out[DEFAULT_CASE] = (default_model, rows, python_reference(default_model, rows))
    return out
