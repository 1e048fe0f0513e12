"""The accuracy study's report: figures (PNG), ``study.json`` and a self-contained ``report.html``.

Every number shown comes from `gyrodrift.fleet.study.StudyResult.to_dict` (the JSON written beside it). The report
leads with the summary (the drift laws' headline per run group, best method, the physical limit, the hybrid default
against it), then the drift-law table (`gyrodrift.fleet.law_study`) and its figure, then the method table, then the
curves (accuracy vs training-set size, vs noise grade, vs latitude).
"""

from __future__ import annotations

import base64
import html
import io
import math
from typing import Any

from gyrodrift.files.atomic import Stage, write_json
from gyrodrift.fleet.law_study import LAW_METHODS
from gyrodrift.fleet.study import FLEET_ROW

__all__ = ["FIGURES", "STUDY_FILES", "make_figures", "method_colours", "summary_lines", "write_study_report"]

FIGURES = ("laws.png", "methods.png", "train_size.png", "noise_grade.png", "latitude.png")
STUDY_FILES = ("study.json", "report.html", *FIGURES)
"""The files `write_study_report` publishes together."""


def _f(x: Any, unit: str = "") -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    return f"{x:.2e}{unit}" if abs(x) < 1e-2 and x != 0 else f"{x:.3g}{unit}"


def _pct(x: Any) -> str:
    return "-" if x is None else f"{100 * x:.0f} %"


