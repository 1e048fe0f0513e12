"""The axial drift compensation of a navigation: a `gyrodrift.drift_law.DriftLaw` applied sample by sample.

A constant law (k1 = k3 = 0) is subtracted as today's constant z gyro bias (`Navigator.set_gyro_bias`: the same
bits and cost). A law that reads the temperature is evaluated on the log's ``temp_c`` piece by piece as the log is
navigated (`AxialBias`): for every sample k,

    b_z,k = b_z,other + eps(T_k, dT/dt_k)   [deg/h],  eps = eps_ref + k1 (T_k - T_ref) + k3 dT/dt_k,

with T_k the temperature at the end of sample k and dT/dt_k the causal `gyrodrift.drift_law.TemperatureRate` estimate
(its filter initialised by the first navigated sample, its state carried across pieces, so the biases do not depend
on the chunking), handed to the core navigator per sample (``Navigator.process(..., axial_bias_rad_s=...)``), which
subtracts b_z,k dt from the sample's z angle increment (measured - estimate).
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from typing import Any

import numpy as np

from gyrodrift.choices import MAX_DRIFT_DEG_H
from gyrodrift.drift_law import DriftLaw, TemperatureRate
from gyrodrift.errors import InputError
from gyrodrift.files.input_files import read_limited
from gyrodrift.logs import ImuLog, LogChunk
from gyrodrift.units import DEG_PER_H

__all__ = [
    "AxialBias",
    "axial_bias",
    "require_temperature_for",
    "compensation_record",
    "compensation_words",
    "load_drift_law",
]

MAX_LAW_FILE_BYTES = 64 * 2**20
"""Largest file `load_drift_law` reads [bytes] (an identification.json is a few kB)."""


class AxialBias:
    """The per-sample z gyro bias [rad/s] of a temperature-dependent drift law, piece by piece of a log.

    Call it once per navigated piece of the log, in order: it returns the bias of every sample of the piece and
    carries the temperature-rate state to the next piece.

    Parameters
    ----------
    law : DriftLaw
        The axial drift [deg/h] to subtract (not constant).
    rate_hz : float
        The log's sample rate [Hz] (the temperature-rate filter's step).
    other_z_deg_h : float
        Any other z gyro bias estimate subtracted as well [deg/h] (0 after an alignment, which does not estimate
        the axial drift).
    where : callable, optional
        ``where(index)``: the log's file and row of 0-based sample `index`, for the message when the law leaves
        +-`MAX_DRIFT_DEG_H` (a wrong coefficient or temperature; `InputError`).
    """

    def __init__(
        self, law: DriftLaw, rate_hz: float, other_z_deg_h: float = 0.0, where: Callable[[int], str] | None = None
    ) -> None:
        self.law = law
        self.other_z_deg_h = float(other_z_deg_h)
        self._rate = TemperatureRate(law.rate_tau_s, 1.0 / rate_hz) if law.uses_rate else None
        self._where = where or (lambda index: f"sample {index}")

    def __call__(self, piece: LogChunk) -> np.ndarray:
        """The z gyro bias [rad/s] of every sample of `piece` (which must carry ``temp_c``)."""
        temp = piece.temp_c
        assert temp is not None  # `axial_bias` required the column
        rate = 0.0 if self._rate is None else self._rate.update(temp)
        drift = self.law.drift_deg_h(temp, rate)
        bad = np.flatnonzero(~(np.abs(drift) <= MAX_DRIFT_DEG_H))
        if bad.size:
            k = int(bad[0])
            raise InputError(
                f"{self._where(piece.first_index + k)}: the drift law gives {float(drift[k]):.6g} deg/h at temp_c "
                f"{float(temp[k]):.6g} degC; a drift to compensate must be within +-{MAX_DRIFT_DEG_H:g} deg/h "
                "(check the law's coefficients and the temperature column)"
            )
        return (self.other_z_deg_h + drift) * DEG_PER_H


def require_temperature_for(law: DriftLaw, log: ImuLog) -> None:
    """Refuse a law reading the temperature on a log without ``temp_c`` (`gyrodrift.logs.LogError` naming the log
    and the column); a constant law needs nothing."""
    if not law.is_constant:
        log.require_temperature(
            f"the drift law (k1 = {law.k1_deg_h_per_c:.6g} deg/h/degC, k3 = {law.k3_deg_h_per_c_per_h:.6g} deg/h "
            "per degC/h)"
        )


def axial_bias(law: DriftLaw, log: ImuLog, other_z_deg_h: float = 0.0) -> AxialBias | None:
    """The per-sample compensation of `law` on `log` (`AxialBias`), or None when the law is constant (then its
    ``eps_ref_deg_h`` is the constant z gyro bias estimate); `require_temperature_for` first."""
    require_temperature_for(law, log)
    return None if law.is_constant else AxialBias(law, log.rate_hz, other_z_deg_h, log.source.where)


def compensation_record(law: DriftLaw | None) -> dict[str, Any]:
    """What an output says about the compensation: ``compensation`` ("none", "constant" or "law") and ``drift_law``
    (`DriftLaw.to_dict`, or None without compensation)."""
    if law is None:
        return {"compensation": "none", "drift_law": None}
    return {"compensation": "constant" if law.is_constant else "law", "drift_law": law.to_dict()}


def compensation_words(law: DriftLaw) -> str:
    """The compensation in words, for a command's closing line or a figure: "constant 0.004000 deg/h" or "drift law
    0.004000 deg/h at 20.0 degC, k1 0.0001 deg/h/degC" (and ", k3 ... deg/h per degC/h" when it reads the rate)."""
    if law.is_constant:
        return f"constant {law.eps_ref_deg_h:.6f} deg/h"
    rate = f", k3 {law.k3_deg_h_per_c_per_h:.6g} deg/h per degC/h" if law.uses_rate else ""
    return (
        f"drift law {law.eps_ref_deg_h:.6f} deg/h at {law.t_ref_c:.1f} degC, k1 {law.k1_deg_h_per_c:.6g} deg/h/degC"
        f"{rate}"
    )


