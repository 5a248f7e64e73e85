"""Imai & Berns (1999): the minimal-norm inverse matrix :math:`S = V R^+` (thesis Sec. 6.1).

References
----------
- Imai, F. H., & Berns, R. S. (1999). Spectral estimation using trichromatic digital cameras.
  Proc. International Symposium on Multispectral Imaging and Color Reproduction for Digital
  Archives, 42-49.
"""

from __future__ import annotations

import numpy as np

from recon.baselines.common import check_image, check_response

__all__ = ["imai"]


def imai(rgb: np.ndarray, response: np.ndarray) -> np.ndarray:
    """Minimal-norm spectra :math:`S = V R^+` (Imai & Berns 1999; thesis Sec. 6.1).

    Parameters
    ----------
    rgb
        ``(..., C)`` device values :math:`V`.
    response
        ``(K, C)`` projection :math:`R` with ``rgb = spectra @ response`` (Eq. 6.2).

    Returns
    -------
    numpy.ndarray
        ``(..., K)`` spectra. For a response of full column rank they reproduce ``rgb`` exactly
        and have no component in the metameric-black space :math:`\\{s : s R = 0\\}`: they are
        the minimal-norm solution, so every reconstructed spectrum lies in the C-dimensional
        span of the response curves.
    """
    pixels = check_image("rgb", rgb)
    matrix = check_response(response, None, pixels.shape[-1])
    return pixels @ np.linalg.pinv(matrix)