def _pm(x: Any, sd: Any, scale: float = 1.0, fmt: str = ".2f", unit: str = "") -> str:
    """``x +- sd`` (times `scale`), "-" for a missing value."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    spread = "" if sd is None else f" +- {scale * sd:{fmt.lstrip('+')}}"
    return f"{scale * x:{fmt}}{spread}{unit}"


def _groups(doc: dict) -> dict[str, dict]:
    """The drift-law groups holding runs (empty without the comparison)."""
    laws = doc.get("drift_laws")
    return {} if laws is None else {g: v for g, v in laws["groups"].items() if v["n"]}


def law_lines(doc: dict) -> list[str]:
    """One line per drift-law group with runs (a group holding every run only as ``all``): the held-out shares and
    RMS of the constant today, the identified law and the offline best constant and law, the law's difference to
    the constant today, the gap it closes; then, with ``drift_laws.limit``, the identified law's physical limit
    (`gyrodrift.fleet.law_limit`): predicted RMS, the lower bound of any law from the 16 h, observed RMS and the
    predicted and observed share under 1 nmi at 72 h."""
    lines = []
    groups = _groups(doc)
    for group, v in groups.items():
        if group != "all" and v["n"] == groups["all"]["n"]:  # the same runs as all: said once
            continue
        m, vs = v["methods"], v["identified_vs"]["constant today"]
        names = doc["drift_laws"]["methods"][1:]
        shares = ", ".join(
            f"{name} {_pm(m[name]['under_1nmi_72h'], m[name]['under_1nmi_72h_std'], 100, '.0f', ' %')}"
            for name in names
        )
        rms = ", ".join(f"{_pm(m[name]['rms_final_nmi'], m[name]['rms_final_nmi_std'])}" for name in names)
        gap = v["gap_closed"]
        lines.append(
            f"Drift laws, {group} ({v['n']} held-out runs): under 1 nmi over the 72 h: {shares}; RMS of the 72 h "
            f"final error [nmi] in the same order: {rms}; identified law minus constant today: "
            f"{_pm(vs['d_under_1nmi_72h'], vs['d_under_1nmi_72h_std'], 100, '+.0f', ' points')}, RMS "
            f"{_pm(vs['d_rms_final_nmi'], vs['d_rms_final_nmi_std'], 1.0, '+.3f', ' nmi')}; gap to the offline best "
            f"law closed: {_f(gap['rms_final_nmi'])} (RMS), {_f(gap['under_1nmi_72h'])} (share over 72 h)."
        )
        limit = (doc["drift_laws"].get("limit") or {}).get("groups", {}).get(group)
        if limit and limit["n"]:  # gyrodrift.fleet.law_limit
            r = limit["laws"]["identified law"]
            lines.append(
                f"Physical limit of the identified law, {group}: predicted RMS {_f(r['predicted_rms_nmi'])} nmi "
                f"(identification {_f(r['predicted_identification_rms_nmi'])}, noise floor "
                f"{_f(limit['noise_floor_rms_nmi'])}; no law from the 16 h below {_f(r['lower_bound_rms_nmi'])}), "
                f"observed {_f(r['observed_rms_nmi'])} (ratio {_f(r['ratio'])}); under 1 nmi at 72 h predicted "
                f"{_pct(r['predicted_under_1nmi_final'])}, observed {_pct(r['observed_under_1nmi_final'])}."
            )
    return lines


def summary_lines(doc: dict) -> list[str]:
    """The report's opening lines (also printed by ``gyrodrift study``)."""
    methods = doc["methods"]
    ranked = sorted(methods, key=lambda n: methods[n]["metrics"]["rms_eff"] or math.inf)
    best = ranked[0]
    lines = [
        f"{doc['n_runs']} runs ({doc['n_failed']} failed), {doc['n_train']} for training, {doc['n_test']} held out "
        f"(seed {doc['seed']}); labels (72 h truth) vs simulated effective drift: RMS "
        f"{_f(doc['label_error_rms_deg_h'])} deg/h.",
        *law_lines(doc),
        f"Best on the held-out runs: {best}, RMS {_f(methods[best]['metrics']['rms_eff'])} deg/h against the "
        f"effective drift, {_pct(methods[best]['metrics']['under_1nmi_final'])} of runs under 1 nmi at hour 72.",
    ]
    limit = doc["physical_limit_deg_h"]
    if limit is not None:
        hyb = methods["hybrid default"]["metrics"]
        lines.append(
            f"Physical limit (16 h smoother's 1-sigma, RMS over the held-out runs): {_f(limit)} deg/h; the hybrid "
            f"default is at {_f(hyb['ratio_to_limit'])}x it, the 12 h inversion at "
            f"{_f(methods['12 h physics inversion']['metrics']['ratio_to_limit'])}x."
        )
        fleet = methods.get(FLEET_ROW)
        if fleet is not None:
            m = fleet["metrics"]
            lines.append(
                f"16 h smoother with the training fleet's k_z prior: {_f(m['ratio_to_limit'])}x the physical limit, "
                f"{_f(m.get('ratio_to_own_sigma'))}x its own (tighter) 1-sigma, 90 % coverage "
                f"{_pct(m.get('coverage_eff'))}."
            )
        else:
            lines.append("No fleet-prior smoother row (see the notes).")
    else:
        lines.append("No smoother estimates in this campaign: no physical-limit line.")
    for name, m in methods.items():
        if m.get("note"):
            lines.append(f"{name}: {m['note']}.")
    return lines


def _png(fig) -> bytes:
    buf = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")  # legends beside or below the axes included
    return buf.getvalue()


def _subplots(figsize):
    from matplotlib.figure import Figure  # no pyplot: no global figure state, any backend

    fig = Figure(figsize=figsize)
    return fig, fig.subplots()


def method_colours(doc: dict) -> dict[str, str]:
    """One colour per method (hex), the same in every figure of the report: the methods in ``doc["methods"]``'s
    order take tab10's colours, then Dark2's; black is kept for the smoother's 1-sigma line."""
    from matplotlib import colormaps
    from matplotlib.colors import to_hex

    palette = [to_hex(colormaps[name](k)) for name, n in (("tab10", 10), ("Dark2", 8)) for k in range(n)]
    return {name: palette[k % len(palette)] for k, name in enumerate(doc["methods"])}


