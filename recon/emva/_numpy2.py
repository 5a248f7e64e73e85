"""emva1288 1.0.2 on NumPy 2: the two NumPy names it still calls, given back to it alone.

``emva1288.process.routines`` calls ``np.asfarray`` (removed in NumPy 2.0) in its linear fits
and ``np.int`` (removed in NumPy 1.24) when rounding results. Rather than restoring the aliases
on NumPy itself, that one module's ``np`` is replaced by a view of NumPy that adds them; every
other module, and NumPy, stays as it is. The shim is idempotent and does nothing on a NumPy that
still has both names.
"""

from __future__ import annotations

import types

import numpy as np
from emva1288.process import routines

__all__ = ["patch_emva1288"]


class _NumPyWithRemovedAliases(types.ModuleType):
    """NumPy as seen by ``emva1288.process.routines``: every name of NumPy, plus the aliases
    NumPy 2 removed."""

    def __getattr__(self, name: str) -> object:
        return getattr(np, name)

    @staticmethod
    def asfarray(values: object, dtype: type = float) -> np.ndarray:
        return np.asarray(values, dtype=dtype)

    int = int


def patch_emva1288() -> None:
    """Give ``emva1288.process.routines`` the NumPy names it needs (once; harmless twice)."""
    if not (hasattr(np, "asfarray") and hasattr(np, "int")) and routines.np is np:
        routines.np = _NumPyWithRemovedAliases("numpy")
