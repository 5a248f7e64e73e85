"""The dome's spectral side set up as in thesis 10.3-10.4: calibration, exposure plan, filters.

:func:`dome_setup` runs, on the twin's cameras (:mod:`twin.dome.capture`):

1. the spectral camera's low-SNR calibration (thesis 10.3): 200 dark frames per exposure time, a
   low-signal exposure series of a colour checker in the 550 nm band through the filtered
   Robertson recovery (Eq. 10.4-10.8), and the band sensitivities from the white reference
   lit by the LED (:func:`recon.calibration.dome.calibrate_spectral_camera`);
2. the RGB camera's calibration: Robertson on an exposure series, the white reference's HDR value;
3. the exposure plan :math:`t_\\lambda = t_{base} / \\sqrt{E L}` with the calibrated :math:`E`
   (:func:`recon.scheduling.dome_schedule.spectral_exposures`), :math:`t_{base}` set by the longest
   band;
4. the filter sizes of Fig. 10.5 from simulated band images of a grey card at the planned
   exposures, converted as the study converts its captures (:func:`recon.scheduling.dome_schedule
   .filter_sizes`, :math:`\\sigma` = size / 5);
5. :math:`R_{cam}` on the 30 bands: the RGB camera's spectral response (what
   ``recon.camera_char`` estimates; here the camera model's own) times the LED, normalized so
   the white reference reads 1.

The thesis gives no numbers for Figure 10.5, so the default longest band follows from its text:
10 images at +61 % last 1.61 x 3.402 s = 5.48 s on average, and an image cannot be shorter than
its longest band (``tests/twin/sensor/test_dome_exposure_plan.py`` explains the reasoning).
That value is a calibration, not a result: it sets :math:`t_{base}`, so every band exposure is
proportional to it, and the schedules' exposure increases follow from it (measured +57 % for 10
images against the thesis's +61 % it was derived from; how they move with it:
``benchmarks/capture_time_sensitivity.py``, ``BENCHMARKS.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from recon.calibration.dome import (
    RgbCameraCalibration,
    SpectralCameraCalibration,
    calibrate_rgb_camera,
    calibrate_spectral_camera,
)
from recon.errors import InputError
from recon.scheduling.dome_schedule import (
    FILTER_SIZE_PER_SIGMA,
    THESIS_RGB_EXPOSURES_S,
    filter_sizes,
    spectral_exposures,
)
from recon.spectra import WavelengthGrid
from twin.components.lamps import FINE_GRID
from twin.components.targets import zenith_white_reflectance
from twin.dome.capture import THESIS_BANDS_NM, DomeCameras, dome_cameras
from twin.dome.exposure_plan import rgb_response_series_s, spectral_response_series_s
from twin.materials.textures import TextureTruth
from twin.render.truth import band_passbands, texture_truth
from twin.rigs.hemisphere import direction

__all__ = [
    "BAND_GRID",
    "CALIBRATION_LIGHT",
    "DARK_FRAMES_PER_TIME",
    "SPECTRAL_VIEW",
    "THESIS_LONGEST_BAND_S",
    "DomeSetup",
    "dome_setup",
]

BAND_GRID = WavelengthGrid(THESIS_BANDS_NM)
"""The reconstruction's grid: the spectral camera's 30 bands."""

THESIS_LONGEST_BAND_S = 1.61 * sum(THESIS_RGB_EXPOSURES_S)
"""Default longest band exposure, 5.48 s: a calibration, derived from the thesis's +61 % for 10
RGB images (10.4; module description), not a result of the twin."""

DARK_FRAMES_PER_TIME = 200
"""Dark frames averaged per exposure time (thesis 10.3)."""

SPECTRAL_VIEW = direction(45.0, 15.0)
"""The spectral camera's direction: 45 degrees elevation, 15 degrees from the RGB arc."""

