"""The reproduction report: figures (matplotlib PNG), ``report.md`` and a self-contained ``report.html``.

The report is built once as a list of blocks (heading, paragraph, table, figure) and rendered to both
formats, so the two always say the same thing. Every number in it comes from ``results.json``.
"""

from __future__ import annotations

import base64
import html
import io
from concurrent.futures import Executor
from pathlib import Path
from typing import Any

import numpy as np

from gyrodrift.files.atomic import Stage


def _fmt(x, digits: int = 5) -> str:
    if x is None:
        return "-"
    if isinstance(x, str):
        return x
    if x == 0:
        return "0"
    if abs(x) < 1e-3 or abs(x) >= 1e4:
        return f"{x:.3e}"
    return f"{x:.{digits}f}".rstrip("0").rstrip(".") if abs(x) < 1 else f"{x:.4g}"


def _method(results: dict, family: str, encoding: str | None = None) -> dict | None:
    for m in results["methods"]:
        if m["family"] == family and (encoding is None or m.get("encoding") == encoding):
            return m
    return None


def key_methods(results: dict) -> list[dict]:
    """The methods shown in the identification table and the per-run figures."""
    chosen_name = results["selected_by_loo"]["name"]
    chosen = next(m for m in results["methods"] if m["name"] == chosen_name)
    enc = chosen["encoding"]
    picks = [
        _method(results, "physics_inversion"),
        _method(results, "latitude_line"),
        chosen,
        _method(results, "cpso_paper", enc),
        _method(results, "grid_loo", enc),
    ]
    return [p for p in picks if p is not None]


def short_name(m: dict) -> str:
    """A column label for a method."""
    labels = {
        "physics_inversion": "physics",
        "latitude_line": "lat. line",
        "cpso_loo": "CPSO-LOO",
        "cpso_paper": "CPSO-paper",
        "pso_loo": "PSO-LOO",
        "grid_loo": "grid-LOO",
        "paper_params": "paper params",
        "physics_encoding": "CPSO-LOO",
    }
    label = labels.get(m["family"], m["family"])
    return f"{label} ({m['encoding']})" if m.get("encoding") else label


REPORT_FIGURES = ("fitness_curve", "pred_vs_true", "error_per_run", "position_error_72h")
"""The report's figures, written as ``<name>.png``."""
REPORT_FILES = ("results.json", "report.md", "report.html") + tuple(f"{name}.png" for name in REPORT_FIGURES)
"""The files of a reproduction output, published together (`gyrodrift.paper.reproduce.reproduce`)."""


def _png(fig) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    return buffer.getvalue()


METHOD_COLOURS = {
    "cpso_loo": "C0",
    "cpso_paper": "C1",
    "physics_inversion": "C2",
    "latitude_line": "C4",
    "grid_loo": "C5",
    "paper_params": "C7",
    "physics_encoding": "C8",
    "pso_loo": "C6",
}
"""One colour per method family in every figure; the paper's claims are black, an uncompensated navigation red
(`gyrodrift.procedure.figures.BEFORE_COLOUR`, never a method's colour)."""
PAPER_COLOUR = "k"
ENCODING_STYLES = {"temp_range": "-", "temp_mean": "--", "temp_span": ":"}
"""Line style per encoding where one family is drawn for several encodings."""
BUDGET_DEG_H = 0.0005
"""The identification error that leaves about 1 nmi after 72 h (0.9 nmi at 28.222 deg)."""


def method_colour(m: dict) -> str:
    """The colour of a method in every figure (by family)."""
    return METHOD_COLOURS.get(m["family"], "C9")


def selected_method(results: dict) -> dict:
    """The model selected by leave-one-out error (``selected_by_loo``)."""
    name = results["selected_by_loo"]["name"]
    return next(m for m in results["methods"] if m["name"] == name)


def _label(m: dict, chosen: dict) -> str:
    return short_name(m) + (" (selected)" if m is chosen else "")


def make_figures(results: dict, pool: Executor | None = None) -> dict[str, bytes]:
    """The report's PNG figures, {name: PNG bytes} for the names in `REPORT_FIGURES`, drawn in this process or by
    ``pool`` (an executor: `gyrodrift.paper.reproduce.worker_pool`'s worker, which `load_plotting` prepared while this
    process was busy; the same bytes)."""
    if pool is None:
        return {name: figure_png(name, results) for name in REPORT_FIGURES}
    drawn = {name: pool.submit(figure_png, name, results) for name in REPORT_FIGURES}
    return {name: future.result() for name, future in drawn.items()}


