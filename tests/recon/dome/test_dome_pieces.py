"""Pieces of the dome's processing against closed forms: the sample's square through the marks'
homography, the LED's field, the band filters' sizes, the joint groups, :math:`R_{cam}`."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage
from skimage.registration import phase_cross_correlation

from recon.calibration.dome_geometric import CameraGeometry
from recon.calibration.dome_lighting import field_scale, led_irradiance
from recon.calibration.dome_spectra import band_response
from recon.dome.processing import (
    TARGET_RELATIVE_NOISE,
    ParallaxLine,
    band_sigma_px,
    band_weight,
    parallax_shift,
)
from recon.dome.run import joint_groups
from recon.errors import InputError
from recon.registration.border import extract_texture
from recon.registration.corners import shifted_corners
from recon.registration.sample_plane import sample_square_corners
from recon.spectra import WavelengthGrid


def _oblique_camera() -> CameraGeometry:
    """A pinhole 0.75 m away, 60 degrees from the normal (OpenCV's conventions)."""
    position = 0.75 * np.array([np.sin(np.radians(60)), 0.0, np.cos(np.radians(60))])
    forward = -position / np.linalg.norm(position)
    right = np.array([0.0, -1.0, 0.0])
    down = np.cross(forward, right)
    matrix = np.array([[4000.0, 0, 131.5], [0, 4000.0, 131.5], [0, 0, 1]])
    return CameraGeometry(matrix, np.zeros(5), np.stack([right, down, forward]), position)


def test_sample_square_is_the_plates_square_seen_through_the_raised_marks():
    """Marks 0.22 mm above the plate, projected by a pinhole at 60 degrees: the square's
    corners on the plate come out where the camera projects them, to 1e-9 px; taking the
    marks' plane for the plate would put them 0.38 mm (1.2 px here) off."""
    camera = _oblique_camera()
    half, height, side = 0.0265, 0.00022, 0.04
    marks = np.array([[-half, half, height], [half, half, height], [half, -half, height]])
    marks = np.vstack([marks, [-half, -half, height]])
    corners = sample_square_corners(camera.project(marks) + 0.5, marks, camera.position_m, side)
    square = np.array([[-1, 1, 0], [1, 1, 0], [1, -1, 0], [-1, -1, 0]]) * side / 2
    np.testing.assert_allclose(corners, camera.project(square) + 0.5, atol=1e-9)
    flat = sample_square_corners(
        camera.project(marks) + 0.5, marks * [1, 1, 0], camera.position_m, side
    )
    assert np.abs(flat - corners).max() > 1.0


def test_sample_square_refuses_a_camera_below_the_marks():
    marks = np.array([[-1.0, 1, 0.1], [1, 1, 0.1], [1, -1, 0.1], [-1, -1, 0.1]])
    image = np.array([[0.0, 0], [10, 0], [10, 10], [0, 10]])
    with pytest.raises(InputError, match="below a camera"):
        sample_square_corners(image, marks, np.array([0.0, 0, 0.05]), 1.0)


def test_led_irradiance_falls_with_distance_and_cosine():
    """A point light 0.75 m above: on the axis 1 / r^2; 4 cm aside cos / r^2 = z / r^3."""
    led = np.array([0.0, 0.0, 0.75])
    points = np.array([[0.0, 0, 0], [0.04, 0, 0]])
    expected = [1 / 0.75**2, 0.75 / np.hypot(0.75, 0.04) ** 3]
    np.testing.assert_allclose(led_irradiance(points, led), expected)
    field = led_irradiance(np.random.default_rng(1).random((5, 5, 3)) * [0.02, 0.02, 0], led)
    values = np.stack([2.0 * field, 3.0 * field], axis=-1)
    np.testing.assert_allclose(field_scale(values, field), [2.0, 3.0])


def test_band_filter_follows_the_noise_of_the_image(rng):
    """White noise of 30 % on a field with a sharp edge: the filter's sigma is the one
    :func:`recon.scheduling.dome_schedule.filter_sizes` gives for the noise (within 10 %), not
    for the edge."""
    clean = np.where(np.arange(64)[None, :] < 32, 0.2, 0.6) * np.ones((64, 1))
    noisy = clean + rng.normal(0, 0.3 * clean.mean(), clean.shape)
    expected = 0.3 / (2 * np.sqrt(np.pi) * TARGET_RELATIVE_NOISE)  # Figure 10.5's rule
    assert band_sigma_px(noisy) == pytest.approx(expected, rel=0.1)
    assert band_sigma_px(clean) == 0.0


def test_band_weight_is_the_noise_over_noise_and_misregistration():
    """On a uniform image every texel weighs 1; beside a step from 0.1 to 0.5 the brightness
    changes by (0.5 - 0.1) / 2 / 0.1 = 2 per texel on the dark side, so 0.25 texels of
    misregistration err by 50 % against the filters' 4 %: weight 1 / sqrt(1 + 12.5^2)."""
    assert np.all(band_weight(np.full((6, 6, 3), 0.3)) == 1.0)
    step = np.where(np.arange(6)[None, :, None] < 3, 0.1, 0.5) * np.ones((6, 1, 3))
    weight = band_weight(step, 0.25, 0.04)
    assert weight[2, 2] == pytest.approx(1 / np.sqrt(1 + 12.5**2))
    assert weight[2, 3] == pytest.approx(1 / np.sqrt(1 + (0.25 * 0.4 / 0.04) ** 2))
    assert weight[2, 0] == 1.0 and weight[2, 5] == 1.0
    assert np.all(band_weight(step, 0.5, 0.04) <= weight)
    assert band_weight(step, 0.0) is None


def test_a_shifted_square_rectifies_what_shifting_the_texture_gives(rng):
    """Rectifying at :func:`shifted_corners` equals rectifying and then shifting the texture
    with :func:`scipy.ndimage.shift` where the shift is whole texels; by half a texel the
    shift's interpolation averages neighbours, rectifying once keeps the texture's contrast."""
    frame = ndimage.gaussian_filter(rng.random((80, 80)), 1.0)
    corners = np.array([[12.0, 10], [66, 14], [68, 70], [10, 64]])
    texture = extract_texture(frame, corners, resolution=16)
    inner = (slice(3, -3), slice(3, -3))
    for shift in (np.array([2.0, -1.0]), np.array([-1.0, 3.0])):
        once = extract_texture(frame, shifted_corners(corners, shift, 16), resolution=16)
        np.testing.assert_allclose(once[inner], ndimage.shift(texture, shift, order=1)[inner])
    half = np.array([0.5, 0.5])
    once = extract_texture(frame, shifted_corners(corners, half, 16), resolution=16)
    twice = ndimage.shift(texture, half, order=1)
    assert once[inner].std() > 1.2 * twice[inner].std()
    assert once[inner].std() == pytest.approx(texture[inner].std(), rel=0.2)


LINE = ParallaxLine(np.array([0.1, -0.2]), np.array([-400.0, 300.0]))
"""A parallax line as the dome's 37.5 degree camera and spectral camera give at 64 texels:
0.4 texels up and 0.3 right a millimetre of height."""


def test_parallax_shift_recovers_a_translation_along_the_line(rng):
    """Two views of one texture (the spectral camera's and its partner's), the surface 5 mm
    above the plate: the shift found is the line's at 5 mm (-1.9, 1.3 texels)."""
    texture = ndimage.gaussian_filter(rng.random((64, 64)), 1.0)
    spectral = ndimage.shift(texture, -LINE.shift(0.005), order=3, mode="wrap")
    found = parallax_shift(texture, spectral, LINE)
    np.testing.assert_allclose(found, LINE.shift(0.005), atol=0.05)


def test_parallax_shift_on_a_small_texture_tries_the_shorter_shifts(rng):
    """At 16 texels the line's shifts up to 20 mm reach 8 texels: only those up to a quarter of
    the side (4 texels) are tried, so that half the texture is compared; the surface 2 mm up
    (-0.7, 0.4 texels) is found."""
    texture = ndimage.gaussian_filter(rng.random((16, 16)), 1.0)
    spectral = ndimage.shift(texture, -LINE.shift(0.002), order=3, mode="wrap")
    np.testing.assert_allclose(parallax_shift(texture, spectral, LINE), [-0.7, 0.4], atol=0.1)


def test_parallax_shift_is_not_fooled_by_a_repeating_texture():
    """A weave-like texture that repeats every 5 texels across and 16 down, each view with
    its own small detail (shading, noise): shifted by (-1.2, 1.0) it correlates about as well
    a period away, where the unconstrained peak of phase correlation lands here (16 texels off
    in rows; on the twin's red fabric at 64 texels it was 11 off in columns); the search along
    the parallax line does not."""
    rng = np.random.default_rng(4)
    rows, columns = np.mgrid[0:64, 0:64]
    weave = np.sin(2 * np.pi * columns / 5) + 0.3 * np.sin(2 * np.pi * rows / 16)
    partner, other = (
        weave + 0.3 * ndimage.gaussian_filter(rng.standard_normal((64, 64)), 1.0) for _ in "ab"
    )
    spectral = ndimage.shift(other, [1.2, -1.0], order=3, mode="wrap")
    line = ParallaxLine(np.zeros(2), np.array([-1.2, 1.0]) / 0.003)
    np.testing.assert_allclose(parallax_shift(partner, spectral, line), [-1.2, 1.0], atol=0.1)
    unconstrained = phase_cross_correlation(
        partner, spectral, upsample_factor=10, normalization=None
    )[0]
    assert np.abs(unconstrained - [-1.2, 1.0]).max() > 5


def test_joint_groups_follow_the_schedule_cycles():
    bands = [[0, 1], [2], [3], [0], [1, 2], [3], [0]]
    assert joint_groups(bands, 3, 4) == [[0, 1, 2], [3, 4, 5, 6]]
    assert joint_groups(bands[:6], 3, 4) == [[0, 1, 2], [3, 4, 5]]
    with pytest.raises(InputError):
        joint_groups([], 3, 4)


def test_band_response_reads_one_on_the_white_standard():
    """:math:`R_{cam}` of a camera whose channels see one band each: a unit white reads one in
    every channel, a colour by its band; a brighter LED band weighs more."""
    bands = WavelengthGrid.regular(410, 690, 10)
    channels = np.stack(
        [np.exp(-0.5 * ((bands.wavelengths_nm - centre) / 20) ** 2) for centre in (600, 540, 450)]
    ).T
    response = band_response(channels, np.ones(bands.size), np.ones(bands.size))
    np.testing.assert_allclose(np.ones(bands.size) @ response, 1.0)
    red = (bands.wavelengths_nm > 580).astype(float)
    assert np.argmax(red @ response) == 0
    blue_led = np.where(bands.wavelengths_nm < 500, 4.0, 1.0)
    assert (red @ band_response(channels, blue_led, np.ones(bands.size)))[2] < (red @ response)[2]
