"""The reproduction report: figures (matplotlib PNG), ``report.md`` and a self-contained ``report.html``.

The report is built once as a list of blocks (heading, paragraph, table, figure) and rendered to both
formats, so the two always say the same thing. Every number in it comes from ``results.json``.
"""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path

import numpy as np

from gyrodrift.atomic import Stage


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


REPORT_FIGURES = ("fitness_curve", "pred_vs_true", "error_per_run")
"""The report's figures, written as ``<name>.png``."""
REPORT_FILES = ("results.json", "report.md", "report.html") + tuple(f"{name}.png" for name in REPORT_FIGURES)
"""The files of a reproduction output, published together (`gyrodrift.reproduce.reproduce`)."""


def _png(fig) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    return buffer.getvalue()


def make_figures(results: dict) -> dict[str, bytes]:
    """The report's PNG figures, {name: PNG bytes} for the names in `REPORT_FIGURES`."""
    from matplotlib.figure import Figure  # object API: no pyplot state, the caller's backend untouched

    claims = results["paper_claims"]
    true = np.array(results["data"]["test_true_deg_h"])
    runs = results["data"]["test_runs"]
    out = {}

    fig = Figure(figsize=(11, 4))
    axes = fig.subplots(1, 2)
    for m in results["methods"]:
        if m["family"] == "cpso_paper":
            axes[0].semilogy(np.arange(1, len(m["fitness_history"]) + 1), m["fitness_history"], label=m["encoding"])
    axes[0].axhline(claims["fitness"], color="k", ls="--", lw=1, label=f"paper's claim {claims['fitness']:.3e}")
    axes[0].set(
        xlabel="iteration", ylabel="fitness: train MAE [deg/h]", title="CPSO, paper settings (cf. paper Fig. 3)"
    )
    axes[0].legend(fontsize=8)
    for m in results["methods"]:
        if m["family"] in ("cpso_loo", "pso_loo") and m["fitness_history"]:
            h = np.asarray(m["fitness_history"])
            evals = np.linspace(m["nfev"] / len(h), m["nfev"], len(h))
            axes[1].plot(evals, h, ls="-" if m["family"] == "cpso_loo" else ":", label=short_name(m))
    axes[1].set(xlabel="objective evaluations", ylabel="LOO MAE [deg/h]", title="chaos vs plain PSO, equal budget")
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    out["fitness_curve"] = _png(fig)

    shown = key_methods(results)
    fig = Figure(figsize=(5.5, 5))
    ax = fig.subplots()
    lim = 1.15 * max(np.abs(true).max(), max(np.abs(m["test_pred_deg_h"]).max() for m in shown))
    ax.plot([-lim, lim], [-lim, lim], color="0.6", lw=1)
    ax.scatter(true, claims["test_pred_deg_h"], marker="x", color="k", label="paper's Table 3 (claimed)")
    for m in shown:
        ax.scatter(true, m["test_pred_deg_h"], s=18, label=short_name(m))
    ax.set(
        xlabel="true drift [deg/h]",
        ylabel="identified drift [deg/h]",
        title="test runs: identified vs true",
        xlim=(-lim, lim),
        ylim=(-lim, lim),
    )
    ax.legend(fontsize=7)
    fig.tight_layout()
    out["pred_vs_true"] = _png(fig)

    fig = Figure(figsize=(10, 4))
    ax = fig.subplots()
    width = 0.8 / (len(shown) + 1)
    x = np.arange(len(runs))
    true_minus_claim = true - np.array(claims["test_pred_deg_h"])
    ax.bar(x, true_minus_claim, width, color="k", label="paper (true - Table 3 prediction)")
    for i, m in enumerate(shown, start=1):
        ax.bar(x + i * width, m["test_err_deg_h"], width, label=short_name(m))
    ax.axhline(0.0005, color="r", ls="--", lw=1)
    ax.axhline(-0.0005, color="r", ls="--", lw=1, label="+-0.0005 deg/h (1 nmi / 72 h budget)")
    ax.set_xticks(x + 0.4 - width / 2, runs)
    ax.set(xlabel="test run", ylabel="error, true - identified [deg/h]", title="identification error per test run")
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    out["error_per_run"] = _png(fig)
    return out


