"""Virtual capture of a spectral environment map with a mirror sphere (thesis 4.2).

The thesis captures the illumination of its validation scene by photographing a chrome sphere at
the sample's position with the spectral camera. Here a mirror sphere of radius ``radius_m`` at
the origin is rendered from ``distance_m`` along ``camera_direction`` through a calibrated
spectral camera (one channel per band, unit-area passbands: band-averaged radiance); the image is
unwrapped into a lat-long :class:`twin.spectral_envmap.SpectralMap`: the environment direction
:math:`d` is seen where the sphere's normal is :math:`n = (d + c) / |d + c|` (:math:`c` the
direction to the camera; exact for a distant camera, which the narrow field of view makes nearly
so). The sphere's reflectance is 1 (a real ball's measured reflectance is divided out); the
directions within ``blind_spot_deg`` of :math:`-c`, hidden behind the sphere, take the nearest
seen row.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import map_coordinates

from recon.errors import SpectwinInputError
from recon.spectra import WavelengthGrid
from twin.hemisphere import angle_between_deg
from twin.rig_scene import PinholeCamera
from twin.spectral_envmap import SpectralMap
from twin.truth import band_passbands
from twin.variant import activate

__all__ = ["capture_mirror_sphere", "unwrap_mirror_sphere"]


def _lat_long_directions(height: int, width: int) -> np.ndarray:
    theta = (np.arange(height) + 0.5) * np.pi / height
    phi = (np.arange(width) + 0.5) * 2 * np.pi / width
    theta, phi = np.meshgrid(theta, phi, indexing="ij")
    return np.stack(
        [np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1
    )


def unwrap_mirror_sphere(
    image: np.ndarray,
    camera: PinholeCamera,
    radius_m: float,
    grid: WavelengthGrid,
    *,
    height: int = 32,
    width: int = 64,
    blind_spot_deg: float = 20.0,
) -> SpectralMap:
    """Lat-long map ``(height, width, K)`` from an image ``(P, P, K)`` of a mirror sphere at the
    origin (module docstring)."""
    to_camera = camera.position_m / np.linalg.norm(camera.position_m)
    directions = _lat_long_directions(height, width)
    normals = directions + to_camera
    normals /= np.linalg.norm(normals, axis=-1, keepdims=True)
    points = camera.project((radius_m * normals).reshape(-1, 3))
    # Image arrays are indexed (row, column) with pixel centres at integer + 0.5.
    coordinates = [points[:, 1] - 0.5, points[:, 0] - 0.5]
    values = np.stack(
        [
            map_coordinates(image[..., band], coordinates, order=1, mode="nearest")
            for band in range(image.shape[-1])
        ],
        axis=-1,
    ).reshape(height, width, -1)
    hidden = angle_between_deg(directions, -to_camera) < blind_spot_deg
    if hidden.all():
        raise SpectwinInputError("blind_spot_deg: hides every direction of the map")
    seen = np.argwhere(~hidden)
    for row, column in np.argwhere(hidden):
        nearest = seen[np.argmin(np.abs(seen[:, 0] - row) + 0.01 * np.abs(seen[:, 1] - column))]
        values[row, column] = values[tuple(nearest)]
    return SpectralMap(np.maximum(values, 0.0), grid)


def capture_mirror_sphere(
    scene_entries: dict[str, object],
    grid: WavelengthGrid,
    *,
    camera_direction: tuple[float, float, float] = (0.0, -1.0, 0.3),
    distance_m: float = 30.0,
    radius_m: float = 0.05,
    pixels: int = 256,
    spp: int = 64,
    height: int = 32,
    width: int = 64,
) -> tuple[SpectralMap, np.ndarray]:
    """Render a mirror sphere at the origin inside ``scene_entries`` (emitters and shapes of a
    Mitsuba scene dict) with a spectral camera of bands ``grid``; returns the unwrapped map and
    the sphere image ``(pixels, pixels, K)``."""
    activate()
    import mitsuba as mi

    direction = np.asarray(camera_direction, np.float64)
    camera = PinholeCamera(
        distance_m * direction / np.linalg.norm(direction), 2.2 * radius_m, pixels
    )
    scene: dict[str, object] = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 4},
        "sensor": camera.mitsuba_sensor(band_passbands(grid), spp),
        "mirror_sphere": {
            "type": "sphere",
            "radius": radius_m,
            "bsdf": {"type": "conductor", "material": "none"},
        },
        **scene_entries,
    }
    image = np.array(mi.render(mi.load_dict(scene)), dtype=np.float64)
    return unwrap_mirror_sphere(image, camera, radius_m, grid, height=height, width=width), image
