"""An emulated device behind a pseudo-terminal: a serial device node any program can open.

``with EmulatorPty(AptStageState()) as path:`` opens a pty pair and, in a thread, answers every
byte written to the terminal ``path`` (``/dev/pts/N``) with the state's ``respond`` and sends its
``due`` messages once they fall due, counting the bytes each way (``received``, ``sent``). A
driver opens ``path`` as it opens a USB serial adapter (termios, baud rate, RTS/CTS), so its own
port code runs as on the real device, not only through pyserial's URL handlers. POSIX only.
"""

from __future__ import annotations

import os
import select
import threading
import time
import tty

from hwbridge.emulators.emulated_port import DeviceState

__all__ = ["EmulatorPty"]


class EmulatorPty:
    """Serve ``state`` on a pseudo-terminal for the duration of a ``with`` block."""

    def __init__(self, state: DeviceState, *, poll_s: float = 0.001):
        self.state, self._poll_s = state, poll_s
        self.path = ""
        self.received = self.sent = 0  # bytes from and to the host
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._controller = self._terminal = -1

    def __enter__(self) -> str:
        self._controller, self._terminal = os.openpty()
        tty.setraw(self._terminal)  # no echo, no line editing: bytes pass as they are
        self.path = os.ttyname(self._terminal)
        self._thread = threading.Thread(target=self._serve, name=f"emulator {self.path}")
        self._thread.start()
        return self.path

    def _serve(self) -> None:
        while not self._stop.is_set():
            ready, _, _ = select.select([self._controller], [], [], self._poll_s)
            data = os.read(self._controller, 4096) if ready else b""
            self.received += len(data)
            answer = self.state.respond(data) if data else b""
            answer += self.state.due(time.monotonic())
            if answer:
                self.sent += os.write(self._controller, answer)

    def __exit__(self, *exc_info: object) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        os.close(self._terminal)
        os.close(self._controller)
