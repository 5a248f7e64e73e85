"""Where the BTF preview's sample and camera sit (``spectwin btf render``), and which
directions of its lights and views lie beyond those the BTF sampled.

The sample lies at the origin: a plane of :data:`SAMPLE_SIZE_M` square tilted by
:data:`PLANE_TILT_DEG` about +x towards the camera, a sphere of radius :data:`SPHERE_RADIUS_M`
(its UV mapping: ``u`` the azimuth, ``v`` the polar angle), or a cloth hanging over a rod along
+x (:mod:`twin.validate.preview_cloth`: the texture repeated in tiles). The camera looks at the
origin from :data:`CAMERA_POSITION_M`. Rays through the pixel centres give every pixel that sees
the sample, its normal and its view direction without a render: the mask of the sample in the
image and the polar angles the BTF is looked up at. They are cast in NumPy on the plane and the
sphere, by Mitsuba's ray tracer on the cloth's mesh (:func:`twin.render.ray_cast.first_hits`:
its normals are those the renderer shades with). The rod (inside the cloth, its ends beyond the
cloth's edges) hides no part of the cloth from the camera.

The BSDF (:mod:`twin.render.plugins.btf_bsdf`) uses the nearest measured direction outside the
hull of the BTF's directions; this module reports the directions beyond the largest polar angle
the BTF sampled (of its lights, of its views), the usual case (grazing views of a sphere's rim,
a low sun); gaps in azimuth inside that angle are not reported.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from twin.render.ray_cast import first_hits
from twin.render.scene import PinholeCamera
from twin.validate.preview_cloth import cloth_mesh

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

Shape = Literal["plane", "sphere", "cloth"]

CAMERA_POSITION_M = np.array([0.0, -0.30, 0.22])
"""The camera, 37 degrees above the horizon, 0.37 m from the sample."""
FIELD_OF_VIEW_M = 0.16
"""Width of the camera's field at the sample."""
SAMPLE_SIZE_M = 0.1
PLANE_TILT_DEG = 25.0
"""The plane's tilt about +x towards the camera (its normal leans to -y)."""
SPHERE_RADIUS_M = 0.05
GROUND_Z_M = -0.051
"""Height of the ground under the sample (just below the sphere, the tilted plane and the
cloth's hem)."""


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
        ``"plane"``, ``"sphere"`` or ``"cloth"``.
    pixels
        Image size.

    Returns
    -------
    SurfaceView
    """
    camera = preview_camera(pixels)
    origin = camera.position_m
    rays = _pixel_rays(camera)
    hit, points, normals = _HITS[shape](np.broadcast_to(origin, rays.shape), rays)
    return SurfaceView(hit.reshape(pixels, pixels), points, normals, -rays[hit])


def _plane_hits(origins: np.ndarray, rays: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    normal = plane_normal()
    distance = -np.sum(origins * normal, axis=1) / (rays @ normal)
    points = origins + distance[:, None] * rays
    tilt = np.radians(PLANE_TILT_DEG)
    along_y = points[:, 1] * np.cos(tilt) + points[:, 2] * np.sin(tilt)
    half = SAMPLE_SIZE_M / 2
    hit = (distance > 0) & (np.abs(points[:, 0]) <= half) & (np.abs(along_y) <= half)
    return hit, points[hit], np.broadcast_to(normal, points[hit].shape)


def _sphere_hits(
    origins: np.ndarray, rays: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    b = np.sum(rays * origins, axis=1)
    discriminant = b**2 - (np.sum(origins**2, axis=1) - SPHERE_RADIUS_M**2)
    distance = -b - np.sqrt(np.maximum(discriminant, 0.0))
    hit = (discriminant > 0) & (distance > 0)
    points = origins[hit] + distance[hit, None] * rays[hit]
    return hit, points, points / SPHERE_RADIUS_M


def _cloth_hits(origins: np.ndarray, rays: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return first_hits(cloth_mesh(), origins, rays)


_HITS = {"plane": _plane_hits, "sphere": _sphere_hits, "cloth": _cloth_hits}
"""Per shape: which rays ``(n, 3)`` from ``origins`` ``(n, 3)`` meet the sample, and where
they do the points and unit normals."""


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
