"""Murakami et al. (2007): Gaussian-prior (Wiener) estimate from the known spectra's statistics
plus a spatially interpolated correction at the known points (thesis Sec. 5, 6.2, 7.1).

References
----------
- Murakami, Y., Ietomi, K., Yamaguchi, M., & Ohyama, N. (2007). Maximum a posteriori
  estimation of spectral reflectance from color image and multipoint spectral measurements.
  Applied Optics, 46(28), 7068-7082.
"""

from __future__ import annotations

import numpy as np
from scipy import linalg, spatial
from scipy.interpolate import RegularGridInterpolator as interpolate_grid

from recon.baselines.common import (
    CHUNK_ELEMENTS,
    check_image,
    check_known_pixels,
    check_positive,
    check_response,
    check_spectra,
    check_target_pixels,
)
from recon.errors import InputError

__all__ = ["default_correlation_length", "murakami"]


def default_correlation_length(height: int, width: int) -> float:
    """The correlation length :math:`L` of :func:`murakami` by default, in pixels: a tenth of
    the image's longer side."""
    return 0.1 * max(height, width)


def murakami(
    rgb: np.ndarray,
    response: np.ndarray,
    *,
    known_spectra: np.ndarray,
    known_pixels: np.ndarray,
    correlation_length: float | None = None,
    rgb_noise_std: float = 0.0,
    nugget: float = 0.0,
    at_pixels: np.ndarray | None = None,
    grid_step: int = 1,
) -> np.ndarray:
    """Gaussian-prior estimate with spatial correction from point spectra (Murakami et al. 2007).

    Our reading of Murakami et al.'s MAP estimate, in two steps:

    1. **Global estimate** (the Gaussian prior): mean :math:`\\mu` and covariance :math:`\\Sigma`
       of the known spectra give the Wiener (linear MMSE) estimate for every pixel,
       :math:`\\hat s = \\mu + (v - \\mu R)(R^T \\Sigma R + \\sigma^2 I)^{-1} R^T \\Sigma`.
       A tiny ridge (:math:`10^{-8}` of the mean variance) keeps :math:`\\Sigma` positive definite
       so the estimate reproduces noise-free RGB exactly.
    2. **Spatial correction**: at the known pixels the residuals
       :math:`e_j = s_j - \\hat s(x_j)` are projected onto the camera's metameric-black space
       :math:`\\{e : e R = 0\\}` (with noise-free RGB they already lie there, and this is then
       the range of the posterior covariance) and interpolated over the image by simple kriging
       with the spatial correlation :math:`\\rho(d) = \\exp(-d / L)` between pixels at distance
       :math:`d`: :math:`\\hat e(x) = k(x)^T (P + \\eta I)^{-1} E` with
       :math:`P_{jl} = \\rho(|x_j - x_l|)`, :math:`k_j(x) = \\rho(|x - x_j|)`. This is the
       conditional mean of the residual field under the separable covariance
       :math:`\\mathrm{Cov}(e(x), e(y)) = \\rho(|x - y|)\\, \\Sigma_e`, in which the spectral factor
       :math:`\\Sigma_e` cancels. Far from every known point the correction fades to zero.

    The result is :math:`\\hat s(x) + \\hat e(x)`. Its RGB equals the input when
    ``rgb_noise_std == 0`` (the correction is metameric black), and with ``nugget == 0`` the
    known spectra are reproduced exactly at their pixels.

    Differences from the paper: the paper derives both steps jointly from one Gaussian model of
    the whole spectral image; here the residual covariance is taken separable (spectral factor
    times spatial factor) so the correction is an interpolation of the residuals, and with RGB
    noise the correction is still restricted to metameric black. The thesis (Sec. 6.2, 7.1)
    notes the method's weakness: the global Gaussian prior fits images with non-normal value
    distributions poorly.

    Parameters
    ----------
    rgb
        ``(H, W, C)`` image (the 2-D layout gives the pixel positions).
    response
        ``(K, C)`` projection with ``rgb = spectra @ response``.
    known_spectra
        ``(m, K)`` spectra measured at ``known_pixels``, m >= 1.
    known_pixels
        Flat row-major indices into ``(H, W)``: pixel ``i`` is at row ``i // W``, column
        ``i % W``.
    correlation_length
        :math:`L` in pixels; default ``0.1 * max(H, W)`` (:func:`default_correlation_length`).
    rgb_noise_std
        Standard deviation :math:`\\sigma` of the RGB noise in ``rgb`` units (Wiener step).
    nugget
        :math:`\\eta`, noise of the known spectra relative to the residual variance; 0
        interpolates the residuals exactly.
    at_pixels
        Flat row-major indices of the pixels to estimate (e.g. spots held out of
        ``known_pixels``); default every pixel.
    grid_step
        With every pixel estimated, the spatial correction is evaluated on every
        ``grid_step``-th row and column (and the last) and interpolated bilinearly between
        them: ``grid_step**2`` times fewer kernel values. 1 (default): at every pixel.

    Returns
    -------
    numpy.ndarray
        ``(H, W, K)`` spectra, or ``(n, K)`` at the ``n`` ``at_pixels``.

    Notes
    -----
    Cost: one ``m x m`` solve and an ``n x m`` kernel evaluated in chunks, ``n`` the pixels
    at which the correction is evaluated.
    """
    image = check_image("rgb", rgb)
    if image.ndim != 3:
        raise InputError(
            f"rgb: murakami needs a 2-D image of shape (H, W, C) for the pixel positions, "
            f"got shape {image.shape}"
        )
    height, width, channels = image.shape
    spectra = check_spectra("known_spectra", known_spectra)
    bands = spectra.shape[1]
    matrix = check_response(response, bands, channels)
    index = check_known_pixels(known_pixels, height * width, len(spectra), (height, width))
    length = (
        default_correlation_length(height, width)
        if correlation_length is None
        else check_positive("correlation_length", correlation_length)
    )
    noise = check_positive("rgb_noise_std", rgb_noise_std, allow_zero=True)
    nugget = check_positive("nugget", nugget, allow_zero=True)

    if not (isinstance(grid_step, (int, np.integer)) and grid_step >= 1):
        raise InputError(f"grid_step: expected a whole number of pixels >= 1, got {grid_step!r}")
    flat = image.reshape(-1, channels)
    if at_pixels is not None:
        targets = check_target_pixels(at_pixels, height * width, (height, width))
        flat = flat[targets]

    # 1. Wiener estimate under the Gaussian prior of the known spectra.
    mean = spectra.mean(axis=0)
    centred = spectra - mean
    covariance = centred.T @ centred / len(spectra)
    scale = (np.trace(covariance) + mean @ mean) / bands
    covariance += (1e-8 * scale + np.finfo(np.float64).tiny) * np.eye(bands)
    projected = covariance @ matrix  # (K, C)
    system = matrix.T @ projected + noise**2 * np.eye(channels)
    gain = np.linalg.pinv(system, hermitian=True) @ projected.T  # (C, K)

    def wiener(values: np.ndarray) -> np.ndarray:
        return mean + (values - mean @ matrix) @ gain

    # 2. Residuals at the known points, metameric black, interpolated by simple kriging.
    black = np.eye(bands) - matrix @ np.linalg.pinv(matrix)
    residuals = (spectra - wiener(image.reshape(-1, channels)[index])) @ black
    known_xy = _positions(index, width)
    kernel = _correlation(known_xy, known_xy, length)
    kernel[np.diag_indices_from(kernel)] += nugget
    try:
        weights = linalg.solve(kernel, residuals, assume_a="pos")
    except (linalg.LinAlgError, ValueError):
        weights = linalg.lstsq(kernel, residuals)[0]
    estimate = wiener(flat)
    if at_pixels is not None:
        return estimate + _kriged(_positions(targets, width), known_xy, weights, length)
    if grid_step == 1:
        estimate += _kriged(_positions(np.arange(len(flat)), width), known_xy, weights, length)
        return estimate.reshape(height, width, bands)
    rows, cols = (np.unique(np.r_[np.arange(0, n, grid_step), n - 1]) for n in (height, width))
    coarse = np.stack(np.meshgrid(rows, cols, indexing="ij"), axis=-1).reshape(-1, 2)
    correction = _kriged(coarse.astype(np.float64), known_xy, weights, length)
    interpolate = interpolate_grid((rows, cols), correction.reshape(rows.size, cols.size, bands))
    estimate = estimate.reshape(height, width, bands)
    for row in range(height):
        estimate[row] += interpolate(np.column_stack([np.full(width, row), np.arange(width)]))
    return estimate


