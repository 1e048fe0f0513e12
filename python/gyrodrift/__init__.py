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

# The public names are imported on first use (PEP 562), so that `import gyrodrift` and the CLI start
# without loading scikit-learn and scipy when the command does not need them.
_PUBLIC = {
    "LSSVR": "gyrodrift.learn.lssvr",
    "minimize_cpso": "gyrodrift.learn.cpso",
    "tune_lssvr": "gyrodrift.learn.tuning",
    "TuningResult": "gyrodrift.learn.tuning",
    "load_paper": "gyrodrift.runs.datasets",
    "RunTable": "gyrodrift.runs.table",
    "read_runs_csv": "gyrodrift.runs.table",
    "DriftModel": "gyrodrift.learn.drift_model",
    "fit_drift_model": "gyrodrift.learn.drift_model",
    "save_model": "gyrodrift.learn.model_io",
    "load_model": "gyrodrift.learn.model_io",
}


def __getattr__(name):
    if name in _PUBLIC:
        import importlib

        return getattr(importlib.import_module(_PUBLIC[name]), name)
    raise AttributeError(f"module 'gyrodrift' has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + list(_PUBLIC))


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
