"""Open every real device of a devices file and ask it who it is (``spectwin lab check``).

Each device the file names is staged (its port opened, its model checked, a stage homed), asked
its identity (:class:`hwbridge.protocols.Identified`: one exchange on its wire, timed) and
unstaged. A device that does not answer, answers wrongly or is not there is reported with the
reason, and the others are still checked.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from typing import Any

from hwbridge.errors import SpectwinError
from hwbridge.lab import DeviceEntry, Lab, open_device

__all__ = ["DeviceCheck", "check_device", "check_lab"]


@dataclass(frozen=True)
class DeviceCheck:
    """What one device said.

    Attributes
    ----------
    role
        Its role in the rig.
    driver
        The driver that spoke to it.
    address
        Its port, URL, producer or serial number, as the file names it.
    model, serial, firmware
        As the device reports them (empty when it did not answer).
    state
        ``ok``, or why it failed.
    round_trip_ms
        The time of the identity exchange (``None`` when it did not answer).
    """

    role: str
    driver: str
    address: str
    model: str = ""
    serial: str = ""
    firmware: str = ""
    state: str = "ok"
    round_trip_ms: float | None = None

    @property
    def ok(self) -> bool:
        """Whether the device answered as it should."""
        return self.state == "ok"

    def as_dict(self) -> dict[str, Any]:
        """As ``--json`` prints it."""
        return asdict(self) | {"ok": self.ok}


def check_device(role: str, entry: DeviceEntry) -> DeviceCheck:
    """Stage the device of ``role``, time its identity and unstage it."""
    found = DeviceCheck(role, entry.driver, entry.address)
    device = open_device(role, entry)
    try:
        device.stage()
        start = time.perf_counter()
        identity = device.identity()
        elapsed_ms = 1e3 * (time.perf_counter() - start)
    except (SpectwinError, OSError) as error:
        return DeviceCheck(**{**asdict(found), "state": str(error).removeprefix(f"{role}: ")})
    finally:
        device.unstage()
    return DeviceCheck(
        role,
        entry.driver,
        found.address,
        identity["model"],
        identity["serial"],
        identity["firmware"],
        "ok",
        round(elapsed_ms, 1),
    )


def check_lab(lab: Lab) -> list[DeviceCheck]:
    """Every real device of ``lab``, in the file's order of roles."""
    return [check_device(role, entry) for role, entry in lab.wired().items()]
