"""Kernel functions of the LSSVM: squared distances, RBF, linear and polynomial kernels.

Units: inputs are whatever the caller scaled (this module never rescales); ``sigma`` carries the unit of
the inputs. Conventions (docs/conventions.md, "Kernel and hyperparameters"):

* RBF ``K(x, z) = exp(-|x - z|^2 / sigma^2)`` - ``sigma^2`` in the denominator, no factor 2
  (Yu et al. 2013, after Suykens). The kernel width is ``sigma``, never ``gamma``: in this project
  ``gamma`` is the LSSVM regularisation (see :mod:`gyrodrift.lssvr`).
* linear ``K(x, z) = x . z``.
* polynomial ``K(x, z) = (x . z / sigma^2 + coef0)^degree``.

Conversions for cross-checks against other libraries:

* scikit-learn (``sklearn.metrics.pairwise``): ``rbf_kernel(gamma=1/sigma^2)``,
  ``polynomial_kernel(gamma=1/sigma^2, coef0=coef0, degree=degree)``, ``linear_kernel``.
* LS-SVMlab 1.8: ``sig2 = sigma^2 / 2`` (docs/conventions.md; this assumes LS-SVMlab's
  ``RBF_kernel`` is ``exp(-|x - z|^2 / (2 sig2))`` - not re-verified against LS-SVMlab here).
"""

from __future__ import annotations

import numbers

import numpy as np
from scipy.spatial.distance import cdist, pdist, squareform

#: Kernel names accepted by :func:`kernel_matrix` ("polynomial" is an alias of "poly", as in scikit-learn).
KERNELS = ("rbf", "linear", "poly", "polynomial")


def check_positive(name: str, value) -> float:
    """Return ``value`` as a float if it is a finite real number > 0, else raise ``ValueError``.

    The message names the parameter and the offending value, e.g.
    ``"sigma must be a finite number > 0, got -1.0"``.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    as_float = float(value)
    if not (np.isfinite(as_float) and as_float > 0.0):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return as_float


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
    sigma = check_positive("sigma", sigma)
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
    ``coef0 < 0`` it may be indefinite and an LSSVM fit may fail (see :mod:`gyrodrift.lssvr`).
    scikit-learn equivalent: ``polynomial_kernel(gamma=1/sigma^2, coef0=coef0, degree=degree)``.
    """
    sigma = check_positive("sigma", sigma)
    degree = _check_degree(degree)
    if isinstance(coef0, bool) or not isinstance(coef0, numbers.Real) or not np.isfinite(coef0):
        raise ValueError(f"coef0 must be a finite real number, got {coef0!r}")
    return (linear_kernel(X, Z) / (sigma * sigma) + float(coef0)) ** degree


def _check_degree(degree) -> int:
    """Integer >= 1; integral floats such as 3.0 (e.g. from a parameter grid) are accepted."""
    ok = (
        not isinstance(degree, bool)
        and isinstance(degree, numbers.Real)
        and np.isfinite(degree)
        and float(degree).is_integer()
        and degree >= 1
    )
    if not ok:
        raise ValueError(f"degree must be an integer >= 1, got {degree!r}")
    return int(degree)


def check_kernel(kernel) -> str:
    """Return the canonical kernel name ("rbf", "linear" or "poly"), or raise ``ValueError``."""
    if not isinstance(kernel, str) or kernel not in KERNELS:
        raise ValueError(f"unknown kernel {kernel!r}; expected one of {', '.join(map(repr, KERNELS))}")
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
    sigma = check_positive("sigma", sigma)
    if kernel == "rbf":
        return rbf_kernel(X, Z, sigma)
    if kernel == "linear":
        return linear_kernel(X, Z)
    return polynomial_kernel(X, Z, sigma=sigma, degree=degree, coef0=coef0)
