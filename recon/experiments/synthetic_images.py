"""Synthetic spectral images with a known number of materials, for experiments and tests.

A Voronoi mosaic assigns each cell one of the given reflectance spectra; a smooth shading field
scales the brightness, as shading does on real textures. With more than three linearly
independent spectra such an image is the case the thesis uses against inverse-matrix methods
(section 6.1: their reconstructions lie on a 3-D subspace).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from recon.errors import SpectwinInputError

__all__ = ["material_mosaic"]


def material_mosaic(
    spectra: np.ndarray,
    shape: tuple[int, int],
    *,
    cells: int = 60,
    shading: tuple[float, float] = (0.6, 1.0),
    seed: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """A ``(height, width, K)`` reflectance image made of ``spectra`` in Voronoi cells.

    Parameters
    ----------
    spectra
        ``(n_materials, K)`` reflectance spectra.
    shape
        ``(height, width)`` in pixels.
    cells
        Number of Voronoi cells; cell ``c`` takes material ``c mod n_materials``.
    shading
        Range of the smooth multiplicative shading field.
    seed
        Seed of the cell centres.

    Returns
    -------
    image : numpy.ndarray
        ``(height, width, K)`` spectra.
    labels : numpy.ndarray
        ``(height, width)`` material index per pixel.
    """
    spectra = np.asarray(spectra, dtype=np.float64)
    if spectra.ndim != 2 or spectra.shape[0] < 1:
        raise SpectwinInputError(f"spectra: expected (n_materials, K), got shape {spectra.shape}")
    height, width = (int(v) for v in shape)
    if height < 1 or width < 1 or cells < 1:
        raise SpectwinInputError(f"shape, cells: expected positive sizes, got {shape}, {cells}")
    low, high = shading
    if not 0 < low <= high:
        raise SpectwinInputError(f"shading: expected 0 < low <= high, got {shading}")
    rng = np.random.default_rng(seed)
    rows, cols = np.mgrid[0:height, 0:width]
    pixels = np.stack([rows.ravel() / height, cols.ravel() / width], axis=1)
    _, cell = cKDTree(rng.random((cells, 2))).query(pixels, workers=-1)
    labels = (np.arange(cells) % spectra.shape[0])[cell].reshape(height, width)
    wave = np.sin(2 * np.pi * (1.3 * rows / height + 0.7 * cols / width)) ** 2
    shade = low + (high - low) * wave
    return spectra[labels] * shade[..., None], labels
