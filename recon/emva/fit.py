r"""The camera model's parameters fitted to an EMVA 1288 measurement.

The ``emva1288`` package's figures (:mod:`recon.emva.analysis`) describe a camera in EMVA 1288's
terms; the twin simulates a camera from physical parameters (:mod:`recon.emva.linear_model`,
``twin.sensor.model``). :func:`fit_sensor` finds the parameters whose simulated measurement,
analysed by the same estimators, gives the measured figures. The frames are quantized; where the
temporal noise is below about a DN the quantizer does not average out, and the estimators see
what :mod:`recon.emva.quantization` predicts rather than the signals themselves (an 8-bit camera
with little dark noise is the common case). So:

- offset spread (DSNU) and offset :math:`\mu_{offset}`: the dark pixels' spread and mean before
  quantization whose quantized spatial dark step gives the measured mean, spatial variance and
  temporal variance (:func:`recon.emva.quantization.unquantized_spread`); the offset is the dark
  mean extrapolated to zero exposure time less the bias quantization gives it. One spatial
  exposure time cannot separate offset and dark-current non-uniformity: the spread is all offset;
- OECF knee :math:`s` and responsivity :math:`A = K \eta` (DN per photon): least squares of the
  model's mean signal :math:`top\,[g((A \mu_p + c t)/top) - g(c t / top)]` against the measured
  :math:`\mu_y - \mu_{y.dark}` over the linearity range (5-95 % of saturation), relative
  residuals, :math:`s \ge 0` (a linear camera gives :math:`s = 0`), with the dark signal rate
  :math:`c = K \mu_I` from the slope of the dark mean divided by :math:`g'(0) = 1 + s`;
- read noise :math:`\sigma_r`: the one whose quantized dark steps, extrapolated to zero exposure
  time as EMVA 1288 does, give the measured temporal dark variance before the package's floor of
  0.24 DN^2 (:math:`\sqrt{\sigma^2_{y.dark} - 1/12} / (1 + s)` where the noise dithers);
- PRNU: the bright pixels' spread before quantization at the spatial step, less the offsets',
  relative to the signal: EMVA 1288's :math:`PRNU_{1288}` of unquantized spatial variances,
  times :math:`1 + s u` at the step's normalized signal :math:`u` (the knee compresses relative
  differences by :math:`u g'(u) / g(u)`); 0 where the measurement resolves none;
- system gain :math:`K`: the knee bends the photon transfer (noise passes through
  :math:`g'`) and quantization changes the variances of the darkest steps, so the gain is the one
  for which the package, run on the model's predicted means and quantized variances, finds the
  measured :math:`K` (fixed-point iteration); then :math:`\eta = A / K` and the dark current
  :math:`\mu_I = c / K`;
- saturation: EMVA 1288 places it at the maximum of the temporal variance. The full well is the
  clip whose predicted variance peak (:func:`recon.emva.linear_model.predicted_saturation_e`)
  lies at the measured saturation step; where the ADC's top alone puts the peak there or later,
  the ADC clips first and the full well, hidden, is placed five shot-noise widths above it, the
  least that leaves every measured frame unchanged.

References
----------
- EMVA Standard 1288, Release 3.1 (2016) and Release 4.0 Linear (2021): the linear model and
  its figures; section 2.5 (saturation: the maximum of the variance), section 4.1 (spatial
  variances, DSNU, PRNU), Appendix C.4 (quantization noise and the limit of the temporal noise).
- The thesis, Eq. 3.1 (the OECF :math:`f` of :math:`p = f(tI) + d`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np
from scipy import optimize

from recon.emva.analysis import (
    EMVAAnalysis,
    PhotonTransfer,
    dark_at_zero_exposure,
    run_results1288,
)
from recon.emva.linear_model import knee_oecf, knee_oecf_slope, predicted_saturation_e
from recon.emva.quantization import quantized_temporal_variance, unquantized_spread
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


@dataclass(frozen=True)
class _Model:
    """The camera model as the fit builds it up: DN per electron and per photon, the knee, the
    linear dark signal rate (DN/s at :math:`g'(0) = 1`), read noise, offset and its spread (DN),
    the ADC's range above the offset (DN), the relative PRNU and the ADC's largest value."""

    gain: float
    responsivity: float
    knee: float
    dark_rate: float
    read_dn: float
    offset: float
    top: float
    offset_sigma: float
    prnu: float
    max_dn: int

    def temporal(self, transfer: PhotonTransfer) -> dict[str, Any]:
        """Means and temporal variances of the digital values at every step of ``transfer``,
        quantized (:mod:`recon.emva.quantization`), in the package's ``Data1288`` layout."""
        dark_dn = self.dark_rate / (1 + self.knee) * transfer.exposure_s
        bright_mean, bright_variance = self._digital(self.responsivity * transfer.photons + dark_dn)
        dark_mean, dark_variance = self._digital(dark_dn)
        return {
            "texp": transfer.exposure_s * 1e9,
            "u_p": transfer.photons,
            "u_y": bright_mean,
            "s2_y": bright_variance,
            "u_ydark": dark_mean,
            "s2_ydark": dark_variance,
        }

    def saturation_e(self, full_well_e: float) -> float:
        """The charge at which the variance of this model with ``full_well_e`` peaks (EMVA
        1288's saturation; :func:`recon.emva.linear_model.predicted_saturation_e`)."""
        return predicted_saturation_e(
            full_well_e,
            gain_dn_per_e=self.gain,
            read_noise_dn=self.read_dn,
            prnu=self.prnu,
            adc_top_dn=self.top,
        )

    def _digital(self, linear_dn: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Mean and temporal variance of the digital value of a linear signal above the offset:
        shot and read noise through the knee's slope (EMVA 1288's linear model), quantized."""
        signal = knee_oecf(linear_dn, self.top, self.knee)
        noise = knee_oecf_slope(linear_dn, self.top, self.knee) * np.sqrt(
            self.gain * linear_dn + self.read_dn**2
        )
        spread = np.hypot(self.offset_sigma, self.prnu * signal)
        mean = self.offset + signal
        return mean, quantized_temporal_variance(mean, spread, noise, max_dn=self.max_dn)


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


def _dark_spread(analysis: EMVAAnalysis, max_dn: int) -> tuple[float, float]:
    """The bias quantization gives the dark mean and the offsets' spread before quantization
    (DN), from the spatial dark step: its mean, spatial and temporal variance."""
    mean, spread, _ = unquantized_spread(analysis.spatial_dark, max_dn=max_dn)
    return analysis.spatial_dark.mean_dn - mean, spread


def _read_noise(analysis: EMVAAnalysis, model: _Model) -> float:
    """The read noise whose quantized dark steps, extrapolated to zero exposure time, give the
    measured temporal dark variance (before the package's floor)."""
    transfer, measured = analysis.transfer, analysis.dark_temporal_variance_dn2

    def residual(read_dn: np.ndarray) -> np.ndarray:
        predicted = replace(model, read_dn=float(read_dn[0])).temporal(transfer)
        return np.array(
            [dark_at_zero_exposure(predicted["texp"], predicted["s2_ydark"]) - measured]
        )

    start = math.sqrt(max(measured - 1 / 12, 1e-6)) / (1 + model.knee)
    return float(optimize.least_squares(residual, [start], bounds=(0.0, np.inf)).x[0])


def _prnu(analysis: EMVAAnalysis, model: _Model, spatial_u: float) -> float:
    """The relative spread of the photo response: the bright pixels' spread before quantization
    at the spatial step less the offsets', relative to the signal and widened by the knee's
    compression :math:`1 + s u` (0 where the measurement resolves none)."""
    _, bright_spread, _ = unquantized_spread(analysis.spatial_bright, max_dn=model.max_dn)
    photo_response_dn2 = bright_spread**2 - model.offset_sigma**2
    if photo_response_dn2 <= 0 or not analysis.spatial_signal_dn > 0:
        return 0.0
    return math.sqrt(photo_response_dn2) / analysis.spatial_signal_dn * (1 + model.knee * spatial_u)


def _gain(analysis: EMVAAnalysis, model: _Model) -> float:
    """The system gain for which the package finds the measured K in the model's predicted
    photon transfer (fixed-point iteration)."""
    transfer = analysis.transfer
    gain = analysis.system_gain_dn_per_e
    for _ in range(20):
        predicted = replace(model, gain=gain).temporal(transfer)
        results = run_results1288(
            {"temporal": predicted, "spatial": {}}, saturation_index=transfer.saturation_index
        )
        correction = analysis.system_gain_dn_per_e / float(results.K)
        gain *= correction
        if abs(correction - 1) < 1e-7:
            break
    return gain


def _seen_until(step_e: np.ndarray, saturation_e: float) -> float:
    """The charge halfway between the first and the second step above the saturation step
    (infinite near the last step): a variance peak below it is seen at the saturation step or
    one step later. The variance curve is flat at its top, so of two steps that straddle the
    peak either may measure the larger variance: on reference set 002's plan, an 8-bit twin
    camera whose ADC clips first (peak predicted at about 7175 e-, between steps at about 7045
    and 7165 e-) measured its peak at the lower step for 3 of 9 serials' fixed patterns."""
    above = np.sort(step_e[step_e > saturation_e])
    return (above[0] + above[1]) / 2 if above.size > 1 else math.inf


def _saturation(
    model: _Model, step_e: np.ndarray, saturation_e: float, source: object
) -> tuple[float, Literal["ADC", "full well"]]:
    """The full well that puts the model's variance peak (EMVA 1288's saturation) at the
    measured saturation step, and what clips first.

    With a full well beyond the ADC's top the peak lies at
    :func:`recon.emva.linear_model.predicted_saturation_e` of an unlimited full well. Where that
    is seen at the measured step or the next (:func:`_seen_until`), the ADC clips first: the full
    well is hidden and placed five shot-noise widths above the ADC's top. Where the measured
    peak comes earlier still, the full well clips first, at the charge whose peak lies at the
    measured saturation (whether the mean reaches the ADC's top does not decide it: a plan may
    end at saturation).
    """

    top_e = model.top / model.gain
    if saturation_e >= top_e or model.saturation_e(math.inf) <= _seen_until(step_e, saturation_e):
        return top_e + _FULL_WELL_MARGIN_SIGMAS * math.sqrt(top_e), "ADC"
    try:
        full_well = optimize.brentq(
            lambda full_well_e: model.saturation_e(full_well_e) - saturation_e,
            saturation_e,
            top_e,
            xtol=1e-3,
        )
    except ValueError as error:
        raise InputError(
            f"{source}: no full well puts the variance peak at the measured saturation "
            f"({saturation_e:.0f} e-); expected a measurement that saturates at its full well "
            "or at the ADC's top"
        ) from error
    return full_well, "full well"


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
    bias, offset_sigma = _dark_spread(analysis, max_dn)
    offset = analysis.dark_offset_dn - bias
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
    model = _Model(
        gain=analysis.system_gain_dn_per_e,
        responsivity=responsivity,
        knee=knee,
        dark_rate=dark_rate,
        read_dn=0.0,
        offset=offset,
        top=top,
        offset_sigma=offset_sigma,
        prnu=0.0,
        max_dn=max_dn,
    )
    model = replace(model, read_dn=_read_noise(analysis, model))
    spatial_u = responsivity * analysis.spatial_photons / top
    model = replace(model, prnu=_prnu(analysis, model, spatial_u))
    model = replace(model, gain=_gain(analysis, model))
    eta = responsivity / model.gain
    dark_current = dark_rate / (1 + knee) / model.gain
    step_e = eta * transfer.photons + dark_current * transfer.exposure_s
    full_well, saturated_by = _saturation(
        model, step_e, float(step_e[transfer.saturation_index]), descriptor.path
    )
    return FittedSensor(
        analysis=analysis,
        wavelength_nm=float(wavelength_nm),
        system_gain_dn_per_e=float(model.gain),
        quantum_efficiency=float(eta),
        read_noise_dn=float(model.read_dn),
        adc_offset_dn=float(offset),
        full_well_e=float(full_well),
        saturated_by=saturated_by,
        dark_current_e_per_s=float(dark_current),
        offset_sigma_dn=float(offset_sigma),
        prnu=float(model.prnu),
        knee_strength=float(knee),
        knee_rms_percent=knee_rms,
        straight_line_rms_percent=straight_rms,
    )
