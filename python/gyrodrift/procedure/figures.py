"""Figures of the procedure: alignment z-bias sigma, true-drift criterion curve, position error before and
after compensation (the paper's Fig. 4/5), and the errors of one navigation (`navigate --plot`). Each function
takes a result and returns a matplotlib `Figure` (object API, no pyplot state); `gyrodrift.procedure.writers`
saves them with `save_png`. Colours: uncompensated ("before") is always `BEFORE_COLOUR`, compensated ("after")
`AFTER_COLOUR`; the 1 nmi line is labelled in every position-error plot."""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

import numpy as np

from gyrodrift.drift_law import DriftLaw
from gyrodrift.earth import radii_of_curvature
from gyrodrift.ins.compensation import compensation_words
from gyrodrift.procedure.results import Alignment, Evaluation, TrueDrift

__all__ = [
    "alignment_sigma_figure",
    "criterion_figure",
    "position_error_figure",
    "navigation_figure",
    "one_nmi_line",
    "save_png",
    "BEFORE_COLOUR",
    "AFTER_COLOUR",
]

BEFORE_COLOUR = "C3"
"""Colour of an uncompensated navigation in every figure."""
AFTER_COLOUR = "C0"
"""Colour of a compensated navigation in every figure."""


def one_nmi_line(ax) -> None:
    """The 1 nmi reference line, labelled on the plot itself (just under the line, at the right)."""
    ax.axhline(1.0, color="k", ls="--", lw=0.8)
    ax.annotate(
        "1 nmi",
        xy=(0.995, 1.0),
        xycoords=("axes fraction", "data"),
        xytext=(0, -3),
        textcoords="offset points",
        fontsize="small",
        ha="right",
        va="top",
    )


def _figure(nrows: int = 1):
    from matplotlib.figure import Figure  # object API: no pyplot global state

    fig = Figure(figsize=(7.5, 3.2 * nrows))
    axes = [fig.add_subplot(nrows, 1, i + 1) for i in range(nrows)]
    return fig, axes


def save_png(fig, path: str | os.PathLike[str]) -> None:
    """Save `fig` as PNG (110 dpi) to `path` as it is; callers publish it (`gyrodrift.files.atomic`)."""
    fig.tight_layout()
    fig.savefig(path, format="png", dpi=110)


def alignment_sigma_figure(alignment: Alignment):
    """1-sigma of the axial (z) gyro bias over the alignment [deg/h] vs log time [h], log scale."""
    fig, (ax,) = _figure()
    ax.semilogy(alignment.hist_t_h, alignment.hist_gyro_z_std_deg_h, color="C0", label="z gyro bias 1-sigma")
    ax.axhline(0.0005, color="C3", ls="--", lw=1, label="0.0005 deg/h (1 nmi / 72 h)")
    ax.set_xlabel("time since start of log [h]")
    ax.set_ylabel("sigma [deg/h]")
    ax.set_title(
        f"{alignment.run}: axial gyro bias uncertainty during alignment (end: {alignment.z_drift_std_deg_h:.2g} deg/h)"
    )
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    return fig


def criterion_figure(truth: TrueDrift):
    """The criterion [nmi] vs the z drift [deg/h]: linear-model curve and the navigated verification points."""
    fig, (ax,) = _figure()
    ax.plot(truth.grid_drift_deg_h, truth.grid_nmi, color="C0", label="linear model")
    ax.plot(truth.verify_drift_deg_h, truth.verify_nmi, "o", color="C3", label="navigated (verification)")
    ax.axvline(truth.drift_deg_h, color="k", lw=0.8, ls=":")
    ax.set_xlabel("z-gyro drift subtracted [deg/h]")
    ax.set_ylabel(f"{truth.criterion} position error over {truth.hours:g} h [nmi]")
    ax.set_title(f"{truth.run}: true drift {truth.drift_deg_h:.6f} deg/h")
    ax.grid(True, alpha=0.3)
    ax.legend()
    return fig


def position_error_figure(ev: Evaluation):
    """Position error [nmi] and latitude/longitude errors [arcsec] vs navigation time [h], before/after.

    The legends give the final and the maximum error over the navigation, and where the compensated drift
    came from (`Evaluation.source`: a model file, ``given``, ...).
    """
    fig, (ax1, ax2) = _figure(2)
    b, a = ev.before, ev.after
    ax1.plot(
        b.t_h,
        b.pos_err_nmi,
        color=BEFORE_COLOUR,
        label=f"before: no axial drift compensated (final {b.final_nmi:.2f} nmi, max {b.max_nmi:.2f} nmi)",
    )
    ax1.plot(
        a.t_h,
        a.pos_err_nmi,
        color=AFTER_COLOUR,
        label=f"after: {_compensated(ev.drift_deg_h, ev.drift_law)} from {_short_source(ev.source)} "
        f"(final {a.final_nmi:.2f} nmi, max {a.max_nmi:.2f} nmi)",
    )
    one_nmi_line(ax1)
    ax1.set_ylabel("position error [nmi]")
    ax1.set_title(f"{ev.run}: {ev.hours:g} h of navigation after alignment")
    ax1.legend(fontsize="small")
    ax1.grid(True, alpha=0.3)
    ax2.plot(b.t_h, b.lat_err_arcsec, color=BEFORE_COLOUR, ls="-", label="latitude, before")
    ax2.plot(b.t_h, b.lon_err_arcsec, color=BEFORE_COLOUR, ls=":", label="longitude, before")
    ax2.plot(a.t_h, a.lat_err_arcsec, color=AFTER_COLOUR, ls="-", label="latitude, after")
    ax2.plot(a.t_h, a.lon_err_arcsec, color=AFTER_COLOUR, ls=":", label="longitude, after")
    ax2.set_xlabel("time since end of alignment [h]")
    ax2.set_ylabel("error [arcsec]")
    ax2.legend(ncol=2, fontsize="small")
    ax2.grid(True, alpha=0.3)
    return fig


