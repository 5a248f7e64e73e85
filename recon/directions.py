"""Directions in the sample frame (z along the normal) from polar angle and azimuth.

The one convention of the project's direction tables, shared by the twin's rigs
(:mod:`twin.rigs.hemisphere`) and the imports of measured BTFs (:mod:`recon.btf.rgb_images`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["direction"]


def direction(theta_deg: np.ndarray | float, phi_deg: np.ndarray | float) -> np.ndarray:
    """Unit vector(s) ``(..., 3)`` at polar angle ``theta_deg`` from +z and azimuth ``phi_deg``
    from +x towards +y, in degrees."""
    theta, phi = np.radians(theta_deg), np.radians(phi_deg)
    return np.stack(
        np.broadcast_arrays(
            np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)
        ),
        axis=-1,
    )
