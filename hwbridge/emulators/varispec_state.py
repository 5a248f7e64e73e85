"""The state machine of a VariSpec liquid-crystal tunable filter controller, as seen on its wire.

Protocol (CRi VariSpec user manual 1.37): ASCII commands terminated by CR; the controller echoes
each command line, then for queries sends one answer line. ``W <nm>`` tunes, ``W?`` answers
``W <nm>`` (``W*`` after an out-of-range request), ``V?`` answers revision, shortest and longest
wavelength and serial number, ``I1`` initializes, ``E1`` exercises, ``R?`` answers the error
code, ``R1`` clears it, ``B0``/``G0`` select standard comms and disable the TTL port. The single
bytes ``@`` (status: bit 0 initialized, bit 1 exercised, bit 5 error) and ``!`` (``>`` ready,
``<`` busy) answer two bytes without a CR.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

__all__ = ["VariSpecState"]

ERROR_OUT_OF_RANGE = 3
ERROR_UNKNOWN_COMMAND = 1
ERROR_NOT_INITIALIZED = 4


@dataclass
class VariSpecState:
    """Controller state; ``respond`` turns bytes from the host into bytes to the host."""

    shortest_nm: float = 400.0
    longest_nm: float = 720.0
    revision: str = "1.37"
    serial_number: str = "10218"
    settle_s: float = 0.05
    initialized: bool = False
    exercised: bool = True
    wavelength_nm: float | None = None
    error: int = 0
    busy_until: float = 0.0
    garble: bool = False  # answer nonsense (tests of the driver's error handling)
    _line: bytearray = field(default_factory=bytearray)

    def respond(self, data: bytes) -> bytes:
        out = bytearray()
        for byte in data:
            character = bytes([byte])
            if character == b"@" and not self._line:
                out += b"@" + bytes([self._status()])
            elif character == b"!" and not self._line:
                out += b"!" + (b"<" if time.monotonic() < self.busy_until else b">")
            elif character == b"\r":
                out += self._command(self._line.decode("ascii", "replace"))
                self._line.clear()
            else:
                self._line += character
        return bytes(out)

    def due(self, now: float) -> bytes:
        """The controller never speaks unasked."""
        return b""

    def _status(self) -> int:
        return (
            (0x01 if self.initialized else 0)
            | (0x02 if self.exercised else 0)
            | (0x20 if self.error else 0)
        )

    def _command(self, line: str) -> bytes:
        if self.garble:
            return b"?garbled\r"
        echo = (line + "\r").encode("ascii")
        command = line.strip()
        if command == "W?":
            if self.error == ERROR_OUT_OF_RANGE or self.wavelength_nm is None:
                return echo + b"W*\r"
            return echo + f"W {self.wavelength_nm:.3f}\r".encode()
        if command.startswith("W "):
            self._tune(command[2:])
            return echo
        if command == "V?":
            return (
                echo
                + (
                    f"V {self.revision} {self.shortest_nm:.3f} {self.longest_nm:.3f} "
                    f"{self.serial_number}\r"
                ).encode()
            )
        if command == "R?":
            return echo + f"R {self.error}\r".encode()
        if command == "R1":
            self.error = 0
            return echo
        if command == "I1":
            self.initialized, self.busy_until = True, time.monotonic() + self.settle_s
            return echo
        if command == "E1":
            self.exercised, self.busy_until = True, time.monotonic() + self.settle_s
            return echo
        if command in ("B0", "G0"):
            return echo
        self.error = ERROR_UNKNOWN_COMMAND
        return echo

    def _tune(self, argument: str) -> None:
        if not self.initialized:
            self.error = ERROR_NOT_INITIALIZED
            return
        try:
            wavelength = float(argument)
        except ValueError:
            self.error = ERROR_UNKNOWN_COMMAND
            return
        if not self.shortest_nm <= wavelength <= self.longest_nm:
            self.error = ERROR_OUT_OF_RANGE
            return
        self.wavelength_nm = wavelength
        self.busy_until = time.monotonic() + self.settle_s
