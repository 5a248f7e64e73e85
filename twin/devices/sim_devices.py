"""Simulated devices implementing the ``hwbridge.protocols`` interfaces over one virtual rig.

The tunable filter, the positioner and the camera share a :class:`VirtualRig` state: the camera's
frame depends on the band the filter is tuned to and the view the positioner has set. Frames come
from the sensor model (``twin.sensor.model``) fed by a *signal*: the mean photo-electrons of the
current state over the exposure window (the lamp's flicker included, see
``twin.gonio.signals``).

A rig is built for the plan steps a session will take, in order (all of them, unless it resumes
or is one task of a distributed capture) and for the session's seed; each frame taken moves it
on to the next step, so the camera knows which step it takes from the rig, not from the session.
Step ``k`` of a session with seed ``s`` draws its noise from ``numpy.random.default_rng([s, k])``
and starts its exposure at the plan's start time for that step, so a resumed session reproduces
an uninterrupted one, and a capture split over Dask workers a serial one. Optional fault injection
raises timeouts and disconnects.

The dome's rotation stage (:class:`SimRotationStage`) and LEDs (:class:`SimLedArray`) check their
requests as the real drivers do (:mod:`hwbridge.dome_targets`) and pass the same contract tests.

:class:`SimGonioDevices` is the recipe of the gonioreflectometer's devices: plain data that builds
them over a fresh :class:`VirtualRig` when called, in the process that runs the steps.
:class:`SimDomeDevices` is the simulated dome's, cameras included (their signals read the stage,
LEDs and filter of the same rig: rendered captures, ``twin.dome``);
:class:`twin.devices.lab_devices.LabDevices` puts a lab's real devices in their place.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

import numpy as np

from hwbridge.dome_targets import check_current_ma, led_pattern, single_led, stage_angle_deg
from hwbridge.errors import DeviceDisconnected, DeviceTimeout, InputError
from hwbridge.protocols import Reading, description, reading
from hwbridge.schema import NO_VIEW
from hwbridge.session import SessionDevices
from recon.spectra import DEFAULT_GRID, WavelengthGrid
from twin.components.lamps import HMILamp, LightSource
from twin.devices.dome_spectrometer import DomeSpectrometer
from twin.sensor.model import Sensor

__all__ = [
    "DeviceRecipe",
    "Signal",
    "SimCamera",
    "SimDomeDevices",
    "SimGonioDevices",
    "SimLamp",
    "SimLedArray",
    "SimPositioner",
    "SimRotationStage",
    "SimSpectrometer",
    "SimTunableFilter",
    "VirtualRig",
    "session_rig",
]


@dataclass
class VirtualRig:
    """State shared by the simulated devices of one rig.

    ``steps`` are the plan steps the rig takes, in this order (``None``: every step of the
    plan, from the first), ``seed`` the session's; each frame taken moves the rig on to the
    next step (:meth:`frame_taken`).
    """

    band_nm: float | None = None
    view_id: int = NO_VIEW
    lamp_on: bool = True
    led_pattern: np.ndarray | None = None
    led_current_ma: float = 0.0
    stage_deg: float = 0.0
    clock_s: float = 0.0  # start of the current exposure (set by the camera for each step)
    seed: int = 0
    steps: Sequence[int] | None = None
    frames_taken: int = 0
    fault_rate: float = 0.0
    fault_rng: np.random.Generator | None = None

    @property
    def step(self) -> int:
        """The plan step being taken: what it places on the holder, its noise, its start."""
        if self.steps is None:
            return self.frames_taken
        if self.frames_taken >= len(self.steps):
            raise InputError(
                f"the simulated rig was built for {len(self.steps)} steps and has taken them all"
            )
        return int(self.steps[self.frames_taken])

    def frame_taken(self) -> None:
        """Move on to the next step."""
        self.frames_taken += 1

    def maybe_fail(self, what: str) -> None:
        """With probability ``fault_rate``, a timeout or (as often) a disconnect."""
        if not self.fault_rate or self.fault_rng is None:
            return
        if self.fault_rng.random() >= self.fault_rate:
            return
        if self.fault_rng.random() < 0.5:
            raise DeviceTimeout(f"simulated timeout of {what}")
        raise DeviceDisconnected(f"simulated disconnect of {what}")


class SimTunableFilter:
    """A VariSpec-like filter: tuning sets the rig's band."""

    def __init__(
        self, rig: VirtualRig, *, name: str = "lctf", range_nm: tuple[float, float] = (400.0, 720.0)
    ):
        self.name, self._rig, self._range = name, rig, range_nm

    @property
    def range_nm(self) -> tuple[float, float]:
        return self._range

    def stage(self) -> None:
        """Nothing to open."""

    def unstage(self) -> None:
        """Nothing to close."""

    def set(self, wavelength_nm: float) -> None:
        low, high = self._range
        if not low <= wavelength_nm <= high:
            raise InputError(f"{self.name}: {wavelength_nm} nm is outside {low}-{high} nm")
        self._rig.maybe_fail(f"{self.name}.set")
        self._rig.band_nm = float(wavelength_nm)

    def read(self) -> Reading:
        return reading(f"{self.name}_wavelength_nm", self._rig.band_nm)

    def describe(self) -> Reading:
        return description(
            f"{self.name}_wavelength_nm", source="simulated", dtype="number", shape=[], units="nm"
        )