def load_plotting() -> None:
    """Import matplotlib's figure and Agg canvas and load its default font: what the first figure of a process pays
    besides its drawing (about 1 s of CPU, as much as the four figures), done ahead by a worker that will draw."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(1, 1))
    fig.text(0.5, 0.5, "0")
    _png(fig)


def figure_png(name: str, results: dict) -> bytes:
    """The PNG bytes of the report's figure ``name`` (one of `REPORT_FIGURES`)."""
    return _png(_FIGURE_MAKERS[name](results))


def _fitness_curve(results: dict):
    """The CPSO fitness histories (cf. the paper's Fig. 3) and chaos against plain PSO at an equal budget."""
    from matplotlib.figure import Figure  # object API: no pyplot state, the caller's backend untouched

    claims = results["paper_claims"]
    chosen = selected_method(results)
    fig = Figure(figsize=(11, 5.6))
    axes = fig.subplots(1, 2)
    paper_iter = claims["fitness_converged_after_iterations"]
    for m in results["methods"]:
        if m["family"] == "cpso_paper":
            h = m["fitness_history"]
            mine = m["encoding"] == chosen["encoding"]
            conv = m.get("converged_iteration")
            axes[0].semilogy(
                np.arange(1, len(h) + 1),
                h,
                color=method_colour(m),
                ls=ENCODING_STYLES.get(m["encoding"], "-"),
                lw=2.2 if mine else 1.2,
                label=f"{m['encoding']}{' (selected)' if mine else ''}: within 1 % of final at it. {conv}",
            )
            if conv:
                axes[0].plot([conv], [h[conv - 1]], "o", color=method_colour(m), ms=5)
    axes[0].axhline(
        claims["fitness"], color=PAPER_COLOUR, ls="--", lw=1, label=f"paper's fitness {claims['fitness']:.3e}"
    )
    axes[0].axvline(paper_iter, color=PAPER_COLOUR, ls=":", lw=1)
    axes[0].annotate(
        f"paper: converged after ~{paper_iter} iterations",
        xy=(paper_iter, 0.8),
        xycoords=("data", "axes fraction"),
        xytext=(4, 0),
        textcoords="offset points",
        va="center",
        fontsize=8,
    )
    axes[0].set(
        xlabel="iteration", ylabel="fitness: train MAE [deg/h]", title="CPSO, paper settings (cf. paper Fig. 3)"
    )
    below = {"fontsize": 7, "loc": "upper center", "bbox_to_anchor": (0.5, -0.16)}  # under the axes: hides no curve
    axes[0].legend(title="CPSO-paper", title_fontsize=7, **below)
    for m in results["methods"]:
        if m["family"] in ("cpso_loo", "pso_loo") and m["fitness_history"]:
            h = np.asarray(m["fitness_history"])
            evals = np.linspace(m["nfev"] / len(h), m["nfev"], len(h))
            axes[1].plot(
                evals,
                h,
                color=method_colour(m),
                ls=ENCODING_STYLES.get(m["encoding"], "-"),
                lw=2.2 if m is chosen else 1.2,
                label=_label(m, chosen),
            )
    axes[1].set(xlabel="objective evaluations", ylabel="LOO MAE [deg/h]", title="chaos vs plain PSO, equal budget")
    axes[1].legend(ncol=2, **below)
    fig.subplots_adjust(**FIGURE_MARGINS["fitness_curve"])
    return fig


def _pred_vs_true(results: dict):
    """The key methods' identified drifts of the test runs against the true ones, with the paper's Table 3."""
    from matplotlib.figure import Figure

    claims = results["paper_claims"]
    true = np.array(results["data"]["test_true_deg_h"])
    chosen = selected_method(results)
    shown = key_methods(results)
    fig = Figure(figsize=(6, 5.5))
    ax = fig.subplots()
    lim = 1.15 * max(np.abs(true).max(), max(np.abs(m["test_pred_deg_h"]).max() for m in shown))
    diag = np.array([-lim, lim])
    ax.fill_between(
        diag, diag - BUDGET_DEG_H, diag + BUDGET_DEG_H, color="0.85", label=f"+-{BUDGET_DEG_H} deg/h (~1 nmi / 72 h)"
    )
    ax.plot(diag, diag, color="0.5", lw=1)
    ax.scatter(true, claims["test_pred_deg_h"], marker="x", color=PAPER_COLOUR, label="paper's Table 3 (claimed)")
    for m in shown:
        sel = m is chosen
        ax.scatter(
            true,
            m["test_pred_deg_h"],
            s=60 if sel else 18,
            color=method_colour(m),
            edgecolors="k" if sel else "none",
            zorder=3 if sel else 2,
            label=_label(m, chosen),
        )
    ax.set(
        xlabel="true drift [deg/h]",
        ylabel="identified drift [deg/h]",
        title="test runs: identified vs true",
        xlim=(-lim, lim),
        ylim=(-lim, lim),
    )
    ax.legend(fontsize=7, loc="upper left")
    fig.subplots_adjust(**FIGURE_MARGINS["pred_vs_true"])
    return fig


