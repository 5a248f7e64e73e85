"""pyserial URL handler ``varispec://``: a serial port with an emulated VariSpec behind it.

Options in the URL query: ``varispec://?settle_ms=50&shortest=400&longest=720&initialized=0``
(``garble=1``: answers nonsense). Every port opened on the same URL talks to its own controller
state.
"""

from __future__ import annotations

from hwbridge.emulators.emulated_port import EmulatedPort
from hwbridge.emulators.varispec_state import VariSpecState

__all__ = ["Serial"]


class Serial(EmulatedPort):
    """A pyserial port whose far end is a :class:`VariSpecState`."""

    scheme = "varispec"
    options = {
        "settle_ms": "50",
        "shortest": "400",
        "longest": "720",
        "initialized": "0",
        "garble": "0",
    }

    @classmethod
    def make_state(cls, options: dict[str, str]) -> VariSpecState:
        return VariSpecState(
            settle_s=float(options["settle_ms"]) / 1000,
            shortest_nm=float(options["shortest"]),
            longest_nm=float(options["longest"]),
            initialized=options["initialized"] == "1",
            garble=options["garble"] == "1",
        )
