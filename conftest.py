"""Fixtures shared by the tests and by the docstring examples of twin, recon and hwbridge."""

import importlib
import os

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
"""The variables that size the BLAS and OpenMP thread pools of numpy, scipy and their kin."""


def pytest_configure(config: pytest.Config) -> None:
    """Each of several test workers gets its share of the cores for BLAS and OpenMP threads, in
    this process and in the processes its tests start (notebook kernels, commands), unless the
    variables are set already. Each worker's library pools are sized for the whole machine
    otherwise: two workers on two cores ran four BLAS threads, whose spinning cost a sixth of
    the suite's CPU time (BENCHMARKS.md, "The test suite")."""
    workers = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
    if workers < 2:
        return
    threads = max(1, (os.cpu_count() or 1) // workers)
    for name in THREAD_VARIABLES:
        os.environ.setdefault(name, str(threads))
    threadpool_limits(int(os.environ["OPENBLAS_NUM_THREADS"]))


NUMPY_DEFAULT_PRINT_OPTIONS = {
    "edgeitems": 3,
    "threshold": 1000,
    "floatmode": "maxprec",
    "precision": 8,
    "suppress": False,
    "linewidth": 75,
    "nanstr": "nan",
    "infstr": "inf",
    "sign": "-",
    "formatter": None,
    "legacy": False,
}
"""numpy's print options as numpy sets them, which the docstring examples are written for."""


@pytest.fixture(autouse=True)
def numpy_default_printing(request):
    """Docstring examples print arrays with numpy's default options, whatever was imported.

    colour-science calls ``np.set_printoptions(legacy="1.13")`` when it is imported; it is
    imported first, so that its change lands before the defaults are set, not in the middle of
    an example. The options in force before the example are restored after it.
    """
    if not isinstance(request.node, pytest.DoctestItem):
        yield
        return
    importlib.import_module("colour")
    with np.printoptions(**NUMPY_DEFAULT_PRINT_OPTIONS):
        yield
