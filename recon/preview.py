"""Display previews of spectral images: CIE 1931 XYZ, then sRGB for a PNG.

References
----------
- CIE 015:2018 Colorimetry (CIE 1931 standard observer), via ``colour``.
- IEC 61966-2-1:1999 (sRGB), via ``colour.XYZ_to_sRGB``.
"""

from __future__ import annotations

import colour
import numpy as np

from recon.errors import InputError
from recon.spectra import SampledSpectra, WavelengthGrid, band_integrals, from_colour, resample

__all__ = ["spectral_to_srgb", "spectral_to_xyz"]

_OBSERVER = "CIE 1931 2 Degree Standard Observer"


def spectral_to_xyz(cube: np.ndarray, grid: WavelengthGrid) -> np.ndarray:
    """Tristimulus values :math:`X = \\int L \\bar{x} d\\lambda` etc. of ``cube`` ``(..., K)``."""
    cube = np.asarray(cube, dtype=np.float64)
    if cube.shape[-1] != grid.size:
        raise InputError(
            f"cube: expected the band axis last with {grid.size} bands, got shape {cube.shape}"
        )
    observer = resample(from_colour(colour.MSDS_CMFS[_OBSERVER]), grid, out_of_range="zero")
    return band_integrals(SampledSpectra(grid, cube), observer)


def spectral_to_srgb(
    cube: np.ndarray,
    grid: WavelengthGrid,
    *,
    white: SampledSpectra | None = None,
    percentile: float = 99.0,
) -> np.ndarray:
    """8-bit sRGB preview ``(H, W, 3)`` of a spectral radiance image ``(H, W, K)``.

    The image is scaled so that the ``percentile`` of luminance Y maps to 1 and, when ``white``
    (the illuminant's spectrum on ``grid``) is given, adapted from that white to D65 with CAT02.
    """
    xyz = spectral_to_xyz(cube, grid)
    scale = np.percentile(xyz[..., 1], percentile)
    if not scale > 0:
        raise InputError("cube: expected some positive luminance to show, got none")
    illuminant = colour.CCS_ILLUMINANTS[_OBSERVER]["D65"]
    if white is not None:
        illuminant = colour.XYZ_to_xy(spectral_to_xyz(white.values, white.grid))
    rgb = colour.XYZ_to_sRGB(
        xyz / scale, illuminant=illuminant, chromatic_adaptation_transform="CAT02"
    )
    return (np.clip(rgb, 0, 1) * 255 + 0.5).astype(np.uint8)