CALIBRATION_LIGHT = direction(15.0, 195.0)
_SERIES_BAND = 14  # 550 nm
_GREY = 0.2
_RGB_DARK_FRAMES = 16
_LONGEST_DARK_S = 600.0  # dark frames up to here, for long reference captures
_TARGET_RELATIVE_NOISE = 0.02


@dataclass(frozen=True)
class DomeSetup:
    """Everything the dome study needs besides the sample.

    Attributes
    ----------
    cameras
        The twin's cameras (simulation side).
    spectral, rgb
        The calibrations (processing side).
    led_per_band
        ``(30,)`` the LED intensity per band as a spectrometer reports it.
    exposures_s
        ``(30,)`` planned band exposures :math:`t_\\lambda`.
    relative_noise
        ``(30,)`` simulated relative noise of a grey card (reflectance 0.2) per band and
        texel.
    target_relative_noise
        The noise the filters leave (:func:`recon.scheduling.dome_schedule.filter_sizes`).
    response
        ``(30, 3)`` :math:`R_{cam}`.
    calibration_truth
        The colour checker used for the calibration series (for the Fig. 10.4 cross-check).
    """

    cameras: DomeCameras
    spectral: SpectralCameraCalibration
    rgb: RgbCameraCalibration
    led_per_band: np.ndarray
    exposures_s: np.ndarray
    relative_noise: np.ndarray
    target_relative_noise: float
    response: np.ndarray
    calibration_truth: TextureTruth

    def filter_sigma(self, exposure_scale: float = 1.0) -> np.ndarray:
        """``(30,)`` Gaussian sigma per band (texels) for the planned exposures times
        ``exposure_scale``: shot-noise-limited noise grows as its inverse square root."""
        noise = self.relative_noise / np.sqrt(exposure_scale)
        return filter_sizes(noise, self.target_relative_noise) / FILTER_SIZE_PER_SIGMA


def _rgb_response(cameras: DomeCameras) -> np.ndarray:
    """:math:`R_{cam}` ``(30, 3)``: camera response times LED averaged over each band's 10 nm
    passband, scaled so that the white reference gives 1 per channel."""
    electrons = cameras.rgb.electron_responses(FINE_GRID).values * cameras.led.values
    passbands = band_passbands(BAND_GRID).values * FINE_GRID.quadrature_weights()
    shape = (passbands / passbands.sum(1, keepdims=True)) @ electrons.T
    white = zenith_white_reflectance(BAND_GRID).values
    return shape / (white @ shape)


def _band_frames_of_white(cameras, rates, exposures, rng) -> np.ndarray:
    side = cameras.spectral.height // cameras.pixels_per_texel
    shape = (side, side)
    return np.stack(
        [
            cameras.band_frame(np.full(shape, rate), float(t), rng)
            for rate, t in zip(rates, exposures, strict=True)
        ]
    )


