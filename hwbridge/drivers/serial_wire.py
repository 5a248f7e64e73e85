"""What the serial drivers share: opening a port, and a wire that fails as a disconnect.

A port that cannot be opened (the adapter unplugged, an emulator's pseudo-terminal gone) and a
read, write or flush that fails on an open one (the far end closed) raise
:class:`~hwbridge.errors.DeviceDisconnected`, which a session answers by staging the device again
and retrying (:mod:`hwbridge.session`).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import serial

from hwbridge.errors import DeviceDisconnected

try:
    import termios

    _WIRE_ERRORS: tuple[type[Exception], ...] = (serial.SerialException, OSError, termios.error)
except ImportError:  # pragma: no cover - not POSIX
    _WIRE_ERRORS = (serial.SerialException, OSError)

__all__ = ["open_port", "wire"]


def open_port(port: str, name: str, **settings: Any) -> serial.Serial:
    """The serial port (device name or pyserial URL) ``port`` of the device ``name``, open."""
    try:
        return serial.serial_for_url(port, **settings)
    except _WIRE_ERRORS as error:
        raise DeviceDisconnected(f"{name}: cannot open {port} ({_reason(error)})") from error


def _reason(error: BaseException) -> str:
    """The operating system's words for why ``error`` happened, where it has them."""
    cause: BaseException | None = error
    while cause is not None:
        if isinstance(cause, OSError) and cause.strerror and "[Errno" not in cause.strerror:
            return cause.strerror
        cause = cause.__context__
    return str(error)


@contextmanager
def wire(name: str) -> Iterator[None]:
    """A block that talks to the device ``name``: a failing port is a disconnect."""
    try:
        yield
    except _WIRE_ERRORS as error:
        raise DeviceDisconnected(f"{name}: {error}") from error