class SimLamp:
    """The gonioreflectometer's lamp: on or off (the camera sees nothing when it is off)."""

    def __init__(self, rig: VirtualRig, *, name: str = "lamp"):
        self.name, self._rig = name, rig

    def set(self, on: bool) -> None:
        self._rig.maybe_fail(f"{self.name}.set")
        self._rig.lamp_on = bool(on)

    def read(self) -> Reading:
        return reading(f"{self.name}_on", self._rig.lamp_on)

    def describe(self) -> Reading:
        return description(
            f"{self.name}_on", source="simulated", dtype="boolean", shape=[], units=""
        )


class SimLedArray:
    """The dome's LEDs: any on/off pattern over ``count`` LEDs, those on at one current of up to
    ``max_current_ma`` (any value: the simulated driver is continuous)."""

    def __init__(
        self,
        rig: VirtualRig,
        count: int,
        *,
        name: str = "leds",
        max_current_ma: float = 700.0,
        drive_current_ma: float | None = None,
    ):
        self.name, self._rig, self.count = name, rig, count
        self._max_current_ma = max_current_ma
        self._drive_current_ma = check_current_ma(
            max_current_ma if drive_current_ma is None else drive_current_ma,
            self.current_range_ma,
            name,
        )

    @property
    def current_range_ma(self) -> tuple[float, float]:
        return (0.0, self._max_current_ma)

    @property
    def current_step_ma(self) -> float:
        return 0.0

    def stage(self) -> None:
        """Nothing to open."""

    def unstage(self) -> None:
        """Nothing to close."""

    def set(self, pattern: np.ndarray, current_ma: float | None = None) -> None:
        pattern = led_pattern(pattern, self.count, self.name)
        current = check_current_ma(
            self._drive_current_ma if current_ma is None else current_ma,
            self.current_range_ma,
            self.name,
        )
        self._rig.maybe_fail(f"{self.name}.set")
        self._rig.led_pattern, self._rig.led_current_ma = pattern, current

    def light(self, led: int, current_ma: float | None = None) -> None:
        self.set(single_led(led, self.count, self.name), current_ma)

    def read(self) -> Reading:
        pattern = self._rig.led_pattern
        currents = np.zeros(self.count) if pattern is None else pattern * self._rig.led_current_ma
        return reading(f"{self.name}_current_ma", currents)

    def describe(self) -> Reading:
        return description(
            f"{self.name}_current_ma",
            source="simulated",
            dtype="array",
            shape=[self.count],
            units="mA",
        )


