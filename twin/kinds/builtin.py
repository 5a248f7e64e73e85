"""The rigs spectwin knows out of the box, in the order the commands list them."""

from __future__ import annotations

from twin.kinds.dome import DOME
from twin.kinds.gonio import GONIO

__all__ = ["BUILTIN_KINDS"]

BUILTIN_KINDS = (GONIO, DOME)
"""The spectral gonioreflectometer and the LED dome."""
