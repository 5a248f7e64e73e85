"""Smits (1999): heuristic RGB-to-reflectance upsampling that uses no known spectra (thesis
Sec. 7.1), via colour-science's implementation. Input is linear RGB with sRGB primaries.

References
----------
- Smits, B. (1999). An RGB-to-spectrum conversion for reflectances. Journal of Graphics Tools,
  4(4), 11-22.
"""

from __future__ import annotations

import functools

import numpy as np
from colour.recovery import RGB_to_sd_Smits1999

from recon.baselines.common import check_reflectance_rgb
from recon.spectra import WavelengthGrid

__all__ = ["smits"]


@functools.lru_cache(maxsize=16)
def _smits_matrices(wavelengths: tuple[float, ...]) -> dict[tuple[int, int, int], np.ndarray]:
    """Per channel order ``(lowest, middle, highest)`` the ``(3, K)`` linear map of Smits.

    Within one ordering of R, G, B Smits' spectrum is linear in the RGB (white times the
    smallest value, a secondary times the middle step, a primary times the top step), so three
    evaluations of colour's ``RGB_to_sd_Smits1999`` on the region's edge points fix it.
    """
    wl = np.asarray(wavelengths)
    matrices = {}
    for order in [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]:
        points = np.zeros((3, 3))
        points[0, order[2]] = 1.0
        points[1, [order[1], order[2]]] = 1.0
        points[2, :] = 1.0
        values = np.array([RGB_to_sd_Smits1999(point)[wl] for point in points])
        matrices[order] = np.linalg.solve(points, values)
    return matrices


def smits(rgb: np.ndarray, *, wavelengths_nm: np.ndarray) -> np.ndarray:
    """Smooth reflectance spectra from RGB by Smits' (1999) method, via colour-science.

    Smits' spectrum is white times the smallest channel plus cyan/magenta/yellow times the
    middle step plus red/green/blue times the top step (colour's
    ``colour.recovery.RGB_to_sd_Smits1999`` and its ``SDS_SMITS1999`` basis spectra). Within one
    ordering of the channels this is linear in RGB, so it is evaluated for all pixels at once.

    Input is **linear RGB with sRGB (ITU-R BT.709) primaries and equal-energy white**: the
    colourspace of colour's Smits implementation, whose illuminant is CIE E (a flat reflectance
    of 1 has RGB (1, 1, 1)). Camera RGB must first be mapped to this space (or from XYZ) by the
    caller. The recovered colour is approximate: Smits' basis spectra are tabulated on ten
    bins between 380 and 720 nm (colour interpolates linearly and extends the end values beyond
    that range).

    Parameters
    ----------
    rgb
        ``(..., 3)`` linear RGB in [0, 1].
    wavelengths_nm
        Strictly increasing output wavelengths in nm (e.g. ``DEFAULT_GRID.wavelengths_nm``).

    Returns
    -------
    numpy.ndarray
        ``(..., K)`` reflectances at ``wavelengths_nm``.
    """
    pixels = check_reflectance_rgb(rgb)
    grid = WavelengthGrid(wavelengths_nm)
    matrices = _smits_matrices(tuple(float(value) for value in grid.wavelengths_nm))
    flat = pixels.reshape(-1, 3)
    order = np.argsort(flat, axis=1, kind="stable")
    result = np.empty((len(flat), grid.size))
    for key, matrix in matrices.items():
        mask = np.all(order == key, axis=1)
        result[mask] = flat[mask] @ matrix
    return result.reshape(*pixels.shape[:-1], grid.size)
