"""pyserial URL handler ``varispec://``: a serial port with an emulated VariSpec behind it.

Options in the URL query: ``varispec://?settle_ms=50&shortest=400&longest=720&initialized=0``.
Every port opened on the same URL talks to its own controller state.
"""

from __future__ import annotations

import time
import urllib.parse

from serial.serialutil import PortNotOpenError, SerialBase, SerialException, Timeout

from hwbridge.emulators.varispec_state import VariSpecState

__all__ = ["Serial"]


class Serial(SerialBase):
    """A pyserial port whose far end is a :class:`VariSpecState`."""

    def open(self) -> None:
        if self._port is None:
            raise SerialException("port must be configured before it can be used")
        if self.is_open:
            raise SerialException("port already open")
        self.state = self._state_from_url(self._port)
        self._buffer = bytearray()
        self.is_open = True

    def close(self) -> None:
        self.is_open = False

    def _reconfigure_port(self) -> None:
        """Baud rate and framing have no effect on an emulated wire."""

    @staticmethod
    def _state_from_url(url: str) -> VariSpecState:
        parts = urllib.parse.urlsplit(url)
        if parts.scheme != "varispec":
            raise SerialException(f"expected a varispec:// URL, got {url!r}")
        options = {key: values[-1] for key, values in urllib.parse.parse_qs(parts.query).items()}
        known = {"settle_ms", "shortest", "longest", "initialized", "garble"}
        unknown = set(options) - known
        if unknown:
            raise SerialException(
                f"varispec:// options: unknown {sorted(unknown)}, expected {sorted(known)}"
            )
        return VariSpecState(
            settle_s=float(options.get("settle_ms", 50)) / 1000,
            shortest_nm=float(options.get("shortest", 400)),
            longest_nm=float(options.get("longest", 720)),
            initialized=options.get("initialized", "0") == "1",
            garble=options.get("garble", "0") == "1",
        )

    @property
    def in_waiting(self) -> int:
        if not self.is_open:
            raise PortNotOpenError()
        return len(self._buffer)

    def read(self, size: int = 1) -> bytes:
        if not self.is_open:
            raise PortNotOpenError()
        timeout = Timeout(self._timeout)
        while len(self._buffer) < size and not timeout.expired():
            time.sleep(0.001)
        data = bytes(self._buffer[:size])
        del self._buffer[:size]
        return data

    def write(self, data: bytes) -> int:
        if not self.is_open:
            raise PortNotOpenError()
        self._buffer += self.state.respond(bytes(data))
        return len(data)

    def reset_input_buffer(self) -> None:
        self._buffer.clear()

    def reset_output_buffer(self) -> None:
        """Nothing is ever pending on the way out."""