def _log_ticks(axis) -> None:
    """Readable ticks on a log axis spanning less than a few decades: 1, 2 and 5 of each decade, labelled."""
    import matplotlib.ticker

    axis.set_major_locator(matplotlib.ticker.LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _pos: f"{v:.0e}".replace("e-0", "e-")))
    axis.set_minor_formatter(matplotlib.ticker.NullFormatter())


def law_figure(doc: dict):
    """The drift laws per run group: the share of held-out runs under 1 nmi over the whole 72 h (bars, binomial
    1-sigma) and at the 72 h end (dots), one colour per `LAW_METHODS` row (Set2's); a note when there is none."""
    import numpy as np
    from matplotlib import colormaps
    from matplotlib.colors import to_hex

    groups = _groups(doc)
    fig, ax = _subplots((8, 4.2))
    if not groups:
        ax.text(0.5, 0.5, "no drift-law comparison (see the notes)", ha="center", va="center")
        ax.set_axis_off()
        return fig
    x = np.arange(len(groups))
    names = doc["drift_laws"]["methods"]
    width = 0.8 / len(names)
    for k, name in enumerate(names):
        c = to_hex(colormaps["Set2"](LAW_METHODS.index(name)))
        m = [v["methods"][name] for v in groups.values()]
        at = x - 0.4 + (k + 0.5) * width
        over = [100 * r["under_1nmi_72h"] for r in m]
        ax.bar(at, over, width, yerr=[100 * r["under_1nmi_72h_std"] for r in m], color=c, label=name, capsize=2)
        ax.plot(at, [100 * r["under_1nmi_final"] for r in m], "o", color="k", ms=3, label="_at the end")
    ax.set_xticks(x, [f"{g}\n({v['n']} runs)" for g, v in groups.items()])
    ax.set_ylabel("held-out runs under 1 nmi [%]")
    ax.set_ylim(0, 105)
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), title="bars: over the 72 h; dots: at 72 h")
    return fig


