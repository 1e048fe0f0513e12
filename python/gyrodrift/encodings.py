"""Encodings of a run into a model's input vector.

The paper feeds "the latitude at the 12th hour" and "the temperature change over the 12 h" (a min~max range)
to its LSSVM without saying how a range became a number or how inputs were scaled. Each plausible reading is
an encoding here; ``gyrodrift reproduce`` reports every one rather than picking by test results.

All encodings start from the latitude error at 12 h, computed minus true, in arcsec (the quantity the physics
ties to the axial drift: dL(12 h) = 2 eps_U cos L / w_ie).
"""

from __future__ import annotations

import numpy as np

from gyrodrift.choices import ENCODINGS
from gyrodrift.errors import OptionError
from gyrodrift.runs import RunTable

ENCODING_DESCRIPTIONS = {
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
    columns = {
        "lat_err_arcsec": runs.lat_err_arcsec,
        "temp_min_c": runs.temp_min_c,
        "temp_max_c": runs.temp_max_c,
        "temp_mean_c": 0.5 * (runs.temp_min_c + runs.temp_max_c),
        "temp_span_c": runs.temp_max_c - runs.temp_min_c,
    }
    return np.column_stack([columns[name] for name in feature_names(encoding)]).astype(float)
