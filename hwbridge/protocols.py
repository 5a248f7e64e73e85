"""Device interfaces of the capture rigs as structural protocols.

Shaped like ``bluesky.protocols``: any object with these methods qualifies, so simulated devices
(``twin``), replayed captures and real drivers are interchangeable without inheritance.
``read`` returns ``{name: {"value": ..., "timestamp": ...}}`` and ``describe`` the matching
``{name: {"source", "dtype", "shape", "units"}}``.
"""

from __future__ import annotations

import time
from typing import Any, Protocol, runtime_checkable

import numpy as np

__all__ = [
    "Camera",
    "description",
    "reading",
    "Describable",
    "Identified",
    "Lamp",
    "LampMonitor",
    "LedArray",
    "Positioner",
    "Reading",
    "Readable",
    "RotationStage",
    "Shutter",
    "Spectrometer",
    "Stageable",
    "TunableFilter",
]

Reading = dict[str, dict[str, Any]]


def reading(key: str, value: Any, timestamp: float | None = None) -> Reading:
    """One field of a ``read`` result, time-stamped now unless ``timestamp`` is given."""
    return {key: {"value": value, "timestamp": time.time() if timestamp is None else timestamp}}


def description(key: str, *, source: str, dtype: str, shape: list[int], units: str) -> Reading:
    """One field of a ``describe`` result."""
    return {key: {"source": source, "dtype": dtype, "shape": shape, "units": units}}


@runtime_checkable
class Describable(Protocol):
    name: str

    def describe(self) -> Reading:
        """What ``read`` returns: source, dtype, shape and units per field."""


@runtime_checkable
class Readable(Describable, Protocol):
    def read(self) -> Reading:
        """Current values with timestamps."""


@runtime_checkable
class Stageable(Protocol):
    def stage(self) -> None:
        """Prepare for a run (open ports, initialize)."""

    def unstage(self) -> None:
        """Release after a run."""


@runtime_checkable
class Identified(Protocol):
    def identity(self) -> dict[str, str]:
        """Ask the staged device who it is: ``model``, ``serial`` and ``firmware`` as it
        reports them (one exchange on its wire, which a device check times)."""


@runtime_checkable
class TunableFilter(Readable, Stageable, Protocol):
    """An electronically tunable band-pass filter (the VariSpec LCTF, thesis 3.2.2)."""

    def set(self, wavelength_nm: float) -> None:
        """Tune to ``wavelength_nm`` and return once the filter has settled."""

    @property
    def range_nm(self) -> tuple[float, float]:
        """Shortest and longest wavelength the filter can be tuned to."""


@runtime_checkable
class Camera(Readable, Stageable, Protocol):
    """A camera: set the exposure, take a raw frame."""

    @property
    def frame_shape(self) -> tuple[int, int]:
        """Height and width of a frame in pixels."""

    def set_exposure(self, exposure_s: float) -> None: ...

    def snap(self) -> tuple[np.ndarray, dict[str, Any]]:
        """One raw uint16 frame and its metadata (exposure, timestamp, temperature, ...)."""


@runtime_checkable
class Shutter(Protocol):
    """A camera's shutter (the CoolSNAP K4's): closed for dark frames."""

    def set_shutter(self, open_: bool) -> None: ...


@runtime_checkable
class Lamp(Readable, Protocol):
    """A lamp that is switched on or off."""

    def set(self, on: bool) -> None: ...


@runtime_checkable
class LedArray(Readable, Stageable, Protocol):
    """The dome's LEDs: any pattern of them on at a drive current (thesis 10.2.1).

    ``read`` reports every LED's current in mA (0: off). Requests are checked as in
    :mod:`hwbridge.dome_targets`.
    """

    count: int

    @property
    def current_range_ma(self) -> tuple[float, float]:
        """Lowest and highest current an LED that is on can be driven at."""

    @property
    def current_step_ma(self) -> float:
        """Resolution of the drive current (0: continuous)."""

    def set(self, pattern: np.ndarray, current_ma: float | None = None) -> None:
        """``pattern``: boolean array, one entry per LED; those on at ``current_ma`` (``None``:
        the array's drive current), all others off."""

    def light(self, led: int, current_ma: float | None = None) -> None:
        """LED ``led`` alone on at ``current_ma`` (``None``: the drive current)."""


@runtime_checkable
class Positioner(Readable, Protocol):
    """Robot pose, rail angle or rotation stage: move and report where it is."""

    def set(self, target: dict[str, float]) -> None: ...


@runtime_checkable
class RotationStage(Positioner, Stageable, Protocol):
    """The dome's rotation stage under the sample (thesis 10.2.2).

    ``set({"angle_deg": a})`` turns to ``a``, ``set({"view_id": k})`` to stage position ``k``
    (``k * step_deg``), both returning once the stage has stopped there; ``read`` reports the
    angle in degrees.
    """

    step_deg: float

    @property
    def range_deg(self) -> tuple[float, float]:
        """Lowest and highest angle the stage may be sent to."""


@runtime_checkable
class Spectrometer(Readable, Protocol):
    """The lamp monitor (X-Rite i1, thesis 3.3): one spectrum per reading."""

    def trigger(self) -> None: ...


@runtime_checkable
class LampMonitor(Spectrometer, Protocol):
    """The lamp monitor of a session: ``read`` gives one field, a spectrum of ``samples``
    values, which the capture store keeps with every lit frame."""

    @property
    def samples(self) -> int:
        """Values of one spectrum."""
