"""Exposure times of the dome's capture programs, from the rig and camera models (thesis 10.3,
10.4).

- The RGB cameras' HDR set: 50, 186, 666, 2500 ms (10.4).
- The spectral camera's band exposures :math:`t_\\lambda = t_{base} / \\sqrt{E(\\lambda)
  L(\\lambda)}` (10.4, :func:`recon.scheduling.dome_schedule.spectral_exposures`), here with
  the model's own :math:`E L` (the white standard's band rates facing the LED over its
  reflectance) instead of a calibrated one, and :math:`t_{base}` set by the longest band
  (:data:`twin.dome.setup.THESIS_LONGEST_BAND_S`, 5.48 s).
- The band schedule: 10 RGB images with the noisiest bands twice (:func:`band_schedules`).
- Frames with every LED on (alignment and geometric frames): the white paper of the holder at
  half the camera's saturation (the spectral camera in the 550 nm band).
- Response series: the RGB cameras' wide series and the spectral camera's low-signal series of
  the colour checker in the 550 nm band, from a few DN to about 3000 DN above the offset for its
  brightest field (the recipes of :func:`twin.dome.setup.dome_setup`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hwbridge.dome_layout import SPECTRAL_CAMERA
from hwbridge.dome_plans import DomeCameraIds, DomeExposures
from recon.scheduling.dome_schedule import (
    THESIS_RGB_EXPOSURES_S,
    fewest_images,
    schedule_bands,
    spectral_exposures,
)
from recon.spectra import SampledSpectra, WavelengthGrid
from twin.components.lamps import FINE_GRID
from twin.components.targets import colorchecker_reflectances, zenith_white_reflectance
from twin.dome.capture import THESIS_BANDS_NM, DomeCameras, dome_cameras
from twin.rigs.dome_geometry import dome_geometry
from twin.rigs.rig_config import DomeConfig

__all__ = [
    "REFERENCE_BAND_NM",
    "band_schedules",
    "dome_exposures",
    "model_band_exposures_s",
    "rgb_response_series_s",
    "spectral_response_series_s",
]

REFERENCE_BAND_NM = 550.0
"""The spectral camera's band for its response series, the per-LED white frames and the frames
with every LED on (the band of the thesis's low-SNR series, 10.3)."""

_PAPER_REFLECTANCE = 0.85  # the holder's white paper (twin.materials.sample_holder)
_ALL_LEDS_FILL = 0.5


def model_band_exposures_s(cameras: DomeCameras, longest_band_s: float) -> np.ndarray:
    """``(30,)`` band exposures :math:`t_\\lambda = t_{base} / \\sqrt{E L}` with the camera
    model's :math:`E L` (the white standard's band rates facing the LED over its reflectance, as
    the calibration of :func:`twin.dome.setup.dome_setup` measures it), the weakest band exposed
    ``longest_band_s``, clipped to the spectral camera's range."""
    _, white_rates = cameras.white_rates()
    support = white_rates / zenith_white_reflectance(WavelengthGrid(THESIS_BANDS_NM)).values
    base = longest_band_s * math.sqrt(support.min())
    return spectral_exposures(
        base, support, np.ones_like(support), limits_s=cameras.spectral.config.exposure_range_s
    )


def band_schedules(exposures_s: np.ndarray) -> dict[str, dict]:
    """The 8-image, the fewest-image and the 10-image schedule (the noisiest bands twice, as
    many as fit in 10 images) of ``(30,)`` band exposures (thesis 10.4: +41 %, +61 %)."""
    exposures = np.asarray(exposures_s, np.float64)
    noisiest = np.argsort(-exposures)
    repeats = 0
    while (
        fewest_images(exposures, repeat_bands=noisiest[: repeats + 1].tolist()).n_images <= 10
        and repeats < exposures.size
    ):
        repeats += 1
    plans = {
        "8_images": schedule_bands(exposures, 8),
        "fewest_images": fewest_images(exposures),
        "10_images": schedule_bands(
            exposures, 10, repeat_bands=noisiest[:repeats].tolist(), image_limit_s=exposures.max()
        ),
    }
    out: dict[str, Any] = {
        name: {
            "images": [list(map(int, image)) for image in plan.images],
            "n_images": plan.n_images,
            "total_s": plan.total_s,
            "increase_pct": 100 * plan.increase,
            "optimal": plan.optimal,
        }
        for name, plan in plans.items()
    }
    out["10_images"]["repeated_bands_nm"] = THESIS_BANDS_NM[noisiest[:repeats]].tolist()
    out["band_exposures_sum_s"] = float(exposures.sum())
    out["rgb_set_s"] = float(sum(THESIS_RGB_EXPOSURES_S))
    return out


def rgb_response_series_s() -> np.ndarray:
    """The RGB cameras' response series: 14 exposures over 1 ms to 3.3 s, no two ratios powers
    of one factor (:mod:`recon.radiometric.response_curve`)."""
    return np.geomspace(1e-3, 3.0, 14) * (1 + 0.1 * (np.arange(14) % 3))


def spectral_response_series_s(brightest_rate_e_per_s: float) -> np.ndarray:
    """The spectral camera's low-signal series: 12 evenly spaced exposures from 20 ms to the one
    that gives the brightest field about 3000 DN above the offset."""
    return np.linspace(0.02, 15000.0 / brightest_rate_e_per_s, 12)


def _irradiance_factor(config: DomeConfig, leds: np.ndarray) -> float:
    """Sum of :math:`\\cos\\theta_i` over ``leds`` (each LED at the dome radius)."""
    return float(dome_geometry(config).led_directions[leds, 2].clip(0).sum())


def _rates(cameras: DomeCameras, reflectance: np.ndarray, cos_sum: float):
    """RGB ``(3,)`` and band ``(30,)`` rates of a diffuse ``reflectance`` on ``FINE_GRID``."""
    radiance = reflectance * cameras.led.values * cos_sum / (math.pi * cameras.config.radius_m**2)
    spectrum = SampledSpectra(FINE_GRID, radiance)
    return cameras.rgb.mean_electrons(spectrum), cameras.spectral.mean_electrons(
        spectrum, cameras.bands
    )


def _fill_exposure_s(rate: float, sensor) -> float:
    exposure = _ALL_LEDS_FILL * sensor.saturation_capacity_e / rate
    return float(np.clip(exposure, *sensor.config.exposure_range_s))


def dome_exposures(
    config: DomeConfig,
    camera_ids: DomeCameraIds,
    *,
    longest_band_s: float,
    calibration_led: int,
    schedule_images: int | None = None,
) -> DomeExposures:
    """The exposures of the dome's programs for ``camera_ids`` (module docstring); the bands
    packed into ``schedule_images`` RGB images each once (:func:`recon.scheduling.dome_schedule
    .schedule_bands`), or by default into the 10 images with the noisiest bands twice."""
    cameras = dome_cameras(1, config=config, texel_px=2)
    bands = model_band_exposures_s(cameras, longest_band_s)
    if schedule_images is None:
        schedule = band_schedules(bands)["10_images"]["images"]
    else:
        schedule = schedule_bands(bands, schedule_images).images
    reference = int(np.flatnonzero(THESIS_BANDS_NM == REFERENCE_BAND_NM)[0])
    every_led = np.arange(config.led_count)
    paper = np.full(FINE_GRID.size, _PAPER_REFLECTANCE)
    paper_rgb, paper_bands = _rates(cameras, paper, _irradiance_factor(config, every_led))
    all_leds = {camera: _fill_exposure_s(paper_rgb.max(), cameras.rgb) for camera in camera_ids.rgb}
    all_leds[SPECTRAL_CAMERA] = _fill_exposure_s(paper_bands[reference], cameras.spectral)
    chart = colorchecker_reflectances(FINE_GRID, out_of_range="clamp").values
    cos_i = _irradiance_factor(config, np.array([calibration_led]))
    _, chart_bands = _rates(cameras, chart, cos_i)
    return DomeExposures(
        rgb_hdr_s=tuple(THESIS_RGB_EXPOSURES_S),
        bands_nm=tuple(THESIS_BANDS_NM.tolist()),
        band_s=tuple(bands.tolist()),
        schedule=tuple(tuple(image) for image in schedule),
        all_leds_s=all_leds,
        rgb_series_s=tuple(rgb_response_series_s().tolist()),
        spectral_series_s=tuple(
            spectral_response_series_s(float(chart_bands[:, reference].max())).tolist()
        ),
        reference_band_nm=REFERENCE_BAND_NM,
    )
