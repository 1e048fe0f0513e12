"""gyrodrift: identify the axial gyro drift of single-axis rotation RLG inertial navigation systems.

The learning side (LSSVR, chaos PSO, tuning, data, reports, CLI) is Python; everything that runs per IMU
sample (IMU simulation, strapdown navigation, alignment) is the Rust core `gyrodrift._core`, used through
`gyrodrift.ins`. Units at this edge: drift in deg/h, latitude in deg, temperature in deg C
(see docs/conventions.md).
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("gyrodrift")
except PackageNotFoundError:  # pragma: no cover - running from an unbuilt source tree
    __version__ = "0+unknown"

from gyrodrift.cpso import minimize_cpso
from gyrodrift.datasets import load_paper
from gyrodrift.lssvr import LSSVR
from gyrodrift.model import DriftModel, fit_drift_model
from gyrodrift.model_io import load_model, save_model
from gyrodrift.runs import RunTable, read_runs_csv
from gyrodrift.tuning import TuningResult, tune_lssvr

__all__ = [
    "__version__",
    "LSSVR",
    "minimize_cpso",
    "tune_lssvr",
    "TuningResult",
    "load_paper",
    "RunTable",
    "read_runs_csv",
    "DriftModel",
    "fit_drift_model",
    "save_model",
    "load_model",
]
