"""The sensor noise model the estimators assume: white noise densities, and optional gyro bias drift.

`SensorNoise` holds the noise in the units of the scenario files' ``[gyro]`` and ``[accel]`` keys
(docs/scenarios.md; `gyrodrift allan` writes them as ``scenario_noise``): angle random walk ``arw_deg_rth``
[deg/sqrt(h)], velocity random walk ``vrw_ug_rthz`` [ug/sqrt(Hz)], a first-order Gauss-Markov gyro bias
``bias_instability_deg_h`` [deg/h] with ``correlation_s`` [s], and rate random walk ``rrw_deg_h_rth``
[deg/h/sqrt(h)].

`estimate_white_noise` measures ARW and VRW from a log itself: on a static base the increments are a smooth
signal (Earth rate, gravity, the table turning) plus white noise, so the fourth differences of consecutive
increments, d_k = x_{k+2} - 4 x_{k+1} + 6 x_k - 4 x_{k-1} + x_{k-2}, remove the signal and keep the noise with
variance C(8, 4) s^2 = 70 s^2 (s^2 the per-sample noise variance; a density N gives s = N sqrt(dt)). The spread is
taken robustly (1.4826 times the median absolute value), so the few samples where the table starts, stops or
reverses do not count, and averaged over the three axes.

The order matters at low rates: the table modulates the horizontal Earth rate and a tilt's share of gravity at its
turning rate w, which a difference of order k keeps with the factor (2 sin(w dt / 2))^k against the noise's
sqrt(C(2k, k)). With 1 deg of tilt on a 6 deg/s table, second differences read a 5 ug/sqrt(Hz) VRW as 2.1 times
itself at 2 Hz and 11 times at 1 Hz, third differences 1.01 and 1.16 times, fourth 1.01 and 1.03; the ARW read
1.04 / 1.57, 1.02 / 1.08 and 1.03 / 1.09 times itself at 2 / 1 Hz (the table's reversals, sparse at 10 Hz, are a
few per cent of the samples at 1 Hz). At 10 Hz every order reads both within 0.5 %; the fourth differences' spread
is 15 % wider than the second's for the same samples (docs/studies/2026-11-28-white-noise-low-rates.md).

Increments that are pulse counts (``unit = "pulse"`` in a log format), or values a file rounded, lie on a lattice
(`lattice_steps` finds its step in the first chunk) and carry the counter's remainder or the rounding as well:
steps below `COUNTING_LIMIT` (half) of the per-sample noise add at most 6 % to the reading; coarser ones, as an
RLG's 0.1-1 arcsec pulses against its 0.003-0.01 arcsec of noise per sample at 10-100 Hz, leave the samples
showing the counting, not the sensor, and `estimate_white_noise` refuses them: the noise must then be given (a
scenario file's keys, or `gyrodrift allan` on a long static log).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gyrodrift import _core
from gyrodrift.errors import InputError
from gyrodrift.files.toml_input import read_toml
from gyrodrift.files.toml_schema import Field, Number, Scope, type_name
from gyrodrift.logs import ImuLog
from gyrodrift.units import ARCSEC, DEG, DEG_PER_H, DEG_PER_SQRT_H, HOUR, MICRO_G

__all__ = ["SensorNoise", "estimate_white_noise", "load_noise_file", "NOISE_FLOOR"]

NOISE_FLOOR = {"arw_deg_rth": 1e-5, "vrw_ug_rthz": 0.05}
"""Smallest densities the filters are given (a noise-free log still needs some process noise: without it the
covariance of a 16 h filter collapses and it stops listening): 1e-5 deg/sqrt(h), 0.05 ug/sqrt(Hz)."""

_KEYS = ("arw_deg_rth", "vrw_ug_rthz", "bias_instability_deg_h", "correlation_s", "rrw_deg_h_rth")


@dataclass(frozen=True)
class SensorNoise:
    """A noise model in user units (the scenario files' keys).

    Attributes
    ----------
    arw_deg_rth : float
        Gyro angle random walk [deg/sqrt(h)].
    vrw_ug_rthz : float
        Accelerometer velocity random walk [ug/sqrt(Hz)].
    bias_instability_deg_h, correlation_s : float
        First-order Gauss-Markov gyro bias: stationary 1-sigma [deg/h] and correlation time [s] (0: none).
    rrw_deg_h_rth : float
        Gyro rate random walk [deg/h/sqrt(h)] (0: none).
    source : str
        Where the numbers come from (``"given"``, ``"log"``, ``"default"``).

    The default ARW and VRW are the smoother's defaults, read from the core (gyrodrift-core
    ``filter_prior::FilterPrior::SMOOTHER``, which also says why the aligner's differ): 0.0005 deg/sqrt(h) and
    5 ug/sqrt(Hz), the RLG grade of the study.
    """

    arw_deg_rth: float = _core.SMOOTHER_GYRO_ARW_DEG_RTH
    vrw_ug_rthz: float = _core.SMOOTHER_ACCEL_VRW_UG_RTHZ
    bias_instability_deg_h: float = 0.0
    correlation_s: float = 3600.0
    rrw_deg_h_rth: float = 0.0
    source: str = "default"

    def __post_init__(self):
        for key in _KEYS:
            v = getattr(self, key)
            if not (isinstance(v, int | float) and math.isfinite(v) and v >= 0):
                raise InputError(f"noise: {key} must be a finite number >= 0, got {v!r}")
        if not self.correlation_s > 0:
            raise InputError(f"noise: correlation_s must be > 0 s, got {self.correlation_s!r}")

    @classmethod
    def from_block(cls, block: Mapping[str, Any], source: str = "given") -> SensorNoise:
        """From a mapping with the keys above, flat or as the ``{"gyro": {...}, "accel": {...}}`` blocks of a
        scenario file or of `gyrodrift allan`'s ``scenario_noise`` (other keys of those blocks, e.g. biases, are
        ignored). Missing keys keep their defaults."""
        flat: dict[str, Any] = {}
        for part in ("gyro", "accel"):
            sub = block.get(part)
            if isinstance(sub, Mapping):
                flat.update({k: v for k, v in sub.items() if k in _KEYS})
        flat.update({k: v for k, v in block.items() if k in _KEYS})
        unknown = [k for k in block if k not in _KEYS and k not in ("gyro", "accel", "source")]
        if unknown:
            raise InputError(f"noise: unknown key {unknown[0]!r}; expected among {', '.join(_KEYS)}")
        return cls(**{k: float(v) for k, v in flat.items()}, source=source)

    def floored(self) -> SensorNoise:
        """The same with ARW and VRW at least `NOISE_FLOOR`."""
        return SensorNoise(
            max(self.arw_deg_rth, NOISE_FLOOR["arw_deg_rth"]),
            max(self.vrw_ug_rthz, NOISE_FLOOR["vrw_ug_rthz"]),
            self.bias_instability_deg_h,
            self.correlation_s,
            self.rrw_deg_h_rth,
            self.source,
        )

    @property
    def arw_rad_rts(self) -> float:
        """ARW [rad/sqrt(s)]."""
        return self.arw_deg_rth * DEG_PER_SQRT_H

    @property
    def vrw_m_s_rts(self) -> float:
        """VRW [m/s/sqrt(s)]."""
        return self.vrw_ug_rthz * MICRO_G

    def core_keywords(self) -> dict[str, float]:
        """The SI keywords of `_core.SmootherConfig` for this noise."""
        return {
            "gyro_arw_rad_rts": self.arw_rad_rts,
            "accel_vrw_m_s_rts": self.vrw_m_s_rts,
            "gyro_bias_instability_rad_s": self.bias_instability_deg_h * DEG_PER_H,
            "gyro_correlation_s": float(self.correlation_s),
            "gyro_rrw_rad_s_rts": self.rrw_deg_h_rth * DEG_PER_H / math.sqrt(HOUR),
        }

    @property
    def white_only_note(self) -> str | None:
        """A one-line caveat when this model was measured from a log (``source="log"``: white noise only), else
        None: a 1-sigma computed under it leaves out any gyro bias instability or rate random walk of the sensor,
        which the fourth differences cannot see and 16 h cannot resolve."""
        if self.source != "log" or self.bias_instability_deg_h > 0 or self.rrw_deg_h_rth > 0:
            return None
        return (
            "the 1-sigma assumes white sensor noise only (ARW and VRW measured from the log); a gyro bias "
            "instability or rate random walk is not in it: give the sensor's noise with --noise FILE (a scenario "
            "file, or gyrodrift allan's scenario_noise)"
        )

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


_NOISE_FILE: dict[str, dict[str, Field]] = {
    "gyro": {
        "arw_deg_rth": Number.non_negative(),
        "bias_instability_deg_h": Number.non_negative(),
        "correlation_s": Number(gt=0.0),
        "rrw_deg_h_rth": Number.non_negative(),
    },
    "accel": {"vrw_ug_rthz": Number.non_negative()},
}
"""The noise keys of a scenario file's ``[gyro]`` and ``[accel]`` tables (docs/scenarios.md), as `load_noise_file`
reads them."""


def load_noise_file(path) -> SensorNoise:
    """A `SensorNoise` from a TOML file with ``[gyro]`` and ``[accel]`` tables (a scenario file, or the
    ``scenario_noise`` block of `gyrodrift allan` saved as TOML); other keys of those tables (biases, ...) are
    ignored. ``[gyro] arw_deg_rth`` and ``[accel] vrw_ug_rthz`` are required. Errors (`InputError`, one line
    ``<file>: [table] key: ...``, `gyrodrift.files.toml_schema`) name the file and the key.
    """
    p = Path(path)
    data = read_toml(p, InputError, expected="a TOML noise file with [gyro] and [accel] tables")
    root = Scope(str(p), InputError)
    values: dict[str, Any] = {}
    for (part, specs), required in zip(_NOISE_FILE.items(), ("arw_deg_rth", "vrw_ug_rthz"), strict=True):
        table = data.get(part, {})
        if not isinstance(table, Mapping):
            raise root.fail(None, f"[{part}] must be a table, got {type_name(table)}")
        scope = root.section(part)
        if required not in table:
            raise scope.fail(required, "missing (a noise file needs [gyro] arw_deg_rth and [accel] vrw_ug_rthz)")
        values.update({k: v for k, v in scope.fields(table, specs).items() if v is not None})
    return SensorNoise(**values, source=str(p))


DIFFERENCE_ORDER = 4
"""The order of the differences `estimate_white_noise` takes of the increments (module docs)."""
_DIFFERENCE_VARIANCE = math.comb(2 * DIFFERENCE_ORDER, DIFFERENCE_ORDER)
"""Variance of a difference of that order of unit white noise: C(8, 4) = 70."""


COUNTING_LIMIT = 0.5
"""The largest pulse step, in per-sample noise (what the differences read), a log's noise is still read from: a pulse
counter's remainder adds to what they read, 6 % of the 1-sigma at half a step per sigma of noise, 13 % at 0.8 and
erratic beyond (a median on a lattice); tests/procedure/test_white_noise.py."""


def _robust_sigma(d4: np.ndarray) -> np.ndarray:
    """Per-column white-noise 1-sigma of a sample from its fourth differences (module docs)."""
    return 1.482602218505602 * np.median(np.abs(d4), axis=0) / math.sqrt(_DIFFERENCE_VARIANCE)


def lattice_steps(x: np.ndarray) -> np.ndarray:
    """Per column of `x` (n, k): the step of the lattice its values lie on (a counter's pulse weight), else 0.

    The step is the smallest gap between the column's distinct values, kept when every value is a whole number of
    it (within 1 % of a step) and it stands above float rounding (1e-12 of the largest magnitude): continuous data
    give 0, as does a column with fewer than three distinct values (two are a jump, not a counter).
    """
    steps = np.zeros(x.shape[1])
    for c in range(x.shape[1]):
        values = np.unique(x[:, c])
        if len(values) < 3:
            continue
        step = float(np.min(np.diff(values)))
        if step <= 1e-12 * float(np.max(np.abs(values))):
            continue
        counts = values / step
        if float(np.max(np.abs(counts - np.round(counts)))) < 0.01:
            steps[c] = step
    return steps


def estimate_white_noise(log: ImuLog, *, hours: float = 1.0, chunk_samples: int = 100_000) -> SensorNoise:
    """ARW and VRW of `log` from the fourth differences of its first `hours` of increments (module docs).

    Returns a `SensorNoise` with ``source="log"`` and no bias drift terms. `InputError` when the increments are
    pulse counts too coarse for their noise (module docs): a step of `COUNTING_LIMIT` or more of the noise the
    samples show.
    """
    span = DIFFERENCE_ORDER + 1  # samples in one difference
    n = min(log.n_samples, max(span, log.samples_for(hours * HOUR)))
    sig_g, sig_a, weights = np.zeros(3), np.zeros(3), 0
    tail_g = tail_a = None
    steps: tuple[np.ndarray, np.ndarray] | None = None
    for chunk in log.chunks(chunk_samples, stop=n):
        g, a = np.asarray(chunk.dtheta_rad, float), np.asarray(chunk.dv_m_s, float)
        if steps is None:  # the log's encoding, from its first chunk
            steps = lattice_steps(g), lattice_steps(a)
        if tail_g is not None and tail_a is not None:  # the differences across chunk boundaries
            g, a = np.vstack([tail_g, g]), np.vstack([tail_a, a])
        if len(g) >= span:
            m = len(g) - DIFFERENCE_ORDER
            sig_g += m * _robust_sigma(np.diff(g, DIFFERENCE_ORDER, axis=0)) ** 2
            sig_a += m * _robust_sigma(np.diff(a, DIFFERENCE_ORDER, axis=0)) ** 2
            weights += m
        tail_g, tail_a = g[-DIFFERENCE_ORDER:], a[-DIFFERENCE_ORDER:]
    if weights == 0 or steps is None:
        raise InputError(f"{log.label}: too few samples to measure the sensor noise")
    sigma_g, sigma_a = np.sqrt(sig_g / weights), np.sqrt(sig_a / weights)  # per sample, per axis [rad], [m/s]
    _check_counting(log, steps, (sigma_g, sigma_a))
    sqrt_dt = math.sqrt(1.0 / log.rate_hz)
    arw = float(np.mean(sigma_g)) / sqrt_dt  # rad/sqrt(s)
    vrw = float(np.mean(sigma_a)) / sqrt_dt  # m/s/sqrt(s)
    return SensorNoise(arw_deg_rth=arw / DEG * 60.0, vrw_ug_rthz=vrw / MICRO_G, source="log")


def _check_counting(log: ImuLog, steps: tuple[np.ndarray, np.ndarray], sigmas: tuple[np.ndarray, np.ndarray]) -> None:
    """`InputError` when a column's increments come in steps (`lattice_steps`) of `COUNTING_LIMIT` or more of the
    per-sample noise its fourth differences show (`sigmas`: rad, m/s, per axis): the counting then makes a tenth or
    more of what they read, and a median of differences on a coarse lattice can read 0."""
    coarse = []
    for sensor, step, sigma, unit, scale in (
        ("gyro", steps[0], sigmas[0], "arcsec", 1.0 / ARCSEC),
        ("accelerometer", steps[1], sigmas[1], "mm/s", 1000.0),
    ):
        for axis, q, s in zip("xyz", step, sigma, strict=True):
            if q > 0.0 and q >= COUNTING_LIMIT * s:
                coarse.append(f"{sensor} {axis}: steps of {q * scale:.3g} {unit}, noise {s * scale:.3g} {unit}")
    if coarse:
        raise InputError(
            f"{log.label}: the increments come in steps (pulse counts, or the file's rounding) too coarse to read "
            "the sensor's white noise from "
            f"({'; '.join(coarse)} per sample): the samples would show the steps, not the sensor; give the "
            "noise (--noise FILE: a scenario file's [gyro] arw_deg_rth and [accel] vrw_ug_rthz, or the "
            "scenario_noise of `gyrodrift allan` on a long static log)"
        )