def _error_per_run(results: dict):
    """The key methods' identification error per test run, with the paper's."""
    from matplotlib.figure import Figure

    claims = results["paper_claims"]
    true = np.array(results["data"]["test_true_deg_h"])
    runs = results["data"]["test_runs"]
    chosen = selected_method(results)
    shown = key_methods(results)
    fig = Figure(figsize=(10, 4.2))
    ax = fig.subplots()
    width = 0.8 / (len(shown) + 1)
    x = np.arange(len(runs))
    ax.axhspan(-BUDGET_DEG_H, BUDGET_DEG_H, color="0.9", zorder=0, label=f"+-{BUDGET_DEG_H} deg/h (~1 nmi / 72 h)")
    ax.bar(x, true - np.array(claims["test_pred_deg_h"]), width, color=PAPER_COLOUR, label="paper (true - Table 3)")
    for i, m in enumerate(shown, start=1):
        sel = m is chosen
        ax.bar(
            x + i * width,
            m["test_err_deg_h"],
            width,
            color=method_colour(m),
            edgecolor="k" if sel else "none",
            linewidth=1.2 if sel else 0,
            label=_label(m, chosen),
        )
    ax.axhline(0.0, color="0.4", lw=0.8)
    ax.set_xticks(x + 0.4 - width / 2, runs)
    ax.set(xlabel="test run", ylabel="error, true - identified [deg/h]", title="identification error per test run")
    ax.legend(fontsize=7, ncol=2)
    fig.subplots_adjust(**FIGURE_MARGINS["error_per_run"])
    return fig


