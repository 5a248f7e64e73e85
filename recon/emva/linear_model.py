"""The camera model of EMVA 1288 with the twin's OECF knee, as closed forms.

The twin's sensor (``twin.sensor.model``) and the fit of a camera to a real measurement
(:mod:`recon.emva.fit`) share these formulas, so the fitted parameters mean what the twin
simulates:

- the linear model, EMVA 1288 Eq. (5)-(6): mean electrons :math:`\\mu_e = \\eta \\mu_p +
  \\mu_{e.dark}`, signal :math:`K \\mu_e` in DN above the offset, temporal variance
  :math:`K^2 \\mu_e + \\sigma_r^2 + \\sigma_q^2` (read noise :math:`\\sigma_r` in DN,
  quantization :math:`\\sigma_q^2 = 1/12` DN^2);
- the OECF (thesis Eq. 3.1's :math:`f`): ``linear``, or a knee
  :math:`g(u) = (1 + s) u / (1 + s u)` on the signal normalized to the ADC's range above the
  offset, :math:`u = K \\mu_e / (2^n - 1 - \\mu_{offset})`; :math:`g(1) = 1`, so the ADC's top
  is reached at the same charge with or without the knee. Noise passes through its slope
  :math:`g'(u) = (1 + s) / (1 + s u)^2`;
- saturation: EMVA 1288 places it at the peak of the temporal variance, which for a signal
  clipped at a full well (or at the ADC's top) lies a few noise widths below the clip.

References
----------
- EMVA Standard 1288, Release 3.0 (2010) and Release 4.0 Linear (2021), European Machine Vision
  Association: the linear camera model, Eq. (5)-(9); saturation as the maximum of the variance.
- The thesis, Eq. 3.1 (:math:`p = f(tI) + d`).
"""

from __future__ import annotations

import numpy as np
from scipy import stats

__all__ = [
    "QUANTIZATION_VARIANCE_DN2",
    "clipped_normal_variance",
    "knee_oecf",
    "knee_oecf_slope",
    "predicted_saturation_e",
]

QUANTIZATION_VARIANCE_DN2 = 1.0 / 12.0


def knee_oecf(linear_dn: np.ndarray, top_dn: float, strength: float) -> np.ndarray:
    """The knee OECF :math:`top \\cdot g(x / top)` of a linear signal above the offset, in DN.

    Below zero (negative read noise in the dark) the curve continues with its slope at zero, so
    dark frames stay unbiased (thesis Fig. 10.3: negative dark-subtracted values occur).
    """
    normalized = np.asarray(linear_dn) / top_dn
    return top_dn * (1 + strength) * normalized / (1 + strength * np.maximum(normalized, 0))


def knee_oecf_slope(linear_dn: np.ndarray, top_dn: float, strength: float) -> np.ndarray:
    """:math:`g'(x / top)`, the factor by which the knee scales noise at signal ``linear_dn``."""
    normalized = np.maximum(np.asarray(linear_dn) / top_dn, 0)
    return (1 + strength) / (1 + strength * normalized) ** 2


def clipped_normal_variance(mean: np.ndarray, sigma: np.ndarray, clip: float) -> np.ndarray:
    r"""Variance of :math:`\min(X, c)` for :math:`X \sim N(m, s^2)` (censored moments)."""
    alpha = (clip - mean) / sigma
    below, density = stats.norm.cdf(alpha), stats.norm.pdf(alpha)
    first = mean * below - sigma * density + clip * (1 - below)
    second = (mean**2 + sigma**2) * below - sigma * (mean + clip) * density + clip**2 * (1 - below)
    return second - first**2


def predicted_saturation_e(
    full_well_e: float,
    *,
    gain_dn_per_e: float,
    read_noise_dn: float,
    prnu: float,
    adc_top_dn: float,
) -> float:
    """Saturation capacity by the EMVA 1288 definition (the variance's peak) of a linear camera.

    The expected variance is that of a Gaussian clipped at the full well (before read noise)
    or at the ADC's top (after it), whichever the charge reaches first, averaged over the PRNU
    spread; its maximum is found on a fine grid of mean photo-electrons.

    Parameters
    ----------
    full_well_e
        Charge at which a pixel clips, e-.
    gain_dn_per_e, read_noise_dn
        System gain :math:`K` and read noise :math:`\\sigma_r` (DN).
    prnu
        Relative standard deviation of the photo response across pixels.
    adc_top_dn
        The ADC's range above the offset, :math:`2^n - 1 - \\mu_{offset}`, in DN.

    Returns
    -------
    float
        The mean photo-electrons at which the temporal variance peaks.
    """
    nodes, weights = np.polynomial.hermite_e.hermegauss(48)
    weights = weights / weights.sum()
    clip_e = min(full_well_e, adc_top_dn / gain_dn_per_e)
    means_e = np.linspace(0.8, 1.05, 5001)[:, None] * clip_e
    pixel_means_e = means_e * (1 + prnu * nodes)
    if full_well_e <= adc_top_dn / gain_dn_per_e:
        shot_dn2 = gain_dn_per_e**2 * clipped_normal_variance(
            pixel_means_e, np.sqrt(pixel_means_e), full_well_e
        )
        variance = shot_dn2 + read_noise_dn**2
    else:
        variance = clipped_normal_variance(
            gain_dn_per_e * pixel_means_e,
            np.sqrt(gain_dn_per_e**2 * pixel_means_e + read_noise_dn**2),
            adc_top_dn,
        )
    return float(means_e[np.argmax(variance @ weights), 0])
