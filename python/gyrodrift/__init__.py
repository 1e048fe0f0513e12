"""gyrodrift: identify the axial gyro drift of single-axis rotation RLG inertial navigation systems.

The learning side (LSSVR, chaos PSO, tuning, data, reports, CLI) is Python; everything that runs per IMU
sample (IMU simulation, strapdown navigation, alignment) is the Rust core `gyrodrift._core`.
Units at this edge: drift in deg/h, latitude in deg, temperature in deg C (see docs/conventions.md).
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("gyrodrift")
except PackageNotFoundError:  # pragma: no cover - running from an unbuilt source tree
    __version__ = "0+unknown"

__all__ = ["__version__"]
