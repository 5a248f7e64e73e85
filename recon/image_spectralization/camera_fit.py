"""The camera term :math:`R_{cam}` of a spectralization (Eq. 6.2), fitted to the spot spectra.

The camera's response :math:`r_c(\\lambda)` is given (by name or CSV), but not the light the
image was taken under, the exposure or the response's units: the image's linear values are
:math:`V_{s,c} = \\sum_\\lambda S_s(\\lambda) L(\\lambda) r_c(\\lambda) w_\\lambda` up to a gain
per channel (Eq. 9.4, with :math:`w_\\lambda` the quadrature weights). A gain per channel
absorbs the light's level in each channel but not its shape within the channel: under CIE D65
(blue-rich, with a dip at 480 nm) the camera sees a spectrum tilted against what the bare
response sees, and the spectralization, held to the wrong camera term, bends every spectrum the
spots do not fix (on the twin's wallpaper BTF 0.65 % Eq. 6.8 and Delta E94 0.42 with gains
alone, 0.04 % and 0.00 with D65 in the response; BENCHMARKS.md, "Spectral BTFs from RGB BTFs
and spot spectra").

So each channel's response is multiplied by a smooth factor, a Legendre series of degree
:math:`d_c` in the wavelength over the grid, :math:`R_{cam}[\\lambda, c] = r_c(\\lambda)
w_\\lambda \\sum_{j \\le d_c} b_{c,j} P_j(t(\\lambda))`, fitted to the spots by linear least
squares: the basic estimate of thesis Eq. 9.3-9.5 with the given response as its base and the
spots as the chart. The degree of each channel (0, the gain alone, to :data:`MAX_DEGREE`) is
the lowest one with (nearly, :data:`PRESS_TIE`) the smallest leave-one-out residual over the
spots (PRESS, Allen 1974), so a few spots or spots of a few colours keep a low degree and noisy
spots do not bend the response.

References
----------
- The thesis, Eq. 6.2 and Eq. 9.3-9.5 (a camera's response from known reflectances).
- Allen, D. M. (1974). The relationship between variable selection and data augmentation and a
  method for prediction. Technometrics 16(1), 125-127 (PRESS, the leave-one-out residual).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre

from recon.errors import InputError
from recon.spectra import SampledSpectra, WavelengthGrid, resample

__all__ = ["MAX_DEGREE", "PRESS_TIE", "CameraTerm", "camera_term"]

MAX_DEGREE = 4
"""Highest degree of the smooth factor per channel (module description). On the twin's BTFs
under D65 degree 2 took away most of the gains' error and 4 all of it (0.04 % on wallpaper,
against 0.08 % at degree 2)."""
PRESS_TIE = 1.05
"""The lowest degree whose leave-one-out residual is within this factor of the smallest is
taken: exact spots (noise-free images) fit every degree above the true one as well."""


@dataclass(frozen=True)
class CameraTerm:
    """:math:`R_{cam}` ``(K, 3)`` on the grid (``matrix``), the gain per channel (the fitted
    factor's constant Legendre coefficient, its mean over the wavelength range, ``gains``), the
    relative RMS residual of the fit per channel over the spots (``fit_residual_pct``, %) and
    the factor's degree per channel (``degrees``)."""

    matrix: np.ndarray
    gains: np.ndarray
    fit_residual_pct: np.ndarray
    degrees: tuple[int, ...]


def _press(design: np.ndarray, values: np.ndarray) -> tuple[float, np.ndarray]:
    """The mean squared leave-one-out residual of the least-squares fit of ``values`` by the
    columns of ``design`` (from the hat matrix's diagonal) and the fit's coefficients; infinite
    where a spot alone decides a coefficient."""
    coefficients, _, rank, _ = np.linalg.lstsq(design, values, rcond=None)
    if rank < design.shape[1] or design.shape[0] <= design.shape[1]:
        return np.inf, coefficients
    q, _ = np.linalg.qr(design)
    leverage = np.sum(q**2, axis=1)
    if np.any(leverage > 1 - 1e-9):
        return np.inf, coefficients
    residual = (values - design @ coefficients) / (1 - leverage)
    return float(np.mean(residual**2)), coefficients


def camera_term(
    response: SampledSpectra,
    grid: WavelengthGrid,
    rgb_at_spots: np.ndarray,
    spectra: np.ndarray,
    *,
    max_degree: int = MAX_DEGREE,
) -> CameraTerm:
    """Fit :math:`R_{cam}` to the spots (module description).

    Parameters
    ----------
    response
        ``(3, K')`` the camera's response, rows R, G, B, any scale.
    grid
        The wavelengths to reconstruct on.
    rgb_at_spots
        ``(m, 3)`` the image's linear values at the spots.
    spectra
        ``(m, K)`` the spots' spectra on ``grid``.
    max_degree
        Highest degree of the smooth factor per channel; 0 fits a gain per channel alone.

    Returns
    -------
    CameraTerm

    Examples
    --------
    A light that rises linearly with the wavelength is found from spots of random spectra:

    >>> import numpy as np
    >>> from recon.spectra import SampledSpectra, WavelengthGrid
    >>> grid = WavelengthGrid.regular(400, 700, 10)
    >>> bands = np.arange(grid.size)
    >>> response = SampledSpectra(grid, np.exp(-((bands - np.array([[25], [15], [5]])) / 4) ** 2))
    >>> light = np.linspace(0.5, 1.5, grid.size)
    >>> spectra = np.random.default_rng(0).random((20, grid.size))
    >>> truth = (response.values * light * grid.quadrature_weights()).T
    >>> term = camera_term(response, grid, spectra @ truth, spectra)
    >>> bool(np.allclose(term.matrix, truth)), term.degrees
    (True, (1, 1, 1))
    """
    if not (isinstance(max_degree, (int, np.integer)) and max_degree >= 0):
        raise InputError(f"max_degree: expected an integer >= 0, got {max_degree!r}")
    on_grid = resample(response, grid, out_of_range="zero").values.T
    integrals = on_grid * grid.quadrature_weights()[:, None]
    predicted = spectra @ integrals
    power = np.sum(predicted**2, axis=0)
    if np.any(power <= 0):
        channel = "RGB"[int(np.argmin(power))]
        raise InputError(
            f"spots: their spectra give no {channel} signal through the camera's response; "
            "expected spectra where the camera is sensitive"
        )
    gains = np.sum(rgb_at_spots * predicted, axis=0) / power
    if not np.all(gains > 0):
        channel = "RGB"[int(np.argmin(gains))]
        raise InputError(
            f"image, spots: the image's {channel} values at the spots do not grow with the "
            "spectra's signal (gain <= 0); expected the spots' coordinates on the image"
        )
    wavelengths = grid.wavelengths_nm
    position = 2 * (wavelengths - wavelengths[0]) / (wavelengths[-1] - wavelengths[0]) - 1
    basis = legendre.legvander(position, max_degree)  # (K, max_degree + 1)
    matrix = np.empty_like(integrals)
    degrees = []
    for column in range(integrals.shape[1]):
        design = spectra @ (integrals[:, column, None] * basis)  # (m, max_degree + 1)
        fits = [_press(design[:, : d + 1], rgb_at_spots[:, column]) for d in range(max_degree + 1)]
        press = np.array([error for error, _ in fits])
        floor = PRESS_TIE * np.min(press) + np.finfo(float).eps * np.mean(rgb_at_spots**2)
        degree = int(np.argmax(press <= floor)) if np.isfinite(press).any() else 0
        coefficients = fits[degree][1]
        matrix[:, column] = integrals[:, column] * (basis[:, : degree + 1] @ coefficients)
        gains[column] = coefficients[0]
        degrees.append(degree)
    residual = rgb_at_spots - spectra @ matrix
    scale = np.sqrt(np.mean(rgb_at_spots**2, axis=0))
    fit = 100 * np.sqrt(np.mean(residual**2, axis=0)) / np.maximum(scale, np.finfo(float).tiny)
    return CameraTerm(matrix, gains, fit, tuple(degrees))
