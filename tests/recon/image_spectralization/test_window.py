"""The central window a large image is cross-validated in
(:mod:`recon.image_spectralization.window`), and ``spectralize_image`` with it on real
reflectances."""

from __future__ import annotations

import numpy as np
import pytest

from recon.errors import InputError
from recon.image_spectralization import window as window_module
from recon.image_spectralization.run import spectralize_image
from recon.image_spectralization.window import MIN_WINDOW_SPOTS, cross_validation_window
from recon.metrics import relative_error
from tests.recon.whisk_broom import blend_with_spots


def _grid_spots(shape: tuple[int, int], step: int) -> np.ndarray:
    rows, cols = np.mgrid[step // 2 : shape[0] : step, step // 2 : shape[1] : step]
    return np.ravel_multi_index((rows.ravel(), cols.ravel()), shape)


def test_the_window_is_centred_of_the_image_shape_and_about_the_pixels_asked():
    window = cross_validation_window((600, 900), _grid_spots((600, 900), 10), 60_000)
    assert (window.height, window.width) == (200, 300)
    assert (window.row, window.col) == (200, 300)
    assert not window.whole
    assert window.describe() == "the central 300 x 200 px"


def test_the_window_grows_until_it_holds_enough_spots():
    """A spot every 20 px: the 100 x 100 window asked holds 25; its sides grow by a quarter
    (125, 156, 195, 244, 305, 381 px: at most 361 spots) to 477 px, which holds 576."""
    shape = (1000, 1000)
    spots = _grid_spots(shape, 20)
    window = cross_validation_window(shape, spots, 10_000)
    mask = np.zeros(shape, bool)
    mask.flat[spots] = True
    assert (window.height, window.width) == (477, 477)
    assert int(mask[window.slices].sum()) == 576 >= MIN_WINDOW_SPOTS
    previous = type(window)(309, 309, 381, 381, shape)
    assert int(mask[previous.slices].sum()) == 361 < MIN_WINDOW_SPOTS


@pytest.mark.parametrize("pixels", [None, 1_000_000, 2_000_000])
def test_the_whole_image_when_no_window_or_a_larger_one_is_asked(pixels):
    window = cross_validation_window((1000, 1000), _grid_spots((1000, 1000), 10), pixels)
    assert window.whole and window.describe() == "the whole image"


def test_a_window_of_no_pixels_is_refused():
    with pytest.raises(InputError, match="cross-validation pixels: expected a positive count"):
        cross_validation_window((100, 100), np.arange(10), 0)


def test_inside_and_local_index_the_windows_pixels(monkeypatch):
    monkeypatch.setattr(window_module, "MIN_WINDOW_SPOTS", 100)
    rng = np.random.default_rng(0)
    image = rng.random((60, 80, 3))
    pixels = rng.choice(60 * 80, 800, replace=False)
    window = cross_validation_window((60, 80), pixels, 1200)
    inside = window.inside(pixels)
    rows, cols = np.divmod(pixels, 80)
    assert 0 < inside.sum() < pixels.size
    assert np.all((rows[inside] >= 15) & (rows[inside] < 45) & (cols[inside] >= 20))
    local = window.local(pixels[inside])
    np.testing.assert_array_equal(
        image[window.slices].reshape(-1, 3)[local], image.reshape(-1, 3)[pixels[inside]]
    )


@pytest.fixture(scope="module")
def clothes_blend():
    """The real VHREL clothes reflectances' smooth blend at 128 px, a spot at every 64th pixel
    (256) of its true spectra, 1 % RGB noise: ``(truth, rgb, spots, response, mask)``."""
    return blend_with_spots("vhrel_clothes blend", 128, 256, noise=0.01)


def test_a_window_chooses_as_the_whole_image_and_reconstructs_as_well(clothes_blend, monkeypatch):
    """With at least 100 spots in a window (a small image's stand-in for a large one's 500),
    the central quarter asked (64 x 64 px, 64 spots) grows to 80 x 80 px to hold 100 of the
    256 spots; the space and prior it chooses are those the whole image
    chooses, the kriging weight about the same, and the image is then reconstructed about as
    well. Measured: the learned space and the thesis's prior both, weight 0.55 against 0.45,
    2.52 % mean Eq. 6.8 off the spots against 2.39 %; cross-validation 2.4 s against 5.8 s."""
    monkeypatch.setattr(window_module, "MIN_WINDOW_SPOTS", 100)
    truth, rgb, spots, response, mask = clothes_blend
    whole = spectralize_image(rgb, spots, response, cross_validation_pixels=None)
    windowed = spectralize_image(rgb, spots, response, cross_validation_pixels=64 * 64)
    assert (windowed.appearance, windowed.prior) == (whole.appearance, whole.prior)
    errors = [float(relative_error(r.cube, truth)[~mask].mean()) for r in (whole, windowed)]
    assert errors[1] == pytest.approx(errors[0], rel=0.1)
    assert abs(windowed.kriging_weight - whole.kriging_weight) <= 0.15
    inside = np.isfinite(windowed.spot_errors)
    assert inside.sum() == 100 and np.all(np.isfinite(whole.spot_errors))
    assert any("the central 80 x 80 px (100 of 256 spot pixels" in note for note in windowed.notes)
    assert {"cross_validation", "graph", "solve"} <= set(windowed.timings_s)
    assert windowed.held_out_errors["blend"] == pytest.approx(
        float(np.mean(windowed.spot_errors[inside]))
    )