def route_map_figure(ev: Evaluation):
    """Moving base: the reference route and the navigated tracks before/after compensation, east/north [km] from
    the position at the end of the alignment (the paper's route map). Navigated = reference + error."""
    ref = ev.reference
    if ref is None:
        raise ValueError("route_map_figure needs an evaluation against a reference track")
    fig, (ax,) = _figure(1)
    t = np.concatenate([[0.0], ev.before.t_h])
    lat, lon, _ = ref.at(ev.start_s + t * 3600.0)
    lat0, lon0 = lat[0], lon[0]
    r_m, r_n = radii_of_curvature(np.array([lat0]))
    north = (lat - lat0) * r_m[0] / 1000.0
    east = (lon - lon0) * r_n[0] * np.cos(lat0) / 1000.0
    # the reference on top, dashed: the navigated tracks run within a few nmi of it and would hide it
    source = "the scenario's true route" if ref.label == "<route>" else os.path.basename(ref.label) or ref.label
    ax.plot(east, north, color="black", lw=1.2, ls=(0, (4, 3)), zorder=3, label=f"reference ({source})")
    for curve, colour, name in ((ev.before, BEFORE_COLOUR, "before"), (ev.after, AFTER_COLOUR, "after")):
        ax.plot(
            east[1:] + curve.east_m / 1000.0,
            north[1:] + curve.north_m / 1000.0,
            color=colour,
            lw=2.0 if name == "before" else 1.4,
            label=f"navigated, {name} (max error {curve.max_nmi:.2f} nmi)",
        )
    ax.plot([0.0], [0.0], "ko")
    ax.set_xlabel("east [km]")
    ax.set_ylabel("north [km]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title(f"{ev.run}: route, {ev.hours:g} h after alignment")
    ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0))  # beside the map: hides no track
    ax.grid(True, alpha=0.3)
    return fig


def _compensated(drift_deg_h: float, law: DriftLaw | Mapping[str, Any] | None) -> str:
    """The compensated drift in a legend or a title: "0.00400 deg/h" (a constant), or a law reading the temperature
    in words (`gyrodrift.ins.compensation.compensation_words`; `law` a `DriftLaw` or its `to_dict`)."""
    if isinstance(law, Mapping):
        law = DriftLaw.from_dict(law)
    if law is None or law.is_constant:
        return f"{drift_deg_h:.5f} deg/h"
    return compensation_words(law)


def _short_source(source: str) -> str:
    """A drift source short enough for a legend (a model path becomes its file name)."""
    if source in ("given", ""):
        return "--drift-deg-h" if source == "given" else "?"
    return os.path.basename(source) or source


def navigation_figure(columns: Mapping[str, np.ndarray], summary: Mapping[str, Any]):
    """The errors of one navigation (`gyrodrift.procedure.navigate`, ``navigate --plot``) vs time [h] since its start:
    position error [nmi] with the 1 nmi line, latitude/longitude errors [arcsec], and pitch/roll/yaw errors
    [arcsec] when the log carries the true attitude (computed minus true). Without a known site the panels say
    so instead of plotting."""
    t_h = np.asarray(columns["t_s"], dtype=float) / 3600.0
    fig, (ax1, ax2, ax3) = _figure(3)
    fig.set_size_inches(7.5, 8.4)
    drift, law = summary.get("compensate_drift_deg_h", 0.0), summary.get("drift_law")
    what = "no axial drift compensated" if not drift and law is None else f"{_compensated(drift, law)} compensated"
    title = f"{summary.get('imu', '')}: {summary.get('hours_navigated', t_h[-1] if len(t_h) else 0):.3g} h, {what}"
    ax1.set_title(title, fontsize="medium")
    if "pos_err_nmi" in columns:
        final, peak = summary.get("final_pos_err_nmi"), summary.get("max_pos_err_nmi")
        ax1.plot(
            t_h,
            columns["pos_err_nmi"],
            color=AFTER_COLOUR if drift else BEFORE_COLOUR,
            label=f"position error (final {final:.3f} nmi, max {peak:.3f} nmi)",
        )
        one_nmi_line(ax1)
        ax1.legend(fontsize="small")
        ax2.plot(t_h, columns["lat_err_arcsec"], color="C2", label="latitude")
        ax2.plot(t_h, columns["lon_err_arcsec"], color="C1", label="longitude")
        ax2.legend(fontsize="small")
    else:
        for ax in (ax1, ax2):
            ax.text(
                0.5, 0.5, "no site known: no position errors (give --lat0-deg)", ha="center", transform=ax.transAxes
            )
    ax1.set_ylabel("position error [nmi]")
    ax2.set_ylabel("lat / lon error [arcsec]")
    if "yaw_err_arcsec" in columns:
        for name, colour in (("pitch", "C4"), ("roll", "C5"), ("yaw", "C6")):
            ax3.plot(t_h, columns[f"{name}_err_arcsec"], color=colour, label=name)
        ax3.legend(fontsize="small", ncol=3)
    else:
        ax3.text(0.5, 0.5, "no true attitude in the log: no attitude errors", ha="center", transform=ax3.transAxes)
    ax3.set_ylabel("attitude error [arcsec]")
    ax3.set_xlabel("time since start of navigation [h]")
    for ax in (ax1, ax2, ax3):
        ax.grid(True, alpha=0.3)
    return fig
