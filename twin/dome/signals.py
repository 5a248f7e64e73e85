"""Signals of the simulated dome's cameras: mean photo-electrons of a frame from the rig's state.

:class:`RenderedDomeSignal` renders, with Mitsuba, what one camera sees: the holder with what
the plan step puts on it (:mod:`twin.dome.holder`), turned to the stage position the rotation
stage has set, lit by the LEDs the LED array has switched on. A render is a rate per pixel
(e-/s; all of the tunable filter's bands at once for the spectral camera), so one render per
(stage position, LEDs, holder content, camera) serves every exposure of the HDR set and every
band: the camera keeps its last render, and a plan that takes a camera's frames of one LED
together renders it once. Each render's Monte Carlo seed follows from what it shows, so a
resumed or distributed capture renders the same images as an uninterrupted one.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, field

import numpy as np

from hwbridge.dome_layout import SPECTRAL_CAMERA
from twin.devices.sim_devices import VirtualRig
from twin.dome.holder import holder_scene_parts
from twin.dome.render import DomeView, dome_shape_rates, dome_shapes
from twin.materials import Material
from twin.rigs.rig_config import DomeConfig

__all__ = ["DomeScene", "RenderedDomeSignal"]


@dataclass(eq=False)
class DomeScene:
    """The dome's world for one plan, shared by the cameras' signals.

    Attributes
    ----------
    config
        The dome rig.
    material
        The material of ``sample`` and ``alignment`` frames (``None`` for a calibration).
    holders
        Per plan step, what lies on the holder (:func:`twin.dome.holder.holder_content`).
    stage_angles_deg
        Angle of every stage position.
    pixels, window
        Pixels across the 0.2 m field and the centred window read out.
    spp
        Samples per pixel of the renders.
    bands_nm
        The spectral camera's bands (one render channel each).
    """

    config: DomeConfig
    material: Material | None
    holders: tuple[str | None, ...]
    stage_angles_deg: tuple[float, ...]
    pixels: int
    window: int
    spp: int
    bands_nm: tuple[float, ...]
    _shapes: dict = field(default_factory=dict, repr=False)

    def __getstate__(self) -> dict:
        return {**self.__dict__, "_shapes": {}}  # Mitsuba shapes stay in their process

    def shapes(self, content: str, view_id: int) -> dict[str, object]:
        """Mitsuba shapes of the holder with ``content`` at stage position ``view_id`` (the
        last ones kept)."""
        key = (content, view_id)
        if key not in self._shapes:
            self._shapes.clear()
            parts = holder_scene_parts(content, self.material)
            self._shapes[key] = dome_shapes(parts, self.stage_angles_deg[view_id])
        return self._shapes[key]


class RenderedDomeSignal:
    """The rates of camera ``camera`` (an arc index, or ``"spectral"``) in the rig's state."""

    def __init__(self, scene: DomeScene, camera: int | str):
        self._scene, self._camera = scene, camera
        self._key: tuple | None = None
        self._rates: np.ndarray | None = None
        self._view: DomeView | None = None

    def __getstate__(self) -> dict:
        return {**self.__dict__, "_key": None, "_rates": None, "_view": None}

    def rates(self, content: str, view_id: int, leds: tuple[int, ...]) -> np.ndarray:
        """Rates ``(H, W, n_channels)`` of one state (the last state's kept)."""
        key = (content, view_id, leds)
        if key != self._key:
            scene = self._scene
            lit = "all" if len(leds) == scene.config.led_count else ",".join(map(str, leds))
            seed = zlib.crc32(f"{content}|{view_id}|{lit}|{self._camera}".encode()) & 0x7FFFFFFF
            if self._view is None:
                self._view = DomeView(
                    scene.config,
                    self._camera,
                    scene.pixels,
                    window=scene.window,
                    bands_nm=scene.bands_nm,
                )
            self._rates = dome_shape_rates(
                scene.config,
                scene.shapes(content, view_id),
                self._view,
                leds=leds,
                spp=scene.spp,
                seed=seed,
            ).astype(np.float32)
            self._key = key
        return self._rates

    def __call__(self, rig: VirtualRig, start_s: float, exposure_s: float) -> np.ndarray:
        content = self._scene.holders[rig.step]
        if content is None or rig.led_pattern is None or not rig.led_pattern.any():
            side = self._scene.window
            shape = (side, side) if self._camera == SPECTRAL_CAMERA else (side, side, 3)
            return np.zeros(shape, np.float32)
        leds = tuple(np.flatnonzero(rig.led_pattern).tolist())
        rates = self.rates(content, rig.view_id, leds)
        if self._camera == SPECTRAL_CAMERA:
            if rig.band_nm is None:
                raise ValueError("the filter has not been tuned yet")
            band = int(np.argmin(np.abs(np.asarray(self._scene.bands_nm) - rig.band_nm)))
            return rates[..., band] * np.float32(exposure_s)
        return rates * np.float32(exposure_s)
