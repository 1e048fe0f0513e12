"""The code skeletons (gyrodrift/export/templates/*.in): each export fills every placeholder of the templates it
uses with a value, passes no value a template does not use, and between a drift model, a hybrid on the 12 h
inversion and a fleet-prior hybrid, in C and in Rust, every template file is used."""

from __future__ import annotations

from importlib.resources import files
from string import Template

import numpy as np
import pytest

import gyrodrift
from gyrodrift.export import render
from gyrodrift.export.languages import LANGUAGES, export_model
from gyrodrift.learn.drift_model import fit_drift_model
from gyrodrift.learn.physics_base import FLEET_PHYSICS
from gyrodrift.runs.columns import SMOOTHER_THERMAL_COLUMNS

TEMPLATES = files("gyrodrift.export").joinpath("templates")


def _smoother_runs():
    """The paper's training runs with the smoother's columns (end drift, its 1-sigma, the k_z estimate; NaN k_z on
    three runs: the smoother's constant model) [deg/h, deg/h/degC]."""
    runs = gyrodrift.load_paper().train
    rng = np.random.default_rng(19)
    n = len(runs)
    constant = np.isin(np.arange(n), [2, 9, 15])
    k_std = rng.uniform(5e-5, 3e-4, n)
    d_std = rng.uniform(1e-4, 3e-4, n)
    kz = {
        "smoother_coeff_deg_h_per_c": rng.normal(2e-4, 4e-5, n),
        "smoother_coeff_std_deg_h_per_c": k_std,
        "smoother_end_coeff_cov": rng.uniform(-0.9, 0.9, n) * d_std * k_std,
        "smoother_coeff_prior_std_deg_h_per_c": np.full(n, 1e-2),
    }
    assert tuple(kz) == SMOOTHER_THERMAL_COLUMNS
    extra = {
        "drift_smoother_deg_h": runs.drift_deg_h + rng.normal(0.0, d_std),
        "drift_smoother_std_deg_h": d_std,
        **{name: np.where(constant, np.nan, v) for name, v in kz.items()},
    }
    return runs.replace(extra=extra)


@pytest.fixture(scope="module")
def models():
    """A drift model, a hybrid on the 12 h inversion and a fleet-prior hybrid (gamma and sigma given: no tuning)."""
    paper = gyrodrift.load_paper().train
    hybrid = {"target": "residual", "max_label_std_deg_h": None}
    return {
        "drift": fit_drift_model(paper, gamma=100.0, sigma=0.7),
        "inversion": fit_drift_model(paper, gamma=100.0, sigma=0.7, physics_column="drift_inversion_deg_h", **hybrid),
        "fleet": fit_drift_model(_smoother_runs(), gamma=100.0, sigma=0.7, physics_column=FLEET_PHYSICS, **hybrid),
    }


@pytest.mark.filterwarnings("ignore::gyrodrift.learn.interval.IntervalOutlierWarning")
def test_every_template_is_used_and_filled_exactly(models, monkeypatch):
    filled: list[tuple[str, set[str]]] = []
    fill = render.fill

    def recording_fill(template: str, **values):
        filled.append((template, set(values)))
        return fill(template, **values)

    monkeypatch.setattr(render, "fill", recording_fill)
    for name, model in models.items():
        assert (
            model.physics_column_ == {"drift": None, "inversion": "drift_inversion_deg_h", "fleet": FLEET_PHYSICS}[name]
        )
        for lang in LANGUAGES:
            for text in export_model(model, lang).values():
                assert "$" not in text  # no placeholder left
    for template, values in filled:
        placeholders = set(Template(TEMPLATES.joinpath(template).read_text(encoding="utf-8")).get_identifiers())
        assert values == placeholders, f"{template}: values {sorted(values)} for placeholders {sorted(placeholders)}"
    on_disk = {path.name for path in TEMPLATES.iterdir() if path.name.endswith(".in")}
    assert {template for template, _ in filled} == on_disk
