"""An Enttec DMX USB Pro with constant-current LED decoders on its DMX line, as seen on its wire.

Protocol: Enttec, *DMX USB Pro Widget API Specification 1.44*, section "Message Format" (start of
message 0x7E, label, data length LSB and MSB, data, end of message 0xE7) and the messages

- "Get Widget Parameters Request (Label=3)" (data: the size of the user configuration to read,
  LSB, MSB) and its reply: firmware version LSB, MSB, DMX output break time in 10.67 us units
  (9-127), mark-after-break time in 10.67 us units (1-127), DMX output rate in packets per second
  (0-40), then the user configuration;
- "Output Only Send DMX Packet Request (Label=6)": the DMX packet, start code first, 25 to 513
  bytes; the widget sends it out of its DMX port at its output rate until it receives a request
  other than this one or Get Widget Parameters;
- "Get Widget Serial Number Request (Label=10)", answered with the serial number in 4 bytes of
  binary-coded decimal, least significant byte first.

Requests with other labels stop the DMX output and get no answer; a message without its end
byte is dropped.

On the DMX line (ANSI E1.11, DMX512-A: one universe of 512 slots; dimmer data under start code 0)
hang ``decoders`` constant-current LED decoders of ``outputs`` channels each, their start
addresses set one after the other from ``first_address`` (9 decoders of 24 outputs hold the
dome's 198 LEDs on slots 1-198). Slot level ``v`` sets an output's PWM duty to ``v / 255`` of its
constant current ``full_scale_ma``; a decoder keeps its outputs when the DMX signal stops.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

import numpy as np

from hwbridge.emulators.emulated_port import MessageDeviceState

__all__ = ["DmxUsbProState", "widget_message"]

START, END = 0x7E, 0xE7
GET_PARAMETERS, SEND_DMX, RECEIVED_DMX, GET_SERIAL = 3, 6, 5, 10
UNIVERSE_SLOTS = 512


def widget_message(label: int, data: bytes = b"") -> bytes:
    """One framed message of the widget API."""
    return struct.pack("<BBH", START, label, len(data)) + data + bytes([END])


@dataclass
class DmxUsbProState(MessageDeviceState):
    """The widget and its decoders; ``respond`` turns bytes from the host into bytes to it.

    Fault injection (tests of the driver): ``garble`` answers noise, ``wrong_label`` answers with
    a Received DMX Packet (label 5, as a widget switched to receiving sends), ``silent`` answers
    nothing.
    """

    serial_number: str = "02015678"
    firmware_version: int = (1 << 8) | 44  # 1.44
    break_time: int = 9
    mark_after_break_time: int = 1
    output_rate: int = 40
    decoders: int = 9
    outputs: int = 24
    first_address: int = 1
    full_scale_ma: float = 700.0
    garble: bool = False
    wrong_label: bool = False
    transmitting: bool = False
    universe: bytearray = field(default_factory=lambda: bytearray(UNIVERSE_SLOTS))

    def output_currents_ma(self) -> np.ndarray:
        """Mean current of every decoder output, ``(decoders, outputs)`` in mA."""
        first = self.first_address - 1  # slot 1 is universe[0]
        levels = np.frombuffer(self.universe, np.uint8)[
            first : first + self.decoders * self.outputs
        ]
        return levels.reshape(self.decoders, self.outputs) / 255.0 * self.full_scale_ma

    def _next_message(self) -> tuple[int, bytes] | None:
        while self._inbox:
            if self._inbox[0] != START:
                del self._inbox[0]
                continue
            if len(self._inbox) < 4:
                return None
            label, length = struct.unpack_from("<BH", self._inbox, 1)
            if len(self._inbox) < 5 + length:
                return None
            if self._inbox[4 + length] != END:
                del self._inbox[0]  # not a message: look for the next start byte
                continue
            data = bytes(self._inbox[4 : 4 + length])
            del self._inbox[: 5 + length]
            return label, data
        return None

    def _handle(self, label: int, data: bytes) -> bytes:
        if label == SEND_DMX:
            if 25 <= len(data) <= UNIVERSE_SLOTS + 1 and data[0] == 0:
                self.universe[: len(data) - 1] = data[1:]
                self.transmitting = True
            return b""
        if label == GET_PARAMETERS and len(data) == 2:
            (user_size,) = struct.unpack("<H", data)
            reply = struct.pack(
                "<HBBB",
                self.firmware_version,
                self.break_time,
                self.mark_after_break_time,
                self.output_rate,
            )
            return self._reply(GET_PARAMETERS, reply + bytes(user_size))
        self.transmitting = False
        if label == GET_SERIAL:
            bcd = bytes.fromhex(self.serial_number)[::-1]
            return self._reply(GET_SERIAL, bcd)
        return b""

    def _spoil(self, answers: bytes) -> bytes:
        return b"\x00\xff?garbled" if answers and self.garble else answers

    def _reply(self, label: int, data: bytes) -> bytes:
        return widget_message(RECEIVED_DMX if self.wrong_label else label, data)
