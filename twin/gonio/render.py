"""Renders and raw frames of the gonioreflectometer for one direction pair.

The material on its holder is rotated by the robot pose, the K4 + VariSpec camera stands on the
rail, the lamp at its position; one render per lamp part (HMI: continuum and flickering lines)
gives photo-electron rates, and any exposure window is their weighted sum
(``Lamp.part_exposure_s``), run through the sensor model.
"""

from __future__ import annotations

import numpy as np

from twin.components.lamps import FINE_GRID, HMILamp, Lamp, QTHLamp
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.materials import Material
from twin.materials.sample_holder import holder_parts
from twin.materials.surfaces import SurfacePart
from twin.render.scene import PinholeCamera, lamp_position, render_view
from twin.rigs.gonio_kinematics import GonioPose
from twin.rigs.rig_config import GonioConfig
from twin.sensor.model import Sensor

__all__ = ["gonio_camera", "gonio_lamp", "gonio_part_rates", "pose_matrix", "simulate_band_frames"]


def gonio_lamp(config: GonioConfig, lamp_id: str) -> tuple[Lamp, np.ndarray]:
    """The lamp model and position of ``lamp_id``."""
    placement = next(lamp for lamp in config.lamps if lamp.id == lamp_id)
    lamp = HMILamp() if placement.spectrum == "hmi" else QTHLamp()
    return lamp, lamp_position(placement.azimuth_deg, placement.elevation_deg, placement.distance_m)


def gonio_camera(
    config: GonioConfig, rail_deg: float, pixels: int, window: int | None = None
) -> PinholeCamera:
    """The spectral camera on the rail at ``rail_deg``: ``pixels`` across its field, the centred
    ``window`` of them read out (default all)."""
    position = config.rail.radius_m * np.array(
        [np.cos(np.radians(rail_deg)), np.sin(np.radians(rail_deg)), 0.0]
    )
    return PinholeCamera(position, config.camera.field_of_view_m, pixels, window=window)


def pose_matrix(pose: GonioPose) -> np.ndarray:
    """4x4 sample-to-world transform of the robot pose (rotation, then the centre's offset)."""
    matrix = np.eye(4)
    matrix[:3, :3] = pose.rotation().as_matrix()
    matrix[:3, 3] = pose.offset_m
    return matrix


def gonio_part_rates(
    config: GonioConfig,
    pose: GonioPose,
    material: Material | None,
    *,
    pixels: int = 256,
    spp: int = 64,
    seed: int = 0,
    holder: bool = True,
    extra_parts: list[SurfacePart] | None = None,
    window: int | None = None,
) -> np.ndarray:
    """Photo-electron rates ``(n_parts, H, W, n_bands)`` in e-/s per pixel, one per lamp part.

    ``holder`` puts the material on the sample holder; ``extra_parts`` adds surfaces in the
    sample frame (e.g. a white target); ``window`` reads out only the centred window of the
    ``pixels`` across the field.
    """
    sensor = Sensor(config.camera.definition)
    bands = LiquidCrystalTunableFilter.varispec(config.camera.filter).transmission(FINE_GRID)
    channels = sensor.electron_responses(FINE_GRID, bands)
    lamp, position = gonio_lamp(config, pose.lamp_id)
    parts = (holder_parts() if holder else []) + list(material.parts if material else [])
    parts += list(extra_parts or [])
    camera = gonio_camera(config, pose.rail_deg, pixels, window)
    spectral_parts = lamp.spectral_parts(FINE_GRID)
    return np.stack(
        [
            render_view(
                parts,
                pose_matrix(pose),
                camera,
                channels,
                position,
                spectral_parts.row(name),
                spp=spp,
                seed=seed,
            )
            for name in spectral_parts.names
        ]
    )


def simulate_band_frames(
    config: GonioConfig,
    pose: GonioPose,
    rates: np.ndarray,
    exposures_s: np.ndarray,
    rng: np.random.Generator,
    *,
    start_s: float = 0.0,
) -> np.ndarray:
    """Raw K4 frames ``(n_bands, H, W)`` of one pair: band by band, each band's exposure window
    following the previous one after the filter switch and download (thesis 4.1.1)."""
    lamp, _ = gonio_lamp(config, pose.lamp_id)
    pixels = rates.shape[1]
    sensor = Sensor(config.camera.definition, roi=(pixels, pixels))
    frames, clock = [], start_s
    for band, exposure_s in enumerate(exposures_s):
        weights = lamp.part_exposure_s(clock, float(exposure_s))
        electrons = np.tensordot(weights, rates[..., band], axes=1)
        frames.append(sensor.capture(electrons.astype(np.float32), float(exposure_s), rng))
        clock += float(exposure_s) + config.timing.switch_and_download_s
    return np.stack(frames)
