r"""Virtual capture of a spectral environment map with a mirror sphere (thesis 4.2).

The thesis captures the illumination of its validation scene by photographing a chrome sphere at
the sample's position with the spectral camera. Here a mirror sphere of radius ``radius_m`` at
the origin is rendered from ``distance_m`` along ``camera_direction`` through a calibrated
spectral camera (one channel per band, unit-area passbands: band-averaged radiance); the image is
unwrapped into a lat-long :class:`twin.render.plugins.spectral_envmap.SpectralMap` by splatting:
every image
pixel on the sphere is traced (camera ray, sphere hit, mirror reflection) to the environment
direction it shows and averaged into that map pixel. Seen orthographically, a mirror sphere
covers the sphere of directions with a constant density per image area (:math:`d\omega/dA =
4/r^2`), so these averages are solid-angle averages and small bright sources (spot lamps) keep
their power. The sphere's reflectance is 1 (a real ball's measured reflectance is divided out);
map pixels within ``blind_spot_deg`` of the direction away from the camera, hidden behind the
sphere, and pixels no image pixel reached take the nearest seen row.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from recon.errors import InputError
from recon.spectra import WavelengthGrid
from twin.render.light_groups import LightGroup, render_lit
from twin.render.plugins.spectral_envmap import SpectralMap
from twin.render.scene import PinholeCamera
from twin.render.truth import band_passbands
from twin.rigs.hemisphere import angle_between_deg, direction, spherical_deg

__all__ = ["capture_mirror_sphere", "lat_long_from_directions", "unwrap_mirror_sphere"]


def _reflected_directions(camera: PinholeCamera, radius_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Per image pixel centre that sees the sphere: its flat index and the direction it
    reflects (``(n,)``, ``(n, 3)``)."""
    left, up, forward = camera.frame()
    focal = camera.pixels / 2 / np.tan(np.radians(camera.fov_deg) / 2)
    centres = np.arange(camera.pixels) + 0.5
    column, row = np.meshgrid(centres, centres)
    rays = (
        forward
        + ((camera.pixels / 2 - column) / focal)[..., None] * left
        + ((camera.pixels / 2 - row) / focal)[..., None] * up
    ).reshape(-1, 3)
    rays /= np.linalg.norm(rays, axis=1, keepdims=True)
    origin = np.asarray(camera.position_m, np.float64)
    along = -(rays @ origin)
    closest = origin + along[:, None] * rays
    miss_sq = radius_m**2 - np.einsum("ij,ij->i", closest, closest)
    hit = miss_sq > 0
    points = closest[hit] - np.sqrt(miss_sq[hit])[:, None] * rays[hit]
    normals = points / radius_m
    incoming = rays[hit]
    reflected = incoming - 2 * np.einsum("ij,ij->i", incoming, normals)[:, None] * normals
    return np.flatnonzero(hit), reflected


def lat_long_from_directions(
    values: np.ndarray,
    directions: np.ndarray,
    away: np.ndarray,
    *,
    height: int,
    width: int,
    blind_spot_deg: float = 20.0,
) -> np.ndarray:
    """Lat-long map ``(height, width, K)``: the mean of ``values`` ``(n, K)`` seen in unit
    ``directions`` ``(n, 3)`` per map pixel; pixels within ``blind_spot_deg`` of ``away`` (the
    direction hidden behind a mirror sphere) and pixels no direction reached take the nearest
    seen row (module docstring)."""
    theta_deg, phi_deg = spherical_deg(directions)
    row = np.minimum((theta_deg / 180 * height).astype(int), height - 1)
    column = np.minimum((phi_deg / 360 * width).astype(int), width - 1)
    cell = row * width + column
    counts = np.bincount(cell, minlength=height * width)
    sums = np.stack(
        [np.bincount(cell, values[:, k], minlength=height * width) for k in range(values.shape[1])],
        axis=-1,
    )
    mean = (sums / np.maximum(counts, 1)[:, None]).reshape(height, width, -1)
    centres = direction(
        ((np.arange(height) + 0.5) * 180 / height)[:, None],
        ((np.arange(width) + 0.5) * 360 / width)[None, :],
    )
    hidden = (angle_between_deg(centres, away / np.linalg.norm(away)) < blind_spot_deg) | (
        counts.reshape(height, width) == 0
    )
    if hidden.all():
        raise InputError("blind_spot_deg: hides every direction of the map")
    seen = np.argwhere(~hidden)
    for row_index, column_index in np.argwhere(hidden):
        distance = np.abs(seen[:, 0] - row_index) + 0.01 * np.abs(seen[:, 1] - column_index)
        mean[row_index, column_index] = mean[tuple(seen[np.argmin(distance)])]
    return np.maximum(mean, 0.0)


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
    pixels, directions = _reflected_directions(camera, radius_m)
    flat = image.reshape(-1, image.shape[-1])[pixels]
    away = -np.asarray(camera.position_m, np.float64)
    values = lat_long_from_directions(
        flat, directions, away, height=height, width=width, blind_spot_deg=blind_spot_deg
    )
    return SpectralMap(values, grid)


def capture_mirror_sphere(
    scene_entries: dict[str, object],
    grid: WavelengthGrid,
    *,
    groups: Sequence[LightGroup] = (),
    camera_direction: tuple[float, float, float] = (0.0, -1.0, 0.3),
    distance_m: float = 1.0,
    radius_m: float = 0.05,
    pixels: int = 256,
    spp: int = 64,
    height: int = 32,
    width: int = 64,
) -> tuple[SpectralMap, np.ndarray]:
    """Render a mirror sphere at the origin inside ``scene_entries`` (shapes and emitters of a
    Mitsuba scene dict) lit by ``groups`` (:func:`twin.render.light_groups.render_lit`) with a
    spectral
    camera of bands ``grid``; returns the unwrapped map and the sphere image
    ``(pixels, pixels, K)``."""
    direction = np.asarray(camera_direction, np.float64)
    camera = PinholeCamera(
        distance_m * direction / np.linalg.norm(direction), 2.2 * radius_m, pixels
    )
    sphere = {
        "type": "sphere",
        "radius": radius_m,
        "bsdf": {"type": "conductor", "material": "none"},
    }
    image = render_lit(
        camera,
        band_passbands(grid),
        {"mirror_sphere": sphere, **scene_entries},
        groups,
        spp=spp,
    )
    return unwrap_mirror_sphere(image, camera, radius_m, grid, height=height, width=width), image
