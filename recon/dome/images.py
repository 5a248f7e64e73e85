"""A dome run's frames as rectified, calibrated textures (thesis 10.2.2, 10.3, 10.4).

For each camera and stage position the holder's registration marks are found in the alignment
frame (every LED on; :func:`register_view`): near where the calibrated camera projects them, to
sub-pixel accuracy by :func:`recon.registration.border.register_frame` (where they are not
found, the projection stands in), and the sample's square on the plate follows
(:func:`recon.registration.sample_plane.sample_square_corners`). Every frame
of that camera and position is then sampled on the texture's texels
(:meth:`TexelGrid.texture`: averaged over each texel's footprint):

- an RGB camera's HDR set: merged with its inverse OECF and dark level (Eq. 10.3), demosaiced
  (``colour-demosaicing``) and rectified, divided per texel by the white standard's linear RGB
  under the same LED there (:mod:`recon.calibration.dome_lighting`): :math:`V`, reflectance
  factors relative to the white standard (:func:`white_balanced_rgb`);
- a spectral band frame: :math:`f(y - D_t + 30) / t` per pixel (10.3), rectified, divided by
  :math:`E_\\lambda L_\\lambda` and the LED's irradiance there: a noisy reflectance factor
  (:func:`band_reflectance`).

Conventions: image points ``(x, y)`` with pixel centres at +0.5 (:mod:`recon.registration`);
OpenCV's cameras (centres at integers) are shifted by half a pixel.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from hwbridge.schema import DomeHolder
from recon.calibration.dome import RgbCameraCalibration
from recon.calibration.dome_capture import DomeCalibration, rgb_linear_image
from recon.calibration.dome_geometric import CameraGeometry, stage_rotation
from recon.calibration.dome_lighting import led_irradiance
from recon.radiometric.demosaic import demosaic
from recon.radiometric.hdr import interpolate_curve
from recon.registration.border import MarksNotFoundError, extract_texture, register_frame
from recon.registration.corners import CornerRefinementError
from recon.registration.sample_plane import sample_square_corners, texel_centres_m

__all__ = [
    "TEXEL_FOOTPRINT",
    "Registration",
    "TexelGrid",
    "band_reflectance",
    "register_view",
    "rgb_alignment_image",
    "white_balanced_rgb",
]


TEXEL_FOOTPRINT = 4
"""Samples per side of a texel's square where a frame is resampled onto the texels
(:func:`recon.registration.border.extract_texture`'s ``footprint``): the frame averaged over the
texel instead of interpolated at its centre, as the twin's truth averages the material over
it. On the dome study's 64-texel stores (BENCHMARKS.md "Dome study from capture stores") the
RGB cameras' white-balanced :math:`V` came out closer to the truth's for every material and
camera (mean Eq. 6.8 over the material texels, top / 37.5 / 75 degree camera: colour checker
22.1 / 27.1 / 50.5 % at the centre only, 19.5 / 21.8 / 48.2 % over the footprint; wallpaper
4.3 / 10.8 / 19.4 to 4.2 / 9.9 / 18.9 %; Lego 36.7 / 57.5 to 32.3 / 53.6 %; red fabric 84.1 /
129.2 / 364.4 to 78.2 / 116.7 / 356.5 %)."""


@dataclass(frozen=True)
class Registration:
    """One camera at one stage position: the marks found and expected, the sample's corners.

    Attributes
    ----------
    marks_xy, expected_xy
        ``(4, 2)`` the registration corners found in the alignment frame (or given in a
        manual corner file) and where the calibrated camera projects them.
    corners_xy
        ``(4, 2)`` the sample's square on the plate, the texture's corners in the frame.
    found
        Whether the marks were found (or given); ``False``: ``marks_xy`` is the projection.
    """

    marks_xy: np.ndarray
    expected_xy: np.ndarray
    corners_xy: np.ndarray
    found: bool

    @property
    def marks_offset_px(self) -> float:
        """Largest distance between a mark found and its calibrated projection."""
        return float(np.linalg.norm(self.marks_xy - self.expected_xy, axis=1).max())


def register_view(
    image: np.ndarray,
    geometry: CameraGeometry,
    holder: DomeHolder,
    stage_deg: float,
    sample_size_m: float,
    *,
    frame_id: str,
    manual_corners: Mapping[str, np.ndarray] | None = None,
) -> Registration:
    """Register a linear alignment frame ``image`` of a camera at ``stage_deg`` (module
    docstring); ``manual_corners`` (keyed ``frame_id``) replace the detection of marks. Where
    the marks are not found (a steep view leaves the print a pixel or two wide) the calibrated
    camera's projection of them stands in."""
    marks_m = np.asarray(holder.registration_corners_m, np.float64)
    expected = geometry.project(marks_m @ stage_rotation(stage_deg).T) + 0.5
    try:
        marks, found = (
            register_frame(
                image, frame_id=frame_id, manual_corners=manual_corners, expected_xy=expected
            ),
            True,
        )
    except (MarksNotFoundError, CornerRefinementError):
        marks, found = expected, False
    corners = sample_square_corners(
        marks, marks_m, geometry.position_in_sample(stage_deg), sample_size_m
    )
    return Registration(marks, expected, corners, found)


def rgb_alignment_image(calibration: RgbCameraCalibration, frame: np.ndarray) -> np.ndarray:
    """A linear grey image of an RGB camera's raw frame, for finding the marks."""
    linear = interpolate_curve(calibration.inverse_response, np.asarray(frame, np.float64))
    return demosaic(linear, method="bilinear").mean(axis=-1)


@dataclass(frozen=True)
class TexelGrid:
    """The texels of the sample at one stage position: their centres in the world frame."""

    texels: int
    sample_size_m: float
    stage_deg: float

    def world_points(self) -> np.ndarray:
        """``(texels, texels, 3)`` texel centres on the plate, turned by the stage."""
        plate = texel_centres_m(self.texels, self.sample_size_m)
        points = np.concatenate([plate, np.zeros((*plate.shape[:2], 1))], axis=-1)
        return points @ stage_rotation(self.stage_deg).T

    def texture(self, image: np.ndarray, corners_xy: np.ndarray) -> np.ndarray:
        """``image`` (``(H, W)`` or ``(H, W, K)``) averaged over every texel's footprint in it
        (:data:`TEXEL_FOOTPRINT`), the sample's square at ``corners_xy``."""
        return extract_texture(image, corners_xy, resolution=self.texels, footprint=TEXEL_FOOTPRINT)

    def irradiance(self, led_position_m: np.ndarray) -> np.ndarray:
        """``(texels, texels)`` the LED's irradiance per unit intensity at every texel."""
        return led_irradiance(self.world_points(), led_position_m)


def white_balanced_rgb(
    calibration: DomeCalibration,
    camera: str,
    frames: np.ndarray,
    corners_xy: np.ndarray,
    grid: TexelGrid,
    led: int,
    led_position_m: np.ndarray,
) -> np.ndarray:
    """:math:`V` ``(texels, texels, 3)`` of one RGB image from its raw HDR set ``(n, 2H, 2W)``
    in the order of the calibration's exposure set (module docstring). Texels saturated in
    every exposure (highlights) are NaN."""
    image = rgb_linear_image(calibration.rgb[camera], frames)
    saturated = ~np.isfinite(image)
    texture = grid.texture(np.where(saturated, 0.0, image), corners_xy)
    if saturated.any():  # a texel that samples a pixel saturated in every exposure is one too
        touched = grid.texture(saturated.astype(float), corners_xy)
        texture = np.where(touched > 0, np.nan, texture)
    white = calibration.rgb_white[camera][calibration.led_index(led)]
    return texture / (white * grid.irradiance(led_position_m)[..., None])


def band_reflectance(
    calibration: DomeCalibration,
    frame: np.ndarray,
    exposure_s: float,
    band: int,
    corners_xy: np.ndarray,
    grid: TexelGrid,
    led: int,
    led_position_m: np.ndarray,
) -> np.ndarray:
    """Noisy reflectance factors ``(texels, texels)`` of band ``band`` from one raw frame of
    the spectral camera (module docstring): :math:`E_\\lambda L_\\lambda` from the white
    standard under the calibration LED, the LED's irradiance from the white standard under
    ``led`` in the reference band."""
    spectral = calibration.spectral
    rate = grid.texture(spectral.linear_rate(frame, exposure_s), corners_xy)
    reference = int(np.argmin(np.abs(calibration.bands_nm - calibration.reference_band_nm)))
    per_irradiance = calibration.spectral_white[calibration.led_index(led)] / (
        spectral.sensitivity[reference]
        * calibration.led_per_band[reference]
        * calibration.white_per_band[reference]
    )
    sensitivity = spectral.sensitivity[band] * calibration.led_per_band[band]
    return rate / (sensitivity * per_irradiance * grid.irradiance(led_position_m))
