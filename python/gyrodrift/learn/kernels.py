"""Kernel functions of the LSSVM: squared distances, RBF, linear and polynomial kernels.

Units: inputs are whatever the caller scaled (this module never rescales); ``sigma`` carries the unit of
the inputs. Conventions (docs/conventions.md, "Kernel and hyperparameters"):

* RBF ``K(x, z) = exp(-|x - z|^2 / sigma^2)`` - ``sigma^2`` in the denominator, no factor 2
  (Yu et al. 2013, after Suykens). The kernel width is ``sigma``, never ``gamma``: in this project
  ``gamma`` is the LSSVM regularisation (see :mod:`gyrodrift.learn.lssvm_system`).
* linear ``K(x, z) = x . z``.
* polynomial ``K(x, z) = (x . z / sigma^2 + coef0)^degree``.

Conversions for cross-checks against other libraries:

* scikit-learn (``sklearn.metrics.pairwise``): ``rbf_kernel(gamma=1/sigma^2)``,
  ``polynomial_kernel(gamma=1/sigma^2, coef0=coef0, degree=degree)``, ``linear_kernel``.
* LS-SVMlab 1.8: ``sig2 = sigma^2 / 2`` (docs/conventions.md; this assumes LS-SVMlab's
  ``RBF_kernel`` is ``exp(-|x - z|^2 / (2 sig2))`` - not re-verified against LS-SVMlab here).
"""

from __future__ import annotations

import math
import numbers
import os

import numpy as np

from gyrodrift.choices import SIGMA_RANGE
from gyrodrift.errors import InputError, OptionError

#: Kernel names accepted by :func:`kernel_matrix` ("polynomial" is an alias of "poly", as in scikit-learn).
KERNELS = ("rbf", "linear", "poly", "polynomial")

SIGMA_MIN, SIGMA_MAX = SIGMA_RANGE
"""Smallest and largest kernel widths [input units] whose square is a normal, finite float64 (about 1.5e-154
and 1.3e154): below, ``sigma**2`` underflows and the RBF kernel's diagonal becomes ``0/0 = NaN``."""


class MemoryLimitError(InputError):
    """An n x n kernel computation that would not fit in the memory available; the message says what fits."""


def check_positive(name: str, value) -> float:
    """Return ``value`` as a float if it is a finite real number > 0, else raise :class:`OptionError`.

    The message names the parameter and the offending value, e.g.
    ``"sigma must be a finite number > 0, got -1.0"``. (``OptionError`` is a ``ValueError``.)
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise OptionError(f"{name} must be a finite number > 0, got {value!r}")
    try:
        as_float = float(value)
    except OverflowError:  # a huge Python int
        raise OptionError(f"{name} must be a finite number > 0, got an integer too large for a float") from None
    if not (np.isfinite(as_float) and as_float > 0.0):
        raise OptionError(f"{name} must be a finite number > 0, got {value!r}")
    return as_float


def check_sigma(value, name: str = "sigma") -> float:
    """A kernel width [input units]: finite, > 0, and within [SIGMA_MIN, SIGMA_MAX] so that ``sigma**2`` is a
    normal, finite float64 (else the kernel is ``0/0`` or loses every distance); raises :class:`OptionError`."""
    sigma = check_positive(name, value)
    if not SIGMA_MIN <= sigma <= SIGMA_MAX:
        raise OptionError(
            f"{name} must be within [{SIGMA_MIN:.3g}, {SIGMA_MAX:.3g}] (its square must be a finite, normal "
            f"float64; beyond, the kernel under- or overflows), got {value!r}"
        )
    return sigma


def available_memory_bytes() -> int | None:
    """Memory the system can give this process without swapping [bytes] (Linux ``MemAvailable``), or None."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, ValueError, OSError):
        return None


