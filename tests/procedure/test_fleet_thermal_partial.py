"""A fleet-base model refuses a run with some but not all of the smoother's thermal columns (issue 18, item 4):
such a run used to be taken silently as under the smoother's constant model."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner
from test_fleet_base import synthetic_fleet

from gyrodrift.cli import main
from gyrodrift.errors import InputError
from gyrodrift.learn.drift_model import fit_drift_model
from gyrodrift.learn.physics_base import FLEET_PHYSICS
from gyrodrift.runs.columns import SMOOTHER_THERMAL_COLUMNS
from gyrodrift.runs.table import check_smoother_thermal


def _drop(runs, run_index: int, column: str):
    """`runs` with `column` emptied for run `run_index` only."""
    values = np.where(np.arange(len(runs)) == run_index, np.nan, runs.column(column))
    return runs.replace(extra={**runs.extra, column: values})


def test_partial_thermal_runs_are_refused_by_fit_and_predict(tmp_path):
    train, _ = synthetic_fleet(14, np.random.default_rng(3), constant=(2, 9))
    model = fit_drift_model(train, encoding="physics", target="residual", gamma=20.0, sigma=1.5)
    assert model.physics_column_ == FLEET_PHYSICS
    new, _ = synthetic_fleet(5, np.random.default_rng(8), constant=(0,))
    check_smoother_thermal(new, "test")  # run r0 has none of them (constant model), the others all: accepted
    partial = _drop(_drop(new, 3, SMOOTHER_THERMAL_COLUMNS[2]), 3, SMOOTHER_THERMAL_COLUMNS[3])
    expected = (
        f"run.s. r3 .missing {SMOOTHER_THERMAL_COLUMNS[2]}, {SMOOTHER_THERMAL_COLUMNS[3]}. have some but not all "
        "of the smoother's thermal columns"
    )
    with pytest.raises(InputError, match=expected):
        model.predict(partial)
    with pytest.raises(InputError, match=expected.replace("r3", "r4")):  # training on such a run too
        fit_drift_model(
            _drop(_drop(train, 4, SMOOTHER_THERMAL_COLUMNS[2]), 4, SMOOTHER_THERMAL_COLUMNS[3]),
            target="residual",
            physics_column=FLEET_PHYSICS,
            gamma=20.0,
            sigma=1.5,
        )
    # the CLI: one line naming the file, the run and the missing columns; exit 1
    model_file, table = tmp_path / "m.json", tmp_path / "partial.csv"
    train.to_csv(tmp_path / "fleet.csv")
    r = CliRunner().invoke(
        main,
        ["fit", str(tmp_path / "fleet.csv"), "--out", str(model_file), "--gamma", "20", "--sigma", "1.5", "--quiet"],
    )
    assert r.exit_code == 0, r.output
    _drop(new, 1, SMOOTHER_THERMAL_COLUMNS[1]).to_csv(table)
    r = CliRunner().invoke(main, ["predict", str(table), "--model", str(model_file)])
    assert r.exit_code == 1 and "Traceback" not in r.output, r.output
    assert len(r.output.strip().splitlines()) == 1
    assert f"{table}: run(s) r1 (missing {SMOOTHER_THERMAL_COLUMNS[1]}) have some but not all" in r.output
