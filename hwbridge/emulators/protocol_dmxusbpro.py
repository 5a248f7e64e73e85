"""pyserial URL handler ``dmxusbpro://``: a serial port with an emulated Enttec DMX USB Pro and
the dome's LED decoders behind it.

Options in the URL query (defaults: 9 decoders of 24 outputs from slot 1, 700 mA full scale):
``dmxusbpro://?decoders=9&outputs=24&first_address=1&full_scale_ma=700`` and the faults
``garble=1``, ``wrong_label=1``, ``silent=1`` (see :class:`DmxUsbProState`). Every port opened
on the same URL talks to its own widget.
"""

from __future__ import annotations

from hwbridge.emulators.dmx_usb_pro_state import DmxUsbProState
from hwbridge.emulators.emulated_port import EmulatedPort

__all__ = ["Serial"]


class Serial(EmulatedPort):
    """A pyserial port whose far end is a :class:`DmxUsbProState`."""

    scheme = "dmxusbpro"
    options = {
        "decoders": "9",
        "outputs": "24",
        "first_address": "1",
        "full_scale_ma": "700",
        "garble": "0",
        "wrong_label": "0",
        "silent": "0",
    }

    @classmethod
    def make_state(cls, options: dict[str, str]) -> DmxUsbProState:
        return DmxUsbProState(
            decoders=int(options["decoders"]),
            outputs=int(options["outputs"]),
            first_address=int(options["first_address"]),
            full_scale_ma=float(options["full_scale_ma"]),
            garble=options["garble"] == "1",
            wrong_label=options["wrong_label"] == "1",
            silent=options["silent"] == "1",
        )