def check_matrix_memory(n_rows: int, n_cols: int, copies: int, what: str, *, unit: str = "runs") -> None:
    """Refuse, before allocating, ``copies`` float64 matrices of ``n_rows x n_cols`` that would not fit.

    ``what`` names the computation (e.g. "fitting the LSSVR"). Raises :class:`MemoryLimitError` saying how much
    is needed, how much is available and how many ``unit`` (rows, for a square ``n x n`` problem) would fit.
    Does nothing when the available memory cannot be read.
    """
    need = 8 * n_rows * n_cols * copies
    avail = available_memory_bytes()
    if avail is None or need <= avail:
        return
    if n_rows == n_cols:
        fits = int(math.isqrt(avail // (8 * copies)))
    else:
        fits = int(avail // (8 * copies * max(n_cols, 1)))
    gib = 2.0**30
    raise MemoryLimitError(
        f"{what} on {n_rows} {unit} needs about {need / gib:.3g} GiB ({copies} float64 matrices of {n_rows} x "
        f"{n_cols}); about {avail / gib:.3g} GiB is available, enough for at most {fits} {unit}"
    )


def _as_2d(X, name: str) -> np.ndarray:
    X = np.asarray(X, dtype=float)
    if X.ndim != 2:
        raise ValueError(f"{name} must be a 2-D array (n_samples, n_features), got shape {X.shape}")
    return X


def squared_distances(X, Z=None) -> np.ndarray:
    """Squared Euclidean distances ``D[i, j] = |X[i] - Z[j]|^2``.

    Parameters
    ----------
    X : array_like, shape (n, d)
    Z : array_like, shape (m, d), optional
        Defaults to ``X``.

    Returns
    -------
    ndarray, shape (n, m)
        Computed from the coordinate differences (not from ``|x|^2 + |z|^2 - 2 x.z``), so identical
        points give exactly 0 - in particular the diagonal is exactly 0 when ``Z`` is None - the
        matrix is exactly symmetric when ``Z`` is None, and no entry is negative (it is clipped at 0
        anyway). Units: the square of the input units.
    """
    from scipy.spatial.distance import cdist, pdist, squareform  # here: scipy.spatial costs ~0.3 s of a start

    X = _as_2d(X, "X")
    if Z is None:
        if X.shape[0] < 2:
            return np.zeros((X.shape[0], X.shape[0]))
        D = squareform(pdist(X, "sqeuclidean"))
    else:
        Z = _as_2d(Z, "Z")
        if Z.shape[1] != X.shape[1]:
            raise ValueError(f"X has {X.shape[1]} features but Z has {Z.shape[1]}")
        D = cdist(X, Z, "sqeuclidean")
    return np.maximum(D, 0.0, out=D)


def rbf_from_squared_distances(sqdist, sigma) -> np.ndarray:
    """RBF kernel ``exp(-sqdist / sigma^2)`` from precomputed squared distances.

    ``sigma`` is a scalar or an array broadcasting against ``sqdist`` (e.g. shape (m, 1, 1) with
    ``sqdist`` of shape (n, n) gives an (m, n, n) stack).
    """
    sigma = np.asarray(sigma, dtype=float)
    return np.exp(-np.asarray(sqdist, dtype=float) / (sigma * sigma))


def rbf_kernel(X, Z=None, sigma: float = 1.0) -> np.ndarray:
    """RBF kernel ``K[i, j] = exp(-|X[i] - Z[j]|^2 / sigma^2)`` (no factor 2; sklearn ``gamma=1/sigma^2``)."""
    sigma = check_sigma(sigma)
    return rbf_from_squared_distances(squared_distances(X, Z), sigma)


def linear_kernel(X, Z=None) -> np.ndarray:
    """Linear kernel ``K[i, j] = X[i] . Z[j]``."""
    X = _as_2d(X, "X")
    Z = X if Z is None else _as_2d(Z, "Z")
    if Z.shape[1] != X.shape[1]:
        raise ValueError(f"X has {X.shape[1]} features but Z has {Z.shape[1]}")
    return X @ Z.T


def polynomial_kernel(X, Z=None, sigma: float = 1.0, degree: int = 3, coef0: float = 1.0) -> np.ndarray:
    """Polynomial kernel ``K[i, j] = (X[i] . Z[j] / sigma^2 + coef0)^degree``.

    ``degree`` is an integer >= 1. The kernel is positive semi-definite for ``coef0 >= 0``; with
    ``coef0 < 0`` it may be indefinite and an LSSVM fit may fail (see :mod:`gyrodrift.learn.lssvm_system`).
    scikit-learn equivalent: ``polynomial_kernel(gamma=1/sigma^2, coef0=coef0, degree=degree)``.
    """
    sigma = check_sigma(sigma)
    degree = _check_degree(degree)
    if isinstance(coef0, bool) or not isinstance(coef0, numbers.Real) or not np.isfinite(coef0):
        raise OptionError(f"coef0 must be a finite real number, got {coef0!r}")
    with np.errstate(over="ignore", invalid="ignore"):  # overflow gives inf, which the LSSVR refuses by name
        return (linear_kernel(X, Z) / (sigma * sigma) + float(coef0)) ** degree


MAX_DEGREE = 64
"""Largest polynomial degree accepted (beyond it any kernel value off [-1, 1] over- or underflows)."""


def _check_degree(degree) -> int:
    """Integer within [1, MAX_DEGREE]; integral floats such as 3.0 (e.g. from a parameter grid) are accepted."""
    ok = not isinstance(degree, bool) and isinstance(degree, numbers.Real)
    if ok and not isinstance(degree, numbers.Integral):
        as_float = float(degree)
        ok = math.isfinite(as_float) and as_float.is_integer()
    if not ok or degree < 1:
        raise OptionError(f"degree must be an integer >= 1, got {degree!r}")
    if degree > MAX_DEGREE:
        raise OptionError(f"degree must be an integer within [1, {MAX_DEGREE}], got a larger number")
    return int(degree)


def check_kernel(kernel) -> str:
    """Return the canonical kernel name ("rbf", "linear" or "poly"), or raise ``ValueError``."""
    if not isinstance(kernel, str) or kernel not in KERNELS:
        raise OptionError(f"unknown kernel {kernel!r}; expected one of {', '.join(map(repr, KERNELS))}")
    return "poly" if kernel == "polynomial" else kernel


def kernel_matrix(
    X, Z=None, *, kernel: str = "rbf", sigma: float = 1.0, degree: int = 3, coef0: float = 1.0
) -> np.ndarray:
    """Kernel matrix ``K[i, j] = k(X[i], Z[j])`` for a named kernel.

    Parameters
    ----------
    X : array_like, shape (n, d)
    Z : array_like, shape (m, d), optional
        Defaults to ``X``.
    kernel : {"rbf", "linear", "poly", "polynomial"}
    sigma : float
        Kernel width (rbf, poly), in input units; ignored by "linear" but still validated (> 0).
    degree, coef0 : int, float
        Polynomial kernel parameters; ignored by the others.

    Returns
    -------
    ndarray, shape (n, m)
    """
    kernel = check_kernel(kernel)
    sigma = check_sigma(sigma)
    if kernel == "rbf":
        return rbf_kernel(X, Z, sigma)
    if kernel == "linear":
        return linear_kernel(X, Z)
    return polynomial_kernel(X, Z, sigma=sigma, degree=degree, coef0=coef0)
