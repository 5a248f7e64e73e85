"""Simulated devices implementing the ``hwbridge.protocols`` interfaces over one virtual rig.

The tunable filter and the camera share a :class:`VirtualRig` state: the camera's frame depends on
the band the filter is tuned to. Frames come from the sensor model (``twin.sensor``) fed with
photo-electron rates per band; the noise of step ``k`` of a session with seed ``s`` is drawn from
``numpy.random.default_rng([s, k])`` so a resumed session reproduces an uninterrupted one.
Optional fault injection raises device timeouts on a fraction of calls.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from hwbridge.errors import BridgeInputError, DeviceTimeout
from twin.sensor import Sensor

__all__ = ["SimCamera", "SimTunableFilter", "VirtualRig"]


@dataclass
class VirtualRig:
    """State shared by the simulated devices of one rig."""

    band_nm: float | None = None
    fault_rate: float = 0.0
    fault_rng: np.random.Generator | None = None

    def maybe_fail(self, what: str) -> None:
        if (
            self.fault_rate
            and self.fault_rng is not None
            and self.fault_rng.random() < self.fault_rate
        ):
            raise DeviceTimeout(f"simulated timeout of {what}")


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
            raise BridgeInputError(f"{self.name}: {wavelength_nm} nm is outside {low}-{high} nm")
        self._rig.maybe_fail(f"{self.name}.set")
        self._rig.band_nm = float(wavelength_nm)

    def read(self) -> dict[str, dict[str, Any]]:
        return {
            f"{self.name}_wavelength_nm": {"value": self._rig.band_nm, "timestamp": time.time()}
        }

    def describe(self) -> dict[str, dict[str, Any]]:
        return {
            f"{self.name}_wavelength_nm": {
                "source": "simulated",
                "dtype": "number",
                "shape": [],
                "units": "nm",
            }
        }


class SimCamera:
    """A camera of the twin: photo-electron rates per band -> the sensor model -> raw frames.

    ``electron_rates(band_nm)`` returns the mean photo-electrons per second per pixel for the
    band the filter is tuned to (``None`` when the camera has no filter in front).
    """

    def __init__(
        self,
        rig: VirtualRig,
        sensor: Sensor,
        electron_rates: Callable[[float | None], np.ndarray],
        *,
        name: str = "camera",
    ):
        self.name, self._rig, self._sensor, self._rates = name, rig, sensor, electron_rates
        self._exposure_s = sensor.config.exposure_range_s[0]
        self._rng = np.random.default_rng()
        self._shutter_open = True

    @property
    def frame_shape(self) -> tuple[int, int]:
        return (self._sensor.height, self._sensor.width)

    def stage(self) -> None:
        """Nothing to open."""

    def unstage(self) -> None:
        """Nothing to close."""

    def set_exposure(self, exposure_s: float) -> None:
        self._sensor.mean_dark_electrons(exposure_s)  # validates against the camera's range
        self._exposure_s = float(exposure_s)

    def set_shutter(self, open_: bool) -> None:
        """Closed for dark frames: only dark signal reaches the sensor."""
        self._shutter_open = bool(open_)

    def set_step(self, seed: int, step: int) -> None:
        """Derive the noise of the next frame from the session seed and the step index."""
        self._rng = np.random.default_rng([seed, step])

    def snap(self) -> tuple[np.ndarray, dict[str, Any]]:
        self._rig.maybe_fail(f"{self.name}.snap")
        rates = self._rates(self._rig.band_nm) if self._shutter_open else np.zeros(self.frame_shape)
        electrons = np.asarray(rates, np.float32) * self._exposure_s
        frame = self._sensor.capture(electrons, self._exposure_s, self._rng)
        return frame, {"timestamp": time.time(), "exposure_s": self._exposure_s}

    def read(self) -> dict[str, dict[str, Any]]:
        return {f"{self.name}_exposure_s": {"value": self._exposure_s, "timestamp": time.time()}}

    def describe(self) -> dict[str, dict[str, Any]]:
        return {
            f"{self.name}_image": {
                "source": f"simulated {self._sensor.config.name}",
                "dtype": "array",
                "shape": list(self.frame_shape),
                "units": "DN",
            }
        }
