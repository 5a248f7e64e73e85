"""Signals for the simulated cameras: mean photo-electrons of a frame from the rig's state.

Lamps are sums of fixed spectral parts with time-varying weights
(``twin.components.LightSource``), so a signal stores photo-electron *rates* per part and band and
weights them by ``LightSource.part_exposure_s(start, exposure)``: HMI frames whose exposure is not
a multiple of 1/15 s then vary with the flicker phase, as on the real rig (thesis 3.2.2).

- :class:`WhiteReferenceSignal`: the Zenith white standard facing the lamp (analytic, uniform).
- :class:`RenderedGonioSignal`: the material on its holder rendered by Mitsuba for the view the
  positioner has set; the scene is built once per process (:class:`twin.gonio.render.
  GonioScene`) and the render of the current view is kept (every lamp part and band at once), so
  a plan that goes view by view renders each view once.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from twin.components.lamps import FINE_GRID, LightSource
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.devices.sim_devices import VirtualRig
from twin.gonio.render import GONIO_SPP, GonioScene, gonio_lamp
from twin.materials import Material
from twin.rigs.gonio_kinematics import GonioPose
from twin.rigs.rig_config import GonioConfig
from twin.sensor.model import Sensor
from twin.sensor.white_reference import white_reference_rates

__all__ = ["RenderedGonioSignal", "WhiteReferenceSignal"]


def _band_index(bands_nm: np.ndarray, band_nm: float | None) -> int:
    if band_nm is None:
        raise ValueError("the filter has not been tuned yet")
    return int(np.argmin(np.abs(bands_nm - band_nm)))


class WhiteReferenceSignal:
    """The white standard at ``distance_m`` from ``lamp``, through the bands of the VariSpec
    ``filter_model`` (default the VS-10), uniform."""

    def __init__(
        self,
        sensor: Sensor,
        lamp: LightSource,
        *,
        distance_m: float = 2.0,
        filter_model: str = "VS-10",
    ):
        lctf = LiquidCrystalTunableFilter.varispec(filter_model)
        self._bands_nm = np.asarray(lctf.band_centres_nm)
        self._rates = white_reference_rates(
            sensor, lamp, lctf.transmission(FINE_GRID), distance_m=distance_m
        )
        self._lamp, self._shape = lamp, (sensor.height, sensor.width)

    def rates_e_per_s(self) -> np.ndarray:
        """Mean photo-electrons per second and pixel in each band ``(n_bands,)``, averaged over
        whole flicker periods."""
        return self._lamp.part_exposure_s(0.0, 1.0) @ self._rates

    def __call__(self, rig: VirtualRig, start_s: float, exposure_s: float) -> np.ndarray:
        weights = self._lamp.part_exposure_s(start_s, exposure_s)
        electrons = weights @ self._rates[:, _band_index(self._bands_nm, rig.band_nm)]
        return np.full(self._shape, electrons, np.float32)


class RenderedGonioSignal:
    """Renders of ``material`` on the gonioreflectometer for the poses of the plan's views."""

    def __init__(
        self,
        config: GonioConfig,
        material: Material | None,
        poses: Sequence[GonioPose] | Mapping[int, GonioPose],
        *,
        pixels: int,
        spp: int = GONIO_SPP,
        window: int | None = None,
    ):
        self._config, self._material, self._poses = config, material, poses
        self._pixels, self._spp, self._window = pixels, spp, window
        self._bands_nm = np.asarray(
            LiquidCrystalTunableFilter.varispec(config.camera.filter).band_centres_nm
        )
        self._scene: GonioScene | None = None
        self._cache: dict[int, np.ndarray] = {}

    def __getstate__(self) -> dict:
        # The Mitsuba scene and the renders stay in the process that made them; a Dask worker
        # builds its own scene from the material.
        return {**self.__dict__, "_scene": None, "_cache": {}}

    def rates(self, view_id: int) -> np.ndarray:
        """Photo-electron rates ``(n_parts, H, W, n_bands)`` of a view (the last view's kept)."""
        if view_id not in self._cache:
            self._cache.clear()
            if self._scene is None:
                self._scene = GonioScene(self._config, self._material)
            self._cache[view_id] = self._scene.part_rates(
                self._poses[view_id], pixels=self._pixels, spp=self._spp, window=self._window
            )
        return self._cache[view_id]

    def __call__(self, rig: VirtualRig, start_s: float, exposure_s: float) -> np.ndarray:
        lamp, _ = gonio_lamp(self._config, self._poses[rig.view_id].lamp_id)
        weights = lamp.part_exposure_s(start_s, exposure_s)
        rates = self.rates(rig.view_id)[..., _band_index(self._bands_nm, rig.band_nm)]
        return np.tensordot(weights, rates, axes=1)
