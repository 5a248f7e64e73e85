"""Spectral error measures of recon.metrics: delta E 94 (thesis 6.2), RMSE and spectral angle."""

import warnings

import colour
import numpy as np
import pytest
from scipy import linalg

from recon.errors import InputError
from recon.metrics import THESIS_ILLUMINANTS, delta_e94, rmse, spectral_angle
from recon.spectra import DEFAULT_GRID

SHAPE = colour.SpectralShape(400, 720, 10)
OBSERVER = "CIE 1931 2 Degree Standard Observer"
PATCHES = ("dark skin", "foliage", "purplish blue", "moderate red", "yellow", "white 9.5 (.05 D)")


def _checker(name: str) -> np.ndarray:
    """ColorChecker (N Ohta) patch reflectance on the thesis grid (5 nm data: exact nodes)."""
    patch = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"][name].copy().align(SHAPE)
    return np.asarray(patch.values)


def _colour_pipeline(estimate: np.ndarray, truth: np.ndarray, illuminant: str) -> float:
    """delta E 94 for one pair, computed with colour's own per-spectrum objects and functions."""
    cmfs = colour.MSDS_CMFS[OBSERVER].copy().align(SHAPE)
    light = colour.SDS_ILLUMINANTS[illuminant].copy().align(SHAPE)

    def xyz(reflectance: np.ndarray) -> np.ndarray:
        sd = colour.SpectralDistribution(reflectance, SHAPE.wavelengths)
        return colour.sd_to_XYZ(sd, cmfs, light, method="Integration")

    white = xyz(np.ones(SHAPE.wavelengths.size))
    white_xy = colour.XYZ_to_xy(white)
    lab_truth = colour.XYZ_to_Lab(xyz(truth) / white[1], white_xy)
    lab_estimate = colour.XYZ_to_Lab(xyz(estimate) / white[1], white_xy)
    return float(colour.delta_E(lab_truth, lab_estimate, method="CIE 1994"))


@pytest.fixture
def checker_pairs(rng):
    truth = np.stack([_checker(name) for name in PATCHES])
    estimate = np.clip(truth * (1 + 0.1 * rng.standard_normal(truth.shape)) + 0.01, 0, 1)
    return estimate, truth


def test_identical_spectra_have_zero_delta_e(checker_pairs):
    _, truth = checker_pairs
    assert np.all(delta_e94(truth, truth, DEFAULT_GRID.wavelengths_nm) == 0)


def test_single_illuminant_matches_colours_own_pipeline(checker_pairs):
    estimate, truth = checker_pairs
    ours = delta_e94(estimate, truth, DEFAULT_GRID, illuminants="D65")
    reference = [_colour_pipeline(e, t, "D65") for e, t in zip(estimate, truth, strict=True)]
    assert ours.shape == (len(PATCHES),)
    np.testing.assert_allclose(ours, reference, rtol=0, atol=1e-3)
    assert np.all(ours > 0.3)  # the perturbations are visible differences, not a trivial 0


def test_fluorescent_illuminant_matches_colours_own_pipeline(checker_pairs):
    estimate, truth = checker_pairs
    ours = delta_e94(estimate, truth, DEFAULT_GRID, illuminants=("FL8",))
    reference = [_colour_pipeline(e, t, "FL8") for e, t in zip(estimate, truth, strict=True)]
    np.testing.assert_allclose(ours, reference, rtol=0, atol=1e-3)


def test_default_is_the_mean_over_the_ten_thesis_illuminants(checker_pairs):
    estimate, truth = checker_pairs
    assert THESIS_ILLUMINANTS == (
        "A", "D65", "D50", "D75", "FL1", "FL4", "FL8", "FL12", "HP1", "HP3",
    )  # fmt: skip
    single = [delta_e94(estimate, truth, DEFAULT_GRID, name) for name in THESIS_ILLUMINANTS]
    np.testing.assert_allclose(
        delta_e94(estimate, truth, DEFAULT_GRID), np.mean(single, axis=0), rtol=1e-12
    )


