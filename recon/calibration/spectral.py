"""Spectral calibration of the gonioreflectometer: white factors, exposure plan, drift, reflectance.

With the camera's inverse response :math:`\\hat f^{-1}` and dark frames :math:`d`, a white
standard of known reflectance :math:`W_\\lambda` (Zenith Ultra-White) photographed under the lamp
:math:`I_\\lambda` fixes one factor per band (thesis Eq. 3.3),

.. math:: F_\\lambda = \\frac{I_\\lambda W_\\lambda t}{\\pi}
          \\frac{1}{\\frac1n \\sum_i \\hat f^{-1}(p_{\\lambda,i,white})},

the band exposure times follow as :math:`t_\\lambda = t_{base} F_\\lambda / I_\\lambda` (Eq. 3.4;
multiples of 1/15 s with the flickering HMI lamp, section 3.2.2), and the BRDF of every pixel
is (Eq. 3.5, and per measurement run with :math:`F'_\\lambda = F_\\lambda / I_\\lambda` and the
lamp-drift factor :math:`F_{i,long}` from the lamp monitor, Eq. 3.6)

.. math:: \\rho(i, x, \\lambda) = \\frac{F'_\\lambda F_{i,long}\\,
          \\hat f^{-1}(p_{i,x,\\lambda} - d_{x,t_\\lambda})}{t_\\lambda}.

The inverse response is passed as a callable (identity for a linear camera); values are
camera values (digital numbers), spectra are on the band grid, band axis first for images
``(K, ...)``.

References
----------
- The thesis, section 3.3, Eq. 3.3-3.6, and section 3.2.2 (HMI flicker at 15 Hz).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from recon.errors import InputError

__all__ = [
    "HMI_FLICKER_PERIOD_S",
    "drift_factors",
    "plan_exposures",
    "reflectance",
    "run_white_factors",
    "white_factors",
]

HMI_FLICKER_PERIOD_S = 1.0 / 15.0
"""Period of the HMI lamp's line-emission oscillation (thesis 3.2.2: 66.6 ms)."""

InverseResponse = Callable[[np.ndarray], np.ndarray]


def _identity(values: np.ndarray) -> np.ndarray:
    return values


def _band_vector(name: str, values: object, bands: int | None = None) -> np.ndarray:
    array = np.asarray(values, dtype=np.float64)
    if array.ndim != 1 or (bands is not None and array.size != bands):
        expected = f"({bands},)" if bands is not None else "1-D"
        raise InputError(f"{name}: expected one value per band {expected}, got {array.shape}")
    if not np.all(np.isfinite(array)) or np.any(array <= 0):
        raise InputError(f"{name}: expected finite, positive values per band")
    return array


def _band_images(name: str, values: object, bands: int) -> np.ndarray:
    array = np.asarray(values, dtype=np.float64)
    if array.ndim < 1 or array.shape[0] != bands:
        raise InputError(
            f"{name}: expected the band axis first with {bands} bands, got shape {array.shape}"
        )
    if not np.all(np.isfinite(array)):
        raise InputError(f"{name}: values must be finite (found NaN or inf)")
    return array


def _mean_linear_signal(
    white_values: np.ndarray, white_dark: np.ndarray | float, inverse_response: InverseResponse
) -> np.ndarray:
    """:math:`\\frac1n \\sum_i \\hat f^{-1}(p_i - d_i)` per band over all but the band axis."""
    bands = white_values.shape[0]
    linear = inverse_response(white_values - white_dark).reshape(bands, -1)
    signal = linear.mean(axis=1)
    if np.any(signal <= 0):
        raise InputError(
            "white_values: the white standard gives no signal above the dark level in band(s) "
            f"{np.flatnonzero(signal <= 0).tolist()}; lengthen the exposure"
        )
    return signal


def white_factors(
    white_values: np.ndarray,
    exposure_s: np.ndarray,
    lamp: np.ndarray,
    white_reflectance: np.ndarray,
    *,
    white_dark: np.ndarray | float = 0.0,
    inverse_response: InverseResponse = _identity,
) -> np.ndarray:
    """:math:`F_\\lambda` of Eq. 3.3 from photographs of the white standard.

    Parameters
    ----------
    white_values
        ``(K, ...)`` camera values of the white standard's pixels, one image (or pixel set) per
        band.
    exposure_s
        ``(K,)`` exposure time of each band's photograph, s.
    lamp
        ``(K,)`` lamp spectrum :math:`I_\\lambda` (irradiance on the standard, any unit).
    white_reflectance
        ``(K,)`` reflectance :math:`W_\\lambda` of the standard (manufacturer data).
    white_dark
        Dark values to subtract before linearizing (scalar or broadcastable to
        ``white_values``).
    inverse_response
        :math:`\\hat f^{-1}`, camera value to relative exposure (default: linear camera).

    Returns
    -------
    numpy.ndarray
        ``(K,)`` factors: BRDF per unit linear signal per second and unit :math:`I`.
    """
    white_values = np.asarray(white_values, dtype=np.float64)
    bands = white_values.shape[0] if white_values.ndim else 0
    exposure = _band_vector("exposure_s", exposure_s, bands)
    lamp = _band_vector("lamp", lamp, bands)
    white = _band_vector("white_reflectance", white_reflectance, bands)
    signal = _mean_linear_signal(
        _band_images("white_values", white_values, bands), white_dark, inverse_response
    )
    return lamp * white * exposure / np.pi / signal


