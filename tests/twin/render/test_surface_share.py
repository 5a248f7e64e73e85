"""Which texels show the sample's surface alone (twin.render.truth.surface_share): a raised
sample seen from the side shows its outer side, a border h tan(theta) deep on the camera's side."""

import numpy as np
import pytest

from recon.spectra import SampledSpectra
from twin.components.lamps import FINE_GRID
from twin.materials import Material
from twin.materials.geometry import box
from twin.materials.surfaces import SurfacePart
from twin.render.truth import surface_share

pytestmark = pytest.mark.render

SIDE_M, HEIGHT_M, TEXELS = 0.04, 0.002, 20  # texels of 2 mm


def _slab() -> Material:
    grey = SampledSpectra(FINE_GRID, np.full(FINE_GRID.size, 0.5))
    slab = SurfacePart("slab", box((0.0, 0.0, HEIGHT_M / 2), (SIDE_M, SIDE_M, HEIGHT_M)), grey)
    return Material("slab", SIDE_M, (slab,), {}, ())


def test_a_raised_slab_seen_from_the_side_hides_a_border_h_tan_theta_deep():
    tan_theta = 2.5  # 2 mm x 2.5 = 5 mm: two and a half texels on the camera's side (+x)
    oblique = np.array([tan_theta, 0.0, 1.0]) / np.hypot(tan_theta, 1.0)
    normal, side = surface_share(_slab(), np.array([[0.0, 0.0, 1.0], oblique]), texels=TEXELS)
    assert np.all(normal == 1.0)
    expected = np.ones(TEXELS)
    expected[-3:] = (0.5, 0.0, 0.0)  # 4 x 4 strata a texel: half of column 17's lie past 15 mm
    np.testing.assert_array_equal(side, np.broadcast_to(expected, (TEXELS, TEXELS)))
