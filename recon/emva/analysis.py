"""The EMVA 1288 analysis of a measurement, by the ``emva1288`` package.

:func:`analyse_measurement` reads a descriptor and its images (checked by
:mod:`recon.emva.descriptor`) and runs the package's reference implementation of EMVA 1288
(``Data1288``, ``Results1288``): system gain :math:`K` from the photon transfer, responsivity and
quantum efficiency, temporal dark noise, saturation capacity, SNR, dark current from the mean
and from the variance of the dark signal, DSNU and PRNU from the spatial measurement, and the
linearity error. The result keeps the photon transfer data for figures and fits.

Saturation is the step of the largest temporal variance, EMVA 1288's definition, given to the
package (whose own search from the brightest step down stops at the first local maximum, on the
read-noise plateau of a camera clipped at its full well).

The spatial estimates come with their standard error: EMVA 1288 subtracts the temporal noise
left in the average of :math:`L` frames from the spatial variance, and the spatial variance of
that residual noise over :math:`MN` pixels scatters by
:math:`\\frac{\\sigma^2_{y.stack}}{L} \\sqrt{2 / (MN - 1)}`. A DSNU whose variance is below a
few such errors is not resolved by the measurement.

References
----------
- EMVA Standard 1288, Release 3.0 (2010): Eq. (9)-(11) (sensitivity, photon transfer), section
  7.2 (dark current), section 8 (spatial non-uniformity, Eq. (33)-(38)).
- The ``emva1288`` package, version 1.0 (EMVA1288/emva1288 on GitHub, LGPL-3.0).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, SupportsFloat

import numpy as np
from emva1288.process import Data1288, LoadImageData, ParseEmvaDescriptorFile, Results1288

from recon.emva._numpy2 import patch_emva1288
from recon.emva.descriptor import EMVADescriptor, read_descriptor, read_frame
from recon.emva.quantization import QuantizedMoments
from recon.errors import InputError

__all__ = [
    "EMVAAnalysis",
    "PhotonTransfer",
    "analyse_measurement",
    "dark_at_zero_exposure",
    "run_results1288",
]

_QUIET = logging.WARNING


@dataclass(frozen=True, eq=False)
class PhotonTransfer:
    """The temporal measurement, one entry per bright step sorted by exposure time (EMVA 1288
    Eq. (9)-(11)), and the index ranges the analysis used."""

    exposure_s: np.ndarray
    photons: np.ndarray
    mean_dn: np.ndarray
    variance_dn2: np.ndarray
    dark_mean_dn: np.ndarray
    dark_variance_dn2: np.ndarray
    saturation_index: int
    sensitivity_stop: int  # last index of the gain and responsivity fits (70 % of saturation)
    linearity_range: tuple[int, int]  # first and last index of the linearity fit (5-95 %)

    @property
    def signal_dn(self) -> np.ndarray:
        """:math:`\\mu_y - \\mu_{y.dark}`."""
        return self.mean_dn - self.dark_mean_dn

    @property
    def temporal_variance_dn2(self) -> np.ndarray:
        """:math:`\\sigma^2_y - \\sigma^2_{y.dark}`."""
        return self.variance_dn2 - self.dark_variance_dn2


@dataclass(frozen=True, eq=False)
class EMVAAnalysis:
    """The figures of an EMVA 1288 measurement, as the ``emva1288`` package computes them.

    Beside the figures, what a model of the camera must reproduce: the photon transfer data,
    the spatial steps' mean, spatial variance (the temporal part removed, the package's
    Eq. (36)) and mean temporal variance of their stacks of frames, and the temporal dark
    variance at zero exposure time before the package's floor of 0.24 DN^2
    (``dark_noise_dn`` is its square root after the floor).
    """

    descriptor: EMVADescriptor
    system_gain_dn_per_e: float
    responsivity_dn_per_photon: float
    quantum_efficiency: float
    dark_noise_dn: float
    dark_noise_e: float
    saturation_photons: float
    saturation_e: float
    snr_max: float
    dynamic_range: float
    dsnu_e: float
    dsnu_dn: float
    dsnu_detection_limit_e: float
    prnu_percent: float
    prnu_standard_error_percent: float
    dark_current_from_mean_e_per_s: float
    dark_current_from_variance_e_per_s: float
    dark_offset_dn: float
    linearity_error_min_percent: float
    linearity_error_max_percent: float
    spatial_photons: float
    spatial_signal_dn: float
    spatial_bright: QuantizedMoments
    spatial_dark: QuantizedMoments
    dark_temporal_variance_dn2: float
    transfer: PhotonTransfer

    def figures(self) -> dict[str, float]:
        """The headline figures of an EMVA 1288 data sheet, keys with their unit."""
        return {
            "system_gain_dn_per_e": self.system_gain_dn_per_e,
            "dark_noise_dn": self.dark_noise_dn,
            "dark_noise_e": self.dark_noise_e,
            "quantum_efficiency_percent": 100 * self.quantum_efficiency,
            "saturation_capacity_photons": self.saturation_photons,
            "saturation_capacity_e": self.saturation_e,
            "dsnu_e": self.dsnu_e,
            "prnu_percent": self.prnu_percent,
            "snr_max": self.snr_max,
            "dynamic_range": self.dynamic_range,
            "dark_current_from_mean_e_per_s": self.dark_current_from_mean_e_per_s,
            "dark_current_from_variance_e_per_s": self.dark_current_from_variance_e_per_s,
            "linearity_error_min_percent": self.linearity_error_min_percent,
            "linearity_error_max_percent": self.linearity_error_max_percent,
        }


def run_results1288(data: dict[str, Any], *, saturation_index: int | None = None) -> Results1288:
    """The ``emva1288`` package's results object on data in its ``Data1288`` layout.

    ``saturation_index`` forces the saturation step (``Results1288``'s ``index_u_ysat``)
    instead of searching for the variance's peak.
    """
    patch_emva1288()
    return Results1288(data, index_u_ysat=saturation_index, loglevel=_QUIET)


def _run_package(descriptor: EMVADescriptor) -> tuple[Data1288, Results1288]:
    parser = ParseEmvaDescriptorFile(str(descriptor.path), loglevel=_QUIET)
    shape = (descriptor.height, descriptor.width)
    images = LoadImageData(
        parser.images,
        loglevel=_QUIET,
        fload=read_frame,
        fload_kwargs={"bit_depth": descriptor.bit_depth, "shape": shape},
    )
    data = Data1288(images.data, loglevel=_QUIET)
    # EMVA 1288 defines saturation as the maximum of the temporal variance. The package's own
    # search walks back from the brightest step and stops at the first local maximum, which
    # for a camera clipped at its full well is the noise of the read-noise plateau beyond it.
    saturation = int(np.argmax(data.data["temporal"]["s2_y"]))
    return data, run_results1288(data.data, saturation_index=saturation)


def dark_at_zero_exposure(exposure_ns: np.ndarray, values: np.ndarray) -> float:
    """A dark figure extrapolated to zero exposure time on a straight line (EMVA 1288's dark
    offset and temporal dark noise); with a single exposure time, its mean."""
    if np.unique(exposure_ns).size < 2:
        return float(np.mean(values))
    return float(np.polynomial.polynomial.polyfit(exposure_ns, values, 1)[0])


def _spatial_moments(spatial: dict[str, Any], variance: float, suffix: str) -> QuantizedMoments:
    """The spatial step's mean, spatial variance (the temporal part removed) and mean
    temporal variance of its stack of frames (EMVA 1288 section 8.1)."""
    return QuantizedMoments(
        mean_dn=float(spatial["avg_mean" + suffix]),
        spatial_variance_dn2=float(variance),
        temporal_variance_dn2=float(spatial["var_mean" + suffix]),
    )


def _finite(value: SupportsFloat) -> float:
    number = float(value)
    return number if math.isfinite(number) else math.nan


def analyse_measurement(descriptor: str | Path | EMVADescriptor) -> EMVAAnalysis:
    """Run the EMVA 1288 analysis of the ``emva1288`` package on a measurement.

    Parameters
    ----------
    descriptor
        The descriptor file, or a descriptor already read by
        :func:`recon.emva.descriptor.read_descriptor`.

    Returns
    -------
    EMVAAnalysis
        The figures and the photon transfer data.

    Raises
    ------
    InputError
        A bad descriptor or image (one line naming it), or a measurement the analysis cannot
        use (no step below saturation for the fits).

    Examples
    --------
    >>> from recon.measured_data import data_path
    >>> result = analyse_measurement(data_path("real/emva1288_basler_ccd12/EMVA1288_Data.txt"))
    >>> round(result.system_gain_dn_per_e, 3)
    0.281
    """
    if not isinstance(descriptor, EMVADescriptor):
        descriptor = read_descriptor(descriptor)
    # The package takes square roots of variances that noise can make negative (a DSNU below
    # the detection limit): those figures become NaN, without a warning per figure.
    with np.errstate(invalid="ignore", divide="ignore"):
        return _analysis(descriptor)


def _analysis(descriptor: EMVADescriptor) -> EMVAAnalysis:
    data, results = _run_package(descriptor)
    temporal, spatial = data.data["temporal"], data.data["spatial"]
    try:
        gain = float(results.K)
        stop = int(results.index_sensitivity_max)
        linearity = results.linearity()
        linearity_range = (int(results.index_linearity_min), int(results.index_linearity_max))
    except (ValueError, IndexError) as error:  # no step between dark and saturation
        raise InputError(
            f"{descriptor.path}: the analysis found no usable steps below saturation ({error}); "
            "expected bright steps from near dark up to beyond saturation"
        ) from error
    dark_stack = spatial["var_mean_dark"] / spatial["L_dark"]
    pixels = descriptor.width * descriptor.height
    dark_error_dn2 = dark_stack * math.sqrt(2 / (pixels - 1))
    bright_error_dn2 = spatial["var_mean"] / spatial["L"] * math.sqrt(2 / (pixels - 1))
    spatial_signal = spatial["avg_mean"] - spatial["avg_mean_dark"]
    prnu_dn = math.sqrt(max(results.s_2_y - results.s_2_y_dark, 0.0))
    offset = dark_at_zero_exposure(temporal["texp"], temporal["u_ydark"])
    transfer = PhotonTransfer(
        exposure_s=np.asarray(temporal["texp"], float) / 1e9,
        photons=np.asarray(temporal["u_p"], float),
        mean_dn=np.asarray(temporal["u_y"], float),
        variance_dn2=np.asarray(temporal["s2_y"], float),
        dark_mean_dn=np.asarray(temporal["u_ydark"], float),
        dark_variance_dn2=np.asarray(temporal["s2_ydark"], float),
        saturation_index=int(results.index_u_ysat),
        sensitivity_stop=stop,
        linearity_range=linearity_range,
    )
    return EMVAAnalysis(
        descriptor=descriptor,
        system_gain_dn_per_e=gain,
        responsivity_dn_per_photon=float(results.R),
        quantum_efficiency=float(results.QE) / 100,
        dark_noise_dn=float(results.sigma_y_dark),
        dark_noise_e=float(results.sigma_d),
        saturation_photons=float(results.u_p_sat),
        saturation_e=float(results.u_e_sat),
        snr_max=float(results.SNR_max),
        dynamic_range=float(results.DR),
        dsnu_e=_finite(results.DSNU1288),
        dsnu_dn=_finite(results.DSNU1288_DN()),
        dsnu_detection_limit_e=math.sqrt(2 * dark_error_dn2) / gain,
        prnu_percent=_finite(results.PRNU1288),
        prnu_standard_error_percent=100
        * bright_error_dn2
        / max(2 * prnu_dn, 1e-12)
        / spatial_signal,
        dark_current_from_mean_e_per_s=_finite(results.u_I_mean),
        dark_current_from_variance_e_per_s=_finite(results.u_I_var),
        dark_offset_dn=float(offset),
        linearity_error_min_percent=float(linearity["linearity_error_min"]),
        linearity_error_max_percent=float(linearity["linearity_error_max"]),
        spatial_photons=float(spatial["u_p"]),
        spatial_signal_dn=float(spatial_signal),
        spatial_bright=_spatial_moments(spatial, results.s_2_y, ""),
        spatial_dark=_spatial_moments(spatial, results.s_2_y_dark, "_dark"),
        dark_temporal_variance_dn2=dark_at_zero_exposure(temporal["texp"], temporal["s2_ydark"]),
        transfer=transfer,
    )
