"""The stable entry points named in ARCHITECTURE.md exist and call the implementations."""

from __future__ import annotations

import inspect

from recon import baselines, metrics, radiometric, spectralize
from recon.radiometric import response_curve


def test_named_entry_points_exist_with_their_leading_arguments():
    parameters = inspect.signature(spectralize.spectralize).parameters
    for name in ("rgb", "response", "known_pixels", "known_spectra", "band_images", "k"):
        assert name in parameters
    assert parameters["appearance"].default == "rgb" and parameters["k"].default == 3
    for name in ("imai", "hardeberg", "murakami", "dong", "a_plus", "smits", "jakob"):
        assert baselines.RECOVERY_METHODS[name] is getattr(baselines, name), name
    parameters = inspect.signature(baselines.recover).parameters
    assert list(parameters)[:5] == ["rgb", "response", "method", "known_pixels", "known_spectra"]
    assert radiometric.robertson is response_curve.robertson
    assert metrics.THESIS_SET == metrics.THESIS_ILLUMINANTS and len(metrics.THESIS_SET) == 10
