"""The camera model's parameters fitted to an EMVA 1288 measurement.

The ``emva1288`` package's figures (:mod:`recon.emva.analysis`) describe a camera in EMVA 1288's
terms; the twin simulates a camera from physical parameters (:mod:`recon.emva.linear_model`,
``twin.sensor.model``). :func:`fit_sensor` finds the parameters whose simulated measurement,
analysed by the same package, gives the measured figures:

- offset :math:`\\mu_{offset}`: the dark mean extrapolated to zero exposure time;
- OECF knee :math:`s` and responsivity :math:`A = K \\eta` (DN per photon): least squares of the
  model's mean signal :math:`top\\,[g((A \\mu_p + c t)/top) - g(c t / top)]` against the measured
  :math:`\\mu_y - \\mu_{y.dark}` over the linearity range (5-95 % of saturation), relative
  residuals, :math:`s \\ge 0` (a linear camera gives :math:`s = 0`), with the dark signal rate
  :math:`c = K \\mu_I` from the slope of the dark mean divided by :math:`g'(0) = 1 + s`;
- system gain :math:`K`: the knee bends the photon transfer (noise passes through
  :math:`g'`), so the gain is the one for which the package, run on the model's predicted means
  and variances, finds the measured :math:`K` (fixed-point iteration; without a knee it is the
  measured :math:`K`); then :math:`\\eta = A / K` and the dark current :math:`\\mu_I = c / K`;
- read noise :math:`\\sigma_r = \\sqrt{\\sigma^2_{y.dark} - 1/12} / (1 + s)`;
- PRNU :math:`\\sigma_{PRNU} = PRNU_{1288} (1 + s u)` at the spatial step's normalized signal
  :math:`u` (the knee compresses relative differences by :math:`u g'(u) / g(u)`);
- DSNU: the package's :math:`DSNU_{1288}` in DN as a per-pixel offset spread (one spatial
  exposure time cannot separate offset and dark-current non-uniformity; a DSNU the package
  cannot compute, a negative variance, is 0);
- saturation: when the brightest steps reach the ADC's top, the ADC clips first and the full well
  is hidden; it is placed five shot-noise widths above the ADC's top, the least that leaves every
  measured frame unchanged. Otherwise the full well is the clip whose variance peak
  (:func:`recon.emva.linear_model.predicted_saturation_e`) lies at the measured saturation.

References
----------
- EMVA Standard 1288, Release 3.0 (2010): the linear model and its figures.
- The thesis, Eq. 3.1 (the OECF :math:`f` of :math:`p = f(tI) + d`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from scipy import optimize

from recon.emva.analysis import EMVAAnalysis, PhotonTransfer, run_results1288
from recon.emva.linear_model import (
    QUANTIZATION_VARIANCE_DN2,
    knee_oecf,
    knee_oecf_slope,
    predicted_saturation_e,
)
from recon.errors import InputError

__all__ = ["FittedSensor", "fit_sensor"]

_FULL_WELL_MARGIN_SIGMAS = 5.0


@dataclass(frozen=True, eq=False)
class FittedSensor:
    """A camera's model parameters fitted to its EMVA 1288 measurement (see the module)."""

    analysis: EMVAAnalysis
    wavelength_nm: float
    system_gain_dn_per_e: float
    quantum_efficiency: float
    read_noise_dn: float
    adc_offset_dn: float
    full_well_e: float
    saturated_by: Literal["ADC", "full well"]
    dark_current_e_per_s: float
    offset_sigma_dn: float
    prnu: float
    knee_strength: float
    knee_rms_percent: float
    straight_line_rms_percent: float

    @property
    def bit_depth(self) -> int:
        return self.analysis.descriptor.bit_depth

    @property
    def size_px(self) -> tuple[int, int]:
        """``(width, height)`` of the measured frames."""
        return self.analysis.descriptor.width, self.analysis.descriptor.height

    @property
    def exposure_range_s(self) -> tuple[float, float]:
        return self.analysis.descriptor.exposure_range_s

    def parameters(self) -> dict[str, object]:
        """The fitted parameters, keys with their unit."""
        return {
            "system_gain_dn_per_e": self.system_gain_dn_per_e,
            "quantum_efficiency_percent": 100 * self.quantum_efficiency,
            "wavelength_nm": self.wavelength_nm,
            "read_noise_dn": self.read_noise_dn,
            "adc_offset_dn": self.adc_offset_dn,
            "full_well_e": self.full_well_e,
            "saturated_by": self.saturated_by,
            "dark_current_e_per_s": self.dark_current_e_per_s,
            "offset_sigma_dn": self.offset_sigma_dn,
            "prnu_percent": 100 * self.prnu,
            "knee_strength": self.knee_strength,
            "knee_rms_percent": self.knee_rms_percent,
            "straight_line_rms_percent": self.straight_line_rms_percent,
            "bit_depth": self.bit_depth,
        }


