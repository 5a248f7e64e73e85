"""Signals of the simulated dome's cameras: mean photo-electrons of a frame from the rig's state.

:class:`RenderedDomeSignal` renders (:mod:`twin.dome.render`) what one camera sees: the holder
with what the plan step puts on it (:mod:`twin.dome.holder`), turned to the angle the rotation
stage has set, lit by the LEDs the LED array has switched on (their intensity in proportion to
the drive current, the LED's nominal one at full scale). A render is a rate per pixel
(e-/s; all of the tunable filter's bands at once for the spectral camera), so one render per
(stage angle, LEDs, holder content, camera) serves every exposure of the HDR set and every
band: the camera keeps its last render, and a plan that takes a camera's frames of one LED
together renders it once.

By default (``led_renders="pose"``) the LEDs a plan switches on one at a time are rendered
together, per camera, stage angle and holder content: one pass traces the camera's paths and
gives every LED's image (:func:`twin.dome.render.dome_scene_rates` with ``each``), in blocks of
LEDs that keep a pass's images within :data:`PASS_MEMORY_BYTES`. ``led_renders="single"``
renders one LED at a time, as before. Where the LEDs lit one at a time at a stage position
all fit in one pass of every channel (an RGB camera of a full run at 64 texels), a frame with
all of them lit together (a run's alignment frame) is the sum of that pass's images: light
transport is linear in the light, so the sum has the expectation of a render of the LEDs
together, and less noise (every LED is lit at a path's bounce, where the render of the LEDs
together samples one). Each render's Monte Carlo seed follows from what it shows (with passes:
the content, stage angle and camera; one LED's image does not depend on the others of its
block), so a resumed or distributed capture renders the same images as an uninterrupted one.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, field

import numpy as np

from hwbridge.dome_layout import SPECTRAL_CAMERA
from twin.devices.sim_devices import VirtualRig
from twin.dome.holder import holder_content, holder_scene_parts
from twin.dome.render import DomeView, dome_scene_rates
from twin.materials import Material
from twin.render.node_transport import NodeScene
from twin.rigs.rig_config import DomeConfig

__all__ = [
    "LED_RENDERS",
    "PASS_MEMORY_BYTES",
    "DomeScene",
    "RenderedDomeSignal",
    "band_index",
    "leds_per_pass",
]

LED_RENDERS = ("pose", "single")
"""How the LEDs lit one at a time are rendered: all of a stage position in passes (``pose``,
the default), or one render per LED (``single``)."""

PASS_MEMORY_BYTES = 160 * 2**20
"""The most memory one camera's pass of LED images takes (float32 rates): at 64 texels
(264 px) the 198 LEDs of the rig's dome in one pass of an RGB camera."""


