"""The state machine of a Thorlabs APT stepper-motor rotation stage, as seen on its wire.

Protocol: Thorlabs, *Thorlabs Motion Controllers Host-Controller Communications Protocol*, the
message format (a 6-byte header: message id, then two 1-byte parameters or, when bit 7 of the
destination byte is set, the little-endian length of a data packet that follows; destination,
source; the host is 0x01, a USB stage controller 0x50) and the messages used here:

- ``MGMSG_HW_REQ_INFO`` (0x0005) answered by ``MGMSG_HW_GET_INFO`` (0x0006, 84 bytes: serial
  number, 8-character model number, type, firmware version, notes, hardware version, module
  state, number of channels);
- ``MGMSG_MOD_SET_CHANENABLESTATE`` (0x0210; parameter 2: 0x01 enable, 0x02 disable);
- ``MGMSG_MOT_MOVE_HOME`` (0x0443) ending in ``MGMSG_MOT_MOVE_HOMED`` (0x0444);
- ``MGMSG_MOT_MOVE_ABSOLUTE`` (0x0453, data: channel, position in counts) ending in
  ``MGMSG_MOT_MOVE_COMPLETED`` (0x0464) or, on a limit switch, ``MGMSG_MOT_MOVE_STOPPED``
  (0x0466), both followed by the 14-byte status (channel, position, encoder count, status bits);
- ``MGMSG_MOT_MOVE_STOP`` (0x0465) answered by ``MGMSG_MOT_MOVE_STOPPED``;
- ``MGMSG_MOT_REQ_STATUSUPDATE`` (0x0480) answered by ``MGMSG_MOT_GET_STATUSUPDATE`` (0x0481);
- ``MGMSG_MOT_REQ_POSCOUNTER`` (0x0411) answered by ``MGMSG_MOT_GET_POSCOUNTER`` (0x0412).

Status bits: 0x1 CW hardware limit, 0x2 CCW hardware limit, 0x10 moving CW, 0x20 moving CCW,
0x100 motor connected, 0x200 homing, 0x400 homed, 0x80000000 channel enabled. Unknown messages
and messages to another address are ignored, as a controller does.

The defaults are those of a K10CR1 rotation mount: 409600/3 microsteps per degree
(:data:`~hwbridge.drivers.apt_rotation_stage.K10CR1_COUNTS_PER_DEG`) and a top speed of
10 deg/s; a stepper
without an encoder, so its encoder count stays 0. Moves take ``|distance| / speed_deg_s``, homing
runs back to the home switch at 0. The K10CR1 turns freely; ``cw_limit_deg`` adds a CW limit
switch, as on stages of limited travel, where a move past it stops.

This module packs and parses the messages from the protocol document alone (``struct`` by hand):
it shares no code with the driver's protocol library, so the two check each other.
"""

from __future__ import annotations

import struct
import time
from dataclasses import dataclass

from hwbridge.drivers.apt_rotation_stage import K10CR1_COUNTS_PER_DEG
from hwbridge.emulators.emulated_port import MessageDeviceState

__all__ = ["AptStageState"]

HOST, CONTROLLER, CHANNEL = 0x01, 0x50, 1
HW_REQ_INFO, HW_GET_INFO = 0x0005, 0x0006
MOD_SET_CHANENABLESTATE = 0x0210
MOT_REQ_POSCOUNTER, MOT_GET_POSCOUNTER = 0x0411, 0x0412
MOT_MOVE_HOME, MOT_MOVE_HOMED = 0x0443, 0x0444
MOT_MOVE_ABSOLUTE, MOT_MOVE_COMPLETED = 0x0453, 0x0464
MOT_MOVE_STOP, MOT_MOVE_STOPPED = 0x0465, 0x0466
MOT_REQ_STATUSUPDATE, MOT_GET_STATUSUPDATE = 0x0480, 0x0481

CW_HARD_LIMIT, MOVING_CW, MOVING_CCW = 0x1, 0x10, 0x20
CONNECTED, HOMING, HOMED, ENABLED = 0x100, 0x200, 0x400, 0x80000000


def short_message(message_id: int, param1: int = 0, param2: int = 0) -> bytes:
    """A header-only message from the controller to the host."""
    return struct.pack("<HBBBB", message_id, param1, param2, HOST, CONTROLLER)


def long_message(message_id: int, data: bytes) -> bytes:
    """A header and ``data`` from the controller to the host."""
    return struct.pack("<HHBB", message_id, len(data), HOST | 0x80, CONTROLLER) + data


@dataclass
class _Motion:
    """A move (or homing run) from ``start`` to ``end`` counts over ``start_s``..``end_s``."""

    start: int
    end: int
    start_s: float
    end_s: float
    homing: bool
    limited: bool  # stops on the CW limit switch before its target

    def counts(self, now: float) -> int:
        if now >= self.end_s:
            return self.end
        fraction = (now - self.start_s) / (self.end_s - self.start_s)
        return round(self.start + fraction * (self.end - self.start))


