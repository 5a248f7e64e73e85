"""Hardeberg et al. (1999): the inverse matrix trained on known spectra (thesis Sec. 6.1).

References
----------
- Hardeberg, J. Y., Schmitt, F., Brettel, H., Crettez, J.-P., & Maitre, H. (1999).
  Multispectral image acquisition and simulation of illuminant changes. In Colour Imaging:
  Vision and Technology (pp. 145-164). Wiley.
"""

from __future__ import annotations

import numpy as np

from recon.baselines.common import check_image, check_known_rgb, check_spectra

__all__ = ["hardeberg"]


def hardeberg(
    rgb: np.ndarray,
    *,
    known_spectra: np.ndarray,
    known_pixels: np.ndarray | None = None,
    known_rgb: np.ndarray | None = None,
) -> np.ndarray:
    """Trained inverse matrix (Hardeberg et al. 1999; thesis Sec. 6.1).

    :math:`W = \\arg\\min_W \\|V_{known} W - S_{known}\\|_F^2 = V_{known}^+ S_{known}` is learned
    from the known spectra and their RGB and applied to every pixel: :math:`S = V W`. It needs
    no camera response. All results lie in a C-dimensional subspace of spectral space, so it is
    exact when the scene's spectra span at most C dimensions (and the RGB is noise free) and
    biased otherwise (thesis Sec. 6.1, 7.1).

    Parameters
    ----------
    rgb
        ``(..., C)`` device values.
    known_spectra
        ``(m, K)`` known spectra, m >= 1.
    known_pixels
        Flat row-major indices into ``rgb.shape[:-1]`` where ``known_spectra`` were measured
        (their RGB is read from ``rgb``). Give this or ``known_rgb``.
    known_rgb
        ``(m, C)`` RGB of the known spectra, for training data that is not in the image.

    Returns
    -------
    numpy.ndarray
        ``(..., K)`` spectra.
    """
    pixels = check_image("rgb", rgb)
    spectra = check_spectra("known_spectra", known_spectra)
    flat = pixels.reshape(-1, pixels.shape[-1])
    train_rgb = check_known_rgb(flat, spectra, known_pixels, known_rgb, pixels.shape[:-1])
    inverse = np.linalg.pinv(train_rgb) @ spectra  # (C, K)
    return pixels @ inverse
