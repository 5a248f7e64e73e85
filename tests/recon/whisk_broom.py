"""Chapter 7's whisk-broom protocol on a real test image, for the spectralization tests."""

from __future__ import annotations

import numpy as np

from recon.experiments.real_images import real_test_image
from recon.experiments.sampling import add_rgb_noise, known_spectra_from_mask, whisk_broom_mask
from recon.image_spectralization.spots import SpotSpectra
from recon.spectra import DEFAULT_GRID, SampledSpectra


def whisk_broom_case(name: str, side: int):
    """Chapter 7's whisk-broom protocol on the real test image ``name`` at ``side`` px, seed 0:
    250 spots of its true spectra and 1 % RGB noise: ``(case, rgb, pixels, spectra)``."""
    case = real_test_image(name, side=side, seed=0)
    pixels, spectra = known_spectra_from_mask(case.truth, whisk_broom_mask(case.truth.shape[:2]))
    rgb = add_rgb_noise(case.truth @ case.response, 0.01, np.random.default_rng(0))
    return case, rgb, pixels, spectra


def blend_with_spots(name: str, side: int, spots: int, noise: float = 0.0):
    """A user's image as ``spectralize_image`` takes it: the real test image ``name``
    (``recon.experiments.real_images``, seed 0) at ``side`` px with ``noise`` Gaussian RGB
    noise (a fraction of the mean), ``spots`` single-pixel spots of its true spectra on the
    whisk-broom grid and the camera's response per nanometre: ``(truth, rgb, spots, response,
    mask)``."""
    case = real_test_image(name, side=side, seed=0)
    mask = whisk_broom_mask(case.truth.shape[:2], n_spots=spots)
    rows, cols = np.nonzero(mask)
    known = SpotSpectra(
        np.stack([cols, rows], 1), SampledSpectra(DEFAULT_GRID, case.truth[rows, cols]), "test"
    )
    response = case.response_per_nm()
    rgb = case.truth @ case.response
    if noise:
        rgb = add_rgb_noise(rgb, noise, np.random.default_rng(0))
    return case.truth, rgb, known, response, mask
