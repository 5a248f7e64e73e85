"""The blend of spectralization with Murakami 2007's kriged estimate, weighted by held-out spots
(:mod:`recon.image_spectralization.kriging_blend`), on real reflectances: smooth blends, where
Murakami's kriging is the best peer (BENCHMARKS.md, "Spectralization on real spectra"), and
mosaics, where spectralization is several times better than it."""

from __future__ import annotations

import numpy as np
import pytest

from recon.baselines import recover
from recon.errors import InputError
from recon.image_spectralization import run
from recon.image_spectralization.kriging_blend import blend_with_kriging, choose_kriging_weight
from recon.image_spectralization.run import spectralize_image
from recon.metrics import relative_error
from recon.spectralize import choose_prior, hierarchy
from recon.spectralize.solve import EnergyWeights, spectralize
from tests.recon.whisk_broom import blend_with_spots, whisk_broom_case

SETTINGS = {"appearance": "rgbxy", "weights": EnergyWeights(delta=0.0), "tol": 1e-8}


def _case(name: str):
    """Chapter 7's whisk-broom protocol at 96 px, seed 0: 250 spots, 1 % RGB noise."""
    case, rgb, pixels, spectra = whisk_broom_case(name, 96)
    choice = choose_prior(rgb, case.response, pixels, spectra, folds=3, **SETTINGS)
    chosen = choose_kriging_weight(rgb, case.response, pixels, spectra, choice)
    alone = spectralize(
        rgb,
        case.response,
        known_pixels=pixels,
        known_spectra=spectra,
        prior=choice.prior,
        **SETTINGS,
    )
    blend = blend_with_kriging(alone, rgb, case.response, pixels, spectra, chosen.kriging_weight)
    kriged = recover(
        rgb, case.response, method="murakami", known_pixels=pixels, known_spectra=spectra
    )
    errors = {
        name: float(relative_error(estimate, case.truth).mean())
        for name, estimate in (("alone", alone), ("blend", blend), ("murakami", kriged))
    }
    return chosen, errors, alone, blend


@pytest.mark.parametrize("name", ["vhrel_food blend", "rawtoaces_training_190 blend"])
def test_on_smooth_blends_the_kriged_estimate_is_weighted_in_and_matches_murakami(name):
    """Measured: food blend weight 0.95, 2.12 % against Murakami's 2.13 % and the chosen prior
    alone 2.48 %; rawtoaces blend weight 1.0, 1.88 % against 1.88 % and 3.05 %."""
    chosen, errors, _, _ = _case(name)
    assert chosen.kriging_weight >= 0.5
    assert errors["blend"] <= errors["murakami"] * 1.005
    assert errors["blend"] < 0.9 * errors["alone"]
    held_out = chosen.held_out_errors
    assert held_out["blend"] <= min(held_out["spectralization"], held_out["kriging"])
    assert chosen.pixel_errors.mean() == pytest.approx(held_out["blend"])


@pytest.mark.parametrize("name", ["vhrel_clothes mosaic", "macbeth_colorchecker mosaic"])
def test_on_mosaics_the_spectralization_is_kept_alone(name):
    """Measured: weight 0 on both; the held-out kriged estimate 17.1 % and 10.3 % against the
    spectralization's 3.7 % and 3.2 %, as the whole images (11.8 and 7.4 % against 2.3 and
    1.7 %)."""
    chosen, errors, alone, blend = _case(name)
    assert chosen.kriging_weight == 0.0
    assert blend is alone
    assert chosen.held_out_errors["kriging"] > 2 * chosen.held_out_errors["spectralization"]
    assert errors["murakami"] > 2 * errors["alone"]


def test_a_weight_outside_zero_to_one_is_refused():
    with pytest.raises(InputError, match=r"kriging_weight: expected a weight in \[0, 1\]"):
        blend_with_kriging(np.zeros((4, 4, 3)), np.zeros((4, 4, 3)), np.eye(3), [0], [[1, 1, 1]], 2)


def test_spectralize_image_blends_unless_there_are_too_many_spots(monkeypatch, small_blend_image):
    """``spectralize_image`` weights the kriged estimate in on a smooth blend (its held-out
    errors then name the kriged estimate and the blend); above ``MAX_KRIGED_PIXELS`` spots it
    keeps the spectralization alone and says so."""
    rgb, spots, response = small_blend_image
    blended = spectralize_image(rgb, spots, response)
    assert blended.kriging_weight > 0
    assert {"kriging", "blend"} <= set(blended.held_out_errors)
    monkeypatch.setattr(run, "MAX_KRIGED_PIXELS", 63)
    alone = spectralize_image(rgb, spots, response)
    assert alone.kriging_weight == 0.0 and "blend" not in alone.held_out_errors
    assert any("no blend with the kriged estimate: 64 spot pixels" in n for n in alone.notes)


def test_a_weight_of_one_takes_the_kriged_estimate_without_a_solve(monkeypatch):
    """On the noiseless food blend (64 px, 128 spots) the held-out spots choose the kriged
    estimate alone (weight 1; measured): the spectralization is not solved, and the result is
    Murakami's estimate from the spots (with the camera's band integrals instead of the term
    fitted to the spots: the same within 0.001 %)."""
    truth, rgb, spots, response, mask = blend_with_spots("vhrel_food blend", 64, 128)
    monkeypatch.setattr(
        hierarchy, "reconstruct_image", lambda *_, **__: pytest.fail("the image was solved")
    )
    result = spectralize_image(rgb, spots, response)
    assert result.kriging_weight == 1.0 and "solve" not in result.timings_s
    assert any(note.startswith("the kriged estimate alone") for note in result.notes)
    pixels = spots.flat_pixels(rgb.shape[:2])
    murakami = recover(
        rgb,
        response.values.T * response.grid.quadrature_weights()[:, None],
        method="murakami",
        known_pixels=pixels,
        known_spectra=truth.reshape(-1, 33)[pixels],
    )
    assert float(relative_error(result.cube, murakami).mean()) < 1e-3
