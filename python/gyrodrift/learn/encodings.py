"""Encodings of a run into a model's input vector.

The paper feeds "the latitude at the 12th hour" and "the temperature change over the 12 h" (a min~max range)
to its LSSVM without saying how a range became a number or how inputs were scaled. Each plausible reading is
an encoding here; ``gyrodrift reproduce`` reports every one rather than picking by test results.

The paper's encodings start from the latitude error at 12 h, computed minus true, in arcsec (the quantity the
physics ties to the axial drift: dL(12 h) = 2 eps_U cos L / w_ie). It scales with cos L, so a model fed arcsec
learns the fleet's latitudes rather than the sensor: the same drift reads 72 % more arcsec at 20 deg than at
57 deg. The ``physics`` encodings feed instead its drift equivalent at the run's own site latitude,
``w_ie dL / ((1 - cos w_ie 12 h) cos L0)`` in deg/h (`gyrodrift.learn.baselines.physics_inversion`), which does not
depend on latitude. ``physics`` (the default of ``fit``) adds the temperature range; ``physics_lat`` also the
site latitude lat0_deg, for fleets whose drift would depend on the site (it lets the RBF kernel separate sites,
so a new site is an extrapolation; the simulated example measures both).
"""

from __future__ import annotations

import numpy as np

from gyrodrift.choices import ENCODINGS
from gyrodrift.errors import OptionError
from gyrodrift.learn.baselines import physics_inversion
from gyrodrift.runs.table import RunTable

ENCODING_DESCRIPTIONS = {
    "physics": "drift equivalent of the latitude error at the site latitude (deg/h), and the temperature range",
    "physics_lat": "as physics, plus the site latitude lat0_deg",
    "temperature": "the temperature range alone (for a hybrid model's correction: physics gives the drift)",
    "temp_range": "latitude error and the temperature range as two inputs (min, max)",
    "temp_mean": "latitude error and the mid-range temperature (min + max) / 2",
    "temp_span": "latitude error and the temperature change max - min",
    "lat_only": "latitude error alone",
}


def feature_names(encoding: str) -> tuple[str, ...]:
    """Names (with units) of the features an encoding produces; an unknown name is an ``OptionError``."""
    if not isinstance(encoding, str):
        raise OptionError(f"unknown encoding {encoding!r}; expected one of {', '.join(ENCODINGS)}")
    try:
        return ENCODINGS[encoding]
    except KeyError:
        raise OptionError(f"unknown encoding {encoding!r}; expected one of {', '.join(ENCODINGS)}") from None


def encode(runs: RunTable, encoding: str) -> np.ndarray:
    """The input matrix of shape (n_runs, n_features) for ``encoding`` (see ``ENCODINGS``)."""
    names = feature_names(encoding)
    columns = {
        "lat_err_arcsec": runs.lat_err_arcsec,
        "lat0_deg": runs.lat0_deg,
        "temp_min_c": runs.temp_min_c,
        "temp_max_c": runs.temp_max_c,
        "temp_mean_c": 0.5 * (runs.temp_min_c + runs.temp_max_c),
        "temp_span_c": runs.temp_max_c - runs.temp_min_c,
    }
    if "drift_equiv_deg_h" in names:
        columns["drift_equiv_deg_h"] = physics_inversion(runs)
    return np.column_stack([columns[name] for name in names]).astype(float)