def leds_per_pass(window: int, channels: int) -> int:
    """LEDs per pass of a camera of ``channels`` channels and ``window`` pixels square within
    :data:`PASS_MEMORY_BYTES`."""
    return max(1, PASS_MEMORY_BYTES // (4 * window * window * channels))


def band_index(bands_nm, band_nm: float) -> int:
    """The index of the band of ``bands_nm`` nearest ``band_nm`` (the render channel of a
    tuned filter)."""
    return int(np.argmin(np.abs(np.asarray(bands_nm, np.float64) - band_nm)))


def _seed(name: str) -> int:
    """The Monte Carlo seed of the render ``name`` (what it shows)."""
    return zlib.crc32(name.encode()) & 0x7FFFFFFF


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
    led_renders
        ``pose`` (passes of the LEDs lit one at a time) or ``single`` (:data:`LED_RENDERS`).
    single_leds
        The LEDs the plan switches on one at a time, in plan order (the passes' blocks).
    led_bands
        Per LED lit alone, the spectral camera's bands (indices into ``bands_nm``) the plan
        takes under it: a pass renders only those (a run's band schedule gives each LED a few).
    """

    config: DomeConfig
    material: Material | None
    holders: tuple[str | None, ...]
    led_full_scale_ma: float
    pixels: int
    window: int
    spp: int
    bands_nm: tuple[float, ...]
    led_renders: str = "pose"
    single_leds: tuple[int, ...] = ()
    led_bands: dict[int, tuple[int, ...]] = field(default_factory=dict)
    _scenes: dict = field(default_factory=dict, repr=False)

    def pass_channels(self, camera: int | str) -> int:
        """Channels per LED in a pass of ``camera``: R, G, B, or the most bands of an LED."""
        if camera != SPECTRAL_CAMERA:
            return 3
        return max(map(len, self.led_bands.values()), default=len(self.bands_nm))

    def led_block(self, led: int, camera: int | str) -> tuple[int, ...]:
        """The LEDs rendered in one pass with ``led`` by ``camera``: consecutive LEDs of
        :attr:`single_leds`, as many as :func:`leds_per_pass` allows."""
        if led not in self.single_leds:
            return (led,)
        size = leds_per_pass(self.window, self.pass_channels(camera))
        start = self.single_leds.index(led) // size * size
        return self.single_leds[start : start + size]

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
        self._pass_key: tuple | None = None
        self._pass: np.ndarray | None = None
        self._view: DomeView | None = None

    def __getstate__(self) -> dict:
        cached = ("_key", "_rates", "_pass_key", "_pass", "_view")
        return {**self.__dict__, **dict.fromkeys(cached)}

    @property
    def view(self) -> DomeView:
        """The camera's view (built on first use, in the process that renders)."""
        if self._view is None:
            scene = self._scene
            self._view = DomeView(
                scene.config,
                self._camera,
                scene.pixels,
                window=scene.window,
                bands_nm=scene.bands_nm,
            )
        return self._view

    def rates(self, content: str, stage_deg: float, leds: tuple[int, ...]) -> np.ndarray:
        """Rates ``(H, W, n_channels)`` of one state at full-scale current (the last state and
        the last pass of LEDs kept)."""
        key = (content, stage_deg, leds)
        if key == self._key and self._rates is not None:
            return self._rates
        scene = self._scene
        every = tuple(range(self.view.weights.shape[1]))
        if len(leds) == 1 and scene.led_renders == "pose":
            block = scene.led_block(leds[0], self._camera)
            if scene.node_scene(content).has_metal:  # rendered LED by LED: no pass to share
                block = leds
            wanted = self._wanted(block, every)
            led_pass = self._led_pass(content, stage_deg, block, wanted)
            index = block.index(leds[0])
            chosen = list(wanted[index])
            if chosen == list(every):  # a copy: the pass's memory is freed with the pass
                rates = np.ascontiguousarray(led_pass[index, ..., : len(chosen)])
            else:
                rates = np.full((*led_pass.shape[1:3], len(every)), np.nan, np.float32)
                rates[..., chosen] = led_pass[index, ..., : len(chosen)]  # NaN: not rendered
        elif self._summed_pass(content, leds, every):
            block = scene.led_block(scene.single_leds[0], self._camera)
            led_pass = self._led_pass(content, stage_deg, block, self._wanted(block, every))
            rates = led_pass.sum(axis=0, dtype=np.float64).astype(np.float32)
        else:
            self._pass = self._pass_key = None
            lit = "all" if len(leds) == scene.config.led_count else ",".join(map(str, leds))
            rates = self._render(content, stage_deg, leds, lit).astype(np.float32)
        self._key, self._rates = key, rates
        return rates

    def _wanted(self, block: tuple[int, ...], every: tuple[int, ...]) -> list[tuple[int, ...]]:
        """The channels of each LED of ``block`` in a pass: every one, or for the spectral
        camera the LED's scheduled bands."""
        if self._camera != SPECTRAL_CAMERA:
            return [every] * len(block)
        return [self._scene.led_bands.get(led, every) for led in block]

    def _led_pass(self, content, stage_deg, block, wanted) -> np.ndarray:
        """The pass of ``block`` (kept until another is asked for)."""
        if (content, stage_deg, block) != self._pass_key or self._pass is None:
            self._pass = None  # the last pass's memory is free for the next
            self._pass = self._render(content, stage_deg, block, "pose", wanted)
            self._pass_key = (content, stage_deg, block)
        return self._pass

    def _summed_pass(self, content: str, leds: tuple[int, ...], every: tuple[int, ...]) -> bool:
        """Whether the LEDs ``leds`` lit together on ``content`` are the sum of one pass: a
        run's alignment frame, which shows the sample its LEDs then light one at a time, all of
        them in one pass of every channel. (A calibration's checkerboard, lit only all
        together, keeps its own render: a pass, dearer, would serve it alone.)"""
        scene = self._scene
        single = scene.single_leds
        if scene.led_renders != "pose" or not single or sorted(leds) != sorted(single):
            return False
        if content != holder_content("sample"):
            return False
        block = scene.led_block(single[0], self._camera)
        return (
            len(block) == len(single)
            and not scene.node_scene(content).has_metal
            and all(chosen == every for chosen in self._wanted(block, every))
        )

    def _render(self, content, stage_deg, leds, lit: str, channels=None) -> np.ndarray:
        """The render of ``leds`` together, or with ``channels`` (one list per LED) a pass of
        each alone; its seed follows from the content, stage angle, ``lit`` and camera."""
        scene = self._scene
        return dome_scene_rates(
            scene.config,
            scene.node_scene(content),
            self.view,
            stage_deg=stage_deg,
            leds=leds,
            spp=scene.spp,
            seed=_seed(f"{content}|{stage_deg:.6f}|{lit}|{self._camera}"),
            each=channels is not None,
            channels=channels,
        )

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
            band = band_index(self._scene.bands_nm, rig.band_nm)
            return rates[..., band] * scale
        return rates * scale
