"""Allan deviation of a static IMU log and the noise parameters that scenario files take.

The overlapping Allan deviation (computed by `allantools.oadev`) of each gyro and accelerometer axis is
fitted, in Allan variance, by the sum of the noise terms the simulator draws
(see docs/scenarios.md, ``[gyro]`` and ``[accel]``):

* white rate noise (angle / velocity random walk) N:   AVAR = N^2 / tau
* a first-order Gauss-Markov bias, sigma s, correlation time T:
  AVAR = (2 s^2 T / tau) [1 - T / (2 tau) (3 - 4 exp(-tau / T) + exp(-2 tau / T))]
* rate random walk K:                                  AVAR = K^2 tau / 3

For each T on a log grid the variance is linear in (N^2, s^2, K^2): a non-negative least-squares fit
weighted by the relative uncertainty of each Allan point; the T with the smallest weighted residual wins.
The classical "bias instability" of the IEEE standards (the flat floor, min ADEV / 0.664) is reported beside
it. A term whose coefficient the data drive to zero is reported as 0.

Units: gyro rates in rad/s inside, reported in deg/h (ADEV), deg/sqrt(h) (ARW), deg/h (Gauss-Markov sigma),
deg/h/sqrt(h) (RRW); specific force in m/s^2 inside, reported in ug (ADEV), ug/sqrt(Hz) (VRW).

The log must be static with the turntable still (rotation off): a turning table puts the table rate in the
z gyro and modulates the Earth rate on x and y, which is not sensor noise. The constant Earth rate and
gravity are constants, invisible to the Allan deviation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gyrodrift.errors import InputError

__all__ = [
    "AxisNoise",
    "AllanResult",
    "allan_deviation",
    "fit_noise",
    "gauss_markov_avar",
    "scenario_noise_block",
    "MAX_TABLE_RATE_DEG_S",
]

_DEG = math.pi / 180.0
_UG = 9.80665e-6
_RAD_S_TO_DEG_H = 3600.0 / _DEG
_BIAS_INSTABILITY_FACTOR = math.sqrt(2.0 * math.log(2.0) / math.pi)  # 0.664: flicker floor of ADEV / B

MAX_TABLE_RATE_DEG_S = 0.01
"""Largest spread [deg/s] of the 1 s mean z rate accepted as a still turntable (Earth rate is 0.0042 deg/s)."""

_MAX_BASE_POINTS = 2_000_000


def gauss_markov_avar(tau_s: np.ndarray, sigma: float, correlation_s: float) -> np.ndarray:
    """Allan variance of a first-order Gauss-Markov process of stationary std `sigma` and correlation time
    `correlation_s` [s], at averaging times `tau_s` [s] (same unit squared as `sigma`)."""
    x = np.asarray(tau_s, dtype=float) / correlation_s
    bracket = 1.0 - (3.0 - 4.0 * np.exp(-x) + np.exp(-2.0 * x)) / (2.0 * x)
    small = x < 1e-3  # series 1 - ... = x^2/3 - x^3/12 avoids cancellation
    bracket = np.where(small, x * x / 3.0 - x**3 / 12.0, bracket)
    return 2.0 * sigma**2 * correlation_s / np.asarray(tau_s, dtype=float) * bracket


@dataclass(frozen=True)
class AxisNoise:
    """The Allan deviation of one axis and its fitted noise terms, all in SI (rad/s or m/s^2 based).

    Attributes
    ----------
    axis : str
        ``gyro_x`` ... ``accel_z``.
    tau_s, adev, adev_err : ndarray
        Averaging times [s], overlapping Allan deviation and its 1-sigma [rad/s or m/s^2].
    white : float
        N [rad/sqrt(s) or m/s/sqrt(s)]: ARW / VRW.
    gm_sigma, gm_correlation_s : float
        Gauss-Markov bias std [rad/s or m/s^2] and correlation time [s] (sigma 0 when not seen).
    rrw : float
        K [rad/s/sqrt(s) or m/s^2/sqrt(s)].
    bias_instability : float
        Classical flicker floor min(ADEV) / 0.664 [rad/s or m/s^2].
    fit_rms_log : float
        RMS of log(model ADEV / measured ADEV) over the fitted points (0.05 = 5 %).
    """

    axis: str
    tau_s: np.ndarray
    adev: np.ndarray
    adev_err: np.ndarray
    white: float
    gm_sigma: float
    gm_correlation_s: float
    rrw: float
    bias_instability: float
    fit_rms_log: float

    def model_adev(self, tau_s: np.ndarray) -> np.ndarray:
        """The fitted Allan deviation at `tau_s` [s]."""
        tau = np.asarray(tau_s, dtype=float)
        avar = self.white**2 / tau + self.rrw**2 * tau / 3.0
        if self.gm_sigma > 0.0:
            avar = avar + gauss_markov_avar(tau, self.gm_sigma, self.gm_correlation_s)
        return np.sqrt(avar)


@dataclass(frozen=True)
class AllanResult:
    """Allan deviations and noise fits of the six axes of one static log.

    Attributes
    ----------
    log : str
        The log's file name.
    rate_hz, duration_s, base_tau_s : float
        Sample rate [Hz], length [s], and the shortest averaging time used [s] (a multiple of the sample
        interval when a long log is thinned to at most 2 million phase points).
    axes : list of AxisNoise
        gyro x, y, z then accel x, y, z.
    """

    log: str
    rate_hz: float
    duration_s: float
    base_tau_s: float
    axes: list[AxisNoise] = field(default_factory=list)

    def axis(self, name: str) -> AxisNoise:
        """The `AxisNoise` called `name` (``gyro_x`` ... ``accel_z``)."""
        for a in self.axes:
            if a.axis == name:
                return a
        raise KeyError(name)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary in user units (deg/h, deg/sqrt(h), ug, ug/sqrt(Hz))."""
        axes = {}
        for a in self.axes:
            gyro = a.axis.startswith("gyro")
            if gyro:
                k = _RAD_S_TO_DEG_H
                entry = {
                    "adev_deg_h": (a.adev * k).tolist(),
                    "adev_err_deg_h": (a.adev_err * k).tolist(),
                    "arw_deg_rth": a.white / _DEG * 60.0,
                    "bias_instability_deg_h": a.bias_instability * k,
                    "gauss_markov_sigma_deg_h": a.gm_sigma * k,
                    "rrw_deg_h_rth": a.rrw * k * 60.0,
                }
            else:
                entry = {
                    "adev_ug": (a.adev / _UG).tolist(),
                    "adev_err_ug": (a.adev_err / _UG).tolist(),
                    "vrw_ug_rthz": a.white / _UG,
                    "bias_instability_ug": a.bias_instability / _UG,
                    "gauss_markov_sigma_ug": a.gm_sigma / _UG,
                    "rrw_ug_per_s_rts": a.rrw / _UG,
                }
            entry["tau_s"] = a.tau_s.tolist()
            entry["gauss_markov_correlation_s"] = a.gm_correlation_s
            entry["fit_rms_log"] = a.fit_rms_log
            axes[a.axis] = entry
        return {
            "format": "gyrodrift-allan/1",
            "log": self.log,
            "rate_hz": self.rate_hz,
            "duration_s": self.duration_s,
            "base_tau_s": self.base_tau_s,
            "axes": axes,
            "scenario_noise": scenario_noise_block(self),
        }


