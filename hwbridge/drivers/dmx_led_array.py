"""Driver of the dome's LED array: DMX512 LED decoders behind an Enttec DMX USB Pro, over pyserial.

Implements ``hwbridge.protocols.LedArray``. The dome has 198 LEDs of 2.5 W that are switched
individually (thesis 10.2.1) and all together for the alignment frames (10.2.2). Choice: one
DMX512 universe (ANSI E1.11, DMX512-A) carries 512 dimmer levels, so every LED gets a slot of
its own on one cable: constant-current DMX LED decoders (9 of 24 outputs for 198 LEDs) are
daisy-chained on the line, each listening from its start address, so LED ``i`` is slot
``first_address + i``. The Enttec DMX USB Pro puts the universe on the line from USB with a
documented serial API (*DMX USB Pro Widget API Specification 1.44*, see
:mod:`hwbridge.emulators.dmx_usb_pro_state`). Multi-channel LED drivers with their own command
sets (Thorlabs DC4100, Mightex SLC) have 2-4 channels: 198 LEDs would need 50 or more of them.

Drive current: a decoder output drives its LED at a constant current ``full_scale_ma`` with the
PWM duty of its slot's level ``v / 255``; the driver speaks of the mean current, in steps of
``full_scale_ma / 255``. DMX is one-way: the decoders confirm nothing. The widget does: after
each change the driver asks its parameters (label 3, the one request that keeps the DMX output
running), so a widget that has gone or answers nonsense is caught before a frame is exposed.
``read`` reports the currents of the universe the widget acknowledged.

Open a real widget by name (``/dev/ttyUSB0``) or the emulator as ``dmxusbpro://``.
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np
import serial

import hwbridge.emulators  # noqa: F401  (registers the dmxusbpro:// URL handler)
from hwbridge.dome_targets import check_current_ma, led_pattern, single_led
from hwbridge.drivers.serial_wire import open_port, wire
from hwbridge.errors import DeviceError, DeviceTimeout, InputError
from hwbridge.protocols import description, reading

__all__ = ["DmxLedArray"]

_START, _END = 0x7E, 0xE7
_GET_PARAMETERS, _SEND_DMX, _GET_SERIAL = 3, 6, 10
_UNIVERSE_SLOTS, _SHORTEST_PACKET_SLOTS, _LEVELS = 512, 24, 255
_LONGEST_MESSAGE = 600  # data bytes of a widget message


class DmxLedArray:
    """``count`` LEDs on DMX slots ``first_address``.. behind the DMX USB Pro on ``port``.

    Parameters
    ----------
    port
        ``/dev/ttyUSB0``, ``COM3`` or ``dmxusbpro://`` (the emulator).
    count
        LEDs, one slot each.
    first_address
        DMX slot (1-512) of LED 0.
    full_scale_ma
        The decoders' constant output current (slot level 255).
    drive_current_ma
        Current of the LEDs a pattern switches on without naming one (default: full scale).
    name
        Prefix of the reading's key.
    timeout_s
        The longest wait for the widget's answer.
    """

    def __init__(
        self,
        port: str,
        *,
        count: int = 198,
        first_address: int = 1,
        full_scale_ma: float = 700.0,
        drive_current_ma: float | None = None,
        name: str = "leds",
        timeout_s: float = 1.0,
    ):
        if not (count >= 1 and first_address >= 1 and first_address + count - 1 <= _UNIVERSE_SLOTS):
            raise InputError(
                f"{name}: {count} LEDs from slot {first_address} do not fit the "
                f"{_UNIVERSE_SLOTS} slots of a DMX universe"
            )
        self.name, self.count = name, count
        self._port_name, self._first_address = port, first_address
        self._full_scale_ma, self._timeout_s = full_scale_ma, timeout_s
        self._drive_current_ma = check_current_ma(
            full_scale_ma if drive_current_ma is None else drive_current_ma,
            self.current_range_ma,
            name,
        )
        self._port: serial.Serial | None = None
        self._levels = np.zeros(count, np.uint8)
        self._widget: dict[str, Any] = {}

    @property
    def current_step_ma(self) -> float:
        return self._full_scale_ma / _LEVELS

    @property
    def current_range_ma(self) -> tuple[float, float]:
        return (self.current_step_ma, self._full_scale_ma)

    # -- staging -----------------------------------------------------------------------------

    def stage(self) -> None:
        """Open the port, read the widget's serial number and parameters, switch all LEDs off."""
        self.unstage()
        try:
            self._port = open_port(
                self._port_name, self.name, baudrate=57600, timeout=self._timeout_s
            )
            # The serial number first: asking it stops the DMX output, which starts below.
            serial_bcd = self._request(_GET_SERIAL, b"", "Get Widget Serial Number")
            if len(serial_bcd) != 4 or not serial_bcd[::-1].hex().isdigit():
                raise DeviceError(
                    f"{self.name}: expected a 4-byte BCD serial number, got {serial_bcd!r}"
                )
            self._widget = {"serial": serial_bcd[::-1].hex(), **self._parameters()}
            self._send_universe(np.zeros(self.count, np.uint8))
        except BaseException:
            self.unstage()  # a half-staged widget leaves no port open
            raise

    def unstage(self) -> None:
        if self._port is not None:
            self._port.close()
            self._port = None

    # -- LedArray ------------------------------------------------------------------------------

    def set(self, pattern: np.ndarray, current_ma: float | None = None) -> None:
        """Switch the LEDs of ``pattern`` on at ``current_ma`` (``None``: the drive current) and
        all others off."""
        pattern = led_pattern(pattern, self.count, self.name)
        current = check_current_ma(
            self._drive_current_ma if current_ma is None else current_ma,
            self.current_range_ma,
            self.name,
        )
        level = round(current / self._full_scale_ma * _LEVELS)
        self._send_universe(np.where(pattern, level, 0).astype(np.uint8))

    def light(self, led: int, current_ma: float | None = None) -> None:
        """LED ``led`` alone on at ``current_ma`` (``None``: the drive current)."""
        self.set(single_led(led, self.count, self.name), current_ma)

    def read(self) -> dict[str, dict[str, Any]]:
        self._require_port()
        return reading(f"{self.name}_current_ma", self._levels * self.current_step_ma)

    def describe(self) -> dict[str, dict[str, Any]]:
        return description(
            f"{self.name}_current_ma",
            source=f"DMX512 via Enttec DMX USB Pro {self._widget.get('serial', '?')} on "
            f"{self._port_name}",
            dtype="array",
            shape=[self.count],
            units="mA",
        )

    def identity(self) -> dict[str, str]:
        """The widget's serial number (read at staging: asking it again would stop the DMX
        output) and firmware (asked now, with the parameters)."""
        self._widget |= self._parameters()
        return {
            "model": "Enttec DMX USB Pro",
            "serial": str(self._widget.get("serial", "?")),
            "firmware": str(self._widget["firmware"]),
        }

    @property
    def widget(self) -> dict[str, Any]:
        """The widget's serial number, firmware version and DMX timing, as read at staging."""
        return dict(self._widget)

    # -- wire ------------------------------------------------------------------------------------

    def _send_universe(self, levels: np.ndarray) -> None:
        """The DMX packet (start code 0, then slots 1..) with the LEDs' ``levels``; then the
        widget's parameters, to know it took the packet and is still there. Only then are the
        levels what ``read`` reports."""
        slots = np.zeros(
            max(self._first_address - 1 + self.count, _SHORTEST_PACKET_SLOTS), np.uint8
        )
        slots[self._first_address - 1 : self._first_address - 1 + self.count] = levels
        self._write(_SEND_DMX, b"\x00" + slots.tobytes())
        self._parameters()
        self._levels = levels

    def _parameters(self) -> dict[str, Any]:
        reply = self._request(_GET_PARAMETERS, struct.pack("<H", 0), "Get Widget Parameters")
        if len(reply) < 5:
            raise DeviceError(f"{self.name}: expected 5 bytes of widget parameters, got {reply!r}")
        firmware, break_time, mark_after_break, rate = struct.unpack_from("<HBBB", reply)
        if not (9 <= break_time <= 127 and 1 <= mark_after_break <= 127 and rate <= 40):
            raise DeviceError(
                f"{self.name}: implausible widget parameters (break {break_time}, mark after "
                f"break {mark_after_break}, rate {rate}); expected 9-127, 1-127, 0-40"
            )
        return {
            "firmware": f"{firmware >> 8}.{firmware & 0xFF}",
            "break_us": round(break_time * 10.67, 1),
            "mark_after_break_us": round(mark_after_break * 10.67, 1),
            "packets_per_s": rate,
        }

    def _require_port(self) -> serial.Serial:
        if self._port is None:
            raise DeviceError(f"{self.name}: not staged; call stage() first")
        return self._port

    def _write(self, label: int, data: bytes) -> None:
        message = struct.pack("<BBH", _START, label, len(data)) + data + bytes([_END])
        port = self._require_port()
        with wire(self.name):
            port.write(message)

    def _request(self, label: int, data: bytes, what: str) -> bytes:
        """Send a request and return the data of the widget's reply, which must carry ``label``."""
        port = self._require_port()
        with wire(self.name):
            port.reset_input_buffer()  # nothing stale is taken for the answer
        self._write(label, data)
        header = self._read(4, what)
        reply_label, length = struct.unpack_from("<BH", header, 1)
        if header[0] != _START or length > _LONGEST_MESSAGE:
            raise DeviceError(f"{self.name}: garbled answer to {what}: {header!r}")
        body = self._read(length + 1, what)
        if body[-1] != _END:
            raise DeviceError(
                f"{self.name}: garbled answer to {what}: no end byte 0xE7 after {length} bytes"
            )
        if reply_label != label:
            raise DeviceError(
                f"{self.name}: expected the {what} reply (label {label}), got label {reply_label}"
            )
        return body[:-1]

    def _read(self, size: int, what: str) -> bytes:
        port = self._require_port()
        with wire(self.name):
            data = port.read(size)
        if len(data) < size:
            raise DeviceTimeout(
                f"{self.name}: no complete answer to {what} within {self._timeout_s:g} s"
            )
        return data
