"""The dome's spectral side end to end on the twin (thesis 10.3-10.4.1): low-SNR calibration from
simulated raw frames, the exposure plan, and single-image spectralization of virtual captures.

Sizes: 32 texels of 8 x 8 camera pixels each (a 4 cm sample at 0.098 mm per pixel would give
about 12 x 12 at this texel count; 8 keeps the test fast).
"""

from __future__ import annotations

import numpy as np
import pytest

from recon.calibration.dome import DARK_VALUE_OFFSET, curve_linearity
from recon.errors import InputError
from recon.scheduling.dome_schedule import THESIS_RGB_EXPOSURES_S
from twin.dome.capture_study import (
    ReconstructionErrors,
    dome_light_directions,
    reconstruct_capture,
    simulate_capture,
)
from twin.dome.setup import SPECTRAL_VIEW, THESIS_LONGEST_BAND_S, dome_setup
from twin.render.truth import texture_truth
from twin.studies.dome import (
    cross_check,
    exposure_comparison,
    metamer_diagnosis,
    multi_image,
    schedules,
    single_image,
)

TEXELS = 32
LED = 40  # polar 26 degrees, away from the spectral camera's mirror direction


@pytest.fixture(scope="module")
def setup():
    return dome_setup(TEXELS, sample_size_m=TEXELS * 8 * 0.2 / 2048)


def test_low_snr_response_is_recovered_linear_with_its_zero_at_the_dark_level(setup):
    """Eq. 10.4-10.8 on frames whose brightest field reaches about 400 DN above the offset:
    the curve is a straight line through the dark level (the K4 model is linear)."""
    curve = setup.spectral.inverse_response
    low, high = setup.spectral.observed_levels
    assert low <= DARK_VALUE_OFFSET + 5 and high > DARK_VALUE_OFFSET + 300
    observed = np.full(curve.shape, np.nan)
    observed[low : high + 1] = curve[low : high + 1]
    assert curve_linearity(observed, DARK_VALUE_OFFSET) < 0.02


def test_sensitivity_is_the_white_rate_over_the_led(setup):
    """Thesis 10.3: sensitivity = linearized white response / LED spectrum. Its shape must be
    the model's (electrons per unit LED intensity), up to the curve's unit."""
    _, white_rates = setup.cameras.white_rates()
    from twin.components.targets import zenith_white_reflectance
    from twin.dome.setup import BAND_GRID

    model = white_rates / (setup.led_per_band * zenith_white_reflectance(BAND_GRID).values)
    ratio = setup.spectral.sensitivity / model
    assert np.ptp(ratio) / ratio.mean() < 0.01


def test_rgb_hdr_is_linear_down_to_one_percent_reflectance(setup, rng):
    """Four exposures merged (Eq. 10.3), dark-subtracted, white-balanced: flat greys read their
    reflectance to 1.5 %. Without the dark subtraction 1 % grey read 1.85 (red)."""
    white_rgb, _ = setup.cameras.white_rates()
    for grey in (0.9, 0.2, 0.05, 0.01):
        rates = np.broadcast_to(grey * white_rgb, (TEXELS, TEXELS, 3))
        frames = setup.cameras.rgb_frames(rates, np.array(THESIS_RGB_EXPOSURES_S), rng)
        value = setup.rgb.white_balanced(frames, 1.0, texel_px=8).reshape(-1, 3).mean(0)
        np.testing.assert_allclose(value / grey, 1.0, atol=0.015)


def test_plan_follows_the_thesis_rule(setup):
    support = setup.spectral.sensitivity * setup.led_per_band
    product = setup.exposures_s * np.sqrt(support)
    np.testing.assert_allclose(product, product[0], rtol=1e-9)
    # The longest band is a calibration input (thesis +61 %, twin.dome.setup), the base of the
    # plan: t_lambda = t_longest sqrt(min E L / E L).
    np.testing.assert_allclose(
        setup.exposures_s, THESIS_LONGEST_BAND_S * np.sqrt(support.min() / support), rtol=1e-9
    )
    # Fig. 10.5: the noisier the band, the larger its filter.
    order = np.argsort(setup.relative_noise)
    assert np.all(np.diff(setup.filter_sigma()[order]) >= -1e-9)


@pytest.fixture(scope="module")
def single_images(setup):
    rng = np.random.default_rng(5)
    light = dome_light_directions(setup, [LED])
    results = {}
    for material in ("wallpaper", "colorchecker16", "red_fabric"):
        truth = texture_truth(material, light, SPECTRAL_VIEW[None], texels=TEXELS)
        capture = simulate_capture(setup, truth, light, [list(range(30))], rng)
        cube = reconstruct_capture(setup, capture)
        results[material] = ReconstructionErrors.of(cube, capture.truth).summary()
    return results


def test_single_image_reconstruction_meets_the_thesis_quality(single_images):
    """Thesis 10.4.1 / Fig. 10.7-10.8: errors concentrated below Delta E94 = 1."""
    for material in ("wallpaper", "colorchecker16"):
        summary = single_images[material]
        assert summary["mean_delta_e94"] < 1.5, material
        assert summary["mean_relative_error_pct"] < 5.0, material


def test_red_fabric_is_the_worst(single_images):
    """Thesis 10.4.2.1: the red fabric, full of metamers for the dome camera, is worse."""
    red = single_images["red_fabric"]["mean_relative_error_pct"]
    assert red > single_images["colorchecker16"]["mean_relative_error_pct"]
    assert red > single_images["wallpaper"]["mean_relative_error_pct"]


