"""A lab's devices file (``lab.yaml``): which device fills each role of a rig, and where it is.

A rig's roles are the devices a capture program drives. The LED dome (thesis 10.2) has a
rotation stage (``stage``: a Thorlabs APT controller), an LED array (``leds``: DMX512 decoders
behind an Enttec DMX USB Pro), a liquid-crystal tunable filter (``lctf``: a VariSpec), the
spectral camera behind it (``spectral_camera``), the RGB cameras of the arc (``rgb_cameras``) and
optionally a spectrometer (``spectrometer``). The gonioreflectometer (chapter 3) has a camera
behind an LCTF (``camera``, ``lctf``), the lamp monitor (``monitor``: an Ocean Optics
spectrometer), and the robot and rail and the lamp (``positioner``, ``lamp``), which have no
driver and stay simulated.

Each role is ``sim`` (the twin's device) or the real device's address: a serial port
(``/dev/ttyUSB0``, ``COM3``) or a pyserial URL (the emulators' ``apt://``, ``dmxusbpro://`` and
``varispec://``, a device server's ``socket://`` or ``rfc2217://``), given as a string or as a
mapping with the driver's settings; a camera's GenTL producer (``.cti``, relative paths read
beside the file) and serial number; a spectrometer's serial number. ``scenes/labs/dome.yaml``
is an annotated example.

:func:`load_lab` reads and checks a file; :func:`open_device` builds the driver of one role.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar, TypeAlias

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from hwbridge.dome_layout import rgb_camera_id
from hwbridge.errors import InputError

__all__ = [
    "ROLES",
    "SIM",
    "DeviceEntry",
    "GenICamEntry",
    "Lab",
    "LctfEntry",
    "LedsEntry",
    "Role",
    "SpectrometerEntry",
    "StageEntry",
    "load_lab",
    "open_device",
]

SIM = "sim"
"""A role filled by the twin's simulated device."""

_DEVICE_PREFIXES = ("/dev/", "COM", "\\\\.\\")
_SERVER_SCHEMES = ("socket", "rfc2217")