def study_figures(doc: dict) -> dict:
    """The figures (matplotlib `Figure`s, no pyplot state), keyed by their ``FIGURES`` file names."""
    import matplotlib.ticker
    import numpy as np
    from matplotlib.patches import Patch

    out: dict = {"laws.png": law_figure(doc)}
    methods = doc["methods"]
    colour = method_colours(doc)
    names = sorted(methods, key=lambda n: methods[n]["metrics"]["rms_eff"] or math.inf)
    fig, ax = _subplots((8, 0.38 * len(names) + 1.8))
    y = np.arange(len(names))
    ax.barh(y - 0.2, [methods[n]["metrics"]["rms_eff"] for n in names], 0.4, color=[colour[n] for n in names])
    ax.barh(
        y + 0.2, [methods[n]["metrics"]["max_eff"] for n in names], 0.4, color=[colour[n] for n in names], alpha=0.4
    )
    handles = [
        Patch(color="0.3", label="RMS vs effective drift (upper bar)"),
        Patch(color="0.3", alpha=0.4, label="max vs effective drift (lower bar)"),
    ]
    if doc["physical_limit_deg_h"] is not None:
        handles.append(ax.axvline(doc["physical_limit_deg_h"], color="k", ls="--", label="smoother 1-sigma"))
    ax.set_yticks(y, names)
    for label, name in zip(ax.get_yticklabels(), names, strict=True):
        label.set_color(colour[name])
    ax.invert_yaxis()
    ax.set_xscale("log")
    _log_ticks(ax.xaxis)
    ax.set_xlabel("identification error on held-out runs [deg/h]")
    ax.legend(handles=handles, fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=3)
    ax.grid(True, axis="x", which="both", alpha=0.3)
    out["methods.png"] = fig

    def curve_figure(x, series: dict, xlabel: str, limit=None, xlog=False):
        fig, ax = _subplots((7, 4.6))
        for name, vals in series.items():
            ax.plot(x, vals, marker="o", ms=4, label=name, color=colour[name])
        if limit is not None and any(v is not None for v in limit):
            ax.plot(x, [math.nan if v is None else v for v in limit], "k--", label="smoother 1-sigma")
        ax.set_yscale("log")
        _log_ticks(ax.yaxis)
        if xlog:
            ax.set_xscale("log")
            ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
            ax.set_xticks(list(x), [f"{v:g}" for v in x])
        ax.set_xlabel(xlabel)
        ax.set_ylabel("RMS error vs effective drift [deg/h]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # beside the axes: covers no curve
        return fig

    ts = doc["train_size"]
    out["train_size.png"] = curve_figure(
        ts["sizes"],
        {k: [math.nan if v is None else v for v in vals] for k, vals in ts["rms_eff"].items()},
        "training runs",
        xlog=True,
    )
    shown = [
        n
        for n in (
            "hybrid default",
            "GP regression",
            "12 h physics inversion",
            "12 h curve fit",
            "CPSO-LSSVM (LOO)",
            "16 h smoother",
            FLEET_ROW,
        )
        if n in methods
    ]
    bg = doc["by_grade"]
    out["noise_grade.png"] = curve_figure(
        bg["arw_deg_rth"],
        {n: [math.nan if v is None else v for v in bg["rms_eff"][n]] for n in shown},
        "gyro ARW of the grade [deg/sqrt(h)]",
        limit=bg["limit_deg_h"],
        xlog=True,
    )
    bl = doc["by_latitude"]
    out["latitude.png"] = curve_figure(
        bl["center_deg"],
        {n: [math.nan if v is None else v for v in bl["rms_eff"][n]] for n in shown},
        "site latitude (held-out runs, mean of the bin) [deg]",
        limit=bl.get("limit_deg_h"),
    )
    return out


def make_figures(doc: dict) -> dict[str, bytes]:
    """The four figures of `study_figures` as PNG bytes."""
    return {name: _png(fig) for name, fig in study_figures(doc).items()}


def _table(head: list[str], rows: list[list[str]]) -> str:
    h = "".join(f"<th>{html.escape(c)}</th>" for c in head)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><tr>{h}</tr>{body}</table>"


CAPTIONS = {
    "laws.png": "Held-out runs under 1 nmi over the 72 h (bars, binomial 1-sigma) and at 72 h (dots) per law.",
    "methods.png": "RMS and max error per method; dashed: the smoother's 1-sigma.",
    "train_size.png": "RMS error vs training-set size (learned methods refitted on nested subsets).",
    "noise_grade.png": "RMS error per noise grade (held-out runs grouped).",
    "latitude.png": "RMS error vs site latitude (held-out runs in latitude quantiles).",
}


def _figure(name: str, images: dict[str, bytes]) -> str:
    """Figure `name` inlined (base64 PNG) under its caption."""
    b64 = base64.b64encode(images[name]).decode()
    return f"<h3>{html.escape(CAPTIONS[name])}</h3><img src='data:image/png;base64,{b64}' alt='{name}'>"


def _law_tables(doc: dict, images: dict[str, bytes]) -> list[str]:
    """The drift-law section of the report: the methods per run group, the identified law's comparisons, the
    figure."""
    groups = _groups(doc)
    if not groups:
        return []
    rows, paired = [], []
    for group, v in groups.items():
        for name in doc["drift_laws"]["methods"]:
            m = v["methods"][name]
            rows.append(
                [
                    f"{group} ({v['n']})",
                    name,
                    _pm(m["under_1nmi_final"], m["under_1nmi_final_std"], 100, ".0f", " %"),
                    _pm(m["under_1nmi_72h"], m["under_1nmi_72h_std"], 100, ".0f", " %"),
                    _pm(m["rms_final_nmi"], m["rms_final_nmi_std"], 1.0, ".3f"),
                ]
            )
        for other, d in v["identified_vs"].items():
            paired.append(
                [
                    f"{group} ({v['n']})",
                    f"identified law - {other}",
                    _pm(d["d_under_1nmi_final"], d["d_under_1nmi_final_std"], 100, "+.0f"),
                    _pm(d["d_under_1nmi_72h"], d["d_under_1nmi_72h_std"], 100, "+.0f"),
                    _pm(d["d_rms_final_nmi"], d["d_rms_final_nmi_std"], 1.0, "+.3f"),
                ]
            )
        gap = v["gap_closed"]
        paired.append(
            [
                f"{group} ({v['n']})",
                "gap closed (today - law) / (today - best law)",
                _f(gap["under_1nmi_final"]),
                _f(gap["under_1nmi_72h"]),
                _f(gap["rms_final_nmi"]),
            ]
        )
    head = ["runs (n)", "method", "<1 nmi @72 h", "<1 nmi over 72 h", "RMS 72 h final error [nmi]"]
    return [
        "<h2>Drift laws on the held-out runs</h2>",
        f"<p>{html.escape(doc['drift_laws']['how'])}.</p>",
        _table(head, rows),
        "<p>The identified law against the constant today and the offline best constant (differences in percentage "
        "points and nmi, paired bootstrap 1-sigma), and the share of the gap to the offline best law it closes.</p>",
        _table(["runs (n)", "comparison", "<1 nmi @72 h", "<1 nmi over 72 h", "RMS 72 h final [nmi]"], paired),
        _figure("laws.png", images),
    ]


def render_html(doc: dict, images: dict[str, bytes]) -> str:
    """The self-contained report (figures inlined as base64 PNG)."""
    methods = doc["methods"]
    rows = []
    for n in sorted(methods, key=lambda n: methods[n]["metrics"]["rms_eff"] or math.inf):
        m = methods[n]["metrics"]
        rows.append(
            [
                n,
                _f(m["rms_eff"]),
                _f(m["max_eff"]),
                _f(m["rms_truth"]),
                _f(m["max_truth"]),
                _pct(m["under_1nmi_final"]),
                _pct(m["under_1nmi_72h"]),
                _pct(m.get("coverage_eff")),
                _f(m["ratio_to_limit"]),
            ]
        )
    head = [
        "method",
        "RMS eff",
        "max eff",
        "RMS truth",
        "max truth",
        "<1 nmi @72 h",
        "<1 nmi over 72 h",
        "90 % cov.",
        "RMS / limit",
    ]
    parts = [
        "<!DOCTYPE html><html><head><meta charset='utf-8'><title>gyrodrift accuracy study</title>",
        "<style>body{font-family:sans-serif;max-width:60em;margin:2em auto}table{border-collapse:collapse}"
        "td,th{border:1px solid #bbb;padding:2px 6px;text-align:right}td:first-child{text-align:left}</style>",
        "</head><body><h1>Accuracy study</h1><h2>Summary</h2>",
        *(f"<p>{html.escape(line)}</p>" for line in summary_lines(doc)),
        *_law_tables(doc, images),
        "<h2>Methods on the held-out runs</h2>",
        "<p>Errors in deg/h: against the simulated effective drift (truth of the noise-free twin) and against the "
        "72 h truth of the noisy run. Runs under 1 nmi after compensating the estimate, from the stored linear "
        "error curves. Coverage of nominal 90 % intervals against the effective drift.</p>",
        _table(head, rows),
    ]
    parts += [_figure(name, images) for name in FIGURES if name != "laws.png"]
    if doc["notes"]:
        parts.append("<h2>Notes</h2>" + "".join(f"<p>{html.escape(n)}</p>" for n in doc["notes"]))
    parts.append("</body></html>\n")
    return "".join(parts)


def write_study_report(doc: dict, stage: Stage) -> None:
    """Write ``STUDY_FILES`` into `stage` (published together by the caller's `OutputFolder`)."""
    images = make_figures(doc)
    write_json(doc, stage.file("study.json"))
    for name in FIGURES:
        stage.file(name).write_bytes(images[name])
    with open(stage.file("report.html"), "w", encoding="utf-8") as fh:
        fh.write(render_html(doc, images))
