"""Driver of a Thorlabs rotation stage over the APT protocol (a K10CR1 by default).

Implements ``hwbridge.protocols.RotationStage`` for the dome's rotation stage under the sample
(thesis 10.2.2: 24 positions, 15 deg apart). Choice: Thorlabs' APT stages are the common
motorized rotation stages of optics labs, their USB controllers speak one documented binary
protocol (*Thorlabs Motion Controllers Host-Controller Communications Protocol*, see
:mod:`hwbridge.emulators.apt_stage_state`) over an FTDI serial port, and the K10CR1 (a stepper
rotation mount with its controller built in, 360 deg continuous) needs no separate controller.
A heavier stage (HDR50 on a BSC201, PRM1 on a KDC101) speaks the same messages: pass its
``model`` and ``counts_per_deg``.

Messages are packed and unpacked by ``thorlabs-apt-protocol`` (the yaq project's
implementation of the protocol, MIT licence; install the extra ``spectwin[rotation-stage]``);
``thorlabs-apt-device`` and ``pylablib`` were not taken: both are GPL and run their own polling
threads. The bytes go through pyserial: a real port by name (``/dev/ttyUSB0``: 115200 baud, 8N1,
RTS/CTS, as the protocol document prescribes) or the emulator as ``apt://``.

``stage`` asks ``MGMSG_HW_REQ_INFO`` and checks the model, enables the channel, and homes
(``MGMSG_MOT_MOVE_HOME``, waiting for ``MGMSG_MOT_MOVE_HOMED``) unless the status says homed.
``set`` sends ``MGMSG_MOT_MOVE_ABSOLUTE`` in microsteps and waits for
``MGMSG_MOT_MOVE_COMPLETED``; a move that ends in ``MGMSG_MOT_MOVE_STOPPED``, with a limit switch
or a motion error in its status bits, or elsewhere than asked raises :class:`DeviceError`; none
within ``move_timeout_s`` stops the motor and raises :class:`DeviceTimeout`. Garbled bytes and
unexpected messages raise :class:`DeviceError`. ``read`` asks ``MGMSG_MOT_REQ_POSCOUNTER``.
"""

from __future__ import annotations

import struct
import time
from typing import Any

import serial

import hwbridge.emulators  # noqa: F401  (registers the apt:// URL handler)
from hwbridge.dome_targets import stage_angle_deg
from hwbridge.drivers.serial_wire import open_port, wire
from hwbridge.errors import (
    DeviceError,
    DeviceTimeout,
    DriverNotInstalled,
    Remedy,
)
from hwbridge.protocols import description, reading

__all__ = ["K10CR1_COUNTS_PER_DEG", "AptRotationStage"]

K10CR1_COUNTS_PER_DEG = 409600 / 3
"""Microsteps per degree of the K10CR1 (Thorlabs' Kinesis scale for it): a 120:1 worm drive, 200
full steps of 2048 microsteps per motor turn."""

_HOST, _USB_CONTROLLER, _CHANNEL = 0x01, 0x50, 1
_ENABLE, _STOP_PROFILED = 0x01, 0x02
_FAULTS = {
    "forward_limit_switch": "the CW limit switch",
    "reverse_limit_switch": "the CCW limit switch",
    "motion_error": "a motion error",
}


def _protocol_library() -> Any:
    try:
        import thorlabs_apt_protocol
    except ImportError as error:
        raise DriverNotInstalled(
            "the Thorlabs APT stage driver needs thorlabs-apt-protocol (the optional "
            "dependencies rotation-stage)",
            remedy=Remedy.install_rotation_stage,
        ) from error
    return thorlabs_apt_protocol