def scenario_noise_block(result: AllanResult) -> dict[str, dict[str, float]]:
    """The ``[gyro]`` / ``[accel]`` noise keys of a scenario file matching the log (mean over the axes).

    The simulator draws one noise level for all three axes; the per-axis values are in `AllanResult`.
    Accelerometer bias drift (Gauss-Markov, RRW) has no scenario key and is left out.
    """
    gyros = [a for a in result.axes if a.axis.startswith("gyro")]
    accels = [a for a in result.axes if a.axis.startswith("accel")]
    k = _RAD_S_TO_DEG_H
    gm = [a for a in gyros if a.gm_sigma > 0.0]
    block = {
        "gyro": {
            "arw_deg_rth": float(np.mean([a.white for a in gyros]) / _DEG * 60.0),
            "bias_instability_deg_h": float(np.mean([a.gm_sigma for a in gyros]) * k),
            "correlation_s": float(np.exp(np.mean([np.log(a.gm_correlation_s) for a in gm]))) if gm else 3600.0,
            "rrw_deg_h_rth": float(np.mean([a.rrw for a in gyros]) * k * 60.0),
        },
        "accel": {"vrw_ug_rthz": float(np.mean([a.white for a in accels]) / _UG)},
    }
    return block


def fit_noise(tau_s: np.ndarray, adev: np.ndarray, adev_err: np.ndarray, *, axis: str = "axis") -> AxisNoise:
    """Fit white noise, a Gauss-Markov bias and rate random walk to one Allan deviation curve.

    Parameters
    ----------
    tau_s, adev, adev_err : ndarray
        Averaging times [s], Allan deviation and its 1-sigma (any consistent unit).
    axis : str
        Name carried into the result.
    """
    tau = np.asarray(tau_s, dtype=float)
    dev = np.asarray(adev, dtype=float)
    err = np.asarray(adev_err, dtype=float)
    ok = np.isfinite(dev) & (dev > 0.0) & np.isfinite(tau) & (tau > 0.0)
    if ok.sum() < 3:
        raise InputError(f"{axis}: fewer than 3 usable Allan deviation points; the log is too short or constant")
    tau, dev, err = tau[ok], dev[ok], err[ok]
    avar = dev**2
    rel = np.clip(np.nan_to_num(2.0 * err / dev, nan=1.0), 0.01, None)  # relative 1-sigma of the variance
    w = 1.0 / (avar * rel)
    from scipy.optimize import minimize_scalar, nnls

    def solve(corr: float) -> tuple[float, float, float, float]:
        """Weighted NNLS for one correlation time (inf: no Gauss-Markov term) -> (residual, N^2, s^2, K^2)."""
        cols = [1.0 / tau, tau / 3.0]
        if math.isfinite(corr):
            cols.append(gauss_markov_avar(tau, 1.0, corr))
        design = np.column_stack(cols)
        coef, _ = nnls(design * w[:, None], avar * w)
        model = design @ coef
        resid = float(np.sqrt(np.mean(np.log(np.maximum(model, 1e-300) / avar) ** 2)) / 2.0)
        return resid, float(coef[0]), float(coef[2]) if len(coef) > 2 else 0.0, float(coef[1])

    grid = np.geomspace(tau[0], tau[-1] * 3.0, 48)
    fits = [solve(c) for c in grid]
    k = int(np.argmin([f[0] for f in fits]))
    best_corr, best = float(grid[k]), fits[k]
    # refine the correlation time between the neighbouring grid points (residual smooth in log T)
    lo, hi = np.log(grid[max(k - 1, 0)]), np.log(grid[min(k + 1, len(grid) - 1)])
    if hi > lo:
        opt = minimize_scalar(
            lambda x: solve(math.exp(x))[0], bounds=(lo, hi), method="bounded", options={"xatol": 1e-4}
        )
        if opt.fun < best[0]:
            best_corr, best = math.exp(opt.x), solve(math.exp(opt.x))
    plain = solve(math.inf)
    if plain[0] <= best[0] + 1e-12:  # no Gauss-Markov term needed
        best_corr, best = math.inf, plain
    resid, white2, gm2, rrw2 = best
    corr = best_corr
    return AxisNoise(
        axis=axis,
        tau_s=np.asarray(tau_s, dtype=float),
        adev=np.asarray(adev, dtype=float),
        adev_err=np.asarray(adev_err, dtype=float),
        white=math.sqrt(white2),
        gm_sigma=math.sqrt(gm2) if gm2 > 0.0 and math.isfinite(corr) else 0.0,
        gm_correlation_s=corr if gm2 > 0.0 and math.isfinite(corr) else 3600.0,
        rrw=math.sqrt(rrw2),
        bias_instability=float(np.min(dev)) / _BIAS_INSTABILITY_FACTOR,
        fit_rms_log=resid,
    )


