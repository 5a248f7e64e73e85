"""How spectwin writes numbers: rounded text for people, full-precision JSON for files.

Quantity names carry their unit as a suffix (``exposure_per_pair_s`` -> "exposure per pair",
"s"). Floats get 4 significant digits, long lists are shortened, dicts are written
``key: value, ...``. JSON converts NumPy scalars and arrays to plain values.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping, Sequence

import numpy as np

__all__ = ["SIGNIFICANT_DIGITS", "dumps", "format_pairs", "format_value", "quantity"]


def _plain(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serializable: {type(value).__name__}")


def dumps(value) -> str:
    """``value`` as indented JSON, NumPy values converted."""
    return json.dumps(value, indent=2, default=_plain)


# Suffix of a quantity name -> its unit (longest first; "_percent_"/"_pct_" may sit inside).
_UNITS = (
    ("_dn_per_e", "DN/e-"),
    ("_e_per_s", "e-/s"),
    ("_dn2", "DN^2"),
    ("_photons", "photons"),
    ("_dn", "DN"),
    ("_e", "e-"),
    ("_percent", "%"),
    ("_pct", "%"),
    ("_ms", "ms"),
    ("_s", "s"),
    ("_h", "h"),
    ("_days", "days"),
    ("_px", "px"),
    ("_nm", "nm"),
    ("_deg", "deg"),
    ("_mm", "mm"),
    ("_m", "m"),
    ("_bytes", "bytes"),
    ("_mb", "MB"),
)
_LABELS = {"all_multiples_of_1_15_s": "all multiples of 1/15 s"}
SIGNIFICANT_DIGITS = 4
_LIST_SHOWN = 6


def quantity(key: str) -> tuple[str, str]:
    """``(name, unit)`` of a summary key: ``"exposure_per_pair_s"`` -> ``("exposure per
    pair", "s")``; keys without a unit suffix give ``(key with spaces, "")``."""
    if key in _LABELS:
        return _LABELS[key], ""
    unit = ""
    for marker in ("_percent_", "_pct_"):
        if marker in key:
            key, unit = key.replace(marker, "_"), "%"
            break
    else:
        for suffix, name in _UNITS:
            if key.endswith(suffix) and len(key) > len(suffix) and not key.endswith("delta_e"):
                key, unit = key[: -len(suffix)], name
                break
    # "near_66_7ms" -> "near 66.7ms": an underscore between digits before a unit is a point.
    return re.sub(r"(?<=\d)_(?=\d+[a-z])", ".", key).replace("_", " "), unit


def _number(value: float) -> str:
    if not math.isfinite(value):
        return str(value)
    if value == 0:
        return "0"
    if 1e-3 <= abs(value) < 1e6:
        text = f"{value:.{SIGNIFICANT_DIGITS}g}"
        # .4g writes 12345.6 as 1.235e+04: keep whole numbers whole.
        return f"{value:.0f}" if "e" in text else text
    return f"{value:.{SIGNIFICANT_DIGITS - 1}e}"


def format_pairs(pairs: Sequence[int]) -> str:
    """Direction pairs (or any indices) as runs of consecutive numbers.

    Parameters
    ----------
    pairs
        Indices, in any order; repeated ones count once.

    Returns
    -------
    str
        Their count and runs, ``"156 pairs: 0-155"``, ``"4 pairs: 1, 3-5"``, ``"1 pair: 7"``.

    Examples
    --------
    >>> format_pairs([5, 3, 4, 1, 9, 10])
    '6 pairs: 1, 3-5, 9-10'
    """
    runs: list[list[int]] = []
    for pair in sorted(set(pairs)):
        if runs and pair == runs[-1][1] + 1:
            runs[-1][1] = pair
        else:
            runs.append([pair, pair])
    count = sum(last - first + 1 for first, last in runs)
    shown = ", ".join(str(first) if first == last else f"{first}-{last}" for first, last in runs)
    return f"{count} pair{'' if count == 1 else 's'}: {shown}"


def format_value(value: object) -> str:
    """A compact, rounded text of a summary value."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return _number(value)
    if isinstance(value, Mapping):
        return ", ".join(f"{key}: {format_value(item)}" for key, item in value.items())
    if isinstance(value, Sequence) and not isinstance(value, str):
        items = [format_value(item) for item in value]
        if len(items) > _LIST_SHOWN:
            items = [*items[: _LIST_SHOWN - 2], "...", items[-1]]
            return f"[{', '.join(items)}] ({len(value)} values)"
        return f"[{', '.join(items)}]"
    return str(value)
