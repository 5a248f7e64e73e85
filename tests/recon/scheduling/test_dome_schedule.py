"""Exposure plan, filter sizes and band schedule of the dome (thesis 10.4, Figure 10.5)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy import ndimage

from recon.errors import InputError
from recon.scheduling.dome_schedule import (
    FILTER_SIZE_PER_SIGMA,
    THESIS_RGB_EXPOSURES_S,
    fewest_images,
    filter_sizes,
    gaussian_noise_factor,
    schedule_bands,
    spectral_exposures,
)


def brute_force_total(exposures, n_images, rgb_s, limit=None):
    """Least total over every assignment of exposures to images (None if none fits)."""
    assignments = np.array(list(itertools.product(range(n_images), repeat=len(exposures))))
    loads = np.stack([(assignments == image) @ exposures for image in range(n_images)], axis=1)
    if limit is not None:
        loads = loads[loads.max(axis=1) <= limit + 1e-12]
    return np.maximum(loads, rgb_s).sum(axis=1).min() if len(loads) else None


# -- exposure times ---------------------------------------------------------------------------


def test_exposures_scale_as_one_over_the_square_root_of_sensitivity_times_light():
    sensitivity = np.array([0.5, 2.0, 1.0, 0.02])
    light = np.array([2.0, 4.0, 0.25, 0.5])
    exposures = spectral_exposures(1.5, sensitivity, light)
    assert np.allclose(exposures * np.sqrt(sensitivity * light), 1.5, rtol=1e-14)
    assert exposures.tolist() == pytest.approx([1.5, 1.5 / np.sqrt(8), 3.0, 15.0])
    # Four times the light halves the exposure: the signal grows only as sqrt(E L).
    assert np.allclose(spectral_exposures(1.5, sensitivity, 4 * light), exposures / 2)
    clipped = spectral_exposures(1.5, sensitivity, light, limits_s=(0.6, 10.0))
    assert clipped.tolist() == pytest.approx([1.5, 0.6, 3.0, 10.0])


@pytest.mark.parametrize(
    ("arguments", "keywords", "message"),
    [
        ((-1.0, [1.0, 2.0], [1.0, 1.0]), {}, "base_s: expected a finite, positive number"),
        ((float("nan"), [1.0], [1.0]), {}, "base_s: expected a finite, positive number"),
        ((1.0, [1.0, -2.0], [1.0, 1.0]), {}, "sensitivity: expected positive values"),
        ((1.0, [1.0, 2.0], [1.0, np.nan]), {}, "light: expected finite values, found NaN"),
        ((1.0, [1.0, 2.0], [1.0, 1.0, 1.0]), {}, r"light: expected .* shape \(2,\)"),
        ((1.0, [[1.0, 2.0]], [1.0, 1.0]), {}, "sensitivity: expected one value per band"),
        ((1.0, [1.0], [1.0]), {"limits_s": (2.0, 1.0)}, "limits_s: expected"),
    ],
)
def test_exposure_input_errors_name_the_argument(arguments, keywords, message):
    with pytest.raises(InputError, match=message):
        spectral_exposures(*arguments, **keywords)


# -- filter sizes -----------------------------------------------------------------------------


@pytest.mark.parametrize("truncate", [4.0, 3.0])  # scipy's default; recon.spectralize.energy uses 3
@pytest.mark.parametrize("sigma_px", [0.8, 1.0, 2.0, 3.0])
def test_noise_factor_matches_scipy_gaussian_filter_on_white_noise(sigma_px, truncate):
    noise = np.random.default_rng(7).standard_normal((1024, 1024))
    filtered = ndimage.gaussian_filter(noise, sigma_px, truncate=truncate, mode="wrap")
    measured = filtered.std() / noise.std()
    assert measured == pytest.approx(float(gaussian_noise_factor(sigma_px)), rel=0.02)


def test_noise_factor_overstates_the_reduction_of_a_sub_pixel_kernel():
    # The documented limit: at sigma = 0.5 px the sampled kernel keeps about 14 % more noise.
    noise = np.random.default_rng(8).standard_normal((1024, 1024))
    measured = ndimage.gaussian_filter(noise, 0.5, mode="wrap").std() / noise.std()
    assert measured / float(gaussian_noise_factor(0.5)) == pytest.approx(1.137, abs=0.02)


def test_filter_sizes_bring_noisy_bands_to_the_target_and_leave_clean_ones():
    sizes = filter_sizes([0.005, 0.01, 0.2, 0.5], 0.01)
    sigma = 0.2 / (2 * np.sqrt(np.pi) * 0.01)
    assert sizes.tolist() == pytest.approx([0.0, 0.0, 5 * sigma, 12.5 * sigma])
    # A flat band image with 30 % relative noise, filtered with the planned sigma, ends at 2 %.
    rng = np.random.default_rng(3)
    band = 200.0 * (1 + 0.3 * rng.standard_normal((1024, 1024)))
    (size,) = filter_sizes([band.std() / band.mean()], 0.02)
    filtered = ndimage.gaussian_filter(band, size / FILTER_SIZE_PER_SIGMA, mode="wrap")
    assert filtered.std() / filtered.mean() == pytest.approx(0.02, rel=0.04)


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (([0.1, -0.2], 0.01), "relative_noise: expected finite, non-negative"),
        (([0.1, np.nan], 0.01), "relative_noise: expected finite, non-negative"),
        (([[0.1]], 0.01), "relative_noise: expected one value per band"),
        (([0.1], 0.0), "target_relative_noise: expected a finite, positive number"),
    ],
)
def test_filter_size_input_errors_name_the_argument(arguments, message):
    with pytest.raises(InputError, match=message):
        filter_sizes(*arguments)


# -- band schedule ----------------------------------------------------------------------------


def test_thesis_rgb_set_lasts_3402_ms():
    assert sum(THESIS_RGB_EXPOSURES_S) == pytest.approx(3.402)


def test_packing_that_longest_first_greedy_misses_is_found():
    # RGB set 6 s, bands 3, 3, 2, 2, 2 s in 2 images. Every image lasts >= 6 s, so the total is
    # >= 12 s; {3, 3} and {2, 2, 2} reach it. Longest-first greedy (3 | 3, then 2 to the less
    # loaded image each time) ends with 7 + 6 = 13 s.
    plan = schedule_bands([3.0, 3.0, 2.0, 2.0, 2.0], 2, rgb_exposures_s=[1.0, 2.0, 3.0])
    assert sorted(plan.images) == [(0, 1), (2, 3, 4)]
    assert plan.total_s == pytest.approx(12.0)
    assert plan.increase == pytest.approx(0.0)
    assert plan.image_s.tolist() == pytest.approx([6.0, 6.0])
    assert plan.optimal


def test_a_long_band_takes_its_own_image():
    # The image holding the 7 s band lasts >= 7 s, the other >= 4 s (RGB): total >= 11 s,
    # reached by putting every short band into the other image.
    plan = schedule_bands([1.0, 7.0, 1.0, 1.0], 2, rgb_exposures_s=[4.0])
    assert sorted(plan.images) == [(0, 2, 3), (1,)]
    assert plan.total_s == pytest.approx(11.0)
    assert plan.increase == pytest.approx(11.0 / 8.0 - 1.0)
    assert sorted(plan.spectral_s.tolist()) == pytest.approx([3.0, 7.0])


def test_equally_short_schedules_are_balanced():
    # Six 1 s bands, RGB set 1 s, 3 images: every assignment without an empty image totals 6 s
    # (e.g. 4 + 1 + 1); the balanced one is returned.
    plan = schedule_bands(np.ones(6), 3, rgb_exposures_s=[1.0])
    assert plan.total_s == pytest.approx(6.0)
    assert plan.image_s.tolist() == pytest.approx([2.0, 2.0, 2.0])


@pytest.mark.parametrize("seed", range(6))
def test_schedule_matches_exhaustive_search(seed):
    rng = np.random.default_rng(seed)
    exposures = rng.lognormal(0.0, 0.8, 7)
    rgb_s = float(rng.uniform(0.5, 1.5) * exposures.sum() / 3)
    plan = schedule_bands(exposures, 3, rgb_exposures_s=[rgb_s])
    assert plan.total_s == pytest.approx(brute_force_total(exposures, 3, rgb_s), rel=1e-9)
    assert sorted(itertools.chain(*plan.images)) == list(range(7))
    assert plan.total_s == pytest.approx(np.maximum(plan.spectral_s, rgb_s).sum())


@pytest.mark.parametrize("seed", range(4))
def test_fewest_images_matches_exhaustive_search(seed):
    rng = np.random.default_rng(100 + seed)
    exposures = rng.uniform(0.5, 3.0, 7)
    rgb_s = 1.0
    limit = exposures.max()
    plan = fewest_images(exposures, rgb_exposures_s=[rgb_s])
    fewest = next(
        n for n in range(1, 8) if brute_force_total(exposures, n, rgb_s, limit) is not None
    )
    assert plan.n_images == fewest
    assert plan.total_s == pytest.approx(brute_force_total(exposures, fewest, rgb_s, limit))
    assert plan.image_s.max() <= limit + 1e-9
    assert plan.optimal


def test_fewest_images_by_the_capacity_bound():
    # Capacity 3 s (the longest band), 7.5 s of bands: at least 3 images, and 3 suffice.
    plan = fewest_images([3.0, 2.0, 1.5, 1.0], rgb_exposures_s=[2.5])
    assert plan.images == ((0,), (1,), (2, 3))
    assert plan.total_s == pytest.approx(3.0 + 2.5 + 2.5)


def test_repeated_bands_go_to_different_images():
    exposures = [2.0, 0.5, 0.5, 0.4]
    plan = schedule_bands(exposures, 3, rgb_exposures_s=[3.0], repeat_bands=[0, 3])
    holding = [
        [image for image, bands in enumerate(plan.images) if band in bands] for band in (0, 3)
    ]
    assert all(len(images) == 2 for images in holding)  # twice, in two images
    assert sum(len(bands) for bands in plan.images) == 6
    # Everything fits under the 3 s RGB set, e.g. 2 + 0.5 | 2 + 0.5 | 0.4 + 0.4.
    assert plan.increase == pytest.approx(0.0)
    # One image cannot take a band twice.
    with pytest.raises(InputError, match="n_images: a band taken twice needs two"):
        schedule_bands(exposures, 1, repeat_bands=[0])


def test_images_of_equal_duration_are_not_swapped_forever():
    # 0.2 + (0.9 - 0.2) < 0.9 in floating point: swapping the two bands looked like shortening
    # the longer image, and balancing swapped them back and forth without end.
    plan = schedule_bands([0.9, 0.2], 2, rgb_exposures_s=[0.1])
    assert plan.images == ((0,), (1,))
    assert plan.total_s == pytest.approx(1.1)


def test_search_proves_what_the_greedy_schedule_misses_and_the_node_limit_is_deterministic():
    # Nine bands summing to three RGB sets (5.73 s) cannot be split exactly: the optimum, 17.21 s,
    # needs the branch and bound search; one node leaves the improved greedy schedule.
    exposures = [1.78, 2.88, 0.86, 2.87, 1.28, 1.56, 2.57, 1.52, 1.87]
    plan = schedule_bands(exposures, 3, rgb_exposures_s=[5.73])
    assert plan.optimal
    assert plan.total_s == pytest.approx(brute_force_total(np.array(exposures), 3, 5.73))
    assert plan.total_s == pytest.approx(17.21)
    cut = [schedule_bands(exposures, 3, rgb_exposures_s=[5.73], node_limit=1) for _ in range(2)]
    assert not cut[0].optimal
    assert cut[0].total_s > plan.total_s + 0.05
    # The result depends on the node count only, never on the machine's speed or load.
    assert cut[0].images == cut[1].images and cut[0].total_s == cut[1].total_s


def test_fewest_images_skips_counts_the_bin_packing_bound_rules_out():
    # Three bands longer than half the image limit need three images although they sum to less
    # than two (Martello and Toth's bound L2).
    plan = fewest_images([0.6, 0.6, 0.6], rgb_exposures_s=[1.0])
    assert plan.n_images == 3 and plan.optimal


def test_thesis_sized_instance_solves_to_proven_optimum():
    # 30 bands with the spread of a real plan (a few long blue/red bands, short green ones).
    rng = np.random.default_rng(11)
    exposures = np.sort(rng.lognormal(0.0, 0.6, 30))[::-1] * 0.9
    exposures[:3] = [5.5, 4.0, 3.6]
    plan = schedule_bands(exposures, 10, repeat_bands=[0, 1])
    lower = max(10 * 3.402, exposures.sum() + 5.5 + 4.0)
    assert plan.optimal
    assert plan.total_s >= lower - 1e-9
    assert plan.total_s == pytest.approx(lower, rel=1e-3)  # balanced: every image spectral-bound


@pytest.mark.parametrize(
    ("arguments", "keywords", "message"),
    [
        (([1.0, -0.5], 2), {}, "band_exposures_s: expected positive values, got -0.5 at index 1"),
        (([1.0, np.nan], 2), {}, "band_exposures_s: expected finite values"),
        (([[1.0, 0.5]], 2), {}, "band_exposures_s: expected one value per band"),
        (([1.0, 0.5], 0), {}, "n_images: expected a positive integer, got 0"),
        (([1.0, 0.5], 2.0), {}, "n_images: expected a positive integer"),
        (([1.0, 0.5], 2), {"rgb_exposures_s": [0.05, -1.0]}, "rgb_exposures_s: expected pos"),
        (([1.0, 0.5], 2), {"repeat_bands": [2]}, r"repeat_bands: expected distinct band ind"),
        (([1.0, 0.5], 2), {"repeat_bands": [0, 0]}, r"repeat_bands: expected distinct band"),
        (([1.0, 0.5], 2), {"image_limit_s": 0.8}, "image_limit_s: 0.8 s is shorter than"),
        (([1.0, 0.9, 0.8], 1), {"image_limit_s": 2.0}, "n_images: no schedule of 3 band exp"),
        (([1.0, 0.5], 2), {"node_limit": 0}, "node_limit: expected a positive integer, got 0"),
        (([1.0, 0.5], 2), {"node_limit": 1.5}, "node_limit: expected a positive integer"),
    ],
)
def test_schedule_input_errors_name_the_argument(arguments, keywords, message):
    with pytest.raises(InputError, match=message):
        schedule_bands(*arguments, **keywords)
