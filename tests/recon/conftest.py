"""Fixtures of the recon tests."""

from __future__ import annotations

import numpy as np
import pytest

from recon.experiments.real_images import real_test_image
from recon.experiments.sampling import whisk_broom_mask
from recon.image_spectralization.spots import SpotSpectra
from recon.spectra import DEFAULT_GRID, SampledSpectra


@pytest.fixture(scope="session")
def small_blend_image():
    """A user's image as ``spectralize_image`` takes it: the real food reflectances' smooth
    blend at 48 px (no RGB noise), 64 single-pixel spots of its true spectra and the camera's
    response per nanometre: ``(rgb, spots, response)``."""
    case = real_test_image("vhrel_food blend", side=48, seed=0)
    rows, cols = np.nonzero(whisk_broom_mask(case.truth.shape[:2], n_spots=64))
    spots = SpotSpectra(
        np.stack([cols, rows], 1), SampledSpectra(DEFAULT_GRID, case.truth[rows, cols]), "test"
    )
    per_nm = case.response / DEFAULT_GRID.quadrature_weights()[:, None]
    response = SampledSpectra(DEFAULT_GRID, per_nm.T, ("R", "G", "B"))
    return case.truth @ case.response, spots, response
