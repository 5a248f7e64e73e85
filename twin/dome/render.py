"""Renders and raw frames of the LED dome: one LED on, the sample turned by the stage, seen by
one RGB camera of the arc or by the spectral camera (thesis 10.2)."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from twin.components.lamps import FINE_GRID, PhosphorWhiteLED
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.materials import Material
from twin.materials.sample_holder import holder_parts
from twin.render.scene import PinholeCamera, render_view
from twin.rigs.dome_geometry import dome_geometry
from twin.rigs.rig_config import DomeConfig
from twin.sensor.model import Sensor

__all__ = ["dome_camera", "dome_rates", "stage_matrix"]


def stage_matrix(stage_deg: float) -> np.ndarray:
    """4x4 sample-to-world transform of the rotation stage."""
    matrix = np.eye(4)
    matrix[:3, :3] = Rotation.from_euler("z", stage_deg, degrees=True).as_matrix()
    return matrix


def dome_camera(
    config: DomeConfig, camera: int | str, pixels: int
) -> tuple[PinholeCamera, Sensor, object]:
    """Camera ``camera`` (index on the RGB arc, or ``"spectral"``), its sensor and its filter."""
    geometry = dome_geometry(config)
    field = config.spectral_camera.field_of_view_m
    if camera == "spectral":
        position = config.radius_m * geometry.spectral_camera_direction
        sensor = Sensor(config.spectral_camera.definition)
        bands = LiquidCrystalTunableFilter.varispec(config.spectral_camera.filter).transmission(
            FINE_GRID
        )
    else:
        position = config.radius_m * geometry.rgb_camera_directions[int(camera)]
        sensor, bands = Sensor(config.rgb_camera), None
    up = (1.0, 0.0, 0.0) if np.allclose(position[:2], 0) else (0.0, 0.0, 1.0)
    return PinholeCamera(position, field, pixels, up=up), sensor, bands


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
    """Photo-electron rates ``(H, W, n_channels)`` in e-/s: R, G, B for an RGB camera (before the
    Bayer mosaic) or one channel per LCTF band for the spectral camera."""
    geometry = dome_geometry(config)
    view, sensor, bands = dome_camera(config, camera, pixels)
    channels = sensor.electron_responses(FINE_GRID, bands)
    parts = holder_parts() + list(material.parts if material else [])
    return render_view(
        parts,
        stage_matrix(stage_deg),
        view,
        channels,
        geometry.led_positions_m[led],
        PhosphorWhiteLED().intensity(FINE_GRID),
        spp=spp,
        seed=seed,
    )
