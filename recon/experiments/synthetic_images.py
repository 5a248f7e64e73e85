"""Synthetic spectral images with a known number of materials, for experiments and tests.

A Voronoi mosaic assigns each cell one of the given reflectance spectra; a smooth shading field
scales the brightness, as shading does on real textures. With more than three linearly
independent spectra such an image is the case the thesis uses against inverse-matrix methods
(section 6.1: their reconstructions lie on a 3-D subspace).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from recon.errors import InputError

__all__ = ["material_mosaic", "smooth_blend"]


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
        raise InputError(f"spectra: expected (n_materials, K), got shape {spectra.shape}")
    height, width = (int(v) for v in shape)
    if height < 1 or width < 1 or cells < 1:
        raise InputError(f"shape, cells: expected positive sizes, got {shape}, {cells}")
    low, high = shading
    if not 0 < low <= high:
        raise InputError(f"shading: expected 0 < low <= high, got {shading}")
    rng = np.random.default_rng(seed)
    rows, cols = np.mgrid[0:height, 0:width]
    pixels = np.stack([rows.ravel() / height, cols.ravel() / width], axis=1)
    _, cell = cKDTree(rng.random((cells, 2))).query(pixels, workers=-1)
    labels = (np.arange(cells) % spectra.shape[0])[cell].reshape(height, width)
    wave = np.sin(2 * np.pi * (1.3 * rows / height + 0.7 * cols / width)) ** 2
    shade = low + (high - low) * wave
    return spectra[labels] * shade[..., None], labels


def smooth_blend(
    spectra: np.ndarray,
    shape: tuple[int, int],
    *,
    blobs: int = 12,
    width: float = 0.12,
    shading: tuple[float, float] = (0.8, 1.2),
    seed: int = 0,
) -> np.ndarray:
    """A ``(height, width, K)`` image whose spectra blend smoothly between ``blobs`` of the
    given ``spectra`` (convex Gaussian weights around random centres), times a smooth shading.

    Unlike :func:`material_mosaic` it has no edges and more distinct spectra than materials: every
    pixel is its own mixture, so the image spans up to ``blobs`` dimensions.

    Parameters
    ----------
    spectra
        ``(n_materials, K)`` reflectance spectra; ``blobs`` of them are drawn (with
        replacement only when there are fewer than ``blobs``).
    shape
        ``(height, width)`` in pixels.
    blobs
        Number of blend centres.
    width
        Standard deviation of the Gaussian weights, as a fraction of the longer image side.
    shading
        Range of the smooth multiplicative shading field.
    seed
        Seed of the centres and the drawn spectra.
    """
    spectra = np.asarray(spectra, dtype=np.float64)
    if spectra.ndim != 2 or spectra.shape[0] < 1:
        raise InputError(f"spectra: expected (n_materials, K), got shape {spectra.shape}")
    height, width_px = (int(v) for v in shape)
    if height < 1 or width_px < 1 or blobs < 1 or not width > 0:
        raise InputError(
            f"shape, blobs, width: expected positive values, got {shape}, {blobs}, {width}"
        )
    low, high = shading
    if not 0 < low <= high:
        raise InputError(f"shading: expected 0 < low <= high, got {shading}")
    rng = np.random.default_rng(seed)
    side = max(height, width_px)
    rows, cols = np.mgrid[0:height, 0:width_px] / side
    centres = rng.random((blobs, 2)) * np.array([height, width_px]) / side
    chosen = rng.choice(spectra.shape[0], blobs, replace=spectra.shape[0] < blobs)
    distance2 = (rows[..., None] - centres[:, 0]) ** 2 + (cols[..., None] - centres[:, 1]) ** 2
    weights = np.exp(-distance2 / (2 * width**2))
    weights /= weights.sum(axis=-1, keepdims=True)
    shade = low + (high - low) * np.sin(2 * np.pi * (1.1 * rows + 0.6 * cols)) ** 2
    return (weights @ spectra[chosen]) * shade[..., None]