class AptRotationStage:
    """A Thorlabs APT rotation stage on ``port`` (device name or pyserial URL).

    Parameters
    ----------
    port
        ``/dev/ttyUSB0``, ``COM3`` or ``apt://`` (the emulator).
    name
        Prefix of the reading's key.
    model
        The model number the controller must report (``MGMSG_HW_GET_INFO``).
    counts_per_deg
        Microsteps (or encoder counts) per degree of the stage.
    step_deg
        The turn between two stage positions of a plan (``set({"view_id": k})``).
    range_deg
        Lowest and highest angle the stage may be sent to.
    timeout_s
        The longest wait for an answer.
    move_timeout_s
        The longest wait for a move or homing run to end (the K10CR1 turns 360 deg in 36 s).
    """

    def __init__(
        self,
        port: str,
        *,
        name: str = "stage",
        model: str = "K10CR1",
        counts_per_deg: float = K10CR1_COUNTS_PER_DEG,
        step_deg: float = 15.0,
        range_deg: tuple[float, float] = (0.0, 360.0),
        timeout_s: float = 1.0,
        move_timeout_s: float = 60.0,
    ):
        self.name, self.step_deg = name, step_deg
        self._port_name, self._model = port, model
        self._counts_per_deg, self._range_deg = counts_per_deg, range_deg
        self._timeout_s, self._move_timeout_s = timeout_s, move_timeout_s
        self._port: serial.SerialBase | None = None
        self._unpacker: Any = None
        self._apt: Any = None
        self._serial_number: int | None = None

    @property
    def range_deg(self) -> tuple[float, float]:
        return self._range_deg

    # -- staging -----------------------------------------------------------------------------

    def stage(self) -> None:
        """Open the port, check the model, enable the channel, home unless homed."""
        self._apt = _protocol_library()
        self.unstage()
        try:
            self._port = open_port(
                self._port_name, self.name, baudrate=115200, rtscts=True, timeout=self._timeout_s
            )
            with wire(self.name):
                self._port.reset_input_buffer()
            self._unpacker = self._apt.Unpacker(self._port, on_error="raise")
            self._check_model()
            self._send("mod_set_chanenablestate", _CHANNEL, _ENABLE)
            if not self.status()["homed"]:
                self._send("mot_move_home", _CHANNEL)
                self._await("mot_move_homed", "MGMSG_MOT_MOVE_HOMED", self._move_timeout_s)
        except BaseException:
            self.unstage()  # a half-staged stage leaves no port open
            raise

    def unstage(self) -> None:
        if self._port is not None:
            self._port.close()
            self._port = None

    def _check_model(self) -> None:
        model = self.identity()["model"]
        if model != self._model:
            raise DeviceError(
                f"{self.name}: the controller on {self._port_name} is a {model!r}, expected a "
                f"{self._model}"
            )

    def identity(self) -> dict[str, str]:
        """The controller's model, serial number and firmware (``MGMSG_HW_GET_INFO``)."""
        self._send("hw_req_info")
        info = self._await("hw_get_info", "MGMSG_HW_GET_INFO", self._timeout_s)
        self._serial_number = info.serial_number
        return {
            "model": info.model_number.split(b"\0")[0].decode("ascii", "replace"),
            "serial": str(info.serial_number),
            "firmware": ".".join(str(part) for part in info.firmware_version[1:]),
        }

    # -- RotationStage -------------------------------------------------------------------------

    def set(self, target: dict[str, float]) -> None:
        """Turn to ``{"angle_deg": a}`` or ``{"view_id": k}`` and return once there."""
        angle = stage_angle_deg(
            target, step_deg=self.step_deg, range_deg=self._range_deg, name=self.name
        )
        self._send("mot_move_absolute", _CHANNEL, round(angle * self._counts_per_deg))
        try:
            ending = self._await(
                ("mot_move_completed", "mot_move_stopped"),
                "MGMSG_MOT_MOVE_COMPLETED",
                self._move_timeout_s,
            )
        except DeviceTimeout:
            self._send("mot_move_stop", _CHANNEL, _STOP_PROFILED)
            self._await("mot_move_stopped", "MGMSG_MOT_MOVE_STOPPED", self._timeout_s)
            raise
        # The status data after the header; a controller that sends the header alone is asked.
        reached = (
            ending.position / self._counts_per_deg
            if hasattr(ending, "position")
            else self.angle_deg()
        )
        faults = [text for flag, text in _FAULTS.items() if getattr(ending, flag, False)]
        if ending.msg == "mot_move_stopped" or faults:
            cause = ", ".join(faults) or "the controller stopped it"
            raise DeviceError(
                f"{self.name}: the move to {angle:g} deg stopped at {reached:.3f} deg: {cause}"
            )
        if abs(reached - angle) > 1e-3:
            raise DeviceError(
                f"{self.name}: the move to {angle:g} deg completed at {reached:.3f} deg"
            )

    def angle_deg(self) -> float:
        """The angle of the controller's position counter (``MGMSG_MOT_REQ_POSCOUNTER``)."""
        self._send("mot_req_poscounter", _CHANNEL)
        counter = self._await("mot_get_poscounter", "MGMSG_MOT_GET_POSCOUNTER", self._timeout_s)
        return float(counter.position) / self._counts_per_deg

    def status(self) -> dict[str, Any]:
        """The decoded status bits of ``MGMSG_MOT_GET_STATUSUPDATE`` and the angle."""
        self._send("mot_req_statusupdate", _CHANNEL)
        update = self._await("mot_get_statusupdate", "MGMSG_MOT_GET_STATUSUPDATE", self._timeout_s)
        header = ("msg", "msgid", "dest", "source", "chan_ident", "position", "enc_count")
        bits = {key: value for key, value in update._asdict().items() if key not in header}
        return {**bits, "angle_deg": update.position / self._counts_per_deg}

    def read(self) -> dict[str, dict[str, Any]]:
        return reading(f"{self.name}_angle_deg", self.angle_deg())

    def describe(self) -> dict[str, dict[str, Any]]:
        return description(
            f"{self.name}_angle_deg",
            source=f"Thorlabs {self._model} {self._serial_number or '?'} on {self._port_name}",
            dtype="number",
            shape=[],
            units="deg",
        )

    # -- wire ------------------------------------------------------------------------------------

    def _require_port(self) -> serial.SerialBase:
        if self._port is None:
            raise DeviceError(f"{self.name}: not staged; call stage() first")
        return self._port

    def _send(self, message: str, *parameters: int) -> None:
        """Write the library's ``message(destination, source, *parameters)``."""
        port = self._require_port()
        with wire(self.name):
            port.write(getattr(self._apt, message)(_USB_CONTROLLER, _HOST, *parameters))

    def _await(self, wanted: str | tuple[str, ...], what: str, timeout_s: float) -> Any:
        """The next message from the controller, which must be (one of) ``wanted``."""
        wanted = (wanted,) if isinstance(wanted, str) else wanted
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                with wire(self.name):
                    message = next(self._unpacker)
            except StopIteration:
                if time.monotonic() >= deadline:
                    raise DeviceTimeout(f"{self.name}: no {what} within {timeout_s:g} s") from None
                continue
            except (RuntimeError, struct.error) as error:
                raise DeviceError(
                    f"{self.name}: garbled bytes where {what} was expected ({error})"
                ) from None
            if message.msg in wanted:
                return message
            raise DeviceError(
                f"{self.name}: expected {what}, got {message.msg} ({message.msgid:#06x})"
            )
