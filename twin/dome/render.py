"""Renders of the LED dome: LEDs on, the sample (or a calibration target) on its holder turned by
the rotation stage, seen by one RGB camera of the arc or by the spectral camera (thesis 10.2).

The light transport is traced once per (LEDs, stage angle, camera) at the materials' wavelength
nodes (:mod:`twin.render.node_transport`): the LEDs share one spectrum, so the R, G, B channels
or every band of the tunable filter follow from the node values by one weight matrix
(the channel responses times the LED's spectrum, :func:`twin.render.node_transport.
node_weights`), without spectral sampling noise. Light transport is linear in the light, so a
render with one LED on, or with all of them (a sum of point lights), is the photo-electron rate
per pixel for any exposure. The stage turns the sample; a render turns the camera and the LEDs
the other way instead, so one scene per holder content serves every stage angle.
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
from twin.materials.surfaces import SurfacePart
from twin.render.node_transport import (
    NodeScene,
    PinholeRays,
    PointLight,
    PointLights,
    node_weights,
)
from twin.render.scene import PinholeCamera
from twin.rigs.dome_geometry import dome_geometry
from twin.rigs.rig_config import DomeConfig
from twin.sensor.model import Sensor

__all__ = [
    "DOME_SPP",
    "DomeView",
    "dome_camera",
    "dome_part_rates",
    "dome_rates",
    "dome_scene_rates",
    "stage_matrix",
]

DOME_SPP = 16
"""Samples per pixel of the dome's renders by default, stratified 4 x 4 over the pixel: the
spectra carry no sampling noise, the samples average the image over each pixel where edges
(marks, checkerboard squares, texture) cross it, as the gonioreflectometer's
(:data:`twin.gonio.render.GONIO_SPP`). A white field's render noise is then far below the
sensors' temporal noise in every channel and band (``tests/twin/dome/test_dome_render_noise.py``,
BENCHMARKS.md)."""


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


def dome_part_rates(
    config: DomeConfig,
    parts: Sequence[SurfacePart],
    *,
    stage_deg: float,
    leds: Sequence[int],
    camera: int | str,
    pixels: int,
    window: int | None = None,
    spp: int = DOME_SPP,
    seed: int = 0,
    bands_nm: Sequence[float] | None = None,
) -> np.ndarray:
    """Photo-electron rates ``(H, W, n_channels)`` in e-/s of ``parts`` (sample frame) turned by
    the stage to ``stage_deg`` and lit by the LEDs ``leds`` together: R, G, B for an RGB camera
    (before the Bayer mosaic), one channel per band for the spectral camera."""
    view = DomeView(config, camera, pixels, window=window, bands_nm=bands_nm)
    return dome_scene_rates(
        config, NodeScene(parts), view, stage_deg=stage_deg, leds=leds, spp=spp, seed=seed
    )


class DomeView:
    """Camera ``camera`` of the dome ready to render (:func:`dome_camera`'s arguments): its
    view and the node weights of its channels (the sensor's electron responses, through the
    filter's bands, times the LEDs' spectrum), built once for all the renders of the camera."""

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
        led = PhosphorWhiteLED().intensity(FINE_GRID)
        self.weights = node_weights(self.channels * led).astype(np.float32)
        """Node weights ``(n_nodes, n_channels)`` of the channels under the LEDs' spectrum."""

    def rays(self, stage_deg: float) -> PinholeRays:
        """The camera's rays in the sample frame of the stage turned to ``stage_deg``."""
        to_sample = stage_matrix(stage_deg)[:3, :3].T
        left, up, forward = self.view.frame()
        return PinholeRays(
            to_sample @ self.view.position_m,
            to_sample @ left,
            to_sample @ up,
            to_sample @ forward,
            float(np.tan(np.radians(self.view.fov_deg) / 2)),
            self.view.pixels,
            self.view.window,
        )


def dome_scene_rates(
    config: DomeConfig,
    scene: NodeScene,
    view: DomeView,
    *,
    stage_deg: float,
    leds: Sequence[int],
    spp: int = DOME_SPP,
    seed: int = 0,
    each: bool = False,
    channels: Sequence[Sequence[int]] | None = None,
) -> np.ndarray:
    """:func:`dome_part_rates` of a scene of parts in the sample frame, seen by ``view``.

    With ``each``, the rates ``(n_leds, H, W, n_channels)`` of every LED of ``leds`` lit alone,
    the camera's paths traced once for all of them (:meth:`twin.render.node_transport.
    NodeScene.transport_each`, whose ``channels`` picks each LED's channels): LED ``i``'s image
    equals the one-LED render of ``leds[i]`` with the same seed, to float rounding."""
    to_sample = stage_matrix(stage_deg)[:3, :3].T
    positions = dome_geometry(config).led_positions_m[np.asarray(leds, int)] @ to_sample.T
    rays = view.rays(stage_deg)
    if each:
        return scene.transport_each(
            rays, positions, view.weights, spp=spp, seed=seed, channels=channels
        )
    light = PointLight(positions[0]) if len(positions) == 1 else PointLights(positions)
    radiance = scene.transport(rays, light, spp=spp, seed=seed)
    height, width, count = radiance.shape
    return (radiance.reshape(-1, count) @ view.weights).reshape(height, width, -1)


def dome_rates(
    config: DomeConfig,
    material: Material | None,
    *,
    stage_deg: float,
    led: int,
    camera: int | str,
    pixels: int = 256,
    spp: int = DOME_SPP,
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
