"""Sparse sampling protocols of thesis chapter 7 (recon.experiments.sampling) and the real Llanos
2019
multispectral image (recon.measured_data.read_llanos2019_multispectral)."""

from pathlib import Path

import numpy as np
import pytest
from scipy import io
from skimage import measure

from recon.errors import InputError, MissingDataError, Remedy
from recon.experiments.sampling import (
    add_rgb_noise,
    exclude_region,
    grid_layout,
    known_spectra_from_mask,
    push_broom_mask,
    spot_mean_spectra,
    whisk_broom_mask,
)
from recon.measured_data import data_path, read_llanos2019_multispectral

TEST_DATA = Path(__file__).resolve().parents[2] / "data"


def _regular_spacing(values: np.ndarray) -> np.ndarray:
    return np.diff(np.unique(np.round(values, 6)))


def test_whisk_broom_places_250_square_spots_on_a_regular_grid():
    mask = whisk_broom_mask((512, 512))
    assert mask.shape == (512, 512) and mask.dtype == bool
    regions = measure.regionprops(measure.label(mask, connectivity=1))
    assert len(regions) == 250
    side = round(0.005 * 512)
    assert side == 3
    for region in regions:
        top, left, bottom, right = region.bbox
        assert (bottom - top, right - left, region.area) == (side, side, side * side)
    centres = np.array([region.centroid for region in regions])
    assert grid_layout((512, 512), 250) == (16, 16)
    for axis in (0, 1):
        spacing = _regular_spacing(centres[:, axis])
        assert spacing.size == 15  # all 16 grid rows and columns are used
        assert spacing.max() - spacing.min() <= 1 and abs(spacing.mean() - 512 / 16) < 0.1
    # Cell centres (i + 1/2) * 32 px, in pixel-index coordinates minus 1/2: within 1/2 px.
    offsets = (centres + 0.5) / 32 - 0.5
    assert np.abs(offsets - np.round(offsets)).max() * 32 <= 0.5


@pytest.mark.parametrize("n_spots", [1, 10, 50, 100, 250, 500, 1000, 2000])
def test_whisk_broom_gives_exactly_the_requested_number_of_spots(n_spots):
    for shape in ((512, 512), (342, 408), (480, 640)):
        labels = measure.label(whisk_broom_mask(shape, n_spots), connectivity=1)
        assert labels.max() == n_spots


def test_grid_layout_follows_the_image_aspect_ratio():
    assert grid_layout((342, 408), 250) == (15, 17)
    assert grid_layout((480, 640), 250) == (14, 18)
    assert grid_layout((100, 400), 100) == (5, 20)
    assert grid_layout((400, 100), 100) == (20, 5)


def test_push_broom_lines_at_a_third_and_two_thirds_of_the_height():
    for height in (512, 342, 100):
        mask = push_broom_mask((height, 64))
        rows = np.flatnonzero(mask.any(axis=1))
        assert rows.tolist() == [round(0.33 * height), round(0.66 * height)]
        assert mask[rows].all() and mask.sum() == 2 * 64


def test_rgb_noise_has_the_requested_sigma_and_leaves_the_input_alone(rng):
    rgb = rng.uniform(0.1, 0.9, (400, 400, 3))
    before = rgb.copy()
    for fraction in (0.005, 0.01, 0.05):
        noisy = add_rgb_noise(rgb, fraction, rng)
        noise = noisy - rgb
        expected = fraction * rgb.mean()
        assert noisy.shape == rgb.shape and noisy is not rgb
        assert noise.std() == pytest.approx(expected, rel=0.01)
        assert abs(noise.mean()) < 5 * expected / np.sqrt(noise.size)
    np.testing.assert_array_equal(rgb, before)
    np.testing.assert_array_equal(add_rgb_noise(rgb, 0.01, 7), add_rgb_noise(rgb, 0.01, 7))
    np.testing.assert_array_equal(add_rgb_noise(rgb, 0.0, 7), rgb)


def test_exclude_region_removes_the_known_pixels_in_the_region():
    mask = whisk_broom_mask((120, 120), 36)
    stripes = np.zeros_like(mask)
    stripes[:, :60] = True
    kept = exclude_region(mask, stripes)
    assert kept.sum() == mask[:, 60:].sum() > 0
    assert not kept[:, :60].any() and np.array_equal(kept[:, 60:], mask[:, 60:])
    with pytest.raises(InputError, match="region: covers all"):
        exclude_region(mask, np.ones_like(mask))
    with pytest.raises(InputError, match="region: expected the mask's shape"):
        exclude_region(mask, stripes[:-1])
    with pytest.raises(InputError, match="region: expected a non-empty 2-D boolean"):
        exclude_region(mask, stripes.astype(int))


def test_known_spectra_come_in_row_major_order(rng):
    image = rng.uniform(size=(6, 5, 4))
    mask = np.zeros((6, 5), dtype=bool)
    mask[[4, 0, 2], [1, 3, 0]] = True
    indices, spectra = known_spectra_from_mask(image, mask)
    assert indices.tolist() == [3, 10, 21]
    np.testing.assert_array_equal(spectra, image[[0, 2, 4], [3, 0, 1]])


