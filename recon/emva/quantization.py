"""What EMVA 1288's estimators measure on quantized frames of a population of pixels.

EMVA 1288's linear model adds the quantization noise :math:`\\sigma_q^2 = 1/12` DN^2 to the
temporal variance; that holds once the temporal noise dithers the quantizer, above about half a
DN (the standard's lower limit of 0.49 DN for the temporal dark noise, which the ``emva1288``
package applies as a floor of 0.24 DN^2). Below it, the quantizer does not average out:

- the temporal variance of a pixel depends on where its mean lies between two digital values;
- the average of :math:`L` frames converges to the expected *quantized* value
  :math:`m(x) = E[\\mathrm{round}(x + n)]`, not to the pixel's signal :math:`x`. The spatial
  variance of the average after the temporal part is removed (the emva1288 package's Eq. (36),
  :math:`s_y^2 = s_{y.measured}^2 - \\sigma_{y.stack}^2 / L`) is the spatial variance of
  :math:`m(x)`, which can be smaller or larger than that of :math:`x`. DSNU and PRNU, which
  EMVA 1288 computes from these spatial variances, inherit the difference.

:func:`quantized_moments` gives the three figures the estimators converge to for pixels whose
signals :math:`x` are normal across the sensor, :math:`N(\\mu, s^2)`, with normal temporal noise
:math:`N(0, \\sigma^2)`, rounded and clipped to the ADC's range: the mean, the spatial variance of
:math:`m(x)` and the mean temporal variance. :func:`unquantized_spread` inverts it: the
:math:`(\\mu, s, \\sigma)` before quantization that give measured figures.

References
----------
- EMVA Standard 1288, Release 3.1 (2016): section 2.3 (noise model, quantization noise),
  section 4.1 (spatial variances, DSNU, PRNU), Appendix C.4 (limit for the minimal temporal
  standard deviation; introduction of quantization noise).
- The ``emva1288`` package, version 1.0 (EMVA1288/emva1288 on GitHub): ``Results1288.s_2_y``
  (Eq. (36)) and ``Results1288.sigma_y_dark`` (the 0.24 DN^2 floor).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import optimize, special

__all__ = [
    "QuantizedMoments",
    "quantized_moments",
    "quantized_temporal_variance",
    "unquantized_spread",
]

_SPAN_SIGMAS = 7.0  # the pixel population's normal, integrated over +-7 standard deviations
_NOISE_SIGMAS = 8.0  # digital values further than this from a pixel's signal do not occur
_MIN_NOISE_DN = 1e-3  # a temporal noise below this is a step function on any grid
_MAX_NODES = 200_001
_DITHERED_DN = 1.0  # from this temporal noise on, quantization adds 1/12 DN^2 (to 3e-9 of it)


@dataclass(frozen=True)
class QuantizedMoments:
    """EMVA 1288's estimates on quantized frames: the mean (DN), the spatial variance after the
    temporal part is removed (DN^2) and the mean temporal variance of a pixel (DN^2)."""

    mean_dn: float
    spatial_variance_dn2: float
    temporal_variance_dn2: float


def _population(
    mean_dn: float, spatial_sigma_dn: float, noise_dn: float
) -> tuple[np.ndarray, np.ndarray]:
    """Signals and weights of the pixel population, on a grid fine against the noise."""
    if spatial_sigma_dn <= 0:
        return np.array([mean_dn]), np.array([1.0])
    step = min(noise_dn, spatial_sigma_dn, 1.0) / 4
    nodes = int(np.clip(math.ceil(2 * _SPAN_SIGMAS * spatial_sigma_dn / step), 65, _MAX_NODES))
    t = np.linspace(-_SPAN_SIGMAS, _SPAN_SIGMAS, nodes)
    weights = np.exp(-0.5 * t * t)
    return mean_dn + spatial_sigma_dn * t, weights / weights.sum()


def _dithered(mean_dn: float, spatial_sigma_dn: float, noise_dn: float, max_dn: int) -> bool:
    """Noise that dithers the quantizer, on pixels clear of the ADC's ends: there EMVA 1288's
    linear model holds (:math:`\\mu`, :math:`s^2`, :math:`\\sigma^2 + 1/12`) to 3e-9 of 1/12."""
    reach = _SPAN_SIGMAS * spatial_sigma_dn + _NOISE_SIGMAS * noise_dn
    return noise_dn >= _DITHERED_DN and 0 <= mean_dn - reach and mean_dn + reach <= max_dn


def quantized_moments(
    mean_dn: float, spatial_sigma_dn: float, temporal_sigma_dn: float, *, max_dn: int
) -> QuantizedMoments:
    """The figures EMVA 1288's estimators converge to on pixels quantized to ``[0, max_dn]``.

    Parameters
    ----------
    mean_dn, spatial_sigma_dn
        Mean and spatial standard deviation of the pixels' signals before quantization (DN).
    temporal_sigma_dn
        Standard deviation of the temporal noise before quantization (DN).
    max_dn
        The ADC's largest value, :math:`2^n - 1`.

    Returns
    -------
    QuantizedMoments
        With :math:`m(x)` and :math:`v(x)` the mean and variance of a pixel's digital value:
        the mean of :math:`m`, the spatial variance of :math:`m` and the mean of :math:`v` over
        the population. Far above the quantization limit these are :math:`\\mu`, :math:`s^2`
        and :math:`\\sigma^2 + 1/12`.

    Examples
    --------
    >>> moments = quantized_moments(100.3, 5.0, 2.0, max_dn=4095)
    >>> round(moments.spatial_variance_dn2, 3), round(moments.temporal_variance_dn2, 3)
    (25.0, 4.083)
    >>> round(quantized_moments(8.0, 0.3, 0.15, max_dn=255).spatial_variance_dn2, 3)
    0.071
    """
    noise = max(temporal_sigma_dn, _MIN_NOISE_DN)
    if _dithered(mean_dn, spatial_sigma_dn, noise, max_dn):
        return QuantizedMoments(float(mean_dn), float(spatial_sigma_dn) ** 2, noise**2 + 1 / 12)
    signal, weights = _population(mean_dn, spatial_sigma_dn, noise)
    # A digital value y is the count of the levels j below it: y = sum_j [y > j], so
    # E[y] = sum_j P(y > j) and E[y^2] = sum_j (2j + 1) P(y > j), over the few levels j
    # within reach of the noise (every level below them counts fully).
    first = np.clip(np.floor(signal - _NOISE_SIGMAS * noise), 0, max_dn)
    levels = first[:, None] + np.arange(math.ceil(2 * _NOISE_SIGMAS * noise) + 2)
    above = special.ndtr((signal[:, None] - levels - 0.5) / noise)
    above[levels > max_dn - 1] = 0.0
    pixel_mean = first + above.sum(axis=1)
    pixel_square = first**2 + ((2 * levels + 1) * above).sum(axis=1)
    mean = float(weights @ pixel_mean)
    return QuantizedMoments(
        mean_dn=mean,
        spatial_variance_dn2=float(weights @ pixel_mean**2 - mean**2),
        temporal_variance_dn2=float(weights @ (pixel_square - pixel_mean**2)),
    )


def quantized_temporal_variance(
    mean_dn: np.ndarray,
    spatial_sigma_dn: np.ndarray,
    temporal_sigma_dn: np.ndarray,
    *,
    max_dn: int,
) -> np.ndarray:
    """The mean temporal variance of quantized pixels, element by element (DN^2): the
    ``temporal_variance_dn2`` of :func:`quantized_moments`.

    Examples
    --------
    >>> quantized_temporal_variance(
    ...     np.array([8.0, 500.0]), np.array([0.3, 3.0]), np.array([0.15, 2.0]), max_dn=4095
    ... ).round(4).tolist()
    [0.0648, 4.0833]
    """
    arrays = np.broadcast_arrays(
        np.asarray(mean_dn, float),
        np.asarray(spatial_sigma_dn, float),
        np.asarray(temporal_sigma_dn, float),
    )
    variance = np.empty(arrays[0].shape)
    for index in np.ndindex(variance.shape):
        moments = quantized_moments(*(float(array[index]) for array in arrays), max_dn=max_dn)
        variance[index] = moments.temporal_variance_dn2
    return variance


def unquantized_spread(measured: QuantizedMoments, *, max_dn: int) -> tuple[float, float, float]:
    """The pixels' mean, spatial and temporal standard deviation before quantization.

    Inverts :func:`quantized_moments` by least squares on the mean and the two standard
    deviations, starting from EMVA 1288's linear model (spatial variance as measured, temporal
    variance less 1/12). A negative measured spatial variance (a spread the measurement does not
    resolve) is taken as none.

    Parameters
    ----------
    measured
        The measured figures.
    max_dn
        The ADC's largest value.

    Returns
    -------
    tuple of float
        ``(mean_dn, spatial_sigma_dn, temporal_sigma_dn)``.

    Examples
    --------
    >>> figures = quantized_moments(8.0, 0.3, 0.15, max_dn=255)
    >>> [round(value, 3) for value in unquantized_spread(figures, max_dn=255)]
    [8.0, 0.3, 0.15]
    """
    spatial = math.sqrt(max(measured.spatial_variance_dn2, 0.0))
    temporal = math.sqrt(max(measured.temporal_variance_dn2, 0.0))
    target = np.array([measured.mean_dn, spatial, temporal])

    def residuals(parameters: np.ndarray) -> np.ndarray:
        moments = quantized_moments(*parameters, max_dn=max_dn)
        return (
            np.array(
                [
                    moments.mean_dn,
                    math.sqrt(max(moments.spatial_variance_dn2, 0.0)),
                    math.sqrt(max(moments.temporal_variance_dn2, 0.0)),
                ]
            )
            - target
        )

    start = np.array(
        [measured.mean_dn, spatial, math.sqrt(max(temporal**2 - 1 / 12, _MIN_NOISE_DN**2))]
    )
    solution = optimize.least_squares(
        residuals, start, bounds=([-np.inf, 0.0, 0.0], np.inf), x_scale=[1.0, 0.1, 0.1]
    )
    mean, spatial_sigma, temporal_sigma = (float(value) for value in solution.x)
    return mean, spatial_sigma, temporal_sigma
