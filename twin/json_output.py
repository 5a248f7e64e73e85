"""JSON for the metrics files of the CLI commands: NumPy scalars and arrays become plain values."""

from __future__ import annotations

import json

import numpy as np

__all__ = ["dumps"]


def _plain(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serializable: {type(value).__name__}")


def dumps(value) -> str:
    """``value`` as indented JSON, NumPy values converted."""
    return json.dumps(value, indent=2, default=_plain)
