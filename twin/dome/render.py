"""Renders of the LED dome: LEDs on, the sample (or a calibration target) on its holder turned by
the rotation stage, seen by one RGB camera of the arc or by the spectral camera (thesis 10.2).

Light transport is linear in the light, so a render with one LED on, or with all of them
(:mod:`twin.render.light_groups`: the LEDs share one spectrum, moved into the camera's channel
responses), is the photo-electron rate per pixel for any exposure; one spectral render gives
every band of the tunable filter at once.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.spatial.transform import Rotation

from recon.spectra import SampledSpectra
from twin.components.lamps import FINE_GRID, PhosphorWhiteLED
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.materials import Material
from twin.materials.sample_holder import holder_parts
from twin.materials.surfaces import SurfacePart, transformed
from twin.render.light_groups import LightGroup, render_lit
from twin.render.scene import PinholeCamera
from twin.render.shapes import mitsuba_shape
from twin.render.spectra import irregular_spectrum
from twin.rigs.dome_geometry import dome_geometry
from twin.rigs.rig_config import DomeConfig
from twin.sensor.model import Sensor

__all__ = [
    "DomeView",
    "dome_camera",
    "dome_part_rates",
    "dome_rates",
    "dome_shape_rates",
    "dome_shapes",
    "stage_matrix",
]

_MAX_DEPTH = 3  # direct light and one bounce, as the gonioreflectometer's renders


def stage_matrix(stage_deg: float) -> np.ndarray:
    """4x4 sample-to-world transform of the rotation stage."""
    matrix = np.eye(4)
    matrix[:3, :3] = Rotation.from_euler("z", stage_deg, degrees=True).as_matrix()
    return matrix


def dome_camera(
    config: DomeConfig,
    camera: int | str,
    pixels: int,
    *,
    window: int | None = None,
    bands_nm: Sequence[float] | None = None,
) -> tuple[PinholeCamera, Sensor, SampledSpectra | None]:
    """Camera ``camera`` (index on the RGB arc, or ``"spectral"``): its view (``pixels`` across
    the 0.2 m field, the centred ``window`` of them read out), its full sensor and, for the
    spectral camera, the filter's transmission per band (``bands_nm``, default every VariSpec
    band)."""
    geometry = dome_geometry(config)
    field = config.spectral_camera.field_of_view_m
    if camera == "spectral":
        position = config.radius_m * geometry.spectral_camera_direction
        sensor = Sensor(config.spectral_camera.definition)
        centres = {} if bands_nm is None else {"band_centres_nm": tuple(map(float, bands_nm))}
        bands = LiquidCrystalTunableFilter.varispec(
            config.spectral_camera.filter, **centres
        ).transmission(FINE_GRID)
    else:
        position = config.radius_m * geometry.rgb_camera_directions[int(camera)]
        sensor, bands = Sensor(config.rgb_camera), None
    up = (1.0, 0.0, 0.0) if np.allclose(position[:2], 0) else (0.0, 0.0, 1.0)
    return PinholeCamera(position, field, pixels, up=up, window=window), sensor, bands


def _led_group(config: DomeConfig, leds: Sequence[int]) -> LightGroup:
    """The LEDs ``leds`` as point lights of a flat unit spectrum, sharing the LED's spectrum."""
    positions = dome_geometry(config).led_positions_m[np.asarray(leds, int)]
    flat = irregular_spectrum(SampledSpectra(FINE_GRID, np.ones(FINE_GRID.size)))
    entries = {
        f"led_{index:03d}": {"type": "point", "position": position.tolist(), "intensity": flat}
        for index, position in zip(leds, positions, strict=True)
    }
    return LightGroup("leds", entries, PhosphorWhiteLED().intensity(FINE_GRID))


def dome_part_rates(
    config: DomeConfig,
    parts: Sequence[SurfacePart],
    *,
    stage_deg: float,
    leds: Sequence[int],
    camera: int | str,
    pixels: int,
    window: int | None = None,
    spp: int = 64,
    seed: int = 0,
    bands_nm: Sequence[float] | None = None,
) -> np.ndarray:
    """Photo-electron rates ``(H, W, n_channels)`` in e-/s of ``parts`` (sample frame) turned by
    the stage to ``stage_deg`` and lit by the LEDs ``leds`` together: R, G, B for an RGB camera
    (before the Bayer mosaic), one channel per band for the spectral camera."""
    view = DomeView(config, camera, pixels, window=window, bands_nm=bands_nm)
    return dome_shape_rates(
        config, dome_shapes(parts, stage_deg), view, leds=leds, spp=spp, seed=seed
    )


def dome_shapes(parts: Sequence[SurfacePart], stage_deg: float) -> dict[str, object]:
    """Mitsuba shapes of ``parts`` turned by the stage to ``stage_deg``, to render with any
    camera and LEDs (:func:`dome_shape_rates`)."""
    matrix = stage_matrix(stage_deg)
    return {part.name: mitsuba_shape(transformed(part, matrix)) for part in parts}


class DomeView:
    """Camera ``camera`` of the dome ready to render (:func:`dome_camera`'s arguments): its
    channels (the sensor's electron responses, through the filter's bands) and its Mitsuba
    sensor, built once for all the renders of the camera."""

    def __init__(
        self,
        config: DomeConfig,
        camera: int | str,
        pixels: int,
        *,
        window: int | None = None,
        bands_nm: Sequence[float] | None = None,
    ):
        self.view, sensor, bands = dome_camera(
            config, camera, pixels, window=window, bands_nm=bands_nm
        )
        self.channels = sensor.electron_responses(FINE_GRID, bands)
        self._sensors: dict[tuple[int, bytes], dict[str, object]] = {}

    def mitsuba_sensor(self, channels: SampledSpectra, spp: int) -> dict[str, object]:
        """:meth:`twin.render.scene.PinholeCamera.mitsuba_sensor`, kept per film and spp."""
        key = (int(spp), channels.values.tobytes())
        if key not in self._sensors:
            self._sensors[key] = self.view.mitsuba_sensor(channels, spp)
        return self._sensors[key]


def dome_shape_rates(
    config: DomeConfig,
    shapes: dict[str, object],
    view: DomeView,
    *,
    leds: Sequence[int],
    spp: int = 64,
    seed: int = 0,
) -> np.ndarray:
    """:func:`dome_part_rates` of shapes made by :func:`dome_shapes`, seen by ``view``."""
    return render_lit(
        view,
        view.channels,
        shapes,
        [_led_group(config, leds)],
        spp=spp,
        seed=seed,
        max_depth=_MAX_DEPTH,
    )


def dome_rates(
    config: DomeConfig,
    material: Material | None,
    *,
    stage_deg: float,
    led: int,
    camera: int | str,
    pixels: int = 256,
    spp: int = 64,
    seed: int = 0,
) -> np.ndarray:
    """:func:`dome_part_rates` of ``material`` on the sample holder, one LED on."""
    parts = holder_parts() + list(material.parts if material else [])
    return dome_part_rates(
        config,
        parts,
        stage_deg=stage_deg,
        leds=[led],
        camera=camera,
        pixels=pixels,
        spp=spp,
        seed=seed,
    )
