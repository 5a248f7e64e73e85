"""A capture program's devices from a lab's devices file: real devices where the file names them,
the twin's elsewhere, and the twin's cameras rendering what the real devices were told.

:class:`LabDevices` is a recipe, like :class:`~twin.devices.sim_devices.SimDomeDevices`, that
the session calls for its seed and steps. It builds the twin's devices over one
:class:`~twin.devices.sim_devices.VirtualRig` and puts a real device in each role the file
(:mod:`hwbridge.lab`) names: the dome's Thorlabs APT rotation stage, its LEDs behind an Enttec DMX
USB Pro, the VariSpec LCTF, GenICam cameras. Hardware in the loop: a real stage, LED array or
LCTF is wrapped so that after each request the rig takes the state read back from the device (the
stage's position counter, the DMX universe the widget acknowledged, the wavelength the LCTF
reports), and the twin's cameras render that state. A real camera takes its own frames.

Read-back values are rounded to a micro-degree, a micro-ampere and a picometre: finer than any of
the devices resolves (a K10CR1 microstep is 7.3 micro-degrees, a DMX level 2.7 mA), so a device
that reached its target renders exactly as the twin's device would, and one that did not renders
where it is.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from hwbridge.dome_targets import single_led
from hwbridge.errors import InputError
from hwbridge.lab import Lab, open_device
from hwbridge.protocols import Camera, LedArray, Reading, RotationStage, TunableFilter
from hwbridge.session import SessionDevices
from twin.devices.sim_devices import SimDomeDevices, SimGonioDevices, VirtualRig, session_rig

__all__ = ["LabDevices", "ReadBackFilter", "ReadBackLeds", "ReadBackStage"]

_DECIMALS = 6


class _ReadBack:
    """A real device whose state the twin's rig takes after each request."""

    def __init__(self, device: Any, rig: VirtualRig):
        self.device, self._rig = device, rig
        self.name = device.name

    def stage(self) -> None:
        self.device.stage()

    def unstage(self) -> None:
        self.device.unstage()

    def read(self) -> Reading:
        return dict(self.device.read())

    def describe(self) -> Reading:
        return dict(self.device.describe())


class ReadBackStage(_ReadBack):
    """A real rotation stage; the rig turns to the angle of its position counter."""

    device: RotationStage

    @property
    def range_deg(self) -> tuple[float, float]:
        return self.device.range_deg

    def set(self, target: dict[str, float]) -> None:
        self.device.set(target)
        (angle,) = self.device.read().values()
        self._rig.stage_deg = round(float(angle["value"]), _DECIMALS)


class ReadBackLeds(_ReadBack):
    """A real LED array; the rig lights the LEDs whose current it reports, at that current."""

    device: LedArray

    def __init__(self, device: LedArray, rig: VirtualRig):
        super().__init__(device, rig)
        self.count = device.count

    @property
    def current_range_ma(self) -> tuple[float, float]:
        return self.device.current_range_ma

    @property
    def current_step_ma(self) -> float:
        return self.device.current_step_ma

    def set(self, pattern: np.ndarray, current_ma: float | None = None) -> None:
        self.device.set(pattern, current_ma)
        (currents,) = self.device.read().values()
        value = np.asarray(currents["value"], np.float64)
        self._rig.led_pattern = value > 0
        self._rig.led_current_ma = round(float(value.max(initial=0.0)), _DECIMALS)

    def light(self, led: int, current_ma: float | None = None) -> None:
        self.set(single_led(led, self.count, self.name), current_ma)


class ReadBackFilter(_ReadBack):
    """A real tunable filter; the rig's band is the wavelength it reports."""

    device: TunableFilter

    @property
    def range_nm(self) -> tuple[float, float]:
        return self.device.range_nm

    def set(self, wavelength_nm: float) -> None:
        self.device.set(wavelength_nm)
        (band,) = self.device.read().values()
        self._rig.band_nm = round(float(band["value"]), 3)


def _roles(devices: SessionDevices) -> list[Any]:
    """The devices of ``devices`` besides the cameras."""
    roles = (devices.positioner, devices.leds, devices.tunable_filter, devices.monitor)
    return [device for device in roles if device is not None]


@dataclass(frozen=True, eq=False)
class LabDevices:
    """The devices of ``lab`` for a program whose twin devices are ``simulated``.

    Attributes
    ----------
    lab
        The devices file.
    simulated
        The program's simulated devices: their cameras render, their devices fill the roles the
        file leaves ``sim``.
    """

    lab: Lab
    simulated: SimDomeDevices | SimGonioDevices

    @property
    def backend(self) -> str:
        """``real`` where a device is on a wire, else ``sim``."""
        return "real" if self.lab.wired() else "sim"

    def __call__(self, seed: int = 0, steps: Sequence[int] | None = None) -> SessionDevices:
        """Build the devices for ``seed`` and ``steps`` and stage the real ones (one that fails
        to stage unstages the others)."""
        rig = session_rig(seed, steps)
        twin = self.simulated.on_rig(rig)
        if isinstance(self.simulated, SimDomeDevices):
            devices = self._dome(rig, twin, self.simulated)
        else:
            devices = self._gonio(rig, twin)
        simulated = {id(device) for device in (*twin.cameras.values(), *_roles(twin))}
        real = [
            device
            for device in (*devices.cameras.values(), *_roles(devices))
            if id(device) not in simulated
        ]
        staged: list[Any] = []
        try:
            for device in real:
                device.stage()
                staged.append(device)
        except BaseException:
            for device in staged:
                device.unstage()
            raise
        return devices

    def _cameras(self, twin: SessionDevices) -> dict[str, Camera]:
        cameras = dict(twin.cameras)
        for camera_id in cameras:
            entry = self.lab.camera(camera_id)
            if entry is not None:
                cameras[camera_id] = open_device(camera_id, entry)
        return cameras

    def _filter(self, rig: VirtualRig, twin: SessionDevices) -> TunableFilter | None:
        entry = self.lab.device("lctf")
        if entry is None:
            return twin.tunable_filter
        return ReadBackFilter(open_device("lctf", entry), rig)

    def _dome(
        self, rig: VirtualRig, twin: SessionDevices, simulated: SimDomeDevices
    ) -> SessionDevices:
        stage, leds = self.lab.device("stage"), self.lab.device("leds")
        return SessionDevices(
            cameras=self._cameras(twin),
            tunable_filter=self._filter(rig, twin),
            positioner=twin.positioner
            if stage is None
            else ReadBackStage(open_device("stage", stage, {"step_deg": simulated.step_deg}), rig),
            leds=twin.leds
            if leds is None
            else ReadBackLeds(open_device("leds", leds, {"count": simulated.led_count}), rig),
            monitor=twin.monitor,
        )

    def _gonio(self, rig: VirtualRig, twin: SessionDevices) -> SessionDevices:
        if self.lab.device("monitor") is not None:
            raise InputError(
                f"{self.lab.path}: monitor: a capture records the twin's lamp monitor; "
                "expected sim (spectwin lab check talks to a real spectrometer)"
            )
        return SessionDevices(
            cameras=self._cameras(twin),
            tunable_filter=self._filter(rig, twin),
            positioner=twin.positioner,
            monitor=twin.monitor,
        )
