"""Calibration of the dome's RGB and spectral cameras and the conversion of their frames (10.3).

Spectral camera, in the low-SNR range its short band exposures live in (thesis 10.3):

1. 200 dark frames per exposure time, averaged in floating point (Fig. 10.2d;
   :func:`recon.radiometric.dark_frames.average_dark_frames`), interpolated to any exposure time;
2. the inverse OECF :math:`f` from an exposure series of dark-subtracted, Gaussian-filtered
   frames, offset by 30 so negative values stay on the curve (Eq. 10.4-10.8,
   :func:`recon.radiometric.response_curve.robertson_filtered`), its ends
   (:data:`CURVE_END_LEVELS`) continued by straight lines;
3. the sensitivity :math:`E_\\lambda` per band: the linearized response to a white diffuse
   reference lit by the LED, divided by the LED spectrum (and the reference's reflectance).

A band frame then gives reflectance factors
:math:`\\rho = f(y - D_t + 30) / (t\\, E_\\lambda L_\\lambda \\cos\\theta_i)`, pixel by pixel,
averaged over the pixels of each texel and still noisy; the reconstruction filters them
(Eq. 10.1).

RGB cameras: Robertson's algorithm on the raw exposure series (the curve absorbs the ADC
offset, thesis 10.3: "Linearizing the response of the RGB cameras is straightforward"), HDR
merging of each image's four exposures (Eq. 10.3), one RGB value per Bayer quad, the quads of a
texel averaged, and white balance by the white reference under the same LED:
:math:`V_c = x_c / x^{white}_c`.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace

import numpy as np
from skimage.measure import block_reduce

from recon.calibration.gonio import extend_curve
from recon.errors import InputError
from recon.radiometric.dark_frames import average_dark_frames, dark_frames_at
from recon.radiometric.demosaic import bin_quads
from recon.radiometric.hdr import interpolate_curve, merge_hdr
from recon.radiometric.response_curve import robertson, robertson_filtered

__all__ = [
    "CURVE_END_LEVELS",
    "DARK_VALUE_OFFSET",
    "RgbCameraCalibration",
    "SpectralCameraCalibration",
    "calibrate_rgb_camera",
    "calibrate_spectral_camera",
    "curve_linearity",
    "rgb_camera_response",
    "texel_mean",
]

DARK_VALUE_OFFSET = 30.0
"""Added to dark-subtracted values before the curve (thesis Fig. 10.3: "offset by 30")."""

CURVE_END_LEVELS = 10
"""Observed levels at each end of the spectral camera's curve that its straight extension
replaces. Eq. 10.8 averages :math:`t_i \\tilde x_j` over the samples that land on a level, and
at the ends of the observed range noise decides which samples do: on a dome calibration
capture's series (12 frames of the colour checker from 20 ms, 8 dark frames per time) the
lowest levels, 27-32, came out up to 3 DN above the line through the others, which biased a
20 ms band frame of a dark field by a third."""


def texel_mean(image: np.ndarray, texel_px: int) -> np.ndarray:
    """Mean over ``texel_px x texel_px`` pixel blocks of the first two axes of ``image``."""
    if texel_px < 1 or image.shape[0] % texel_px or image.shape[1] % texel_px:
        raise InputError(
            f"texel_px: expected a divisor of the image sides {image.shape[:2]}, got {texel_px}"
        )
    block = (texel_px, texel_px) + (1,) * (image.ndim - 2)
    return block_reduce(image, block, np.mean)


def curve_linearity(curve: np.ndarray, offset: float = 0.0) -> float:
    """Largest deviation of an inverse response from the straight line through its zero at
    ``offset``, over its observed (finite) levels, relative to the curve's largest value."""
    levels = np.flatnonzero(np.isfinite(curve))
    if levels.size < 2:
        raise InputError("curve: fewer than two observed levels")
    shifted = levels - offset
    slope = np.sum(shifted * curve[levels]) / np.sum(shifted**2)
    return float(np.max(np.abs(curve[levels] - slope * shifted)) / np.max(np.abs(curve[levels])))


