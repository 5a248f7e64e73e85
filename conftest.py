"""Fixtures shared by the tests and by the docstring examples of twin, recon and hwbridge."""

import importlib

import numpy as np
import pytest

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
