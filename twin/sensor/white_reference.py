"""Signal of the white reference standard: the basis of band exposure times (thesis Eq. 3.3-3.4).

The Zenith Ultra-White standard faces the lamp at a known distance; its radiance
:math:`W(\\lambda) E(\\lambda) / \\pi` (Lambertian, Eq. 3.3) reaches the camera through the
optics. Because lamps are sums of fixed spectral parts with time-varying weights
(``twin.components.LightSource``), the mean signal is computed once per part, in photo-electrons per
second, and any exposure window is a weighted sum of those rates.
"""

from __future__ import annotations

import math

import numpy as np

from recon.errors import InputError
from recon.spectra import SampledSpectra
from twin.components.lamps import FINE_GRID, LightSource
from twin.components.targets import zenith_white_reflectance
from twin.sensor.model import Sensor

__all__ = ["equalized_exposures_s", "white_reference_rates"]


def white_reference_rates(
    sensor: Sensor,
    lamp: LightSource,
    bands: SampledSpectra | None = None,
    *,
    distance_m: float,
) -> np.ndarray:
    """Photo-electrons per second of each lamp part and channel, ``(n_parts, n_channels)``.

    ``bands`` are filter transmissions on ``FINE_GRID`` (LCTF bands for the monochrome camera),
    or ``None`` for a colour camera's own R, G, B channels.
    """
    if not distance_m > 0:
        raise InputError(f"distance_m: expected a positive distance, got {distance_m}")
    reflectance = zenith_white_reflectance(FINE_GRID).values
    parts = lamp.spectral_parts(FINE_GRID)
    radiance = SampledSpectra(FINE_GRID, parts.values * reflectance / math.pi / distance_m**2)
    return sensor.mean_electrons(radiance, bands)


def equalized_exposures_s(
    sensor: Sensor,
    rates_e_per_s: np.ndarray,
    *,
    white_fill: float,
    round_to_s: float | None = None,
) -> np.ndarray:
    """Band exposure times that bring the white standard to ``white_fill`` of saturation (Eq. 3.4).

    :math:`t_\\lambda \\propto F_\\lambda / I_\\lambda`: the weaker the band's signal, the longer
    its exposure. With ``round_to_s`` (the HMI flicker period, thesis 3.3) times are rounded up to
    its multiples; all times are clipped to the camera's exposure range.
    """
    if not 0 < white_fill <= 1:
        raise InputError(f"white_fill: expected a fraction in (0, 1], got {white_fill}")
    rates = np.asarray(rates_e_per_s, dtype=np.float64)
    if np.any(rates <= 0):
        raise InputError("rates_e_per_s: expected positive signal rates in every band")
    exposures = white_fill * sensor.saturation_capacity_e / rates
    if round_to_s:
        exposures = np.ceil(exposures / round_to_s - 1e-9) * round_to_s
    low, high = sensor.config.exposure_range_s
    return np.clip(exposures, low, high)
