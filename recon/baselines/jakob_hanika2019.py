"""Jakob & Hanika (2019): heuristic RGB-to-reflectance upsampling by a sigmoid of a quadratic,
using no known spectra (thesis Sec. 7.1), fitted directly or through colour-science's lookup
table. Input is linear sRGB.

References
----------
- Jakob, W., & Hanika, J. (2019). A low-dimensional function space for efficient spectral
  upsampling. Computer Graphics Forum, 38(2), 147-155.
"""

from __future__ import annotations

import contextlib
import functools
import io

import colour
import numpy as np
from colour.recovery import LUT3D_Jakob2019

from recon.baselines.common import CHUNK_ELEMENTS, check_count, check_reflectance_rgb
from recon.errors import InputError
from recon.spectra import WavelengthGrid

__all__ = ["jakob"]

_CMFS_NAME = "CIE 1931 2 Degree Standard Observer"


def _jakob_model(coefficients: np.ndarray, basis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Jakob & Hanika's sigmoid-of-quadratic reflectance and its polynomial ``U``."""
    poly = coefficients @ basis
    return 0.5 + poly / (2.0 * np.sqrt(1.0 + poly * poly)), poly


def _jakob_fit(targets: np.ndarray, weights: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """Coefficients ``(n, 3)`` whose model spectrum has the target XYZ (``(n, 3)``).

    Levenberg-Marquardt on the XYZ residual, vectorized over colours, with a homotopy from the
    grey of equal luminance (whose flat spectrum is an exact solution) to the target, like the
    lightness walk in colour's LUT generation. ``weights`` ``(K, 3)`` integrate a reflectance to
    XYZ; ``basis`` ``(3, K)`` holds ``x**2, x, 1`` of the normalized wavelength ``x``.
    """
    white = weights.sum(axis=0)
    luminance = np.clip(targets[:, 1] / white[1], 1e-4, 1.0 - 1e-4)
    coefficients = np.zeros_like(targets)
    coefficients[:, 2] = (2 * luminance - 1) / (2 * np.sqrt(luminance * (1 - luminance)))
    grey = luminance[:, None] * white

    def solve(coefficients: np.ndarray, target: np.ndarray, iterations: int) -> np.ndarray:
        damping = np.full(len(target), 1e-2)
        spectra, poly = _jakob_model(coefficients, basis)
        residual = spectra @ weights - target
        error = np.einsum("nc,nc->n", residual, residual)
        for _ in range(iterations):
            slope = 0.5 / (1.0 + poly * poly) ** 1.5  # d reflectance / d poly
            jacobian = np.einsum("nk,kc,jk->ncj", slope, weights, basis)
            normal = np.einsum("nci,ncj->nij", jacobian, jacobian)
            scale = damping * (np.trace(normal, axis1=1, axis2=2) / 3 + 1e-300)
            normal += scale[:, None, None] * np.eye(3)
            gradient = np.einsum("nci,nc->ni", jacobian, residual)
            trial = coefficients - np.linalg.solve(normal, gradient[..., None])[..., 0]
            trial_spectra, trial_poly = _jakob_model(trial, basis)
            trial_residual = trial_spectra @ weights - target
            trial_error = np.einsum("nc,nc->n", trial_residual, trial_residual)
            better = trial_error < error
            coefficients = np.where(better[:, None], trial, coefficients)
            poly = np.where(better[:, None], trial_poly, poly)
            residual = np.where(better[:, None], trial_residual, residual)
            error = np.where(better, trial_error, error)
            damping = np.where(better, damping / 3, damping * 4)
        return coefficients

    steps = 8
    for step in range(1, steps + 1):
        fraction = step / steps
        coefficients = solve(coefficients, grey + fraction * (targets - grey), 10)
    return solve(coefficients, targets, 30)


@functools.lru_cache(maxsize=1)
def _srgb() -> colour.RGB_Colourspace:
    """sRGB with matrices derived from its primaries and white (the published ones are rounded
    to 4 decimals, which would tint greys by ~1e-4)."""
    colourspace = colour.models.RGB_COLOURSPACE_sRGB.copy()
    colourspace.use_derived_transformation_matrices(True)
    return colourspace


@functools.lru_cache(maxsize=4)
def _jakob_lut(size: int, start: float, end: float, interval: float) -> LUT3D_Jakob2019:
    """colour's Jakob & Hanika LUT for sRGB under D65, optimized on the given spectral shape."""
    shape = colour.SpectralShape(start, end, interval)
    cmfs = colour.MSDS_CMFS[_CMFS_NAME].copy().align(shape)
    illuminant = colour.SDS_ILLUMINANTS["D65"].copy().align(shape)
    lut = LUT3D_Jakob2019()
    with contextlib.redirect_stderr(io.StringIO()):  # colour shows a tqdm progress bar
        lut.generate(_srgb(), cmfs, illuminant, size, lambda *_: None)
    return lut


def jakob(
    rgb: np.ndarray, *, wavelengths_nm: np.ndarray, lut_size: int | None = None
) -> np.ndarray:
    """Smooth reflectance spectra from RGB by Jakob & Hanika's (2019) sigmoid model.

    Each reflectance is :math:`r(\\lambda) = \\frac12 + \\frac{U}{2\\sqrt{1 + U^2}}` with a
    quadratic :math:`U = c_0 \\lambda^2 + c_1 \\lambda + c_2` whose coefficients make the
    spectrum's colour (CIE 1931 2 degree observer, illuminant D65, integrated on
    ``wavelengths_nm``) equal the target. Two ways to get the coefficients:

    - ``lut_size=None`` (default): fit every distinct colour directly, vectorized
      (Levenberg-Marquardt on the XYZ residual starting from the grey of equal luminance). This
      is the optimization colour-science runs per colour in
      ``colour.XYZ_to_sd(..., method="Jakob 2019")``, for all colours at once (~0.2 s per
      colour there, ~0.2 ms here); the target colour is met to about 1e-6 except at the
      unreachable limits 0 and 1 of a channel.
    - ``lut_size=n``: the paper's run-time method, colour's ``LUT3D_Jakob2019`` of size ``n``
      (generated for sRGB and D65 on ``wavelengths_nm``, which must be regular, and cached in
      this process), interpolated. Generation is slow (measured on 2 busy cores: size 4 in
      8-80 s, size 8 in ~3 min) and small tables are coarse (size 4: mean colour error 0.04,
      max 0.3); the published tables have size 64.

    Input is **linear sRGB** (D65 white, :math:`(1, 1, 1)` is a perfect white reflector under
    D65). Camera RGB must first be mapped to linear sRGB (or XYZ) by the caller. As in colour's
    LUT generation, sRGB's white is adapted (CAT02) to the white of a perfect reflector
    integrated on ``wavelengths_nm``, so grey inputs give exactly flat spectra; to check a
    result, integrate it under D65 on the same grid and convert to sRGB with that white. The
    sRGB matrices are derived from the primaries (colour's published ones are rounded).

    Parameters
    ----------
    rgb
        ``(..., 3)`` linear sRGB in [0, 1].
    wavelengths_nm
        Strictly increasing output wavelengths in nm.
    lut_size
        ``None`` to fit each colour, or the size (>= 2) of colour's lookup table to use.

    Returns
    -------
    numpy.ndarray
        ``(..., K)`` reflectances in (0, 1) at ``wavelengths_nm``.
    """
    pixels = check_reflectance_rgb(rgb)
    grid = WavelengthGrid(wavelengths_nm)
    wl = grid.wavelengths_nm
    flat = pixels.reshape(-1, 3)
    colours, inverse = np.unique(flat, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    if lut_size is not None:
        size = check_count("lut_size", lut_size, 2)
        steps = np.diff(wl)
        if not np.allclose(steps, steps[0], rtol=1e-9, atol=0):
            raise InputError(
                "wavelengths_nm: the LUT path (lut_size) needs a regular grid; use "
                "lut_size=None for irregular grids"
            )
        lut = _jakob_lut(size, float(wl[0]), float(wl[-1]), float(steps[0]))
        dimensional = np.reshape(lut.RGB_to_coefficients(colours), (-1, 3))
        poly = dimensional @ np.stack([wl**2, wl, np.ones_like(wl)])
        spectra = 0.5 + poly / (2.0 * np.sqrt(1.0 + poly * poly))
        return spectra[inverse].reshape(*pixels.shape[:-1], grid.size)

    cmfs = colour.MSDS_CMFS[_CMFS_NAME]
    illuminant = colour.SDS_ILLUMINANTS["D65"]
    weights = cmfs[wl] * (illuminant[wl] * np.gradient(wl))[:, None]
    weights /= weights[:, 1].sum()  # a perfect white reflector has Y = 1
    # Like colour's LUT generation: adapt sRGB's D65 white to the white of a perfect reflector
    # integrated on this grid (CAT02), so grey inputs give exactly flat spectra.
    white_xy = colour.XYZ_to_xy(weights.sum(axis=0))
    targets = colour.RGB_to_XYZ(colours, _srgb(), white_xy)
    x = (wl - wl[0]) / (wl[-1] - wl[0])
    basis = np.stack([x**2, x, np.ones_like(x)])
    spectra = np.empty((len(colours), grid.size))
    rows_per_chunk = max(1, CHUNK_ELEMENTS // (9 * grid.size))
    for start in range(0, len(colours), rows_per_chunk):
        chunk = slice(start, start + rows_per_chunk)
        coefficients = _jakob_fit(targets[chunk], weights, basis)
        spectra[chunk] = _jakob_model(coefficients, basis)[0]
    return spectra[inverse].reshape(*pixels.shape[:-1], grid.size)