def test_capture_needs_a_band_list_per_image(setup):
    light = dome_light_directions(setup, [LED])
    truth = texture_truth("wallpaper", light, SPECTRAL_VIEW[None], texels=4)
    with pytest.raises(InputError, match="bands_per_image"):
        simulate_capture(setup, truth, light, [[0], [1]], np.random.default_rng(0))


# -- the chapter 10 experiments (twin.studies.dome) ------------------------------------------------


def test_schedules_for_the_thesis_parameters(setup):
    """Thesis 10.4: 30 bands in 8 images at +41 %, 10 images with the noisiest twice at +61 %.
    The twin's bands sum to 48 s (the thesis's to about 38 s), so 8 images are spectral-bound
    (measured +77 %) and 10 images hold the 410 nm band twice (measured +57 %): the totals are
    the band sum and the band sum plus the repeated band."""
    plans = schedules(setup)
    band_sum, rgb_s = plans["band_exposures_sum_s"], sum(THESIS_RGB_EXPOSURES_S)
    assert band_sum == pytest.approx(setup.exposures_s.sum())
    assert plans["8_images"]["increase_pct"] == pytest.approx(
        100 * (band_sum / (8 * rgb_s) - 1), rel=1e-6
    )
    assert plans["10_images"]["repeated_bands_nm"] == [410.0]
    with_repeat = band_sum + setup.exposures_s[0]  # 410 nm twice
    assert plans["10_images"]["increase_pct"] == pytest.approx(
        100 * (with_repeat / (10 * rgb_s) - 1), rel=1e-6
    )
    assert sorted(b for image in plans["8_images"]["images"] for b in image) == list(range(30))


def test_multi_image_without_bands_is_only_slightly_worse(setup):
    """Thesis 10.4.2, finding 2: the 10 images without spectral data are only slightly worse
    than the 10 at 45 degrees that carry the scheduled bands."""
    _, _, result = multi_image(setup, "colorchecker16", np.random.default_rng(7))
    with_bands = result["with_spectral_data"]["mean_relative_error_pct"]
    without = result["without_spectral_data"]["mean_relative_error_pct"]
    assert with_bands < 5.0
    assert with_bands <= without < with_bands + 1.5


@pytest.fixture(scope="module")
def per_pixel():
    """The dome imaging each texel with one Bayer quad (2 x 2 spectral-camera pixels)."""
    return dome_setup(TEXELS, texel_px=2)


def test_red_fabric_is_the_worst_per_pixel(per_pixel):
    """Thesis 10.4.2.1 where the thesis works, at camera pixels: the red fabric has the largest
    median relative error and Delta E94 of the four materials (the Lego's mean is pulled up by
    its near-black stud shadows). The diagnosis: its RGB appearance links are the farthest
    apart and its 600 nm band's filter keeps the least of its structure (measured 31 % against
    74-89 %; Fig. 10.21)."""
    rng = np.random.default_rng(6)
    results = {}
    for material in ("lego", "wallpaper", "colorchecker16", "red_fabric"):
        single = single_image(per_pixel, material, rng, leds=(LED,))
        results[material] = (
            single.summary(),
            metamer_diagnosis(per_pixel, single.captures[0]),
        )
    red_errors, red_links = results.pop("red_fabric")
    for material, (errors, links) in results.items():
        for key in ("median_relative_error_pct", "mean_delta_e94"):
            assert red_errors[key] > errors[key], (material, key)
        assert red_links["structure_kept_600nm_pct"] < links["structure_kept_600nm_pct"]
        assert red_links["median_rgb_link_distance_pct"] > links["median_rgb_link_distance_pct"], (
            material
        )


def test_hybrid_capture_is_one_and_a_half_orders_faster_than_the_reference(per_pixel):
    """Thesis 10.5 (7.5 s instead of 226 s, Fig. 10.24) in its per-pixel regime (one Bayer quad
    per texel). The reference brings the white to 80 % of saturation in every band (1766 s,
    1.3 %); the hybrid at the plan's exposures (51.4 s) reconstructs to 4.4 % (Delta E94 0.8),
    1.5 orders of magnitude faster, where the same noisy bands used as they are are off by 17 %.
    At equal error, spectral-only frames need 6x the hybrid's time (measured 325 s)."""
    result = exposure_comparison(
        per_pixel, "colorchecker16", np.random.default_rng(8), hybrid_scales=(1.0,)
    )
    (hybrid,) = result["hybrid"]
    assert result["pixels_per_texel"] == 2
    assert 1.3 < np.log10(result["reference_total_s"] / hybrid["total_s"]) < 1.7
    assert result["reference_error_pct"] < hybrid["error_pct"] < 5.0
    assert result["reference_delta_e94"] < hybrid["delta_e94"] < 1.0
    assert hybrid["direct_error_pct"] > 3 * hybrid["error_pct"]
    assert hybrid["equal_error_spectral_only_s"] > 3 * hybrid["total_s"]
    errors = result["spectral_only_errors_pct"]
    assert np.all(np.diff(errors) > 0)  # less light, more error: the curve the hybrid is set on


def test_pixels_per_texel_must_be_whole_bayer_quads():
    with pytest.raises(InputError, match="texel_px: expected an even number"):
        dome_setup(TEXELS, texel_px=3)


def test_a_calibration_needs_a_dark_frame_per_exposure_time():
    with pytest.raises(InputError, match="dark_frames: expected at least 1 per exposure time"):
        dome_setup(TEXELS, dark_frames=0)


def test_calibration_cross_check_fig_10_4(setup):
    """RGB predicted from the calibrated spectral image matches the measured RGB per field."""
    check = cross_check(setup, np.random.default_rng(9))
    assert check["mean_abs_field_difference_pct"] < 2.0