def _position_error(results: dict):
    """The Fig. 4/5 counterpart: the three 72 h navigations of the representative test run."""
    from matplotlib.figure import Figure

    from gyrodrift.procedure.figures import BEFORE_COLOUR, one_nmi_line

    chosen = selected_method(results)
    f45 = results["position_error_72h"]
    c = f45["curves"]
    t_h = np.asarray(c["t_h"])
    fig = Figure(figsize=(8, 4.5))
    ax = fig.subplots()
    d = f45["compensated_drift_deg_h"]
    rows = (
        ("uncompensated", BEFORE_COLOUR, "-", "no axial drift compensated"),
        ("selected", method_colour(chosen), "-", f"{d['selected']:.6f} deg/h from {short_name(chosen)} (selected)"),
        ("paper", PAPER_COLOUR, "--", f"{d['paper']:.6f} deg/h from the paper's Table 3"),
    )
    for key, colour, ls, what in rows:
        ax.plot(
            t_h,
            c[f"{key}_pos_err_nmi"],
            color=colour,
            ls=ls,
            lw=2.0 if key == "selected" else 1.3,
            label=f"{what} (final {f45[f'{key}_final_pos_err_nmi']:.2f} nmi, "
            f"max {f45[f'{key}_max_pos_err_nmi']:.2f} nmi)",
        )
    one_nmi_line(ax)
    ax.set(
        xlabel="time since start of navigation [h]",
        ylabel="position error [nmi]",
        title=f"test run {f45['run']} (true drift {f45['true_drift_deg_h']:.6f} deg/h), simulated at "
        f"{f45['lat_deg']} deg, {f45['rate_hz']:g} Hz (cf. paper Fig. 4/5)",
    )
    ax.title.set_fontsize(9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    fig.subplots_adjust(**FIGURE_MARGINS["position_error_72h"])
    return fig


FIGURE_MARGINS = {
    "fitness_curve": {"left": 0.07, "right": 0.985, "bottom": 0.3, "top": 0.935, "wspace": 0.34},
    "pred_vs_true": {"left": 0.16, "right": 0.975, "bottom": 0.105, "top": 0.935},
    "error_per_run": {"left": 0.095, "right": 0.985, "bottom": 0.14, "top": 0.915},
    "position_error_72h": {"left": 0.085, "right": 0.98, "bottom": 0.13, "top": 0.925},
}
"""Each figure's fixed layout (fractions of the figure): at least the room ``tight_layout`` gave on the paper's data
(seeds 0 and 3); computing that layout per figure was a fifth of the drawing's time."""
_FIGURE_MAKERS = {
    "fitness_curve": _fitness_curve,
    "pred_vs_true": _pred_vs_true,
    "error_per_run": _error_per_run,
    "position_error_72h": _position_error,
}


def _headline(results: dict) -> dict[str, Any]:
    """The numbers of the verdict: the paper's Table 3 test MAE, the selected model and its test errors, the
    physics inversion, and how many trained models beat it on the test runs."""
    true = np.array(results["data"]["test_true_deg_h"])
    chosen = next(m for m in results["methods"] if m["name"] == results["selected_by_loo"]["name"])
    physics = _method(results, "physics_inversion")
    assert physics is not None, "results without the physics inversion"
    trained = [m for m in results["methods"] if m["family"] not in ("physics_inversion", "paper_params")]
    return {
        "paper_mae": float(np.mean(np.abs(true - np.array(results["paper_claims"]["test_pred_deg_h"])))),
        "chosen": chosen,
        "within": int(np.sum(np.abs(np.array(chosen["test_err_deg_h"])) <= 0.0005)),
        "physics": physics,
        "trained": trained,
        "n_beating_physics": sum(m["test_mae_deg_h"] < physics["test_mae_deg_h"] for m in trained),
    }


def verdict(results: dict) -> str:
    """The one-sentence verdict (the terminal's first line, the report's first paragraph), from the results."""
    h = _headline(results)
    chosen, paper_mae = h["chosen"], h["paper_mae"]
    ratio = chosen["test_mae_deg_h"] / paper_mae
    reproduced = "is reproduced" if ratio <= 1.0 else "is not reproduced"
    return (
        f"Verdict: the paper's test MAE of {paper_mae:.2g} deg/h (its Table 3) {reproduced}: the model gyrodrift "
        f"selects without test data ({chosen['name']}) reaches {chosen['test_mae_deg_h']:.2g} deg/h on the same 10 "
        f"test runs ({ratio:.1f} times the paper's), {h['within']} of 10 within the 0.0005 deg/h that 1 nmi in 72 h "
        f"needs; {h['n_beating_physics']} of the {len(h['trained'])} trained models beat the untrained 12 h physics "
        f"inversion ({h['physics']['test_mae_deg_h']:.2g} deg/h)."
    )


def conclusion(results: dict) -> list[str]:
    """Paragraphs of the report's conclusion, computed from the results."""
    claims = results["paper_claims"]
    true = np.array(results["data"]["test_true_deg_h"])
    claim_pred = np.array(claims["test_pred_deg_h"])
    claim_err = np.array(claims["test_err_deg_h"])
    h = _headline(results)
    paper_mae, chosen, physics, trained = h["paper_mae"], h["chosen"], h["physics"], h["trained"]
    best_learned = min(
        (m for m in results["methods"] if m["family"] not in ("physics_inversion", "paper_params")),
        key=lambda m: m["test_mae_deg_h"],
    )
    paper_param_best = min(
        (m for m in results["methods"] if m["family"] == "paper_params"), key=lambda m: m["test_mae_deg_h"]
    )
    cpso_paper = [m for m in results["methods"] if m["family"] == "cpso_paper"]
    within, n_beating_physics = h["within"], h["n_beating_physics"]
    tuned = [m for m in results["methods"] if "on_search_bound" in m]
    on_bound = [m for m in tuned if m["on_search_bound"]]
    nonzero = claim_err != 0
    mags_agree = bool(np.allclose(np.abs(claim_err), np.abs(true - claim_pred), rtol=0, atol=5e-7))
    agree_true_minus = int(np.sum(np.isclose(claim_err, true - claim_pred, atol=5e-7) & nonzero))
    agree_minus_true = int(np.sum(np.isclose(claim_err, claim_pred - true, atol=5e-7) & nonzero))
    collapsed = []
    for m in cpso_paper + [paper_param_best]:
        pred = np.array(m["test_pred_deg_h"])
        collapsed.append(int(np.sum(np.isclose(pred, np.median(pred), rtol=0, atol=2e-6))))
    paras = [
        f"The model chosen without looking at the test runs ({chosen['name']}) identifies the 10 test drifts "
        f"with a mean absolute error of {_fmt(chosen['test_mae_deg_h'])} deg/h (largest "
        f"{_fmt(chosen['test_max_abs_err_deg_h'])} deg/h; {within} of 10 within the 0.0005 deg/h that "
        f"1 nmi / 72 h needs); its 90 % interval (calibrated on the training runs' leave-one-out scores), +-"
        f"{_fmt(chosen['interval_90_half_width_deg_h'])} deg/h, covers {chosen['test_covered_by_interval_90']} of "
        f"the 10 test runs. The paper's Table 3 implies a mean absolute error of {_fmt(paper_mae)} deg/h: "
        f"the reproduction is {chosen['test_mae_deg_h'] / paper_mae:.1f} times less accurate than the paper claims.",
        f"The physics inversion of the 12 h latitude error alone, with no training, reaches "
        f"{_fmt(physics['test_mae_deg_h'])} deg/h; the best of all trained methods on the test runs (reported, "
        f"not selected) is {best_learned['name']} at {_fmt(best_learned['test_mae_deg_h'])} deg/h. "
        f"{n_beating_physics} of the {len(trained)} trained models beat the physics inversion on the test runs.",
        "The paper's fitness (training MAE, eq. 16) rewards interpolation: the paper-settings swarm drives it to "
        + ", ".join(
            f"{_fmt(m['fitness'])} ({m['encoding']}, gamma {_fmt(m['gamma'])}, sigma {_fmt(m['sigma'])})"
            for m in cpso_paper
        )
        + f" against the paper's {_fmt(claims['fitness'])}, which says little about new runs: compare their test "
        "errors with the leave-one-out tuned models. Such an interpolating model falls back to its bias b away "
        "from the training points: "
        + ", ".join(
            f"{c} of 10 test predictions of {m['name']} lie within 2e-6 deg/h of one value"
            for c, m in zip(collapsed, cpso_paper + [paper_param_best], strict=False)
        )
        + ".",
        f"{len(on_bound)} of the {len(tuned)} tuned models end on the edge of the search box "
        f"(gamma in [{_fmt(tuned[0]['search_bounds'][0][0])}, {_fmt(tuned[0]['search_bounds'][0][1])}], sigma in "
        f"[{_fmt(tuned[0]['search_bounds'][1][0])}, {_fmt(tuned[0]['search_bounds'][1][1])}], scaled units; marked "
        "'(bound)' in the table): " + (", ".join(m["name"] for m in on_bound) or "none") + ". Their optimum lies "
        "outside the box or the objective is flat there; a wider box would move them.",
        f"The paper's published gamma = {claims['gamma']} and sigma = {claims['sigma']} give at best "
        f"{_fmt(paper_param_best['test_mae_deg_h'])} deg/h ({paper_param_best['encoding']}, "
        f"{paper_param_best['scaling']} scaling) with the encodings and scalings tried here; the paper does not "
        "say how inputs were encoded or scaled, so its parameters cannot be transferred as they stand.",
        f"The paper's Table 3 error column has mixed signs: of its {int(nonzero.sum())} non-zero rows, "
        f"{agree_true_minus} equal true minus identified and {agree_minus_true} identified minus true; the "
        f"magnitudes {'all agree' if mags_agree else 'do not all agree'} with |true - identified|. The tables here "
        "recompute errors as true minus identified.",
    ]
    return paras


def _col(fmt: str):
    """A column formatter: one format for every number of the column, "-" for a missing value."""

    def f(x) -> str:
        if x is None or (isinstance(x, float) and not np.isfinite(x)):
            return "-"
        return format(x, fmt)

    return f


DRIFT = _col(".6f")  # deg/h: predictions, errors, MAEs of the order of 1e-4
SCI = _col(".3e")  # quantities spanning decades: gamma, sigma, train-MAE fitness
NMI = _col(".2f")
COUNT = _col("d")


def summary_box(results: dict) -> tuple:
    """The box at the top of the report: the paper's claims as printed (its text and tables), what gyrodrift
    computes from the paper's Table 3 predictions (their errors, implied and simulated 72 h position errors), and
    the selected model's results, in three separate columns."""
    claims = results["paper_claims"]
    true = np.array(results["data"]["test_true_deg_h"])
    claim_err = true - np.array(claims["test_pred_deg_h"])
    chosen = selected_method(results)
    twin = _method(results, "cpso_paper", chosen["encoding"])
    implied = results["paper_implied_72h_pos_err_nmi"]
    f45 = results["position_error_72h"]
    rows = [  # the paper's claims | what gyrodrift computes from the paper's Table 3 | gyrodrift's reproduction
        ["test MAE [deg/h]", "-", DRIFT(float(np.mean(np.abs(claim_err)))), DRIFT(chosen["test_mae_deg_h"])],
        [
            "test max abs error [deg/h]",
            f"all within {claims['claimed_accuracy_deg_h']:g}",
            DRIFT(float(np.max(np.abs(claim_err)))),
            DRIFT(chosen["test_max_abs_err_deg_h"]),
        ],
        [
            "72 h position error implied by the test errors, mean / max [nmi]",
            "-",
            f"{NMI(implied['mean'])} / {NMI(implied['max'])}",
            f"{NMI(chosen['implied_72h_pos_err_nmi_mean'])} / {NMI(chosen['implied_72h_pos_err_nmi_max'])}",
        ],
        [
            f"72 h position error of test run {f45['run']}, simulated, compensated (uncompensated: "
            f"{NMI(f45['uncompensated_max_pos_err_nmi'])}) [nmi, max]",
            "-",
            NMI(f45["paper_max_pos_err_nmi"]),
            NMI(f45["selected_max_pos_err_nmi"]),
        ],
        ["gamma (regularisation)", SCI(claims["gamma"]), "-", SCI(chosen["gamma"]) + " (standardised inputs)"],
        ["sigma (RBF width)", SCI(claims["sigma"]), "-", SCI(chosen["sigma"]) + " (standardised inputs)"],
        [
            "fitness: train MAE of the paper-settings swarm [deg/h]",
            SCI(claims["fitness"]),
            "-",
            SCI(twin["fitness"]) + f" ({twin['encoding']}; the selected model's LOO MAE: "
            f"{DRIFT(chosen['loo_mae_deg_h'])})"
            if twin
            else "-",
        ],
        [
            "convergence [iterations]",
            f"~{claims['fitness_converged_after_iterations']}",
            "-",
            f"{twin['converged_iteration'] if twin else '-'} (paper settings), {chosen['converged_iteration']} "
            "(selected); within 1 % of the final fitness",
        ],
    ]
    note = (
        f"Selected without test data: {chosen['name']}. Implied errors: the closed-form 72 h position error of a "
        f"residual drift equal to each test error at {results['data']['lat0_deg']} deg (0.0005 deg/h leaves 0.90 "
        "nmi). Simulated run: the test run with the median error of the selected model, noise-free, 10 Hz "
        "(figure position_error_72h.png), simulated by gyrodrift with each drift compensated; the paper publishes "
        "no such number. '-': no such number."
    )
    return (
        "box",
        "Result: the paper's claims, gyrodrift's computations on the paper's numbers, and its reproduction",
        ["", "the paper claims", "gyrodrift computes from the paper's Table 3", "gyrodrift reproduces"],
        rows,
        note,
    )


def report_blocks(results: dict, figures: dict[str, Path]) -> list[tuple]:
    """The report as blocks: ("h1"|"h2", text), ("p", text), ("box", title, header, rows, note),
    ("table", header, rows, highlighted row indices, highlighted column indices), ("img", path, caption).

    The selected model is highlighted in every table (its row or columns) and every figure.
    """
    claims = results["paper_claims"]
    true = results["data"]["test_true_deg_h"]
    shown = key_methods(results)
    chosen = selected_method(results)
    sel_cols = {4 + i for i, m in enumerate(shown) if m is chosen} | {
        4 + len(shown) + i for i, m in enumerate(shown) if m is chosen
    }
    methods = results["methods"]
    blocks: list[tuple] = [
        ("h1", "gyrodrift reproduce: CPSO-LSSVM axial drift identification (Yu et al. 2013)"),
        ("p", verdict(results)),
        summary_box(results),
        (
            "p",
            f"gyrodrift {results['gyrodrift_version']}, seed {results['seed']}, methods computed in "
            f"{results['elapsed_s']:.1f} s (wall time). Trained on the paper's 22 training runs, tested on its 10 "
            f"test runs (site latitude {results['data']['lat0_deg']} deg). Drifts in deg/h; errors are true minus "
            "identified. The selected model is marked in bold (highlighted in the HTML) in every table and drawn "
            "thicker or outlined in every figure; each method keeps one colour in every figure.",
        ),
        ("h2", "How the inputs were encoded and scaled"),
        (
            "p",
            "The paper does not say. Latitude feature: "
            + results["input_handling"]["latitude_feature"]
            + ". Encodings of the temperature range: "
            + "; ".join(f"{k}: {v}" for k, v in results["input_handling"]["encodings"].items())
            + ". Scaling: "
            + results["input_handling"]["scaling"]
            + ". Selection: "
            + results["selected_by_loo"]["rule"]
            + f" -> {results['selected_by_loo']['name']}.",
        ),
        ("h2", "Identification of the test runs (cf. the paper's Table 3) [deg/h]"),
        (
            "table",
            ["run", "true", "paper pred (claimed)", "paper err (published)"]
            + [f"{_label(m, chosen)} pred" for m in shown]
            + [f"{_label(m, chosen)} err" for m in shown],
            [
                [run, DRIFT(true[i]), DRIFT(claims["test_pred_deg_h"][i]), DRIFT(claims["test_err_deg_h"][i])]
                + [DRIFT(m["test_pred_deg_h"][i]) for m in shown]
                + [DRIFT(m["test_err_deg_h"][i]) for m in shown]
                for i, run in enumerate(results["data"]["test_runs"])
            ],
            set(),
            sel_cols,
        ),
        ("h2", "Every method"),
        (
            "p",
            "Errors and MAEs in deg/h; gamma and sigma in standardised input units; 'converged' is the first "
            "iteration within 1 % of the final fitness; the 72 h columns are the closed-form position errors the "
            "10 test errors imply at the paper's latitude (mean and max).",
        ),
        (
            "table",
            [
                "method",
                "gamma",
                "sigma",
                "evaluations",
                "converged",
                "train MAE",
                "LOO MAE",
                "test MAE",
                "test max abs err",
                "72 h mean [nmi]",
                "72 h max [nmi]",
            ],
            [
                [
                    m["name"] + (" (selected)" if m is chosen else ""),
                    SCI(m.get("gamma")) + (" (bound)" if "gamma" in m.get("on_search_bound", ()) else ""),
                    SCI(m.get("sigma")) + (" (bound)" if "sigma" in m.get("on_search_bound", ()) else ""),
                    COUNT(m.get("nfev") or None),
                    COUNT(m.get("converged_iteration")),
                    SCI(m["train_mae_deg_h"]),
                    DRIFT(m.get("loo_mae_deg_h")),
                    DRIFT(m["test_mae_deg_h"]),
                    DRIFT(m["test_max_abs_err_deg_h"]),
                    NMI(m["implied_72h_pos_err_nmi_mean"]),
                    NMI(m["implied_72h_pos_err_nmi_max"]),
                ]
                for m in methods
            ],
            {i for i, m in enumerate(methods) if m is chosen},
            set(),
        ),
        ("h2", "Figures"),
        (
            "img",
            figures["position_error_72h"],
            "72 h position error of a representative test run simulated at the paper's latitude: uncompensated, "
            "with the selected model's drift and with the paper's Table 3 drift compensated (the paper's Fig. 4/5).",
        ),
        (
            "img",
            figures["fitness_curve"],
            "Fitness per iteration of the paper-settings CPSO with the paper's ~55 iterations marked (left; paper "
            "Fig. 3) and LOO MAE against evaluations, chaos vs plain PSO (right).",
        ),
        (
            "img",
            figures["pred_vs_true"],
            "Identified vs true drift on the 10 test runs; grey band: +-0.0005 deg/h around the diagonal.",
        ),
        ("img", figures["error_per_run"], "Error per test run; grey band: the +-0.0005 deg/h budget."),
        ("h2", "Conclusion"),
    ]
    blocks += [("p", p) for p in conclusion(results)]
    return blocks


def _md_cell(text: str, bold: bool) -> str:
    return f"**{text}**" if bold and text else text


def render_markdown(blocks: list[tuple]) -> str:
    lines = []
    for b in blocks:
        if b[0] == "h1":
            lines += [f"# {b[1]}", ""]
        elif b[0] == "h2":
            lines += [f"## {b[1]}", ""]
        elif b[0] == "p":
            lines += [b[1], ""]
        elif b[0] == "box":
            _, title, header, rows, note = b
            lines += [f"> **{title}**", ">"]
            lines.append("> | " + " | ".join(header) + " |")
            lines.append("> |" + "---|" * len(header))
            lines += ["> | " + " | ".join(row) + " |" for row in rows]
            lines += [">", f"> {note}", ""]
        elif b[0] == "table":
            _, header, rows, hl_rows, hl_cols = b
            lines.append("| " + " | ".join(_md_cell(h, j in hl_cols) for j, h in enumerate(header)) + " |")
            lines.append("|" + "---|" * len(header))
            lines += [
                "| " + " | ".join(_md_cell(c, i in hl_rows or j in hl_cols) for j, c in enumerate(row)) + " |"
                for i, row in enumerate(rows)
            ]
            lines.append("")
        elif b[0] == "img":
            lines += [f"![{b[2]}]({Path(b[1]).name})", "", f"*{b[2]}*", ""]
    return "\n".join(lines)


def render_html(blocks: list[tuple], images: dict[str, bytes]) -> str:
    """A self-contained page: the figures (`images`, PNG bytes by file name) are embedded as base64 PNG."""
    parts = [
        "<!DOCTYPE html><html><head><meta charset='utf-8'><title>gyrodrift reproduce</title>",
        "<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;line-height:1.4}"
        "table{border-collapse:collapse;font-size:12px}td,th{border:1px solid #bbb;padding:2px 6px;text-align:right}"
        "td:first-child{text-align:left}img{max-width:100%}.sel{background:#fff2b3;font-weight:bold}"
        ".box{border:2px solid #333;background:#f4f7fb;padding:0.6em 1em;margin:1em 0}"
        ".box table{font-size:13px}.box p{font-size:12px}</style></head><body>",
    ]

    def cls(on: bool) -> str:
        return " class='sel'" if on else ""

    for b in blocks:
        if b[0] in ("h1", "h2"):
            parts.append(f"<{b[0]}>{html.escape(b[1])}</{b[0]}>")
        elif b[0] == "p":
            parts.append(f"<p>{html.escape(b[1])}</p>")
        elif b[0] == "box":
            _, title, header, rows, note = b
            parts.append(f"<div class='box'><h2>{html.escape(title)}</h2><table><tr>")
            parts.append("".join(f"<th>{html.escape(h)}</th>" for h in header) + "</tr>")
            for row in rows:
                parts.append("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>")
            parts.append(f"</table><p>{html.escape(note)}</p></div>")
        elif b[0] == "table":
            _, header, rows, hl_rows, hl_cols = b
            parts.append(
                "<table><tr>"
                + "".join(f"<th{cls(j in hl_cols)}>{html.escape(h)}</th>" for j, h in enumerate(header))
                + "</tr>"
            )
            for i, row in enumerate(rows):
                parts.append(
                    f"<tr{cls(i in hl_rows)}>"
                    + "".join(f"<td{cls(j in hl_cols)}>{html.escape(c)}</td>" for j, c in enumerate(row))
                    + "</tr>"
                )
            parts.append("</table>")
        elif b[0] == "img":
            data = base64.b64encode(images[Path(b[1]).name]).decode()
            parts.append(
                f"<figure><img src='data:image/png;base64,{data}' alt='{html.escape(b[2])}'>"
                f"<figcaption>{html.escape(b[2])}</figcaption></figure>"
            )
    parts.append("</body></html>")
    return "\n".join(parts)


def write_report(results: dict, stage: Stage, pool: Executor | None = None) -> None:
    """Write the figures, ``report.md`` and ``report.html`` into `stage` (a `gyrodrift.files.atomic.Stage`; the
    caller publishes them with ``results.json``); ``pool`` draws the figures (`make_figures`)."""
    pngs = make_figures(results, pool)
    images = {f"{name}.png": data for name, data in pngs.items()}
    for filename, data in images.items():
        stage.file(filename).write_bytes(data)
    blocks = report_blocks(results, {name: Path(f"{name}.png") for name in pngs})
    stage.file("report.md").write_text(render_markdown(blocks), encoding="utf-8")
    stage.file("report.html").write_text(render_html(blocks, images), encoding="utf-8")


def summary_lines(results: dict) -> list[str]:
    """A one-screen terminal summary, led by the `verdict`."""
    chosen = selected_method(results)
    lines = [
        verdict(results),
        f"  {'method [deg/h; 72 h: nmi implied, mean]':<72} {'test MAE':>10} {'max|err|':>10} {'LOO MAE':>10} "
        f"{'72 h':>6}",
    ]
    for m in results["methods"]:
        if m["family"] == "paper_params" and m.get("scaling") != "standard":
            continue
        mark = "* " if m is chosen else "  "
        lines.append(
            f"{mark}{m['name'][:72]:<72} {DRIFT(m['test_mae_deg_h']):>10} {DRIFT(m['test_max_abs_err_deg_h']):>10} "
            f"{DRIFT(m.get('loo_mae_deg_h')):>10} {NMI(m['implied_72h_pos_err_nmi_mean']):>6}"
        )
    true = np.array(results["data"]["test_true_deg_h"])
    claim_err = true - np.array(results["paper_claims"]["test_pred_deg_h"])
    lines.append(
        f"  {'paper Table 3 (claimed)':<72} {DRIFT(float(np.mean(np.abs(claim_err)))):>10} "
        f"{DRIFT(float(np.max(np.abs(claim_err)))):>10} {'':>10} "
        f"{NMI(results['paper_implied_72h_pos_err_nmi']['mean']):>6}"
    )
    f45 = results["position_error_72h"]
    lines.append(f"* selected by LOO (no test data): {chosen['name']}")
    lines.append(
        f"test run {f45['run']} simulated 72 h at {f45['lat_deg']} deg: max position error "
        f"{NMI(f45['uncompensated_max_pos_err_nmi'])} nmi uncompensated, {NMI(f45['selected_max_pos_err_nmi'])} nmi "
        f"with the selected model, {NMI(f45['paper_max_pos_err_nmi'])} nmi with the paper's Table 3 drift"
    )
    return lines
