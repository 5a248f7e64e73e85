"""Chapter 7's whisk-broom protocol on a real test image, for the spectralization tests."""

from __future__ import annotations

import numpy as np

from recon.experiments.real_images import real_test_image
from recon.experiments.sampling import add_rgb_noise, known_spectra_from_mask, whisk_broom_mask


def whisk_broom_case(name: str, side: int):
    """Chapter 7's whisk-broom protocol on the real test image ``name`` at ``side`` px, seed 0:
    250 spots of its true spectra and 1 % RGB noise: ``(case, rgb, pixels, spectra)``."""
    case = real_test_image(name, side=side, seed=0)
    pixels, spectra = known_spectra_from_mask(case.truth, whisk_broom_mask(case.truth.shape[:2]))
    rgb = add_rgb_noise(case.truth @ case.response, 0.01, np.random.default_rng(0))
    return case, rgb, pixels, spectra
