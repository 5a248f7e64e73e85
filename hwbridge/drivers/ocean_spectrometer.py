"""An Ocean Optics spectrometer (the thesis used a USB4000, section 3.2.2) through ``seabreeze``.

Implements ``hwbridge.protocols.Spectrometer`` as the lamp monitor. Install the optional extra
``spectwin[spectrometer]``; tests on a real device are opt-in (``pytest -m hardware``).
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

import numpy as np

from hwbridge.errors import DeviceError, InputError
from hwbridge.protocols import description, reading

if TYPE_CHECKING:
    from seabreeze.spectrometers import Spectrometer

__all__ = ["OceanSpectrometer"]


class OceanSpectrometer:
    """The spectrometer with ``serial_number`` (or the first one found) on the USB bus."""

    def __init__(
        self,
        *,
        serial_number: str | None = None,
        integration_s: float = 0.01,
        name: str = "monitor",
    ):
        if not integration_s > 0:
            raise InputError(f"integration_s: expected a positive time, got {integration_s}")
        self.name, self._serial, self._integration_s = name, serial_number, integration_s
        self._device: Spectrometer | None = None
        self._last: tuple[np.ndarray, np.ndarray, float] | None = None

    def stage(self) -> None:
        import seabreeze

        seabreeze.use("cseabreeze")
        from seabreeze.spectrometers import Spectrometer, list_devices

        devices = list_devices()
        serials = [device.serial_number for device in devices]
        if not devices:
            raise DeviceError(f"{self.name}: no Ocean Optics spectrometer found on USB")
        if self._serial is not None and self._serial not in serials:
            raise DeviceError(
                f"{self.name}: no spectrometer with serial {self._serial!r}; found {serials}"
            )
        self._device = Spectrometer.from_serial_number(self._serial)
        self._device.integration_time_micros(int(self._integration_s * 1e6))

    def unstage(self) -> None:
        if self._device is not None:
            self._device.close()
            self._device = None

    def identity(self) -> dict[str, str]:
        """The spectrometer's model and serial number (seabreeze reports no firmware)."""
        if self._device is None:
            raise DeviceError(f"{self.name}: not staged; call stage() first")
        return {
            "model": f"Ocean Optics {self._device.model}",
            "serial": str(self._device.serial_number),
            "firmware": "?",
        }

    def trigger(self) -> None:
        """Take one spectrum."""
        if self._device is None:
            raise DeviceError(f"{self.name}: not staged; call stage() first")
        self._last = (self._device.wavelengths(), self._device.intensities(), time.time())

    def read(self) -> dict[str, dict[str, Any]]:
        if self._last is None:
            raise DeviceError(f"{self.name}: no spectrum yet; call trigger() first")
        wavelengths, intensities, timestamp = self._last
        return {
            **reading(f"{self.name}_wavelengths_nm", wavelengths, timestamp),
            **reading(f"{self.name}_counts", intensities, timestamp),
        }

    def describe(self) -> dict[str, dict[str, Any]]:
        shape = [] if self._last is None else [len(self._last[0])]
        return {
            **description(
                f"{self.name}_wavelengths_nm",
                source="seabreeze",
                dtype="array",
                shape=shape,
                units="nm",
            ),
            **description(
                f"{self.name}_counts",
                source="seabreeze",
                dtype="array",
                shape=shape,
                units="counts",
            ),
        }