def run_white_factors(
    white_values: np.ndarray,
    exposure_s: np.ndarray,
    white_reflectance: np.ndarray,
    *,
    white_dark: np.ndarray | float = 0.0,
    inverse_response: InverseResponse = _identity,
) -> np.ndarray:
    """:math:`F'_\\lambda = F_\\lambda / I_\\lambda` for one measurement run (Eq. 3.6): the lamp
    spectrum cancels, so the run's white photographs alone fix it (the lamp distance may differ
    by centimetres between runs, thesis 3.3)."""
    white_values = np.asarray(white_values, dtype=np.float64)
    bands = white_values.shape[0] if white_values.ndim else 0
    return white_factors(
        white_values,
        exposure_s,
        np.ones(bands),
        white_reflectance,
        white_dark=white_dark,
        inverse_response=inverse_response,
    )


def plan_exposures(
    base_s: float,
    factors: np.ndarray,
    lamp: np.ndarray,
    *,
    round_to_s: float | None = None,
    limits_s: tuple[float, float] = (0.0, np.inf),
) -> np.ndarray:
    """Band exposure times :math:`t_\\lambda = t_{base} F_\\lambda / I_\\lambda` (Eq. 3.4).

    Parameters
    ----------
    base_s
        :math:`t_{base}`, s.
    factors, lamp
        ``(K,)`` :math:`F_\\lambda` (Eq. 3.3) and the measurement lamp's :math:`I_\\lambda`.
    round_to_s
        Round every time up to a multiple of this period (``HMI_FLICKER_PERIOD_S`` for the HMI
        lamp, so every exposure integrates whole flicker periods).
    limits_s
        The camera's exposure range; rounded times that leave it raise an error.

    Returns
    -------
    numpy.ndarray
        ``(K,)`` exposure times, s.
    """
    if not (np.isfinite(base_s) and base_s > 0):
        raise InputError(f"base_s: expected a positive time in s, got {base_s}")
    factors = _band_vector("factors", factors)
    lamp = _band_vector("lamp", lamp, factors.size)
    times = base_s * factors / lamp
    if round_to_s is not None:
        if not round_to_s > 0:
            raise InputError(f"round_to_s: expected a positive period, got {round_to_s}")
        times = np.maximum(np.ceil(times / round_to_s - 1e-9), 1.0) * round_to_s
    low, high = limits_s
    outside = np.flatnonzero((times < low) | (times > high))
    if outside.size:
        raise InputError(
            f"plan_exposures: band(s) {outside.tolist()} need "
            f"{times[outside].round(4).tolist()} s, outside the camera's range [{low}, {high}] s; "
            "change base_s"
        )
    return times


def drift_factors(monitor_spectra: np.ndarray, *, reference: int = 0) -> np.ndarray:
    """:math:`F_{i,long}`: one scale per measurement point that maps its lamp-monitor spectrum
    onto the reference point's (least squares over the bands; thesis 3.3, Fig. 3.5(c)).

    Parameters
    ----------
    monitor_spectra
        ``(n_points, K_monitor)`` spectra of the lamp monitor (X-Rite i1 opposite the lamp).
    reference
        Index of the point :math:`i_0` the others are related to.

    Returns
    -------
    numpy.ndarray
        ``(n_points,)`` factors; 1 at ``reference``, below 1 where the lamp was brighter.
    """
    spectra = np.asarray(monitor_spectra, dtype=np.float64)
    if spectra.ndim != 2 or spectra.shape[0] < 1 or not np.all(np.isfinite(spectra)):
        raise InputError(
            f"monitor_spectra: expected finite (n_points, K) spectra, got shape {spectra.shape}"
        )
    if not 0 <= reference < spectra.shape[0]:
        raise InputError(f"reference: expected an index below {spectra.shape[0]}")
    power = np.einsum("ik,ik->i", spectra, spectra)
    if np.any(power <= 0):
        raise InputError("monitor_spectra: a point has an all-zero lamp spectrum")
    return spectra @ spectra[reference] / power


def reflectance(
    values: np.ndarray,
    exposure_s: np.ndarray,
    run_factors: np.ndarray,
    *,
    dark: np.ndarray | float = 0.0,
    drift: float = 1.0,
    inverse_response: InverseResponse = _identity,
) -> np.ndarray:
    """BRDF :math:`\\rho(i, x, \\lambda)` of Eq. 3.6 (1/sr) from one direction pair's frames.

    Parameters
    ----------
    values
        ``(K, ...)`` camera values, band axis first.
    exposure_s
        ``(K,)`` :math:`t_\\lambda`.
    run_factors
        ``(K,)`` :math:`F'_\\lambda` of the run (:func:`run_white_factors`).
    dark
        :math:`d_{x,t_\\lambda}`, dark values for these exposures (broadcastable to ``values``).
    drift
        :math:`F_{i,long}` of this direction pair (:func:`drift_factors`).
    inverse_response
        :math:`\\hat f^{-1}`.

    Returns
    -------
    numpy.ndarray
        ``(K, ...)`` BRDF values.
    """
    values = np.asarray(values, dtype=np.float64)
    bands = values.shape[0] if values.ndim else 0
    values = _band_images("values", values, bands)
    exposure = _band_vector("exposure_s", exposure_s, bands)
    factors = _band_vector("run_factors", run_factors, bands)
    if not (np.isfinite(drift) and drift > 0):
        raise InputError(f"drift: expected a positive factor, got {drift}")
    scale = (factors * drift / exposure).reshape((bands,) + (1,) * (values.ndim - 1))
    return scale * inverse_response(values - dark)
