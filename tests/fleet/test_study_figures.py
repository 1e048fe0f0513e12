"""Issue 22: one colour per method across every figure of the study's report, readable log ticks, legends that
cover no curve (drawn on a study document whose numbers are made up: only the drawing is under test)."""

import numpy as np
import pytest

from gyrodrift.fleet.study import FLEET_ROW
from gyrodrift.fleet.study_report import FIGURES, make_figures, method_colours, study_figures

METHODS = ["CPSO-LSSVM (LOO)", "GP regression", "hybrid default", "12 h physics inversion", "16 h smoother", FLEET_ROW]


@pytest.fixture(scope="module")
def doc():
    rms = {n: 1e-4 * (k + 1) for k, n in enumerate(METHODS)}
    curve = {n: [rms[n], 1.5 * rms[n]] for n in METHODS}
    return {
        "methods": {n: {"metrics": {"rms_eff": rms[n], "max_eff": 2 * rms[n]}} for n in METHODS},
        "physical_limit_deg_h": 1.5e-4,
        "train_size": {"sizes": [10, 20], "rms_eff": {n: curve[n] for n in METHODS[:3]}},
        "by_grade": {"arw_deg_rth": [1e-4, 5e-4], "rms_eff": curve, "limit_deg_h": [1e-4, 2e-4]},
        "by_latitude": {"center_deg": [10.0, 40.0], "rms_eff": curve, "limit_deg_h": [1e-4, None]},
    }


@pytest.fixture(scope="module")
def figures(doc):
    """The study's figures of `doc`, drawn once for the module (the tests only read and render them)."""
    return study_figures(doc)


def test_each_method_has_one_colour_in_every_figure(doc, figures):
    from matplotlib.colors import to_hex

    colour = method_colours(doc)
    assert len(set(colour.values())) == len(METHODS)
    assert set(figures) == set(FIGURES)
    seen = 0
    for name, fig in figures.items():
        (ax,) = fig.axes
        for line in ax.get_lines():
            if line.get_label() in colour:
                assert to_hex(line.get_color()) == colour[line.get_label()], (name, line.get_label())
                seen += 1
        if name == "methods.png":
            labels = [t.get_text() for t in ax.get_yticklabels()]
            bars = [p for p in ax.patches if p.get_width() > 0]
            assert len(bars) == 2 * len(labels)
            for k, label in enumerate(labels):  # RMS bars first, then max bars, in the label order
                assert to_hex(bars[k].get_facecolor()) == colour[label]
                assert to_hex(bars[len(labels) + k].get_facecolor()) == colour[label]
    assert seen == 3 + 2 * len(METHODS)


def test_log_axes_label_more_than_one_tick_and_legends_sit_outside_the_axes(doc, figures):
    fig = figures["methods.png"]
    fig.canvas.draw()
    (ax,) = fig.axes
    lo, hi = ax.get_xlim()
    shown = [t.get_text() for t in ax.get_xticklabels() if t.get_text() and lo <= t.get_position()[0] <= hi]
    assert len(shown) >= 3, shown
    for name in ("noise_grade.png", "latitude.png", "train_size.png"):
        fig = figures[name]
        fig.canvas.draw()
        (ax,) = fig.axes
        box, legend = ax.get_window_extent(), ax.get_legend().get_window_extent()
        assert legend.x0 >= box.x1, name  # beside the axes: no curve under it
    png = make_figures(doc)["methods.png"]
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and np.frombuffer(png, np.uint8).size > 1000
