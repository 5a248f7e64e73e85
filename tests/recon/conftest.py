"""Fixtures of the recon tests."""

from __future__ import annotations

import pytest

from tests.recon.whisk_broom import blend_with_spots


@pytest.fixture(scope="session")
def small_blend_image():
    """The real food reflectances' smooth blend at 48 px (no RGB noise) and 64 spots
    (:func:`tests.recon.whisk_broom.blend_with_spots`): ``(rgb, spots, response)``."""
    _, rgb, spots, response, _ = blend_with_spots("vhrel_food blend", 48, 64)
    return rgb, spots, response
