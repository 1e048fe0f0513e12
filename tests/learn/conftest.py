"""The learn room's tests run with one BLAS thread, as `gyrodrift.learn.tuning.tune_lssvr` runs its own
factorisations: their matrices are small (tens to hundreds of rows), where OpenBLAS's second thread gives no time
and costs CPU while it waits, and under ``pytest -n auto`` each worker's BLAS threads compete with the other
worker. A test compares values computed in its own process under this one limit (scikit-learn's and gyrodrift's
alike), so what it asserts does not depend on it. Measured at 824401c (``pytest tests/learn -n 0``, user + sys CPU
of the tests summed, one process on the loaded shared 2-core machine): 47 s with the default threads, 32 s with this
fixture; the same 535 tests pass."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from threadpoolctl import threadpool_limits


@pytest.fixture(autouse=True, scope="module")
def one_blas_thread() -> Iterator[None]:
    """One BLAS thread for the module's tests; the previous limits come back after them."""
    with threadpool_limits(limits=1, user_api="blas"):
        yield