def test_spot_means_average_each_spot(rng):
    image = rng.uniform(size=(64, 64, 5))
    mask = whisk_broom_mask((64, 64), 9, spot_fraction=0.05)
    labels, spectra = spot_mean_spectra(image, mask)
    assert spectra.shape == (9, 5)
    for spot in range(9):
        np.testing.assert_allclose(spectra[spot], image[labels == spot + 1].mean(axis=0))


def test_sampling_functions_reject_bad_input(rng):
    with pytest.raises(InputError, match="shape"):
        whisk_broom_mask((0, 10))
    with pytest.raises(InputError, match="shape"):
        whisk_broom_mask((10,))
    with pytest.raises(InputError, match="n_spots"):
        whisk_broom_mask((10, 10), 0)
    with pytest.raises(InputError, match="n_spots"):
        whisk_broom_mask((10, 10), 101)
    with pytest.raises(InputError, match="n_spots: 100 spots of side 2"):
        whisk_broom_mask((10, 10), 100, spot_fraction=0.2)
    for fraction in (0.0, 1.0, -0.1):
        with pytest.raises(InputError, match="spot_fraction"):
            whisk_broom_mask((10, 10), 4, fraction)
    for heights in ((0.33, 1.0), (-0.1,), (), (0.5, 0.501)):
        with pytest.raises(InputError, match="line_heights"):
            push_broom_mask((100, 10), heights)
    rgb = rng.uniform(size=(4, 4, 3))
    with pytest.raises(InputError, match="sigma_fraction"):
        add_rgb_noise(rgb, -0.01, rng)
    with pytest.raises(InputError, match="rgb: expected a positive mean"):
        add_rgb_noise(np.zeros((4, 4, 3)), 0.01, rng)
    with pytest.raises(InputError, match="rgb: expected a non-empty array of finite"):
        add_rgb_noise(np.full((4, 4, 3), np.nan), 0.01, rng)
    image = rng.uniform(size=(6, 5, 4))
    with pytest.raises(InputError, match="mask: expected at least one"):
        known_spectra_from_mask(image, np.zeros((6, 5), dtype=bool))
    with pytest.raises(InputError, match="mask: expected the image's"):
        known_spectra_from_mask(image, np.ones((5, 6), dtype=bool))
    with pytest.raises(InputError, match="spectral_image"):
        spot_mean_spectra(image[..., 0], np.ones((6, 5), dtype=bool))


def test_llanos2019_multispectral_image_and_camera():
    data = read_llanos2019_multispectral()
    assert data.image.shape == (342, 408, 7) and data.image.dtype == np.float64
    assert data.wavelengths_nm.tolist() == [400, 450, 500, 550, 600, 650, 700]
    assert np.all(np.diff(data.wavelengths_nm) > 0)
    assert data.wavelengths_nm.min() >= 400 and data.wavelengths_nm.max() <= 720
    assert np.all(np.isfinite(data.image))
    # The source script clipped the image to zero; the brightest value is 0.953.
    assert data.image.min() == 0.0 and 0.9 < data.image.max() < 1.0
    assert data.sensor_map.shape == (7, 3) and data.response.shape == (7, 3)
    # Sensitivities relative to Green: the Green column is flat by construction, Red peaks at
    # 650 nm, Blue at 450 nm.
    np.testing.assert_allclose(data.sensor_map[:, 1], data.sensor_map[0, 1])
    assert data.wavelengths_nm[np.argmax(data.sensor_map[:, 0])] == 650
    assert data.wavelengths_nm[np.argmax(data.sensor_map[:, 2])] == 450
    rgb = data.image @ data.response
    means = rgb.mean(axis=(0, 1))
    assert np.all(np.isfinite(means / means[1])) and np.all(means > 0)
    # Llanos's own simulated RAW image (GBRG Bayer) from this image and sensor: its Green sites
    # equal image @ response exactly (the demosaiced Green keeps the measured Green samples).
    raw = io.loadmat(TEST_DATA / "llanos2019" / "d2_colorChecker30cm_raw.mat")["I_raw"]
    green = np.concatenate([raw[0::2, 0::2].ravel(), raw[1::2, 1::2].ravel()])
    ours = np.concatenate([rgb[0::2, 0::2, 1].ravel(), rgb[1::2, 1::2, 1].ravel()])
    np.testing.assert_allclose(ours, green, rtol=0, atol=1e-6)
    # Its Red and Blue sites came from a differently made image: close, not equal.
    for channel, (row, col) in ((0, (1, 0)), (2, (0, 1))):
        correlation = np.corrcoef(raw[row::2, col::2].ravel(), rgb[row::2, col::2, channel].ravel())
        assert correlation[0, 1] > 0.95


def test_missing_shipped_data_raises_with_the_path():
    with pytest.raises(MissingDataError, match="real/nosuch.mat is missing .* package") as missing:
        data_path("real/nosuch.mat")
    assert missing.value.remedy is Remedy.reinstall