class _Entry(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class _SerialEntry(_Entry):
    """A device on a serial port; ``scheme`` is its emulator's URL scheme."""

    scheme: ClassVar[str]
    driver: ClassVar[str]

    port: str = Field(description="serial port, or pyserial URL")

    @property
    def address(self) -> str:
        """Where the device is, as the file names it."""
        return self.port

    @field_validator("port")
    @classmethod
    def _an_address(cls, port: str) -> str:
        scheme, separator, _ = port.partition("://")
        if separator:
            allowed = (cls.scheme, *_SERVER_SCHEMES)
            if scheme not in allowed:
                raise ValueError(
                    f"a {scheme}:// URL is not a {cls.driver}; expected a serial port or one of "
                    + ", ".join(f"{name}://" for name in allowed)
                )
        elif not port.startswith(_DEVICE_PREFIXES):
            raise ValueError(
                f"{port!r} is not a serial port; expected /dev/..., COMn or a {cls.scheme}:// URL"
            )
        return port


class StageEntry(_SerialEntry):
    """A Thorlabs APT rotation stage (:class:`~hwbridge.drivers.apt_rotation_stage.
    AptRotationStage`)."""

    scheme: ClassVar[str] = "apt"
    driver: ClassVar[str] = "Thorlabs APT stage"

    model: str = Field("K10CR1", description="the model the controller must report")
    counts_per_deg: float | None = Field(None, gt=0, description="microsteps per degree")


class LedsEntry(_SerialEntry):
    """DMX512 LED decoders behind an Enttec DMX USB Pro (:class:`~hwbridge.drivers.
    dmx_led_array.DmxLedArray`)."""

    scheme: ClassVar[str] = "dmxusbpro"
    driver: ClassVar[str] = "DMX USB Pro"

    first_address: int = Field(1, ge=1, le=512, description="DMX slot of LED 0")
    full_scale_ma: float = Field(700.0, gt=0, description="the decoders' output current")


class LctfEntry(_SerialEntry):
    """A VariSpec liquid-crystal tunable filter (:class:`~hwbridge.drivers.varispec.VariSpec`)."""

    scheme: ClassVar[str] = "varispec"
    driver: ClassVar[str] = "VariSpec LCTF"


class GenICamEntry(_Entry):
    """A GenICam camera of a GenTL producer (:class:`~hwbridge.drivers.genicam_camera.
    GenICamCamera`)."""

    driver: ClassVar[str] = "GenICam"

    producer: Path = Field(description="the GenTL producer (.cti)")
    serial: str | None = Field(None, description="the camera's serial number (default: first)")

    @property
    def address(self) -> str:
        """Where the device is, as the file names it."""
        return f"{self.producer}" + (f" serial {self.serial}" if self.serial else "")

    @field_validator("producer")
    @classmethod
    def _a_producer(cls, producer: Path) -> Path:
        if producer.suffix != ".cti":
            raise ValueError(f"{producer} is not a GenTL producer; expected a .cti file")
        return producer


class SpectrometerEntry(_Entry):
    """An Ocean Optics spectrometer (:class:`~hwbridge.drivers.ocean_spectrometer.
    OceanSpectrometer`)."""

    driver: ClassVar[str] = "Ocean Optics"

    serial: str | None = Field(None, description="its serial number (default: the first found)")
    integration_s: float = Field(0.01, gt=0, description="integration time")

    @property
    def address(self) -> str:
        """Where the device is, as the file names it."""
        return f"USB serial {self.serial}" if self.serial else "USB (the first found)"


DeviceEntry: TypeAlias = StageEntry | LedsEntry | LctfEntry | GenICamEntry | SpectrometerEntry


@dataclass(frozen=True)
class Role:
    """A role of a rig: the model of a real device's entry (``None``: no driver), whether
    ``sim`` may fill it, whether the file must name it, and what fills it, for messages."""

    entry: type[DeviceEntry] | None
    expected: str
    sim: bool = True
    required: bool = True


_RGB_CAMERAS = tuple(rgb_camera_id(index) for index in range(11))

ROLES: dict[str, dict[str, Role]] = {
    "dome": {
        "stage": Role(StageEntry, "sim, a serial port or an apt:// URL"),
        "leds": Role(LedsEntry, "sim, a serial port or a dmxusbpro:// URL"),
        "lctf": Role(LctfEntry, "sim, a serial port or a varispec:// URL"),
        "spectral_camera": Role(GenICamEntry, "sim or a GenTL producer (.cti) and serial"),
        "rgb_cameras": Role(
            GenICamEntry,
            f"sim, or a mapping of each RGB camera ({_RGB_CAMERAS[0]} ...) to sim or a GenTL "
            "producer (.cti) and serial",
        ),
        "spectrometer": Role(
            SpectrometerEntry, "a spectrometer's serial and integration_s", False, False
        ),
    },
    "gonioreflectometer": {
        "camera": Role(GenICamEntry, "sim or a GenTL producer (.cti) and serial"),
        "lctf": Role(LctfEntry, "sim, a serial port or a varispec:// URL"),
        "monitor": Role(SpectrometerEntry, "sim or a spectrometer's serial and integration_s"),
        "positioner": Role(None, "sim (the robot and rail have no driver)"),
        "lamp": Role(None, "sim (the lamp has no driver)"),
    },
}
"""Every rig's roles, by name."""


@dataclass(frozen=True)
class Lab:
    """A checked devices file.

    Attributes
    ----------
    rig
        The kind of rig (``dome`` or ``gonioreflectometer``).
    devices
        Every role it names and what fills it; the dome's RGB cameras by camera id
        (``rgb00`` ...) when the file names them one by one, else as ``rgb_cameras``.
    path
        The file.
    """

    rig: str
    devices: dict[str, DeviceEntry | str]
    path: Path

    def device(self, role: str) -> DeviceEntry | None:
        """The real device of ``role`` (``None``: the twin's, also for an optional role the
        file leaves out)."""
        entry = self.devices.get(role, SIM)
        return None if isinstance(entry, str) else entry

    def camera(self, camera_id: str) -> DeviceEntry | None:
        """The real camera that takes the frames of ``camera_id`` (the dome's ``spectral``,
        ``rgb00`` ...; the gonioreflectometer's one camera), ``None``: the twin's."""
        if self.rig == "gonioreflectometer":
            return self.device("camera")
        if camera_id == "spectral":
            return self.device("spectral_camera")
        if "rgb_cameras" in self.devices:
            return self.device("rgb_cameras")
        if camera_id not in self.devices:
            raise InputError(
                f"{self.path}: rgb_cameras: the capture uses camera {camera_id}, which the file "
                "does not name; expected an entry for it (sim or a GenTL producer)"
            )
        return self.device(camera_id)

    def wired(self) -> dict[str, DeviceEntry]:
        """The roles a real device fills, by name."""
        return {name: entry for name, entry in self.devices.items() if not isinstance(entry, str)}


def _entry(role: Role, value: object, folder: Path, where: str) -> DeviceEntry | str:
    """One role's value, checked."""
    if value == SIM and role.sim:
        return SIM
    if role.entry is None or not isinstance(value, str | dict):
        raise InputError(f"{where}: expected {role.expected}, got {value!r}")
    if isinstance(value, str):
        if not issubclass(role.entry, _SerialEntry):
            raise InputError(f"{where}: expected {role.expected}, got {value!r}")
        value = {"port": value}
    try:
        entry = role.entry.model_validate(value)
    except ValidationError as error:
        first = error.errors()[0]
        field = ".".join(str(part) for part in first["loc"])
        message = first["msg"].removeprefix("Value error, ")
        if first["type"] == "extra_forbidden":
            known = ", ".join(role.entry.model_fields)
            message = f"unknown setting; expected {known}"
        raise InputError(f"{where}.{field}: {message}") from None
    if isinstance(entry, GenICamEntry) and not entry.producer.is_absolute():
        entry = entry.model_copy(update={"producer": folder / entry.producer})
    return entry


def _devices(rig: str, devices: dict[str, object], path: Path) -> dict[str, DeviceEntry | str]:
    roles = ROLES[rig]
    unknown = sorted(set(devices) - set(roles))
    if unknown:
        raise InputError(
            f"{path}: devices.{unknown[0]}: unknown role of the {rig}; expected {', '.join(roles)}"
        )
    checked: dict[str, DeviceEntry | str] = {}
    folder = path.parent.resolve()
    for name, role in roles.items():
        where = f"{path}: devices.{name}"
        if name not in devices:
            if role.required:
                raise InputError(f"{where}: missing; expected {role.expected}")
            continue
        value = devices[name]
        if name == "rgb_cameras" and isinstance(value, dict):
            strange = sorted(set(map(str, value)) - set(_RGB_CAMERAS))
            if strange:
                raise InputError(
                    f"{where}.{strange[0]}: no such RGB camera; expected {_RGB_CAMERAS[0]} to "
                    f"{_RGB_CAMERAS[-1]}"
                )
            for camera, entry in value.items():
                checked[camera] = _entry(role, entry, folder, f"{where}.{camera}")
            continue
        checked[name] = _entry(role, value, folder, where)
    return checked


def load_lab(path: str | Path) -> Lab:
    """The devices file at ``path``, checked.

    Parameters
    ----------
    path
        A ``lab.yaml``: ``rig`` (``dome`` or ``gonioreflectometer``) and ``devices`` (role:
        device).

    Returns
    -------
    Lab
        Its producers' relative paths read beside the file.

    Raises
    ------
    InputError
        One line naming the file, the role and what was expected.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> _ = (folder / "lab.yaml").write_text(
    ...     "rig: gonioreflectometer\\n"
    ...     "devices: {camera: sim, lctf: /dev/ttyUSB0, monitor: sim,\\n"
    ...     "          positioner: sim, lamp: sim}\\n"
    ... )
    >>> load_lab(folder / "lab.yaml").device("lctf").port
    '/dev/ttyUSB0'
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"devices file: no file {path}; expected a lab.yaml")
    try:
        document = yaml.safe_load(path.read_text())
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        raise InputError(f"{path}: not YAML{where}; expected a devices file") from None
    if not isinstance(document, dict) or set(document) != {"rig", "devices"}:
        shown = sorted(map(str, document)) if isinstance(document, dict) else document
        raise InputError(f"{path}: expected the keys rig and devices, got {shown!r}")
    rig = document["rig"]
    if rig not in ROLES:
        raise InputError(f"{path}: rig: expected one of {', '.join(ROLES)}, got {rig!r}")
    devices = document["devices"]
    if not isinstance(devices, dict):
        raise InputError(f"{path}: devices: expected a mapping of role: device, got {devices!r}")
    return Lab(rig, _devices(rig, devices, path), path)


def open_device(role: str, entry: DeviceEntry, settings: Mapping[str, Any] | None = None) -> Any:
    """The driver of ``role`` on ``entry``'s address, not yet staged.

    Parameters
    ----------
    role
        The role's name (the driver's name, which its readings carry).
    entry
        What the devices file says of it.
    settings
        What the rig adds to the driver (e.g. ``count`` of an LED array, ``step_deg`` of a
        stage).
    """
    extra = dict(settings or {})
    if isinstance(entry, StageEntry):
        from hwbridge.drivers.apt_rotation_stage import AptRotationStage

        if entry.counts_per_deg is not None:
            extra["counts_per_deg"] = entry.counts_per_deg
        return AptRotationStage(entry.port, name=role, model=entry.model, **extra)
    if isinstance(entry, LedsEntry):
        from hwbridge.drivers.dmx_led_array import DmxLedArray

        return DmxLedArray(
            entry.port,
            name=role,
            first_address=entry.first_address,
            full_scale_ma=entry.full_scale_ma,
            **extra,
        )
    if isinstance(entry, LctfEntry):
        from hwbridge.drivers.varispec import VariSpec

        return VariSpec(entry.port, name=role, **extra)
    if isinstance(entry, GenICamEntry):
        from hwbridge.drivers.genicam_camera import GenICamCamera

        return GenICamCamera(entry.producer, serial_number=entry.serial, name=role, **extra)
    from hwbridge.drivers.ocean_spectrometer import OceanSpectrometer

    return OceanSpectrometer(
        serial_number=entry.serial, integration_s=entry.integration_s, name=role, **extra
    )