def _mean_above_dark(
    params: np.ndarray, photons: np.ndarray, exposure_s: np.ndarray, dark_rate: float, top: float
) -> np.ndarray:
    """Model of :math:`\\mu_y - \\mu_{y.dark}`: ``params`` = (A DN/photon, knee s); the linear
    dark signal rate ``dark_rate`` (DN/s at g'(0) = 1) is divided by 1 + s."""
    responsivity, knee = params
    dark_dn = dark_rate / (1 + knee) * exposure_s
    return knee_oecf(responsivity * photons + dark_dn, top, knee) - knee_oecf(dark_dn, top, knee)


def _predicted_temporal(
    transfer: PhotonTransfer,
    *,
    gain: float,
    responsivity: float,
    knee: float,
    dark_rate: float,
    read_dn: float,
    offset: float,
    top: float,
) -> dict[str, Any]:
    """Means and variances the model predicts for every step, in the package's layout."""
    dark_dn = dark_rate / (1 + knee) * transfer.exposure_s
    bright_dn = responsivity * transfer.photons + dark_dn

    def variance(linear_dn: np.ndarray) -> np.ndarray:
        slope = knee_oecf_slope(linear_dn, top, knee)
        return slope**2 * (gain * linear_dn + read_dn**2) + QUANTIZATION_VARIANCE_DN2

    return {
        "texp": transfer.exposure_s * 1e9,
        "u_p": transfer.photons,
        "u_y": offset + knee_oecf(bright_dn, top, knee),
        "s2_y": variance(bright_dn),
        "u_ydark": offset + knee_oecf(dark_dn, top, knee),
        "s2_ydark": variance(dark_dn),
    }


def _fit_knee(
    analysis: EMVAAnalysis, dark_rate: float, top: float
) -> tuple[np.ndarray, float, float]:
    """(A, s) and the rms relative residuals (%) of the knee and of a straight line."""
    transfer = analysis.transfer
    first, last = transfer.linearity_range
    chosen = slice(first, last + 1)
    photons, exposure_s = transfer.photons[chosen], transfer.exposure_s[chosen]
    signal = transfer.signal_dn[chosen]
    if signal.size < 3 or np.any(signal <= 0):
        raise InputError(
            f"{analysis.descriptor.path}: {signal.size} steps in the linearity range, or a "
            "signal not above the dark level; expected at least 3 steps between 5 and 95 % of "
            "saturation"
        )

    def residuals(params: np.ndarray) -> np.ndarray:
        return _mean_above_dark(params, photons, exposure_s, dark_rate, top) / signal - 1

    start = np.array([analysis.responsivity_dn_per_photon, 0.0])
    knee = optimize.least_squares(residuals, start, bounds=([0, 0], [np.inf, 10.0]))
    line = optimize.least_squares(lambda p: residuals(np.array([p[0], 0.0])), start[:1])
    return (
        knee.x,
        100 * math.sqrt(np.mean(knee.fun**2)),
        100 * math.sqrt(np.mean(line.fun**2)),
    )


def _gain(analysis: EMVAAnalysis, **model: float) -> float:
    """The system gain for which the package finds the measured K in the model's predicted
    photon transfer (fixed-point iteration; the measured K itself without a knee)."""
    transfer = analysis.transfer
    gain = analysis.system_gain_dn_per_e
    for _ in range(20):
        predicted = _predicted_temporal(transfer, gain=gain, **model)
        results = run_results1288(
            {"temporal": predicted, "spatial": {}}, saturation_index=transfer.saturation_index
        )
        correction = analysis.system_gain_dn_per_e / float(results.K)
        gain *= correction
        if abs(correction - 1) < 1e-7:
            break
    return gain


