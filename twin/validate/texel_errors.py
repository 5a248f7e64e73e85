"""Per-texel errors of a measured texture against the truth, over the texels that show the
material: Eq. 6.8 and Delta E94 (the thesis's ten illuminants), both of reflectance factors."""

from __future__ import annotations

import numpy as np

from recon.metrics import delta_e94, relative_error
from recon.spectra import WavelengthGrid

__all__ = ["texel_errors"]


def texel_errors(
    measured: np.ndarray, truth: np.ndarray, grid: WavelengthGrid, material: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Errors of ``measured`` against ``truth`` (both ``(n_pairs, H, W, K)``) where ``material``
    ``(n_pairs, H, W)`` is true.

    Returns
    -------
    tuple of numpy.ndarray
        Eq. 6.8 (%) and Delta E94 per pair and texel ``(n_pairs, H * W)``, NaN where no material
        shows, then their means per pair ``(n_pairs,)`` (NaN for a pair that shows none).
    """
    relative = np.where(material, relative_error(measured, truth), np.nan)
    colour = np.where(material, delta_e94(measured, truth, grid), np.nan)
    relative_flat, colour_flat = (values.reshape(len(values), -1) for values in (relative, colour))
    counts = material.reshape(len(material), -1).sum(axis=1)
    shown = material.reshape(counts.size, -1)
    relative_mean, colour_mean = (
        np.where(counts > 0, np.where(shown, flat, 0).sum(1) / np.maximum(counts, 1), np.nan)
        for flat in (relative_flat, colour_flat)
    )
    return relative_flat, colour_flat, relative_mean, colour_mean