class SimRotationStage:
    """The dome's rotation stage: turning it sets the rig's stage angle at once."""

    def __init__(
        self,
        rig: VirtualRig,
        *,
        step_deg: float = 15.0,
        range_deg: tuple[float, float] = (0.0, 360.0),
        name: str = "stage",
    ):
        self.name, self._rig, self.step_deg, self._range_deg = name, rig, step_deg, range_deg

    @property
    def range_deg(self) -> tuple[float, float]:
        return self._range_deg

    def stage(self) -> None:
        """Nothing to open."""

    def unstage(self) -> None:
        """Nothing to close."""

    def set(self, target: dict[str, float]) -> None:
        angle = stage_angle_deg(
            target, step_deg=self.step_deg, range_deg=self._range_deg, name=self.name
        )
        self._rig.maybe_fail(f"{self.name}.set")
        self._rig.stage_deg = angle

    def read(self) -> Reading:
        return reading(f"{self.name}_angle_deg", self._rig.stage_deg)

    def describe(self) -> Reading:
        return description(
            f"{self.name}_angle_deg", source="simulated", dtype="number", shape=[], units="deg"
        )


class SimSpectrometer:
    """The lamp monitor (thesis 3.3): the lamp's spectrum integrated over the current exposure,
    drift included, through a fixed collection efficiency."""

    def __init__(
        self,
        rig: VirtualRig,
        lamp: LightSource,
        grid: WavelengthGrid,
        *,
        efficiency: float = 1e-3,
        name: str = "monitor",
    ):
        self.name, self._rig, self._lamp, self._grid, self._efficiency = (
            name,
            rig,
            lamp,
            grid,
            efficiency,
        )
        self._last: np.ndarray | None = None

    @property
    def samples(self) -> int:
        return self._grid.size

    def trigger(self) -> None:
        self._rig.maybe_fail(f"{self.name}.trigger")
        spectrum = self._lamp.exposure_integral(self._grid, self._rig.clock_s, 1.0).values
        self._last = self._efficiency * spectrum * (1.0 if self._rig.lamp_on else 0.0)

    def read(self) -> Reading:
        if self._last is None:
            raise InputError(f"{self.name}: no spectrum yet; call trigger() first")
        return reading(f"{self.name}_counts", self._last)

    def describe(self) -> Reading:
        return description(
            f"{self.name}_counts",
            source="simulated",
            dtype="array",
            shape=[self.samples],
            units="counts",
        )


class SimPositioner:
    """The gonioreflectometer's robot and rail, addressed by view (direction pair) index, or the
    dome's rotation stage, addressed by stage position."""

    def __init__(self, rig: VirtualRig, views: int, *, name: str = "goniometer"):
        self.name, self._rig, self._views = name, rig, views

    def set(self, target: dict[str, float]) -> None:
        view = int(target["view_id"])
        if not 0 <= view < self._views:
            raise InputError(f"{self.name}: view_id {view} is not in 0..{self._views - 1}")
        self._rig.maybe_fail(f"{self.name}.set")
        self._rig.view_id = view

    def read(self) -> Reading:
        return reading(f"{self.name}_view_id", self._rig.view_id)

    def describe(self) -> Reading:
        return description(
            f"{self.name}_view_id", source="simulated", dtype="integer", shape=[], units=""
        )


Signal = Callable[[VirtualRig, float, float], np.ndarray]
"""(rig state, exposure start in s, exposure in s) -> mean photo-electrons per pixel."""


