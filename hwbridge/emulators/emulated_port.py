"""A pyserial port with an emulated device at its far end, the base of the URL handlers.

A handler module ``protocol_<scheme>`` defines ``Serial``, a subclass naming its ``scheme``, its
URL options with their defaults and how they build the device's state. The state turns bytes from
the host into bytes to the host (``respond``) and sends what it says on its own once it is due
(``due``, e.g. a stage's move-completed message), so the driver under test reads the device's real
bytes through pyserial's port object.
"""

from __future__ import annotations

import time
import urllib.parse
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

from serial.serialutil import PortNotOpenError, SerialBase, SerialException, Timeout

if TYPE_CHECKING:
    from typing_extensions import Buffer

__all__ = ["DeviceState", "EmulatedPort", "MessageDeviceState"]


class DeviceState(Protocol):
    """The far end of an emulated wire."""

    def respond(self, data: bytes) -> bytes:
        """The device's answer to ``data`` from the host."""

    def due(self, now: float) -> bytes:
        """What the device sends unasked by ``now`` (``time.monotonic`` seconds)."""


@dataclass
class MessageDeviceState(ABC):
    """A device that answers whole messages: ``respond`` gathers the host's bytes and answers
    each message the subclass finds in them (``_next_message``) with ``_handle``; ``_spoil``
    may turn the answers into a fault's. ``silent`` answers nothing (an unplugged device)."""

    silent: bool = False
    _inbox: bytearray = field(default_factory=bytearray)

    def respond(self, data: bytes) -> bytes:
        if self.silent:
            return b""
        self._inbox += data
        answers = bytearray()
        while (message := self._next_message()) is not None:
            answers += self._handle(*message)
        return self._spoil(bytes(answers))

    @abstractmethod
    def _next_message(self) -> tuple[Any, ...] | None:
        """Take the next whole message out of the inbox (``None``: none yet)."""

    @abstractmethod
    def _handle(self, *message: Any) -> bytes:
        """The answer to one message."""

    def _spoil(self, answers: bytes) -> bytes:
        return answers

    def due(self, now: float) -> bytes:
        """Nothing unasked, unless a subclass says otherwise."""
        return b""


class EmulatedPort(SerialBase):
    """A pyserial port whose far end is the :class:`DeviceState` its URL describes.

    Subclasses set ``scheme`` and ``options`` (name: default, as strings) and build the state in
    ``make_state``. Every port opened on a URL talks to a state of its own.
    """

    scheme: ClassVar[str]
    options: ClassVar[dict[str, str]]

    @classmethod
    @abstractmethod
    def make_state(cls, options: dict[str, str]) -> DeviceState:
        """The device's state, built from the URL's ``options``."""

    def open(self) -> None:
        if self.port is None:
            raise SerialException("port must be configured before it can be used")
        if self.is_open:
            raise SerialException("port already open")
        self.state = self.make_state(self._url_options(self.port))
        self._buffer = bytearray()
        self.is_open = True

    def close(self) -> None:
        self.is_open = False

    def _reconfigure_port(self) -> None:
        """Baud rate, framing and flow control have no effect on an emulated wire."""

    @classmethod
    def _url_options(cls, url: str) -> dict[str, str]:
        parts = urllib.parse.urlsplit(url)
        if parts.scheme != cls.scheme:
            raise SerialException(f"expected a {cls.scheme}:// URL, got {url!r}")
        given = {key: values[-1] for key, values in urllib.parse.parse_qs(parts.query).items()}
        unknown = set(given) - set(cls.options)
        if unknown:
            raise SerialException(
                f"{cls.scheme}:// options: unknown {sorted(unknown)}, expected "
                f"{sorted(cls.options)}"
            )
        return {**cls.options, **given}

    @property
    def in_waiting(self) -> int:
        if not self.is_open:
            raise PortNotOpenError()
        self._buffer += self.state.due(time.monotonic())
        return len(self._buffer)

    def read(self, size: int = 1) -> bytes:
        if not self.is_open:
            raise PortNotOpenError()
        # pyserial's Timeout takes None (wait for ever), which its stub leaves out
        timeout = Timeout(self.timeout)  # type: ignore[arg-type]
        while True:
            self._buffer += self.state.due(time.monotonic())
            if len(self._buffer) >= size or timeout.expired():
                break
            time.sleep(0.001)
        data = bytes(self._buffer[:size])
        del self._buffer[:size]
        return data

    def write(self, data: Buffer) -> int:
        if not self.is_open:
            raise PortNotOpenError()
        received = bytes(data)
        self._buffer += self.state.respond(received)
        return len(received)

    def reset_input_buffer(self) -> None:
        self._buffer.clear()

    def reset_output_buffer(self) -> None:
        """Nothing is ever pending on the way out."""
