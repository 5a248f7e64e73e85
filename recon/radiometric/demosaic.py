"""Demosaicing of Bayer raw frames, through the ``colour-demosaicing`` package.

References
----------
- Malvar, H. S., He, L., & Cutler, R. (2004). High-quality linear interpolation for demosaicing
  of Bayer-patterned color images. ICASSP. doi:10.1109/ICASSP.2004.1326587
- Menon, D., Andriani, S., & Calvagno, G. (2007). Demosaicing With Directional Filtering and a
  posteriori Decision. IEEE TIP, 16(1), 132-141. doi:10.1109/TIP.2006.884928
"""

from __future__ import annotations

from typing import Literal

import colour_demosaicing
import numpy as np

from recon.errors import InputError

__all__ = ["DEMOSAIC_METHODS", "bin_quads", "demosaic"]

DEMOSAIC_METHODS = {
    "bilinear": colour_demosaicing.demosaicing_CFA_Bayer_bilinear,
    "Malvar2004": colour_demosaicing.demosaicing_CFA_Bayer_Malvar2004,
    "Menon2007": colour_demosaicing.demosaicing_CFA_Bayer_Menon2007,
}


def demosaic(
    mosaic: np.ndarray,
    *,
    pattern: Literal["RGGB", "BGGR", "GRBG", "GBRG"] = "RGGB",
    method: str = "bilinear",
) -> np.ndarray:
    """Interpolate a Bayer mosaic ``(H, W)`` (dark-subtracted, linear) to RGB ``(H, W, 3)``."""
    mosaic = np.asarray(mosaic, dtype=np.float64)
    if mosaic.ndim != 2:
        raise InputError(f"mosaic: expected a 2-D raw frame, got shape {mosaic.shape}")
    if method not in DEMOSAIC_METHODS:
        raise InputError(f"method: expected one of {sorted(DEMOSAIC_METHODS)}, got {method!r}")
    if pattern not in ("RGGB", "BGGR", "GRBG", "GBRG"):
        raise InputError(f"pattern: expected RGGB, BGGR, GRBG or GBRG, got {pattern!r}")
    return np.asarray(DEMOSAIC_METHODS[method](mosaic, pattern))


def bin_quads(
    mosaic: np.ndarray, *, pattern: Literal["RGGB", "BGGR", "GRBG", "GBRG"] = "RGGB"
) -> np.ndarray:
    """Superpixel demosaicing: each 2x2 Bayer quad of ``mosaic`` ``(..., 2H, 2W)`` becomes one
    RGB pixel ``(..., H, W, 3)`` (its red, the mean of its two greens, its blue).

    No interpolation across quads, so no colour fringes at edges; the price is half the
    resolution. Used where one quad images one texel (the dome simulation, thesis 10.4).
    """
    mosaic = np.asarray(mosaic, dtype=np.float64)
    if mosaic.ndim < 2 or mosaic.shape[-1] % 2 or mosaic.shape[-2] % 2:
        raise InputError(
            f"mosaic: expected (..., 2H, 2W) with even sides, got shape {mosaic.shape}"
        )
    if pattern not in ("RGGB", "BGGR", "GRBG", "GBRG"):
        raise InputError(f"pattern: expected RGGB, BGGR, GRBG or GBRG, got {pattern!r}")
    sites = {(0, 0): pattern[0], (0, 1): pattern[1], (1, 0): pattern[2], (1, 1): pattern[3]}
    planes: dict[str, list[np.ndarray]] = {"R": [], "G": [], "B": []}
    for (row, column), channel in sites.items():
        planes[channel].append(mosaic[..., row::2, column::2])
    return np.stack([np.mean(planes[channel], axis=0) for channel in "RGB"], axis=-1)
