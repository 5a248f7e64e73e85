"""Frame sizes of the dome's captures and the geometry a dome store carries for its processing.

Frames are sized by the texture resolution processing will rectify into: ``texels`` across a
nominal 4 cm sample, each texel one Bayer quad (2 x 2 pixels) of a camera seen from the top, so
the pixel pitch at the rig centre is ``0.04 m / (2 texels)`` (at 64 texels 0.31 mm, about 3 of
the real sensor's 0.098 mm pixels: a sub-sampled sensor, as in the gonioreflectometer's reduced
captures). Every camera reads out the centred square window that holds the holder's
registration marks at every stage angle (their corners turn on a circle of
:math:`\\sqrt{2}` x 26.5 mm) with a margin.

:func:`geometry_metadata` describes cameras, LEDs, stage and targets in the conventions of
:mod:`hwbridge.dome_layout` (OpenCV's camera model: x right, y down, z forward, pixel centres at
integer coordinates).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from hwbridge.dome_layout import SPECTRAL_CAMERA
from hwbridge.schema import DomeCamera, DomeGeometry
from recon.errors import InputError
from twin.dome.holder import holder_geometry, target_geometry
from twin.dome.render import dome_camera, stage_matrix
from twin.materials.sample_holder import PRINT_OUTER_HALF_M, registration_corners
from twin.render.scene import PinholeCamera
from twin.rigs.dome_geometry import dome_geometry
from twin.rigs.rig_config import DomeConfig

__all__ = ["FrameSize", "camera_arc_index", "frame_size", "geometry_metadata"]

NOMINAL_SAMPLE_M = 0.04
"""The sample size that ``texels`` spans."""

_MARGIN_M = 0.0035  # around the marks' circle: the print's width, the corners' detection window
_WINDOW_STEP = 8


class FrameSize:
    """``pixels`` across the 0.2 m field and the ``window`` read out, for ``texels``."""

    def __init__(self, config: DomeConfig, texels: int):
        if not isinstance(texels, int | np.integer) or not 4 <= texels <= 1024:
            raise InputError(f"texels: expected 4..1024 texels across, got {texels}")
        field = config.spectral_camera.field_of_view_m
        self.texels = int(texels)
        self.pitch_m = NOMINAL_SAMPLE_M / (2 * self.texels)
        self.pixels = 2 * math.ceil(field / self.pitch_m / 2)
        radius = math.sqrt(2) * PRINT_OUTER_HALF_M + _MARGIN_M
        steps = math.ceil(2 * radius / self.pitch_m / _WINDOW_STEP)
        self.window = min(_WINDOW_STEP * steps, self.pixels)


def frame_size(config: DomeConfig, texels: int) -> FrameSize:
    """The frame size for ``texels`` (module docstring)."""
    return FrameSize(config, texels)


def camera_arc_index(camera_id: str) -> int | str:
    """The :func:`twin.dome.render.dome_camera` argument of a store's camera id (``rgb06`` -> 6,
    ``spectral`` -> ``"spectral"``)."""
    if camera_id == SPECTRAL_CAMERA:
        return SPECTRAL_CAMERA
    return int(camera_id.removeprefix("rgb"))


def _opencv(view: PinholeCamera) -> tuple[np.ndarray, np.ndarray]:
    """Rotation world -> camera and the camera matrix of ``view`` in OpenCV's conventions."""
    left, up, forward = view.frame()
    rotation = np.stack([-left, -up, forward])
    focal = view.pixels / 2 / math.tan(math.radians(view.fov_deg) / 2)
    centre = view.pixels / 2 - 0.5 - view.window_offset
    matrix = np.array([[focal, 0.0, centre], [0.0, focal, centre], [0.0, 0.0, 1.0]])
    return rotation, matrix


def _camera_entry(
    config: DomeConfig, camera_id: str, size: FrameSize, stage_views: Sequence[int]
) -> DomeCamera:
    arc = camera_arc_index(camera_id)
    view, sensor, _ = dome_camera(config, arc, size.pixels, window=size.window)
    rotation, matrix = _opencv(view)
    angles = dome_geometry(config).stage_angles_deg
    corners = registration_corners()[[1, 0, 3, 2]]
    marks = {}
    for stage in stage_views:
        world = corners @ stage_matrix(angles[stage])[:3, :3].T
        marks[str(stage)] = (view.project(world) - 0.5).tolist()
    return DomeCamera(
        role="spectral" if arc == SPECTRAL_CAMERA else "rgb",
        definition=sensor.config.name,
        mosaic="none" if not sensor.is_colour else "RGGB",
        arc_index=None if arc == SPECTRAL_CAMERA else arc,
        bit_depth=sensor.config.bit_depth,
        position_m=np.asarray(view.position_m, float).tolist(),
        rotation_world_to_camera=rotation.tolist(),
        camera_matrix=matrix.tolist(),
        distortion=[0.0] * 5,
        frame_px=(size.window, size.window),
        pixel_pitch_m=size.pitch_m,
        marker_corners_xy=marks,
    )


def geometry_metadata(
    config: DomeConfig,
    camera_ids: Sequence[str],
    size: FrameSize,
    *,
    stage_views: Sequence[int],
    tilts_deg: Sequence[float] = (),
) -> DomeGeometry:
    """The ``geometry`` of a dome store's ``rig`` attribute (:mod:`hwbridge.dome_layout`):
    stage angles, LED positions, every camera of ``camera_ids`` with the nominal image points of
    the registration marks at ``stage_views``, the holder, and the checkerboard at
    ``tilts_deg``."""
    geometry = dome_geometry(config)
    return DomeGeometry(
        frame="world: origin at the sample centre on the stage, z up, metres; the sample "
        "frame is the world turned about z by the stage angle",
        stage_angles_deg=geometry.stage_angles_deg.tolist(),
        led_positions_m=geometry.led_positions_m.tolist(),
        cameras={camera: _camera_entry(config, camera, size, stage_views) for camera in camera_ids},
        holder=holder_geometry(),
        geometric_target=target_geometry(list(tilts_deg)),
    )
