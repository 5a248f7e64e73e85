"""Driver of the CRi VariSpec liquid-crystal tunable filter (thesis 3.2.2) over a serial port.

Implements ``hwbridge.protocols.TunableFilter``. Every command line is checked against the
controller's echo; status (``@``) and busy (``!``) bytes are decoded; controller errors are read
(``R?``), cleared (``R1``) and raised. See ``hwbridge.emulators.varispec_state`` for the
protocol. Open a real port by name (``/dev/ttyUSB0``) or the emulator as ``varispec://``.
"""

from __future__ import annotations

import time
from typing import Any

import serial

import hwbridge.emulators  # noqa: F401  (registers the varispec:// URL handler)
from hwbridge.drivers.serial_wire import open_port, wire
from hwbridge.errors import DeviceError, DeviceTimeout, InputError
from hwbridge.protocols import description, reading

__all__ = ["VariSpec"]

_STATUS_INITIALIZED, _STATUS_EXERCISED, _STATUS_ERROR = 0x01, 0x02, 0x20


class VariSpec:
    """A VariSpec controller on ``port`` (device name or pyserial URL)."""

    def __init__(
        self,
        port: str,
        *,
        name: str = "lctf",
        timeout_s: float = 1.0,
        settle_timeout_s: float = 5.0,
    ):
        self.name = name
        self._port_name = port
        self._timeout_s = timeout_s
        self._settle_timeout_s = settle_timeout_s
        self._port: serial.SerialBase | None = None
        self._range_nm: tuple[float, float] | None = None
        self._version: dict[str, Any] = {}

    # -- staging -----------------------------------------------------------------------------

    def stage(self) -> None:
        """Open the port, select standard comms, initialize if needed, read version and range."""
        self._port = open_port(self._port_name, self.name, baudrate=9600, timeout=self._timeout_s)
        with wire(self.name):
            self._port.reset_input_buffer()
        self._command("B0")
        self._command("G0")
        status = self.status()
        if not status["exercised"]:
            self._command("E1")
            self._wait_until_ready()
        if not status["initialized"]:
            self._command("I1")
            self._wait_until_ready()
        self.identity()

    def identity(self) -> dict[str, str]:
        """The controller's serial number, firmware revision and range (``V?``)."""
        fields = self._query("V?").split()
        if len(fields) != 5 or fields[0] != "V":
            raise DeviceError(
                f"{self.name}: expected 'V <revision> <min> <max> <serial>' to V?, "
                f"got {' '.join(fields)!r}"
            )
        self._range_nm = (float(fields[2]), float(fields[3]))
        self._version = {"revision": fields[1], "serial": fields[4]}
        return {
            "model": f"VariSpec {float(fields[2]):g}-{float(fields[3]):g} nm",
            "serial": fields[4],
            "firmware": fields[1],
        }

    def unstage(self) -> None:
        if self._port is not None:
            self._port.close()
            self._port = None

    # -- TunableFilter ------------------------------------------------------------------------

    @property
    def range_nm(self) -> tuple[float, float]:
        if self._range_nm is None:
            raise DeviceError(f"{self.name}: not staged; call stage() first")
        return self._range_nm

    def set(self, wavelength_nm: float) -> None:
        """Tune and wait until the liquid crystals have settled."""
        low, high = self.range_nm
        if not low <= wavelength_nm <= high:
            raise InputError(
                f"{self.name}: wavelength {wavelength_nm} nm is outside the filter's range "
                f"{low}-{high} nm"
            )
        self._command(f"W {wavelength_nm:.3f}")
        self._raise_controller_error()
        self._wait_until_ready()

    def wavelength_nm(self) -> float:
        """The wavelength the controller reports (``W?``)."""
        answer = self._query("W?")
        if answer == "W*":
            self._raise_controller_error()
            raise DeviceError(f"{self.name}: the controller reports an out-of-range tuning (W*)")
        fields = answer.split()
        if len(fields) != 2 or fields[0] != "W":
            raise DeviceError(f"{self.name}: expected 'W <nm>' to W?, got {answer!r}")
        return float(fields[1])

    def read(self) -> dict[str, dict[str, Any]]:
        return reading(f"{self.name}_wavelength_nm", self.wavelength_nm())

    def describe(self) -> dict[str, dict[str, Any]]:
        return description(
            f"{self.name}_wavelength_nm",
            source=f"VariSpec {self._version.get('serial', '?')} on {self._port_name}",
            dtype="number",
            shape=[],
            units="nm",
        )

    # -- status --------------------------------------------------------------------------------

    def status(self) -> dict[str, bool]:
        """Decoded status byte (``@``)."""
        reply = self._exchange(b"@", 2)
        if reply[:1] != b"@":
            raise DeviceError(f"{self.name}: expected '@' and a status byte, got {reply!r}")
        byte = reply[1]
        return {
            "initialized": bool(byte & _STATUS_INITIALIZED),
            "exercised": bool(byte & _STATUS_EXERCISED),
            "error": bool(byte & _STATUS_ERROR),
        }

    def busy(self) -> bool:
        """Whether the liquid crystals are still switching (``!``)."""
        reply = self._exchange(b"!", 2)
        if reply == b"!<":
            return True
        if reply == b"!>":
            return False
        raise DeviceError(f"{self.name}: expected '!>' or '!<' to a busy check, got {reply!r}")

    # -- wire ------------------------------------------------------------------------------------

    def _require_port(self) -> serial.SerialBase:
        if self._port is None:
            raise DeviceError(f"{self.name}: not staged; call stage() first")
        return self._port

    def _exchange(self, request: bytes, reply_length: int) -> bytes:
        port = self._require_port()
        with wire(self.name):
            port.write(request)
            reply = port.read(reply_length)
        if len(reply) < reply_length:
            raise DeviceTimeout(f"{self.name}: no answer to {request!r} within {self._timeout_s} s")
        return reply

    def _read_line(self) -> str:
        port = self._require_port()
        with wire(self.name):
            line = port.read_until(b"\r")
        if not line.endswith(b"\r"):
            raise DeviceTimeout(f"{self.name}: incomplete line {line!r} within {self._timeout_s} s")
        return line[:-1].decode("ascii", "replace")

    def _command(self, command: str) -> None:
        port = self._require_port()
        with wire(self.name):
            port.write(command.encode("ascii") + b"\r")
        echo = self._read_line()
        if echo != command:
            raise DeviceError(f"{self.name}: sent {command!r}, the controller echoed {echo!r}")

    def _query(self, command: str) -> str:
        self._command(command)
        return self._read_line()

    def _raise_controller_error(self) -> None:
        if not self.status()["error"]:
            return
        answer = self._query("R?")
        self._command("R1")
        raise DeviceError(
            f"{self.name}: the controller reports error {answer.removeprefix('R ').strip()}"
        )

    def _wait_until_ready(self) -> None:
        deadline = time.monotonic() + self._settle_timeout_s
        while self.busy():
            if time.monotonic() > deadline:
                raise DeviceTimeout(f"{self.name}: still busy after {self._settle_timeout_s} s")
            time.sleep(0.005)