def allan_deviation(log: Any, *, chunk_samples: int = 200_000, quiet: bool = True) -> AllanResult:
    """Allan deviations and noise fits of every axis of a static log with the turntable still.

    Parameters
    ----------
    log : ImuLog
        An opened log (`gyrodrift.logs.open_log`); it is streamed once (memory: the cumulative angle and
        velocity at most 2 million points per axis, whatever the log length).
    chunk_samples : int
        Samples per streamed chunk.
    quiet : bool
        True hides the progress bar.

    Raises
    ------
    InputError
        The log is shorter than 100 samples, or its turntable turns (z rate varying by more than
        `MAX_TABLE_RATE_DEG_S` between 1 s means).
    """
    import allantools

    from gyrodrift.progress import progress

    n = int(log.n_samples)
    if n < 100:
        raise InputError(f"{log.path}: {n} samples; an Allan deviation needs at least 100 (minutes of a static log)")
    stride = max(1, math.ceil(n / _MAX_BASE_POINTS))
    per_second = max(1, int(round(log.rate_hz)))
    n_points = n // stride
    phase = np.empty((n_points + 1, 6))
    phase[0] = 0.0
    total = np.zeros(6)
    filled = 1
    carry = 0  # samples of the current stride already summed
    z_means: list[float] = []
    z_acc, z_cnt = 0.0, 0
    with progress(n, "allan", quiet, unit="sample") as bar:
        for chunk in log.chunks(chunk_samples):
            inc = np.hstack([chunk.dtheta_rad, chunk.dv_m_s])
            # still-table check on 1 s means of the z rate
            dz = chunk.dtheta_rad[:, 2]
            i = 0
            while i < len(dz):
                take = min(per_second - z_cnt, len(dz) - i)
                z_acc += float(dz[i : i + take].sum())
                z_cnt += take
                i += take
                if z_cnt == per_second:
                    z_means.append(z_acc * log.rate_hz / per_second)
                    z_acc, z_cnt = 0.0, 0
            cum = total + np.cumsum(inc, axis=0)
            # phase points at the end of every `stride` samples
            first = (stride - carry) - 1
            idx = np.arange(first, len(inc), stride)
            idx = idx[: max(0, min(len(idx), n_points + 1 - filled))]
            phase[filled : filled + len(idx)] = cum[idx]
            filled += len(idx)
            carry = (carry + len(inc)) % stride
            total = cum[-1]
            bar.update(len(inc))
    phase = phase[:filled]
    if z_means:
        spread = (max(z_means) - min(z_means)) / _DEG
        if spread > MAX_TABLE_RATE_DEG_S:
            raise InputError(
                f"{log.path}: the z rate varies by {spread:.3g} deg/s between 1 s means: the turntable turns. "
                f"An Allan deviation needs a static log with the rotation off (at most {MAX_TABLE_RATE_DEG_S} deg/s)"
            )
    base_tau = stride / log.rate_hz
    names = ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
    axes = []
    for k, name in enumerate(names):
        taus, adev, _, _ = allantools.oadev(phase[:, k], rate=1.0 / base_tau, data_type="phase", taus="octave")
        taus, adev = np.asarray(taus, dtype=float), np.asarray(adev, dtype=float)
        # 1-sigma of each point from its number of independent averages (allantools' own error bar is
        # 1/sqrt(number of overlapping terms), far too small at long tau, where few averages exist)
        independent = np.maximum(len(phase) / np.round(taus / base_tau) - 1.0, 1.0)
        axes.append(fit_noise(taus, adev, adev / np.sqrt(independent), axis=name))
    return AllanResult(
        log=str(log.path), rate_hz=float(log.rate_hz), duration_s=n / log.rate_hz, base_tau_s=base_tau, axes=axes
    )
