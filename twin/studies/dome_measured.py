"""The cost of measuring the dome's spectra, and Eq. 10.2's exponent on dome stores.

The dome calibrates from what a real dome can measure (:mod:`recon.calibration.dome_spectra`):
the LED spectrum from the spectrometer's readings of the white standard, every RGB camera's
response from its photograph of the colour chart by the chapter 9 estimator. This study, on the
stores of :mod:`twin.studies.dome_stores` (one calibration store, one run store per material):

1. the measured spectra against the twin's truths (:func:`spectra_errors`): the LED spectrum's
   RMSE in % of its peak; per RGB camera and channel the response's RMSE in % of the channel's
   peak (in the spectral camera's bands), with the default prior and with a prior that has not
   seen the twin's camera (the Nikon D70's response stands in for the dome's cameras, and the
   default prior is learned from 51 measured cameras, the D70 among them);
2. per material the dome BTF's mean Eq. 6.8 error processed with the measured :math:`R_{cam}`
   against the same run processed with the truth's (the model's camera response times its LED
   spectrum): the cost of measuring;
3. per material the same at Eq. 10.2 exponents ``p_dyn`` 0, 0.5 and 0.6 (the stores and the
   analytic path on the same images, :func:`twin.studies.dome_stores.same_images`).

The truths live here, in the twin: ``recon`` never sees them (the calibration store records no
model spectrum, only the certified reflectances of the white standard and the chart).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from recon.calibration.dome_capture import DomeCalibration, calibrate_dome
from recon.calibration.dome_spectra import band_response
from recon.camera_prior import ResponsePrior, learn_response_prior
from recon.dome.processing import P_DYN
from recon.measured_data import camera_names, read_camera_sensitivities
from recon.spectra import SampledSpectra, WavelengthGrid, resample
from twin.components.lamps import FINE_GRID, PhosphorWhiteLED
from twin.dome.programs import DomeCaptureSize
from twin.dome.setup import dome_setup
from twin.rigs.rig_config import load_rig
from twin.sensor.model import Sensor
from twin.studies.dome_stores import STORE_CAPTURE, material_stores, same_images

__all__ = [
    "P_DYNS",
    "STAND_IN_CAMERA",
    "measured_study",
    "prior_without",
    "spectra_errors",
    "true_camera_response",
    "true_led_spectrum",
    "with_true_spectra",
]

P_DYNS = (0.0, 0.5, 0.6)
"""Eq. 10.2 exponents compared: none, and the thesis's 0.5-0.6."""

STAND_IN_CAMERA = "Nikon D70"
"""The measured camera whose relative response the dome's RGB camera model uses."""


def true_led_spectrum(wavelengths_nm: np.ndarray) -> np.ndarray:
    """The twin's LED spectrum at ``wavelengths_nm``, peak one."""
    values = PhosphorWhiteLED().intensity(WavelengthGrid(wavelengths_nm)).values
    return values / values.max()


def true_camera_response(grid: WavelengthGrid) -> np.ndarray:
    """The twin's RGB camera response ``(K, 3)`` averaged over each cell of ``grid``, peak one
    per channel."""
    electrons = Sensor(load_rig("dome").rgb_camera).electron_responses(FINE_GRID).values
    response = resample(SampledSpectra(FINE_GRID, electrons), grid, method="box").values.T
    return response / response.max(axis=0)


def with_true_spectra(calibration: DomeCalibration) -> DomeCalibration:
    """``calibration`` with :math:`R_{cam}` from the twin's true camera response and LED
    spectrum (as the capture store gave them before they were measured)."""
    grid = calibration.grid
    lit = SampledSpectra(
        FINE_GRID,
        Sensor(load_rig("dome").rgb_camera).electron_responses(FINE_GRID).values
        * PhosphorWhiteLED().intensity(FINE_GRID).values,
    )
    product = resample(lit, grid, method="box", out_of_range="zero").values.T
    return replace(
        calibration,
        response=band_response(product, np.ones(grid.size), calibration.white_per_band),
    )


def _rmse_pct(estimate: np.ndarray, truth: np.ndarray) -> list[float]:
    """Per column (or the one spectrum) the RMSE in % of the truth's peak."""
    estimate, truth = np.atleast_2d(estimate.T).T, np.atleast_2d(truth.T).T
    error = np.sqrt(np.mean((estimate - truth) ** 2, axis=0)) / truth.max(axis=0)
    return [round(float(value), 2) for value in 100 * error]


def prior_without(camera: str, grid: WavelengthGrid) -> ResponsePrior:
    """The response prior learned from every measured camera but ``camera`` on ``grid``."""
    responses = np.array(
        [
            resample(
                read_camera_sensitivities(name), grid, method="box", out_of_range="clamp"
            ).values.T
            for name in camera_names()
            if name != camera
        ]
    )
    return learn_response_prior(responses, grid.wavelengths_nm)


def spectra_errors(calibration: DomeCalibration) -> dict:
    """The measured spectra of ``calibration`` against the twin's truths (module docstring, 1)."""
    led = calibration.led_spectrum
    truth = true_camera_response(calibration.grid)
    true_response = with_true_spectra(calibration).response
    return {
        "led_rmse_pct_of_peak": _rmse_pct(led.values, true_led_spectrum(led.wavelengths_nm))[0],
        "led_largest_uncertainty_pct_of_peak": round(float(100 * led.uncertainty.max()), 3),
        "led_spread_pct_of_peak": max(led.spread_pct.values(), default=0.0),
        "readings": led.readings,
        "cameras": {
            camera: {
                "rmse_pct_of_peak_rgb": _rmse_pct(measured.values, truth),
                "fit_residual_pct": round(measured.fit_residual_pct, 2),
            }
            for camera, measured in calibration.camera_response.items()
        },
        "response_rmse_pct_of_peak_rgb": _rmse_pct(calibration.response, true_response),
    }


def measured_study(
    folder: Path,
    materials: Sequence[str],
    size: DomeCaptureSize = STORE_CAPTURE,
    *,
    seed: int = 0,
    p_dyns: Sequence[float] = P_DYNS,
    step: Callable[[str], None] = lambda name: None,
) -> dict:
    """The study (module docstring) on the stores in ``folder`` (captured where missing)."""
    setup = dome_setup(size.texels, texel_px=2, seed=seed)
    result: dict = {"capture": size.__dict__, "seed": seed, "materials": {}}
    calibration: DomeCalibration | None = None
    for material in materials:
        run_store, calibration_store = material_stores(folder, material, size, seed=seed, step=step)
        if calibration is None:
            step("calibrating from the store (measured spectra)")
            calibration = calibrate_dome(calibration_store)
            step("calibrating with a prior that has not seen the twin's camera")
            unseen = calibrate_dome(
                calibration_store,
                camera_prior=prior_without(STAND_IN_CAMERA, calibration.grid),
            )
            result["spectra"] = spectra_errors(calibration)
            result["spectra_prior_without_the_camera"] = spectra_errors(unseen)
        variants = {"true spectra": (with_true_spectra(calibration), P_DYN)} | {
            f"measured, p_dyn {p_dyn:g}": (calibration, p_dyn) for p_dyn in p_dyns
        }
        rows = {}
        for name, (chosen, p_dyn) in variants.items():
            step(f"{material}: processing with {name}")
            images = same_images(
                setup,
                run_store,
                chosen,
                folder / f"{material}.{name.replace(' ', '_').replace(',', '')}.btf.zarr",
                np.random.default_rng(seed),
                p_dyn=p_dyn,
            )
            rows[name] = images.summary()
        result["materials"][material] = rows
    return result
