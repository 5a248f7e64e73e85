"""Where the BTF preview's sample and camera sit (``spectwin btf render``), and which
directions of its lights and views lie beyond those the BTF sampled.

The sample lies at the origin: a plane of :data:`SAMPLE_SIZE_M` square tilted by
:data:`PLANE_TILT_DEG` about +x towards the camera, or a sphere of radius
:data:`SPHERE_RADIUS_M` (its UV mapping: ``u`` the azimuth, ``v`` the polar angle). The camera
looks at the origin from :data:`CAMERA_POSITION_M`. Rays through the pixel centres, cast here in
NumPy, give every pixel that sees the sample, its normal and its view direction without a render:
the mask of the sample in the image and the polar angles the BTF is looked up at.

The BSDF (:mod:`twin.render.plugins.btf_bsdf`) uses the nearest measured direction outside the
hull of the BTF's directions; this module reports the directions beyond the largest polar angle
the BTF sampled (of its lights, of its views), the usual case (grazing views of a sphere's rim,
a low sun); gaps in azimuth inside that angle are not reported.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from twin.render.scene import PinholeCamera

__all__ = [
    "CAMERA_POSITION_M",
    "PLANE_TILT_DEG",
    "SAMPLE_SIZE_M",
    "SPHERE_RADIUS_M",
    "Shape",
    "SurfaceView",
    "beyond_fraction",
    "preview_camera",
    "surface_view",
]

Shape = Literal["plane", "sphere"]

CAMERA_POSITION_M = np.array([0.0, -0.30, 0.22])
"""The camera, 37 degrees above the horizon, 0.37 m from the sample."""
FIELD_OF_VIEW_M = 0.16
"""Width of the camera's field at the sample."""
SAMPLE_SIZE_M = 0.1
PLANE_TILT_DEG = 25.0
"""The plane's tilt about +x towards the camera (its normal leans to -y)."""
SPHERE_RADIUS_M = 0.05
GROUND_Z_M = -0.051
"""Height of the ground under the sample (just below the sphere and the tilted plane)."""


def preview_camera(pixels: int) -> PinholeCamera:
    """The preview's camera, ``pixels`` square."""
    return PinholeCamera(CAMERA_POSITION_M, FIELD_OF_VIEW_M, pixels)


def plane_normal() -> np.ndarray:
    """The tilted plane's normal in the world."""
    tilt = np.radians(PLANE_TILT_DEG)
    return np.array([0.0, -np.sin(tilt), np.cos(tilt)])


@dataclass(frozen=True)
class SurfaceView:
    """The sample as the camera sees it: ``mask`` ``(pixels, pixels)`` of the pixels whose
    centre ray meets it, and for those pixels (in row-major order) the surface ``points``,
    unit ``normals`` and unit ``views`` (towards the camera), each ``(n, 3)``."""

    mask: np.ndarray
    points: np.ndarray
    normals: np.ndarray
    views: np.ndarray


def _pixel_rays(camera: PinholeCamera) -> np.ndarray:
    """Unit directions ``(pixels * pixels, 3)`` through the pixel centres (inverse of
    :meth:`PinholeCamera.project`)."""
    left, up, forward = camera.frame()
    size = camera.pixels
    focal = size / 2 / np.tan(np.radians(camera.fov_deg) / 2)
    centres = np.arange(size) + 0.5
    rows, columns = np.meshgrid(centres, centres, indexing="ij")
    across = (size / 2 - columns.ravel())[:, None] * left / focal
    down = (size / 2 - rows.ravel())[:, None] * up / focal
    rays = forward + across + down
    return rays / np.linalg.norm(rays, axis=1, keepdims=True)


def surface_view(shape: Shape, pixels: int) -> SurfaceView:
    """The sample's pixels, points, normals and view directions (module docstring).

    Parameters
    ----------
    shape
        ``"plane"`` or ``"sphere"``.
    pixels
        Image size.

    Returns
    -------
    SurfaceView
    """
    camera = preview_camera(pixels)
    origin = camera.position_m
    rays = _pixel_rays(camera)
    if shape == "plane":
        normal = plane_normal()
        distance = -(origin @ normal) / (rays @ normal)
        points = origin + distance[:, None] * rays
        tilt = np.radians(PLANE_TILT_DEG)
        along_y = points[:, 1] * np.cos(tilt) + points[:, 2] * np.sin(tilt)
        half = SAMPLE_SIZE_M / 2
        hit = (distance > 0) & (np.abs(points[:, 0]) <= half) & (np.abs(along_y) <= half)
        normals = np.broadcast_to(normal, points.shape)
    else:
        b = rays @ origin
        discriminant = b**2 - (origin @ origin - SPHERE_RADIUS_M**2)
        distance = -b - np.sqrt(np.maximum(discriminant, 0.0))
        hit = (discriminant > 0) & (distance > 0)
        points = origin + distance[:, None] * rays
        normals = points / SPHERE_RADIUS_M
    views = -rays[hit]
    return SurfaceView(hit.reshape(pixels, pixels), points[hit], normals[hit], views)


def polar_deg(normals: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Polar angles in degrees of ``directions`` relative to ``normals`` (broadcast)."""
    cosines = np.clip(np.sum(normals * directions, axis=-1), -1.0, 1.0)
    return np.degrees(np.arccos(cosines))


def beyond_fraction(
    normals: np.ndarray, directions: np.ndarray, weights: np.ndarray, limit_deg: float
) -> float:
    """Fraction of the cosine-weighted light from ``directions`` ``(m, 3)`` (weights ``(m,)``,
    e.g. radiance times solid angle) on surfaces of ``normals`` ``(n, 3)`` that arrives beyond
    the polar angle ``limit_deg``; 0 where no light arrives."""
    cosines = np.clip(normals @ directions.T, 0.0, None) * weights[None, :]
    total = cosines.sum()
    if not total > 0:
        return 0.0
    beyond = (normals @ directions.T) < np.cos(np.radians(limit_deg))
    return float(cosines[beyond].sum() / total)
