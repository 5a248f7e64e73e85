"""pyserial URL handler ``apt://``: a serial port with an emulated Thorlabs APT rotation stage.

Options in the URL query (defaults: a K10CR1 at 0 deg, not homed):
``apt://?speed=10&homed=0&angle=0&model=K10CR1&cw_limit=none`` and the faults ``garble=1``,
``wrong_reply=1``, ``silent=1``, ``stall=1``, and ``short_endings=1`` (see
:class:`AptStageState`). Every port opened on
the same URL talks to its own controller state.
"""

from __future__ import annotations

from hwbridge.emulators.apt_stage_state import AptStageState
from hwbridge.emulators.emulated_port import EmulatedPort

__all__ = ["Serial"]


class Serial(EmulatedPort):
    """A pyserial port whose far end is an :class:`AptStageState`."""

    scheme = "apt"
    options = {
        "speed": "10",
        "homed": "0",
        "angle": "0",
        "model": "K10CR1",
        "cw_limit": "none",
        "garble": "0",
        "wrong_reply": "0",
        "silent": "0",
        "stall": "0",
        "short_endings": "0",
    }

    @classmethod
    def make_state(cls, options: dict[str, str]) -> AptStageState:
        state = AptStageState(
            model=options["model"],
            speed_deg_s=float(options["speed"]),
            homed=options["homed"] == "1",
            cw_limit_deg=None if options["cw_limit"] == "none" else float(options["cw_limit"]),
            garble=options["garble"] == "1",
            wrong_reply=options["wrong_reply"] == "1",
            silent=options["silent"] == "1",
            stall=options["stall"] == "1",
            short_endings=options["short_endings"] == "1",
        )
        state.position = round(float(options["angle"]) * state.counts_per_deg)
        return state
