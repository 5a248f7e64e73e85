"""A GenICam camera (GigE Vision, USB3 Vision, ...) through ``harvesters`` and a GenTL producer.

Implements ``hwbridge.protocols.Camera``. The thesis's RGB cameras (SVS-Vistek 4022, section
10.2.1) are GigE Vision devices; any GenTL producer (``.cti``) works, including the simulated
"Viky" producer shipped in the ``genicam`` package, which the tests use. Install the optional
extra ``spectwin[genicam]``.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from hwbridge.errors import DeviceError, DeviceTimeout, InputError
from hwbridge.protocols import description, reading

if TYPE_CHECKING:
    from harvesters.core import Harvester, ImageAcquirer

__all__ = ["GenICamCamera", "simulated_producer"]

_INFO = ("vendor", "model", "serial_number", "version")
_EXPOSURE_FEATURES = ("ExposureTime", "ExposureTimeAbs")
"""The exposure time's feature: the SFNC name, then that of older GigE Vision cameras."""
_EXPOSURE_TOLERANCE = 1e-3
"""Largest relative difference between the exposure asked for and the one read back."""


def simulated_producer() -> Path:
    """The simulated GenTL producer of the ``genicam`` package."""
    import genicam

    return Path(genicam.__file__).resolve().parent / "viky.cti"


class GenICamCamera:
    """The camera with ``serial_number`` (or the first one) of the GenTL producer ``cti``."""

    def __init__(
        self,
        cti: str | Path,
        *,
        serial_number: str | None = None,
        name: str = "camera",
        timeout_s: float = 5.0,
    ):
        self.name = name
        self._cti, self._serial, self._timeout_s = Path(cti), serial_number, timeout_s
        self._harvester: Harvester | None = None
        self._acquirer: ImageAcquirer | None = None
        self._exposure_s: float | None = None
        self._info: dict[str, Any] = {}

    def stage(self) -> None:
        from harvesters.core import Harvester

        if not self._cti.is_file():
            raise InputError(f"{self.name}: GenTL producer {self._cti} does not exist")
        self.unstage()
        self._harvester = Harvester()
        try:
            self._acquirer = self._create_acquirer(self._harvester)
        except BaseException:
            # A failed stage releases the producer: a harvester left behind would hide its
            # cameras from the next one in this process.
            self.unstage()
            raise
        if self._exposure_s is not None:
            self.set_exposure(self._exposure_s)

    def _create_acquirer(self, harvester: Harvester) -> ImageAcquirer:
        harvester.add_file(str(self._cti))
        harvester.update()
        devices = harvester.device_info_list
        if not devices:
            raise DeviceError(f"{self.name}: the producer {self._cti.name} offers no camera")
        serials = [info.serial_number for info in devices]
        if self._serial is None:
            index = 0
        elif self._serial in serials:
            index = serials.index(self._serial)
        else:
            raise DeviceError(
                f"{self.name}: no camera with serial {self._serial!r}; found {serials}"
            )
        found = devices[index]
        self._info = {key: getattr(found, key, "?") for key in _INFO}
        return harvester.create(index)

    def unstage(self) -> None:
        if self._acquirer is not None:
            self._acquirer.destroy()
            self._acquirer = None
        if self._harvester is not None:
            self._harvester.reset()
            self._harvester = None

    def identity(self) -> dict[str, str]:
        """The camera's vendor and model, serial number and version as its producer lists
        them; its node map is read (``Width``) to know it answers."""
        if int(self._node_map().Width.value) <= 0:
            raise DeviceError(f"{self.name}: the camera reports no image width")
        return {
            "model": f"{self._info.get('vendor', '?')} {self._info.get('model', '?')}",
            "serial": str(self._info.get("serial_number", "?")),
            "firmware": str(self._info.get("version", "?")),
        }

    @property
    def frame_shape(self) -> tuple[int, int]:
        node_map = self._node_map()
        return (int(node_map.Height.value), int(node_map.Width.value))

    def set_exposure(self, exposure_s: float) -> None:
        """Set the exposure time (``ExposureTime``, or ``ExposureTimeAbs`` of older GigE Vision
        cameras; microseconds) and read it back: a camera that took another exposure, or has
        no exposure time to set, is refused (its frames would be stored under an exposure they
        were not taken at)."""
        if not np.isfinite(exposure_s) or exposure_s <= 0:
            raise InputError(f"{self.name}: expected a positive exposure time, got {exposure_s}")
        node_map = self._node_map()
        feature = next((name for name in _EXPOSURE_FEATURES if hasattr(node_map, name)), None)
        if feature is None:
            raise DeviceError(
                f"{self.name}: the camera ({self._info.get('model', '?')}) has no ExposureTime "
                "feature; expected a camera whose exposure time can be set"
            )
        node = getattr(node_map, feature)
        node.value = exposure_s * 1e6
        taken_s = float(node.value) / 1e6
        if abs(taken_s / exposure_s - 1) > _EXPOSURE_TOLERANCE:
            raise DeviceError(
                f"{self.name}: asked for an exposure of {exposure_s:g} s, the camera reads back "
                f"{taken_s:g} s; expected the plan's exposures within the camera's range"
            )
        self._exposure_s = taken_s

    def snap(self) -> tuple[np.ndarray, dict[str, Any]]:
        """One frame as uint16 ``(H, W)``: mono and Bayer formats as delivered, packed colour
        formats (the simulated producer's RGBa8) averaged over their colour components."""
        acquirer = self._require()
        acquirer.start()
        try:
            with acquirer.fetch(timeout=self._timeout_s) as buffer:
                component = buffer.payload.components[0]
                data = np.asarray(component.data)
                height, width, pixel_format = (
                    component.height,
                    component.width,
                    component.data_format,
                )
                channels = data.size // (height * width)
                image = data.reshape(height, width, channels)
                if pixel_format.startswith(("RGB", "BGR")):
                    colour = image[..., : min(channels, 3)].astype(np.float64)
                    frame = np.rint(colour.mean(axis=-1)).astype(np.uint16)
                else:
                    frame = image[..., 0].astype(np.uint16)
        except Exception as error:  # harvesters raises its own timeout types
            if "timeout" in type(error).__name__.lower():
                raise DeviceTimeout(f"{self.name}: no frame within {self._timeout_s} s") from error
            raise
        finally:
            acquirer.stop()
        return frame, {
            "timestamp": time.time(),
            "exposure_s": self._exposure_s,
            "pixel_format": pixel_format,
        }

    def read(self) -> dict[str, dict[str, Any]]:
        return reading(f"{self.name}_exposure_s", self._exposure_s)

    def describe(self) -> dict[str, dict[str, Any]]:
        return description(
            f"{self.name}_image",
            source=f"GenICam via {self._cti.name}",
            dtype="array",
            shape=list(self.frame_shape),
            units="DN",
        )

    def _require(self) -> ImageAcquirer:
        if self._acquirer is None:
            raise DeviceError(f"{self.name}: not staged; call stage() first")
        return self._acquirer

    def _node_map(self) -> Any:
        return self._require().remote_device.node_map
