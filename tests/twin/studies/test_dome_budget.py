"""The cameras' sampling model of the dome stores' error budget
(:func:`twin.studies.dome_budget.camera_sampled_texture`) on textures whose sampled values are
known: a linear ramp (area means and bilinear interpolation both keep a linear function, so
every texel reads the ramp at its centre) and a grey field through the Bayer mosaic."""

from __future__ import annotations

import numpy as np
import pytest

from recon.dome.images import TexelGrid
from twin.studies.dome_budget import camera_sampled_texture

TEXELS = 16
FINE = 64
GRID = TexelGrid(TEXELS, 0.04, 0.0)
FRONTAL = np.array([[40.0, 72.0], [40.0, 40.0], [72.0, 40.0], [72.0, 72.0]])
"""A frontal view, 2 px a texel, as the top camera's (texture order of the dome's corners)."""
OBLIQUE = np.array([[71.3, 30.2], [73.9, 81.6], [41.2, 81.9], [43.7, 30.4]])
"""An oblique view of about 1.6 x 3.2 px a texel, as the 37.5 degree camera's, turned."""


def _fine_ramp() -> np.ndarray:
    """``(FINE, FINE, 3)``: each channel a different linear function of the texture point."""
    centres = (np.arange(FINE) + 0.5) / FINE
    u, v = np.meshgrid(centres, centres)
    return np.stack([0.2 + 0.5 * u, 0.3 + 0.4 * v, 0.1 + 0.3 * u + 0.3 * v], axis=-1)


def _texel_ramp() -> np.ndarray:
    """The ramp of :func:`_fine_ramp` at the texels' centres."""
    return _fine_ramp().reshape(TEXELS, 4, TEXELS, 4, 3).mean(axis=(1, 3))


@pytest.mark.parametrize("corners", [FRONTAL, OBLIQUE], ids=["frontal", "oblique"])
def test_a_ramp_is_sampled_where_the_texels_are(corners):
    """Without the mosaic every texel away from the square's border reads the ramp's value at
    its centre: the pixels, the homography and the resampling agree on where the texels lie
    (pixel areas taken half a pixel up instead: 7.8e-3). Measured: largest difference 3e-16
    (frontal) and 1.1e-3 (oblique: the fine texture's steps of a quarter texel), of values
    0.1-0.7."""
    sampled = camera_sampled_texture(_fine_ramp(), corners, GRID, mosaic=False)
    inner = (slice(1, -1), slice(1, -1))
    assert np.abs(sampled - _texel_ramp())[inner].max() < 2e-3


def test_a_grey_field_keeps_its_value_through_the_mosaic():
    """A uniform grey through the RGGB mosaic and Malvar's demosaicing is the same grey in
    every channel and texel."""
    grey = np.full((FINE, FINE, 3), 0.37)
    sampled = camera_sampled_texture(grey, OBLIQUE, GRID, mosaic=True)
    np.testing.assert_allclose(sampled, 0.37, atol=1e-9)
