"""A lab on the wire without hardware: the rig's serial devices emulated on pseudo-terminals and
a devices file pointing at them (``spectwin lab emulate``).

:class:`EmulatedLab` serves the Thorlabs APT stage, the Enttec DMX USB Pro with the LED decoders
and the VariSpec LCTF (the dome; the gonioreflectometer has the LCTF alone) each on a pty of
its own (:class:`~hwbridge.emulators.pty_link.EmulatorPty`), so the real drivers open them as
they open USB serial adapters, and writes ``lab.yaml`` with their device paths. The cameras are
the twin's (``sim``: it renders what the devices were told) or the camera of the ``genicam``
package's simulated GenTL producer. The file is removed when the lab stops: its ports are gone.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from hwbridge.emulators import protocol_apt, protocol_dmxusbpro, protocol_varispec
from hwbridge.emulators.emulated_port import EmulatedPort
from hwbridge.emulators.pty_link import EmulatorPty
from hwbridge.errors import InputError

__all__ = ["EmulatedLab", "SERIAL_ROLES"]

SERIAL_ROLES: dict[str, dict[str, tuple[str, type[EmulatedPort]]]] = {
    "dome": {
        "stage": ("Thorlabs APT stage", protocol_apt.Serial),
        "leds": ("DMX USB Pro", protocol_dmxusbpro.Serial),
        "lctf": ("VariSpec LCTF", protocol_varispec.Serial),
    },
    "gonioreflectometer": {"lctf": ("VariSpec LCTF", protocol_varispec.Serial)},
}
"""The emulated serial devices of each rig: role to (device, its URL handler)."""

_OTHER_ROLES = {
    "dome": ("spectral_camera", "rgb_cameras"),
    "gonioreflectometer": ("camera", "monitor", "positioner", "lamp"),
}
_CAMERAS = {"dome": ("spectral_camera",), "gonioreflectometer": ("camera",)}


@dataclass
class EmulatedLab:
    """The emulated devices of ``rig`` and their devices file ``folder/lab.yaml``, for the
    duration of a ``with`` block.

    Attributes
    ----------
    folder
        Where ``lab.yaml`` is written.
    rig
        ``dome`` or ``gonioreflectometer``.
    options
        Per role, the emulator's URL options (:mod:`hwbridge.emulators.protocol_apt` ...), e.g.
        ``{"stage": {"speed": "360"}}``.
    genicam_producer
        With a GenTL producer, the rig's spectral camera (the gonioreflectometer's camera) is
        the producer's first camera; ``None``: the twin's.
    """

    folder: Path
    rig: str = "dome"
    options: dict[str, dict[str, str]] = field(default_factory=dict)
    genicam_producer: Path | None = None
    ptys: dict[str, EmulatorPty] = field(default_factory=dict, init=False)

    def __post_init__(self) -> None:
        if self.rig not in SERIAL_ROLES:
            raise InputError(f"rig: expected one of {', '.join(SERIAL_ROLES)}, got {self.rig!r}")
        unknown = sorted(set(self.options) - set(SERIAL_ROLES[self.rig]))
        if unknown:
            raise InputError(
                f"options: the {self.rig} emulates no {unknown[0]}; expected "
                f"{', '.join(SERIAL_ROLES[self.rig])}"
            )

    @property
    def path(self) -> Path:
        """The devices file."""
        return self.folder / "lab.yaml"

    def __enter__(self) -> Path:
        self.folder.mkdir(parents=True, exist_ok=True)
        try:
            for role, (_, handler) in SERIAL_ROLES[self.rig].items():
                given = self.options.get(role, {})
                unknown = sorted(set(given) - set(handler.options))
                if unknown:
                    raise InputError(
                        f"options.{role}: unknown {unknown}; expected {sorted(handler.options)}"
                    )
                state = handler.make_state({**handler.options, **given})
                link = EmulatorPty(state)
                link.__enter__()
                self.ptys[role] = link
            self._write()
        except BaseException:
            self.__exit__()
            raise
        return self.path

    def _write(self) -> None:
        devices: dict[str, Any] = {role: link.path for role, link in self.ptys.items()}
        for role in _OTHER_ROLES[self.rig]:
            devices[role] = "sim"
        if self.genicam_producer is not None:
            for role in _CAMERAS[self.rig]:
                devices[role] = {"producer": str(self.genicam_producer)}
        text = yaml.safe_dump({"rig": self.rig, "devices": devices}, sort_keys=False)
        partial = self.path.with_suffix(".yaml.partial")
        note = "# The emulated lab of spectwin lab emulate; gone when it stops.\n"
        partial.write_text(note + text)
        partial.replace(self.path)

    def traffic(self) -> dict[str, dict[str, Any]]:
        """Per role: the device, its pty and the bytes it received from and sent to the host."""
        return {
            role: {
                "device": SERIAL_ROLES[self.rig][role][0],
                "port": link.path,
                "bytes_from_host": link.received,
                "bytes_to_host": link.sent,
            }
            for role, link in self.ptys.items()
        }

    def __exit__(self, *exc_info: object) -> None:
        self.path.unlink(missing_ok=True)
        for link in self.ptys.values():
            link.__exit__()
