"""Direction samplings of the hemisphere above a sample (local frame: z is the surface normal).

References
----------
- Sattler, M., Sarlette, R., & Klein, R. (2003). Efficient and realistic visualization of cloth.
  Eurographics Symposium on Rendering, 167-177: 81 directions on rings of polar angle
  0, 15, 30, 45, 60, 75 degrees with 1, 6, 12, 18, 20, 24 azimuths; 81 x 81 = 6561 light x view
  pairs, used unchanged by the thesis (section 4.1.1).
"""

from __future__ import annotations

import numpy as np

from recon.directions import direction
from recon.errors import InputError

__all__ = ["SATTLER_RINGS", "angle_between_deg", "direction", "sattler_directions", "spherical_deg"]

SATTLER_RINGS = ((0.0, 1), (15.0, 6), (30.0, 12), (45.0, 18), (60.0, 20), (75.0, 24))
"""(polar angle in degrees, number of equally spaced azimuths starting at 0) of Sattler et al."""


def spherical_deg(vectors: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Polar angle and azimuth (degrees, azimuth in [0, 360)) of unit vectors ``(..., 3)``."""
    vectors = np.asarray(vectors, dtype=np.float64)
    theta = np.degrees(np.arccos(np.clip(vectors[..., 2], -1.0, 1.0)))
    phi = np.degrees(np.arctan2(vectors[..., 1], vectors[..., 0])) % 360.0
    return theta, phi


def angle_between_deg(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """Angle in degrees between unit vectors (numerically stable for tiny angles)."""
    first, second = np.asarray(first, np.float64), np.asarray(second, np.float64)
    cross = np.linalg.norm(np.cross(first, second), axis=-1)
    return np.degrees(np.arctan2(cross, np.sum(first * second, axis=-1)))


def sattler_directions(rings: tuple[tuple[float, int], ...] = SATTLER_RINGS) -> np.ndarray:
    """The 81 directions of Sattler et al. (2003), ``(81, 3)``, ring by ring, azimuth ascending."""
    if not rings or any(count < 1 or not 0 <= theta < 90 for theta, count in rings):
        raise InputError(
            "rings: expected (polar angle in [0, 90) degrees, azimuth count >= 1) pairs"
        )
    return np.concatenate(
        [direction(theta, np.arange(count) * 360.0 / count) for theta, count in rings]
    )