@contextmanager
def _iteration_budget() -> Iterator[None]:
    """Robertson's iteration on the spectral camera's low-signal series creeps toward its fixed
    point and may use its whole iteration budget; the calibration uses the curve it reached
    (its linearity is checked against the frames' exposure in the tests), so the convergence
    warning tells a user nothing to act on."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Robertson's iteration did not converge")
        yield


@dataclass(frozen=True)
class SpectralCameraCalibration:
    """Dark model, low-SNR inverse OECF and band sensitivities of the spectral camera.

    Attributes
    ----------
    dark_exposure_s, mean_dark_frames
        ``(n_times,)`` and ``(n_times, H, W)``: the averaged dark frames.
    inverse_response
        ``(levels,)`` :math:`f` at dark-subtracted value ``m - DARK_VALUE_OFFSET``, observed
        part from Eq. 10.8, ends extended by straight lines.
    observed_levels
        ``(2,)`` first and last level the calibration series reached.
    sensitivity
        ``(n_bands,)`` :math:`E_\\lambda`: curve units per second per unit LED intensity.
    """

    dark_exposure_s: np.ndarray
    mean_dark_frames: np.ndarray
    inverse_response: np.ndarray
    observed_levels: tuple[int, int]
    sensitivity: np.ndarray

    def linear_rate(self, frames: np.ndarray, exposure_s: float) -> np.ndarray:
        """:math:`f(y - D_t + 30) / t` of raw frames ``(..., H, W)`` taken at ``exposure_s``."""
        dark = dark_frames_at(float(exposure_s), self.dark_exposure_s, self.mean_dark_frames)
        values = np.asarray(frames, np.float64) - dark + DARK_VALUE_OFFSET
        top = self.inverse_response.size - 1
        if np.any(values < 0) or np.any(values > top):
            raise InputError(
                f"frames: dark-subtracted values outside the curve's range [-30, {top - 30}] "
                "(saturated or wrong dark model)"
            )
        return interpolate_curve(self.inverse_response, values) / float(exposure_s)

    def reflectance(
        self,
        frame: np.ndarray,
        exposure_s: float,
        band: int,
        light: float,
        cos_incidence: float,
        *,
        texel_px: int = 1,
    ) -> np.ndarray:
        """Reflectance factors ``(H, W)`` of band ``band`` from one raw frame
        ``(texel_px H, texel_px W)``, for a sample lit with LED intensity ``light`` (the
        spectrometer's value in that band) at :math:`\\cos\\theta_i` = ``cos_incidence``."""
        rate = texel_mean(self.linear_rate(frame, exposure_s), texel_px)
        return rate / (self.sensitivity[band] * light * cos_incidence)


def calibrate_spectral_camera(
    dark_exposure_s: np.ndarray,
    mean_dark_frames: np.ndarray,
    series_frames: np.ndarray,
    series_exposure_s: np.ndarray,
    white_frames: np.ndarray,
    white_exposure_s: np.ndarray,
    led_per_band: np.ndarray,
    white_reflectance: np.ndarray,
    *,
    sigma_px: float,
    bit_depth: int,
    white_region: np.ndarray | None = None,
) -> SpectralCameraCalibration:
    """Low-SNR calibration of the spectral camera (module description, thesis 10.3).

    Parameters
    ----------
    dark_exposure_s, mean_dark_frames
        Increasing exposure times ``(n_times,)`` and the dark frames averaged at each
        ``(n_times, H, W)`` (:func:`recon.radiometric.dark_frames.average_dark_frames`; 200 per
        time in the
        thesis); they must span the exposure times used later.
    series_frames, series_exposure_s
        ``(m, H, W)`` raw frames of a static scene in one band at ``(m,)`` exposure times, low
        values included, for the filtered Robertson recovery.
    white_frames, white_exposure_s
        ``(n_bands, H, W)`` raw frames of the white reference facing the LED, one per band, and
        their exposure times.
    led_per_band
        ``(n_bands,)`` LED intensity per band (spectrometer).
    white_reflectance
        ``(n_bands,)`` the white reference's reflectance (data sheet).
    sigma_px
        Gaussian filter of the Robertson recovery (Eq. 10.4).
    bit_depth
        The camera's bit depth.
    white_region
        ``(H, W)`` bool: the pixels that see the white reference (default: every pixel), whose
        mean linear rate gives the sensitivity.
    """
    led = np.asarray(led_per_band, np.float64)
    white = np.asarray(white_reflectance, np.float64)
    frames = np.asarray(white_frames)
    if frames.ndim != 3 or not (led.shape == white.shape == (frames.shape[0],)):
        raise InputError(
            f"white_frames, led_per_band, white_reflectance: expected (n_bands, H, W), (n_bands,) "
            f"and (n_bands,), got {frames.shape}, {led.shape} and {white.shape}"
        )
    times, means = np.asarray(dark_exposure_s, np.float64), np.asarray(mean_dark_frames)
    if times.ndim != 1 or means.shape[:1] != times.shape or np.any(np.diff(times) <= 0):
        raise InputError(
            f"dark_exposure_s, mean_dark_frames: expected increasing times (n,) and frames "
            f"(n, H, W), got {times.shape} and {means.shape}"
        )
    series_times = np.asarray(series_exposure_s, np.float64)
    with _iteration_budget():
        curve, _ = robertson_filtered(
            series_frames,
            series_times,
            sigma_px=sigma_px,
            dark=dark_frames_at(series_times, times, means),
            offset=DARK_VALUE_OFFSET,
            bit_depth=bit_depth,
        )
    observed = np.flatnonzero(np.isfinite(curve))
    partial = SpectralCameraCalibration(
        times,
        means,
        extend_curve(curve, trim_levels=CURVE_END_LEVELS),
        (int(observed[0]), int(observed[-1])),
        np.ones(led.size),
    )
    region = np.ones(frames.shape[1:], bool) if white_region is None else white_region
    if np.shape(region) != frames.shape[1:] or not np.any(region):
        raise InputError(
            f"white_region: expected a non-empty mask of the frames' shape {frames.shape[1:]}, "
            f"got shape {np.shape(region)}"
        )
    rates = np.array(
        [
            np.mean(partial.linear_rate(frame, float(t))[region])
            for frame, t in zip(frames, np.asarray(white_exposure_s), strict=True)
        ]
    )
    return SpectralCameraCalibration(
        times, means, partial.inverse_response, partial.observed_levels, rates / (led * white)
    )


@dataclass(frozen=True)
class RgbCameraCalibration:
    """Inverse OECF of the RGB camera (offset absorbed) and its white reference.

    Attributes
    ----------
    inverse_response
        ``(levels,)`` :math:`f` per raw value, extended at the ends.
    exposure_s
        ``(n_exposures,)`` the HDR exposure set.
    dark
        ``(2H, 2W)`` HDR value of the averaged dark frames, per raw pixel (the offset's and
        dark current's share, about 1 % of the white in the red channel).
    white
        ``(3,)`` dark-subtracted HDR value of the white reference facing the LED.
    """

    inverse_response: np.ndarray
    exposure_s: np.ndarray
    dark: np.ndarray
    white: np.ndarray

    def linear_mosaic(self, frames: np.ndarray) -> np.ndarray:
        """Dark-subtracted HDR value per raw pixel ``(2H, 2W)`` (still a Bayer mosaic) from one
        image's raw exposure set ``(n_exposures, 2H, 2W)`` (Eq. 10.3)."""
        return merge_hdr(frames, self.exposure_s, self.inverse_response) - self.dark

    def hdr(self, frames: np.ndarray) -> np.ndarray:
        """Dark-subtracted HDR RGB per Bayer quad ``(H, W, 3)`` from one image's raw exposure
        set ``(n_exposures, 2H, 2W)``."""
        return bin_quads(self.linear_mosaic(frames))

    def white_balanced(
        self, frames: np.ndarray, cos_incidence: float, *, texel_px: int = 2
    ) -> np.ndarray:
        """:math:`V` ``(H, W, 3)`` per texel of ``texel_px`` pixels (an even count): the HDR
        image relative to the white reference, per unit :math:`\\cos\\theta_i`."""
        if texel_px % 2:
            raise InputError(f"texel_px: expected whole Bayer quads, got {texel_px}")
        return texel_mean(self.hdr(frames), texel_px // 2) / (self.white * cos_incidence)


def rgb_camera_response(
    series_frames: np.ndarray,
    series_exposure_s: np.ndarray,
    dark_frames: np.ndarray,
    dark_exposure_s: np.ndarray,
    exposure_s: np.ndarray,
    *,
    bit_depth: int,
) -> RgbCameraCalibration:
    """Inverse OECF and dark level of the RGB camera for HDR images taken with the set
    ``exposure_s``, without a white reference (``white`` is one).

    Robertson on the raw series ``(m, 2H, 2W)``; dark frames ``(n, 2H, 2W)`` at every time of
    the HDR set, averaged per time and merged.
    """
    times = np.asarray(exposure_s, np.float64)
    with _iteration_budget():
        curve, _ = robertson(series_frames, np.asarray(series_exposure_s), bit_depth=bit_depth)
    curve = extend_curve(curve)
    dark_times, mean_darks = average_dark_frames(dark_frames, dark_exposure_s)
    if not np.array_equal(dark_times, np.sort(times)):
        raise InputError(
            f"dark_exposure_s: expected dark frames at the HDR set {sorted(times)}, got "
            f"{dark_times.tolist()}"
        )
    order = np.argsort(times)
    dark = np.empty_like(mean_darks)
    dark[order] = mean_darks
    return RgbCameraCalibration(curve, times, merge_hdr(dark, times, curve), np.ones(3))


def calibrate_rgb_camera(
    series_frames: np.ndarray,
    series_exposure_s: np.ndarray,
    dark_frames: np.ndarray,
    dark_exposure_s: np.ndarray,
    white_frames: np.ndarray,
    exposure_s: np.ndarray,
    *,
    bit_depth: int,
) -> RgbCameraCalibration:
    """Calibrate the RGB camera for HDR images taken with the set ``exposure_s``:
    :func:`rgb_camera_response`, and the white reference's frames ``(n_exposures, 2H, 2W)``
    merged, dark-subtracted and averaged over the frame."""
    partial = rgb_camera_response(
        series_frames,
        series_exposure_s,
        dark_frames,
        dark_exposure_s,
        exposure_s,
        bit_depth=bit_depth,
    )
    return replace(partial, white=partial.hdr(white_frames).reshape(-1, 3).mean(0))
