"""A camera definition (``scenes/cameras/*.yaml``) from parameters fitted to an EMVA 1288
measurement (:func:`recon.emva.fit.fit_sensor`), written with comments that say which values
were fitted, which were assumed and where the measurement came from.

What an EMVA 1288 measurement does not give is filled in and said so in the file: the spectral
quantum efficiency away from the measurement's wavelength (the measured value carried by the
curve shape of a KAI-4021-class interline CCD, :class:`twin.components.CCDQuantumEfficiency`
with its default peak and widths, scaled so that it passes through the measured value), the pixel
pitch, the optics, the temperature (the dark current holds at the measurement's temperature,
taken as the reference), hot pixels and the CCD transfer gradient (none), a colour mosaic (none).

References
----------
- EMVA Standard 1288, Release 3.0 (2010): the figures the fit starts from.
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np
import yaml

from recon.emva.fit import FittedSensor
from recon.errors import InputError
from recon.measured_data import data_path
from recon.spectra import WavelengthGrid
from twin.components.detectors import CCDQuantumEfficiency
from twin.rigs.camera_config import CameraConfig

__all__ = ["descriptor_reference", "fitted_camera_config", "write_fitted_camera"]

_SIGNIFICANT = 5
_QE_SHAPE = CCDQuantumEfficiency(peak_qe=1.0)  # the K4's KAI-4021-class shape, peak 1
_ASSUMED_F_NUMBER, _ASSUMED_TRANSMISSION = 8.0, 0.9
_ASSUMED_TEMPERATURE_C = 25.0


def _rounded(value: float, digits: int = _SIGNIFICANT) -> float:
    """``value`` to ``digits`` significant digits (the YAML is read by people too)."""
    value = float(value)
    if value == 0 or not math.isfinite(value):
        return value
    return round(value, digits - 1 - math.floor(math.log10(abs(value))))


def descriptor_reference(path: Path | None) -> str:
    """How a camera file names its descriptor: relative to spectwin's measured data when it
    lies there (so the shipped camera works wherever spectwin is installed), else absolute."""
    if path is None:
        raise InputError("measurement: a fitted camera needs the descriptor's file")
    path = Path(path).resolve()
    try:
        return path.relative_to(data_path().resolve()).as_posix()
    except ValueError:
        return str(path)


def _peak_qe(fit: FittedSensor) -> float:
    grid = WavelengthGrid(np.array([fit.wavelength_nm, fit.wavelength_nm + 1.0]))
    shape_at = float(_QE_SHAPE(grid).values[0])
    peak = fit.quantum_efficiency / shape_at
    if not 0 < peak <= 1:
        raise InputError(
            f"wavelength_nm: a quantum efficiency of {100 * fit.quantum_efficiency:.1f} % at "
            f"{fit.wavelength_nm:g} nm needs a peak of {100 * peak:.0f} % on the CCD curve shape "
            f"(peak at {_QE_SHAPE.peak_nm:g} nm); expected a wavelength where the shape allows it"
        )
    return peak


def fitted_camera_config(
    fit: FittedSensor, *, name: str, serial: str, pixel_pitch_um: float
) -> CameraConfig:
    """The twin camera of a fit (see the module for what is assumed).

    Parameters
    ----------
    fit
        Parameters fitted to an EMVA 1288 measurement.
    name, serial
        The camera's name and serial (the serial seeds its fixed patterns).
    pixel_pitch_um
        Pixel pitch; EMVA 1288's photon counts per pixel do not need it, the rigs' optics do.
    """
    descriptor = fit.analysis.descriptor
    width, height = fit.size_px
    low, high = fit.exposure_range_s
    knee = _rounded(fit.knee_strength, 3)
    document = {
        "name": name,
        "serial": serial,
        "mosaic": "none",
        "width": width,
        "height": height,
        "pixel_pitch_um": pixel_pitch_um,
        "bit_depth": fit.bit_depth,
        "sensor_temperature_c": _ASSUMED_TEMPERATURE_C,
        "exposure_range_s": [low, high],
        "optics": {"f_number": _ASSUMED_F_NUMBER, "transmission": _ASSUMED_TRANSMISSION},
        "quantum_efficiency": {
            "model": "ccd",
            "peak_qe": _rounded(_peak_qe(fit)),
            "peak_nm": _QE_SHAPE.peak_nm,
            "log_width_blue": _QE_SHAPE.log_width_blue,
            "log_width_red": _QE_SHAPE.log_width_red,
        },
        "system_gain_dn_per_e": _rounded(fit.system_gain_dn_per_e),
        "read_noise_dn": _rounded(fit.read_noise_dn),
        "full_well_e": _rounded(fit.full_well_e),
        "adc_offset_dn": _rounded(fit.adc_offset_dn),
        "dark_current": {
            "e_per_s_at_reference": _rounded(fit.dark_current_e_per_s),
            "reference_temperature_c": _ASSUMED_TEMPERATURE_C,
            "doubling_temperature_c": 6.3,
        },
        "fixed_pattern": {
            "prnu_sigma": _rounded(fit.prnu),
            "offset_sigma_dn": _rounded(fit.offset_sigma_dn, 3),
        },
        "oecf": {"model": "knee", "strength": knee} if knee > 0 else {"model": "linear"},
        "emva1288": {
            "descriptor": descriptor_reference(descriptor.path),
            "wavelength_nm": fit.wavelength_nm,
        },
    }
    return CameraConfig.model_validate(document)


def _header(fit: FittedSensor, config: CameraConfig, source: str) -> list[str]:
    analysis = fit.analysis
    figures = (
        f"K = {analysis.system_gain_dn_per_e:.4g} DN/e-, QE = "
        f"{100 * analysis.quantum_efficiency:.3g} %, dark noise = {analysis.dark_noise_dn:.3g} DN, "
        f"saturation = {analysis.saturation_photons:.5g} photons "
        f"({analysis.saturation_e:.5g} e-), DSNU = {analysis.dsnu_e:.2g} e- (resolved above "
        f"{analysis.dsnu_detection_limit_e:.2g} e-), PRNU = {analysis.prnu_percent:.3g} %, "
        f"dark current = {analysis.dark_current_from_mean_e_per_s:.3g} e-/s (from the mean), "
        f"linearity error {analysis.linearity_error_min_percent:.2g} to "
        f"{analysis.linearity_error_max_percent:.2g} %."
    )
    saturation = (
        "the ADC clips before the full well, which is hidden: full_well_e is the ADC's top plus "
        "five shot-noise widths, the least that leaves the measured frames unchanged."
        if fit.saturated_by == "ADC"
        else "the full well clips first: full_well_e puts the variance peak at the measured "
        "saturation."
    )
    qe = _QE_SHAPE  # the shape of the camera's quantum efficiency (fitted_camera_config)
    descriptor = analysis.descriptor
    paragraphs = [
        f"{config.name}: fitted by `spectwin camera fit` to the EMVA 1288 measurement {source} "
        f"({descriptor.width} x {descriptor.height} px, {descriptor.frame_count} frames "
        f"in {len(descriptor.steps)} steps).",
        f"The emva1288 analysis of that measurement: {figures}",
        "Fitted (recon.emva.fit: the parameters whose simulated measurement gives those "
        "figures): system gain, quantum efficiency at the measurement's wavelength, read noise, "
        "offset, dark current, offset DSNU, PRNU and the OECF knee (strength "
        f"{fit.knee_strength:.3g}: {fit.knee_rms_percent:.2g} % rms from the measured means, a "
        f"straight line {fit.straight_line_rms_percent:.2g} %). Saturation: {saturation}",
        f"Spectral QE: measured only at {fit.wavelength_nm:g} nm "
        f"({100 * fit.quantum_efficiency:.3g} %); elsewhere the curve shape of a KAI-4021-class "
        f"interline CCD (peak {qe.peak_nm:g} nm, log widths {qe.log_width_blue:g} / "
        f"{qe.log_width_red:g}) scaled through that value: a typical shape, not a measurement.",
        f"Assumed, not measured: the pixel pitch ({config.pixel_pitch_um:g} um), the optics "
        f"(f/{config.optics.f_number:g}, transmission {config.optics.transmission:g}), the "
        f"temperature ({config.sensor_temperature_c:g} C, the dark current's reference), no hot "
        "pixels, no transfer gradient, no mosaic. The exposure range is the measured one, the "
        "sensor size that of the measured frames.",
    ]
    return [
        line
        for paragraph in paragraphs  # a path stays whole on its line, however long
        for line in textwrap.wrap(paragraph, 97, break_long_words=False, break_on_hyphens=False)
    ]


def write_fitted_camera(
    fit: FittedSensor,
    path: Path,
    *,
    name: str,
    serial: str,
    pixel_pitch_um: float,
    source: str | None = None,
) -> CameraConfig:
    """Write the twin camera of a fit to ``path`` as commented YAML and return it.

    ``source`` names the measurement in the header (its descriptor path by default).
    """
    config = fitted_camera_config(fit, name=name, serial=serial, pixel_pitch_um=pixel_pitch_um)
    source = source or str(fit.analysis.descriptor.path)
    header = "".join(f"# {line}\n" for line in _header(fit, config, source))
    document = config.model_dump(mode="json", exclude_defaults=False)
    body = yaml.safe_dump(document, sort_keys=False, default_flow_style=False, width=100)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(header + body, encoding="utf-8")
    return config