def load_drift_law(path: str | os.PathLike[str]) -> DriftLaw:
    """The drift law of a JSON file: the ``drift_law`` object of a document holding one (``identification.json`` of
    `gyrodrift identify`), or a bare law (the object `DriftLaw.to_dict` writes). `InputError` naming the file (and
    the key) for anything else."""
    try:
        raw = read_limited(path, MAX_LAW_FILE_BYTES)  # a device or FIFO is refused, never read or waited on
        if len(raw) > MAX_LAW_FILE_BYTES:
            raise InputError(f"{path}: more than {MAX_LAW_FILE_BYTES} bytes; not a drift law file")
        doc = json.loads(raw.decode("utf-8"))
    except OSError as exc:
        raise InputError(f"{path}: cannot read: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a text file (expected JSON holding a drift_law object)") from None
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}: corrupted JSON at line {exc.lineno}, column {exc.colno}: {exc.msg}") from None
    except (RecursionError, ValueError) as exc:
        raise InputError(f"{path}: unreadable JSON: {exc}") from None
    if not isinstance(doc, dict):
        raise InputError(f"{path}: expected a JSON object holding drift_law, got {type(doc).__name__}")
    if "drift_law" in doc:
        if doc["drift_law"] is None:
            raise InputError(f"{path}: drift_law is null (no law identified)")
        return DriftLaw.from_dict(doc["drift_law"], str(path))
    if "eps_ref_deg_h" in doc:
        return DriftLaw.from_dict(doc, str(path))
    raise InputError(
        f"{path}: no drift_law key (expected identification.json of `gyrodrift identify`, or a law object with "
        "eps_ref_deg_h, t_ref_c, k1_deg_h_per_c, ...)"
    )
