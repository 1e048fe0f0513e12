"""Test helpers shipped with the package (as ``numpy.testing``): nothing in the library imports this package.

``gyrodrift.testing.reference_nav`` is a plain numpy strapdown navigator, the tests' independent oracle for
the Rust navigator (and the reference of benchmarks/bench_navigation.py).

Standard optimisation test functions (global minimum 0), for checking and benchmarking optimisers such as
:func:`gyrodrift.learn.cpso.minimize_cpso`. Each takes a 1-D point ``x`` and returns a float. Minima: sphere,
rastrigin, ackley, griewank at 0; rosenbrock at (1, ..., 1). Used by tests/learn/test_cpso.py and by
benchmarks/bench_cpso_chaos_vs_plain.py.
"""

from __future__ import annotations

import numpy as np

__all__ = ["sphere", "rastrigin", "rosenbrock", "ackley", "griewank"]


def sphere(x) -> float:
    """sum x_i^2."""
    return float(np.sum(x**2))


def rastrigin(x) -> float:
    """10 d + sum (x_i^2 - 10 cos 2 pi x_i): many regularly spaced local minima."""
    return float(10.0 * x.size + np.sum(x**2 - 10.0 * np.cos(2.0 * np.pi * x)))


def rosenbrock(x) -> float:
    """sum 100 (x_{i+1} - x_i^2)^2 + (1 - x_i)^2: a curved narrow valley."""
    return float(np.sum(100.0 * (x[1:] - x[:-1] ** 2) ** 2 + (1.0 - x[:-1]) ** 2))


def ackley(x) -> float:
    """Ackley's function: a nearly flat outer region around a deep central hole."""
    d = x.size
    return float(
        -20.0 * np.exp(-0.2 * np.sqrt(np.sum(x**2) / d)) - np.exp(np.sum(np.cos(2.0 * np.pi * x)) / d) + 20.0 + np.e
    )


def griewank(x) -> float:
    """sum x_i^2 / 4000 - prod cos(x_i / sqrt(i)) + 1."""
    i = np.arange(1, x.size + 1)
    return float(np.sum(x**2) / 4000.0 - np.prod(np.cos(x / np.sqrt(i))) + 1.0)
