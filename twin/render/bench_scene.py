"""A real bench's chart, lamp and camera as a Mitsuba scene: the chart posed where a real
camera saw it, lit by a point lamp, rendered through the camera's channels behind each filter.

The camera is a pinhole with its principal point at the image centre, in OpenCV's frame (x right,
y down, z forward); the chart is :func:`twin.materials.chart_parts` moved by its pose in that
frame. Filters in front of the lamp and the camera's channels multiply in a scene without
fluorescence, so one render with one film channel per (filter, camera channel) pair gives every
filter's image at once.
"""

from __future__ import annotations

import numpy as np

from recon.errors import InputError
from recon.spectra import SampledSpectra
from twin.materials.calibration_targets import chart_parts
from twin.render.scene import PinholeCamera, render_view

__all__ = ["render_chart_bench"]


def render_chart_bench(
    reflectances: SampledSpectra,
    channels: SampledSpectra,
    *,
    columns: int,
    pitch_m: float,
    patch_fill: float,
    chart_to_camera: np.ndarray,
    focal_px: float,
    image_px: tuple[int, int],
    lamp_position_m: tuple[float, float, float] = (0.0, 0.0, 0.0),
    spp: int = 64,
    seed: int = 0,
) -> np.ndarray:
    """Render a chart on a bench: ``(H, W, n_channels)`` per unit lamp intensity.

    Parameters
    ----------
    reflectances
        The patches' reflectances, ``(n_patches, K)``, in the chart's reading order.
    channels
        Film channels ``(n, K)`` on the reflectances' grid, e.g. a sensor's electron responses
        times a filter (then the image is in e-/s for a lamp of 1 W sr^-1 nm^-1).
    columns, pitch_m, patch_fill
        The chart's layout: patches per row, centre-to-centre distance, fraction of a cell
        filled.
    chart_to_camera
        4 x 4 pose of the chart (its centre at the origin, z its normal, y up along its columns)
        in the camera's OpenCV frame.
    focal_px
        Focal length in pixels.
    image_px
        ``(height, width)`` of the image; the principal point is its centre.
    lamp_position_m
        The point lamp's position in the camera frame.
    spp, seed
        Samples per pixel and the render's seed.
    """
    height, width = image_px
    pose = np.asarray(chart_to_camera, np.float64)
    if pose.shape != (4, 4) or not np.all(np.isfinite(pose)):
        raise InputError(f"chart_to_camera: expected a finite 4x4 pose, got {pose.shape}")
    depth = float(pose[2, 3])
    if depth <= 0 or height > width:
        raise InputError(
            f"chart_to_camera, image_px: expected the chart in front of the camera and an image "
            f"at least as wide as high, got depth {depth} m and {height}x{width} px"
        )
    # The world is the camera frame moved along the optical axis to the chart's depth, so that
    # the camera looks at the world's origin (PinholeCamera's convention) with image up = -y.
    to_world = np.eye(4)
    to_world[2, 3] = -depth
    camera = PinholeCamera(
        position_m=np.array([0.0, 0.0, -depth]),
        field_of_view_m=depth * width / focal_px,
        pixels=width,
        up=(0.0, -1.0, 0.0),
    )
    parts = chart_parts(reflectances, columns, columns * pitch_m, patch_fill)
    flat = SampledSpectra(channels.grid, np.ones(channels.grid.size))
    lamp = np.asarray(lamp_position_m, np.float64) + to_world[:3, 3]
    square = render_view(parts, to_world @ pose, camera, channels, lamp, flat, spp=spp, seed=seed)
    top = (width - height) // 2
    return square[top : top + height]