def dome_setup(
    texels: int = 48,
    *,
    sample_size_m: float = 0.04,
    texel_px: int | None = None,
    longest_band_s: float = THESIS_LONGEST_BAND_S,
    target_relative_noise: float = _TARGET_RELATIVE_NOISE,
    dark_frames: int = DARK_FRAMES_PER_TIME,
    seed: int = 0,
) -> DomeSetup:
    """Calibrate the twin dome and plan its spectral exposures (module description);
    ``texels``, ``sample_size_m`` and ``texel_px`` size the cameras
    (:func:`twin.dome.capture.dome_cameras`); ``dark_frames`` spectral-camera dark frames are
    averaged at each of the calibration's eight exposure times."""
    if not longest_band_s > 0:
        raise InputError(f"longest_band_s: expected a positive time, got {longest_band_s}")
    if dark_frames < 1:
        raise InputError(f"dark_frames: expected at least 1 per exposure time, got {dark_frames}")
    rng = np.random.default_rng(seed)
    cameras = dome_cameras(texels, sample_size_m=sample_size_m, texel_px=texel_px)
    led = np.interp(THESIS_BANDS_NM, FINE_GRID.wavelengths_nm, cameras.led.values)
    white_reflectance = zenith_white_reflectance(BAND_GRID).values
    white_rgb_rate, white_band_rate = cameras.white_rates()
    # White reference frames: 300 DN above the offset, inside the range the low-signal series
    # calibrates (beyond it the curve is extrapolated), but no band longer than 8 s (averaging
    # the whole frame leaves the weak blue bands' noise far below 0.1 %).
    gain = cameras.spectral.config.system_gain_dn_per_e
    white_t = np.clip(300.0 / (gain * white_band_rate), 1e-3, 8.0)
    chart = texture_truth(
        "colorchecker16", CALIBRATION_LIGHT[None], SPECTRAL_VIEW[None], texels=texels
    )
    cos_i = float(CALIBRATION_LIGHT[2])
    rgb_basis, band_basis = cameras.basis_rates(chart)
    chart_bands = cos_i * chart.weights[0] @ band_basis
    # Series from a few DN (the darkest field at the shortest time) to about 3000 DN above the
    # offset for the brightest field: the low-SNR range and the long reference exposures.
    # (evenly spaced, so no two ratios are powers of one factor: see
    # recon.radiometric.response_curve)
    series_t = spectral_response_series_s(float(chart_bands[..., _SERIES_BAND].max()))
    series = np.stack(
        [cameras.band_frame(chart_bands[..., _SERIES_BAND], float(t), rng) for t in series_t]
    )
    longest = max(_LONGEST_DARK_S, longest_band_s, white_t.max(), series_t.max())
    dark_times = np.geomspace(0.01, longest, 8)
    spectral = calibrate_spectral_camera(
        *cameras.dark_frames(dark_times, dark_frames, rng),
        series,
        series_t,
        _band_frames_of_white(cameras, white_band_rate, white_t, rng),
        white_t,
        led,
        white_reflectance,
        sigma_px=2.0,
        bit_depth=cameras.spectral.config.bit_depth,
    )
    rgb_series_t = rgb_response_series_s()
    chart_rgb = cos_i * chart.weights[0] @ rgb_basis
    hdr_set = np.array(THESIS_RGB_EXPOSURES_S)
    rgb = calibrate_rgb_camera(
        cameras.rgb_frames(chart_rgb, rgb_series_t, rng),
        rgb_series_t,
        np.concatenate(
            [
                cameras.rgb_frames(np.zeros_like(chart_rgb), hdr_set, rng)
                for _ in range(_RGB_DARK_FRAMES)
            ]
        ),
        np.tile(hdr_set, _RGB_DARK_FRAMES),
        cameras.rgb_frames(
            np.broadcast_to(white_rgb_rate, chart_rgb.shape), np.array(THESIS_RGB_EXPOSURES_S), rng
        ),
        np.array(THESIS_RGB_EXPOSURES_S),
        bit_depth=cameras.rgb.config.bit_depth,
    )
    support = spectral.sensitivity * led
    base_s = longest_band_s * math.sqrt(support.min())
    exposures = spectral_exposures(
        base_s, spectral.sensitivity, led, limits_s=cameras.spectral.config.exposure_range_s
    )
    grey = _band_frames_of_white(
        cameras, _GREY * white_band_rate / white_reflectance, exposures, rng
    )
    grey_values = [
        spectral.reflectance(
            frame, float(t), band, led[band], 1.0, texel_px=cameras.pixels_per_texel
        )
        for band, (frame, t) in enumerate(zip(grey, exposures, strict=True))
    ]
    relative_noise = np.array([np.std(v) / np.mean(v) for v in grey_values])
    return DomeSetup(
        cameras,
        spectral,
        rgb,
        led,
        exposures,
        relative_noise,
        target_relative_noise,
        _rgb_response(cameras),
        chart,
    )
