"""Curves exported beside the figures: `evaluate`'s position_error.parquet holds exactly the plotted curves."""

from __future__ import annotations

import numpy as np
import pyarrow.parquet as pq

from gyrodrift.procedure.results import Evaluation, NavCurve
from gyrodrift.procedure.writers import EVALUATION_CURVE_COLUMNS, write_evaluation


def _curve(drift, scale):
    t = np.linspace(0.0, 72.0, 73)
    north = scale * 1852.0 * np.sin(t / 12.0)
    east = scale * 1852.0 * (1 - np.cos(t / 24.0))
    return NavCurve(drift, t, north, east, north / 30.9, east / 27.2, np.full(73, 28.2), north[:73] / 30.9)


def test_evaluate_writes_the_plotted_curves_with_the_figure(tmp_path):
    ev = Evaluation(
        run="r07",
        drift_deg_h=0.0012,
        hours=72.0,
        before=_curve(0.0, 2.0),
        after=_curve(0.0012, 0.3),
        source="models/model.json",
    )
    paths = write_evaluation(ev, tmp_path / "out")
    assert sorted(p.name for p in paths.values()) == ["evaluation.json", "position_error.parquet", "position_error.png"]
    t = pq.read_table(paths["curves"])
    assert tuple(t.column_names) == EVALUATION_CURVE_COLUMNS
    assert t.schema.metadata[b"gyrodrift.format"] == b"gyrodrift-evaluation-curves/1"
    passes = t.column("pass").to_pylist()
    assert passes == ["before"] * 73 + ["after"] * 73
    for k, c in ((0, ev.before), (73, ev.after)):
        np.testing.assert_array_equal(t.column("pos_err_nmi").to_numpy()[k : k + 73], c.pos_err_nmi)
        np.testing.assert_array_equal(t.column("lat_err_arcsec").to_numpy()[k : k + 73], c.lat_err_arcsec)
    assert t.column("pos_err_nmi").to_numpy()[:73].max() == ev.before.max_nmi