def _full_well(
    saturation_e: float, *, gain: float, read_dn: float, prnu: float, top: float, source: object
) -> float:
    """The full well whose variance peak lies at the measured saturation (charge, e-)."""

    def peak_offset(full_well_e: float) -> float:
        peak = predicted_saturation_e(
            full_well_e, gain_dn_per_e=gain, read_noise_dn=read_dn, prnu=prnu, adc_top_dn=top
        )
        return peak - saturation_e

    try:
        return optimize.brentq(peak_offset, saturation_e, 1.5 * saturation_e, xtol=1e-3)
    except ValueError as error:
        raise InputError(
            f"{source}: no full well puts the variance peak at the measured saturation "
            f"({saturation_e:.0f} e-); expected a measurement that saturates at its full well "
            "or at the ADC's top"
        ) from error


def fit_sensor(analysis: EMVAAnalysis, *, wavelength_nm: float) -> FittedSensor:
    """Fit the camera model's parameters to an EMVA 1288 measurement.

    Parameters
    ----------
    analysis
        The ``emva1288`` analysis of the measurement
        (:func:`recon.emva.analysis.analyse_measurement`).
    wavelength_nm
        The wavelength of the measurement's light, where the fitted quantum efficiency holds
        (EMVA 1288 measures at one wavelength; the descriptor does not record it).

    Returns
    -------
    FittedSensor
        The parameters (see the module for how each is found).

    Raises
    ------
    InputError
        A measurement without enough steps in the linearity range, or whose offset leaves no
        range for the signal.
    """
    if not (math.isfinite(wavelength_nm) and wavelength_nm > 0):
        raise InputError(f"wavelength_nm: expected a positive value, got {wavelength_nm}")
    descriptor, transfer = analysis.descriptor, analysis.transfer
    max_dn = 2**descriptor.bit_depth - 1
    offset = analysis.dark_offset_dn
    top = max_dn - offset
    if top <= 0:
        raise InputError(
            f"{descriptor.path}: dark offset {offset:.1f} DN at the ADC's top {max_dn}; expected "
            "dark frames below saturation"
        )
    dark_rate = max(analysis.dark_current_from_mean_e_per_s, 0.0) * analysis.system_gain_dn_per_e
    if not math.isfinite(dark_rate):
        dark_rate = 0.0  # a single exposure time: no dark current measured
    (responsivity, knee), knee_rms, straight_rms = _fit_knee(analysis, dark_rate, top)
    read_dn = math.sqrt(max(analysis.dark_noise_dn**2 - QUANTIZATION_VARIANCE_DN2, 0.0)) / (
        1 + knee
    )
    gain = _gain(
        analysis,
        responsivity=responsivity,
        knee=knee,
        dark_rate=dark_rate,
        read_dn=read_dn,
        offset=offset,
        top=top,
    )
    eta = responsivity / gain
    dark_current = dark_rate / (1 + knee) / gain
    spatial_u = (responsivity * analysis.spatial_photons) / top
    prnu = analysis.prnu_percent / 100 * (1 + knee * spatial_u)
    if not math.isfinite(prnu):
        prnu = 0.0
    offset_sigma = analysis.dsnu_dn if math.isfinite(analysis.dsnu_dn) else 0.0
    saturated_by: Literal["ADC", "full well"]
    if transfer.mean_dn.max() >= max_dn - 0.5:
        saturated_by = "ADC"
        top_e = top / gain
        full_well = top_e + _FULL_WELL_MARGIN_SIGMAS * math.sqrt(top_e)
    else:
        saturated_by = "full well"
        index = transfer.saturation_index
        full_well = _full_well(
            eta * transfer.photons[index] + dark_current * transfer.exposure_s[index],
            gain=gain,
            read_dn=read_dn,
            prnu=prnu,
            top=top,
            source=descriptor.path,
        )
    return FittedSensor(
        analysis=analysis,
        wavelength_nm=float(wavelength_nm),
        system_gain_dn_per_e=float(gain),
        quantum_efficiency=float(eta),
        read_noise_dn=float(read_dn),
        adc_offset_dn=float(offset),
        full_well_e=float(full_well),
        saturated_by=saturated_by,
        dark_current_e_per_s=float(dark_current),
        offset_sigma_dn=float(offset_sigma),
        prnu=float(prnu),
        knee_strength=float(knee),
        knee_rms_percent=knee_rms,
        straight_line_rms_percent=straight_rms,
    )
