"""Figures of the procedure: alignment z-bias sigma, true-drift criterion curve, position error before and
after compensation (the paper's Fig. 4/5). Each function takes a result and returns a matplotlib `Figure`
(object API, no pyplot state); `gyrodrift.procedure.writers` saves them with `save_png`."""

from __future__ import annotations

import os

from gyrodrift.procedure.results import Alignment, Evaluation, TrueDrift

__all__ = ["alignment_sigma_figure", "criterion_figure", "position_error_figure", "save_png"]


def _figure(nrows: int = 1):
    from matplotlib.figure import Figure  # object API: no pyplot global state

    fig = Figure(figsize=(7.5, 3.2 * nrows))
    axes = [fig.add_subplot(nrows, 1, i + 1) for i in range(nrows)]
    return fig, axes


def save_png(fig, path: str | os.PathLike[str]) -> None:
    """Save `fig` as PNG (110 dpi) to `path` as it is; callers publish it (`gyrodrift.atomic`)."""
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
    """Position error [nmi] and latitude/longitude errors [arcsec] vs navigation time [h], before/after."""
    fig, (ax1, ax2) = _figure(2)
    b, a = ev.before, ev.after
    ax1.plot(b.t_h, b.pos_err_nmi, color="C3", label=f"before (final {ev.before_final_nmi:.2f} nmi)")
    ax1.plot(
        a.t_h, a.pos_err_nmi, color="C0", label=f"after {ev.drift_deg_h:.5f} deg/h (final {ev.after_final_nmi:.2f} nmi)"
    )
    ax1.axhline(1.0, color="k", ls="--", lw=0.8)
    ax1.set_ylabel("position error [nmi]")
    ax1.set_title(f"{ev.run}: {ev.hours:g} h of navigation after alignment")
    ax1.legend()
    ax1.grid(True, alpha=0.3)
    ax2.plot(b.t_h, b.lat_err_arcsec, color="C3", ls="-", label="latitude, before")
    ax2.plot(b.t_h, b.lon_err_arcsec, color="C3", ls=":", label="longitude, before")
    ax2.plot(a.t_h, a.lat_err_arcsec, color="C0", ls="-", label="latitude, after")
    ax2.plot(a.t_h, a.lon_err_arcsec, color="C0", ls=":", label="longitude, after")
    ax2.set_xlabel("time since end of alignment [h]")
    ax2.set_ylabel("error [arcsec]")
    ax2.legend(ncol=2, fontsize="small")
    ax2.grid(True, alpha=0.3)
    return fig
