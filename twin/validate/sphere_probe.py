"""The light at the sample from a user's photograph of a mirror sphere (thesis 4.2: the
validation scene's light captured with a chrome ball at the sample's position).

The sphere is photographed by the camera of the sample's photograph, from the same place, where
the sample lay (:mod:`twin.validate.photo_camera` gives that camera's pose). Its circle in the
photograph (centre and radius, pixels) is given. Seen from afar, a pixel at offset ``(dx, dy)``
from the centre, in radii, shows the sphere's normal ``dx`` along the image's right, ``dy`` along
its down and ``-sqrt(1 - dx^2 - dy^2)`` along the ray to the centre; it reflects that ray into
one direction of the world, and the pixels are averaged into a lat-long map by direction
(:func:`twin.validate.envmap_capture.lat_long_from_directions`; the directions hidden behind
the sphere take the nearest seen row). The outer 2 % of the radius, where the reflection grazes,
is left out. The map's RGB (linear sRGB) becomes spectra as an RGB environment map does
(:func:`twin.validate.preview_lighting.radiance_from_linear_srgb`); the sphere's own
reflectance is not divided out: the photograph's exposure, fitted by default, takes it up.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from recon.errors import InputError
from recon.spectra import DEFAULT_GRID
from twin.render.plugins.spectral_envmap import SpectralMap
from twin.validate.envmap_capture import lat_long_from_directions
from twin.validate.photo_camera import PhotoCamera
from twin.validate.preview_lighting import radiance_from_linear_srgb

__all__ = ["MirrorSphere", "unwrap_sphere_photo"]

_RIM = 0.98


@dataclass(frozen=True)
class MirrorSphere:
    """A photograph of a mirror sphere: ``path`` and its circle ``(x, y, radius)`` in pixels."""

    path: Path
    circle: tuple[float, float, float]


def _check_circle(circle: tuple[float, float, float], width: int, height: int) -> None:
    x, y, radius = circle
    inside = radius > 1 and x - radius >= 0 and y - radius >= 0
    if not (inside and x + radius <= width and y + radius <= height):
        raise InputError(
            f"--sphere-circle {x:g},{y:g},{radius:g}: not inside the {width} x {height} "
            "photograph; expected the sphere's centre and radius in its pixels"
        )


def unwrap_sphere_photo(
    rgb: np.ndarray,
    circle: tuple[float, float, float],
    camera: PhotoCamera,
    to_srgb: np.ndarray,
    *,
    height: int,
) -> SpectralMap:
    """The lat-long map ``(height, 2 height)`` of the light seen in a mirror sphere (module
    docstring).

    Parameters
    ----------
    rgb
        ``(H, W, 3)`` the sphere's photograph, linear, the size ``camera`` has.
    circle
        ``(x, y, radius)`` of the sphere in it, pixels.
    camera
        The camera that took it, posed relative to the sample.
    to_srgb
        ``(3, 3)`` the photograph's values to linear sRGB.
    height
        Rows of the map.

    Returns
    -------
    SpectralMap
    """
    _check_circle(circle, rgb.shape[1], rgb.shape[0])
    x, y, radius = circle
    columns, rows = np.meshgrid(np.arange(rgb.shape[1]) + 0.5, np.arange(rgb.shape[0]) + 0.5)
    dx, dy = (columns - x) / radius, (rows - y) / radius
    seen = dx**2 + dy**2 < _RIM**2
    centre = camera.ray(x, y)
    right = np.array([1.0, 0.0, 0.0]) - centre[0] * centre
    right /= np.linalg.norm(right)
    down = np.cross(centre, right)
    normals = (
        dx[seen, None] * right
        + dy[seen, None] * down
        - np.sqrt(1 - dx[seen] ** 2 - dy[seen] ** 2)[:, None] * centre
    )
    reflected = centre - 2 * (normals @ centre)[:, None] * normals
    world = reflected @ camera.rotation  # camera axes to the world's: R^T r, row-wise
    away = camera.rotation.T @ centre
    linear = lat_long_from_directions(
        rgb[seen] @ to_srgb.T, world, away, height=height, width=2 * height
    )
    return SpectralMap(radiance_from_linear_srgb(linear), DEFAULT_GRID)