class SimCamera:
    """A camera of the twin: the signal of the rig's state -> the sensor model -> raw frames.

    ``start_times_s[k]`` is when the exposure of plan step ``k`` starts (``hwbridge.plans.
    plan_start_times_s``): it sets the lamp's flicker phase for that frame. Which step a frame
    is, the camera reads from the rig (:attr:`VirtualRig.step`).
    """

    def __init__(
        self,
        rig: VirtualRig,
        sensor: Sensor,
        signal: Signal,
        start_times_s: np.ndarray,
        *,
        name: str = "camera",
    ):
        self.name, self._rig, self._sensor, self._signal = name, rig, sensor, signal
        self._start_times_s = np.asarray(start_times_s, dtype=np.float64)
        self._exposure_s = sensor.config.exposure_range_s[0]
        self._shutter_open = True

    @property
    def frame_shape(self) -> tuple[int, int]:
        return (self._sensor.height, self._sensor.width)

    def stage(self) -> None:
        """Nothing to open."""

    def unstage(self) -> None:
        """Nothing to close."""

    def set_exposure(self, exposure_s: float) -> None:
        self._sensor.check_exposure(exposure_s)
        self._exposure_s = float(exposure_s)

    def set_shutter(self, open_: bool) -> None:
        """Closed for dark frames: only dark signal reaches the sensor."""
        self._shutter_open = bool(open_)

    def snap(self) -> tuple[np.ndarray, dict[str, Any]]:
        """The frame of the rig's step: its noise drawn from ``[seed, step]``, its exposure
        starting at the step's start time; the rig moves on to its next step."""
        self._rig.maybe_fail(f"{self.name}.snap")
        step = self._rig.step
        start_s = float(self._start_times_s[step])
        self._rig.clock_s = start_s
        if self._shutter_open and self._rig.lamp_on:
            electrons = np.asarray(self._signal(self._rig, start_s, self._exposure_s), np.float32)
        else:  # shutter closed: dark signal only (R, G, B planes for a colour sensor)
            channels = (3,) if self._sensor.is_colour else ()
            electrons = np.zeros((*self.frame_shape, *channels), np.float32)
        rng = np.random.default_rng([self._rig.seed, step])
        frame = self._sensor.capture(electrons, self._exposure_s, rng)
        self._rig.frame_taken()
        return frame, {"timestamp": time.time(), "exposure_s": self._exposure_s}

    def read(self) -> Reading:
        return reading(f"{self.name}_exposure_s", self._exposure_s)

    def describe(self) -> Reading:
        return description(
            f"{self.name}_image",
            source=f"simulated {self._sensor.config.name}",
            dtype="array",
            shape=list(self.frame_shape),
            units="DN",
        )


class DeviceRecipe(Protocol):
    """Builds a session's devices, in the process that takes its steps, for the session
    ``seed`` and the plan ``steps`` they take, in this order (``None``: every step); its
    ``backend`` (``sim`` or ``real``) is the store's."""

    @property
    def backend(self) -> str: ...

    def __call__(self, seed: int = 0, steps: Sequence[int] | None = None) -> SessionDevices: ...


def session_rig(
    seed: int, steps: Sequence[int] | None, fault_rate: float = 0.0, fault_seed: int = 0
) -> VirtualRig:
    """The rig of a session with ``seed`` taking plan ``steps`` (``None``: all), its injected
    faults drawn from ``[fault_seed, 99]``."""
    return VirtualRig(
        seed=seed,
        steps=None if steps is None else tuple(steps),
        fault_rate=fault_rate,
        fault_rng=np.random.default_rng([fault_seed, 99]),
    )