def conclusion(results: dict) -> list[str]:
    """Paragraphs of the report's conclusion, computed from the results."""
    claims = results["paper_claims"]
    true = np.array(results["data"]["test_true_deg_h"])
    claim_pred = np.array(claims["test_pred_deg_h"])
    claim_err = np.array(claims["test_err_deg_h"])
    paper_mae = float(np.mean(np.abs(true - claim_pred)))
    chosen = next(m for m in results["methods"] if m["name"] == results["selected_by_loo"]["name"])
    physics = _method(results, "physics_inversion")
    assert physics is not None, "results without the physics inversion"
    best_learned = min(
        (m for m in results["methods"] if m["family"] not in ("physics_inversion", "paper_params")),
        key=lambda m: m["test_mae_deg_h"],
    )
    paper_param_best = min(
        (m for m in results["methods"] if m["family"] == "paper_params"), key=lambda m: m["test_mae_deg_h"]
    )
    cpso_paper = [m for m in results["methods"] if m["family"] == "cpso_paper"]
    within = int(np.sum(np.abs(np.array(chosen["test_err_deg_h"])) <= 0.0005))
    tuned = [m for m in results["methods"] if "on_search_bound" in m]
    on_bound = [m for m in tuned if m["on_search_bound"]]
    nonzero = claim_err != 0
    mags_agree = bool(np.allclose(np.abs(claim_err), np.abs(true - claim_pred), rtol=0, atol=5e-7))
    agree_true_minus = int(np.sum(np.isclose(claim_err, true - claim_pred, atol=5e-7) & nonzero))
    agree_minus_true = int(np.sum(np.isclose(claim_err, claim_pred - true, atol=5e-7) & nonzero))
    trained = [m for m in results["methods"] if m["family"] not in ("physics_inversion", "paper_params")]
    n_beating_physics = sum(m["test_mae_deg_h"] < physics["test_mae_deg_h"] for m in trained)
    collapsed = []
    for m in cpso_paper + [paper_param_best]:
        pred = np.array(m["test_pred_deg_h"])
        collapsed.append(int(np.sum(np.isclose(pred, np.median(pred), rtol=0, atol=2e-6))))
    paras = [
        f"The model chosen without looking at the test runs ({chosen['name']}) identifies the 10 test drifts "
        f"with a mean absolute error of {_fmt(chosen['test_mae_deg_h'])} deg/h (largest "
        f"{_fmt(chosen['test_max_abs_err_deg_h'])} deg/h; {within} of 10 within the 0.0005 deg/h that "
        f"1 nmi / 72 h needs); its 90 % jackknife interval from the leave-one-out residuals, +-"
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


def report_blocks(results: dict, figures: dict[str, Path]) -> list[tuple]:
    """The report as blocks: ("h1"|"h2", text), ("p", text), ("table", header, rows), ("img", path, caption)."""
    claims = results["paper_claims"]
    true = results["data"]["test_true_deg_h"]
    shown = key_methods(results)
    blocks: list[tuple] = [
        ("h1", "gyrodrift reproduce: CPSO-LSSVM axial drift identification (Yu et al. 2013)"),
        (
            "p",
            f"gyrodrift {results['gyrodrift_version']}, seed {results['seed']}, "
            f"{results['elapsed_s']:.1f} s. Trained on the paper's 22 training runs, tested on its 10 test runs "
            f"(site latitude {results['data']['lat0_deg']} deg). Drifts in deg/h; errors are true minus identified.",
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
        ("h2", "Identification of the test runs (cf. the paper's Table 3)"),
        (
            "table",
            ["run", "true", "paper pred (claimed)", "paper err (published)"]
            + [f"{short_name(m)} pred" for m in shown]
            + [f"{short_name(m)} err" for m in shown],
            [
                [run, _fmt(true[i]), _fmt(claims["test_pred_deg_h"][i]), _fmt(claims["test_err_deg_h"][i])]
                + [_fmt(m["test_pred_deg_h"][i]) for m in shown]
                + [_fmt(m["test_err_deg_h"][i]) for m in shown]
                for i, run in enumerate(results["data"]["test_runs"])
            ],
        ),
        ("h2", "Every method"),
        (
            "table",
            ["method", "gamma", "sigma", "evaluations", "train MAE", "LOO MAE", "test MAE", "test max |err|"],
            [
                [
                    m["name"],
                    _fmt(m.get("gamma")) + (" (bound)" if "gamma" in m.get("on_search_bound", ()) else ""),
                    _fmt(m.get("sigma")) + (" (bound)" if "sigma" in m.get("on_search_bound", ()) else ""),
                    str(m.get("nfev", "-")) if m.get("nfev") else "-",
                    _fmt(m["train_mae_deg_h"]),
                    _fmt(m.get("loo_mae_deg_h")),
                    _fmt(m["test_mae_deg_h"]),
                    _fmt(m["test_max_abs_err_deg_h"]),
                ]
                for m in results["methods"]
            ],
        ),
        ("h2", "Figures"),
        (
            "img",
            figures["fitness_curve"],
            "Fitness per iteration of the paper-settings CPSO (left; paper Fig. 3) "
            "and LOO MAE against evaluations, chaos vs plain PSO (right).",
        ),
        ("img", figures["pred_vs_true"], "Identified vs true drift on the 10 test runs."),
        ("img", figures["error_per_run"], "Error per test run; dashed red: the 0.0005 deg/h budget."),
        ("h2", "Conclusion"),
    ]
    blocks += [("p", p) for p in conclusion(results)]
    return blocks


def render_markdown(blocks: list[tuple]) -> str:
    lines = []
    for b in blocks:
        if b[0] == "h1":
            lines += [f"# {b[1]}", ""]
        elif b[0] == "h2":
            lines += [f"## {b[1]}", ""]
        elif b[0] == "p":
            lines += [b[1], ""]
        elif b[0] == "table":
            lines.append("| " + " | ".join(b[1]) + " |")
            lines.append("|" + "---|" * len(b[1]))
            lines += ["| " + " | ".join(row) + " |" for row in b[2]]
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
        "td:first-child{text-align:left}img{max-width:100%}</style></head><body>",
    ]
    for b in blocks:
        if b[0] in ("h1", "h2"):
            parts.append(f"<{b[0]}>{html.escape(b[1])}</{b[0]}>")
        elif b[0] == "p":
            parts.append(f"<p>{html.escape(b[1])}</p>")
        elif b[0] == "table":
            parts.append("<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in b[1]) + "</tr>")
            for row in b[2]:
                parts.append("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>")
            parts.append("</table>")
        elif b[0] == "img":
            data = base64.b64encode(images[Path(b[1]).name]).decode()
            parts.append(
                f"<figure><img src='data:image/png;base64,{data}' alt='{html.escape(b[2])}'>"
                f"<figcaption>{html.escape(b[2])}</figcaption></figure>"
            )
    parts.append("</body></html>")
    return "\n".join(parts)


def write_report(results: dict, stage: Stage) -> None:
    """Write the figures, ``report.md`` and ``report.html`` into `stage` (a `gyrodrift.atomic.Stage`; the
    caller publishes them with ``results.json``)."""
    pngs = make_figures(results)
    images = {f"{name}.png": data for name, data in pngs.items()}
    for filename, data in images.items():
        stage.file(filename).write_bytes(data)
    blocks = report_blocks(results, {name: Path(f"{name}.png") for name in pngs})
    stage.file("report.md").write_text(render_markdown(blocks), encoding="utf-8")
    stage.file("report.html").write_text(render_html(blocks, images), encoding="utf-8")


def summary_lines(results: dict) -> list[str]:
    """A one-screen terminal summary."""
    lines = [f"{'method':<72} {'test MAE':>10} {'max|err|':>10} {'LOO MAE':>10}"]
    for m in results["methods"]:
        if m["family"] == "paper_params" and m.get("scaling") != "standard":
            continue
        lines.append(
            f"{m['name'][:72]:<72} {_fmt(m['test_mae_deg_h']):>10} {_fmt(m['test_max_abs_err_deg_h']):>10} "
            f"{_fmt(m.get('loo_mae_deg_h')):>10}"
        )
    true = np.array(results["data"]["test_true_deg_h"])
    paper_mae = float(np.mean(np.abs(true - np.array(results["paper_claims"]["test_pred_deg_h"]))))
    lines.append(f"{'paper Table 3 (claimed)':<72} {_fmt(paper_mae):>10}")
    lines.append(f"selected by LOO (no test data): {results['selected_by_loo']['name']}")
    return lines
