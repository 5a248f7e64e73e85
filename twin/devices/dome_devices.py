"""The LED dome's devices for a capture session, simulated or real (thesis 10.2).

:class:`DomeDevices` is the recipe of the dome's rotation stage, LED array and LCTF, as
:class:`~twin.devices.sim_devices.SimGonioDevices` is the gonioreflectometer's: plain data that
builds and stages the devices when called. ``backend="sim"`` builds the simulated ones over a
fresh :class:`~twin.devices.sim_devices.VirtualRig`; ``backend="real"`` the drivers of
``hwbridge.drivers`` on their ports: the Thorlabs APT rotation stage
(:class:`~hwbridge.drivers.apt_rotation_stage.AptRotationStage`), the LEDs on DMX512 decoders
behind an Enttec DMX USB Pro (:class:`~hwbridge.drivers.dmx_led_array.DmxLedArray`) and the
VariSpec LCTF (:class:`~hwbridge.drivers.varispec.VariSpec`). Both backends pass the same
contract tests, so a plan (:func:`hwbridge.dome_plans.dome_run`) runs on either unchanged. The
cameras are the caller's (GenICam cameras on the real dome), handed over as they are.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from hwbridge.errors import InputError
from hwbridge.protocols import Camera, LedArray, RotationStage, TunableFilter
from hwbridge.session import SessionDevices
from twin.devices.sim_devices import (
    SimLedArray,
    SimRotationStage,
    SimTunableFilter,
    VirtualRig,
)
from twin.rigs.rig_config import DomeConfig

__all__ = ["DomeDevices"]

BACKENDS = ("sim", "real")


@dataclass(frozen=True, eq=False)
class DomeDevices:
    """The dome's stage, LEDs and LCTF for one session, as a recipe.

    Attributes
    ----------
    backend
        ``"sim"`` or ``"real"``.
    led_count, step_deg
        The dome's LEDs and the turn between two stage positions (``scenes/rigs/dome.yaml``:
        198 and 15 deg; :meth:`for_rig`).
    drive_current_ma
        Current of the LEDs a step switches on (``None``: the LED array's full scale).
    stage_port, led_port, lctf_port
        The real devices' serial ports (device names, or the emulators' ``apt://``,
        ``dmxusbpro://`` and ``varispec://``); needed with ``backend="real"``.
    cameras
        Camera id to camera, passed to the session as they are.
    """

    backend: str = "sim"
    led_count: int = 198
    step_deg: float = 15.0
    drive_current_ma: float | None = None
    stage_port: str | None = None
    led_port: str | None = None
    lctf_port: str | None = None
    cameras: Mapping[str, Camera] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.backend not in BACKENDS:
            raise InputError(f"backend: expected one of {BACKENDS}, got {self.backend!r}")
        if self.backend == "real":
            self._real_ports()

    def _real_ports(self) -> tuple[str, str, str]:
        """The serial ports of the real stage, LEDs and LCTF."""
        stage, leds, lctf = self.stage_port, self.led_port, self.lctf_port
        if not (stage and leds and lctf):
            ports = {"stage_port": stage, "led_port": leds, "lctf_port": lctf}
            missing = [key for key, port in ports.items() if not port]
            raise InputError(f"the real dome needs the serial ports {missing}")
        return stage, leds, lctf

    @classmethod
    def for_rig(cls, config: DomeConfig, **settings: Any) -> DomeDevices:
        """The recipe for the dome rig ``config``: its LED count and stage step."""
        return cls(led_count=config.led_count, step_deg=config.rotation_stage_step_deg, **settings)

    def __call__(self) -> SessionDevices:
        """Build the devices and stage them (a device that fails to stage unstages the others)."""
        stage: RotationStage
        leds: LedArray
        lctf: TunableFilter
        if self.backend == "sim":
            rig = VirtualRig()
            stage = SimRotationStage(rig, step_deg=self.step_deg)
            leds = SimLedArray(rig, self.led_count, drive_current_ma=self.drive_current_ma)
            lctf = SimTunableFilter(rig)
        else:
            from hwbridge.drivers.apt_rotation_stage import AptRotationStage
            from hwbridge.drivers.dmx_led_array import DmxLedArray
            from hwbridge.drivers.varispec import VariSpec

            stage_port, led_port, lctf_port = self._real_ports()
            stage = AptRotationStage(stage_port, step_deg=self.step_deg)
            leds = DmxLedArray(
                led_port, count=self.led_count, drive_current_ma=self.drive_current_ma
            )
            lctf = VariSpec(lctf_port)
        staged = []
        try:
            for device in (stage, leds, lctf):
                device.stage()
                staged.append(device)
        except BaseException:
            for device in staged:
                device.unstage()
            raise
        return SessionDevices(
            cameras=dict(self.cameras),
            positioner=stage,
            tunable_filter=lctf,
            leds=leds,
        )