@dataclass(frozen=True, eq=False)
class SimGonioDevices:
    """The simulated gonioreflectometer's devices for one plan, as a recipe.

    Calling it (a :class:`DeviceRecipe`) builds, over a fresh :class:`VirtualRig` for the
    session's seed and steps, the camera ``camera_id`` (``sensor`` fed by ``signal``, exposure
    ``k`` starting at ``start_times_s[k]``), the LCTF, the positioner over ``views`` views and
    the HMI lamp monitor. It holds plain data, so it pickles: each Dask worker of a distributed
    capture builds its own devices from it (:mod:`twin.devices.cluster`).

    Attributes
    ----------
    camera_id
        The camera's id in the plan.
    sensor
        Sensor model of the camera (its window is the frame shape).
    signal
        Mean photo-electrons of the rig's state (:mod:`twin.gonio.signals`).
    start_times_s
        Exposure start of every plan step (:func:`hwbridge.plans.plan_start_times_s`).
    views
        Number of views (direction pairs) the positioner knows.
    fault_rate, fault_seed
        Injected device faults per call and the seed of their draws (``[fault_seed, 99]``);
        each build starts the draws afresh.
    """

    camera_id: str
    sensor: Sensor
    signal: Signal
    start_times_s: np.ndarray
    views: int
    fault_rate: float = 0.0
    fault_seed: int = 0
    backend: ClassVar[str] = "sim"

    def __call__(self, seed: int = 0, steps: Sequence[int] | None = None) -> SessionDevices:
        return self.on_rig(session_rig(seed, steps, self.fault_rate, self.fault_seed))

    def on_rig(self, rig: VirtualRig) -> SessionDevices:
        """The devices over ``rig``."""
        camera = SimCamera(rig, self.sensor, self.signal, self.start_times_s, name=self.camera_id)
        return SessionDevices(
            cameras={self.camera_id: camera},
            tunable_filter=SimTunableFilter(rig),
            positioner=SimPositioner(rig, self.views),
            monitor=SimSpectrometer(rig, HMILamp(), DEFAULT_GRID),
        )


@dataclass(frozen=True, eq=False)
class SimDomeDevices:
    """The simulated LED dome's devices for one plan, as a recipe (it pickles, like
    :class:`SimGonioDevices`).

    Calling it (a :class:`DeviceRecipe`) builds, over a fresh :class:`VirtualRig` for the
    session's seed and steps, one camera per entry of ``cameras`` (its sensor fed by its signal,
    exposure ``k`` starting at ``start_times_s[k]``), the tunable filter in front of the
    spectral camera, the rotation stage (:class:`SimRotationStage`) and the array of
    ``led_count`` LEDs (:class:`SimLedArray`, at full scale unless a step asks for another
    current).

    Attributes
    ----------
    cameras
        ``(camera id, sensor, signal)`` of every camera of the plan.
    start_times_s
        Exposure start of every plan step (:func:`hwbridge.dome_plans.dome_start_times_s`).
    step_deg
        The stage's turn between two stage positions.
    led_count, led_full_scale_ma
        Number of LEDs and the current at which they emit their nominal intensity.
    fault_rate, fault_seed
        Injected device faults per call and the seed of their draws (``[fault_seed, 99]``).
    spectrometer
        The spectrometer on the white standard (the session's monitor), or none.
    """

    cameras: tuple[tuple[str, Sensor, Signal], ...]
    start_times_s: np.ndarray
    step_deg: float
    led_count: int
    led_full_scale_ma: float = 700.0
    fault_rate: float = 0.0
    fault_seed: int = 0
    spectrometer: DomeSpectrometer | None = None
    backend: ClassVar[str] = "sim"

    def __call__(self, seed: int = 0, steps: Sequence[int] | None = None) -> SessionDevices:
        return self.on_rig(session_rig(seed, steps, self.fault_rate, self.fault_seed))

    def on_rig(self, rig: VirtualRig) -> SessionDevices:
        """The devices over ``rig``."""
        return SessionDevices(
            monitor=None if self.spectrometer is None else self.spectrometer.on_rig(rig),
            cameras={
                camera_id: SimCamera(rig, sensor, signal, self.start_times_s, name=camera_id)
                for camera_id, sensor, signal in self.cameras
            },
            tunable_filter=SimTunableFilter(rig),
            positioner=SimRotationStage(rig, step_deg=self.step_deg),
            leds=SimLedArray(rig, self.led_count, max_current_ma=self.led_full_scale_ma),
        )