@dataclass
class AptStageState(MessageDeviceState):
    """Controller state; ``respond`` turns bytes from the host into bytes to the host and ``due``
    sends the end of a move once it has arrived.

    Fault injection (tests of the driver): ``garble`` answers noise, ``wrong_reply`` answers every
    request with ``MGMSG_MOT_GET_POSCOUNTER``, ``silent`` answers nothing, ``stall`` starts moves
    that never end. ``short_endings`` ends moves with the header alone, without the status.
    """

    model: str = "K10CR1"
    serial_number: int = 55000001
    counts_per_deg: float = K10CR1_COUNTS_PER_DEG
    speed_deg_s: float = 10.0
    position: int = 0
    homed: bool = False
    enabled: bool = False
    cw_limit_deg: float | None = None
    garble: bool = False
    wrong_reply: bool = False
    stall: bool = False
    short_endings: bool = False
    _motion: _Motion | None = None

    def due(self, now: float) -> bytes:
        motion = self._motion
        if motion is None or self.stall or now < motion.end_s:
            return b""
        self._motion, self.position = None, motion.end
        if motion.homing:
            self.homed = True
            return self._spoil(short_message(MOT_MOVE_HOMED, CHANNEL))
        ending = MOT_MOVE_STOPPED if motion.limited else MOT_MOVE_COMPLETED
        if self.short_endings:
            return self._spoil(short_message(ending, CHANNEL))
        return self._spoil(long_message(ending, self._status(now)))

    def angle_deg(self, now: float) -> float:
        """Where the stage is, in degrees."""
        return self._counts(now) / self.counts_per_deg

    # -- the wire ---------------------------------------------------------------------------

    def _next_message(self) -> tuple[int, int, int, bytes] | None:
        """The next whole message for this controller in the inbox: id, parameters, data."""
        while len(self._inbox) >= 6:
            message_id, param1, param2, destination, source = struct.unpack_from(
                "<HBBBB", self._inbox
            )
            length = struct.unpack_from("<H", self._inbox, 2)[0] if destination & 0x80 else 0
            if len(self._inbox) < 6 + length:
                return None
            data = bytes(self._inbox[6 : 6 + length])
            del self._inbox[: 6 + length]
            if (destination & 0x7F, source) == (CONTROLLER, HOST):
                return message_id, param1, param2, data
        return None

    def _spoil(self, answers: bytes) -> bytes:
        if not answers:
            return answers
        if self.garble:
            return b"\xff\xfe?garbled\r\n"
        if self.wrong_reply:
            return long_message(MOT_GET_POSCOUNTER, struct.pack("<Hl", CHANNEL, self.position))
        return answers

    def _handle(self, message_id: int, param1: int, param2: int, data: bytes) -> bytes:
        now = time.monotonic()
        if message_id == HW_REQ_INFO:
            return long_message(HW_GET_INFO, self._info())
        if message_id == MOD_SET_CHANENABLESTATE and param1 == CHANNEL:
            self.enabled = param2 == 0x01
        elif message_id == MOT_MOVE_HOME and self.enabled:
            self._start(0, now, homing=True)
        elif message_id == MOT_MOVE_ABSOLUTE and self.enabled and len(data) == 6:
            _, target = struct.unpack("<Hl", data)
            self._start(target, now, homing=False)
        elif message_id == MOT_MOVE_STOP:
            self.position, self._motion = self._counts(now), None
            return long_message(MOT_MOVE_STOPPED, self._status(now))
        elif message_id == MOT_REQ_STATUSUPDATE:
            return long_message(MOT_GET_STATUSUPDATE, self._status(now))
        elif message_id == MOT_REQ_POSCOUNTER:
            return long_message(MOT_GET_POSCOUNTER, struct.pack("<Hl", CHANNEL, self._counts(now)))
        return b""

    # -- the mechanics ----------------------------------------------------------------------

    def _info(self) -> bytes:
        return struct.pack(
            "<l8sH4s48s12sHHH",
            self.serial_number,
            self.model.encode("ascii"),
            0,  # hardware type: the driver does not read it
            bytes([3, 0, 2, 0]),  # firmware 2.0.3 (minor, interim, major, unused)
            b"APT stepper rotation stage (emulated)",
            b"",
            1,  # hardware version
            0,  # module state
            1,  # channels
        )

    def _counts(self, now: float) -> int:
        if self._motion is None:
            return self.position
        return self._motion.start if self.stall else self._motion.counts(now)

    def _limit_counts(self) -> int | None:
        if self.cw_limit_deg is None:
            return None
        return round(self.cw_limit_deg * self.counts_per_deg)

    def _start(self, target: int, now: float, *, homing: bool) -> None:
        start = self._counts(now)
        limit = self._limit_counts()
        end, limited = target, False
        if limit is not None and target > start and target > limit:
            end, limited = min(target, max(limit, start)), True
        counts_per_s = self.speed_deg_s * self.counts_per_deg
        self.position = start
        self._motion = _Motion(
            start, end, now, now + abs(end - start) / counts_per_s, homing, limited
        )

    def _status(self, now: float) -> bytes:
        counts = self._counts(now)
        limit = self._limit_counts()
        bits = CONNECTED | (ENABLED if self.enabled else 0) | (HOMED if self.homed else 0)
        if limit is not None and counts >= limit:
            bits |= CW_HARD_LIMIT
        motion = self._motion
        if motion is not None and (self.stall or now < motion.end_s):
            bits |= HOMING if motion.homing else 0
            bits |= MOVING_CW if motion.end > motion.start else MOVING_CCW
        return struct.pack("<HllL", CHANNEL, counts, 0, bits)
