"""The stable entry points named in ARCHITECTURE.md exist and call the implementations."""

from __future__ import annotations

import inspect

import numpy as np

from recon import baselines, metrics, radiometric, spectralize
from recon.radiometric import response_curve


def test_named_entry_points_exist_with_their_leading_arguments():
    parameters = inspect.signature(spectralize.spectralize).parameters
    for name in ("rgb", "response", "known_pixels", "known_spectra", "band_images", "k"):
        assert name in parameters
    assert parameters["appearance"].default == "rgb" and parameters["k"].default == 3
    for name in ("imai", "smits", "jakob2019", "hardeberg", "murakami", "dong", "aplus"):
        assert callable(getattr(baselines, name)), name
    assert radiometric.robertson is response_curve.robertson
    assert metrics.THESIS_SET == metrics.THESIS_ILLUMINANTS and len(metrics.THESIS_SET) == 10


def test_aplus_in_project_order_equals_spectral_a_plus():
    rng = np.random.default_rng(0)
    response = rng.random((12, 3))
    spectra = rng.random((60, 12))
    rgb = spectra @ response
    known = np.arange(0, 60, 2)
    short = baselines.aplus(rgb, response, spectra[known], known_pixels=known, n_atoms=8)
    long = baselines.spectral_a_plus(
        rgb, spectra[known], known_pixels=known, response=response, n_atoms=8
    )
    assert np.array_equal(short, long)
