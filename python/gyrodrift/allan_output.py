"""Files of `gyrodrift allan`: the Allan deviation plot, the JSON summary and a scenario noise block."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from gyrodrift.allan import AllanResult, scenario_noise_block
from gyrodrift.atomic import OutputFolder, Stage, staged, write_json
from gyrodrift.ins.toml_writer import dumps_toml

__all__ = ["plot_allan", "allan_files", "ALLAN_FILES"]

ALLAN_FILES = ("allan.json", "allan.png", "noise.toml")
"""The files of `gyrodrift allan`, published together."""

_UG = 9.80665e-6
_RAD_S_TO_DEG_H = 3600.0 * 180.0 / np.pi


def plot_allan(result: AllanResult, path: str | os.PathLike[str]) -> None:
    """Log-log Allan deviation of the gyros [deg/h] and accelerometers [ug] with the fitted noise models
    and the -1/2 (random walk) and +1/2 (rate random walk) slopes through them."""
    from matplotlib.figure import Figure  # object API: no pyplot global state

    fig = Figure(figsize=(7.5, 8.0))
    panels = (
        (fig.add_subplot(2, 1, 1), "gyro", _RAD_S_TO_DEG_H, "deg/h"),
        (fig.add_subplot(2, 1, 2), "accel", 1 / _UG, "ug"),
    )
    for ax, kind, scale, unit in panels:
        for k, axis in enumerate(a for a in result.axes if a.axis.startswith(kind)):
            color = f"C{k}"
            ax.errorbar(
                axis.tau_s,
                axis.adev * scale,
                yerr=axis.adev_err * scale,
                fmt="o",
                ms=3,
                color=color,
                lw=0.8,
                label=f"{axis.axis} measured",
            )
            tau = np.geomspace(axis.tau_s[0], axis.tau_s[-1], 200)
            ax.plot(tau, axis.model_adev(tau) * scale, color=color, lw=1.2, label=f"{axis.axis} fit")
            if axis.white > 0:
                ax.plot(tau, axis.white / np.sqrt(tau) * scale, color=color, lw=0.6, ls=":")
            if axis.rrw > 0:
                ax.plot(tau, axis.rrw * np.sqrt(tau / 3.0) * scale, color=color, lw=0.6, ls="--")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("averaging time tau [s]")
        ax.set_ylabel(f"Allan deviation [{unit}]")
        ax.grid(True, which="both", lw=0.3)
        ax.legend(fontsize=7, ncol=3)
    noise = scenario_noise_block(result)
    g, a = noise["gyro"], noise["accel"]
    panels[0][0].set_title(
        f"{Path(result.log).name}: ARW {g['arw_deg_rth']:.3g} deg/sqrt(h), "
        f"Gauss-Markov {g['bias_instability_deg_h']:.3g} deg/h ({g['correlation_s']:.0f} s), "
        f"RRW {g['rrw_deg_h_rth']:.3g} deg/h/sqrt(h)\n"
        "dotted: -1/2 slope (random walk), dashed: +1/2 slope (rate random walk)",
        fontsize=8,
    )
    panels[1][0].set_title(f"VRW {a['vrw_ug_rthz']:.3g} ug/sqrt(Hz)", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, format="png", dpi=110)


def allan_files(result: AllanResult, out_dir: str | os.PathLike[str] | OutputFolder | Stage) -> list[Path]:
    """Write ``allan.json``, ``allan.png`` and ``noise.toml`` (the ``[gyro]``/``[accel]`` keys a scenario or
    campaign file accepts) into `out_dir`, published together (`gyrodrift.atomic.staged`, docs/outputs.md);
    returns the paths written."""
    header = (
        f"Noise of {Path(result.log).name} from its Allan deviation (gyrodrift allan).\n"
        "Paste into a scenario file; one value for all three axes (the mean; per-axis values in allan.json)."
    )
    text = dumps_toml(scenario_noise_block(result), header)
    with staged(out_dir, "allan", ALLAN_FILES) as stage:
        write_json(result.to_dict(), stage.file("allan.json"))
        plot_allan(result, stage.file("allan.png"))
        stage.file("noise.toml").write_text(text, encoding="utf-8")
    return [stage.folder / name for name in ALLAN_FILES]
