"""Files of `gyrodrift plan`: the figure (drift 1-sigma and predicted mission error against the span) and the JSON."""

from __future__ import annotations

import os
import textwrap
from pathlib import Path

from gyrodrift.files.atomic import OutputFolder, Stage, staged, write_json
from gyrodrift.procedure.plan import Plan

__all__ = ["plot_plan", "plan_files", "PLAN_FILES"]

PLAN_FILES = ("plan.json", "plan.png")
"""The files of `gyrodrift plan`, published together."""


def plot_plan(plan: Plan, path: str | os.PathLike[str]) -> None:
    """Two panels against the span [h]: the drift 1-sigma [deg/h] with the largest the budget allows, and the
    predicted quantile of the mission error [nmi] with the budget and the error floor (the exact drift); the answer
    as the title."""
    from matplotlib.figure import Figure  # object API: no pyplot global state

    b = plan.budget
    fig = Figure(figsize=(7.5, 7.5))
    top, bottom = fig.add_subplot(2, 1, 1), fig.add_subplot(2, 1, 2, sharex=None)
    thermal = plan.coeff_std_deg_h_per_c * abs(plan.temp_change_c) > 0
    label = "drift 1-sigma (with the thermal term)" if thermal else "drift 1-sigma"
    top.semilogy(plan.spans_h, plan.drift_std_deg_h, color="C0", lw=1.5, label=label)
    if thermal:
        top.semilogy(plan.spans_h, plan.drift_std_id_deg_h, color="C0", lw=0.8, ls=":", label="smoother alone")
    if plan.max_drift_std_deg_h is not None:
        top.axhline(plan.max_drift_std_deg_h, color="C3", lw=1, ls="--", label="largest the budget allows")
    top.set_ylabel("drift 1-sigma [deg/h]")
    top.set_xlabel("observation span from the first sample [h] (alignment + static navigation)")
    bottom.plot(plan.spans_h, plan.quantile_nmi, color="C1", lw=1.5, label=f"predicted {100 * b.share:g} % quantile")
    bottom.axhline(b.error_nmi, color="C3", lw=1, ls="--", label=f"budget {b.error_nmi:g} nmi")
    bottom.axhline(plan.floor_quantile_nmi, color="0.4", lw=1, ls=":", label="error floor (exact drift)")
    bottom.set_ylabel(f"{b.hours:g} h position error [nmi]")
    bottom.set_xlabel("observation span from the first sample [h]")
    for ax in (top, bottom):
        if plan.shortest_span_h is not None:
            ax.axvline(plan.shortest_span_h, color="C2", lw=1, label=f"shortest span {plan.shortest_span_h:g} h")
        ax.grid(True, which="both", lw=0.3)
        ax.legend(fontsize=7)
    n = plan.noise
    fig.suptitle(
        "\n".join(textwrap.wrap(plan.reason, 100))
        + f"\nARW {n.arw_deg_rth:g} deg/sqrt(h), VRW {n.vrw_ug_rthz:g} ug/sqrt(Hz), latitude {plan.lat_deg:g} deg, "
        f"rotation {plan.rotation}",
        fontsize=8,
    )
    fig.tight_layout()
    fig.savefig(path, format="png", dpi=110)


def plan_files(plan: Plan, out_dir: str | os.PathLike[str] | OutputFolder | Stage) -> list[Path]:
    """Write ``plan.json`` and ``plan.png`` into `out_dir`, published together (`gyrodrift.files.atomic.staged`);
    returns the paths written."""
    with staged(out_dir, "plan", PLAN_FILES) as stage:
        write_json(plan.to_dict(), stage.file("plan.json"))
        plot_plan(plan, stage.file("plan.png"))
    return [stage.folder / name for name in PLAN_FILES]
