"""Geometry of the LED dome (thesis 10.2): LED and camera directions, rotation stage.

World frame: origin at the sample centre on the rotation stage, z up. Turning the stage by
:math:`\\phi` rotates the sample about z, so a world direction appears in the sample frame rotated
by :math:`-\\phi`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from twin.rigs.hemisphere import direction
from twin.rigs.rig_config import DomeConfig

__all__ = ["DomeGeometry", "dome_geometry", "to_sample_frame"]


@dataclass(frozen=True)
class DomeGeometry:
    """Unit directions from the sample centre (world frame) and the stage angles."""

    led_directions: np.ndarray  # (n_leds, 3)
    rgb_camera_directions: np.ndarray  # (n_cameras, 3)
    spectral_camera_direction: np.ndarray  # (3,)
    stage_angles_deg: np.ndarray  # (n_positions,)
    radius_m: float

    @property
    def led_positions_m(self) -> np.ndarray:
        return self.radius_m * self.led_directions


def dome_geometry(config: DomeConfig) -> DomeGeometry:
    """LED rings, the RGB camera arc and the spectral camera of ``config``."""
    leds = np.concatenate(
        [
            direction(
                ring.polar_deg, ring.azimuth_offset_deg + np.arange(ring.count) * 360.0 / ring.count
            )
            for ring in config.led_rings
        ]
    )
    cameras = direction(np.array(config.rgb_camera_polar_deg), config.rgb_camera_azimuth_deg)
    spectral = direction(
        config.spectral_camera_polar_deg,
        config.rgb_camera_azimuth_deg + config.spectral_camera_azimuth_offset_deg,
    )
    stage = np.arange(config.rotation_stage_positions) * config.rotation_stage_step_deg
    return DomeGeometry(leds, cameras, spectral, stage, config.radius_m)


def to_sample_frame(world_directions: np.ndarray, stage_deg: float) -> np.ndarray:
    """World directions seen in the frame of a sample turned by ``stage_deg`` about z."""
    return Rotation.from_euler("z", -stage_deg, degrees=True).apply(world_directions)