def _positions(index: np.ndarray, width: int) -> np.ndarray:
    """``(n, 2)`` float (row, column) of flat row-major pixel indices."""
    return np.column_stack(np.divmod(index, width)).astype(np.float64)


def _correlation(first: np.ndarray, second: np.ndarray, length: float) -> np.ndarray:
    """``exp(-d / L)`` between two sets of ``(n, 2)`` positions, in place of the distances."""
    distances = spatial.distance.cdist(first, second)
    np.divide(distances, -length, out=distances)
    return np.exp(distances, out=distances)


def _kriged(
    positions: np.ndarray, known_xy: np.ndarray, weights: np.ndarray, length: float
) -> np.ndarray:
    """Simple kriging's correction ``k(x)^T (P + eta I)^{-1} E`` at ``(n, 2)`` positions,
    ``weights`` being the solved ``(P + eta I)^{-1} E``; the ``n x m`` kernel in chunks."""
    correction = np.empty((len(positions), weights.shape[1]))
    rows_per_chunk = max(1, CHUNK_ELEMENTS // len(known_xy))
    for start in range(0, len(positions), rows_per_chunk):
        chunk = slice(start, start + rows_per_chunk)
        near = _correlation(positions[chunk], known_xy, length)
        correction[chunk] = near @ weights
    return correction