def test_metamers_under_d65_differ_under_the_other_illuminants():
    truth = _checker("neutral 5 (.70 D)")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", colour.utilities.ColourRuntimeWarning)
        weighting = colour.sd_to_XYZ(
            np.eye(SHAPE.wavelengths.size),
            colour.MSDS_CMFS[OBSERVER],
            colour.SDS_ILLUMINANTS["D65"],
            method="Integration",
            shape=SHAPE,
        )
    # A metameric black: orthogonal to the D65 colour-matching weights, so XYZ(D65) is unchanged.
    black = linalg.null_space(weighting.T) @ np.ones(SHAPE.wavelengths.size - 3)
    metamer = truth + 0.15 * black / np.abs(black).max()
    assert metamer.min() >= 0 and np.abs(metamer - truth).max() > 0.1
    under_d65 = float(delta_e94(metamer, truth, DEFAULT_GRID, "D65"))
    averaged = float(delta_e94(metamer, truth, DEFAULT_GRID))
    assert under_d65 < 1e-6
    assert averaged > 0.5


def test_delta_e_keeps_the_leading_shape(rng):
    # A 250 x 400 image at once (its time: benchmarks/foundation.py, delta_e94_250x400x33_s).
    truth = rng.uniform(0.05, 0.95, (250, 400, 33))
    estimate = truth + 0.02 * rng.standard_normal(truth.shape)
    value = delta_e94(estimate, truth, DEFAULT_GRID)
    assert value.shape == (250, 400)
    assert np.all(value > 0) and np.all(np.isfinite(value))


def test_delta_e_rejects_bad_input(checker_pairs):
    estimate, truth = checker_pairs
    with pytest.raises(InputError, match="shape"):
        delta_e94(estimate[:, :-1], truth, DEFAULT_GRID)
    with pytest.raises(InputError, match="wavelengths_nm: expected 32 wavelengths"):
        delta_e94(estimate[:, :-1], truth[:, :-1], DEFAULT_GRID)
    with pytest.raises(InputError, match="regular grid"):
        irregular = np.concatenate([[395.0], DEFAULT_GRID.wavelengths_nm[1:]])
        delta_e94(estimate, truth, irregular)
    with pytest.raises(InputError, match="illuminants"):
        delta_e94(estimate, truth, DEFAULT_GRID, ("D65", "no such lamp"))
    with pytest.raises(InputError, match="illuminants"):
        delta_e94(estimate, truth, DEFAULT_GRID, ())
    bad = estimate.copy()
    bad[0, 3] = np.nan
    with pytest.raises(InputError, match="estimate contains NaN"):
        delta_e94(bad, truth, DEFAULT_GRID)


def test_rmse_of_hand_computed_cases():
    truth = np.array([[0.0, 0.0, 0.0, 0.0], [1.0, 2.0, 3.0, 4.0]])
    estimate = np.array([[1.0, -1.0, 1.0, -1.0], [1.0, 2.0, 3.0, 8.0]])
    np.testing.assert_allclose(rmse(estimate, truth), [1.0, 2.0])
    assert rmse(np.ones((2, 3, 5)), np.ones((2, 3, 5))).shape == (2, 3)


def test_spectral_angle_of_hand_computed_cases():
    estimate = np.array([[1.0, 0.0, 0.0], [2.0, 4.0, 6.0], [1.0, 1.0, 0.0], [0.0, 0.0, 0.0]])
    truth = np.array([[0.0, 3.0, 0.0], [1.0, 2.0, 3.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    np.testing.assert_allclose(spectral_angle(estimate, truth), [90.0, 0.0, 45.0, 0.0], atol=1e-12)
    # A zero spectrum against a non-zero one: 90 degrees by definition, either way round.
    zero, ramp = np.zeros(4), np.arange(1.0, 5.0)
    assert spectral_angle(zero, ramp) == 90.0 and spectral_angle(ramp, zero) == 90.0
    assert spectral_angle(-ramp, ramp) == pytest.approx(180.0)


def test_rmse_and_angle_reject_bad_input():
    for function in (rmse, spectral_angle):
        with pytest.raises(InputError, match="differ in shape"):
            function(np.ones((2, 3)), np.ones((3, 2)))
        with pytest.raises(InputError, match="truth contains NaN"):
            function(np.ones(3), np.array([1.0, np.nan, 1.0]))
        with pytest.raises(InputError, match=r"\(\.\.\., K\)"):
            function(np.float64(1.0), np.float64(1.0))
