"""Signals of the simulated dome's cameras: mean photo-electrons of a frame from the rig's state.

:class:`RenderedDomeSignal` renders (:mod:`twin.dome.render`) what one camera sees: the holder
with what the plan step puts on it (:mod:`twin.dome.holder`), turned to the angle the rotation
stage has set, lit by the LEDs the LED array has switched on (their intensity in proportion to
the drive current, the LED's nominal one at full scale). A render is a rate per pixel
(e-/s; all of the tunable filter's bands at once for the spectral camera), so one render per
(stage angle, LEDs, holder content, camera) serves every exposure of the HDR set and every
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
from twin.dome.render import DomeView, dome_scene_rates
from twin.materials import Material
from twin.render.node_transport import NodeScene
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
    led_full_scale_ma
        The LEDs' current at their nominal intensity
        (:class:`twin.components.lamps.PhosphorWhiteLED`).
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
    led_full_scale_ma: float
    pixels: int
    window: int
    spp: int
    bands_nm: tuple[float, ...]
    _scenes: dict = field(default_factory=dict, repr=False)

    def __getstate__(self) -> dict:
        return {**self.__dict__, "_scenes": {}}  # Mitsuba scenes stay in their process

    def node_scene(self, content: str) -> NodeScene:
        """The holder with ``content`` in the sample frame, for every stage angle (the last one
        kept)."""
        if content not in self._scenes:
            self._scenes.clear()
            self._scenes[content] = NodeScene(holder_scene_parts(content, self.material))
        return self._scenes[content]


class RenderedDomeSignal:
    """The rates of camera ``camera`` (an arc index, or ``"spectral"``) in the rig's state."""

    def __init__(self, scene: DomeScene, camera: int | str):
        self._scene, self._camera = scene, camera
        self._key: tuple | None = None
        self._rates: np.ndarray | None = None
        self._view: DomeView | None = None

    def __getstate__(self) -> dict:
        return {**self.__dict__, "_key": None, "_rates": None, "_view": None}

    def rates(self, content: str, stage_deg: float, leds: tuple[int, ...]) -> np.ndarray:
        """Rates ``(H, W, n_channels)`` of one state at full-scale current (the last kept)."""
        key = (content, stage_deg, leds)
        if key != self._key:
            scene = self._scene
            lit = "all" if len(leds) == scene.config.led_count else ",".join(map(str, leds))
            name = f"{content}|{stage_deg:.6f}|{lit}|{self._camera}"
            seed = zlib.crc32(name.encode()) & 0x7FFFFFFF
            if self._view is None:
                self._view = DomeView(
                    scene.config,
                    self._camera,
                    scene.pixels,
                    window=scene.window,
                    bands_nm=scene.bands_nm,
                )
            self._rates = dome_scene_rates(
                scene.config,
                scene.node_scene(content),
                self._view,
                stage_deg=stage_deg,
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
        rates = self.rates(content, rig.stage_deg, leds)
        scale = np.float32(exposure_s * rig.led_current_ma / self._scene.led_full_scale_ma)
        if self._camera == SPECTRAL_CAMERA:
            if rig.band_nm is None:
                raise ValueError("the filter has not been tuned yet")
            band = int(np.argmin(np.abs(np.asarray(self._scene.bands_nm) - rig.band_nm)))
            return rates[..., band] * scale
        return rates * scale
