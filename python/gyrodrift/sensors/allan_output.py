"""Files of `gyrodrift allan`: the Allan deviation plot, the JSON summary and a scenario noise block."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from gyrodrift.files.atomic import OutputFolder, Stage, staged, write_json
from gyrodrift.files.toml_writer import dumps_toml
from gyrodrift.sensors.allan import CONFIDENCE, AllanResult, scenario_noise_axes, scenario_noise_block

__all__ = ["plot_allan", "allan_files", "noise_summary", "noise_toml", "ALLAN_FILES"]

ALLAN_FILES = ("allan.json", "allan.png", "noise.toml")
"""The files of `gyrodrift allan`, published together."""

_UG = 9.80665e-6
_RAD_S_TO_DEG_H = 3600.0 * 180.0 / np.pi


def noise_summary(result: AllanResult) -> str:
    """One line of the noise block and the axes it used (``not resolved`` for a term no axis shows)."""
    noise, used = scenario_noise_block(result), scenario_noise_axes(result)
    g, a, ug, ua = noise["gyro"], noise["accel"], used["gyro"], used["accel"]

    def term(value: float, unit: str, axes: list[str]) -> str:
        return f"{value:.4g} {unit} ({', '.join(axes)})" if axes else "not resolved"

    gm_unit = f"deg/h over {g['correlation_s']:.0f} s" if ug["bias_instability_deg_h"] else "deg/h"
    gyro = (
        f"gyro ARW {term(g['arw_deg_rth'], 'deg/sqrt(h)', ug['arw_deg_rth'])}, "
        f"Gauss-Markov {term(g['bias_instability_deg_h'], gm_unit, ug['bias_instability_deg_h'])}, "
        f"RRW {term(g['rrw_deg_h_rth'], 'deg/h/sqrt(h)', ug['rrw_deg_h_rth'])}"
    )
    accel = f"accel VRW {term(a['vrw_ug_rthz'], 'ug/sqrt(Hz)', ua['vrw_ug_rthz'])}"
    varying = {kind: any(x.axis.startswith(kind) for x in result.axes) for kind in ("gyro", "accel")}
    return (
        f"{gyro if varying['gyro'] else 'gyro: every channel constant'}; "
        f"{accel if varying['accel'] else 'accel: every channel constant'}"
    )


def plot_allan(result: AllanResult, path: str | os.PathLike[str]) -> None:
    """Log-log Allan deviation of the gyros [deg/h] and accelerometers [ug] with their 1-sigma confidence
    intervals, the fitted model of the terms the log shows and the -1/2 (random walk) and +1/2 (rate random
    walk) slopes through them."""
    from matplotlib.figure import Figure  # object API: no pyplot global state

    fig = Figure(figsize=(7.5, 8.0))
    panels = (
        (fig.add_subplot(2, 1, 1), "gyro", _RAD_S_TO_DEG_H, "deg/h"),
        (fig.add_subplot(2, 1, 2), "accel", 1 / _UG, "ug"),
    )
    for ax, kind, scale, unit in panels:
        shown = [a for a in result.axes if a.axis.startswith(kind)]
        for k, axis in enumerate(shown):
            color = f"C{k}"
            ax.errorbar(
                axis.tau_s,
                axis.adev * scale,
                yerr=np.vstack([axis.adev - axis.adev_lo, axis.adev_hi - axis.adev]) * scale,
                fmt="o",
                ms=3,
                color=color,
                lw=0.8,
                label=f"{axis.axis} measured",
            )
            tau = np.geomspace(axis.tau_s[0], axis.tau_s[-1], 200)
            ax.plot(tau, axis.model_adev(tau) * scale, color=color, lw=1.2, label=f"{axis.axis} fit")
            if axis.white is not None:
                ax.plot(tau, axis.white / np.sqrt(tau) * scale, color=color, lw=0.6, ls=":")
            if axis.rrw is not None:
                ax.plot(tau, axis.rrw * np.sqrt(tau / 3.0) * scale, color=color, lw=0.6, ls="--")
        dead = [name for name in result.constant_axes if name.startswith(kind)]
        if dead:
            ax.text(0.02, 0.02, f"constant, left out: {', '.join(dead)}", transform=ax.transAxes, fontsize=7)
        if shown:
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.legend(fontsize=7, ncol=3)
        ax.set_xlabel("averaging time tau [s]")
        ax.set_ylabel(f"Allan deviation [{unit}]")
        ax.grid(True, which="both", lw=0.3)
    summary = noise_summary(result).split("; ")
    panels[0][0].set_title(
        f"{Path(result.log).name}: {summary[0]}\n"
        "bars: 1-sigma (Greenhall edf); dotted: -1/2 slope (random walk), dashed: +1/2 slope (rate random walk)",
        fontsize=7,
    )
    panels[1][0].set_title(summary[1], fontsize=8)
    fig.tight_layout()
    fig.savefig(path, format="png", dpi=110)


def noise_toml(result: AllanResult) -> str:
    """``noise.toml``: the ``[gyro]``/``[accel]`` keys a scenario or campaign file accepts, with a header saying
    which axes each value averages and which terms the log does not show (written 0, the simulator's "none")."""
    used = scenario_noise_axes(result)
    lines = [
        f"Noise of {Path(result.log).name} from its Allan deviation (gyrodrift allan).",
        "Paste into a scenario file; one value for all three axes (the mean over the axes that show the term;",
        "per-axis values in allan.json).",
    ]
    if result.constant_axes:
        lines.append(f"Constant (every sample equal), left out: {', '.join(result.constant_axes)}.")
    for sensor in ("gyro", "accel"):
        for key, axes in used[sensor].items():
            if key == "correlation_s":
                continue
            if axes:
                lines.append(f"[{sensor}] {key}: mean of {', '.join(axes)}.")
            elif not any(a.axis.startswith(sensor) for a in result.axes):
                lines.append(f"[{sensor}] {key} = 0: every {sensor} channel is constant, nothing measured.")
            else:
                lines.append(
                    f"[{sensor}] {key} = 0: not resolved on any axis (not above the {CONFIDENCE:.0%} confidence "
                    "interval of the Allan deviation at the averaging times the log reaches), not measured as 0."
                )
    return dumps_toml(scenario_noise_block(result), "\n".join(lines))


def allan_files(result: AllanResult, out_dir: str | os.PathLike[str] | OutputFolder | Stage) -> list[Path]:
    """Write ``allan.json``, ``allan.png`` and ``noise.toml`` (`noise_toml`) into `out_dir`, published together
    (`gyrodrift.files.atomic.staged`, docs/outputs.md); returns the paths written."""
    text = noise_toml(result)
    with staged(out_dir, "allan", ALLAN_FILES) as stage:
        write_json(result.to_dict(), stage.file("allan.json"))
        plot_allan(result, stage.file("allan.png"))
        stage.file("noise.toml").write_text(text, encoding="utf-8")
    return [stage.folder / name for name in ALLAN_FILES]
